//! The exact Smith Λ of the GTR distribution (masking.rs has the closed
//! forms of GGX and Beckmann; GTR with γ ∉ {2} has none).   [Heitz14, eq. 72]
//!
//! Smith's Λ of a direction v at cos θv = μ is the projected area of the
//! back-facing microfacets over the geometric one:
//!
//! Λ(μ) = (1/μ) ∫ over m with v·m < 0 of |v·m| D(m) dω_m.
//!
//! For an isotropic D, with v = (s, 0, μ), s = √(1 − μ²), the φ integral at
//! fixed θm has a closed form: with A = s sin θ, B = μ cos θ, v·m =
//! A cos φ + B is negative for cos φ < −B/A, which happens only for
//! θ > θ0 = π/2 − θv, and there
//!
//! ∫ max(0, −(A cos φ + B)) dφ = 2 √(A² − B²) − 2 B acos(B/A).
//!
//! That leaves μΛ(μ) = ∫_{θ0}^{π/2} D(θ) I(θ) sin θ dθ, a smooth 1-D
//! integral except for a (θ − θ0)^{3/2} onset, which the substitution
//! θ = θ0 + θv t² turns smooth: Gauss–Legendre in t on equal panels, the
//! first split geometrically toward t = 0 (`PANELS`'s docs: at grazing
//! views a narrow lobe's mass sits there).
//!
//! γ and α are constants of a material, so the material tabulates its own
//! slice of Λ over (γ, α, μ): μΛ on a [`Table1`] in x = ln μ over
//! [ln(1e-5 α), 0], N_X nodes on both ends, linear in x. Only
//! N_LOW + N_HIGH + 1 = 113 x get a quadrature, evenly spaced on each side
//! of μ = SPLIT_OVER_ALPHA · α (sparse below, where q is nearly flat); the
//! N_X nodes take the cubic through the four nearest of those (in f64,
//! before rounding to f32). Over γ ∈ [¼, 128], α ∈ [0.05, 1] that keeps
//! the table within 7.7e-5 of a direct 2-D quadrature (and within 5.3e-5
//! over γ ∈ [1, 10], α ∈ [0.001, 0.03]; core/tests/gtr_lambda.rs) and
//! within 7.6e-5 of the 1-D quadrature (2048 quadratures: 8.9e-5,
//! the lerp's and f32's own error) at 1/18 of the cost. μΛ is bounded
//! and flat below μ ≈ α (α/2 at μ = 0 for GGX; it moves by a relative
//! ~μ/α there, so clamping below 1e-5 α costs ~1e-5), changes on the
//! scale of α around μ ≈ α and on the scale of 1 toward μ = 1: a
//! logarithmic axis spreads both evenly (x = μ/(μ + α) squeezed the second
//! into the last percent of the axis at small α: 1.7e-3 error at α = 0.01).
//! The table stores ln q, q = μΛ / (1 − μ²): q stays away from 0 as μ → 1
//! (D is finite at θm = π/2 for every γ, and μΛ vanishes like 1 − μ²
//! there), and its logarithm is close to linear where Λ falls steeply
//! (large γ: Beckmann-like, nearly exponential in μ/α), so the lerp's
//! error is relative everywhere (linear q was off by 1.6e-4 at γ = 10,
//! α = 0.15, μ = 0.1); exp and a multiplication by (1 − μ²)/μ at lookup
//! restore Λ, including its 1/μ growth at grazing angles. Within 1e-4
//! relative of a direct 2-D quadrature of the definition wherever
//! Λ ≥ 1e-4, and 1e-8 absolute below (`core/tests/gtr_lambda.rs`).

use crate::ndf::d_gtr;
use crate::quadrature::GaussLegendre;
use crate::real::Real;
use crate::table::{Axis, Nodes, Table1, Warp};
use std::f64::consts::FRAC_PI_2;
use std::sync::Arc;

/// Which Smith Λ a GTR distribution uses (the other NDFs ignore it).
#[derive(Clone, Debug, PartialEq, Default)]
pub enum GtrLambda {
    /// GGX's Λ at the same α: cheap, exact at γ = 2, and for γ < 2 a lobe
    /// that reflects more than it receives at grazing angles (the docs of
    /// models/microfacet.rs).
    #[default]
    Ggx,
    /// The distribution's own Λ, tabulated at the material's (γ, α)
    /// ([`GtrLambdaTable`]).
    Exact(Arc<GtrLambdaTable>),
}

impl GtrLambda {
    /// The exact Λ of GTR(γ, α), tabulated now (~1e5 evaluations of D).
    pub fn exact(gamma: f32, alpha: f32) -> GtrLambda {
        GtrLambda::Exact(Arc::new(GtrLambdaTable::new(gamma as f64, alpha as f64)))
    }
}

/// Nodes of the μΛ table.
pub(crate) const N_X: usize = 2048;
/// Quadrature intervals below and above μ = SPLIT_OVER_ALPHA · α, each
/// side evenly spaced in x: μΛ is computed by quadrature only at their
/// ends, and the N_X table nodes take a cubic through the four nearest of
/// those (ln q is smooth in ln μ, so the cubic's h⁴ error is far below the
/// lerp's h²).
pub(crate) const N_LOW: usize = 12;
/// See [`N_LOW`].
pub(crate) const N_HIGH: usize = 100;
/// Where the quadrature nodes change spacing: μ = SPLIT_OVER_ALPHA · α.
/// Below it q is nearly flat (it tends to its μ = 0 limit like μ/α).
pub(crate) const SPLIT_OVER_ALPHA: f64 = 0.003;
/// Smallest μ of the table, relative to α.
const MU_MIN_OVER_ALPHA: f64 = 1e-5;
/// Panels and Gauss–Legendre points per panel of the θ integral: equal
/// panels in t over [1/PANELS, 1], and the first one split geometrically
/// into GRADED panels [0, 2^−(4+GRADED−1)], …, [1/32, 1/16] (t² = (θ − θ0)/θv:
/// at grazing views the region starts at θ0 ≈ μ, inside a narrow lobe
/// (width ~α/√γ), whose mass then sits at t ≲ √(α/√γ): one equal first
/// panel left γ = 10, α = 0.002 off by 1.5e-2 at μ = 5e-4).
const PANELS: usize = 16;
const GRADED: usize = 7;
const POINTS: usize = 8;

/// Λ of one GTR(γ, α), tabulated (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct GtrLambdaTable {
    pub(crate) gamma: f64,
    pub(crate) alpha: f64,
    /// ln q, q = μΛ/(1 − μ²), over ln μ.
    mu_lambda: Table1<1>,
}

/// μΛ(μ) of GTR(γ, α) by the 1-D quadrature of the module docs, with its
/// Gauss–Legendre rule formed by the caller.
fn mu_lambda_gtr_with(rule: &GaussLegendre, gamma: f64, alpha: f64, mu: f64) -> f64 {
    let mu = mu.clamp(0.0, 1.0);
    if mu >= 1.0 {
        return 0.0;
    }
    let s = (1.0 - mu * mu).sqrt();
    let theta_v = s.atan2(mu);
    let theta0 = FRAC_PI_2 - theta_v;
    let first = 1.0 / PANELS as f64;
    let graded = (0..GRADED).map(|k| {
        let hi = first * 0.5f64.powi(k as i32);
        (if k + 1 == GRADED { 0.0 } else { 0.5 * hi }, hi)
    });
    let equal = (1..PANELS).map(|p| (p as f64 / PANELS as f64, (p + 1) as f64 / PANELS as f64));
    let mut sum = 0.0;
    for (t0, t1) in graded.chain(equal) {
        let [part] = rule.integrate(t0, t1, |t| {
            let theta = theta0 + theta_v * t * t;
            let (st, ct) = theta.sin_cos();
            let (a, b) = (s * st, mu * ct);
            if a <= b {
                return [0.0];
            }
            let i = 2.0 * (a * a - b * b).sqrt() - 2.0 * b * (b / a).min(1.0).acos();
            let d = d_gtr(alpha, gamma, ct * ct, st * st);
            // dθ = 2 θv t dt.
            [d * i * st * 2.0 * theta_v * t]
        });
        sum += part;
    }
    sum
}

impl GtrLambdaTable {
    /// Tabulates μΛ: N_LOW + N_HIGH + 1 one-dimensional quadratures,
    /// then the N_X table nodes by a cubic through the four nearest.
    pub fn new(gamma: f64, alpha: f64) -> GtrLambdaTable {
        let lo = (MU_MIN_OVER_ALPHA * alpha).ln();
        let xs_split = (SPLIT_OVER_ALPHA * alpha).ln().clamp(lo + 1.0, -1.0);
        let xs: Vec<f64> = (0..N_LOW)
            .map(|k| lo + (xs_split - lo) * k as f64 / N_LOW as f64)
            .chain((0..N_HIGH).map(|k| xs_split * (1.0 - k as f64 / N_HIGH as f64)))
            .chain([0.0])
            .collect();
        let rule = GaussLegendre::new(POINTS);
        let ys: Vec<f64> = xs
            .iter()
            .map(|&x| {
                // At μ = 1 (x = 0), q's limit: its value a hair below.
                let mu = x.exp().min(1.0 - 1e-6);
                // Floored so a tail that underflows stays finite (Λ → 0).
                (mu_lambda_gtr_with(&rule, gamma, alpha, mu) / (1.0 - mu * mu))
                    .max(1e-300)
                    .ln()
            })
            .collect();
        let axis = Axis::new(N_X, lo, 0.0, Warp::Linear, Nodes::Ends);
        let mu_lambda = Table1::build(axis, |x| [cubic(&xs, &ys, x)]);
        GtrLambdaTable {
            gamma,
            alpha,
            mu_lambda,
        }
    }

    /// Λ(μ) per lane; `cos_theta` > 0 (callers pass the floored cosine).
    #[inline(always)]
    pub fn lambda<R: Real>(&self, cos_theta: R) -> R {
        let [ln_q] = self.mu_lambda.lookup(cos_theta.ln());
        ln_q.exp() * (R::ONE - cos_theta * cos_theta) / cos_theta
    }
}

/// The cubic through the four points (xs, ys) nearest to x (one-sided at
/// the ends; xs increasing, at least 4), in Lagrange form.
fn cubic(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    let j = xs
        .partition_point(|&xk| xk <= x)
        .saturating_sub(2)
        .min(xs.len() - 4);
    let (x4, y4) = (&xs[j..j + 4], &ys[j..j + 4]);
    (0..4)
        .map(|k| {
            let l: f64 = (0..4)
                .filter(|&m| m != k)
                .map(|m| (x - x4[m]) / (x4[k] - x4[m]))
                .product();
            l * y4[k]
        })
        .sum()
}
