//! The tables that add image-space stages and outlines: `[posterize]`
//! and `[[outline]]` (the outlines' own checks are in `lines.rs`).

use super::super::desc::{PosterizeDesc, PosterizeModeDesc};
use super::BuildError;
use std::collections::HashMap;

/// `[[outline]]`s; the materials they name must exist.
pub(in crate::scene) fn check_outlines(
    descs: &[crate::lines::OutlineDesc],
    by_name: &HashMap<String, u32>,
) -> Result<Vec<crate::lines::OutlineSpec>, BuildError> {
    descs
        .iter()
        .enumerate()
        .map(|(i, o)| o.check(&format!("outline[{i}]"), &|n| by_name.contains_key(n)))
        .collect::<Result<_, _>>()
        .map_err(|e| BuildError::Lines(Box::new(e)))
}

/// `[posterize]`: the image-space stage it asks for, if any.
pub(in crate::scene) fn build_posterize(
    p: Option<&PosterizeDesc>,
) -> Result<Vec<std::sync::Arc<dyn specula_raster::post::PostStage>>, BuildError> {
    let mut post_stages: Vec<std::sync::Arc<dyn specula_raster::post::PostStage>> = Vec::new();
    if let Some(p) = p {
        use specula_npr::posterize::{Posterize, PosterizeMode};
        let mode = match p.mode {
            PosterizeModeDesc::Rgb => PosterizeMode::Rgb,
            PosterizeModeDesc::Luminance => PosterizeMode::Luminance,
        };
        let stage = Posterize::new(p.levels, mode)?;
        post_stages.push(std::sync::Arc::new(stage));
    }
    Ok(post_stages)
}
