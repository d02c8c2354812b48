//! specula-npr: the screen-space non-photorealistic passes, built on the
//! visibility and colour buffers of specula-raster.
//!
//! So far: `plot`, line plots for the furnace tool; `tam`, tonal art maps
//! generated with tiny-skia. Planned (see DESIGN.md, "NPR"): outlines by
//! shading (N·V threshold), by geometry (back faces extruded along normals)
//! and by image (Sobel on depth, normals, ids and colour); stroke overlays
//! of silhouette, crease and boundary edges.

pub mod plot;
pub mod posterize;
pub mod tam;
