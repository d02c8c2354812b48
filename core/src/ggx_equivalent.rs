//! The GGX α that stands in for another NDF's lobe where only GGX lobes
//! are at hand: the prefiltered environment chain is made with GGX, so a
//! Beckmann or GTR material reads it at the GGX α whose lobe spreads like
//! its own.
//!
//! "Spreads like" is the median polar angle of the microfacet normals:
//! the θ_½ that D(m) cos θm puts half of its (unit) mass within. For GGX
//! tan²θ_½ = α², so the equivalent α is tan θ_½ of the other NDF. Each
//! NDF's importance-sampling inverse gives θ_½ in closed form (ξ = ½):
//!
//! - Beckmann: tan²θ = −α² ln(1 − ξ), so α_GGX = α √(ln 2);
//! - GTR(γ ≠ 1) \[Burley12, App. B\]:
//!   cos²θ = (1 − ((α²)^(1−γ)(1 − ξ) + ξ)^(1/(1−γ))) / (1 − α²);
//! - GTR(1): cos²θ = (1 − (α²)^(1−ξ)) / (1 − α²), so α_GGX = √α.
//!
//! The median was chosen over the mean cosine of the prefiltered kernel
//! (which weights the tails more) by the split sum's error against the
//! Monte Carlo reference (docs/accuracy.md). `median_matches_quadrature`
//! checks the closed forms against a quadrature of each NDF's own D.

use crate::ndf::Ndf;

/// The GGX α whose microfacet normals have the same median polar angle
/// as `ndf`'s at `alpha` (module docs), at most 1 (GTR at α = 1 is the
/// uniform 1/π, as GGX at 1 is).
pub(crate) fn ggx_equivalent_alpha(ndf: Ndf, alpha: f64) -> f64 {
    let a2 = alpha * alpha;
    let tan2 = match ndf {
        Ndf::Ggx => a2,
        Ndf::Beckmann => a2 * std::f64::consts::LN_2,
        Ndf::Gtr { gamma } => gtr_median_tan2(alpha, gamma as f64),
    };
    tan2.sqrt().min(1.0)
}

/// tan²θ_½ of GTR(γ) at α. With q = (1 + (α²)^(γ−1)) / 2 and
/// p = α² q^(1/(1−γ)) (the ξ = ½ root, rearranged so that small α keeps
/// its digits): tan²θ_½ = α² expm1(ln q / (1 − γ)) / (1 − p); at γ = 1
/// (the limit) p = α and tan²θ_½ = α.
fn gtr_median_tan2(alpha: f64, gamma: f64) -> f64 {
    let a2 = alpha * alpha;
    // Near α = 1 the inverse is 0/0; D is uniform there (tan²θ_½ = 1).
    if (1.0 - a2).abs() < 1e-9 {
        return 1.0;
    }
    if (gamma - 1.0).abs() < 1e-9 {
        return alpha;
    }
    let q = 0.5 * (1.0 + a2.powf(gamma - 1.0));
    let e = (q.ln() / (1.0 - gamma)).exp_m1();
    let p = a2 * (1.0 + e);
    a2 * e / (1.0 - p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ndf::{d_beckmann, d_ggx, d_gtr};

    /// An NDF's D(cos²θ, sin²θ).
    type D = Box<dyn Fn(f64, f64) -> f64>;

    /// θ_½ of an NDF by quadrature of its own D: the cumulative mass of
    /// D(m) cos θm sin θm dθm 2π (midpoint rule, 200 000 steps in θ),
    /// the median found between steps.
    fn median_by_quadrature(d: impl Fn(f64, f64) -> f64) -> f64 {
        let steps = 200_000;
        let h = std::f64::consts::FRAC_PI_2 / steps as f64;
        let mass = |t: f64| {
            let (s, c) = t.sin_cos();
            d(c * c, s * s) * c * s * std::f64::consts::TAU * h
        };
        let total: f64 = (0..steps).map(|i| mass((i as f64 + 0.5) * h)).sum();
        let mut acc = 0.0;
        for i in 0..steps {
            let m = mass((i as f64 + 0.5) * h);
            if acc + m >= 0.5 * total {
                return (i as f64 + (0.5 * total - acc) / m) * h;
            }
            acc += m;
        }
        std::f64::consts::FRAC_PI_2
    }

    /// The closed forms against the quadrature of each NDF's D: the GGX
    /// α returned has the NDF's median angle (GGX's is atan α), within
    /// 0.1 % of α; GGX maps to itself.
    #[test]
    fn median_matches_quadrature() {
        for alpha in [0.02, 0.1, 0.3, 0.6, 0.9] {
            let cases: [(Ndf, D); 5] = [
                (Ndf::Ggx, Box::new(move |c2, s2| d_ggx(alpha, c2, s2))),
                (
                    Ndf::Beckmann,
                    Box::new(move |c2, s2| d_beckmann(alpha, c2, s2)),
                ),
                (
                    Ndf::Gtr { gamma: 1.0 },
                    Box::new(move |c2, s2| d_gtr(alpha, 1.0, c2, s2)),
                ),
                (
                    Ndf::Gtr { gamma: 1.5 },
                    Box::new(move |c2, s2| d_gtr(alpha, 1.5, c2, s2)),
                ),
                (
                    Ndf::Gtr { gamma: 4.0 },
                    Box::new(move |c2, s2| d_gtr(alpha, 4.0, c2, s2)),
                ),
            ];
            for (ndf, d) in cases {
                let want = median_by_quadrature(d).tan();
                let got = ggx_equivalent_alpha(ndf, alpha);
                assert!(
                    (got - want).abs() <= 1e-3 * alpha,
                    "{ndf:?} α {alpha}: {got} vs quadrature {want}"
                );
            }
        }
        assert_eq!(ggx_equivalent_alpha(Ndf::Ggx, 0.37), 0.37);
        assert_eq!(ggx_equivalent_alpha(Ndf::Beckmann, 1.0), 2f64.ln().sqrt());
    }
}
