//! Directional-albedo tables for uniform environment light on the
//! metallic-roughness model (the "split sum" factorization, \[Karis13\]).
//!
//! With Schlick's F = F0 + (1 − F0) w, w = (1 − wi·h)⁵, and the specular
//! integrand s(wi) = D(h) V(wi, wo) (n·wi) of GGX + height-correlated Smith:
//!
//! - E_spec(μo, α) = F0 · A(μo, α) + B(μo, α),  A = ∫ s (1 − w) dωi,  B = ∫ s w dωi
//! - E_diff(μo)    = (1 − F0) ρd (1 − C(μo)),   C = ∫ w (n·wi)/π dωi  (independent of α)
//!
//! Layout (table.rs): A, B are one 2-channel table over μo (x) and α (y),
//! C a 1-channel table over μo, bilinear. Both axes have nodes on their
//! ends, so that the normal view and roughness 0 and 1 (glTF's default)
//! are nodes, not clamped to a neighbour: E falls steeply toward α = 1
//! and toward μo = 1 there, so a rough metal read at the nearest texel
//! centres instead comes out visibly too bright (docs/accuracy.md,
//! "The albedo at roughness 1"). α:
//! √α_k = k/(N_ALPHA − 1) (`Warp::Sqrt`, roughness spacing: the
//! integrals change fastest at small α). μo: from `MU_LO` to 1, evenly;
//! below `MU_LO` (views within a degree of grazing) lanes read the first
//! node, as the integrals at μo = 0 are limits the quadrature does not
//! reach (at α = 0 its one half vector, the normal, is at 90° from the
//! view).
//!
//! Computed once per process by deterministic quadrature (Hammersley points,
//! importance-sampling D(h)(n·h)); see the tests for the measured error.

use crate::fresnel::schlick_weight;
use crate::masking::v_smith_ggx_correlated;
use crate::real::Real;
use crate::table::{Axis, Nodes, Table1, Table2, Warp};
use std::sync::OnceLock;

pub(crate) const N_MU: usize = 32;
pub(crate) const N_ALPHA: usize = 32;
/// Quadrature points per table entry.
const SAMPLES: u32 = 2048;

/// The three integrals of the module docs, per lane.
pub(crate) struct SplitSum<R> {
    pub(crate) a: R,
    pub(crate) b: R,
    pub(crate) c: R,
}

pub struct AlbedoTables {
    /// [A, B] over (μo, α).
    ab: Table2<2>,
    /// C over μo.
    c: Table1<1>,
}

/// The lowest μo node (module docs).
const MU_LO: f64 = 1.0 / 64.0;
const MU_AXIS: Axis = Axis::new(N_MU, MU_LO, 1.0, Warp::Linear, Nodes::Ends);
const ALPHA_AXIS: Axis = Axis::new(N_ALPHA, 0.0, 1.0, Warp::Sqrt, Nodes::Ends);

/// Point `i` of an `n`-point Hammersley set in [0, 1)².
fn hammersley(i: u32, n: u32) -> (f64, f64) {
    (
        (i as f64 + 0.5) / n as f64,
        i.reverse_bits() as f64 / 4294967296.0,
    )
}

/// A, B at (μo, α) by importance sampling h ∝ D(h)(n·h): with
/// pdf(wi) = D(h)(n·h) / (4 wo·h), s/pdf = V (n·wi) 4 (wo·h) / (n·h).
fn integrate_ab(mu_o: f64, alpha: f64) -> (f64, f64) {
    let wo = [(1.0 - mu_o * mu_o).sqrt(), 0.0, mu_o];
    let a2 = alpha * alpha;
    let (mut sa, mut sb) = (0.0, 0.0);
    for i in 0..SAMPLES {
        let (u1, u2) = hammersley(i, SAMPLES);
        // GGX inversion: cos²θh = (1 − u) / (1 + (α² − 1) u).
        let cos_h = ((1.0 - u1) / (1.0 + (a2 - 1.0) * u1)).sqrt();
        let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
        let phi = 2.0 * std::f64::consts::PI * u2;
        let h = [sin_h * phi.cos(), sin_h * phi.sin(), cos_h];
        let o_h = wo[0] * h[0] + wo[2] * h[2];
        if o_h <= 0.0 {
            continue;
        }
        let cos_i = 2.0 * o_h * h[2] - wo[2];
        if cos_i <= 0.0 {
            continue;
        }
        let weight = v_smith_ggx_correlated(alpha, cos_i, mu_o) * cos_i * 4.0 * o_h / cos_h;
        let w = schlick_weight(o_h);
        sa += weight * (1.0 - w);
        sb += weight * w;
    }
    (sa / SAMPLES as f64, sb / SAMPLES as f64)
}

/// C(μo) = ∫ (1 − wi·h)⁵ (n·wi)/π dωi, by cosine-weighted sampling of wi.
fn integrate_c(mu_o: f64) -> f64 {
    let wo = [(1.0 - mu_o * mu_o).sqrt(), 0.0, mu_o];
    let n = SAMPLES * 4;
    let mut s = 0.0;
    for i in 0..n {
        let (u1, u2) = hammersley(i, n);
        let r = u1.sqrt();
        let phi = 2.0 * std::f64::consts::PI * u2;
        let wi = [r * phi.cos(), r * phi.sin(), (1.0 - u1).sqrt()];
        let hv = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
        let len = (hv[0] * hv[0] + hv[1] * hv[1] + hv[2] * hv[2]).sqrt();
        let i_h = (wi[0] * hv[0] + wi[1] * hv[1] + wi[2] * hv[2]) / len;
        s += schlick_weight(i_h);
    }
    s / n as f64
}

impl AlbedoTables {
    fn build() -> Self {
        AlbedoTables {
            ab: Table2::build(MU_AXIS, ALPHA_AXIS, |mu, alpha| {
                let (a, b) = integrate_ab(mu, alpha);
                [a, b]
            }),
            c: Table1::build(MU_AXIS, |mu| [integrate_c(mu)]),
        }
    }

    /// The process-wide tables, built on first use (about 400 M
    /// instructions: ~0.1 s on one core; scenes build them when they load).
    pub fn get() -> &'static AlbedoTables {
        static T: OnceLock<AlbedoTables> = OnceLock::new();
        T.get_or_init(Self::build)
    }

    /// A, B, C per lane.
    #[inline(always)]
    pub(crate) fn ggx_schlick<R: Real>(&self, alpha: R, mu_o: R) -> SplitSum<R> {
        let [a, b] = self.ab.lookup(mu_o, alpha);
        let [c] = self.c.lookup(mu_o);
        SplitSum { a, b, c }
    }

    /// C alone (`AlbedoTables::ggx_schlick`'s c), per lane.
    #[inline(always)]
    pub(crate) fn c<R: Real>(&self, mu_o: R) -> R {
        let [c] = self.c.lookup(mu_o);
        c
    }
}
