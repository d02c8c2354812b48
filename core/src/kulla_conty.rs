//! Kulla–Conty multiple-scattering compensation [Kulla17].
//!
//! Single scattering loses energy at high roughness: with F = 1 the
//! directional albedo E(μ) of the specular lobe is below 1. The added lobe
//!
//! f_ms(μi, μo) = (1 − E(μi)) (1 − E(μo)) / (π (1 − E_avg)),
//! E_avg = 2 ∫₀¹ E(μ) μ dμ,
//!
//! reflects exactly 1 − E(μo), so E + E_ms = 1: the white furnace test.
//! With Fresnel, the bounce series sums to a total energy of
//! F_avg E_avg / (1 − F_avg (1 − E_avg)) (F_avg = 2 ∫ F(μ) μ dμ); the added
//! lobe carries that total minus the single-scattering F_avg E_avg, i.e.
//! f_ms times F_avg² E_avg / (1 − F_avg (1 − E_avg)) (the default,
//! `KcColor::KullaConty`). The course notes multiply by
//! F_avg E_avg / (1 − F_avg (1 − E_avg)) instead (`KcColor::Notes`, which
//! over-counts by a factor 1/F_avg).
//!
//! Tables, per (NDF, Smith) pair, computed once per process and cached:
//! E on a [`Table2`] over μ (x) and α (y): N_MU nodes μ_j = (j/(N_MU − 1))²
//! (`Warp::Sqrt`, dense near grazing, where E changes fastest), linear in
//! μ between nodes; N_ALPHA nodes √α_k = k/(N_ALPHA − 1) (α floored at
//! ALPHA_MIN); E at μ = 0 is its limit 0. A material takes the α slice
//! ([`KcTable::slice`]: Catmull–Rom in √α, once per material) and
//! integrates E_avg from the slice's own interpolant (exactly:
//! Gauss–Legendre per node interval, see `Table1::integrate`), so the
//! lobe reflects exactly 1 − E(μo) of the E it reads.
//!
//! Accuracy matters most through 1 − E_avg, which divides f_ms and is small
//! for smooth lobes (2.3e-3 for Beckmann at α = 0.07): with 32 × 32 nodes
//! and a lerp in √α the slice's 1 − E_avg was off by up to 2.2% there
//! (f_ms by as much); 64 μ nodes (0.7% → 0.18% at a fixed α) and the cubic
//! in α (1.6% → 0.2%) bring the worst to ≈ 0.3% over α, μ ∈ [0.05, 1].
//! Building a table takes 0.6–1.2 s (0.4–0.5 s at 32 × 32): N_MU × N_ALPHA
//! quadratures of `MicrofacetParams::specular_albedo` with F = 1 (~1e-5).
//! `core/tests/kulla_conty.rs` measures all of this against brute-force
//! quadrature of the BRDF.

use crate::brdf::ALPHA_MIN;
use crate::models::microfacet::{Fresnel, GtrLambda, MicrofacetParams, Ndf, Smith};
use crate::real::Real;
use crate::table::{Axis, Nodes, Table1, Table2, Warp};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

pub const N_MU: usize = 64;
pub const N_ALPHA: usize = 32;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum KcColor {
    #[default]
    KullaConty,
    Notes,
}

/// (NDF kind, GTR γ bits, separable Smith, exact GTR Λ): what a table
/// depends on.
type TableKey = (u8, u32, bool, bool);

/// The μ axis of E: see the module docs.
pub const MU_AXIS: Axis = Axis::new(N_MU, 0.0, 1.0, Warp::Sqrt, Nodes::Ends).linear_between_nodes();
/// The α axis of E: see the module docs.
pub const ALPHA_AXIS: Axis = Axis::new(N_ALPHA, 0.0, 1.0, Warp::Sqrt, Nodes::Ends);

/// E(μ, α) for one (NDF, Smith) pair; see the module docs.
#[derive(Debug)]
pub struct KcTable {
    pub e: Table2<1>,
}

impl KcTable {
    fn build(ndf: Ndf, smith: Smith, exact_gtr: bool) -> KcTable {
        let e = Table2::build(MU_AXIS, ALPHA_AXIS, |mu, alpha| {
            let alpha = (alpha as f32).max(ALPHA_MIN);
            let gtr_lambda = match ndf {
                Ndf::Gtr { gamma } if exact_gtr => GtrLambda::exact(gamma, alpha),
                _ => GtrLambda::Ggx,
            };
            let p = MicrofacetParams {
                ndf,
                alpha,
                smith,
                fresnel: Fresnel::Schlick { f0: [1.0; 3] },
                diffuse: [0.0; 3],
                gtr_lambda,
            };
            // E(0) = 0 is the limit; E ≤ 1 up to quadrature error.
            [if mu == 0.0 {
                0.0
            } else {
                p.specular_albedo(mu)[0].min(1.0)
            }]
        });
        KcTable { e }
    }

    /// The cached table of an (NDF, Smith) pair, built on first use (GTR
    /// with GGX's Λ).
    pub fn get(ndf: Ndf, smith: Smith) -> Arc<KcTable> {
        KcTable::get_with(ndf, smith, false)
    }

    /// [`KcTable::get`], for GTR with its exact Λ when `exact_gtr`
    /// (ignored by the other NDFs).
    pub fn get_with(ndf: Ndf, smith: Smith, exact_gtr: bool) -> Arc<KcTable> {
        static CACHE: OnceLock<Mutex<HashMap<TableKey, Arc<KcTable>>>> = OnceLock::new();
        let sep = smith == Smith::Separable;
        let key = match ndf {
            Ndf::Ggx => (0, 0, sep, false),
            Ndf::Beckmann => (1, 0, sep, false),
            Ndf::Gtr { gamma } => (2, gamma.to_bits(), sep, exact_gtr),
        };
        let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
        if let Some(t) = cache.lock().expect("table cache").get(&key) {
            return t.clone();
        }
        // Built outside the lock; two threads may both build, one wins.
        let t = Arc::new(KcTable::build(ndf, smith, key.3));
        cache
            .lock()
            .expect("table cache")
            .entry(key)
            .or_insert(t)
            .clone()
    }

    /// The α slice of the table (Catmull–Rom in √α, clamped to [0, 1]
    /// since the cubic can overshoot) and its E_avg = 2 ∫₀¹ E(μ) μ dμ,
    /// integrated from the slice's interpolant.
    pub fn slice(&self, alpha: f64) -> KcSlice {
        let cubic = self.e.slice_y_cubic(alpha);
        let nodes = (0..N_MU)
            .map(|j| cubic.node_value(j).map(|v| v.clamp(0.0, 1.0)))
            .collect();
        let e = Table1::from_nodes(MU_AXIS, nodes);
        let [e_avg] = e.integrate(|mu| 2.0 * mu);
        KcSlice { e, e_avg }
    }
}

/// E(μ) at one α, and its E_avg: what one material needs at shading time.
#[derive(Clone, Debug, PartialEq)]
pub struct KcSlice {
    pub e: Table1<1>,
    pub e_avg: f64,
}

impl KcSlice {
    /// E(μ), linear in μ between the nodes ([`KcSlice::e_lanes`] in f64).
    pub fn e_at(&self, mu: f64) -> f64 {
        self.e_lanes(mu)
    }

    /// E(μ) per lane.
    #[inline(always)]
    pub fn e_lanes<R: Real>(&self, mu: R) -> R {
        self.e.lookup(mu)[0]
    }
}

/// Colour factor multiplying f_ms (module docs), per channel.
pub fn color_factor(f_avg: f64, e_avg: f64, mode: KcColor) -> f64 {
    let total = f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg));
    match mode {
        KcColor::KullaConty => total * f_avg,
        KcColor::Notes => total,
    }
}

/// F_avg = 2 ∫₀¹ F(μ) μ dμ of a Fresnel term, per channel: closed form
/// F0 + (1 − F0)/21 for Schlick, composite midpoint rule otherwise.
pub fn f_avg(fresnel: &Fresnel) -> [f64; 3] {
    if let Fresnel::Schlick { f0 } = fresnel {
        return f0.map(|f| f as f64 + (1.0 - f as f64) / 21.0);
    }
    let p = MicrofacetParams {
        ndf: Ndf::Ggx,
        alpha: 0.5,
        smith: Smith::HeightCorrelated,
        fresnel: *fresnel,
        diffuse: [0.0; 3],
        gtr_lambda: GtrLambda::Ggx,
    };
    // Composite midpoint with 4096 panels: |error| < 1e-8 for these curves.
    let n = 4096;
    let mut s = [0.0; 3];
    for i in 0..n {
        let mu = (i as f64 + 0.5) / n as f64;
        let f = p.f::<f64>(mu);
        s[0] += f.x * mu;
        s[1] += f.y * mu;
        s[2] += f.z * mu;
    }
    s.map(|v| 2.0 * v / n as f64)
}
