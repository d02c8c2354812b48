//! glTF 2.0 core metallic-roughness model (the everyday model of OBJ/MTL and
//! glTF assets):
//!
//! f = D_GGX(α) · V_SmithGGXCorrelated(α) · F_Schlick(F0)
//!   + (1 − F_Schlick(F0)) (1 − metallic) base_color / π
//!
//! with α = roughness², F0 = mix(0.04, base_color, metallic).   [glTF2, Appendix B]
//!
//! Every parameter (base colour, roughness, metallic) is a lane parameter:
//! its tables are indexed per lane.

use crate::albedo_tables::AlbedoTables;
use crate::brdf::{Brdf, EnvLobes, HalfAngles, LaneParams, Outgoing, ALPHA_MIN};
use crate::diffuse::f_lambert;
use crate::fresnel::schlick_weight_half;
use crate::light::PolygonLocal;
use crate::ltc::ggx::LtcGgx;
use crate::masking::{dv_ggx_correlated, smith_ggx_root};
use crate::real::{Mask, Real};
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
    /// α = roughness², floored at `ALPHA_MIN` (α = 0 would make D a delta and
    /// the formula 0/0 at the peak).
    #[inline]
    pub fn alpha(&self) -> f32 {
        (self.roughness * self.roughness).max(ALPHA_MIN)
    }

    /// Albedo of the diffuse lobe: (1 − metallic) base_color.
    #[inline]
    pub fn diffuse_color(&self) -> [f32; 3] {
        self.base_color.map(|c| c * (1.0 - self.metallic))
    }
}

/// The model's parameters per lane: all of them.
#[derive(Clone, Copy, Debug)]
pub struct MetallicRoughnessLaneParams<R: Real> {
    /// Linear RGB.
    pub(crate) base_color: Rgb<R>,
    /// α = roughness², floored at `ALPHA_MIN`.
    pub alpha: R,
    pub metallic: R,
}

impl<R: Real> MetallicRoughnessLaneParams<R> {
    /// Parameters from a perceptual roughness per lane (α = roughness²,
    /// floored as [`MetallicRoughness::alpha`] does).
    #[inline(always)]
    pub fn new(base_color: Rgb<R>, roughness: R, metallic: R) -> Self {
        MetallicRoughnessLaneParams {
            base_color,
            alpha: (roughness * roughness).max(R::splat(ALPHA_MIN as f64)),
            metallic,
        }
    }
}

impl<R: Real> LaneParams<R> for MetallicRoughnessLaneParams<R> {
    #[inline(always)]
    fn base_color_mut(&mut self) -> Option<&mut Rgb<R>> {
        Some(&mut self.base_color)
    }

    #[inline(always)]
    fn metallic_mut(&mut self) -> Option<&mut R> {
        Some(&mut self.metallic)
    }

    /// roughness → g · roughness, so α = roughness² → max(α g², α_min):
    /// the same as flooring (g · roughness)² afresh, whether or not the
    /// material's own α was floored (if r² < α_min then (g r)² < α_min).
    #[inline(always)]
    fn scale_roughness(&mut self, g: R) -> bool {
        self.alpha = (self.alpha * g * g).max(R::splat(ALPHA_MIN as f64));
        true
    }
}

/// What a metallic-roughness pixel's parameters determine before the
/// view is known.
#[derive(Clone, Copy, Debug)]
pub struct MetallicRoughnessPixel<R: Real> {
    pub(crate) alpha: R,
    /// F0 = mix(0.04, base_color, metallic), and 1 − F0.
    pub(crate) f0: Rgb<R>,
    pub(crate) one_minus_f0: Rgb<R>,
    /// Albedo of the diffuse lobe, (1 − metallic) base_color, and its
    /// Lambertian lobe ρd/π.
    pub(crate) diffuse: Rgb<R>,
    pub(crate) kd: Rgb<R>,
}

/// A metallic-roughness pixel: its view, the Smith root of the view, and
/// what its parameters determine.
#[derive(Clone, Copy)]
pub struct MetallicRoughnessPrepared<R: Real> {
    pub(crate) o: Outgoing<R>,
    pub(crate) px: MetallicRoughnessPixel<R>,
    /// √(α² + (1 − α²) μo²) (masking.rs).
    pub(crate) smith_root_o: R,
}

impl<R: Real> MetallicRoughnessPrepared<R> {
    /// f from the half-vector quantities of the pixel's view and a light.
    #[inline(always)]
    fn f_half(&self, h: HalfAngles<R>) -> Rgb<R> {
        let px = &self.px;
        let kd = px.kd;
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
            px.alpha,
            s,
            len2,
            cos_i,
            cos_o,
            smith_ggx_root(px.alpha, cos_i),
            self.smith_root_o,
        );
        // F·DV + (1 − F)·kd = kd + F·(DV − kd), with Schlick's
        // F = F0 + (1 − F0) w per channel: two fused steps a channel.
        let channel = |f0: R, one_minus_f0: R, kd: R| {
            let f = one_minus_f0.mul_add(w, f0);
            f.mul_add(dv - kd, kd)
        };
        let (f0, f0c) = (px.f0, px.one_minus_f0);
        let f = Rgb::new(
            channel(f0.x, f0c.x, kd.x),
            channel(f0.y, f0c.y, kd.y),
            channel(f0.z, f0c.z, kd.z),
        );
        Rgb::select(above, f, Rgb::zero())
    }
}

impl Brdf for MetallicRoughness {
    type Params<R: Real> = MetallicRoughnessLaneParams<R>;
    type Pixel<R: Real> = MetallicRoughnessPixel<R>;
    type Prepared<R: Real> = MetallicRoughnessPrepared<R>;
    type PolygonPrepared<R: Real> = MetallicRoughnessPolygons<R>;
    const POLYGON_LIGHTS: bool = true;

    #[inline(always)]
    fn params<R: Real>(&self) -> MetallicRoughnessLaneParams<R> {
        MetallicRoughnessLaneParams {
            base_color: Rgb::from_f32(self.base_color),
            alpha: R::splat(self.alpha() as f64),
            metallic: R::splat(self.metallic as f64),
        }
    }

    #[inline(always)]
    fn params_lane<R: Real>(
        p: &MetallicRoughnessLaneParams<R>,
        i: usize,
    ) -> MetallicRoughnessLaneParams<f64> {
        MetallicRoughnessLaneParams {
            base_color: p.base_color.lane(i),
            alpha: p.alpha.lane(i),
            metallic: p.metallic.lane(i),
        }
    }

    /// F0 = mix(0.04, base_color, metallic) and the diffuse albedo
    /// (1 − metallic) base_color, with 1 − F0 and ρd/π.
    #[inline(always)]
    fn pixel<R: Real>(&self, params: &MetallicRoughnessLaneParams<R>) -> MetallicRoughnessPixel<R> {
        let m = params.metallic;
        let f0_d = R::splat(F0_DIELECTRIC as f64);
        // Unfused: the rounding of F0 the model has always had, so
        // rendered images keep their bytes.
        let mix = |c: R| f0_d + (c - f0_d) * m;
        let b = params.base_color;
        let f0 = Rgb::new(mix(b.x), mix(b.y), mix(b.z));
        let diffuse = b * (R::ONE - m);
        MetallicRoughnessPixel {
            alpha: params.alpha,
            f0,
            one_minus_f0: Rgb::splat(R::ONE) - f0,
            diffuse,
            kd: f_lambert(diffuse),
        }
    }

    #[inline(always)]
    fn prepare_with<R: Real>(
        &self,
        px: &MetallicRoughnessPixel<R>,
        wo: V3<R>,
    ) -> MetallicRoughnessPrepared<R> {
        let o = Outgoing::new(wo);
        MetallicRoughnessPrepared {
            smith_root_o: smith_ggx_root(px.alpha, o.cos_o),
            px: *px,
            o,
        }
    }

    #[inline(always)]
    fn f_local<R: Real>(&self, p: &MetallicRoughnessPrepared<R>, wi: V3<R>) -> Rgb<R> {
        p.f_half(HalfAngles::new(wi, &p.o))
    }

    #[inline(always)]
    fn f_local_scaled<R: Real>(
        &self,
        p: &MetallicRoughnessPrepared<R>,
        v: V3<R>,
        inv_len: R,
    ) -> Rgb<R> {
        p.f_half(HalfAngles::scaled(v, inv_len, &p.o))
    }

    #[inline(always)]
    fn albedo_local<R: Real>(&self, p: &MetallicRoughnessPrepared<R>) -> Rgb<R> {
        let (spec, diff) = split_sum_terms(p);
        Rgb::select(p.o.above, spec + diff, Rgb::zero())
    }

    /// The split sum's two terms: F0·A + B on the GGX lobe at α, and
    /// (1 − F0)(1 − C)·ρd on the irradiance.
    #[inline(always)]
    fn env_lobes<R: Real>(&self, p: &MetallicRoughnessPrepared<R>) -> EnvLobes<R> {
        let (spec, diff) = split_sum_terms(p);
        EnvLobes::new(
            Rgb::select(p.o.above, diff, Rgb::zero()),
            Rgb::select(p.o.above, spec, Rgb::zero()),
            p.px.alpha.sqrt(),
        )
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
        let ltc = LtcGgx::new(p.px.alpha, o.wo);
        let f0 = p.px.f0;
        let specular = Rgb::new(
            ltc.schlick_albedo(f0.x),
            ltc.schlick_albedo(f0.y),
            ltc.schlick_albedo(f0.z),
        );
        let c = AlbedoTables::get().c(o.wo.z.max(R::ZERO));
        let diffuse = p.px.one_minus_f0.mul_elem(p.px.diffuse) * (R::ONE - c);
        let zero = R::ZERO;
        MetallicRoughnessPolygons {
            ltc,
            specular: Rgb::select(o.above, specular, Rgb::zero()),
            diffuse: Rgb::select(o.above, diffuse, Rgb::zero()),
            metal: !(p.px.diffuse.x.gt(zero) | p.px.diffuse.y.gt(zero) | p.px.diffuse.z.gt(zero))
                .any(),
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
        if pp.metal {
            // Metal in every lane: no diffuse lobe, so no form factor to
            // integrate (the specular integral is the same either way, bit
            // for bit).
            return pp.specular * pp.ltc.integral(poly);
        }
        let (ff, spec) = pp.ltc.form_factor_and_integral(poly);
        pp.specular * spec + pp.diffuse * ff
    }
}

/// A metallic-roughness material's per-pixel state for polygon lights.
#[derive(Clone, Copy)]
pub struct MetallicRoughnessPolygons<R: Real> {
    pub(crate) ltc: LtcGgx<R>,
    /// F0 (n − n_w) + n_w per channel: the specular lobe's albedo.
    pub(crate) specular: Rgb<R>,
    /// (1 − F0) ρd (1 − C(μo)): what multiplies the form factor.
    pub(crate) diffuse: Rgb<R>,
    /// No lane has a diffuse lobe.
    pub(crate) metal: bool,
}

/// The split sum's two terms at the prepared view (see albedo_tables):
/// E_spec = F0·A + B and E_diff = (1 − F0)(1 − C)·ρd, before the horizon
/// test.
#[inline(always)]
fn split_sum_terms<R: Real>(p: &MetallicRoughnessPrepared<R>) -> (Rgb<R>, Rgb<R>) {
    let t = AlbedoTables::get().ggx_schlick(p.px.alpha, p.o.wo.z.max(R::ZERO));
    let f0 = p.px.f0;
    let spec = Rgb::new(
        f0.x.mul_add(t.a, t.b),
        f0.y.mul_add(t.a, t.b),
        f0.z.mul_add(t.a, t.b),
    );
    let diff = p.px.one_minus_f0.mul_elem(p.px.diffuse) * (R::ONE - t.c);
    (spec, diff)
}
