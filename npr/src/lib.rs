//! specula-npr: the screen-space non-photorealistic passes, built on the
//! visibility and colour buffers of specula-raster.
//!
//! So far: colour blocks — `toon` (hard shading, a surface shader) and
//! `posterize` (a post stage); `tam`, tonal art maps generated with
//! tiny-skia, and `hatching`, the shader that draws with them; `lights`,
//! the scene's lights as these shaders read them; `plot`, line plots for
//! the furnace tool. Planned (see DESIGN.md, "NPR"): outlines by
//! shading (N·V threshold), by geometry (back faces extruded along normals)
//! and by image (Sobel on depth, normals, ids and colour); stroke overlays
//! of silhouette, crease and boundary edges.

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
