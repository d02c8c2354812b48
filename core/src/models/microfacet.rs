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

use crate::brdf::{Brdf, HalfAngles, LaneParams, Outgoing, ALPHA_MIN};
use crate::fresnel::{f_conductor, f_dielectric, f_schlick, r0_from_ior};
use crate::gtr_lambda::GtrLambdaTable;
use crate::kulla_conty::{color_factor, f_avg, slice_for, KcColor, KcSlice};
use crate::light::PolygonLocal;
use crate::ltc::ggx::LtcGgx;
use crate::masking::{g2_height_correlated, g2_separable, lambda_beckmann, lambda_ggx};
use crate::ndf::{d_beckmann, d_ggx, d_gtr};
use crate::quadrature::{adaptive_simpson, simpson};
use crate::real::Real;
use crate::table::{Axis, Nodes, Table1, Warp};
use crate::vec3::{Rgb, V3};
use std::sync::Arc;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ndf {
    Ggx,
    Beckmann,
    /// Generalized Trowbridge–Reitz with exponent γ > 0 (γ = 2 is GGX).
    Gtr {
        gamma: f32,
    },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Smith {
    Separable,
    HeightCorrelated,
}

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

/// Which Smith Λ a GTR distribution uses (the other NDFs ignore it).
#[derive(Clone, Debug, PartialEq, Default)]
pub enum GtrLambda {
    /// GGX's Λ at the same α: cheap, exact at γ = 2, and for γ < 2 a lobe
    /// that reflects more than it receives at grazing angles (module docs).
    #[default]
    Ggx,
    /// The distribution's own Λ, tabulated at the material's (γ, α)
    /// (gtr_lambda.rs).
    Exact(Arc<GtrLambdaTable>),
}

impl GtrLambda {
    /// The exact Λ of GTR(γ, α), tabulated now (~1e5 evaluations of D).
    pub fn exact(gamma: f32, alpha: f32) -> GtrLambda {
        GtrLambda::Exact(Arc::new(GtrLambdaTable::new(gamma as f64, alpha as f64)))
    }
}

/// Parameters of the model; see the module docs. Build with
/// [`Microfacet::new`], which validates α and tabulates the albedo.
#[derive(Clone, Debug, PartialEq)]
pub struct MicrofacetParams {
    pub ndf: Ndf,
    /// Roughness as the NDF takes it, in [ALPHA_MIN, 1].
    pub alpha: f32,
    pub smith: Smith,
    pub fresnel: Fresnel,
    /// Lambertian albedo added to the specular lobe.
    pub diffuse: [f32; 3],
    /// Smith Λ of GTR: GGX's (default) or the exact one, tabulated for
    /// this γ and α (build it with [`GtrLambda::exact`] at the same values).
    pub gtr_lambda: GtrLambda,
}

/// Directional albedo E(μo) per channel at `N_MU` texel centres
/// μ_j = (j + ½)/N_MU, linear interpolation clamped at the ends.
#[derive(Clone, Debug, PartialEq)]
pub struct AlbedoTable {
    e: Table1<3>,
}

const N_MU: usize = 64;
const MU_AXIS: Axis = Axis::new(N_MU, 0.0, 1.0, Warp::Linear, Nodes::Centres);
/// Simpson intervals (even) over φ in `albedo_ring`.
const N_PHI: usize = 32;

#[derive(Clone, Debug, PartialEq)]
pub struct Microfacet {
    pub params: MicrofacetParams,
    albedo: AlbedoTable,
    /// Kulla–Conty compensation, when enabled.
    kc: Option<Compensation>,
}

/// The compensation lobe of one material: E(μ) at its α, E_avg, and the
/// colour factor per channel (kulla_conty.rs).
#[derive(Clone, Debug, PartialEq)]
pub struct Compensation {
    pub slice: KcSlice,
    pub factor: [f32; 3],
    /// factor / (π (1 − E_avg)) per channel: everything in f_ms that does
    /// not depend on the directions, folded once here.
    scale: [f32; 3],
}

impl Compensation {
    pub fn new(p: &MicrofacetParams, mode: KcColor) -> Compensation {
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
    pub fn prepare<R: Real>(&self, cos_o: R) -> R {
        R::ONE - self.slice.e_lanes(cos_o)
    }

    /// f_ms(μi, μo) · factor, per channel (no cosine), from the prepared
    /// 1 − E(μo); the caller masks lanes below either horizon.
    #[inline(always)]
    pub fn f<R: Real>(&self, cos_i: R, one_minus_e_o: R) -> Rgb<R> {
        let ms = (R::ONE - self.slice.e_lanes(cos_i)) * one_minus_e_o;
        Rgb::from_f32(self.scale) * ms
    }
}

impl MicrofacetParams {
    /// D(h) for the chosen NDF, from cos²θh and sin²θh.
    #[inline(always)]
    pub fn d<R: Real>(&self, cos2_h: R, sin2_h: R) -> R {
        let alpha = R::splat(self.alpha as f64);
        match self.ndf {
            Ndf::Ggx => d_ggx(alpha, cos2_h, sin2_h),
            Ndf::Beckmann => d_beckmann(alpha, cos2_h, sin2_h),
            Ndf::Gtr { gamma } => d_gtr(alpha, gamma as f64, cos2_h, sin2_h),
        }
    }

    /// Smith Λ matching the NDF (for GTR: GGX's, or the exact table).
    #[inline(always)]
    pub fn lambda<R: Real>(&self, cos: R) -> R {
        let alpha = R::splat(self.alpha as f64);
        match (self.ndf, &self.gtr_lambda) {
            (Ndf::Beckmann, _) => lambda_beckmann(alpha, cos),
            (Ndf::Gtr { .. }, GtrLambda::Exact(t)) => t.lambda(cos),
            (Ndf::Ggx | Ndf::Gtr { .. }, _) => lambda_ggx(alpha, cos),
        }
    }

    /// G2 from the two Λ.
    #[inline(always)]
    pub fn g2<R: Real>(&self, cos_i: R, cos_o: R) -> R {
        self.g2_lambdas(self.lambda(cos_i), self.lambda(cos_o))
    }

    /// G2 from Λ(i) and Λ(o) already formed.
    #[inline(always)]
    pub fn g2_lambdas<R: Real>(&self, li: R, lo: R) -> R {
        match self.smith {
            Smith::Separable => g2_separable(li, lo),
            Smith::HeightCorrelated => g2_height_correlated(li, lo),
        }
    }

    /// F at cos θd = i·h, per channel.
    #[inline(always)]
    pub fn f<R: Real>(&self, cos_d: R) -> Rgb<R> {
        match self.fresnel {
            Fresnel::Schlick { f0 } => f_schlick(Rgb::from_f32(f0), cos_d),
            Fresnel::Dielectric { ior } => Rgb::splat(f_dielectric(cos_d, R::splat(ior as f64))),
            Fresnel::Conductor { eta, k } => Rgb::new(
                f_conductor(cos_d, R::splat(eta[0] as f64), R::splat(k[0] as f64)),
                f_conductor(cos_d, R::splat(eta[1] as f64), R::splat(k[1] as f64)),
                f_conductor(cos_d, R::splat(eta[2] as f64), R::splat(k[2] as f64)),
            ),
        }
    }

    /// The specular lobe F G2 D / (4 μi μo) (no diffuse, no cosine) for
    /// angles already formed and the view's Λ(o) (a per-pixel value); the
    /// caller zeroes lanes outside `h.above`.
    #[inline(always)]
    pub fn specular<R: Real>(&self, h: &HalfAngles<R>, lambda_o: R) -> Rgb<R> {
        let g2 = self.g2_lambdas(self.lambda(h.cos_i), lambda_o);
        let dg = self.d(h.cos2_h, h.sin2_h) * g2 / (R::splat(4.0) * h.cos_i * h.cos_o);
        self.f(h.cos_d) * dg
    }

    /// E_spec(μo) = ∫ f cos θi dωi (F included), by deterministic
    /// quadrature in half-vector space. With u the CDF of D(h)(n·h) over θh
    /// (so D(h)(n·h) dωh = du dφ / 2π) and dωi = 4 (o·h) dωh:
    ///
    /// E = (1/2π) ∫₀¹ ring(u) du,  ring(u) = ∫ F G2 (o·h) / (μo cos θh) dφ
    ///
    /// over the φ where o·h > 0 and wi is above the horizon; for fixed θh
    /// both read cos φ > c, so the φ range is [−φmax, φmax] in closed form and
    /// the ring integrand is smooth: Simpson in φ. ring(u) has kinks where
    /// that range opens, so u is integrated by adaptive Simpson (tolerance
    /// 1e-5). Sampling h ∝ D(h)(n·h) instead was off by up to 6e-3 at grazing
    /// μo, where the weight (o·h)/(μo cos θh) swings with φ.
    pub fn specular_albedo(&self, mu_o: f64) -> [f64; 3] {
        let mu_o = mu_o.clamp(1e-6, 1.0);
        let ring = |u: f64| self.albedo_ring(mu_o, u);
        // Adaptive Simpson can stop early on a panel whose five samples miss
        // a kink; starting from 16 panels makes that unlikely.
        const PANELS: usize = 16;
        let mut s = [0.0f64; 3];
        for p in 0..PANELS {
            let a = (p as f64 / PANELS as f64).max(1e-9);
            let b = ((p + 1) as f64 / PANELS as f64).min(1.0 - 1e-9);
            let m = 0.5 * (a + b);
            let (fa, fm, fb) = (ring(a), ring(m), ring(b));
            let whole = simpson(a, b, fa, fm, fb);
            let part = adaptive_simpson(&ring, a, b, fa, fm, fb, whole, 1e-5 / PANELS as f64, 40);
            for c in 0..3 {
                s[c] += part[c];
            }
        }
        s.map(|v| v / std::f64::consts::TAU)
    }

    /// ring(u) of [`MicrofacetParams::specular_albedo`], per channel.
    fn albedo_ring(&self, mu_o: f64, u: f64) -> [f64; 3] {
        let cos_h = self.sample_cos_h(u);
        if cos_h <= 0.0 {
            return [0.0; 3];
        }
        let sin_o = (1.0 - mu_o * mu_o).max(0.0).sqrt();
        let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
        // o·h = sin_o sin_h cos φ + μo cos_h > 0 and
        // wi.z = 2 (o·h) cos_h − μo > 0: both lower bounds on cos φ.
        let a = sin_o * sin_h;
        let c = if a > 1e-300 {
            (-mu_o * cos_h / a).max(mu_o * (1.0 - 2.0 * cos_h * cos_h) / (2.0 * cos_h * a))
        } else if 2.0 * cos_h * cos_h > 1.0 {
            -1.0
        } else {
            1.0
        };
        if c >= 1.0 {
            return [0.0; 3];
        }
        let phi_max = c.max(-1.0).acos();
        let step = phi_max / N_PHI as f64;
        let mut ring = [0.0f64; 3];
        for k in 0..=N_PHI {
            // Simpson weights 1, 4, 2, …, 4, 1 (N_PHI even).
            let w = if k == 0 || k == N_PHI {
                1.0
            } else if k % 2 == 1 {
                4.0
            } else {
                2.0
            };
            let phi = k as f64 * step;
            let o_h = (a * phi.cos() + mu_o * cos_h).max(0.0);
            let wi_z = 2.0 * o_h * cos_h - mu_o;
            if wi_z <= 0.0 {
                continue;
            }
            let g = self.g2(wi_z, mu_o) * o_h / (mu_o * cos_h);
            let f = self.f(o_h);
            ring[0] += w * f.x * g;
            ring[1] += w * f.y * g;
            ring[2] += w * f.z * g;
        }
        // ∫ over [−φmax, φmax] = 2 × Simpson over [0, φmax].
        ring.map(|r| 2.0 * r * step / 3.0)
    }

    /// F at normal incidence per channel: Schlick's F0, or the exact
    /// Fresnel's value at cos θ = 1 (what the LTC's Schlick split takes for
    /// the other Fresnel kinds).
    pub fn f0(&self) -> [f32; 3] {
        match self.fresnel {
            Fresnel::Schlick { f0 } => f0,
            Fresnel::Dielectric { ior } => [r0_from_ior(ior as f64) as f32; 3],
            Fresnel::Conductor { eta, k } => {
                core::array::from_fn(|c| f_conductor(1.0f64, eta[c] as f64, k[c] as f64) as f32)
            }
        }
    }

    /// Inverts the CDF of D(h)(n·h) over θh: cos θh for uniform u ∈ (0, 1).
    fn sample_cos_h(&self, u: f64) -> f64 {
        let a2 = (self.alpha as f64).powi(2);
        let cos2 = match self.ndf {
            Ndf::Ggx => (1.0 - u) / (1.0 + (a2 - 1.0) * u),
            Ndf::Beckmann => 1.0 / (1.0 - a2 * (1.0 - u).ln()),
            Ndf::Gtr { gamma } => {
                let g = gamma as f64;
                if (a2 - 1.0).abs() < 1e-4 {
                    1.0 - u // D uniform: cos²θ uniform
                } else if (g - 1.0).abs() < 1e-4 {
                    (1.0 - a2.powf(1.0 - u)) / (1.0 - a2) // [Burley12, eq. 2]
                } else {
                    // [Burley12, App. B]: cos²θ = (1 − ((α²)^(1−γ)(1−u) + u)^(1/(1−γ))) / (1 − α²)
                    (1.0 - (a2.powf(1.0 - g) * (1.0 - u) + u).powf(1.0 / (1.0 - g))) / (1.0 - a2)
                }
            }
        };
        cos2.clamp(0.0, 1.0).sqrt()
    }
}

impl Microfacet {
    /// Takes α already clamped into [ALPHA_MIN, 1] (the caller warns),
    /// sets up compensation when asked (`kc`), and tabulates the directional
    /// albedo: single scattering (quadrature, ~1 ms per entry), plus the
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
    pub o: Outgoing<R>,
    /// ρd.
    pub diffuse: Rgb<R>,
    /// Smith Λ(o) of the view direction.
    pub lambda_o: R,
    /// 1 − E(μo) of the compensation lobe (unused without compensation).
    pub one_minus_e_o: R,
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

    /// The GGX LTC lookup at this α and the view, with the factors of
    /// [`Brdf::polygon_local_with`] below folded per channel (zero where
    /// the view is below the horizon).
    #[inline(always)]
    fn prepare_polygons<R: Real>(&self, p: &MicrofacetPrepared<R>) -> MicrofacetPolygons<R> {
        let params = &self.params;
        let ltc = LtcGgx::new(R::splat(params.alpha as f64), p.o.wo);
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
    /// Smith uses the height-correlated fit, measured p90 1.3 %, max 9 %;
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
    pub ltc: LtcGgx<R>,
    /// F0 (n − n_w) + n_w per channel: the specular lobe's albedo.
    pub specular: Rgb<R>,
    /// ρd, plus the compensation lobe's factor · (1 − E(μo)): what
    /// multiplies the form factor.
    pub diffuse: Rgb<R>,
}

/// α clamped into [ALPHA_MIN, 1], and whether that changed it.
pub fn clamp_alpha(alpha: f32) -> (f32, bool) {
    let c = alpha.clamp(ALPHA_MIN, 1.0);
    (c, c != alpha)
}
