//! The microfacet BRDF of the course notes, every term selectable:
//!
//! f(i, o) = F(i·h) G2(i, o) D(h) / (4 (n·i)(n·o)) + ρd / π
//!
//! D: GGX, Beckmann or GTR(γ); G2: separable or height-correlated Smith
//! with the NDF's Λ (GTR has no closed-form Λ: by default it uses the GGX
//! Λ at the same α, whose mismatch lets γ < 2 lobes reflect more than they
//! receive at grazing angles, E(0.1) = 1.21 at γ = 1.5, α = 0.15;
//! [`GtrLambda::Exact`] tabulates GTR's own Λ, gtr_lambda.rs); F: Schlick (F0), exact dielectric (IOR) or exact
//! conductor (η, κ per channel); an optional Lambertian base ρd is added
//! (not weighted: the notes' "microfacet + diffuse" sum).
//!
//! Uniform environment light needs the directional albedo E(μo): it is
//! tabulated per material when the material is built (`AlbedoTable`).
//!
//! Lane parameters: the diffuse base ρd. The terms (NDF, Smith, Fresnel)
//! and α are the material's: E(μo) and the compensation slice are
//! tabulated at its α.

pub use crate::fresnel::Fresnel;
pub use crate::gtr_lambda::GtrLambda;
pub use crate::masking::Smith;
pub use crate::ndf::Ndf;
pub use crate::specular_lobe::MicrofacetParams;

use crate::brdf::{Brdf, EnvLobes, HalfAngles, LaneParams, Outgoing, ALPHA_MIN};
use crate::ggx_equivalent::ggx_equivalent_alpha;
use crate::kulla_conty::{color_factor, f_avg, slice_for, KcColor, KcSlice};
use crate::light::PolygonLocal;
use crate::ltc::ggx::LtcGgx;
use crate::real::Real;
use crate::table::{Axis, Nodes, Table1, Warp};
use crate::vec3::{Rgb, V3};

/// Directional albedo E(μo) per channel at `N_MU` nodes from μ = 0 to
/// μ = 1 inclusive, linear between them: the normal view (μ = 1) reads its
/// own quadrature value, not the nearest texel centre's.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct AlbedoTable {
    e: Table1<3>,
}

const N_MU: usize = 64;
const MU_AXIS: Axis = Axis::new(N_MU, 0.0, 1.0, Warp::Linear, Nodes::Ends);

#[derive(Clone, Debug, PartialEq)]
pub struct Microfacet {
    pub params: MicrofacetParams,
    albedo: AlbedoTable,
    /// The perceptual roughness of the GGX lobe that stands in for the
    /// specular lobe under environment maps (ggx_equivalent.rs).
    env_roughness: f32,
    /// Kulla–Conty compensation, when enabled.
    kc: Option<Compensation>,
}

/// The compensation lobe of one material: E(μ) at its α, E_avg, and the
/// colour factor per channel (kulla_conty.rs).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Compensation {
    pub(crate) slice: KcSlice,
    pub(crate) factor: [f32; 3],
    /// factor / (π (1 − E_avg)) per channel: everything in f_ms that does
    /// not depend on the directions, folded once here.
    scale: [f32; 3],
}

impl Compensation {
    pub(crate) fn new(p: &MicrofacetParams, mode: KcColor) -> Compensation {
        let exact = matches!(p.gtr_lambda, GtrLambda::Exact(_));
        let slice = slice_for(p.ndf, p.smith, exact, p.alpha as f64);
        let fa = f_avg(&p.fresnel);
        let factor = fa.map(|f| color_factor(f, slice.e_avg, mode));
        let k = 1.0 / (std::f64::consts::PI * (1.0 - slice.e_avg).max(1e-6));
        Compensation {
            scale: factor.map(|f| (f * k) as f32),
            factor: factor.map(|f| f as f32),
            slice,
        }
    }

    /// 1 − E(μo): the view's factor of f_ms, computed once per pixel.
    #[inline(always)]
    pub(crate) fn prepare<R: Real>(&self, cos_o: R) -> R {
        R::ONE - self.slice.e_lanes(cos_o)
    }

    /// f_ms(μi, μo) · factor, per channel (no cosine), from the prepared
    /// 1 − E(μo); the caller masks lanes below either horizon.
    #[inline(always)]
    pub(crate) fn f<R: Real>(&self, cos_i: R, one_minus_e_o: R) -> Rgb<R> {
        let ms = (R::ONE - self.slice.e_lanes(cos_i)) * one_minus_e_o;
        Rgb::from_f32(self.scale) * ms
    }
}

impl Microfacet {
    /// Takes α already clamped into [ALPHA_MIN, 1] (the caller warns),
    /// sets up compensation when asked (`kc`), and tabulates the directional
    /// albedo: single scattering (an adaptive quadrature per entry), plus the
    /// compensation lobe's exact factor · (1 − E(μo)), plus the diffuse ρd.
    pub fn new(params: MicrofacetParams, kc: Option<KcColor>) -> Microfacet {
        let kc = kc.map(|mode| Compensation::new(&params, mode));
        let e = Table1::build(MU_AXIS, |mu| {
            let s = params.specular_albedo(mu);
            let ms = kc.as_ref().map_or(0.0, |k| 1.0 - k.slice.e_at(mu));
            [0, 1, 2].map(|c| {
                let f = kc.as_ref().map_or(0.0, |k| k.factor[c] as f64);
                s[c] + f * ms + params.diffuse[c] as f64
            })
        });
        Microfacet {
            env_roughness: env_roughness(&params),
            params,
            albedo: AlbedoTable { e },
            kc,
        }
    }

    /// The model without the albedo table (for evaluating f only; its
    /// `albedo` is then zero). Cheap to build.
    pub fn new_without_table(params: MicrofacetParams, kc: Option<KcColor>) -> Microfacet {
        Microfacet {
            kc: kc.map(|mode| Compensation::new(&params, mode)),
            env_roughness: env_roughness(&params),
            params,
            albedo: AlbedoTable {
                e: Table1::from_nodes(MU_AXIS, vec![[0.0; 3]; N_MU]),
            },
        }
    }

    /// Tabulated E(μo) per channel: the lane lookup of `albedo` at f32.
    pub fn albedo_at(&self, mu_o: f32) -> [f32; 3] {
        self.albedo.e.lookup(mu_o)
    }
}

/// √ of the GGX α equivalent to the material's NDF at its α.
fn env_roughness(params: &MicrofacetParams) -> f32 {
    ggx_equivalent_alpha(params.ndf, params.alpha as f64).sqrt() as f32
}

/// The microfacet model's parameters per lane (module docs).
#[derive(Clone, Copy, Debug)]
pub struct MicrofacetLaneParams<R: Real> {
    /// Lambertian albedo ρd added to the specular lobe.
    pub diffuse: Rgb<R>,
}

impl<R: Real> LaneParams<R> for MicrofacetLaneParams<R> {}

/// A microfacet material's per-pixel state.
#[derive(Clone, Copy)]
pub struct MicrofacetPrepared<R: Real> {
    pub(crate) o: Outgoing<R>,
    /// ρd.
    pub(crate) diffuse: Rgb<R>,
    /// Smith Λ(o) of the view direction.
    pub(crate) lambda_o: R,
    /// 1 − E(μo) of the compensation lobe (unused without compensation).
    pub(crate) one_minus_e_o: R,
}

impl Brdf for Microfacet {
    type Params<R: Real> = MicrofacetLaneParams<R>;
    type Pixel<R: Real> = MicrofacetLaneParams<R>;
    type Prepared<R: Real> = MicrofacetPrepared<R>;
    type PolygonPrepared<R: Real> = MicrofacetPolygons<R>;
    const POLYGON_LIGHTS: bool = true;

    #[inline(always)]
    fn params<R: Real>(&self) -> MicrofacetLaneParams<R> {
        MicrofacetLaneParams {
            diffuse: Rgb::from_f32(self.params.diffuse),
        }
    }

    /// The parameters themselves: nothing to derive before the view.
    #[inline(always)]
    fn pixel<R: Real>(&self, params: &MicrofacetLaneParams<R>) -> MicrofacetLaneParams<R> {
        *params
    }

    #[inline(always)]
    fn params_lane<R: Real>(p: &MicrofacetLaneParams<R>, i: usize) -> MicrofacetLaneParams<f64> {
        MicrofacetLaneParams {
            diffuse: p.diffuse.lane(i),
        }
    }

    #[inline(always)]
    fn prepare_with<R: Real>(
        &self,
        params: &MicrofacetLaneParams<R>,
        wo: V3<R>,
    ) -> MicrofacetPrepared<R> {
        let o = Outgoing::new(wo);
        MicrofacetPrepared {
            diffuse: params.diffuse,
            lambda_o: self.params.lambda(o.cos_o),
            o,
            one_minus_e_o: match &self.kc {
                Some(k) => k.prepare(o.cos_o),
                None => R::ZERO,
            },
        }
    }

    #[inline(always)]
    fn f_local<R: Real>(&self, p: &MicrofacetPrepared<R>, wi: V3<R>) -> Rgb<R> {
        let params = &self.params;
        let h = HalfAngles::new(wi, &p.o);
        let mut f = params.specular(&h, p.lambda_o) + p.diffuse * R::FRAC_1_PI;
        if let Some(k) = &self.kc {
            f += k.f(h.cos_i, p.one_minus_e_o);
        }
        Rgb::select(h.above, f, Rgb::zero())
    }

    #[inline(always)]
    fn albedo_local<R: Real>(&self, p: &MicrofacetPrepared<R>) -> Rgb<R> {
        // The table holds the material's own ρd: a pixel's ρd replaces it
        // (exactly nothing to add where the pixel has the material's).
        let [r, g, b] = self.albedo.e.lookup(p.o.wo.z);
        let e = Rgb::new(r, g, b) + (p.diffuse - Rgb::from_f32(self.params.diffuse));
        Rgb::select(p.o.above, e, Rgb::zero())
    }

    /// ρd and the compensation lobe's albedo F_ms (1 − E(μo)) on the
    /// irradiance (both spread like a Lambertian lobe); the rest on the
    /// GGX lobe at the material's α, or for Beckmann and GTR at the GGX α
    /// whose normals spread like theirs (ggx_equivalent.rs).
    #[inline(always)]
    fn env_lobes<R: Real>(&self, p: &MicrofacetPrepared<R>) -> EnvLobes<R> {
        let total = self.albedo_local(p);
        let mut diffuse = p.diffuse;
        if let Some(k) = &self.kc {
            diffuse += Rgb::from_f32(k.factor) * p.one_minus_e_o;
        }
        let diffuse = Rgb::select(p.o.above, diffuse, Rgb::zero());
        EnvLobes::split(total, diffuse, R::splat(self.env_roughness as f64))
    }

    /// The GGX LTC lookup at this α and the view, with the factors of
    /// [`Brdf::polygon_local_with`] below folded per channel (zero where
    /// the view is below the horizon).
    #[inline(always)]
    fn prepare_polygons<R: Real>(&self, p: &MicrofacetPrepared<R>) -> MicrofacetPolygons<R> {
        let params = &self.params;
        let ltc = LtcGgx::new(R::splat(params.alpha as f64), p.o.wo);
        let ltc = match (params.ndf, params.smith) {
            (Ndf::Ggx, Smith::Separable) => ltc.with_separable_smith(),
            (Ndf::Ggx, _) => ltc,
            // Other lobes (refused under polygon lights by scenes and
            // eval; measured through the GGX fit by the tests) are not
            // the GGX lobe the correction follows.
            _ => ltc.without_lobe(),
        };
        let f0 = params.f0().map(|c| R::splat(c as f64));
        let specular = Rgb::new(
            ltc.schlick_albedo(f0[0]),
            ltc.schlick_albedo(f0[1]),
            ltc.schlick_albedo(f0[2]),
        );
        let mut diffuse = p.diffuse;
        if let Some(k) = &self.kc {
            diffuse += Rgb::from_f32(k.factor) * p.one_minus_e_o;
        }
        MicrofacetPolygons {
            ltc,
            specular: Rgb::select(p.o.above, specular, Rgb::zero()),
            diffuse: Rgb::select(p.o.above, diffuse, Rgb::zero()),
        }
    }

    /// The specular lobe by the GGX LTC at this α (ltc/ggx.rs; separable
    /// Smith uses the height-correlated fit, corrected toward its own lobe;
    /// Beckmann and GTR lobes would get the GGX fit at the same α, off by
    /// up to 30 %, so scenes and eval refuse polygon lights on them), with
    /// Schlick's split at F0 (`f0`: exact
    /// Fresnel kinds are taken at normal incidence); the diffuse base as ρd
    /// times the form factor (exact); the Kulla–Conty lobe as its albedo
    /// factor (1 − E(μo)) times the form factor (exact when 1 − E(μi) is
    /// replaced by its cosine-weighted mean 1 − E_avg).
    #[inline(always)]
    fn polygon_local_with<R: Real>(
        &self,
        _p: &MicrofacetPrepared<R>,
        pp: &MicrofacetPolygons<R>,
        poly: &PolygonLocal<R>,
    ) -> Rgb<R> {
        let (ff, spec) = pp.ltc.form_factor_and_integral(poly);
        pp.specular * spec + pp.diffuse * ff
    }
}

/// A microfacet material's per-pixel state for polygon lights.
#[derive(Clone, Copy)]
pub struct MicrofacetPolygons<R: Real> {
    pub(crate) ltc: LtcGgx<R>,
    /// F0 (n − n_w) + n_w per channel: the specular lobe's albedo.
    pub(crate) specular: Rgb<R>,
    /// ρd, plus the compensation lobe's factor · (1 − E(μo)): what
    /// multiplies the form factor.
    pub(crate) diffuse: Rgb<R>,
}

/// α clamped into [ALPHA_MIN, 1], and whether that changed it.
pub fn clamp_alpha(alpha: f32) -> (f32, bool) {
    let c = alpha.clamp(ALPHA_MIN, 1.0);
    (c, c != alpha)
}
