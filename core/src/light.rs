//! Light sources as the shading pass sees them (world space, linear RGB).
//! The uniform environment is not here: it is the scene's `environment`,
//! met through each model's directional albedo.

use crate::real::Real;
use crate::vec3::V3;

/// Most vertices a polygon light may have.
pub const MAX_POLYGON_VERTICES: usize = 16;

#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Radiant intensity I (W/sr) at `position`; irradiance I / d² (inverse square).
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
    },
    /// Irradiance E (W/m²) on a surface facing the light; `to_light` is the
    /// unit direction from the scene toward the light.
    Directional {
        to_light: [f32; 3],
        irradiance: [f32; 3],
    },
    /// A planar simple polygon (convex or not) of uniform radiance L
    /// (W/m²/sr), emitting from its front side, the side from which its
    /// vertices run counter-clockwise (like front faces), or from both
    /// sides. Validated where scenes load.
    Polygon {
        vertices: Vec<[f32; 3]>,
        radiance: [f32; 3],
        two_sided: bool,
        /// How materials integrate it.
        method: AreaMethod,
    },
}

/// How polygon lights are integrated (the scene's `area_lights`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AreaMethod {
    /// Linearly transformed cosines: closed form, per pixel \[Heitz16\].
    #[default]
    Ltc,
    /// The converged quadrature of `ltc::reference` (slow; for comparing).
    Reference,
}

/// A polygon light seen from the shading points of a packet: its vertices
/// relative to each lane's point, in that lane's local shading frame (not
/// normalized, not clipped to the horizon), in the light's order.
#[derive(Clone, Copy, Debug)]
pub struct PolygonLocal<R> {
    pub vertices: [V3<R>; MAX_POLYGON_VERTICES],
    pub len: usize,
    /// The light emits from both sides.
    pub two_sided: bool,
}

impl<R: Real> PolygonLocal<R> {
    pub fn vertices(&self) -> &[V3<R>] {
        &self.vertices[..self.len]
    }
}
