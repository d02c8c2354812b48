//! Kulla–Conty multiple-scattering compensation \[Kulla17\].
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
//!
//! **GTR and γ.** E depends on GTR's γ too, and γ is a per-material
//! number (eval scripts sweep it), so one table per γ would cost a build
//! per material. Instead GTR takes E from node tables on a γ axis:
//! x = log₂ γ over [−2, 7] (γ ∈ [¼, 128]), a node every third of an
//! octave ([`GAMMA_AXIS`]), each node an ordinary table at that γ
//! (committed, see below; building one takes ~0.3 s on two cores). A
//! material's slice ([`slice_for`]) takes the α slice of the
//! four nearest nodes and a Catmull–Rom cubic in log₂ γ through them;
//! E_avg is then integrated from that slice as above. Against a table
//! built at the material's own γ, half-way between nodes
//! (`gtr_gamma_axis_matches_tables_built_at_that_gamma`): |ΔE| ≤ 1.3e-3
//! for μ ≥ 0.05 and 1 − E_avg within 1.0%. E is stored unclamped (GTR with
//! GGX's Λ exceeds 1 at grazing angles for some γ; a clamp would put a
//! kink in E along γ, which took the cubic's error to 6e-3) and clamped
//! to [0, 1] in the slice. γ outside [¼, 128] gets a table of its own.
//!
//! **Where tables come from.** GGX, Beckmann and the GTR γ nodes (with
//! GGX's and with the exact Λ) are committed (`core/data/kc_tables.bin`,
//! [`committed`]), so no run builds them; GTR off the γ axis gets its
//! table built on first use and kept in the [`TableStore`] the CLI
//! installs (the user's cache folder).

pub mod committed;

use crate::brdf::ALPHA_MIN;
use crate::fresnel::Fresnel;
use crate::gtr_lambda::GtrLambda;
use crate::masking::Smith;
use crate::ndf::Ndf;
use crate::real::Real;
use crate::specular_lobe::MicrofacetParams;
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
pub(crate) const ALPHA_AXIS: Axis = Axis::new(N_ALPHA, 0.0, 1.0, Warp::Sqrt, Nodes::Ends);

/// GTR's γ axis: x = log₂ γ over [GAMMA_LOG2_LO, GAMMA_LOG2_HI], nodes on
/// both ends, one every third of an octave (module docs, "GTR and γ").
pub(crate) const GAMMA_LOG2_LO: f64 = -2.0;
pub(crate) const GAMMA_LOG2_HI: f64 = 7.0;
pub(crate) const N_GAMMA: usize = 28;
pub const GAMMA_AXIS: Axis = Axis::new(
    N_GAMMA,
    GAMMA_LOG2_LO,
    GAMMA_LOG2_HI,
    Warp::Linear,
    Nodes::Ends,
);

thread_local! {
    /// Tables built by this thread (diagnostics and tests).
    static BUILDS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// How many E tables the calling thread has built so far (each costs
/// N_MU × N_ALPHA albedo quadratures): a test can check that a sweep of
/// GTR materials builds none beyond the γ nodes.
pub fn tables_built_on_this_thread() -> usize {
    BUILDS.with(|b| b.get())
}

/// Somewhere to keep built tables between runs (the CLI keeps them in
/// the user's cache folder, src/table_cache.rs; core itself does no I/O).
/// A table is its N_MU × N_ALPHA node values, α rows in order, under a
/// name that says everything it depends on, `TABLE_VERSION` included.
pub trait TableStore: Send + Sync {
    fn load(&self, name: &str) -> Option<Vec<f32>>;
    fn save(&self, name: &str, values: &[f32]);
}

/// Part of every stored table's name: bump it whenever what a table holds
/// changes (axes, quadrature, clamping), so old stored tables are ignored.
/// 4: the exact GTR Λ's θ integral graded at grazing views (its tables
/// for small α and large γ moved by up to 1.9e-2 at μ = 2.5e-4).
pub(crate) const TABLE_VERSION: u32 = 5;

static STORE: OnceLock<Box<dyn TableStore>> = OnceLock::new();

/// Installs the store tables are loaded from and saved to (once per
/// process; later calls are ignored).
pub fn set_table_store(store: Box<dyn TableStore>) {
    let _ = STORE.set(store);
}

fn table_key(ndf: Ndf, smith: Smith, exact_gtr: bool) -> TableKey {
    let sep = smith == Smith::Separable;
    match ndf {
        Ndf::Ggx => (0, 0, sep, false),
        Ndf::Beckmann => (1, 0, sep, false),
        Ndf::Gtr { gamma } => (2, gamma.to_bits(), sep, exact_gtr),
    }
}

fn table_name(key: TableKey) -> String {
    format!(
        "kc-v{TABLE_VERSION}-{N_MU}x{N_ALPHA}-ndf{}-g{:08x}-sep{}-exact{}",
        key.0, key.1, key.2 as u8, key.3 as u8
    )
}

/// E(μ, α) for one (NDF, Smith) pair; see the module docs.
#[derive(Debug)]
pub struct KcTable {
    pub e: Table2<1>,
}

impl KcTable {
    /// Evaluates E at every node: one α row per task, the rows spread over
    /// the machine's cores (each node is independent, so the values do not
    /// depend on the thread count). The per-row parameters, GTR's exact Λ
    /// table included, are formed once per row.
    fn build(ndf: Ndf, smith: Smith, exact_gtr: bool) -> KcTable {
        BUILDS.with(|b| b.set(b.get() + 1));
        let row = |j: usize| -> Vec<[f32; 1]> {
            let alpha = (ALPHA_AXIS.node(j) as f32).max(ALPHA_MIN);
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
            (0..N_MU)
                .map(|i| {
                    let mu = MU_AXIS.node(i);
                    // E(0) = 0 is the limit. E is stored unclamped: GTR
                    // with GGX's Λ exceeds 1 at grazing angles for some γ,
                    // and a clamp here would put a kink into E along α
                    // and γ, which the cubics interpolate badly; slices
                    // clamp to [0, 1] after interpolating.
                    [if mu == 0.0 {
                        0.0
                    } else {
                        p.specular_albedo(mu)[0] as f32
                    }]
                })
                .collect()
        };
        // Scoped std threads rather than rayon: tables are built inside
        // OnceLock initialisers that rayon workers reach while shading, and
        // a nested rayon join there may steal another pixel job that waits
        // on the same OnceLock, on the same thread: a deadlock.
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .clamp(1, N_ALPHA);
        let mut rows: Vec<Vec<[f32; 1]>> = vec![Vec::new(); N_ALPHA];
        std::thread::scope(|s| {
            let row = &row;
            let workers: Vec<_> = (0..threads)
                .map(|t| {
                    s.spawn(move || {
                        (t..N_ALPHA)
                            .step_by(threads)
                            .map(|j| (j, row(j)))
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            for w in workers {
                for (j, r) in w.join().expect("table row worker") {
                    rows[j] = r;
                }
            }
        });
        KcTable {
            e: Table2::from_rows(MU_AXIS, ALPHA_AXIS, rows),
        }
    }

    /// The table from its store layout (α rows in order, μ inside a row).
    fn from_values(v: &[f32]) -> KcTable {
        let rows = v
            .chunks(N_MU)
            .map(|r| r.iter().map(|&x| [x]).collect())
            .collect();
        KcTable {
            e: Table2::from_rows(MU_AXIS, ALPHA_AXIS, rows),
        }
    }

    /// The table's node values in store layout.
    fn values(&self) -> Vec<f32> {
        (0..N_ALPHA)
            .flat_map(|j| (0..N_MU).map(move |i| (i, j)))
            .map(|(i, j)| self.e.node_value(i, j)[0])
            .collect()
    }

    /// Builds the table of (NDF, Smith, exact GTR Λ) afresh, whatever is
    /// committed or stored, and returns its values in store layout (for
    /// the generator of `core/data/kc_tables.bin` and its test).
    pub fn build_values(ndf: Ndf, smith: Smith, exact_gtr: bool) -> Vec<f32> {
        KcTable::build(ndf, smith, exact_gtr).values()
    }

    /// The committed table ([`committed`]) when there is one, else the
    /// store's when it holds a valid one (the right length, finite
    /// values), else built and saved there.
    fn load_or_build(ndf: Ndf, smith: Smith, key: TableKey) -> KcTable {
        let name = table_name(key);
        if let Some(v) = committed::committed().get(&name) {
            return KcTable::from_values(v);
        }
        let store = STORE.get();
        if let Some(v) = store.and_then(|s| s.load(&name)) {
            if v.len() == N_MU * N_ALPHA && v.iter().all(|x| x.is_finite()) {
                return KcTable::from_values(&v);
            }
        }
        let t = KcTable::build(ndf, smith, key.3);
        if let Some(s) = store {
            s.save(&name, &t.values());
        }
        t
    }

    /// The name the table of (NDF, Smith, exact GTR Λ) has in a
    /// [`TableStore`].
    pub fn store_name(ndf: Ndf, smith: Smith, exact_gtr: bool) -> String {
        table_name(table_key(ndf, smith, exact_gtr))
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
        let key = table_key(ndf, smith, exact_gtr);
        let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
        if let Some(t) = cache.lock().expect("table cache").get(&key) {
            return t.clone();
        }
        // Built outside the lock; two threads may both build, one wins.
        let t = Arc::new(KcTable::load_or_build(ndf, smith, key));
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
        KcSlice::from_e(Table1::from_nodes(MU_AXIS, nodes))
    }
}

/// The compensation slice of a material: for GTR with γ inside the γ
/// axis, interpolated from the node tables (module docs, "GTR and γ");
/// otherwise the α slice of the (NDF, Smith) table.
pub fn slice_for(ndf: Ndf, smith: Smith, exact_gtr: bool, alpha: f64) -> KcSlice {
    let gamma = match ndf {
        Ndf::Gtr { gamma } => gamma as f64,
        _ => return KcTable::get_with(ndf, smith, exact_gtr).slice(alpha),
    };
    let x = gamma.log2();
    if !(GAMMA_LOG2_LO..=GAMMA_LOG2_HI).contains(&x) {
        return KcTable::get_with(ndf, smith, exact_gtr).slice(alpha);
    }
    let (j, w) = GAMMA_AXIS.locate(x);
    let j = j as usize;
    let node = |k: isize| {
        let k = (j as isize + k).clamp(0, N_GAMMA as isize - 1) as usize;
        let gamma = gamma_node(k);
        KcTable::get_with(Ndf::Gtr { gamma }, smith, exact_gtr)
            .e
            .slice_y_cubic(alpha)
    };
    if w == 0.0 {
        // On a node: exactly that node's table.
        return KcTable::get_with(
            Ndf::Gtr {
                gamma: gamma_node(j),
            },
            smith,
            exact_gtr,
        )
        .slice(alpha);
    }
    let (v0, v1, v2, v3) = (node(-1), node(0), node(1), node(2));
    let nodes = (0..N_MU)
        .map(|i| {
            let [p0, p1, p2, p3] = [&v0, &v1, &v2, &v3].map(|t| t.node_value(i)[0] as f64);
            [catmull_rom(p0, p1, p2, p3, w).clamp(0.0, 1.0) as f32]
        })
        .collect();
    KcSlice::from_e(Table1::from_nodes(MU_AXIS, nodes))
}

/// γ of node k of [`GAMMA_AXIS`], as materials store it (f32).
pub fn gamma_node(k: usize) -> f32 {
    GAMMA_AXIS.node(k).exp2() as f32
}

/// The Catmull–Rom cubic through p0..p3 at w ∈ [0, 1] between p1 and p2
/// (as [`Table2::slice_y_cubic`]).
fn catmull_rom(p0: f64, p1: f64, p2: f64, p3: f64, w: f64) -> f64 {
    let t = 3.0 * (p1 - p2) + p3 - p0;
    p1 + 0.5 * w * (p2 - p0 + w * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3 + w * t))
}

/// E(μ) at one α, and its E_avg: what one material needs at shading time.
#[derive(Clone, Debug, PartialEq)]
pub struct KcSlice {
    pub e: Table1<1>,
    pub e_avg: f64,
}

impl KcSlice {
    /// A slice from its E(μ) nodes: E_avg integrated from its interpolant.
    fn from_e(e: Table1<1>) -> KcSlice {
        let [e_avg] = e.integrate(|mu| 2.0 * mu);
        KcSlice { e, e_avg }
    }

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
pub(crate) fn color_factor(f_avg: f64, e_avg: f64, mode: KcColor) -> f64 {
    let total = f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg));
    match mode {
        KcColor::KullaConty => total * f_avg,
        KcColor::Notes => total,
    }
}

/// F_avg = 2 ∫₀¹ F(μ) μ dμ of a Fresnel term, per channel: closed form
/// F0 + (1 − F0)/21 for Schlick, composite midpoint rule otherwise.
pub(crate) fn f_avg(fresnel: &Fresnel) -> [f64; 3] {
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
