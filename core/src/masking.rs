//! Smith shadowing-masking: Λ, G1 and the joint G2 (or the visibility form
//! V = G2 / (4 |n·i| |n·o|) when that folds in the BRDF denominator).

use crate::real::Real;
use crate::vec3::V3;

/// Which Smith G2 a microfacet material forms from the two Λ.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Smith {
    Separable,
    HeightCorrelated,
}

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
pub(crate) fn v_smith_ggx_correlated<R: Real>(alpha: R, cos_i: R, cos_o: R) -> R {
    let (s_i, s_o) = (smith_ggx_root(alpha, cos_i), smith_ggx_root(alpha, cos_o));
    v_smith_ggx_correlated_roots(cos_i, cos_o, s_i, s_o)
}

/// √(α² + (1 − α²) cos²θ), the per-direction root of
/// [`v_smith_ggx_correlated`]: a shader computes the view's once per pixel.
#[inline(always)]
pub(crate) fn smith_ggx_root<R: Real>(alpha: R, cos_theta: R) -> R {
    let a2 = alpha * alpha;
    // The hardware root, not x·rsqrt(x): it runs beside the multipliers
    // the light loop is bound by, where the estimate and its Newton step
    // would add to them (docs/PERFORMANCE.md lists the experiment).
    let r = (cos_theta * cos_theta).mul_add(R::ONE - a2, a2);
    r.sqrt()
}

/// [`v_smith_ggx_correlated`] from the two roots of [`smith_ggx_root`]:
/// V = 0.5 / (μo s_i + μi s_o).
#[inline(always)]
pub(crate) fn v_smith_ggx_correlated_roots<R: Real>(cos_i: R, cos_o: R, s_i: R, s_o: R) -> R {
    R::HALF * cos_o.mul_add(s_i, cos_i * s_o).rcp()
}

/// D_GGX · V for the height-correlated Smith GGX of
/// [`v_smith_ggx_correlated_roots`], from the unnormalized half vector s
/// (h = s/|s|, `len2` = |s|²) and with one division where D and V and the
/// angles of h take three:
///
/// D·V = α² / (π t²) · 0.5 / (μo s_i + μi s_o),  t = α² cos²θh + sin²θh,
///
/// (D as [`crate::ndf::d_ggx`] writes it) and t = u / |s|² with
/// u = α² s_z² + s_x² + s_y², so
///
/// D·V = (α² / 2π) |s|⁴ / (u² (μo s_i + μi s_o)).
///
/// u sums squares (no cancellation at the GGX peak, where s_x, s_y → 0
/// and α is small). Everything stays in f32's normal range for |s|² ≥
/// [`crate::brdf::HALF_LEN2_MIN`] (which `HalfAngles` guarantees): u ≥ α²
/// |s|² and the Smith sum ≥ ~2e-7 α (cosine floor 1e-7), so the
/// denominator is ≥ ~2e-7 α⁵ |s|⁴ ≥ 2e-34 at α = ALPHA_MIN.
///
/// A true division, not `rcp` (estimate + Newton step): one operation on
/// the light loop's dependency chain instead of four, and the divider
/// runs beside the multipliers.
#[inline(always)]
pub(crate) fn dv_ggx_correlated<R: Real>(
    alpha: R,
    s: V3<R>,
    len2: R,
    cos_i: R,
    cos_o: R,
    s_i: R,
    s_o: R,
) -> R {
    let a2 = alpha * alpha;
    let u = (s.z * a2).mul_add(s.z, s.x.mul_add(s.x, s.y * s.y));
    let smith = cos_o.mul_add(s_i, cos_i * s_o);
    (a2 * R::splat(0.5 * std::f64::consts::FRAC_1_PI)) * (len2 * len2) / (u * u * smith)
}

/// [`dv_ggx_correlated`] about a unit normal `n` other than +Z (a
/// clearcoat's own normal): s_z becomes n·s and s_x² + s_y² becomes
/// |n × s|² (a sum of squares, so no cancellation at the peak either);
/// `cos_i`, `cos_o` and the roots are the cosines against `n`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn dv_ggx_correlated_about<R: Real>(
    alpha: R,
    n: V3<R>,
    s: V3<R>,
    len2: R,
    cos_i: R,
    cos_o: R,
    s_i: R,
    s_o: R,
) -> R {
    let a2 = alpha * alpha;
    let nz = n.dot(s);
    let c = n.cross(s);
    let u = (nz * a2).mul_add(nz, c.length_squared());
    let smith = cos_o.mul_add(s_i, cos_i * s_o);
    (a2 * R::splat(0.5 * std::f64::consts::FRAC_1_PI)) * (len2 * len2) / (u * u * smith)
}

/// Smith Λ for Beckmann [Walter07, eq. 25; Heitz14, eq. 83]: with
/// a = 1 / (α tan θ) = cos θ / (α sin θ),
///
/// Λ = (erf(a) − 1) / 2 + exp(−a²) / (2 a √π).
///
/// `cos_theta` in (0, 1]; at cos θ = 1, a = ∞ and Λ = 0 (the formula's
/// terms are guarded so no inf·0 appears).
#[inline(always)]
pub(crate) fn lambda_beckmann<R: Real>(alpha: R, cos_theta: R) -> R {
    let sin_theta = (R::ONE - cos_theta * cos_theta).max(R::ZERO).sqrt();
    // a ≥ 1e-30 and finite: cap at 1e15, far past where Λ underflows to 0.
    let a = (cos_theta / (alpha * sin_theta)).min(R::splat(1e15));
    let inv_sqrt_pi = R::splat(0.564_189_583_547_756_3);
    let lambda = (erf(a) - R::ONE) * R::HALF + (-(a * a)).exp() * inv_sqrt_pi * R::HALF / a;
    lambda.max(R::ZERO)
}

/// The error function, Abramowitz & Stegun 7.1.26 (|error| ≤ 1.5e-7), odd
/// extension for x < 0.   \[AS64\]
#[inline(always)]
pub(crate) fn erf<R: Real>(x: R) -> R {
    let ax = x.abs();
    let t = R::ONE / R::splat(0.327_591_1).mul_add(ax, R::ONE);
    let poly = t * R::splat(1.061_405_429)
        .mul_add(t, R::splat(-1.453_152_027))
        .mul_add(t, R::splat(1.421_413_741))
        .mul_add(t, R::splat(-0.284_496_736))
        .mul_add(t, R::splat(0.254_829_592));
    let y = R::ONE - poly * (-(ax * ax)).exp();
    R::select(x.lt(R::ZERO), -y, y)
}

/// Smith G1 = 1 / (1 + Λ).   [Heitz14, eq. 43]
#[inline(always)]
pub(crate) fn g1_smith<R: Real>(lambda: R) -> R {
    R::ONE / (R::ONE + lambda)
}

/// Separable (uncorrelated) Smith G2 = G1(i) G1(o).   [Heitz14, eq. 98]
#[inline(always)]
pub(crate) fn g2_separable<R: Real>(lambda_i: R, lambda_o: R) -> R {
    g1_smith(lambda_i) * g1_smith(lambda_o)
}

/// Height-correlated Smith G2 = 1 / (1 + Λ(i) + Λ(o)).   [Heitz14, eq. 99]
#[inline(always)]
pub(crate) fn g2_height_correlated<R: Real>(lambda_i: R, lambda_o: R) -> R {
    R::ONE / (R::ONE + lambda_i + lambda_o)
}

/// Smith Λ for anisotropic GGX [Heitz14, eq. 86]: with the projected
/// roughness α(φ)² = αx² cos²φ + αy² sin²φ,
///
/// Λ(v) = (−1 + √(1 + α(φ)² tan²θ)) / 2 = (√(vz² + αx² vx² + αy² vy²) / vz − 1) / 2
///
/// for a unit local v (tangent x, bitangent y, normal z); the second form
/// avoids tan²θ (it overflows as vz → 0). `cos_theta` = vz must be > 0
/// (callers pass the floored cosine).
#[inline(always)]
pub(crate) fn lambda_ggx_aniso<R: Real>(alpha_x: R, alpha_y: R, vx: R, vy: R, cos_theta: R) -> R {
    let (ax, ay) = (alpha_x * vx, alpha_y * vy);
    let s = ax.mul_add(ax, ay.mul_add(ay, cos_theta * cos_theta)).sqrt();
    (s / cos_theta - R::ONE) * R::HALF
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::{ALPHA_MIN, HALF_LEN2_MIN};
    use crate::ndf::d_ggx;

    /// The fused D·V from the unnormalized half vector equals D times V
    /// computed from h's angles, at the extremes too: the smallest α,
    /// cosines at their 1e-7 floor, the GGX peak and grazing, and |s|²
    /// from HALF_LEN2_MIN to 4.
    #[test]
    fn fused_dv_is_d_times_v() {
        let alphas = [ALPHA_MIN as f64, 0.01, 0.2, 0.6, 1.0];
        let cosines = [1e-7, 1e-3, 0.1, 0.5, 0.9, 1.0];
        let lengths = [HALF_LEN2_MIN.sqrt(), 0.3, 1.0, 2.0];
        let mut worst32 = 0.0f64;
        for &a in &alphas {
            for &cos_h in &cosines {
                let (c2, s2) = (cos_h * cos_h, 1.0 - cos_h * cos_h);
                let sin_h = s2.sqrt();
                for (k, &len) in lengths.iter().enumerate() {
                    // h at azimuth 0.7 k radians, scaled to |s| = len.
                    let phi = 0.7 * k as f64;
                    let s = V3::new(sin_h * phi.cos(), sin_h * phi.sin(), cos_h) * len;
                    let s32 = V3::new(s.x as f32, s.y as f32, s.z as f32);
                    let len2_32 = s32.length_squared();
                    for &ci in &cosines {
                        for &co in &cosines {
                            let (si, so) = (smith_ggx_root(a, ci), smith_ggx_root(a, co));
                            let want =
                                d_ggx(a, c2, s2) * v_smith_ggx_correlated_roots(ci, co, si, so);
                            let got = dv_ggx_correlated(a, s, len * len, ci, co, si, so);
                            assert!(
                                (got - want).abs() <= 1e-12 * want,
                                "f64 α={a} cosθh={cos_h} |s|={len} μi={ci} μo={co}: {got} vs {want}"
                            );
                            let f = |x: f64| x as f32;
                            let (si32, so32) =
                                (smith_ggx_root(f(a), f(ci)), smith_ggx_root(f(a), f(co)));
                            let got32 =
                                dv_ggx_correlated(f(a), s32, len2_32, f(ci), f(co), si32, so32)
                                    as f64;
                            assert!(got32.is_finite() && got32 > 0.0, "f32 {got32}");
                            worst32 = worst32.max((got32 - want).abs() / want);
                        }
                    }
                }
            }
        }
        // f32 inputs rounded (≤ 6e-8 each; s's components relative to
        // |s|, so u's terms carry it), the Smith roots and a dozen roundings.
        assert!(worst32 < 3e-6, "worst f32 relative error {worst32:e}");
    }
}
