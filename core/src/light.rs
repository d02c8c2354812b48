//! Light sources as the shading pass sees them (world space, linear RGB).
//! The uniform environment is not here: it is the scene's `environment`,
//! met through each model's directional albedo.

use crate::real::Real;
use crate::vec3::V3;

/// Most vertices a polygon light may have.
pub const MAX_POLYGON_VERTICES: usize = 16;

#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Radiant intensity I (W/sr) at `position`; irradiance I / d² (inverse
    /// square), times [`range_window`] when `range` is finite.
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
        /// Distance beyond which the light is off (`f32::INFINITY`: never).
        range: f32,
    },
    /// A point light restricted to a cone: radiant intensity I (W/sr) along
    /// `direction` within `cos_inner`, falling off to zero at `cos_outer`
    /// by [`spot_attenuation`] (KHR_lights_punctual's curve); irradiance
    /// I · attenuation / d², times [`range_window`] when `range` is finite.
    Spot {
        position: [f32; 3],
        /// Unit direction the cone points (from the light into the scene).
        direction: [f32; 3],
        intensity: [f32; 3],
        /// Cosines of the inner and outer half-angles, cos_inner > cos_outer.
        cos_inner: f32,
        cos_outer: f32,
        /// Distance beyond which the light is off (`f32::INFINITY`: never).
        range: f32,
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

/// The scale and offset of [`spot_attenuation`]'s ramp on cos θ:
/// s = 1 / max(0.001, cos θinner − cos θouter), o = −cos θouter · s
/// (KHR_lights_punctual, "Inner and Outer Cone Angles"; the 0.001 floor
/// keeps s finite when the two angles meet).
pub fn spot_scale_offset(cos_inner: f32, cos_outer: f32) -> (f32, f32) {
    let scale = 1.0 / (cos_inner - cos_outer).max(0.001);
    (scale, -cos_outer * scale)
}

/// A spot light's angular attenuation at cd = cos of the angle between its
/// axis and the direction from it to the shaded point:
/// a = saturate(cd · s + o)², with (s, o) from [`spot_scale_offset`]: 1
/// inside the inner cone, 0 outside the outer one (KHR_lights_punctual).
#[inline(always)]
pub fn spot_attenuation<R: Real>(cd: R, scale: f32, offset: f32) -> R {
    spot_attenuation_lanes(cd, R::splat(scale as f64), R::splat(offset as f64))
}

/// [`spot_attenuation`] with the scale and offset per lane (lanes of
/// different lights).
#[inline(always)]
pub fn spot_attenuation_lanes<R: Real>(cd: R, scale: R, offset: R) -> R {
    let a = cd.mul_add(scale, offset).clamp(R::ZERO, R::ONE);
    a * a
}

/// The smooth cutoff a finite `range` puts on the inverse-square law, as a
/// factor of I / d²: clamp(1 − (d / range)⁴, 0, 1) (KHR_lights_punctual,
/// "Range Property"), from d² so no square root is needed.
#[inline(always)]
pub fn range_window<R: Real>(d2: R, range: f32) -> R {
    range_window_lanes(d2, range_squared(range))
}

/// `range`² as [`range_window`] broadcasts it.
#[inline(always)]
pub fn range_squared<R: Real>(range: f32) -> R {
    R::splat((range as f64) * (range as f64))
}

/// [`range_window`] with the squared range per lane (lanes of different
/// lights; [`range_squared`]).
#[inline(always)]
pub fn range_window_lanes<R: Real>(d2: R, range2: R) -> R {
    let q = d2 / range2;
    (R::ONE - q * q).clamp(R::ZERO, R::ONE)
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
