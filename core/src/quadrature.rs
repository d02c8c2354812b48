//! Numeric integration for the tables (table.rs, albedo and Kulla–Conty
//! tables, the per-material albedo), written once.
//!
//! - `adaptive_simpson`: for integrands with kinks at unknown places (the
//!   albedo ring of `MicrofacetParams::specular_albedo`), on C channels at
//!   once, refining where any channel needs it.
//! - [`GaussLegendre`]: n-point rule, exact for polynomials of degree
//!   2n − 1; what [`crate::table::Table1::integrate`] uses per node interval,
//!   where the interpolant is a low-degree polynomial.

/// Simpson's rule on [a, b] from f(a), f((a + b)/2), f(b), per channel.
pub(crate) fn simpson<const C: usize>(
    a: f64,
    b: f64,
    fa: [f64; C],
    fm: [f64; C],
    fb: [f64; C],
) -> [f64; C] {
    core::array::from_fn(|c| (b - a) / 6.0 * (fa[c] + 4.0 * fm[c] + fb[c]))
}

/// Adaptive Simpson on a vector integrand (Lyness 1969): splits [a, b] until
/// the two halves agree with the whole within 15 `tol` in every channel (or
/// `depth` runs out), then adds the Richardson correction. `fa`, `fm`, `fb`
/// are f at a, the midpoint and b, `whole` their Simpson estimate.
#[allow(clippy::too_many_arguments)]
pub(crate) fn adaptive_simpson<const C: usize>(
    f: &dyn Fn(f64) -> [f64; C],
    a: f64,
    b: f64,
    fa: [f64; C],
    fm: [f64; C],
    fb: [f64; C],
    whole: [f64; C],
    tol: f64,
    depth: u32,
) -> [f64; C] {
    let m = 0.5 * (a + b);
    let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
    let (flm, frm) = (f(lm), f(rm));
    let left = simpson(a, m, fa, flm, fm);
    let right = simpson(m, b, fm, frm, fb);
    let err = (0..C)
        .map(|c| (left[c] + right[c] - whole[c]).abs())
        .fold(0.0, f64::max);
    if depth == 0 || err <= 15.0 * tol {
        return core::array::from_fn(|c| {
            left[c] + right[c] + (left[c] + right[c] - whole[c]) / 15.0
        });
    }
    let l = adaptive_simpson(f, a, m, fa, flm, fm, left, tol / 2.0, depth - 1);
    let r = adaptive_simpson(f, m, b, fm, frm, fb, right, tol / 2.0, depth - 1);
    core::array::from_fn(|c| l[c] + r[c])
}

/// The n-point Gauss–Legendre rule on [−1, 1]: nodes are the roots of the
/// Legendre polynomial Pₙ, found by Newton's method from Tricomi's
/// estimate cos(π (i + ¾)/(n + ½)); weights 2 / ((1 − x²) Pₙ′(x)²).
#[derive(Clone, Debug, PartialEq)]
pub struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussLegendre {
    pub fn new(n: usize) -> GaussLegendre {
        assert!(n >= 1, "a rule needs at least one node");
        let (mut nodes, mut weights) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for i in 0..n {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                // P_n(x) and P_n'(x) by the three-term recurrence.
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let k = k as f64;
                    (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            nodes.push(x);
            weights.push(2.0 / ((1.0 - x * x) * dp * dp));
        }
        GaussLegendre { nodes, weights }
    }

    /// The (node, weight) pairs on [−1, 1].
    pub fn nodes_weights(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.nodes.iter().copied().zip(self.weights.iter().copied())
    }

    /// ∫ₐᵇ f, per channel.
    pub fn integrate<const C: usize>(
        &self,
        a: f64,
        b: f64,
        f: impl Fn(f64) -> [f64; C],
    ) -> [f64; C] {
        let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
        let mut s = [0.0; C];
        for (x, w) in self.nodes.iter().zip(&self.weights) {
            let v = f(mid + half * x);
            for c in 0..C {
                s[c] += w * v[c];
            }
        }
        s.map(|v| v * half)
    }
}
