//! Normal distribution functions D(m). Each is normalized so that
//! ∫ D(m) (n·m) dω_m = 1 over the hemisphere (core/tests/microfacet.rs
//! checks it numerically).
//!
//! They take cos²θm and sin²θm rather than cos θm: near the peak of a narrow
//! lobe 1 − cos²θm has no correct digits left in f32, while sin²θm = |n × m|²
//! keeps them, and both can be formed from an unnormalized half vector s as
//! (n·s)²/|s|² and |n × s|²/|s|² with one exact division: the rounding of a
//! normalization would otherwise be multiplied by the lobe's sharpness.
//! `brdf::HalfAngles` forms them that way.

use crate::real::Real;

/// GGX / Trowbridge–Reitz NDF: D(m) = α² / (π ((n·m)²(α²−1) + 1)²)   [Walter07]
///
/// The denominator's base is formed as sin²θm + α² cos²θm (module docs).
/// The result is finite for any α > 0, which is why alpha is floored where
/// materials are built.
#[inline(always)]
pub fn d_ggx<R: Real>(alpha: R, cos2_theta_m: R, sin2_theta_m: R) -> R {
    let a2 = alpha * alpha;
    let t = cos2_theta_m.mul_add(a2, sin2_theta_m);
    // t ≥ α² cos²θm + sin²θm ≥ α⁴-ish > 0: `rcp` sees a normal number.
    a2 * (R::PI * t * t).rcp()
}

/// Beckmann NDF: D(m) = exp(−tan²θm / α²) / (π α² cos⁴θm)   [Beckmann63, Walter07]
///
/// tan²θm = sin²θm / cos²θm. Callers pass cos²θm > 0.
#[inline(always)]
pub fn d_beckmann<R: Real>(alpha: R, cos2_theta_m: R, sin2_theta_m: R) -> R {
    let a2 = alpha * alpha;
    let c2 = cos2_theta_m;
    let tan2 = sin2_theta_m / c2;
    (-tan2 / a2).exp() / (R::PI * a2 * c2 * c2)
}

/// Generalized Trowbridge–Reitz: D(m) = c / (1 + (α² − 1) cos²θm)^γ with
/// Burley's normalization [Burley12, App. B]
///
/// c = (γ − 1)(α² − 1) / (π (1 − (α²)^(1−γ)))  for γ ≠ 1,
/// c = (α² − 1) / (π ln α²)                    for γ = 1 (the clearcoat lobe).
///
/// γ = 2 is GGX; large γ approaches Beckmann. Near α = 1 both forms are
/// 0/0 (D is then the uniform 1/π for every γ): α² − 1 is formed as
/// (α − 1)(α + 1) and ln α² as 2 ln1p(α − 1), and 1 − (α²)^(1−γ) as
/// −expm1(−(γ − 1) ln α²), so the ratio keeps its digits in f32 all the way
/// to α = 1, where the limit 1/π is used. The base 1 + (α² − 1)cos²θm is
/// formed as sin²θm + α² cos²θm (module docs). The power base^−γ is
/// base^−⌊γ⌋ by squaring times exp(−frac(γ) ln base): exp(−γ ln base)
/// alone multiplies ln's rounding error by γ (2e-5 relative at γ = 10 in
/// f32). `gamma` > 0 is a per-material constant.
#[inline(always)]
pub fn d_gtr<R: Real>(alpha: R, gamma: f64, cos2_theta_m: R, sin2_theta_m: R) -> R {
    let (g_int, g_frac) = (gamma.floor(), gamma - gamma.floor());
    let gamma = R::splat(gamma);
    let a_m1 = alpha - R::ONE;
    let a2m1 = a_m1 * (alpha + R::ONE);
    let ln_a2 = R::splat(2.0) * a_m1.ln_1p();
    let gm1 = gamma - R::ONE;
    let general = gm1 * a2m1 / (R::PI * -(-gm1 * ln_a2).exp_m1());
    let clearcoat = a2m1 / (R::PI * ln_a2);
    // γ = 1 exactly is the clearcoat form (the general one is 0/0 there).
    let c = R::select(gm1.abs().lt(R::splat(1e-6)), clearcoat, general);
    let c = R::select(a_m1.abs().lt(R::splat(1e-7)), R::FRAC_1_PI, c);
    let a2 = alpha * alpha;
    let base = cos2_theta_m.mul_add(a2, sin2_theta_m);
    let inv = R::ONE / base;
    let mut p = R::ONE;
    let (mut sq, mut n) = (inv, g_int as u32);
    while n > 0 {
        if n & 1 == 1 {
            p *= sq;
        }
        sq *= sq;
        n >>= 1;
    }
    let frac = if g_frac > 0.0 {
        (-R::splat(g_frac) * base.ln()).exp()
    } else {
        R::ONE
    };
    c * p * frac
}
