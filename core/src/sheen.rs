//! The sheen lobe of KHR_materials_sheen: the "Charlie" microfiber
//! distribution and its visibility \[Conty17; KhrSheen\], and the lobe's
//! directional albedo E(μ), which scales the layer beneath it.
//!
//! With α = sheen_roughness² (the extension's `alphaG`):
//!
//! - D(h) = (2 + 1/α) sin^(1/α)θh / (2π) (`d_charlie`);
//! - V = 1 / ((1 + Λ(μo) + Λ(μi)) 4 μo μi) (`v_charlie`), with the
//!   fitted Λ of `lambda_sheen`;
//! - f_sheen = sheen_color · D · V (no Fresnel: the extension lets F = 1);
//! - E(μ, sheen_roughness) = ∫ D V μi dωi at sheen_color = 1, the lobe's
//!   directional albedo, tabulated here by quadrature ([`SheenTable`]).
//!
//! α is floored at `SHEEN_ALPHA_MIN`: the extension's default roughness
//! is 0, where 1/α is infinite; below the floor D's peak, (2 + 1/α)/(2π),
//! and the power 1/(2α) of sin²θh leave what f32 resolves well, and the
//! lobe is already confined to within a few degrees of the horizon.

use crate::quadrature::GaussLegendre;
use crate::real::Real;
use crate::table::{Axis, Nodes, Table2, Warp};
use crate::vec3::V3;
use std::f64::consts::PI;
use std::sync::OnceLock;

/// Smallest sheen α (module docs): sheen_roughness below ≈ 0.032 acts as
/// ≈ 0.032.
pub(crate) const SHEEN_ALPHA_MIN: f64 = 1e-3;

/// α = max(sheen_roughness², [`SHEEN_ALPHA_MIN`]).
#[inline(always)]
pub(crate) fn sheen_alpha<R: Real>(sheen_roughness: R) -> R {
    (sheen_roughness * sheen_roughness).max(R::splat(SHEEN_ALPHA_MIN))
}

/// Charlie sheen distribution [Conty17; KhrSheen]:
/// D(h) = (2 + 1/α) (sin²θh)^(1/(2α)) / (2π).
///
/// Takes sin²θh (see ndf.rs for why not cos θh); its power is formed as
/// exp(ln(sin²θh) / (2α)), with sin²θh floored at 1e-30 so that h = n
/// gives exp(−huge) = 0 rather than ln(0).
#[inline(always)]
pub(crate) fn d_charlie<R: Real>(alpha: R, sin2_theta_h: R) -> R {
    let inv = R::ONE / alpha;
    let p = (sin2_theta_h.max(R::splat(1e-30)).ln() * inv * R::HALF).exp();
    (R::splat(2.0) + inv) * p * R::splat(0.5 * std::f64::consts::FRAC_1_PI)
}

/// The fitted exponent of the Charlie Λ [Conty17; KhrSheen]: with
/// t = (1 − α)²,
/// l(x) = a / (1 + b x^c) + d x + e, each of a…e = mix(value at α = 1,
/// value at α = 0, t). `x` > 0 (x^c is exp(c ln x), x floored at 1e-30).
#[inline(always)]
fn l_sheen<R: Real>(x: R, t: R) -> R {
    let mix = |a0: f64, a1: f64| R::splat(a1 - a0).mul_add(t, R::splat(a0));
    let (a, b, c) = (
        mix(21.5473, 25.3245),
        mix(3.82987, 3.32435),
        mix(0.19823, 0.16801),
    );
    let (d, e) = (mix(-1.97760, -1.27393), mix(-4.32054, -4.85967));
    let xc = (c * x.max(R::splat(1e-30)).ln()).exp();
    a / b.mul_add(xc, R::ONE) + d.mul_add(x, e)
}

/// Charlie Λ(θ) for cos θ ∈ (0, 1] [Conty17; KhrSheen]:
/// exp(l(cos θ)) for cos θ < ½, exp(2 l(½) − l(1 − cos θ)) otherwise.
#[inline(always)]
pub(crate) fn lambda_sheen<R: Real>(alpha: R, cos_theta: R) -> R {
    let t = (R::ONE - alpha) * (R::ONE - alpha);
    let low = l_sheen(cos_theta, t);
    let high = R::splat(2.0) * l_sheen(R::HALF, t) - l_sheen(R::ONE - cos_theta, t);
    R::select(cos_theta.lt(R::HALF), low, high).exp()
}

/// Charlie visibility V = 1 / ((1 + Λ(μo) + Λ(μi)) 4 μo μi), from the two
/// Λ (a shader forms the view's once per pixel); cosines > 0.
#[inline(always)]
pub(crate) fn v_charlie<R: Real>(lambda_i: R, lambda_o: R, cos_i: R, cos_o: R) -> R {
    R::ONE / ((R::ONE + lambda_i + lambda_o) * (R::splat(4.0) * cos_i * cos_o))
}

/// The sheen lobe D V at sheen_color = 1 for unit local directions above
/// the horizon (f64; what the table integrates).
pub(crate) fn sheen_lobe(alpha: f64, wi: V3<f64>, wo: V3<f64>) -> f64 {
    let s = wi + wo;
    let len2 = s.length_squared();
    if len2 <= 0.0 || wi.z <= 0.0 || wo.z <= 0.0 {
        return 0.0;
    }
    let sin2_h = (s.x * s.x + s.y * s.y) / len2;
    let (li, lo) = (lambda_sheen(alpha, wi.z), lambda_sheen(alpha, wo.z));
    d_charlie(alpha, sin2_h) * v_charlie(li, lo, wi.z, wo.z)
}

/// μ nodes, ends included, √ spacing (the albedo changes fastest at
/// grazing views).
pub const SHEEN_MU_AXIS: Axis = Axis::new(64, 0.0, 1.0, Warp::Sqrt, Nodes::Ends);
/// sheen_roughness nodes, ends included, √ spacing (E changes fastest at
/// small roughness).
pub const SHEEN_ROUGHNESS_AXIS: Axis = Axis::new(32, 0.0, 1.0, Warp::Sqrt, Nodes::Ends);

/// E(μo, sheen_roughness) = ∫ D V μi dωi by Gauss–Legendre in t with
/// μi = t² (64 nodes; dμi = 2t dt puts nodes toward the horizon, where the
/// lobe lives) times the midpoint rule in φ over [0, π] (128 nodes; the
/// lobe is even in φ, the view's azimuth being 0).
pub fn sheen_albedo_quadrature(mu_o: f64, sheen_roughness: f64) -> f64 {
    const N_T: usize = 64;
    const N_PHI: usize = 128;
    let alpha = sheen_alpha(sheen_roughness);
    let mu_o = mu_o.clamp(1e-6, 1.0);
    let wo = V3::new((1.0 - mu_o * mu_o).sqrt(), 0.0, mu_o);
    let rule = GaussLegendre::new(N_T);
    let mut acc = 0.0;
    for k in 0..N_PHI {
        let phi = PI * (k as f64 + 0.5) / N_PHI as f64;
        for (x, w) in rule.nodes_weights() {
            let t = 0.5 * (x + 1.0);
            let mu = t * t;
            let s = (1.0 - mu * mu).max(0.0).sqrt();
            let wi = V3::new(s * phi.cos(), s * phi.sin(), mu);
            // μi dωi over both halves of φ: μi · 2t (dt = w/2) · 2 dφ.
            acc += sheen_lobe(alpha, wi, wo) * mu * 2.0 * t * 0.5 * w * 2.0 * PI / N_PHI as f64;
        }
    }
    acc
}

/// The sheen lobe's directional albedo over (μ, sheen_roughness), built
/// once per process on first use (64 μ × 32 roughness quadratures of
/// 8192 evaluations; core/tests/gltf.rs measures it against an independent
/// integration).
pub struct SheenTable {
    e: Table2<1>,
    /// K(μo, sheen_roughness) = 2 ∫₀¹ (E(μ) − E(μo))⁺ μ dμ: what the
    /// albedo scaling 1 − max3 max(E(μo), E(μi)) takes from a Lambertian
    /// lobe beyond its view-only form 1 − max3 E(μo), per unit albedo and
    /// max3 (models/gltf.rs, "Lights").
    k: Table2<1>,
}

impl SheenTable {
    pub fn get() -> &'static SheenTable {
        static T: OnceLock<SheenTable> = OnceLock::new();
        T.get_or_init(|| {
            let e = Table2::build(SHEEN_MU_AXIS, SHEEN_ROUGHNESS_AXIS, |mu, r| {
                [sheen_albedo_quadrature(mu, r)]
            });
            // K by Gauss–Legendre (128 nodes) in t with μ = t² over the
            // interpolated E, dμ μ = 2t³ dt.
            let rule = GaussLegendre::new(128);
            let k = Table2::build(SHEEN_MU_AXIS, SHEEN_ROUGHNESS_AXIS, |mu_o, r| {
                let [e_o] = e.lookup(mu_o, r);
                let mut acc = 0.0;
                for (x, w) in rule.nodes_weights() {
                    let t = 0.5 * (x + 1.0);
                    let [e_i] = e.lookup(t * t, r);
                    acc += (e_i - e_o).max(0.0) * 2.0 * t * t * t * 0.5 * w;
                }
                [2.0 * acc]
            });
            SheenTable { e, k }
        })
    }

    /// E(μ, sheen_roughness) per lane (μ clamped into [0, 1]).
    #[inline(always)]
    pub fn e<R: Real>(&self, mu: R, sheen_roughness: R) -> R {
        let [e] = self.e.lookup(mu, sheen_roughness);
        e
    }

    /// K(μo, sheen_roughness) per lane (see the field).
    #[inline(always)]
    pub(crate) fn k<R: Real>(&self, mu: R, sheen_roughness: R) -> R {
        let [k] = self.k.lookup(mu, sheen_roughness);
        k
    }
}
