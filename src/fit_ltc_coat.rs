//! `specula fit-ltc-coat`: fits the clearcoat LTC table of
//! core/src/ltc/coat.rs (its module docs give the lobe, the two-cosine
//! mixture, the axes and the file format).
//!
//! Per cell (ln α, √(1 − μo)) of the 12 × 32 grid, with K = 3 cosines:
//! - the lobe p(wi) = f_r(wi, wo) μi / n: the Disney model's own clearcoat
//!   lobe (`Disney::lobes`, weight 1, view in the xz-plane), n its albedo
//!   by the model's quadrature (`Disney::albedo_quadrature`);
//! - the mixture D = Σ wₖ Dₖ minimizing the L1 distance ∫ |D − p| dω
//!   (which bounds every polygon's error as a fraction of n), by
//!   Nelder–Mead (argmin) over the 4K + K − 1 parameters (ln a, ln c, b, d
//!   of each M; the weights as a softmax of K − 1 free logits and 0),
//!   restarted once from its best point. The distance is estimated with
//!   fixed stratified points (fit_ltc.rs's), drawn in equal numbers from
//!   the lobe (h ∝ D_GTR1(h)(n·h), reflected) and from each cosine, with
//!   the balance heuristic: |D − p| / mean of the K + 1 densities is
//!   bounded.
//!
//! Warm start: the α = 0.001 column runs from the normal view to grazing,
//! the first cell from isotropic cosines a = c = α^((2K − 2k − 1)/2K),
//! equal weights (GTR1's D cos θh mass is uniform in ln tan θh over
//! [ln α, 0]: one cosine at the middle of each K-th of it), each next
//! from the previous view; then each view's row runs from α = 0.001 up to
//! 0.1, each cell from its neighbour (rows in parallel, each in a fixed
//! order: the table does not depend on the thread count). Each cosine
//! thus changes continuously along both axes, so that bilinear
//! interpolation blends like with like (the mixture is the same under any
//! order of its cosines; fitted column by column from the normal view
//! instead, neighbouring columns at grazing views held them in different
//! orders, and a coat between two α nodes erred by up to 16 %).

use crate::fit_ltc::{
    cell_progress, cosine_step, ltc_density, ltc_sample, nelder_mead, outside_search, params_to_m,
    points, reflect, reflected_pdf, MU_MIN,
};
use argmin::core::{CostFunction, Error};
use rayon::prelude::*;
use specula_core::ltc::coat::{CoatCell, K, NX, NY, X_AXIS, Y_AXIS};
use specula_core::models::disney::{Disney, DisneyParams, Lobe};
use specula_core::ndf::d_gtr;
use specula_core::{Brdf, V3};
use std::f64::consts::PI;

/// The clearcoat lobe at one (α, μo).
pub(crate) struct CoatLobe {
    /// The model's α (from an f32 clearcoat_gloss, as a material has it).
    pub(crate) alpha: f64,
    pub(crate) wo: V3<f64>,
    model: Disney,
    /// n = ∫ f_r μi dωi.
    pub(crate) n: f64,
}

impl CoatLobe {
    pub(crate) fn new(alpha: f64, mu_o: f64) -> CoatLobe {
        let mu = mu_o.clamp(MU_MIN, 1.0);
        let wo = V3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
        let model = Disney::new_without_table(
            DisneyParams {
                base_color: [0.0; 3],
                specular: 0.0,
                // Weight ¼ clearcoat = 1.
                clearcoat: 4.0,
                clearcoat_gloss: ((0.1 - alpha) / 0.099) as f32,
                ..DisneyParams::default()
            },
            false,
        );
        let n = model.albedo_quadrature(&model.prepare(wo), Lobe::Clearcoat)[0];
        CoatLobe {
            alpha: model.params.clearcoat_alpha(),
            wo,
            model,
            n,
        }
    }

    /// p(wi): the normalized lobe (0 below the horizon).
    pub(crate) fn p(&self, wi: V3<f64>) -> f64 {
        if wi.z <= 0.0 {
            return 0.0;
        }
        let pr = self.model.prepare(self.wo);
        self.model.lobes(&pr, wi).0.clearcoat * wi.z / self.n
    }

    /// D_GTR1(h) (n·h): the density of h in the lobe's sampling.
    fn d_cos(&self, h: V3<f64>) -> f64 {
        let c2 = h.z * h.z;
        d_gtr(self.alpha, 1.0, c2, (1.0 - c2).max(0.0)) * h.z
    }

    /// A direction from the lobe's sampling (h ∝ D(h)(n·h) by GTR1's
    /// inverse CDF, cos²θh = (1 − (α²)^(1−u1)) / (1 − α²) [Burley12,
    /// eq. 2], reflected) and its density; it may be below the horizon.
    fn sample(&self, u1: f64, u2: f64) -> (V3<f64>, f64) {
        let a2 = self.alpha * self.alpha;
        let cos2 = ((1.0 - a2.powf(1.0 - u1)) / (1.0 - a2)).clamp(0.0, 1.0);
        let (cos_h, sin_h) = (cos2.sqrt(), (1.0 - cos2).sqrt());
        let phi = 2.0 * PI * u2;
        let h = V3::new(sin_h * phi.cos(), sin_h * phi.sin(), cos_h);
        reflect(self.wo, h, self.d_cos(h))
    }

    /// The density of [`CoatLobe::sample`] at `wi`.
    fn pdf(&self, wi: V3<f64>) -> f64 {
        reflected_pdf(self.wo, wi, |h| self.d_cos(h))
    }
}

/// Fitted parameters per cell: (ln a, ln c, b, d) of each Mₖ, then the
/// logits of w₂ … w_K (w₁'s is 0).
pub(crate) const N_PARAMS: usize = 4 * K + K - 1;
pub(crate) type Params = [f64; N_PARAMS];

/// (Mₖ, wₖ) of a parameter vector.
pub(crate) fn unpack(p: &[f64]) -> ([[f64; 4]; K], [f64; K]) {
    let m = core::array::from_fn(|k| params_to_m(&p[4 * k..4 * k + 4]));
    let e: [f64; K] = core::array::from_fn(|k| if k == 0 { 1.0 } else { p[4 * K + k - 1].exp() });
    let sum: f64 = e.iter().sum();
    (m, e.map(|x| x / sum))
}

/// The parameters of (Mₖ, wₖ) (w₁ > 0).
pub(crate) fn pack(m: &[[f64; 4]; K], w: &[f64; K]) -> Params {
    let mut p = [0.0; N_PARAMS];
    for k in 0..K {
        p[4 * k..4 * k + 4].copy_from_slice(&[m[k][0].ln(), m[k][2].ln(), m[k][1], m[k][3]]);
        if k > 0 {
            p[4 * K + k - 1] = (w[k] / w[0]).ln();
        }
    }
    p
}

/// ∫ |Σ wₖ Dₖ − p| dω, estimated as in the module docs.
pub(crate) fn l1_error(lobe: &CoatLobe, p: &[f64], pts: &[(f64, f64)]) -> f64 {
    let (m, w) = unpack(p);
    let term = |x: V3<f64>, pdf_lobe: f64| {
        let d = m.map(|m| ltc_density(m, x));
        let q = (pdf_lobe + d.iter().sum::<f64>()) / (K + 1) as f64;
        if q > 0.0 {
            let mix: f64 = d.iter().zip(&w).map(|(d, w)| d * w).sum();
            (mix - lobe.p(x)).abs() / q
        } else {
            0.0
        }
    };
    let mut sum = 0.0;
    for &(u1, u2) in pts {
        let (x, pdf) = lobe.sample(u1, u2);
        sum += term(x, pdf);
        for mk in m {
            let x = ltc_sample(mk, u1, u2);
            sum += term(x, lobe.pdf(x));
        }
    }
    sum / ((K + 1) * pts.len()) as f64
}

struct Problem<'a> {
    lobe: &'a CoatLobe,
    pts: &'a [(f64, f64)],
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, p: &Vec<f64>) -> Result<f64, Error> {
        // Each cosine inside the search region, no weight pinned to 0.
        if (0..K).any(|k| outside_search(&p[4 * k..4 * k + 4]))
            || p[4 * K..].iter().any(|l| l.abs() > 20.0)
        {
            return Ok(1e9);
        }
        Ok(l1_error(self.lobe, p, self.pts))
    }
}

/// The initial simplex step of parameter k: the cosines' as in `fit-ltc`,
/// 0.5 for the weights' logits.
fn step(x0: &[f64], k: usize) -> f64 {
    if k >= 4 * K {
        0.5
    } else {
        cosine_step(&x0[4 * (k / 4)..], k % 4)
    }
}

/// Fits one cell from a starting parameter vector; returns the cell, its
/// parameters and its L1 error.
pub(crate) fn fit_cell(
    alpha: f64,
    mu_o: f64,
    start: &Params,
    pts: &[(f64, f64)],
) -> (CoatCell, Params, f64) {
    let lobe = CoatLobe::new(alpha, mu_o);
    let (x, _) = nelder_mead(
        Problem { lobe: &lobe, pts },
        start,
        |k| step(start, k),
        4000,
    );
    let (x, err) = nelder_mead(Problem { lobe: &lobe, pts }, &x, |k| step(&x, k), 3000);
    let p: Params = core::array::from_fn(|k| x[k]);
    let (m, w) = unpack(&p);
    (CoatCell { m, w, n: lobe.n }, p, err)
}

/// α and μo of node (i, j).
pub(crate) fn node(i: usize, j: usize) -> (f64, f64) {
    let t = Y_AXIS.node(j);
    (X_AXIS.node(i).exp(), 1.0 - t * t)
}

/// The first cell's start (module docs): isotropic cosines
/// a = c = α^((2K − 2k − 1)/2K), equal weights.
pub(crate) fn first_start(alpha: f64) -> Params {
    let m = core::array::from_fn(|k| {
        let a = alpha.powf((2 * K - 2 * k - 1) as f64 / (2 * K) as f64);
        [a, 0.0, a, 0.0]
    });
    pack(&m, &[1.0 / K as f64; K])
}

/// One line per fitted cell on stderr where the progress bar is not
/// drawn (stderr not a terminal).
fn log(progress: bool, i: usize, j: usize, r: &(CoatCell, Params, f64)) {
    use std::io::IsTerminal;
    if progress && !std::io::stderr().is_terminal() {
        let (alpha, mu) = node(i, j);
        let c = &r.0;
        eprintln!(
            "cell ({i}, {j}) α {alpha:.4} μo {mu:.3}: L1 {:.4}, w {:.3?}, M {:.4?}, n {:.5}",
            r.2, c.w, c.m, c.n
        );
    }
}

/// The whole table, rows in y (view), with each cell's L1 error; progress
/// on stderr when `progress` (a bar on a terminal, else plain lines).
pub(crate) fn fit_table(progress: bool) -> (Vec<Vec<CoatCell>>, Vec<Vec<f64>>) {
    let pts = points();
    let bar = cell_progress("fit-ltc-coat", NX * NY, progress);
    // The α = 0.001 column, from the normal view to grazing.
    let mut start = first_start(node(0, 0).0);
    let mut first = Vec::with_capacity(NY);
    for j in 0..NY {
        let (alpha, mu) = node(0, j);
        let r = fit_cell(alpha, mu, &start, &pts);
        log(progress, 0, j, &r);
        start = r.1;
        first.push(r);
        bar.inc();
    }
    // Each view's row from α = 0.001 up.
    let rows: Vec<Vec<(CoatCell, f64)>> = (0..NY)
        .into_par_iter()
        .map(|j| {
            let (cell, mut s, err) = first[j];
            let mut row = vec![(cell, err)];
            for i in 1..NX {
                let (alpha, mu) = node(i, j);
                let r = fit_cell(alpha, mu, &s, &pts);
                log(progress, i, j, &r);
                s = r.1;
                row.push((r.0, r.2));
                bar.inc();
            }
            row
        })
        .collect();
    bar.finish();
    let cells = rows
        .iter()
        .map(|r| r.iter().map(|c| c.0).collect())
        .collect();
    let errs = rows
        .iter()
        .map(|r| r.iter().map(|c| c.1).collect())
        .collect();
    (cells, errs)
}

/// Fits the table and writes it to `out` (atomically), with the command,
/// the axes and the error summary in its header.
pub(crate) fn run(out: &std::path::Path) -> Result<(), String> {
    specula::output_plan::check_early("--output", out)?;
    let t = std::time::Instant::now();
    let (cells, errs) = fit_table(true);
    let summary = crate::fit_ltc::error_summary(&errs);
    eprintln!("{summary} ({:.0} s)", t.elapsed().as_secs_f64());
    for (j, row) in errs.iter().enumerate() {
        let (_, mu) = node(0, j);
        let r: Vec<String> = row.iter().map(|e| format!("{e:.3}")).collect();
        eprintln!("  μo {mu:.3}: {}", r.join(" "));
    }
    let comments = vec![
        format!("written by `specula fit-ltc-coat --output {}`", out.display()),
        "Disney clearcoat f_r mu_i: GTR1(alpha), separable Smith GGX at 0.25, Schlick F0 0.04, weight 1; view in the xz-plane".into(),
        "f_r mu_i / n ~ w1 D1 + w2 D2 + w3 D3, Dk the cosine through Mk = [[a,0,b],[0,c,0],[d,0,1]]".into(),
        "x = ln(alpha): 12 nodes on [ln 0.001, ln 0.1], ends; y = sqrt(1 - mu_o): 32 nodes on [0, 1], ends".into(),
        "per node, f32 LE: c M1^-1 entries m00 m02 m20 m22, the same for M2 and M3, w1 w2 w3, n; rows in y, x inside a row".into(),
        summary,
    ];
    crate::fit_ltc::write_table(out, &specula_core::ltc::coat::encode(&cells, &comments))
}

#[cfg(test)]
mod tests {
    use super::*;
    use specula_core::ltc::coat::table;

    /// The parameters of a stored node: each (a, b, c, d) from c M⁻¹
    /// (m11 = 1; M is proportional to its inverse's inverse, normalized to
    /// M₂₂ = 1), the weights; and n.
    fn stored(i: usize, j: usize) -> (Params, f32) {
        let v = table().node_value(i, j);
        let m = core::array::from_fn(|k| {
            let q = &v[4 * k..4 * k + 4];
            let (m00, m02, m20, m22) = (q[0] as f64, q[1] as f64, q[2] as f64, q[3] as f64);
            let det = m00 * m22 - m02 * m20;
            let (a, b, d, e) = (m22 / det, -m02 / det, -m20 / det, m00 / det);
            [a / e, b / e, 1.0 / e, d / e]
        });
        let w = core::array::from_fn(|k| v[4 * K + k] as f64);
        (pack(&m, &w), v[5 * K])
    }

    #[test]
    fn refitting_cells_from_their_stored_neighbours_matches_the_committed_table() {
        let pts = points();
        // (i = α node, j = view node): glossy, rough, grazing, on the horizon.
        for (i, j) in [(1, 5), (6, 20), (11, 28), (3, 31)] {
            // The fit of (i, j) warm-starts from (i − 1, j).
            let (start, _) = stored(i - 1, j);
            let (alpha, mu) = node(i, j);
            let (cell, _, err) = fit_cell(alpha, mu, &start, &pts);
            let (here, want) = stored(i, j);
            let lobe = CoatLobe::new(alpha, mu);
            let stored_err = l1_error(&lobe, &here, &pts);
            eprintln!("cell ({i}, {j}): refit L1 {err:.5}, stored L1 {stored_err:.5}");
            // Nelder–Mead from an f32-rounded start: the same minimum to
            // within the optimizer's tolerance.
            assert!(
                (err - stored_err).abs() < 0.01 * stored_err,
                "({i}, {j}): {err} vs {stored_err}"
            );
            let n = cell.channels()[5 * K];
            assert!(
                (n - want).abs() <= 1e-6 * want,
                "({i}, {j}): n {n} vs {want}"
            );
        }
    }

    #[test]
    fn the_l1_estimate_matches_quadrature() {
        // An independent check of the MIS estimate: ∫ |D − p| by a plain
        // midpoint rule in (cos θ, φ) on a fine grid, for the roughest coat
        // at an oblique view and a mixture near its fit.
        let lobe = CoatLobe::new(0.1, 0.6);
        let p = pack(
            &[
                [0.12, -0.05, 0.1, 0.02],
                [0.5, -0.2, 0.45, 0.05],
                [1.2, -0.4, 0.9, 0.1],
            ],
            &[0.4, 0.35, 0.25],
        );
        let est = l1_error(&lobe, &p, &points());
        let (m, w) = unpack(&p);
        let q = crate::fit_ltc::sphere_midpoint(1600, 800, |x| {
            let d: f64 = (0..K).map(|k| w[k] * ltc_density(m[k], x)).sum();
            (d - lobe.p(x)).abs()
        });
        assert!((est - q).abs() < 0.02 * q, "MIS {est} vs quadrature {q}");
    }
}
