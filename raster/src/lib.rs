//! specula-raster: the hand-written rasterizer and shading pass.
//!
//! Data flow (one frame): `frame::visibility` transforms vertices, clips
//! (`clip`), sets up fixed-point edge functions (`setup`, `fixed`), bins screen
//! triangles into 64×64 tiles (`bin`) and scan-converts each tile into the
//! visibility buffer (`scan`, `target`); `frame::shade` rebuilds attributes at
//! pixel centres (`resolve`) and evaluates materials 8 pixels at a time
//! (`shade`); `post` resolves supersampling and tone maps.

pub mod bin;
pub mod camera;
pub mod clip;
pub mod fixed;
pub mod frame;
pub mod post;
pub mod resolve;
pub mod scan;
pub mod scene;
pub mod setup;
pub mod shade;
pub mod target;

pub use camera::{Camera, View};
pub use frame::{
    render, render_into, shade, shade_into, visibility, visibility_into, Frame, FrameStats,
    PassTimes, ShadePath, Visibility,
};
pub use scene::SceneData;
pub use target::{Target, MISS, TILE};
