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
//! E at N_MU × N_ALPHA nodes μ_j = (j / (N_MU − 1))² (dense near grazing,
//! where E changes fastest), √α_k = k / (N_ALPHA − 1) (α floored at
//! ALPHA_MIN), bilinear between nodes; E at μ = 0 is its limit 0. E_avg is
//! integrated exactly from the same piecewise-linear E(μ), so the
//! compensation is consistent with the E it complements. E comes from
//! `MicrofacetParams::specular_albedo` with F = 1 (deterministic quadrature,
//! ~1e-5); `core/tests/kulla_conty.rs` measures the table error.

use crate::brdf::ALPHA_MIN;
use crate::models::microfacet::{Fresnel, MicrofacetParams, Ndf, Smith};
use crate::real::Real;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

pub const N_MU: usize = 32;
pub const N_ALPHA: usize = 32;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum KcColor {
    #[default]
    KullaConty,
    Notes,
}

/// (NDF kind, GTR γ bits, separable Smith): what a table depends on.
type TableKey = (u8, u32, bool);

/// E(μ, α) and E_avg(α) for one (NDF, Smith) pair; see the module docs.
#[derive(Debug)]
pub struct KcTable {
    /// Row-major: e[k * N_MU + j] = E(μ_j, α_k).
    pub e: Vec<f32>,
    pub e_avg: Vec<f32>,
}

pub fn mu_node(j: usize) -> f64 {
    let t = j as f64 / (N_MU - 1) as f64;
    t * t
}

pub fn alpha_node(k: usize) -> f64 {
    let r = k as f64 / (N_ALPHA - 1) as f64;
    (r * r).max(ALPHA_MIN as f64)
}

/// Position of x on a node axis given the node function's inverse
/// (x ↦ fractional node index), clamped.
fn locate(frac_index: f64, n: usize) -> (usize, usize, f64) {
    let x = frac_index.clamp(0.0, (n - 1) as f64);
    let i0 = (x.floor() as usize).min(n - 2);
    (i0, i0 + 1, x - i0 as f64)
}

/// ∫ over [a, b] of μ·E(μ) for E linear from ea to eb.
fn segment_moment(a: f64, b: f64, ea: f64, eb: f64) -> f64 {
    // E(μ) = ea + (eb − ea)(μ − a)/(b − a); integrate μ E(μ) exactly.
    let h = b - a;
    let slope = (eb - ea) / h;
    let c0 = ea - slope * a;
    c0 * (b * b - a * a) / 2.0 + slope * (b * b * b - a * a * a) / 3.0
}

impl KcTable {
    fn build(ndf: Ndf, smith: Smith) -> KcTable {
        let mut e = vec![0.0f32; N_MU * N_ALPHA];
        let mut e_avg = vec![0.0f32; N_ALPHA];
        for k in 0..N_ALPHA {
            let p = MicrofacetParams {
                ndf,
                alpha: alpha_node(k) as f32,
                smith,
                fresnel: Fresnel::Schlick { f0: [1.0; 3] },
                diffuse: [0.0; 3],
            };
            let row: Vec<f64> = (0..N_MU)
                .map(|j| {
                    if j == 0 {
                        0.0
                    } else {
                        p.specular_albedo(mu_node(j))[0].min(1.0)
                    }
                })
                .collect();
            let moment: f64 = (0..N_MU - 1)
                .map(|j| segment_moment(mu_node(j), mu_node(j + 1), row[j], row[j + 1]))
                .sum();
            e_avg[k] = (2.0 * moment) as f32;
            for (j, v) in row.iter().enumerate() {
                e[k * N_MU + j] = *v as f32;
            }
        }
        KcTable { e, e_avg }
    }

    /// The cached table of an (NDF, Smith) pair, built on first use.
    pub fn get(ndf: Ndf, smith: Smith) -> Arc<KcTable> {
        static CACHE: OnceLock<Mutex<HashMap<TableKey, Arc<KcTable>>>> = OnceLock::new();
        let key = match ndf {
            Ndf::Ggx => (0, 0, smith == Smith::Separable),
            Ndf::Beckmann => (1, 0, smith == Smith::Separable),
            Ndf::Gtr { gamma } => (2, gamma.to_bits(), smith == Smith::Separable),
        };
        let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
        if let Some(t) = cache.lock().expect("table cache").get(&key) {
            return t.clone();
        }
        // Built outside the lock; two threads may both build, one wins.
        let t = Arc::new(KcTable::build(ndf, smith));
        cache
            .lock()
            .expect("table cache")
            .entry(key)
            .or_insert(t)
            .clone()
    }

    /// The α slice of the table: E at the μ nodes and E_avg, linear in the
    /// α weight (so E_avg stays the exact moment of the sliced E).
    pub fn slice(&self, alpha: f64) -> KcSlice {
        let (k0, k1, t) = locate(alpha.max(0.0).sqrt() * (N_ALPHA - 1) as f64, N_ALPHA);
        let lerp = |a: f32, b: f32| a as f64 + (b as f64 - a as f64) * t;
        KcSlice {
            e: (0..N_MU)
                .map(|j| lerp(self.e[k0 * N_MU + j], self.e[k1 * N_MU + j]) as f32)
                .collect(),
            e_avg: lerp(self.e_avg[k0], self.e_avg[k1]),
        }
    }
}

/// E(μ) at one α, and its E_avg: what one material needs at shading time.
#[derive(Clone, Debug, PartialEq)]
pub struct KcSlice {
    pub e: Vec<f32>,
    pub e_avg: f64,
}

impl KcSlice {
    /// E(μ), linear between the μ nodes.
    pub fn e_at(&self, mu: f64) -> f64 {
        // The node below μ from √μ; then linear in μ (not in √μ) between
        // the two nodes, the interpolant E_avg was integrated from.
        let (j0, j1, _) = locate(mu.max(0.0).sqrt() * (N_MU - 1) as f64, N_MU);
        let (a, b) = (mu_node(j0), mu_node(j1));
        let t = ((mu - a) / (b - a)).clamp(0.0, 1.0);
        self.e[j0] as f64 + (self.e[j1] as f64 - self.e[j0] as f64) * t
    }
}

impl KcSlice {
    /// [`KcSlice::e_at`] for every lane: the node index and weights in lane
    /// arithmetic, then two table reads per lane (a gather).
    #[inline(always)]
    pub fn e_lanes<R: Real>(&self, mu: R) -> R {
        let last = (N_MU - 1) as f64;
        let mu = mu.clamp(R::ZERO, R::ONE);
        let j0 = (mu.sqrt() * R::splat(last))
            .floor()
            .min(R::splat(last - 1.0));
        let j1 = j0 + R::ONE;
        let inv = R::splat(1.0 / last);
        let (a, b) = ((j0 * inv).sqr(), (j1 * inv).sqr());
        let t = ((mu - a) / (b - a)).clamp(R::ZERO, R::ONE);
        let (mut e0, mut e1) = ([0.0f32; 8], [0.0f32; 8]);
        for lane in 0..R::LANES {
            let j = j0.lane(lane) as usize;
            e0[lane] = self.e[j];
            e1[lane] = self.e[j + 1];
        }
        let (e0, e1) = (R::load(&e0), R::load(&e1));
        (e1 - e0).mul_add(t, e0)
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
