//! What the shading pass hands a shader for the lanes of a packet: the
//! attributes rebuilt at pixel centres ([`Fragment`]) and, for shaders
//! that sample textures, the uv frame ([`Surface`]). `resolve` fills them;
//! the shader seam (`shader`) and the shaders read them. They sit below
//! both so the seam does not depend on `resolve`, which reads the scene,
//! which holds the materials' shaders.

use specula_core::{Real, Rgb, ShadingFrame, V3};

/// Per-lane surface data the shading pass needs.
#[derive(Clone, Copy, Debug)]
pub struct Fragment<R: Real> {
    /// World position.
    pub p: V3<R>,
    /// Unit shading normal (flipped toward the viewer on back faces of
    /// double-sided materials).
    pub n: V3<R>,
    /// Unit direction toward the eye.
    pub wo: V3<R>,
    /// View depth w (distance along the camera's forward axis).
    pub w: R,
    /// Perspective-correct barycentrics of vertices 1 and 2 (b0 = 1 − b1 − b2).
    pub b1: R,
    pub b2: R,
}

/// Texture-space attributes of a fragment, for materials that sample
/// textures (see [`ResolveContext::surface`](crate::resolve::ResolveContext::surface)).
#[derive(Clone, Copy, Debug)]
pub struct Surface<R: Real> {
    pub uv: [R; 2],
    /// [∂u/∂x, ∂v/∂x] and [∂u/∂y, ∂v/∂y] per pixel: what mip selection needs.
    pub duv_dx: [R; 2],
    pub duv_dy: [R; 2],
    /// Unit tangent (direction of increasing u), orthogonal to the shading
    /// normal; zero where the mesh has no uvs.
    pub tangent: V3<R>,
    /// ±1: bitangent = sign · n × tangent (mirrored uv layouts give −1).
    pub bitangent_sign: R,
    /// The shading frame of the uv tangent where the mesh has one, any
    /// frame around the normal elsewhere.
    pub frame: ShadingFrame<R>,
    /// The vertex colour (linear RGB), interpolated perspective-correctly;
    /// 1 where the scene has no vertex colours.
    pub color: Rgb<R>,
    /// The vertex colour's alpha, likewise.
    pub alpha: R,
}
