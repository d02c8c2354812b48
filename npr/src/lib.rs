//! specula-npr: the screen-space non-photorealistic passes, built on the
//! visibility and colour buffers of specula-raster.
//!
//! Colour blocks — `toon` (hard shading, a surface shader) and
//! `posterize` (a post stage); `tam`, tonal art maps generated with
//! tiny-skia, and `hatching`, the shader that draws with them; `lights`,
//! the scene's lights as these shaders read them; `plot`, line plots for
//! the furnace tool. Lines: `outline` (the outline by shading and what the
//! image-space outlines share), `sobel` (the outline by image), `extrude`
//! (the outline by geometry: a pass of pushed-out back faces), `edges`
//! (silhouette, crease, boundary and material edges from mesh topology,
//! their visibility and chaining) and `overlay` (drawing them with
//! tiny-skia, and SVG).

#![warn(unreachable_pub)]

mod dilate;
pub mod edges;
pub mod extrude;
pub mod hatching;
pub mod lights;
pub mod outline;
pub mod overlay;
pub mod plot;
pub mod posterize;
pub mod sobel;
pub mod tam;
pub mod toon;

/// A parameter out of range: the field it is about (as the scene names
/// it) and why.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{field}: {reason}")]
pub struct ParamError {
    pub field: String,
    pub(crate) reason: String,
}

impl ParamError {
    pub(crate) fn new(field: impl Into<String>, reason: String) -> ParamError {
        ParamError {
            field: field.into(),
            reason,
        }
    }
}
