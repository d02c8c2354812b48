//! Normal distribution functions D(m). Each is normalized so that
//! ∫ D(m) (n·m) dω_m = 1 over the hemisphere (tests/ndf checks it numerically).

use crate::real::Real;

/// GGX / Trowbridge–Reitz NDF: D(m) = α² / (π ((n·m)²(α²−1) + 1)²)   [Walter07]
///
/// Callers pass `cos_theta_m` > 0; the formula itself stays finite for any
/// α > 0, which is why alpha is floored where materials are built.
#[inline(always)]
pub fn d_ggx<R: Real>(alpha: R, cos_theta_m: R) -> R {
    let a2 = alpha * alpha;
    let t = (cos_theta_m * cos_theta_m).mul_add(a2 - R::ONE, R::ONE);
    a2 / (R::PI * t * t)
}
