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

/// Which NDF a microfacet material uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ndf {
    Ggx,
    Beckmann,
    /// Generalized Trowbridge–Reitz with exponent γ > 0 (γ = 2 is GGX).
    Gtr {
        gamma: f32,
    },
}

/// GGX / Trowbridge–Reitz NDF: D(m) = α² / (π ((n·m)²(α²−1) + 1)²)   \[Walter07\]
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
pub(crate) fn d_beckmann<R: Real>(alpha: R, cos2_theta_m: R, sin2_theta_m: R) -> R {
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
/// γ = 2 is GGX; large γ approaches Beckmann. `gamma` > 0 is a per-material
/// constant.
///
/// Evaluated as the peak value times the falloff, so nothing overflows:
/// with base = 1 + (α² − 1)cos²θm = sin²θm + α² cos²θm = α² r,
///
/// D = c α^(−2γ) · r^(−γ),  r = cos²θm + sin²θm / α² ≥ 1,
/// c α^(−2γ) = D(n) = (γ − 1)(α² − 1) / (π α² expm1((γ − 1) ln α²)).
///
/// Formed directly, c and base^(−γ) under- and overflow in f32 at small α
/// and large γ (c (α²)^(−γ) with (α²)^(1−γ) = 1e41 at α = 0.005, γ = 10):
/// 0 · inf = NaN. Here expm1 of a non-positive argument (γ > 1) lies in
/// (−1, 0], and for γ < 1 its argument is at most |γ − 1| · |ln α²|, so the
/// peak is finite for α ≥ ALPHA_MIN; r^(−γ) ∈ (0, 1] underflows
/// gracefully. At γ = 1 the ratio (γ − 1)/expm1((γ − 1) ln α²) is its limit
/// 1/ln α². Near α = 1 the peak is 0/0 (D is then the uniform 1/π for
/// every γ): α² − 1 is formed as (α − 1)(α + 1) (exact for α ≥ ½) and
/// ln α² as 2 ln α, both relatively accurate, so the ratio keeps its digits
/// in f32 all the way to α = 1, where the limit 1/π is used. r^(−γ) is r^(−⌊γ⌋) by squaring
/// times exp(−frac(γ) ln r): exp(−γ ln r) alone multiplies ln's rounding
/// error by γ. Within 1e-5 relative of an f64 oracle for γ ∈ [0.5, 100],
/// α ∈ [1e-3, 1] (core/tests/numerics.rs).
#[inline(always)]
pub fn d_gtr<R: Real>(alpha: R, gamma: f64, cos2_theta_m: R, sin2_theta_m: R) -> R {
    let (g_int, g_frac) = (gamma.floor(), gamma - gamma.floor());
    let gm1 = gamma - 1.0;
    let a2 = alpha * alpha;
    let a_m1 = alpha - R::ONE;
    let a2m1 = a_m1 * (alpha + R::ONE);
    // 2 ln α, not 2 ln1p(α − 1): α − 1 rounds away the digits of a small α
    // (1.3e-5 relative error in D at α = 0.002), and ln keeps its relative
    // accuracy next to 1.
    let ln_a2 = R::splat(2.0) * alpha.ln();
    // (γ − 1) / expm1((γ − 1) ln α²); NaN only at α = 1 (0/0), selected away.
    let ratio = if gm1 == 0.0 {
        R::ONE / ln_a2
    } else {
        R::splat(gm1) / (R::splat(gm1) * ln_a2).exp_m1()
    };
    let peak = a2m1 * ratio / (R::PI * a2);
    let peak = R::select(a_m1.abs().lt(R::splat(1e-7)), R::FRAC_1_PI, peak);
    // r^(−γ) has condition number γ: one f32 rounding of r alone costs
    // 100 · 6e-8 = 6e-6 at γ = 100. So r is carried as r_hi + r_lo (α²'s and
    // the quotient's rounding errors by FMA, the sum's by two-sum), 1/r_hi
    // is raised to ⌊γ⌋ by squaring (times exp(−frac(γ) ln r_hi)), and the
    // power is corrected by (1 + e)^(−γ) ≈ 1 − γ e, where r/r_hi = 1 + e
    // (|e| ≲ 1e-7, so the dropped e² term is 1e-10).
    let a2_lo = alpha.mul_add(alpha, -a2);
    let q = sin2_theta_m / a2;
    let q_res = (-q).mul_add(a2, sin2_theta_m);
    let q_lo = (-q).mul_add(a2_lo, q_res) / a2;
    let r_hi = q + cos2_theta_m;
    let b = r_hi - q;
    let r_lo = ((q - (r_hi - b)) + (cos2_theta_m - b)) + q_lo;
    let inv = R::ONE / r_hi;
    let e = inv.mul_add(r_hi, -R::ONE) + inv * r_lo;
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
        (-R::splat(g_frac) * r_hi.ln()).exp()
    } else {
        R::ONE
    };
    peak * p * frac * (-R::splat(gamma)).mul_add(e, R::ONE)
}

/// Anisotropic GGX (Burley's GTR2 with two roughnesses) along the tangent
/// frame: D(m) = 1 / (π αx αy (mx²/αx² + my²/αy² + mz²)²)   [Burley12, App. B; Heitz14]
///
/// Takes the squared local components of the unit microfacet normal m
/// (tangent x, bitangent y, normal z): the caller forms them from an
/// unnormalized half vector s as s_k² / |s|² (see the module docs). With
/// αx = αy = α it is [`d_ggx`]. The base is ≥ mz² + (mx² + my²) / max(α)²,
/// > 0 for any unit m and finite α > 0.
#[inline(always)]
pub(crate) fn d_ggx_aniso<R: Real>(alpha_x: R, alpha_y: R, mx2: R, my2: R, mz2: R) -> R {
    let t = (mx2 / (alpha_x * alpha_x)).mul_add(R::ONE, my2 / (alpha_y * alpha_y)) + mz2;
    R::ONE / (R::PI * alpha_x * alpha_y * t * t)
}
