//! `specula fit-ltc-coat`: fits the clearcoat LTC table of
//! core/src/ltc/coat.rs (its module docs give the lobe, the two-cosine
//! mixture, the axes and the file format).
//!
//! Per cell (ln α, √(1 − μo)) of the 12 × 32 grid:
//! - the lobe p(wi) = f_r(wi, wo) μi / n: the Disney model's own clearcoat
//!   lobe (`Disney::lobes`, weight 1, view in the xz-plane), n its albedo
//!   by the model's quadrature (`Disney::albedo_quadrature`);
//! - the mixture w D₁ + (1 − w) D₂ minimizing the L1 distance
//!   ∫ |w D₁ + (1 − w) D₂ − p| dω (which bounds every polygon's error as a
//!   fraction of n), by Nelder–Mead (argmin) over the nine parameters
//!   (ln a, ln c, b, d of each M and logit w), restarted once from its
//!   best point. The distance is estimated with fixed stratified points
//!   (fit_ltc.rs's), a third drawn from the lobe (h ∝ D_GTR1(h)(n·h),
//!   reflected), a third from each cosine, with the balance heuristic:
//!   |D − p| / mean of the three densities is bounded.
//!
//! Warm start: the normal view's row runs from α = 0.1 down to 0.001, the
//! first cell from `fit_coat_mixture`'s two GGX α (as isotropic
//! transforms), each next from its neighbour; then each α column runs
//! from the normal view to grazing, each cell from the previous view
//! (columns in parallel, each in a fixed order: the table does not depend
//! on the thread count).

use crate::fit_ltc::{ltc_density, ltc_sample, points, MU_MIN};
use argmin::core::{CostFunction, Error, Executor, State};
use argmin::solver::neldermead::NelderMead;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use specula_core::ltc::coat::{CoatCell, NX, NY, X_AXIS, Y_AXIS};
use specula_core::models::disney::{fit_coat_mixture, Disney, DisneyParams, Lobe};
use specula_core::ndf::d_gtr;
use specula_core::{Brdf, V3};
use std::f64::consts::PI;

/// The clearcoat lobe at one (α, μo).
pub struct CoatLobe {
    /// The model's α (from an f32 clearcoat_gloss, as a material has it).
    pub alpha: f64,
    pub wo: V3<f64>,
    model: Disney,
    /// n = ∫ f_r μi dωi.
    pub n: f64,
}

impl CoatLobe {
    pub fn new(alpha: f64, mu_o: f64) -> CoatLobe {
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
    pub fn p(&self, wi: V3<f64>) -> f64 {
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
        let o_h = self.wo.dot(h);
        let wi = h * (2.0 * o_h) - self.wo;
        (wi, self.d_cos(h) / (4.0 * o_h.abs().max(1e-12)))
    }

    /// The density of [`CoatLobe::sample`] at `wi`.
    fn pdf(&self, wi: V3<f64>) -> f64 {
        let s = wi + self.wo;
        let l = s.length();
        if l == 0.0 {
            return 0.0;
        }
        let h = s * (1.0 / l);
        if h.z <= 0.0 {
            return 0.0;
        }
        self.d_cos(h) / (4.0 * self.wo.dot(h).abs().max(1e-12))
    }
}

/// A cell's nine fitted parameters: (ln a, ln c, b, d) of M₁ and M₂,
/// logit w.
pub type Params = [f64; 9];

/// (M₁, M₂, w) of a parameter vector.
pub fn unpack(p: &[f64]) -> ([f64; 4], [f64; 4], f64) {
    (
        [p[0].exp(), p[2], p[1].exp(), p[3]],
        [p[4].exp(), p[6], p[5].exp(), p[7]],
        1.0 / (1.0 + (-p[8]).exp()),
    )
}

/// ∫ |w D₁ + (1 − w) D₂ − p| dω, estimated as in the module docs.
pub fn l1_error(lobe: &CoatLobe, p: &[f64], pts: &[(f64, f64)]) -> f64 {
    let (m1, m2, w) = unpack(p);
    let term = |x: V3<f64>, pdf_lobe: f64| {
        let (d1, d2) = (ltc_density(m1, x), ltc_density(m2, x));
        let q = (pdf_lobe + d1 + d2) / 3.0;
        if q > 0.0 {
            (w * d1 + (1.0 - w) * d2 - lobe.p(x)).abs() / q
        } else {
            0.0
        }
    };
    let mut sum = 0.0;
    for &(u1, u2) in pts {
        let (x, pdf) = lobe.sample(u1, u2);
        sum += term(x, pdf);
        for m in [m1, m2] {
            let x = ltc_sample(m, u1, u2);
            sum += term(x, lobe.pdf(x));
        }
    }
    sum / (3 * pts.len()) as f64
}

struct Problem<'a> {
    lobe: &'a CoatLobe,
    pts: &'a [(f64, f64)],
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, p: &Vec<f64>) -> Result<f64, Error> {
        // Keep the simplex out of absurd transforms (a, c within e^±12,
        // w not pinned to 0 or 1, det M > 0).
        let (m1, m2, _) = unpack(p);
        let bad = |m: [f64; 4], q: &[f64]| {
            q[0].abs() > 12.0 || q[1].abs() > 12.0 || q[2].abs() > 1e4 || m[0] - m[1] * m[3] <= 1e-9
        };
        if bad(m1, &p[0..4]) || bad(m2, &p[4..8]) || p[8].abs() > 20.0 {
            return Ok(1e9);
        }
        Ok(l1_error(self.lobe, p, self.pts))
    }
}

fn nelder_mead(problem: Problem, x0: &[f64], iters: u64) -> (Vec<f64>, f64) {
    let step = [0.15, 0.15, 0.1, 0.1, 0.15, 0.15, 0.1, 0.1, 0.5];
    let mut simplex = vec![x0.to_vec()];
    for (k, s) in step.iter().enumerate() {
        let mut x = x0.to_vec();
        x[k] += s * if k % 4 == 2 { 1.0 + x0[k].abs() } else { 1.0 };
        simplex.push(x);
    }
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(1e-7)
        .expect("a positive tolerance");
    let res = Executor::new(problem, solver)
        .configure(|s| s.max_iters(iters))
        .run()
        .expect("the cost never fails");
    let best = res.state().get_best_param().expect("a best point").clone();
    (best, res.state().get_best_cost())
}

/// Fits one cell from a starting parameter vector; returns the cell, its
/// parameters and its L1 error.
pub fn fit_cell(
    alpha: f64,
    mu_o: f64,
    start: &Params,
    pts: &[(f64, f64)],
) -> (CoatCell, Params, f64) {
    let lobe = CoatLobe::new(alpha, mu_o);
    let (x, _) = nelder_mead(Problem { lobe: &lobe, pts }, start, 1500);
    let (x, err) = nelder_mead(Problem { lobe: &lobe, pts }, &x, 1000);
    let p: Params = core::array::from_fn(|k| x[k]);
    let (m1, m2, w) = unpack(&p);
    (
        CoatCell {
            m1,
            m2,
            w,
            n: lobe.n,
        },
        p,
        err,
    )
}

/// α and μo of node (i, j).
pub fn node(i: usize, j: usize) -> (f64, f64) {
    let t = Y_AXIS.node(j);
    (X_AXIS.node(i).exp(), 1.0 - t * t)
}

/// The first cell's start: `fit_coat_mixture`'s (w, α₁, α₂) as isotropic
/// transforms diag(αₖ, αₖ, 1).
pub fn mixture_start(alpha: f64) -> Params {
    let ([w, a1, a2], _) = fit_coat_mixture(alpha);
    let w = w.clamp(0.01, 0.99);
    let (l1, l2) = (a1.ln(), a2.ln());
    [l1, l1, 0.0, 0.0, l2, l2, 0.0, 0.0, (w / (1.0 - w)).ln()]
}

/// One line per fitted cell on stderr where the progress bar is not
/// drawn (stderr not a terminal).
fn log(progress: bool, i: usize, j: usize, r: &(CoatCell, Params, f64)) {
    use std::io::IsTerminal;
    if progress && !std::io::stderr().is_terminal() {
        let (alpha, mu) = node(i, j);
        let c = &r.0;
        eprintln!(
            "cell ({i}, {j}) α {alpha:.4} μo {mu:.3}: L1 {:.4}, w {:.3}, M1 {:.4?}, M2 {:.4?}, n {:.5}",
            r.2, c.w, c.m1, c.m2, c.n
        );
    }
}

/// The whole table, rows in y (view), with each cell's L1 error; a
/// progress bar on stderr when `progress`.
pub fn fit_table(progress: bool) -> (Vec<Vec<CoatCell>>, Vec<Vec<f64>>) {
    let pts = points();
    let bar = if progress {
        let b = ProgressBar::new((NX * NY) as u64);
        b.set_style(
            ProgressStyle::with_template(
                "fit-ltc-coat {bar:40} {pos}/{len} cells, {elapsed} (eta {eta})",
            )
            .expect("a valid template"),
        );
        b
    } else {
        ProgressBar::hidden()
    };
    // The normal view's row, from α = 0.1 down.
    let mut start = mixture_start(node(NX - 1, 0).0);
    let mut first = vec![None; NX];
    for i in (0..NX).rev() {
        let (alpha, mu) = node(i, 0);
        let r = fit_cell(alpha, mu, &start, &pts);
        log(progress, i, 0, &r);
        start = r.1;
        first[i] = Some(r);
        bar.inc(1);
    }
    // Each α column from the normal view to grazing.
    let columns: Vec<Vec<(CoatCell, f64)>> = (0..NX)
        .into_par_iter()
        .map(|i| {
            let (cell, mut s, err) = first[i].expect("fitted above");
            let mut col = vec![(cell, err)];
            for j in 1..NY {
                let (alpha, mu) = node(i, j);
                let r = fit_cell(alpha, mu, &s, &pts);
                log(progress, i, j, &r);
                s = r.1;
                col.push((r.0, r.2));
                bar.inc(1);
            }
            col
        })
        .collect();
    bar.finish();
    let cells = (0..NY)
        .map(|j| (0..NX).map(|i| columns[i][j].0).collect())
        .collect();
    let errs = (0..NY)
        .map(|j| (0..NX).map(|i| columns[i][j].1).collect())
        .collect();
    (cells, errs)
}

/// Fits the table and writes it to `out` (atomically), with the command,
/// the axes and the error summary in its header.
pub fn run(out: &std::path::Path) -> Result<(), String> {
    let t = std::time::Instant::now();
    let (cells, errs) = fit_table(true);
    let mut all: Vec<f64> = errs.iter().flatten().copied().collect();
    all.sort_by(f64::total_cmp);
    let q = |f: f64| all[((all.len() - 1) as f64 * f) as usize];
    let summary = format!(
        "L1 distance of the fit over the {} cells: median {:.4}, p90 {:.4}, max {:.4}",
        all.len(),
        q(0.5),
        q(0.9),
        q(1.0)
    );
    eprintln!("{summary} ({:.0} s)", t.elapsed().as_secs_f64());
    for (j, row) in errs.iter().enumerate() {
        let (_, mu) = node(0, j);
        let r: Vec<String> = row.iter().map(|e| format!("{e:.3}")).collect();
        eprintln!("  μo {mu:.3}: {}", r.join(" "));
    }
    let comments = vec![
        format!("written by `specula fit-ltc-coat --output {}`", out.display()),
        "Disney clearcoat f_r mu_i: GTR1(alpha), separable Smith GGX at 0.25, Schlick F0 0.04, weight 1; view in the xz-plane".into(),
        "f_r mu_i / n ~ w D1 + (1 - w) D2, Dk the cosine through Mk = [[a,0,b],[0,c,0],[d,0,1]]".into(),
        "x = ln(alpha): 12 nodes on [ln 0.001, ln 0.1], ends; y = sqrt(1 - mu_o): 32 nodes on [0, 1], ends".into(),
        "per node, f32 LE: c M1^-1 entries m00 m02 m20 m22, the same for M2, w, n; rows in y, x inside a row".into(),
        summary,
    ];
    let bytes = specula_core::ltc::coat::encode(&cells, &comments);
    let sink = crate::outputs::Output {
        flag: "--output".into(),
        path: out.to_path_buf(),
        sink: crate::outputs::resolve(out, false)?,
    };
    sink.write(&bytes)?;
    eprintln!("wrote {}", out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use specula_core::ltc::coat::table;

    /// The parameters of a stored node: each (a, b, c, d) from c M⁻¹
    /// (m11 = 1; M is proportional to its inverse's inverse, normalized to
    /// M₂₂ = 1), and logit w.
    fn stored(i: usize, j: usize) -> (Params, [f32; 10]) {
        let v = table().node_value(i, j);
        let m = |k: usize| {
            let (m00, m02, m20, m22) = (
                v[k] as f64,
                v[k + 1] as f64,
                v[k + 2] as f64,
                v[k + 3] as f64,
            );
            let det = m00 * m22 - m02 * m20;
            let (a, b, d, e) = (m22 / det, -m02 / det, -m20 / det, m00 / det);
            [a / e, b / e, 1.0 / e, d / e]
        };
        let (m1, m2, w) = (m(0), m(4), v[8] as f64);
        (
            [
                m1[0].ln(),
                m1[2].ln(),
                m1[1],
                m1[3],
                m2[0].ln(),
                m2[2].ln(),
                m2[1],
                m2[3],
                (w / (1.0 - w)).ln(),
            ],
            v,
        )
    }

    #[test]
    fn refitting_cells_from_their_stored_neighbours_matches_the_committed_table() {
        let pts = points();
        // (i = α node, j = view node): glossy, rough, grazing, on the horizon.
        for (i, j) in [(1, 5), (6, 20), (11, 28), (3, 31)] {
            // The fit of (i, j) warm-starts from (i, j − 1).
            let (start, _) = stored(i, j - 1);
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
            let n = cell.channels()[9];
            assert!(
                (n - want[9]).abs() <= 1e-6 * want[9],
                "({i}, {j}): n {n} vs {}",
                want[9]
            );
        }
    }

    #[test]
    fn the_l1_estimate_matches_quadrature() {
        // An independent check of the three-way MIS estimate: ∫ |D − p|
        // by a plain midpoint rule in (cos θ, φ) on a fine grid, for the
        // roughest coat at an oblique view and a mixture near its fit.
        let lobe = CoatLobe::new(0.1, 0.6);
        let p = [
            (0.12f64).ln(),
            (0.1f64).ln(),
            -0.05,
            0.02,
            (0.5f64).ln(),
            (0.45f64).ln(),
            -0.2,
            0.05,
            0.3,
        ];
        let est = l1_error(&lobe, &p, &points());
        let (m1, m2, w) = unpack(&p);
        let (nt, np) = (1600, 800);
        let mut q = 0.0;
        for a in 0..nt {
            let z = -1.0 + 2.0 * (a as f64 + 0.5) / nt as f64;
            let r = (1.0 - z * z).sqrt();
            for b in 0..np {
                let phi = 2.0 * PI * (b as f64 + 0.5) / np as f64;
                let x = V3::new(r * phi.cos(), r * phi.sin(), z);
                let d = w * ltc_density(m1, x) + (1.0 - w) * ltc_density(m2, x);
                q += (d - lobe.p(x)).abs();
            }
        }
        q *= 4.0 * PI / (nt * np) as f64;
        assert!((est - q).abs() < 0.02 * q, "MIS {est} vs quadrature {q}");
    }
}
