//! `[output]`: the image size and supersampling, the background, the
//! exposure and the labels.

use super::super::desc::OutputDesc;
use crate::checks;

/// `[output]` and its `[[output.label]]`s.
pub(in crate::scene) fn check_output(o: &OutputDesc) -> Result<(), String> {
    check_output_size(o)?;
    checks::radiometric("output.background", o.background)?;
    if !o.exposure.is_finite() {
        return Err("output.exposure: must be finite".into());
    }
    for (i, l) in o.labels.iter().enumerate() {
        l.validate().map_err(|e| format!("output.label[{i}].{e}"))?;
    }
    Ok(())
}

/// The image size and supersampling: each side, supersampled, within the
/// render target's limit.
fn check_output_size(o: &OutputDesc) -> Result<(), String> {
    let max = specula_raster::target::MAX_DIM;
    if !(1..=16).contains(&o.ssaa) {
        return Err(format!("output.ssaa: must be in 1..=16, got {}", o.ssaa));
    }
    for (field, v) in [("output.width", o.width), ("output.height", o.height)] {
        let limit = max / o.ssaa;
        if !(1..=limit).contains(&v) {
            return Err(format!(
                "{field}: must be in 1..={limit} (at most {max} after ssaa {}), got {v}",
                o.ssaa
            ));
        }
    }
    Ok(())
}
