//! glTF 2.0 core metallic-roughness model (the everyday model of OBJ/MTL and
//! glTF assets):
//!
//! f = D_GGX(α) · V_SmithGGXCorrelated(α) · F_Schlick(F0)
//!   + (1 − F_Schlick(F0)) (1 − metallic) base_color / π
//!
//! with α = roughness², F0 = mix(0.04, base_color, metallic).   [glTF2, Appendix B]

use crate::albedo_tables::AlbedoTables;
use crate::brdf::{Brdf, HalfAngles, Outgoing, ALPHA_MIN};
use crate::diffuse::f_lambert;
use crate::fresnel::schlick_weight_half;
use crate::light::PolygonLocal;
use crate::ltc::ggx::LtcGgx;
use crate::masking::{dv_ggx_correlated, smith_ggx_root};
use crate::real::Real;
use crate::vec3::{Rgb, V3};

/// Parameters as the user gives them; see the module docs for the formula.
#[derive(Clone, Debug, PartialEq)]
pub struct MetallicRoughness {
    pub base_color: [f32; 3],
    /// Perceptual roughness in [0, 1]; α = roughness².
    pub roughness: f32,
    /// 0 = dielectric, 1 = metal.
    pub metallic: f32,
}

/// Reflectance at normal incidence of the dielectric end (IOR 1.5).
const F0_DIELECTRIC: f32 = 0.04;

impl MetallicRoughness {
    /// α = roughness², floored at [`ALPHA_MIN`] (α = 0 would make D a delta and
    /// the formula 0/0 at the peak).
    #[inline]
    pub fn alpha(&self) -> f32 {
        (self.roughness * self.roughness).max(ALPHA_MIN)
    }

    /// F0 = mix(0.04, base_color, metallic).
    #[inline]
    pub fn f0(&self) -> [f32; 3] {
        self.base_color
            .map(|c| F0_DIELECTRIC + (c - F0_DIELECTRIC) * self.metallic)
    }

    /// Albedo of the diffuse lobe: (1 − metallic) base_color.
    #[inline]
    pub fn diffuse_color(&self) -> [f32; 3] {
        self.base_color.map(|c| c * (1.0 - self.metallic))
    }

    /// f from the half-vector quantities of the pixel's view and a light.
    #[inline(always)]
    fn f_half<R: Real>(&self, p: &MetallicRoughnessPrepared<R>, h: HalfAngles<R>) -> Rgb<R> {
        let alpha = R::splat(self.alpha() as f64);
        let f0 = self.f0();
        let kd = f_lambert(Rgb::from_f32(self.diffuse_color()));

        let HalfAngles {
            cos_i,
            cos_o,
            above,
            s,
            len2,
            len,
            ..
        } = h;

        let w = schlick_weight_half(len);
        let dv = dv_ggx_correlated(
            alpha,
            s,
            len2,
            cos_i,
            cos_o,
            smith_ggx_root(alpha, cos_i),
            p.smith_root_o,
        );
        // F·DV + (1 − F)·kd = kd + F·(DV − kd), with Schlick's
        // F = F0 + (1 − F0) w per channel: two fused steps a channel.
        let channel = |f0: f32, kd: R| {
            let f = R::splat(1.0 - f0 as f64).mul_add(w, R::splat(f0 as f64));
            f.mul_add(dv - kd, kd)
        };
        let f = Rgb::new(
            channel(f0[0], kd.x),
            channel(f0[1], kd.y),
            channel(f0[2], kd.z),
        );
        Rgb::select(above, f, Rgb::zero())
    }
}

/// Per-pixel state: the view direction and its Smith root.
#[derive(Clone, Copy)]
pub struct MetallicRoughnessPrepared<R: Real> {
    pub o: Outgoing<R>,
    /// √(α² + (1 − α²) μo²) (masking.rs).
    pub smith_root_o: R,
}

impl Brdf for MetallicRoughness {
    type Prepared<R: Real> = MetallicRoughnessPrepared<R>;
    type PolygonPrepared<R: Real> = MetallicRoughnessPolygons<R>;
    const POLYGON_LIGHTS: bool = true;

    #[inline(always)]
    fn prepare<R: Real>(&self, wo: V3<R>) -> MetallicRoughnessPrepared<R> {
        let o = Outgoing::new(wo);
        MetallicRoughnessPrepared {
            smith_root_o: smith_ggx_root(R::splat(self.alpha() as f64), o.cos_o),
            o,
        }
    }

    #[inline(always)]
    fn f_local<R: Real>(&self, p: &MetallicRoughnessPrepared<R>, wi: V3<R>) -> Rgb<R> {
        self.f_half(p, HalfAngles::new(wi, &p.o))
    }

    #[inline(always)]
    fn f_local_scaled<R: Real>(
        &self,
        p: &MetallicRoughnessPrepared<R>,
        v: V3<R>,
        inv_len: R,
    ) -> Rgb<R> {
        self.f_half(p, HalfAngles::scaled(v, inv_len, &p.o))
    }

    #[inline(always)]
    fn albedo_local<R: Real>(&self, p: &MetallicRoughnessPrepared<R>) -> Rgb<R> {
        let o = &p.o;
        let t = AlbedoTables::get().ggx_schlick(self.alpha(), o.wo.z.max(R::ZERO));
        // Split sum: E_spec = F0·A + B, E_diff = (1 − F0)(1 − C)·ρd   (see albedo_tables)
        let f0: Rgb<R> = Rgb::from_f32(self.f0());
        let diffuse: Rgb<R> = Rgb::from_f32(self.diffuse_color());
        let spec = Rgb::new(
            f0.x.mul_add(t.a, t.b),
            f0.y.mul_add(t.a, t.b),
            f0.z.mul_add(t.a, t.b),
        );
        let one = Rgb::splat(R::ONE);
        let diff = (one - f0).mul_elem(diffuse) * (R::ONE - t.c);
        Rgb::select(o.above, spec + diff, Rgb::zero())
    }

    /// The GGX LTC lookup and the split sum's C(μo), with the factors of
    /// [`Brdf::polygon_local_with`] below folded per channel (zero where
    /// the view is below the horizon).
    #[inline(always)]
    fn prepare_polygons<R: Real>(
        &self,
        p: &MetallicRoughnessPrepared<R>,
    ) -> MetallicRoughnessPolygons<R> {
        let o = &p.o;
        let ltc = LtcGgx::new(R::splat(self.alpha() as f64), o.wo);
        let f0: Rgb<R> = Rgb::from_f32(self.f0());
        let specular = Rgb::new(
            ltc.schlick_albedo(f0.x),
            ltc.schlick_albedo(f0.y),
            ltc.schlick_albedo(f0.z),
        );
        let c = AlbedoTables::get().c(o.wo.z.max(R::ZERO));
        let diffuse: Rgb<R> = Rgb::from_f32(self.diffuse_color());
        let diffuse = (Rgb::splat(R::ONE) - f0).mul_elem(diffuse) * (R::ONE - c);
        MetallicRoughnessPolygons {
            ltc,
            specular: Rgb::select(o.above, specular, Rgb::zero()),
            diffuse: Rgb::select(o.above, diffuse, Rgb::zero()),
        }
    }

    /// Specular by the GGX LTC (ltc/ggx.rs) with Schlick's split at F0;
    /// diffuse as the split sum's (1 − F0) ρd (1 − C(μo)) times the form
    /// factor (the (1 − F) weight replaced by its hemispherical mean).
    #[inline(always)]
    fn polygon_local_with<R: Real>(
        &self,
        _p: &MetallicRoughnessPrepared<R>,
        pp: &MetallicRoughnessPolygons<R>,
        poly: &PolygonLocal<R>,
    ) -> Rgb<R> {
        if self.diffuse_color() == [0.0; 3] {
            // A metal: no diffuse lobe, so no form factor to integrate
            // (the specular integral is the same either way, bit for bit).
            return pp.specular * pp.ltc.integral(poly);
        }
        let (ff, spec) = pp.ltc.form_factor_and_integral(poly);
        pp.specular * spec + pp.diffuse * ff
    }
}

/// A metallic-roughness material's per-pixel state for polygon lights.
#[derive(Clone, Copy)]
pub struct MetallicRoughnessPolygons<R: Real> {
    pub ltc: LtcGgx<R>,
    /// F0 (n − n_w) + n_w per channel: the specular lobe's albedo.
    pub specular: Rgb<R>,
    /// (1 − F0) ρd (1 − C(μo)): what multiplies the form factor.
    pub diffuse: Rgb<R>,
}
