//! A point, spot or directional light's term in the light loop, for the
//! f32x8 light loop of `lit.rs` (one packet) and the packet pairs of
//! `packet_pairs.rs` (two packets, one in each half of sixteen lanes):
//! one source, so both do the same operations per lane.

use crate::fragment::Fragment;
use specula_core::light::{
    range_squared, range_window_lanes, spot_attenuation_lanes, spot_scale_offset, Light,
};
use specula_core::{Brdf, Real, Rgb, ShadingFrame, V3};

/// Squared distances below this are treated as this, so a light lying on a
/// surface gives a large finite value instead of inf·0 = NaN.
const MIN_DIST2: f64 = 1e-8;

/// A point or spot light's parameters as lanes: one light broadcast
/// ([`Punctual::of`]).
struct Punctual<R: Real> {
    position: V3<R>,
    intensity: V3<R>,
    /// A spot light's axis and [`spot_scale_offset`]'s scale and offset.
    cone: Option<(V3<R>, R, R)>,
    /// A finite range, squared ([`range_squared`]).
    range2: Option<R>,
}

impl<R: Real> Punctual<R> {
    /// `light`'s, if it is a point or spot light.
    #[inline(always)]
    fn of(light: &Light) -> Option<Punctual<R>> {
        let (position, intensity, range, cone) = match light {
            Light::Point {
                position,
                intensity,
                range,
            } => (position, intensity, *range, None),
            Light::Spot {
                position,
                direction,
                intensity,
                cos_inner,
                cos_outer,
                range,
            } => {
                let (scale, offset) = spot_scale_offset(*cos_inner, *cos_outer);
                let k = |x: f32| R::splat(x as f64);
                (
                    position,
                    intensity,
                    *range,
                    Some((V3::from_f32(*direction), k(scale), k(offset))),
                )
            }
            _ => return None,
        };
        Some(Punctual {
            position: V3::from_f32(*position),
            intensity: V3::from_f32(*intensity),
            cone,
            range2: range.is_finite().then(|| range_squared(range)),
        })
    }
}

/// A point light, or with a cone a spot light: I / d² · cos θi · f,
/// times the range window and the cone's attenuation, as f and the
/// factor it is multiplied by (the caller adds f · factor to its sum with
/// one fused multiply-add per channel).
#[inline(always)]
fn punctual_part<B: Brdf, R: Real>(
    brdf: &B,
    prepared: &B::Prepared<R>,
    frag: &Fragment<R>,
    frame: &ShadingFrame<R>,
    light: &Punctual<R>,
) -> (Rgb<R>, Rgb<R>) {
    let to_light = light.position - frag.p;
    let d2 = to_light.length_squared().max(R::splat(MIN_DIST2));
    let inv_d = d2.rsqrt();
    // The light loop is bound by its dependency chains (it is not
    // short of multipliers): the unnormalized vector goes to the
    // local frame while its rsqrt is computed, the model folds the
    // 1/d into its first step, and the factors of f are multiplied
    // into I / d² · cos θi before f is ready, so f reaches the sum
    // in one step.
    let v = frame.to_local(to_light);
    let mut k = (v.z * inv_d).max(R::ZERO) * (inv_d * inv_d);
    if let Some((axis, scale, offset)) = light.cone {
        // cd: the axis against the direction from the light to the point.
        let cd = -axis.dot(to_light) * inv_d;
        k *= spot_attenuation_lanes(cd, scale, offset);
    }
    if let Some(range2) = light.range2 {
        k *= range_window_lanes(d2, range2);
    }
    let radiance = light.intensity * k;
    (brdf.f_local_scaled(prepared, v, inv_d), radiance)
}

/// `acc` plus a point or directional light's reflected radiance (plus
/// nothing for a polygon light, which `lit.rs`'s `lights_from_polygon`
/// shades).
#[inline(always)]
pub(crate) fn add_delta_light<B: Brdf, R: Real>(
    brdf: &B,
    prepared: &B::Prepared<R>,
    frag: &Fragment<R>,
    frame: &ShadingFrame<R>,
    light: &Light,
    acc: Rgb<R>,
) -> Rgb<R> {
    if let Some(light) = Punctual::of(light) {
        let (f, radiance) = punctual_part(brdf, prepared, frag, frame, &light);
        return f.mul_elem_add(radiance, acc);
    }
    match light {
        Light::Directional {
            to_light,
            irradiance,
        } => {
            let wi = frame.to_local(V3::from_f32(*to_light));
            let f_cos = brdf.f_cos_local(prepared, wi);
            f_cos.mul_elem_add(V3::from_f32(*irradiance), acc)
        }
        // Point and spot lights are shaded above.
        Light::Point { .. } | Light::Spot { .. } | Light::Polygon { .. } => acc,
    }
}
