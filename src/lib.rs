#![warn(unreachable_pub)]
//! specula: a CPU software rasterizer with a packed-SIMD fragment-shading
//! core. This facade ties the crates together: scene files (`scene`), meshes
//! (`mesh`), the material contract shared by scenes and `specula eval`
//! (`material_desc`), rendering with statistics (`render`) and image output
//! (`image_file`; where files go: `output_plan`), image files as textures (`textures`), text labels on images
//! (`label`). The built-in demo lives in `demo`; `fuzzing` holds the fuzz
//! targets' entry points. The generators only the command line runs
//! (`furnace`, `fit-ltc`, `fit-ltc-coat`) are modules of the binary
//! (src/main.rs), not of this library.

pub mod batch;
mod checks;
pub mod demo;
pub mod diff;
pub mod envmap_file;
pub mod eval;
/// The fuzz targets' entry points (fuzz/fuzz_targets and the corpus
/// tests in tests/ call them); not part of the library's API.
#[doc(hidden)]
pub mod fuzzing;
pub mod gltf;
pub mod huge_pages;
pub mod image_file;
pub mod label;
pub mod lines;
pub mod material_desc;
pub mod memory;
pub mod mesh;
mod mesh_cache;
pub mod objcheck;
pub mod output_plan;
mod polygon_light;
pub mod progress;
pub mod render;
pub mod scene;
pub mod sky;
pub mod table_cache;
mod tangents;
mod textures;
pub mod validate;

pub use specula_core as core;
pub use specula_raster as raster;
