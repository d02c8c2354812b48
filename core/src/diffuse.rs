//! Diffuse lobes.

use crate::real::Real;
use crate::vec3::Rgb;

/// Lambertian BRDF f = ρ / π (no cosine folded in).   [Lambert1760]
#[inline(always)]
pub fn f_lambert<R: Real>(albedo: Rgb<R>) -> Rgb<R> {
    albedo * R::FRAC_1_PI
}
