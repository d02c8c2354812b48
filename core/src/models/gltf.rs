//! The glTF 2.0 material as Appendix B defines it, with the
//! KHR_materials_ior, _specular, _clearcoat and _sheen extensions
//! \[glTF2; KhrIor; KhrSpecular; KhrClearcoat; KhrSheen\].
//!
//! **Base** (Appendix B, "Material Structure", with the ior and specular
//! extensions' `fresnel_mix`):
//!
//! - specular_brdf(α) = D_GGX V_GGX, height-correlated Smith, α = roughness²;
//! - w = (1 − |V·H|)⁵ (Schlick);
//! - metal_brdf = (base + (1 − base) w) specular_brdf;
//! - dielectric: f0_c = min(r0(ior) specular_color, 1), r0 = ((ior − 1)/(ior + 1))²
//!   (ior = 0: r0 = 1, the extension's infinite IOR), F_d = k (f0_c + (1 − f0_c) w)
//!   with k = specular (the specular factor), and
//!   dielectric_brdf = F_d specular_brdf + (1 − max(F_d.r, F_d.g, F_d.b)) base/π;
//! - material = mix(dielectric_brdf, metal_brdf, metallic).
//!
//! The specular lobe of `material` is then F_s specular_brdf with
//! F_s = F0 + (F90 − F0) w, F0 = (1 − m) k f0_c + m base, F90 = (1 − m) k + m
//! (expanding the mix), and its diffuse lobe (1 − m)(1 − G) base/π with
//! G = G0 + (G90 − G0) w, G0 = k max(f0_c), G90 = k (max over channels of F_d).
//!
//! **`fresnel = "simplified"`** instead weights the diffuse lobe with the
//! specular lobe's own F_s per channel: G = F_s. Without extensions that is
//! F0 = mix(0.04, base, metallic), the form of Appendix B's earlier
//! revisions that the `metallic_roughness` model implements (equal to it:
//! core/tests/gltf.rs). The specular lobes of the two options are equal
//! for every metallic; the diffuse lobes are equal at metallic 0 and 1 and
//! differ by (1 − m) base/π (F_s − G) in between.
//!
//! **Sheen** (KHR_materials_sheen, sheen.rs): the base above is scaled by
//! the albedo-scaling term and the sheen lobe added:
//! f = f_sheen + f_base (1 − max(sheen_color) max(E(μo), E(μi))),
//! which is the extension's min(1 − max3 E(VdotN), 1 − max3 E(LdotN)),
//! with E the sheen lobe's directional albedo (sheen.rs). The extension's
//! lobe reflects more than it receives at grazing views of smooth sheens
//! (E above 1: core/tests/gltf.rs, figures in docs/accuracy.md), where
//! the scaling would turn negative; it is clamped at 0, so f stays ≥ 0
//! (the white furnace then exceeds 1 there, as the extension's lobe
//! does).
//!
//! **Clearcoat** (KHR_materials_clearcoat) over all of that:
//! f = (1 − c F_c) f_under + c F_c specular_brdf(α_c), with c = clearcoat,
//! α_c = clearcoat_roughness², F_c = 0.04 + 0.96 (1 − |V·N_c|)⁵ (IOR 1.5,
//! by the view and the coat's normal N_c, not the half vector). N_c is the
//! base normal unless the material's normal maps make them differ (a
//! clearcoat normal map; or a base normal map, which the coat does not
//! take, as the extension says) ([`Gltf::with_coat_normal`]): then N_c is
//! a lane parameter (a unit vector in the local frame, whose +Z is the
//! base's normal), and the
//! coat's lobe takes its cosines, its half-vector angle and F_c against
//! N_c (`dv_ggx_correlated_about`), while the base keeps its own normal.
//! The coat's lobe then receives light by its own cosine N_c·L, as
//! Khronos's sample viewer and Filament shade it (the base by N·L): f
//! carries the ratio (N_c·L)/(N·L) on that lobe, since whoever lights f
//! multiplies it by N·L. The whole f is still zero where wi or wo is
//! below the base's horizon, and the coat's lobe where wi is below N_c's.
//!
//! The clearcoat term depends on μo alone and is not reciprocal, as the
//! extension says; the rest is.
//!
//! **Layers per material.** Sheen and clearcoat are material switches:
//! a layer whose factor is 0 in the material is off in every lane (a glTF
//! texture multiplies its factor), and the kernels skip it; so is the
//! coat's own normal, which materials without a clearcoat normal map do
//! not pay for.
//!
//! **Lights.** Point and directional lights evaluate f. The uniform
//! environment uses the directional albedo: the specular and diffuse lobes
//! through the split-sum tables at the lane's α (albedo_tables.rs; F_s and
//! G are affine in w, so their integrals are exact in the tables' A, B, C),
//! the coat through the same tables at α_c times c F_c(μo) (exact: F_c
//! depends on μo only), the sheen lobe through E(μo), and the scaling of
//! the base by its view-only form 1 − max3 E(μo) less what the larger
//! E(μi) takes: for a Lambertian lobe exactly max3 K(μo) times its albedo,
//! K = 2 ∫ (E(μ) − E(μo))⁺ μ dμ (tabulated with E), and for the specular
//! lobe K times α (no spread at a mirror, about Lambertian at α = 1);
//! `directional_albedo_against_numeric_integration` (core/tests/gltf.rs)
//! bounds the error, docs/accuracy.md gives it. Polygon lights: the GGX LTC
//! (ltc/ggx.rs) per lobe at its α (specular; clearcoat times c F_c(μo)),
//! the diffuse lobe as its albedo at μo times the form factor (as
//! `metallic_roughness`); the coat's LTC is looked up in a frame around
//! N_c (`LtcGgx::in_frame`); sheen has no LTC here, and materials with sheen
//! are refused under polygon lights where the scene loads.
//!
//! **Lane parameters** ([`GltfLaneParams`]): every factor a glTF texture
//! can modulate (base colour, metallic, roughness, specular, specular
//! colour, clearcoat, clearcoat roughness, sheen colour, sheen roughness),
//! and the coat's normal. The IOR and the Fresnel option are the
//! material's.

use crate::albedo_tables::AlbedoTables;
use crate::brdf::{
    Brdf, EnvLobes, HalfAngles, LaneParams, Outgoing, ShadingFrame, ALPHA_MIN, COS_FLOOR,
};
use crate::fresnel::{schlick_weight, schlick_weight_half};
use crate::light::PolygonLocal;
use crate::ltc::ggx::LtcGgx;
use crate::masking::{dv_ggx_correlated, dv_ggx_correlated_about, smith_ggx_root};
use crate::real::Real;
use crate::sheen::{d_charlie, lambda_sheen, sheen_alpha, v_charlie, SheenTable};
use crate::vec3::{Rgb, V3};

/// How the diffuse lobe is weighted (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GltfFresnel {
    /// Appendix B: 1 − max over channels of the dielectric's Fresnel.
    #[default]
    Normative,
    /// 1 − F_s per channel, F0 = mix(dielectric F0, base, metallic).
    Simplified,
}

/// Normal-incidence reflectance of the clearcoat (IOR 1.5).
const COAT_F0: f64 = 0.04;

/// A glTF material's factors, with the glTF names in snake_case; the
/// defaults are the specification's.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfParams {
    /// Linear RGB.
    pub base_color: [f32; 3],
    pub metallic: f32,
    /// Perceptual; α = roughness².
    pub roughness: f32,
    /// ≥ 1, or 0 for an infinite IOR (KHR_materials_ior).
    pub ior: f32,
    /// KHR_materials_specular's specularFactor.
    pub specular: f32,
    /// KHR_materials_specular's specularColorFactor (may exceed 1: f0 is
    /// clamped after the IOR's r0 multiplies it).
    pub specular_color: [f32; 3],
    pub clearcoat: f32,
    pub clearcoat_roughness: f32,
    pub sheen_color: [f32; 3],
    pub sheen_roughness: f32,
    pub fresnel: GltfFresnel,
}

impl Default for GltfParams {
    fn default() -> GltfParams {
        GltfParams {
            base_color: [1.0; 3],
            metallic: 1.0,
            roughness: 1.0,
            ior: 1.5,
            specular: 1.0,
            specular_color: [1.0; 3],
            clearcoat: 0.0,
            clearcoat_roughness: 0.0,
            sheen_color: [0.0; 3],
            sheen_roughness: 0.0,
            fresnel: GltfFresnel::Normative,
        }
    }
}

/// r0 = ((ior − 1)/(ior + 1))², and 1 for ior = 0 (KHR_materials_ior's
/// infinite IOR, where the Fresnel term is 1).
pub fn r0_of_ior(ior: f64) -> f64 {
    if ior == 0.0 {
        1.0
    } else {
        ((ior - 1.0) / (ior + 1.0)).powi(2)
    }
}

/// A glTF material: its factors, the IOR's r0 and which layers it has.
#[derive(Clone, Debug, PartialEq)]
pub struct Gltf {
    pub(crate) params: GltfParams,
    r0: f64,
    sheen: bool,
    coat: bool,
    /// The coat has its own normal per lane ([`Gltf::with_coat_normal`]).
    coat_normal: bool,
}

impl Gltf {
    /// The material (parameters are trusted: the scene reader validates
    /// them).
    pub fn new(params: GltfParams) -> Gltf {
        Gltf {
            r0: r0_of_ior(params.ior as f64),
            sheen: params.sheen_color.iter().any(|c| *c > 0.0),
            coat: params.clearcoat > 0.0,
            coat_normal: false,
            params,
        }
    }

    /// The clearcoat reads its own normal from the lane parameters
    /// ([`GltfLaneParams::coat_normal`], set where the material's normal
    /// maps make it differ from the base's) instead of the base's; no
    /// effect without a clearcoat layer.
    pub fn with_coat_normal(mut self) -> Gltf {
        self.coat_normal = self.coat;
        self
    }

    /// The clearcoat has its own normal ([`Gltf::with_coat_normal`]).
    pub fn has_coat_normal(&self) -> bool {
        self.coat_normal
    }

    /// The material has a sheen layer (some sheen colour above 0).
    pub fn has_sheen(&self) -> bool {
        self.sheen
    }
}

/// The factors per lane (module docs, "Lane parameters").
#[derive(Clone, Copy, Debug)]
pub struct GltfLaneParams<R: Real> {
    pub base_color: Rgb<R>,
    pub metallic: R,
    /// Perceptual.
    pub roughness: R,
    pub specular: R,
    pub specular_color: Rgb<R>,
    pub clearcoat: R,
    /// Perceptual.
    pub clearcoat_roughness: R,
    pub sheen_color: Rgb<R>,
    /// Perceptual.
    pub sheen_roughness: R,
    /// The clearcoat's unit normal in the local frame; +Z (the base's
    /// normal) unless the material's maps set it. Read only by
    /// materials [`Gltf::with_coat_normal`].
    pub coat_normal: V3<R>,
}

impl<R: Real> LaneParams<R> for GltfLaneParams<R> {
    #[inline(always)]
    fn base_color_mut(&mut self) -> Option<&mut Rgb<R>> {
        Some(&mut self.base_color)
    }

    #[inline(always)]
    fn metallic_mut(&mut self) -> Option<&mut R> {
        Some(&mut self.metallic)
    }

    /// The lanes hold perceptual roughness, which the map's green channel
    /// multiplies as glTF defines it (α is derived, and floored, in
    /// [`Brdf::pixel`]).
    #[inline(always)]
    fn scale_roughness(&mut self, g: R) -> bool {
        self.roughness *= g;
        true
    }

    #[inline(always)]
    fn specular_mut(&mut self) -> Option<&mut R> {
        Some(&mut self.specular)
    }

    #[inline(always)]
    fn specular_color_mut(&mut self) -> Option<&mut Rgb<R>> {
        Some(&mut self.specular_color)
    }

    #[inline(always)]
    fn clearcoat_mut(&mut self) -> Option<&mut R> {
        Some(&mut self.clearcoat)
    }

    #[inline(always)]
    fn clearcoat_roughness_mut(&mut self) -> Option<&mut R> {
        Some(&mut self.clearcoat_roughness)
    }

    #[inline(always)]
    fn coat_normal_mut(&mut self) -> Option<&mut V3<R>> {
        Some(&mut self.coat_normal)
    }

    #[inline(always)]
    fn sheen_color_mut(&mut self) -> Option<&mut Rgb<R>> {
        Some(&mut self.sheen_color)
    }

    #[inline(always)]
    fn sheen_roughness_mut(&mut self) -> Option<&mut R> {
        Some(&mut self.sheen_roughness)
    }
}

/// What a pixel's factors determine before the view is known.
#[derive(Clone, Copy, Debug)]
pub struct GltfPixel<R: Real> {
    /// α = max(roughness², ALPHA_MIN), and the coat's.
    pub(crate) alpha: R,
    pub(crate) coat_alpha: R,
    /// The specular lobe's F0 and F90 (module docs).
    pub(crate) f0: Rgb<R>,
    pub(crate) f90: R,
    /// The diffuse lobe's Fresnel weight G0, G90 (module docs).
    pub(crate) g0: Rgb<R>,
    pub(crate) g90: Rgb<R>,
    /// (1 − metallic) base, and its Lambertian lobe / π.
    pub(crate) diffuse: Rgb<R>,
    pub(crate) kd: Rgb<R>,
    pub(crate) clearcoat: R,
    pub(crate) sheen_color: Rgb<R>,
    /// max(sheen_color), the albedo scaling's weight.
    pub(crate) sheen_max: R,
    pub(crate) sheen_alpha: R,
    pub(crate) sheen_roughness: R,
    /// The coat's unit normal in the local frame (read only with
    /// [`Gltf::with_coat_normal`]).
    pub(crate) coat_normal: V3<R>,
}

/// A pixel's BRDF once the view is known.
#[derive(Clone, Copy)]
pub struct GltfPrepared<R: Real> {
    pub(crate) o: Outgoing<R>,
    pub(crate) px: GltfPixel<R>,
    /// √(α² + (1 − α²) μo²) of the base (masking.rs).
    pub(crate) smith_root_o: R,
    /// The coat's view cosine V·N_c (floored like μo), its Smith root, and
    /// its layer weight c F_c; zero without a coat.
    pub(crate) coat_cos_o: R,
    pub(crate) coat_smith_root_o: R,
    pub(crate) coat_weight: R,
    /// E(μo) and Λ(μo) of the sheen lobe; zero without sheen.
    pub(crate) sheen_e_o: R,
    pub(crate) sheen_lambda_o: R,
}

impl Gltf {
    /// f from the half-vector quantities of the pixel's view and a light
    /// (`wi` the light's unit local direction, read only by a coat with
    /// its own normal).
    #[inline(always)]
    fn f_half<R: Real>(&self, p: &GltfPrepared<R>, h: HalfAngles<R>, wi: V3<R>) -> Rgb<R> {
        let px = &p.px;
        let HalfAngles {
            cos_i,
            cos_o,
            above,
            s,
            len2,
            len,
            sin2_h,
            ..
        } = h;
        let w = schlick_weight_half(len);
        let dv = dv_ggx_correlated(
            px.alpha,
            s,
            len2,
            cos_i,
            cos_o,
            smith_ggx_root(px.alpha, cos_i),
            p.smith_root_o,
        );
        // F_s DV + (1 − G) kd per channel.
        let fs = |f0: R| (px.f90 - f0).mul_add(w, f0);
        let g = |g0: R, g90: R| (g90 - g0).mul_add(w, g0);
        let channel = |f0: R, g0: R, g90: R, kd: R| fs(f0).mul_add(dv, (R::ONE - g(g0, g90)) * kd);
        let mut f = Rgb::new(
            channel(px.f0.x, px.g0.x, px.g90.x, px.kd.x),
            channel(px.f0.y, px.g0.y, px.g90.y, px.kd.y),
            channel(px.f0.z, px.g0.z, px.g90.z, px.kd.z),
        );
        if self.sheen {
            let e_i = SheenTable::get().e(cos_i, px.sheen_roughness);
            let scale = (R::ONE - px.sheen_max * e_i.max(p.sheen_e_o)).max(R::ZERO);
            let lambda_i = lambda_sheen(px.sheen_alpha, cos_i);
            let dv_s = d_charlie(px.sheen_alpha, sin2_h)
                * v_charlie(lambda_i, p.sheen_lambda_o, cos_i, cos_o);
            f = px.sheen_color * dv_s + f * scale;
        }
        if self.coat {
            let dv_c = if self.coat_normal {
                // The coat's lobe about N_c, times (N_c·L)/(N·L) (module
                // docs); zero where wi is below the coat's horizon (wo is
                // above it: the map keeps V·N_c ≥ 0.02, as the base normal
                // map does).
                let n = px.coat_normal;
                let c = n.dot(wi);
                let cos_i_c = c.max(R::splat(COS_FLOOR));
                let dv = dv_ggx_correlated_about(
                    px.coat_alpha,
                    n,
                    s,
                    len2,
                    cos_i_c,
                    p.coat_cos_o,
                    smith_ggx_root(px.coat_alpha, cos_i_c),
                    p.coat_smith_root_o,
                );
                R::select(c.gt(R::ZERO), dv * (cos_i_c / cos_i), R::ZERO)
            } else {
                dv_ggx_correlated(
                    px.coat_alpha,
                    s,
                    len2,
                    cos_i,
                    p.coat_cos_o,
                    smith_ggx_root(px.coat_alpha, cos_i),
                    p.coat_smith_root_o,
                )
            };
            f = f * (R::ONE - p.coat_weight) + Rgb::splat(p.coat_weight * dv_c);
        }
        Rgb::select(above, f, Rgb::zero())
    }

    /// The directional albedo in two layers: what is under the coat
    /// (specular, diffuse and sheen, before the coat's transmission) and
    /// the coat's own c F_c (A + B)(α_c, V·N_c); not masked by the horizon.
    #[inline(always)]
    fn albedo_layers<R: Real>(&self, p: &GltfPrepared<R>) -> (Rgb<R>, R) {
        let (o, px) = (&p.o, &p.px);
        let mu = o.wo.z.max(R::ZERO);
        let tables = AlbedoTables::get();
        let t = tables.ggx_schlick(px.alpha, mu);
        // ∫ F_s DV μi = F0 A + F90 B; ∫ (1 − G) μi/π = 1 − G0 (1 − C) − G90 C.
        let spec = |f0: R| f0.mul_add(t.a, px.f90 * t.b);
        let diff = |g0: R, g90: R| R::ONE - g0.mul_add(R::ONE - t.c, g90 * t.c);
        let specular = Rgb::new(spec(px.f0.x), spec(px.f0.y), spec(px.f0.z));
        let diffuse = Rgb::new(
            px.diffuse.x * diff(px.g0.x, px.g90.x),
            px.diffuse.y * diff(px.g0.y, px.g90.y),
            px.diffuse.z * diff(px.g0.z, px.g90.z),
        );
        let mut e = specular + diffuse;
        if self.sheen {
            let t = SheenTable::get();
            let scale = (R::ONE - px.sheen_max * p.sheen_e_o).max(R::ZERO);
            // What the scaling takes beyond its view-only form: K for a
            // Lambertian lobe, and for the specular lobe K times α (its
            // spread: none for a mirror, about Lambertian's at α = 1).
            let k = px.sheen_max * t.k(mu, px.sheen_roughness);
            let lost = (diffuse + specular * px.alpha) * k;
            let b = e * scale - lost;
            let b = Rgb::new(b.x.max(R::ZERO), b.y.max(R::ZERO), b.z.max(R::ZERO));
            e = px.sheen_color * p.sheen_e_o + b;
        }
        let coat = if self.coat {
            let tc = tables.ggx_schlick(px.coat_alpha, p.coat_cos_o.min(R::ONE));
            p.coat_weight * (tc.a + tc.b)
        } else {
            R::ZERO
        };
        (e, coat)
    }
}

#[inline(always)]
fn max3<R: Real>(c: Rgb<R>) -> R {
    c.x.max(c.y).max(c.z)
}

impl Brdf for Gltf {
    type Params<R: Real> = GltfLaneParams<R>;
    type Pixel<R: Real> = GltfPixel<R>;
    type Prepared<R: Real> = GltfPrepared<R>;
    type PolygonPrepared<R: Real> = GltfPolygons<R>;
    const POLYGON_LIGHTS: bool = true;

    #[inline(always)]
    fn params<R: Real>(&self) -> GltfLaneParams<R> {
        let p = &self.params;
        GltfLaneParams {
            base_color: Rgb::from_f32(p.base_color),
            metallic: R::splat(p.metallic as f64),
            roughness: R::splat(p.roughness as f64),
            specular: R::splat(p.specular as f64),
            specular_color: Rgb::from_f32(p.specular_color),
            clearcoat: R::splat(p.clearcoat as f64),
            clearcoat_roughness: R::splat(p.clearcoat_roughness as f64),
            sheen_color: Rgb::from_f32(p.sheen_color),
            sheen_roughness: R::splat(p.sheen_roughness as f64),
            coat_normal: V3::new(R::ZERO, R::ZERO, R::ONE),
        }
    }

    #[inline(always)]
    fn params_lane<R: Real>(p: &GltfLaneParams<R>, i: usize) -> GltfLaneParams<f64> {
        GltfLaneParams {
            base_color: p.base_color.lane(i),
            metallic: p.metallic.lane(i),
            roughness: p.roughness.lane(i),
            specular: p.specular.lane(i),
            specular_color: p.specular_color.lane(i),
            clearcoat: p.clearcoat.lane(i),
            clearcoat_roughness: p.clearcoat_roughness.lane(i),
            sheen_color: p.sheen_color.lane(i),
            sheen_roughness: p.sheen_roughness.lane(i),
            coat_normal: p.coat_normal.lane(i),
        }
    }

    /// F0, F90, G0, G90 and the diffuse colour (module docs).
    #[inline(always)]
    fn pixel<R: Real>(&self, l: &GltfLaneParams<R>) -> GltfPixel<R> {
        let floor = R::splat(ALPHA_MIN as f64);
        let (m, k) = (l.metallic, l.specular);
        let r0 = R::splat(self.r0);
        let sc = l.specular_color * r0;
        let f0c = Rgb::new(sc.x.min(R::ONE), sc.y.min(R::ONE), sc.z.min(R::ONE));
        let dk = (R::ONE - m) * k;
        let f0 = Rgb::new(
            l.base_color.x.mul_add(m, dk * f0c.x),
            l.base_color.y.mul_add(m, dk * f0c.y),
            l.base_color.z.mul_add(m, dk * f0c.z),
        );
        let f90 = dk + m;
        let (g0, g90) = match self.params.fresnel {
            GltfFresnel::Normative => (Rgb::splat(k * max3(f0c)), Rgb::splat(k)),
            GltfFresnel::Simplified => (f0, Rgb::splat(f90)),
        };
        let diffuse = l.base_color * (R::ONE - m);
        GltfPixel {
            alpha: (l.roughness * l.roughness).max(floor),
            coat_alpha: (l.clearcoat_roughness * l.clearcoat_roughness).max(floor),
            f0,
            f90,
            g0,
            g90,
            diffuse,
            kd: diffuse * R::FRAC_1_PI,
            clearcoat: l.clearcoat,
            sheen_color: l.sheen_color,
            sheen_max: max3(l.sheen_color),
            sheen_alpha: sheen_alpha(l.sheen_roughness),
            sheen_roughness: l.sheen_roughness,
            coat_normal: l.coat_normal,
        }
    }

    #[inline(always)]
    fn prepare_with<R: Real>(&self, px: &GltfPixel<R>, wo: V3<R>) -> GltfPrepared<R> {
        let o = Outgoing::new(wo);
        let mut p = GltfPrepared {
            smith_root_o: smith_ggx_root(px.alpha, o.cos_o),
            coat_cos_o: R::ZERO,
            coat_smith_root_o: R::ZERO,
            coat_weight: R::ZERO,
            sheen_e_o: R::ZERO,
            sheen_lambda_o: R::ZERO,
            px: *px,
            o,
        };
        if self.coat {
            // Without its own normal the coat's is the base's (module
            // docs): its view cosine is μo.
            p.coat_cos_o = if self.coat_normal {
                px.coat_normal.dot(wo).max(R::splat(COS_FLOOR))
            } else {
                o.cos_o
            };
            p.coat_smith_root_o = smith_ggx_root(px.coat_alpha, p.coat_cos_o);
            let fc =
                R::splat(1.0 - COAT_F0).mul_add(schlick_weight(p.coat_cos_o), R::splat(COAT_F0));
            p.coat_weight = px.clearcoat * fc;
        }
        if self.sheen {
            p.sheen_e_o = SheenTable::get().e(o.cos_o, px.sheen_roughness);
            p.sheen_lambda_o = lambda_sheen(px.sheen_alpha, o.cos_o);
        }
        p
    }

    #[inline(always)]
    fn f_local<R: Real>(&self, p: &GltfPrepared<R>, wi: V3<R>) -> Rgb<R> {
        self.f_half(p, HalfAngles::new(wi, &p.o), wi)
    }

    #[inline(always)]
    fn f_local_scaled<R: Real>(&self, p: &GltfPrepared<R>, v: V3<R>, inv_len: R) -> Rgb<R> {
        self.f_half(p, HalfAngles::scaled(v, inv_len, &p.o), v * inv_len)
    }

    /// Split sum per lobe (module docs, "Lights").
    #[inline(always)]
    fn albedo_local<R: Real>(&self, p: &GltfPrepared<R>) -> Rgb<R> {
        let (under, coat) = self.albedo_layers(p);
        let e = under * (R::ONE - p.coat_weight) + Rgb::splat(coat);
        Rgb::select(p.o.above, e, Rgb::zero())
    }

    /// The diffuse lobe's albedo (1 − G)·ρd on the irradiance, the rest of
    /// what is under the coat (specular, sheen) on the GGX lobe at the
    /// base's α around the base's mirror direction, both times the coat's
    /// transmission 1 − c F_c; the coat's albedo c F_c (A + B)(α_c) on the
    /// GGX lobe at α_c around the mirror direction about the coat's normal.
    #[inline(always)]
    fn env_lobes<R: Real>(&self, p: &GltfPrepared<R>) -> EnvLobes<R> {
        let px = &p.px;
        let t = AlbedoTables::get().ggx_schlick(px.alpha, p.o.wo.z.max(R::ZERO));
        let diff = |g0: R, g90: R| R::ONE - g0.mul_add(R::ONE - t.c, g90 * t.c);
        let diffuse = Rgb::new(
            px.diffuse.x * diff(px.g0.x, px.g90.x),
            px.diffuse.y * diff(px.g0.y, px.g90.y),
            px.diffuse.z * diff(px.g0.z, px.g90.z),
        );
        let (under, coat) = self.albedo_layers(p);
        let k = R::ONE - p.coat_weight;
        let above = p.o.above;
        let lobes = EnvLobes::split(
            Rgb::select(above, under * k, Rgb::zero()),
            Rgb::select(above, diffuse * k, Rgb::zero()),
            px.alpha.sqrt(),
        );
        if !self.coat {
            return lobes;
        }
        let normal = if self.coat_normal {
            px.coat_normal
        } else {
            V3::new(R::ZERO, R::ZERO, R::ONE)
        };
        lobes.with_coat(
            R::select(above, coat, R::ZERO),
            px.coat_alpha.sqrt(),
            normal,
        )
    }

    /// The LTC lookups and the lobes' albedo factors (zero where the view
    /// is below the horizon).
    #[inline(always)]
    fn prepare_polygons<R: Real>(&self, p: &GltfPrepared<R>) -> GltfPolygons<R> {
        let (o, px) = (&p.o, &p.px);
        let ltc = LtcGgx::new(px.alpha, o.wo);
        let spec = |f0: R| f0.mul_add(ltc.n - ltc.n_w, px.f90 * ltc.n_w);
        let c = AlbedoTables::get().c(o.wo.z.max(R::ZERO));
        let diff = |g0: R, g90: R| R::ONE - g0.mul_add(R::ONE - c, g90 * c);
        let under = if self.coat {
            R::ONE - p.coat_weight
        } else {
            R::ONE
        };
        let specular = Rgb::new(spec(px.f0.x), spec(px.f0.y), spec(px.f0.z)) * under;
        let diffuse = Rgb::new(
            px.diffuse.x * diff(px.g0.x, px.g90.x),
            px.diffuse.y * diff(px.g0.y, px.g90.y),
            px.diffuse.z * diff(px.g0.z, px.g90.z),
        ) * under;
        let coat = self.coat.then(|| {
            let l = if self.coat_normal {
                // Looked up in a frame around N_c, then composed with it
                // so that it maps the vertices' base-local coordinates.
                let frame = ShadingFrame::from_normal(px.coat_normal);
                LtcGgx::new(px.coat_alpha, frame.to_local(o.wo)).in_frame(&frame)
            } else {
                LtcGgx::new(px.coat_alpha, o.wo)
            };
            let k = R::select(o.above, p.coat_weight * l.n, R::ZERO);
            (l, k)
        });
        GltfPolygons {
            ltc,
            specular: Rgb::select(o.above, specular, Rgb::zero()),
            diffuse: Rgb::select(o.above, diffuse, Rgb::zero()),
            coat,
        }
    }

    /// Specular and coat by their GGX LTCs, diffuse as its albedo at μo
    /// times the form factor (module docs, "Lights").
    #[inline(always)]
    fn polygon_local_with<R: Real>(
        &self,
        _p: &GltfPrepared<R>,
        pp: &GltfPolygons<R>,
        poly: &PolygonLocal<R>,
    ) -> Rgb<R> {
        let (ff, spec) = pp.ltc.form_factor_and_integral(poly);
        let mut e = pp.specular * spec + pp.diffuse * ff;
        if let Some((l, k)) = &pp.coat {
            e += Rgb::splat(*k * l.integral(poly));
        }
        e
    }
}

/// A glTF material's per-pixel state for polygon lights.
#[derive(Clone, Copy)]
pub struct GltfPolygons<R: Real> {
    pub(crate) ltc: LtcGgx<R>,
    /// The specular lobe's albedo F0 (n − n_w) + F90 n_w, times 1 − c F_c.
    pub(crate) specular: Rgb<R>,
    /// The diffuse lobe's albedo at μo, times 1 − c F_c.
    pub(crate) diffuse: Rgb<R>,
    /// The coat's LTC and c F_c(μo) n(α_c, μo); `None` without a coat.
    pub(crate) coat: Option<(LtcGgx<R>, R)>,
}
