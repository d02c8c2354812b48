//! specula: a CPU software rasterizer with a packed-SIMD fragment-shading
//! core. This facade ties the crates together: scene files (`scene`), meshes
//! (`mesh`), the material contract shared by scenes and `specula eval`
//! (`material_desc`), rendering with statistics (`render`) and image output
//! (`output`), text labels on images (`label`). The built-in demo lives in
//! `demo`.

pub mod demo;
pub mod eval;
pub mod furnace;
pub mod label;
pub mod material_desc;
pub mod mesh;
pub mod output;
pub mod render;
pub mod scene;

pub use specula_core as core;
pub use specula_raster as raster;
