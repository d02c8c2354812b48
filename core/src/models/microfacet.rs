//! The microfacet BRDF of the course notes, every term selectable:
//!
//! f(i, o) = F(i·h) G2(i, o) D(h) / (4 (n·i)(n·o)) + ρd / π
//!
//! D: GGX, Beckmann or GTR(γ); G2: separable or height-correlated Smith
//! with the NDF's Λ (GTR with γ ≠ 2 uses the GGX Λ at the same α: GTR has
//! no closed-form Λ); F: Schlick (F0), exact dielectric (IOR) or exact
//! conductor (η, κ per channel); an optional Lambertian base ρd is added
//! (not weighted: the notes' "microfacet + diffuse" sum).
//!
//! Uniform environment light needs the directional albedo E(μo): it is
//! tabulated per material when the material is built (`AlbedoTable`).

use crate::brdf::{Brdf, HalfAngles, ALPHA_MIN};
use crate::fresnel::{f_conductor, f_dielectric, f_schlick};
use crate::masking::{g2_height_correlated, g2_separable, lambda_beckmann, lambda_ggx};
use crate::ndf::{d_beckmann, d_ggx, d_gtr};
use crate::real::Real;
use crate::vec3::{Rgb, V3};

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
}

/// Directional albedo E(μo) per channel at `N_MU` texel centres
/// μ_j = (j + ½)/N_MU, linear interpolation clamped at the ends.
#[derive(Clone, Debug, PartialEq)]
pub struct AlbedoTable {
    e: Vec<[f32; 3]>,
}

const N_MU: usize = 64;
/// Quadrature points per table entry (Hammersley, NDF importance sampling).
const SAMPLES: u32 = 4096;

#[derive(Clone, Debug, PartialEq)]
pub struct Microfacet {
    pub params: MicrofacetParams,
    albedo: AlbedoTable,
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

    /// Smith Λ matching the NDF (GGX's for GTR).
    #[inline(always)]
    pub fn lambda<R: Real>(&self, cos: R) -> R {
        let alpha = R::splat(self.alpha as f64);
        match self.ndf {
            Ndf::Beckmann => lambda_beckmann(alpha, cos),
            Ndf::Ggx | Ndf::Gtr { .. } => lambda_ggx(alpha, cos),
        }
    }

    /// G2 from the two Λ.
    #[inline(always)]
    pub fn g2<R: Real>(&self, cos_i: R, cos_o: R) -> R {
        let (li, lo) = (self.lambda(cos_i), self.lambda(cos_o));
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

    /// The specular lobe F G2 D / (4 μi μo) (no diffuse, no cosine); zero
    /// below either horizon.
    #[inline(always)]
    pub fn specular<R: Real>(&self, n: V3<R>, wi: V3<R>, wo: V3<R>) -> Rgb<R> {
        let HalfAngles {
            cos_i,
            cos_o,
            above,
            cos2_h,
            sin2_h,
            cos_d,
        } = HalfAngles::new(n, wi, wo);
        let dg = self.d(cos2_h, sin2_h) * self.g2(cos_i, cos_o) / (R::splat(4.0) * cos_i * cos_o);
        Rgb::select(above, self.f(cos_d) * dg, Rgb::zero())
    }

    /// E_spec(μo) (F included) by importance sampling h ∝ D(h)(n·h):
    /// f cos θi / pdf(wi) = F G2 (o·h) / (μo (n·h)).
    fn specular_albedo(&self, mu_o: f64) -> [f64; 3] {
        let wo = V3::new((1.0 - mu_o * mu_o).max(0.0).sqrt(), 0.0, mu_o);
        let mut s = [0.0f64; 3];
        for i in 0..SAMPLES {
            let (u1, u2) = (
                (i as f64 + 0.5) / SAMPLES as f64,
                i.reverse_bits() as f64 / 4294967296.0,
            );
            let cos_h = self.sample_cos_h(u1);
            let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
            let phi = std::f64::consts::TAU * u2;
            let h = V3::new(sin_h * phi.cos(), sin_h * phi.sin(), cos_h);
            let o_h = wo.dot(h);
            if o_h <= 0.0 || cos_h <= 0.0 {
                continue;
            }
            let wi = h * (2.0 * o_h) - wo;
            if wi.z <= 0.0 {
                continue;
            }
            let w = self.g2(wi.z, mu_o) * o_h / (mu_o * cos_h);
            let f = self.f(wi.dot(h));
            s[0] += f.x * w;
            s[1] += f.y * w;
            s[2] += f.z * w;
        }
        s.map(|v| v / SAMPLES as f64)
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
    /// Validates α (clamped into [ALPHA_MIN, 1] by the caller, which warns)
    /// and tabulates the directional albedo (~65k f64 evaluations).
    pub fn new(params: MicrofacetParams) -> Microfacet {
        let e = (0..N_MU)
            .map(|j| {
                let mu = (j as f64 + 0.5) / N_MU as f64;
                let s = params.specular_albedo(mu);
                [0, 1, 2].map(|c| (s[c] + params.diffuse[c] as f64) as f32)
            })
            .collect();
        Microfacet {
            params,
            albedo: AlbedoTable { e },
        }
    }

    /// The model without the albedo table (for evaluating f only; its
    /// `albedo` is then zero). Cheap to build.
    pub fn new_without_table(params: MicrofacetParams) -> Microfacet {
        Microfacet {
            params,
            albedo: AlbedoTable {
                e: vec![[0.0; 3]; N_MU],
            },
        }
    }

    /// Tabulated E(μo), one channel set (scalar twin of the lane lookup).
    pub fn albedo_at(&self, mu_o: f32) -> [f32; 3] {
        let x = (mu_o * N_MU as f32 - 0.5).clamp(0.0, (N_MU - 1) as f32);
        let j0 = x as usize;
        let j1 = (j0 + 1).min(N_MU - 1);
        let t = x - j0 as f32;
        let (a, b) = (self.albedo.e[j0], self.albedo.e[j1]);
        [0, 1, 2].map(|c| a[c] + (b[c] - a[c]) * t)
    }
}

impl Brdf for Microfacet {
    #[inline(always)]
    fn f<R: Real>(&self, n: V3<R>, wi: V3<R>, wo: V3<R>) -> Rgb<R> {
        let p = &self.params;
        let above = n.dot(wi).gt(R::ZERO) & n.dot(wo).gt(R::ZERO);
        let diffuse = Rgb::select(above, Rgb::from_f32(p.diffuse) * R::FRAC_1_PI, Rgb::zero());
        p.specular(n, wi, wo) + diffuse
    }

    fn albedo<R: Real>(&self, n: V3<R>, wo: V3<R>) -> Rgb<R> {
        let mu = n.dot(wo);
        let mut out = [[0.0f32; 8]; 3];
        for lane in 0..R::LANES {
            let e = self.albedo_at(mu.lane(lane) as f32);
            for (o, v) in out.iter_mut().zip(e) {
                o[lane] = v;
            }
        }
        let e = Rgb::new(R::load(&out[0]), R::load(&out[1]), R::load(&out[2]));
        Rgb::select(mu.gt(R::ZERO), e, Rgb::zero())
    }
}

/// α clamped into [ALPHA_MIN, 1], and whether that changed it.
pub fn clamp_alpha(alpha: f32) -> (f32, bool) {
    let c = alpha.clamp(ALPHA_MIN, 1.0);
    (c, c != alpha)
}
