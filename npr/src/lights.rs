//! The scene's lights as NPR shaders read them: per light, a unit
//! direction toward it and the irradiance on a surface facing it, so a
//! stylized shader can threshold the cosine itself (toon bands) or sum a
//! Lambertian luminance (hatching).
//!
//! Polygon lights are reduced to their vector irradiance \[Arvo94\]:
//! F = (1/2π) Σₖ θₖ ĉₖ over the edges (θₖ the angle the edge subtends,
//! ĉₖ the unit normal of the plane through it and the shading point), so
//! the irradiance on a plane of normal n is π L (F·n). The shaders see the
//! direction F/|F| and the irradiance π L |F|: exact for a polygon wholly
//! above the surface's horizon, and the cosine a toon ramp thresholds is the
//! one toward the polygon's "centre of light". (Parts of a polygon below
//! the horizon are not clipped away.)

use specula_core::light::{
    range_window, spot_attenuation, spot_scale_offset, Light, MAX_POLYGON_VERTICES,
};
use specula_core::{Real, Rgb, V3};
use specula_raster::{ShadeEnv, ShadeInput};

/// Squared distances below this are treated as this (as lit.rs does).
const MIN_DIST2: f64 = 1e-8;

/// arccos x for x in [−1, 1] within 7e-5 rad: √(1 − |x|) times a cubic
/// in |x| [Abramowitz64, 4.4.45], reflected for x < 0 (π − arccos(−x)).
/// Input is clamped to [−1, 1], so rounding past 1 gives 0, not NaN.
#[inline(always)]
pub fn acos_approx<R: Real>(x: R) -> R {
    let x = x.clamp(-R::ONE, R::ONE);
    let a = x.abs();
    let p = a
        .mul_add(R::splat(-0.018_729_3), R::splat(0.074_261_0))
        .mul_add(a, R::splat(-0.212_114_4))
        .mul_add(a, R::splat(1.570_728_8));
    let r = (R::ONE - a).max(R::ZERO).sqrt() * p;
    R::select(x.lt(R::ZERO), R::PI - r, r)
}

/// Calls `f(wi, e)` for every light: `wi` the unit world direction toward
/// it from the lanes' points `p`, `e` the irradiance on a surface facing
/// it (RGB). Zero-irradiance lanes (behind a polygon light) keep a finite
/// direction.
#[inline(always)]
pub fn for_each_light<R: Real>(p: V3<R>, env: &ShadeEnv, mut f: impl FnMut(V3<R>, Rgb<R>)) {
    for light in env.lights {
        match light {
            Light::Point {
                position,
                intensity,
                range,
            } => {
                let to = V3::from_f32(*position) - p;
                let d2 = to.length_squared().max(R::splat(MIN_DIST2));
                let inv_d = d2.rsqrt();
                let mut k = inv_d * inv_d;
                if range.is_finite() {
                    k *= range_window(d2, *range);
                }
                f(to * inv_d, V3::from_f32(*intensity) * k);
            }
            Light::Spot {
                position,
                direction,
                intensity,
                cos_inner,
                cos_outer,
                range,
            } => {
                let to = V3::from_f32(*position) - p;
                let d2 = to.length_squared().max(R::splat(MIN_DIST2));
                let inv_d = d2.rsqrt();
                let wi = to * inv_d;
                let (scale, offset) = spot_scale_offset(*cos_inner, *cos_outer);
                let cd = -V3::from_f32(*direction).dot(wi);
                let mut k = inv_d * inv_d * spot_attenuation(cd, scale, offset);
                if range.is_finite() {
                    k *= range_window(d2, *range);
                }
                f(wi, V3::from_f32(*intensity) * k);
            }
            Light::Directional {
                to_light,
                irradiance,
            } => f(V3::from_f32(*to_light), V3::from_f32(*irradiance)),
            Light::Polygon {
                vertices,
                radiance,
                two_sided,
                ..
            } => {
                let (dir, scale) = polygon_irradiance(p, vertices, *two_sided);
                f(dir, V3::from_f32(*radiance) * scale);
            }
        }
    }
}

/// [`for_each_light`] at a packet, each light's irradiance times its
/// shadow factor at the packet's points where it has a shadow map.
#[inline(always)]
pub(crate) fn for_each_light_shadowed<R: Real>(
    input: &ShadeInput<R>,
    env: &ShadeEnv,
    mut f: impl FnMut(V3<R>, Rgb<R>),
) {
    let frag = input.frag;
    let Some(shadows) = env.shadows else {
        return for_each_light(frag.p, env, f);
    };
    let mut k = 0;
    for_each_light(frag.p, env, |wi, e| {
        let e = match shadows.light(k) {
            Some(s) => e * input.light_visibility(k, s, &e),
            None => e,
        };
        k += 1;
        f(wi, e)
    });
}

/// The direction of the vector irradiance of a unit-radiance polygon at
/// `p` and its magnitude π|F| (module docs); zero where `p` is behind the
/// emitting side of a one-sided light (a two-sided light emits from both,
/// and its direction is then toward the polygon from either side).
#[inline(always)]
fn polygon_irradiance<R: Real>(p: V3<R>, vertices: &[[f32; 3]], two_sided: bool) -> (V3<R>, R) {
    let n = vertices.len().min(MAX_POLYGON_VERTICES);
    let mut v = [V3::zero(); MAX_POLYGON_VERTICES];
    for (v, q) in v.iter_mut().zip(vertices) {
        *v = (V3::from_f32(*q) - p).normalize_or(V3::zero());
    }
    let mut sum = V3::zero();
    let mut centre = V3::zero();
    for k in 0..n {
        let (a, b) = (v[k], v[(k + 1) % n]);
        let theta = acos_approx(a.dot(b));
        sum += a.cross(b).normalize_or(V3::zero()) * theta;
        centre += V3::from_f32(vertices[k]);
    }
    // Counter-clockwise seen from the front (light.rs), Σ θ ĉ points away
    // from the polygon; toward it is the negation.
    let f = sum * R::splat(-0.5 * core::f64::consts::FRAC_1_PI);
    let to_centre = centre * R::splat(1.0 / n as f64) - p;
    let len2 = f.length_squared();
    let toward = f.dot(to_centre).gt(R::ZERO);
    let len = len2.sqrt();
    let dir = f.normalize_or(V3::new(R::ZERO, R::ZERO, R::ONE));
    if two_sided {
        // Seen from behind, Σ θ ĉ turns around: flip it back toward the polygon.
        let dir = V3::select(toward, dir, -dir);
        return (
            dir,
            R::select(len2.gt(R::splat(1e-30)), len * R::PI, R::ZERO),
        );
    }
    let front = toward & len2.gt(R::splat(1e-30));
    (dir, R::select(front, len * R::PI, R::ZERO))
}
