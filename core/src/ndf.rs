//! Normal distribution functions D(m). Each is normalized so that
//! ∫ D(m) (n·m) dω_m = 1 over the hemisphere (tests/ndf checks it numerically).

use crate::real::Real;

/// GGX / Trowbridge–Reitz NDF: D(m) = α² / (π ((n·m)²(α²−1) + 1)²)   [Walter07]
///
/// Takes sin²θm as well as cos θm and forms the denominator as
/// sin²θm + α² cos²θm: near the peak of a narrow lobe 1 − cos²θm has no
/// correct digits left in f32, while sin²θm = |n × m|² keeps them. Callers
/// pass `cos_theta_m` ≥ 0; the result is finite for any α > 0, which is why
/// alpha is floored where materials are built.
#[inline(always)]
pub fn d_ggx<R: Real>(alpha: R, cos_theta_m: R, sin2_theta_m: R) -> R {
    let a2 = alpha * alpha;
    let t = (cos_theta_m * cos_theta_m).mul_add(a2, sin2_theta_m);
    // t ≥ α² cos²θm + sin²θm ≥ α⁴-ish > 0: `rcp` sees a normal number.
    a2 * (R::PI * t * t).rcp()
}
