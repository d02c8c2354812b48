//! `[output]`: the image size and supersampling, the background, the
//! exposure and the labels.

use super::super::desc::OutputDesc;
use super::BuildError;
use crate::checks;

/// `[output]` and its `[[output.label]]`s.
pub(in crate::scene) fn check_output(o: &OutputDesc) -> Result<(), BuildError> {
    check_output_size(o)?;
    checks::radiometric("output.background", o.background)?;
    if !o.exposure.is_finite() {
        return Err(BuildError::Exposure);
    }
    for (i, l) in o.labels.iter().enumerate() {
        l.validate().map_err(|source| BuildError::Label {
            index: i,
            source: Box::new(source),
        })?;
    }
    Ok(())
}

/// The image size and supersampling: each side, supersampled, within the
/// render target's limit.
fn check_output_size(o: &OutputDesc) -> Result<(), BuildError> {
    let max = specula_raster::target::MAX_DIM;
    if !(1..=16).contains(&o.ssaa) {
        return Err(BuildError::Ssaa(o.ssaa));
    }
    for (field, v) in [("output.width", o.width), ("output.height", o.height)] {
        let limit = max / o.ssaa;
        if !(1..=limit).contains(&v) {
            return Err(BuildError::ImageSide {
                field,
                limit,
                max,
                ssaa: o.ssaa,
                got: v,
            });
        }
    }
    Ok(())
}
