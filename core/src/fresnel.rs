//! Fresnel reflectance F.

use crate::real::Real;
use crate::vec3::Rgb;

/// Schlick's weight (1 − cos θ)⁵, the part of [`f_schlick`] that does not
/// depend on F0. `cos_theta` is clamped to [0, 1] so a lane slightly below
/// the horizon does not raise a weight above 1.   [Schlick94]
#[inline(always)]
pub fn schlick_weight<R: Real>(cos_theta: R) -> R {
    let m = (R::ONE - cos_theta).clamp(R::ZERO, R::ONE);
    let m2 = m * m;
    m2 * m2 * m
}

/// Schlick's approximation F = F0 + (1 − F0)(1 − cos θ)⁵, per RGB channel.   [Schlick94]
#[inline(always)]
pub fn f_schlick<R: Real>(f0: Rgb<R>, cos_theta: R) -> Rgb<R> {
    let w = schlick_weight(cos_theta);
    Rgb::new(
        (R::ONE - f0.x).mul_add(w, f0.x),
        (R::ONE - f0.y).mul_add(w, f0.y),
        (R::ONE - f0.z).mul_add(w, f0.z),
    )
}
