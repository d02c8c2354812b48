//! Diffuse lobes.

use crate::fresnel::schlick_weight;
use crate::real::Real;
use crate::vec3::Rgb;

/// Lambertian BRDF f = ρ / π (no cosine folded in).   [Lambert1760]
#[inline(always)]
pub(crate) fn f_lambert<R: Real>(albedo: Rgb<R>) -> Rgb<R> {
    albedo * R::FRAC_1_PI
}

/// Burley's diffuse Fresnel factor, without the 1/π or the colour
/// [Burley12, §5.3]:
///
/// F_d = (1 + (F_D90 − 1)(1 − μi)⁵) (1 + (F_D90 − 1)(1 − μo)⁵),
/// F_D90 = ½ + 2 cos²θd · roughness.
///
/// Takes the Schlick weights w_i = (1 − μi)⁵, w_o = (1 − μo)⁵ (a shader
/// forms w_o once per pixel). At roughness 0 it darkens grazing angles to
/// half; past roughness ¼ F_D90 can exceed 1 (the retro-reflection peak),
/// and the lobe then reflects more than it receives at grazing angles.
#[inline(always)]
pub(crate) fn fd_burley<R: Real>(roughness: R, cos2_theta_d: R, w_i: R, w_o: R) -> R {
    let fd90_m1 = (R::splat(2.0) * cos2_theta_d).mul_add(roughness, -R::HALF);
    fd90_m1.mul_add(w_i, R::ONE) * fd90_m1.mul_add(w_o, R::ONE)
}

/// Burley's subsurface approximation, Hanrahan–Krueger-like, without the
/// 1/π or the colour [Burley12, §5.3; Hanrahan93]:
///
/// F_ss = (1 + (F_ss90 − 1) w_i)(1 + (F_ss90 − 1) w_o),  F_ss90 = cos²θd · roughness,
/// ss = 1.25 (F_ss (1/(μi + μo) − ½) + ½).
///
/// The 1.25 roughly preserves the albedo of the Lambertian lobe it is
/// blended with; `cos_i`, `cos_o` > 0 (floored by the caller).
#[inline(always)]
pub(crate) fn f_subsurface_burley<R: Real>(
    roughness: R,
    cos2_theta_d: R,
    w_i: R,
    w_o: R,
    cos_i: R,
    cos_o: R,
) -> R {
    let fss90_m1 = cos2_theta_d.mul_add(roughness, -R::ONE);
    let fss = fss90_m1.mul_add(w_i, R::ONE) * fss90_m1.mul_add(w_o, R::ONE);
    R::splat(1.25) * fss.mul_add((cos_i + cos_o).rcp() - R::HALF, R::HALF)
}

/// Burley's sheen weight (1 − cos θd)⁵, the Schlick weight of the
/// difference angle θd (between wi and the half vector): multiplied by the
/// sheen amount and colour, it brightens grazing retro-reflection on
/// cloth-like surfaces [Burley12, §5.4]. No 1/π: the sheen lobe is added
/// to the diffuse lobe's f as is.
#[inline(always)]
pub(crate) fn sheen_burley<R: Real>(cos_theta_d: R) -> R {
    schlick_weight(cos_theta_d)
}
