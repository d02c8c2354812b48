//! Smith shadowing-masking: Λ, G1 and the joint G2 (or the visibility form
//! V = G2 / (4 |n·i| |n·o|) when that folds in the BRDF denominator).

use crate::real::Real;

/// Smith Λ for GGX: Λ(θ) = (−1 + √(1 + α² tan²θ)) / 2   [Walter07, Heitz14]
///
/// Written as (√(α² + (1−α²) cos²θ) / cos θ − 1) / 2, which avoids forming
/// tan²θ (it overflows as cos θ → 0). `cos_theta` must be > 0.
#[inline(always)]
pub fn lambda_ggx<R: Real>(alpha: R, cos_theta: R) -> R {
    let a2 = alpha * alpha;
    let s = (cos_theta * cos_theta).mul_add(R::ONE - a2, a2).sqrt();
    (s / cos_theta - R::ONE) * R::HALF
}

/// Height-correlated Smith G2 = 1 / (1 + Λ(i) + Λ(o)) for GGX, already divided
/// by the microfacet denominator 4 (n·i)(n·o):
///
/// V = G2 / (4 μi μo) = 0.5 / (μo √(α² + (1−α²) μi²) + μi √(α² + (1−α²) μo²))
///
/// (substitute Λ above into G2 and simplify).   [Heitz14, eq. 99]
/// `cos_i`, `cos_o` must be > 0.
#[inline(always)]
pub fn v_smith_ggx_correlated<R: Real>(alpha: R, cos_i: R, cos_o: R) -> R {
    let a2 = alpha * alpha;
    let one_minus_a2 = R::ONE - a2;
    // Both radicands are ≥ α² > 0, so √x = x·rsqrt(x) is safe.
    let r_i = (cos_i * cos_i).mul_add(one_minus_a2, a2);
    let r_o = (cos_o * cos_o).mul_add(one_minus_a2, a2);
    let s_i = r_i * r_i.rsqrt();
    let s_o = r_o * r_o.rsqrt();
    R::HALF * cos_o.mul_add(s_i, cos_i * s_o).rcp()
}
