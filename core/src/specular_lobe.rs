//! The microfacet specular lobe with every term selectable,
//!
//! f_spec(i, o) = F(i·h) G2(i, o) D(h) / (4 (n·i)(n·o)),
//!
//! and its directional albedo by quadrature: the part of the microfacet
//! model (models/microfacet.rs) that the Kulla–Conty tables
//! (kulla_conty.rs) are built from, so it sits below both. The term
//! choices are the enums of their families: [`Ndf`] (ndf.rs), [`Smith`]
//! (masking.rs), [`Fresnel`] (fresnel.rs) and [`GtrLambda`]
//! (gtr_lambda.rs).

use crate::brdf::HalfAngles;
use crate::fresnel::{f_conductor, f_dielectric, f_schlick, r0_from_ior, Fresnel};
use crate::gtr_lambda::GtrLambda;
use crate::masking::{g2_height_correlated, g2_separable, lambda_beckmann, lambda_ggx, Smith};
use crate::ndf::{d_beckmann, d_ggx, d_gtr, Ndf};
use crate::quadrature::{adaptive_simpson, simpson};
use crate::real::Real;
use crate::vec3::Rgb;

/// Parameters of the microfacet model (models/microfacet.rs): its terms,
/// α and diffuse base. Build the model with
/// [`Microfacet::new`](crate::models::Microfacet::new), which tabulates
/// the albedo.
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

/// Simpson intervals (even) over φ in `albedo_ring`.
const N_PHI: usize = 32;

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
    pub(crate) fn g2_lambdas<R: Real>(&self, li: R, lo: R) -> R {
        match self.smith {
            Smith::Separable => g2_separable(li, lo),
            Smith::HeightCorrelated => g2_height_correlated(li, lo),
        }
    }

    /// F at cos θd = i·h, per channel.
    #[inline(always)]
    pub(crate) fn f<R: Real>(&self, cos_d: R) -> Rgb<R> {
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
    pub(crate) fn specular<R: Real>(&self, h: &HalfAngles<R>, lambda_o: R) -> Rgb<R> {
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
    /// the ring integrand is smooth: Simpson in φ. ring(u) is not smooth
    /// where that range starts to close or vanishes (a kink, or at μo = 1 a
    /// step), so u is integrated by adaptive Simpson (tolerance 1e-5) on
    /// pieces that end there (`MicrofacetParams::albedo_breaks`).
    /// Sampling h ∝ D(h)(n·h) instead was off by up to 6e-3 at grazing μo,
    /// where the weight (o·h)/(μo cos θh) swings with φ.
    pub fn specular_albedo(&self, mu_o: f64) -> [f64; 3] {
        let mu_o = mu_o.clamp(1e-6, 1.0);
        let ring = |u: f64| self.albedo_ring(mu_o, u);
        // Adaptive Simpson can stop early on a panel whose five samples miss
        // a kink; 16 panels, cut at the known kinks, make that unlikely.
        const PANELS: usize = 16;
        let mut ends: Vec<f64> = (0..=PANELS).map(|p| p as f64 / PANELS as f64).collect();
        ends.extend(self.albedo_breaks(mu_o));
        ends.sort_by(f64::total_cmp);
        ends.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
        let mut s = [0.0f64; 3];
        for w in ends.windows(2) {
            let a = w[0].max(1e-9);
            let b = w[1].min(1.0 - 1e-9);
            if b <= a {
                continue;
            }
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

    /// The u of [`MicrofacetParams::albedo_ring`] where its φ range changes
    /// form, with θo = acos μo: wi, the mirror of o about h, is above the
    /// horizon for every φ while θh < (90° − θo)/2 (h tilted away from o)
    /// and for no φ once θh > (90° + θo)/2 (h tilted toward o); o·h > 0 for
    /// every φ while θh < 90° − θo. At μo = 1 the first two meet and the
    /// ring steps from whole to empty.
    fn albedo_breaks(&self, mu_o: f64) -> Vec<f64> {
        let theta_o = mu_o.clamp(-1.0, 1.0).acos();
        let quarter = std::f64::consts::FRAC_PI_4;
        [
            quarter - 0.5 * theta_o,
            quarter + 0.5 * theta_o,
            2.0 * quarter - theta_o,
        ]
        .into_iter()
        .filter(|t| *t > 0.0 && *t < 2.0 * quarter)
        .map(|t| self.u_of_cos_h(t.cos()))
        .collect()
    }

    /// Inverts [`MicrofacetParams::sample_cos_h`] (decreasing in u) by
    /// bisection: the u whose cos θh is `cos_h`.
    fn u_of_cos_h(&self, cos_h: f64) -> f64 {
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            if self.sample_cos_h(mid) > cos_h {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
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
    pub(crate) fn f0(&self) -> [f32; 3] {
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
