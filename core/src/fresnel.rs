//! Fresnel reflectance F.

use crate::real::Real;
use crate::vec3::Rgb;

/// Which Fresnel term a microfacet material uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fresnel {
    Schlick {
        f0: [f32; 3],
    },
    /// Relative IOR (inside over outside); below 1 total internal
    /// reflection occurs past the critical angle.
    Dielectric {
        ior: f32,
    },
    /// Complex IOR η + iκ per channel.
    Conductor {
        eta: [f32; 3],
        k: [f32; 3],
    },
}

/// Schlick's weight (1 − cos θ)⁵, the part of [`f_schlick`] that does not
/// depend on F0. `cos_theta` is clamped to [0, 1] so a lane slightly below
/// the horizon does not raise a weight above 1.   \[Schlick94\]
#[inline(always)]
pub(crate) fn schlick_weight<R: Real>(cos_theta: R) -> R {
    let m = (R::ONE - cos_theta).clamp(R::ZERO, R::ONE);
    let m2 = m * m;
    m2 * m2 * m
}

/// [`schlick_weight`] at cos θd = |wi + wo| / 2 (the Fresnel angle of the
/// half vector), from `len` = |wi + wo| ∈ [0, 2] ([`crate::brdf::HalfAngles`]).
/// 1 − len/2 is one fused step, and only its lower clamp can act (len ≥ 0):
/// two fewer operations on the light loop's longest dependency chain,
/// which bounds it. Within one rounding of `schlick_weight(len / 2)`.
#[inline(always)]
pub(crate) fn schlick_weight_half<R: Real>(len: R) -> R {
    let m = len.mul_add(-R::HALF, R::ONE).max(R::ZERO);
    let m2 = m * m;
    m2 * m2 * m
}

/// Schlick's approximation F = F0 + (1 − F0)(1 − cos θ)⁵, per RGB channel.   \[Schlick94\]
#[inline(always)]
pub fn f_schlick<R: Real>(f0: Rgb<R>, cos_theta: R) -> Rgb<R> {
    let w = schlick_weight(cos_theta);
    Rgb::new(
        (R::ONE - f0.x).mul_add(w, f0.x),
        (R::ONE - f0.y).mul_add(w, f0.y),
        (R::ONE - f0.z).mul_add(w, f0.z),
    )
}

/// R0 = ((η − 1) / (η + 1))²: normal-incidence reflectance of a dielectric
/// with relative IOR η, for use with [`f_schlick`].
pub fn r0_from_ior(eta: f64) -> f64 {
    let r = (eta - 1.0) / (eta + 1.0);
    r * r
}

/// Exact dielectric Fresnel reflectance for unpolarized light: the mean of
/// the s- and p-polarized reflectances [BornWolf99, §1.5; Walter07, eq. 22],
///
/// R_s = ((cos θi − η cos θt) / (cos θi + η cos θt))²,
/// R_p = ((η cos θi − cos θt) / (η cos θi + cos θt))², F = (R_s + R_p) / 2,
///
/// with η = n_t / n_i and sin²θt = (1 − cos²θi) / η² (Snell). Where
/// sin²θt ≥ 1 the light is totally internally reflected: F = 1. `cos_i` is
/// clamped to [0, 1] (reflection off the side the light arrives from).
#[inline(always)]
pub fn f_dielectric<R: Real>(cos_i: R, eta: R) -> R {
    let cos_i = cos_i.clamp(R::ZERO, R::ONE);
    let sin2_t = (R::ONE - cos_i * cos_i) / (eta * eta);
    let tir = sin2_t.ge(R::ONE);
    // Under TIR the radicand is negative; the select below discards it.
    let cos_t = (R::ONE - sin2_t).max(R::ZERO).sqrt();
    let r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    R::select(tir, R::ONE, (r_s * r_s + r_p * r_p) * R::HALF)
}

/// Exact conductor Fresnel reflectance for complex IOR η + iκ (one channel),
/// unpolarized, in the real-arithmetic form of [PBRT3, §8.2.1]:
///
/// a² + b² = √((η² − κ² − sin²θ)² + 4η²κ²),  a = √((a² + b² + η² − κ² − sin²θ) / 2),
/// R_s = (a² + b² + cos²θ − 2a cos θ) / (a² + b² + cos²θ + 2a cos θ),
/// R_p = R_s (cos²θ (a² + b²) + sin⁴θ − 2a cos θ sin²θ) / (cos²θ (a² + b²) + sin⁴θ + 2a cos θ sin²θ),
/// F = (R_s + R_p) / 2.
#[inline(always)]
pub fn f_conductor<R: Real>(cos_i: R, eta: R, k: R) -> R {
    let c = cos_i.clamp(R::ZERO, R::ONE);
    let c2 = c * c;
    let s2 = R::ONE - c2;
    let (eta2, k2) = (eta * eta, k * k);
    let t0 = eta2 - k2 - s2;
    let a2pb2 = (t0 * t0 + R::splat(4.0) * eta2 * k2).sqrt();
    let a = ((a2pb2 + t0) * R::HALF).max(R::ZERO).sqrt();
    let t1 = a2pb2 + c2;
    let t2 = R::splat(2.0) * a * c;
    let r_s = (t1 - t2) / (t1 + t2);
    let t3 = c2 * a2pb2 + s2 * s2;
    let t4 = t2 * s2;
    let r_p = r_s * (t3 - t4) / (t3 + t4);
    (r_s + r_p) * R::HALF
}

#[cfg(test)]
mod tests {
    use super::*;
    use wide::f32x8;

    /// The half-vector form against (1 − |s|/2)⁵ in f64, over |s| ∈ [0, 2]
    /// and a little past 2 (rounding can put a sum of unit vectors there),
    /// in f32 and f32x8 alike.
    #[test]
    fn schlick_weight_half_is_one_minus_half_len_to_the_fifth() {
        for i in 0..=20_050u32 {
            let len = i as f32 * 1e-4;
            let want = (1.0 - len as f64 / 2.0).max(0.0).powi(5);
            let got = schlick_weight_half(len) as f64;
            assert!((got - want).abs() <= 4e-7, "|s| = {len}: {got} vs {want}");
            let lanes = schlick_weight_half(f32x8::splat(len)).to_array();
            assert!(lanes.iter().all(|&w| w as f64 == got), "|s| = {len}");
        }
    }
}
