#![warn(unreachable_pub)]
//! specula-raster: the hand-written rasterizer and shading pass.
//!
//! A frame is a list of passes (`frame`): the scene's geometry passes
//! (`geometry`: vertex stage, cull mode, id range) each transform vertices,
//! clip (`clip`), skip triangles hidden behind earlier passes
//! (`occlusion`), set up fixed-point edge functions (`setup`, `fixed`;
//! `setup_x4` does 4 triangles at once, bit-identical), bin
//! screen triangles into 64×64 tiles (`bin`) and scan-convert each tile into
//! the one visibility buffer (`scan`, `target`); the shading pass rebuilds
//! attributes at pixel centres (`resolve`, into `fragment`'s types) and runs each material's surface
//! shader (`shader`: `lit` for the physically based models, `unlit`) 8
//! pixels at a time (`shading_pass`) into row-major frame buffers (`buffers`:
//! colour, depth, normal, id); `texture` is the mip-mapped texture
//! sampler shaders read (base-colour maps, tonal art maps), `maps` fills a
//! material's per-pixel parameters from it; `post` runs the post stages (downsampling the
//! supersamples, exposure, tone map, encode, and any custom image-space stage).

mod alpha;
mod bin;
mod blend;
pub mod buffers;
pub mod camera;
pub mod clip;
pub mod closed;
mod delta_light;
mod depth_pass;
pub mod envmap;
pub mod envmap_reference;
mod envmap_sample;
pub mod envmap_sun;
pub mod equirect;
mod fixed;
mod fragment;
pub mod frame;
pub mod geometry;
#[cfg(target_arch = "x86_64")]
mod lanes16;
mod lit;
pub mod maps;
mod occlusion;
mod packet_pairs;
pub mod post;
pub mod resolve;
mod scan;
pub mod scene;
pub mod setup;
mod setup_x4;
mod shader;
mod shading_pass;
pub mod shadow;
pub mod shadow_pass;
mod split_sum;
mod stats;
pub mod target;
pub mod texture;
mod unlit;
mod visibility;

pub use alpha::{AlphaMode, MaterialAlpha};
pub use buffers::{BufferSet, FrameBuffers, Planes3};
pub use camera::{Camera, View};
pub use fragment::{Fragment, Surface};
pub use frame::{
    render, render_into, render_ldr, render_ldr_into, render_with, shade, shade_into, visibility,
    visibility_into, Frame, FrameStats, PassTimes, ShadePath, Visibility,
};
pub use geometry::{Cull, FrameContext, GeometryPass, Project, SceneMesh, VertexStage};
pub use lit::{Lit, UnsupportedMap};
pub use scene::{Material, SceneData, SceneDataError, SceneParts};
pub use shader::{LightRefusal, PacketShader, ShadeEnv, ShadeInput, SurfaceShader};
pub use split_sum::{env_split_sum, prefilter_reading};
pub use target::{Target, MISS, TILE};
pub use unlit::{Unlit, UnlitBase};
pub use visibility::ShadowBuffers;

/// The fixed-point setup, binning and scan conversion, reached past the
/// frame's pass list. Public only so specula's fuzz entry points and this
/// crate's coverage and occlusion tests can drive each step on its own;
/// not part of the renderer's API.
#[doc(hidden)]
pub mod fuzzing {
    pub use crate::bin::{bin_chunk, BinnedChunk};
    pub use crate::fixed::{pixel_centre, snap, SUBPIXEL_ONE};
    pub use crate::occlusion::DepthBounds;
    pub use crate::scan::{covered_groups, rasterize_tile, scan_triangle};
    pub use crate::setup::{
        DepthPlanes, RasterTri, RectCoverage, SetupContext, SetupCounts, SetupPlanes, TriPlanes,
    };
    pub use crate::setup_x4::LANES;
}
