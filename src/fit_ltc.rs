//! `specula fit-ltc`: fits the LTC table of core/src/ltc/ggx.rs (its module
//! docs give the transform, the axes and the file format).
//!
//! Per cell (√α, √(1 − μo)) of the 64 × 64 grid:
//! - the lobe p(wi) = f(wi, wo) cos θi / n: GGX, height-correlated Smith,
//!   F = 1, the project's own `Microfacet` (view in the xz-plane);
//! - n and n_w by the model's deterministic albedo quadrature
//!   (`MicrofacetParams::specular_albedo`, ~1e-5) with Schlick F0 = 1 and
//!   F0 = 0;
//! - M's (a, b, c) minimizing the L1 distance ∫ |D − p| dω, by Nelder–Mead
//!   (argmin) over (ln a, ln c, b). The L1 distance bounds the error of
//!   every polygon integral as a fraction of the albedo n (the measure the
//!   issue sets), however the polygon sits, horizon included. It is
//!   estimated with fixed stratified points (so the cost is a
//!   deterministic function of the parameters) drawn half from the lobe
//!   (h ∝ D(h)(n·h)) and half from the LTC, with the balance heuristic:
//!   |D − p| / (½ pdf_lobe + ½ D) is bounded, so the estimate is smooth.
//!
//! Warm start: the α = 1 row is fitted from the normal view outward, each
//! cell from its neighbour; then each view column runs from α = 1 down to
//! the smallest α, each cell from the rougher neighbour (columns in
//! parallel, each in a fixed order, so the table does not depend on the
//! thread count).

use argmin::core::{CostFunction, Error, Executor, State};
use argmin::solver::neldermead::NelderMead;
use rayon::prelude::*;
use specula::progress::Progress;
use specula_core::ltc::ggx::{Cell, N, X_AXIS, Y_AXIS};
use specula_core::models::microfacet::{Fresnel, Microfacet, MicrofacetParams, Ndf, Smith};
use specula_core::small_light::{self, Scene};
use specula_core::table::Table2;
use specula_core::{Brdf, V3};
use std::f64::consts::PI;

/// Stratified points per distribution in the error estimate (a 32 × 32
/// grid, jittered by a fixed Hammersley offset).
const SIDE: usize = 32;
/// Smallest μo fitted (the last view node is μo = 0, a view on the
/// horizon): the one the runtime's lobe correction uses.
pub(crate) use specula_core::ltc::ggx::MU_MIN;

/// The lobe at one (α, μo): everything the cost needs.
pub(crate) struct Lobe {
    pub(crate) alpha: f64,
    pub(crate) wo: V3<f64>,
    model: Microfacet,
    /// n: ∫ f cos with F = 1.
    pub(crate) n: f64,
    /// n_w: ∫ f cos (1 − wi·h)⁵.
    pub(crate) n_w: f64,
}

fn ggx(alpha: f64, f0: f32) -> MicrofacetParams {
    MicrofacetParams {
        ndf: Ndf::Ggx,
        alpha: alpha as f32,
        smith: Smith::HeightCorrelated,
        fresnel: Fresnel::Schlick { f0: [f0; 3] },
        diffuse: [0.0; 3],
        gtr_lambda: Default::default(),
    }
}

impl Lobe {
    pub(crate) fn new(alpha: f64, mu_o: f64) -> Lobe {
        let mu = mu_o.clamp(MU_MIN, 1.0);
        let wo = V3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
        let n = ggx(alpha, 1.0).specular_albedo(mu)[0];
        let n_w = ggx(alpha, 0.0).specular_albedo(mu)[0];
        Lobe {
            alpha: (alpha as f32) as f64,
            wo,
            model: Microfacet::new_without_table(ggx(alpha, 1.0), None),
            n,
            n_w,
        }
    }

    /// p(wi): the normalized lobe.
    pub(crate) fn p(&self, wi: V3<f64>) -> f64 {
        let pr = self.model.prepare(self.wo);
        self.model.f_cos_local(&pr, wi).x / self.n
    }

    /// A direction from the lobe's sampling (h ∝ D(h)(n·h), reflected) and
    /// that sampling's density; the direction may be below the horizon.
    fn sample(&self, u1: f64, u2: f64) -> (V3<f64>, f64) {
        let a2 = self.alpha * self.alpha;
        let cos2 = (1.0 - u1) / (1.0 + (a2 - 1.0) * u1);
        let cos_h = cos2.sqrt();
        let sin_h = (1.0 - cos2).max(0.0).sqrt();
        let phi = 2.0 * PI * u2;
        let h = V3::new(sin_h * phi.cos(), sin_h * phi.sin(), cos_h);
        let d = a2 / (PI * (cos2 * (a2 - 1.0) + 1.0).powi(2));
        reflect(self.wo, h, d * cos_h)
    }
}

/// `wo` reflected about the half vector `h`, drawn with density `d_cos`
/// (D(h)(n·h)), and the reflected direction's density d_cos / (4 |wo·h|).
pub(crate) fn reflect(wo: V3<f64>, h: V3<f64>, d_cos: f64) -> (V3<f64>, f64) {
    let o_h = wo.dot(h);
    (h * (2.0 * o_h) - wo, d_cos / (4.0 * o_h.abs().max(1e-12)))
}

/// The density at `wi` of [`reflect`]ed directions whose half vectors have
/// density `d_cos(h)`: zero where h is below the horizon (never drawn).
pub(crate) fn reflected_pdf(wo: V3<f64>, wi: V3<f64>, d_cos: impl Fn(V3<f64>) -> f64) -> f64 {
    let s = wi + wo;
    let l = s.length();
    if l == 0.0 {
        return 0.0;
    }
    let h = s * (1.0 / l);
    if h.z <= 0.0 {
        return 0.0;
    }
    d_cos(h) / (4.0 * wo.dot(h).abs().max(1e-12))
}

/// The LTC density D(ω) of M = [[a, 0, b], [0, c, 0], [0, 0, 1]] at unit ω.
pub(crate) fn ltc_density(m: [f64; 4], w: V3<f64>) -> f64 {
    let [a, b, c, d] = m;
    let det = a - b * d;
    let o = V3::new((w.x - b * w.z) / det, w.y / c, (a * w.z - d * w.x) / det);
    let l2 = o.length_squared();
    let l = l2.sqrt();
    if o.z <= 0.0 {
        return 0.0;
    }
    (o.z / l) / PI / (det * c * l2 * l)
}

/// A direction of the LTC's distribution from uniform (u1, u2).
pub(crate) fn ltc_sample(m: [f64; 4], u1: f64, u2: f64) -> V3<f64> {
    let [a, b, c, d] = m;
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let o = V3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt());
    V3::new(a * o.x + b * o.z, c * o.y, d * o.x + o.z).normalize()
}

/// The stratified points of the estimate.
pub(crate) fn points() -> Vec<(f64, f64)> {
    (0..SIDE * SIDE)
        .map(|k| {
            let (i, j) = (k % SIDE, k / SIDE);
            // A fixed irrational jitter inside each stratum.
            let ju = (k as f64 * 0.618_033_988_749_894_9).fract();
            let jv = (k as f64 * 0.754_877_666_246_692_7).fract();
            ((i as f64 + ju) / SIDE as f64, (j as f64 + jv) / SIDE as f64)
        })
        .collect()
}

/// ∫ |D − p| dω, estimated as in the module docs.
pub(crate) fn l1_error(lobe: &Lobe, m: [f64; 4], pts: &[(f64, f64)]) -> f64 {
    let mut sum = 0.0;
    let term = |w: V3<f64>, pdf_lobe: f64| {
        let d = ltc_density(m, w);
        let p = if w.z > 0.0 { lobe.p(w) } else { 0.0 };
        let q = 0.5 * pdf_lobe + 0.5 * d;
        if q > 0.0 {
            (d - p).abs() / q
        } else {
            0.0
        }
    };
    for &(u1, u2) in pts {
        let (w, pdf) = lobe.sample(u1, u2);
        sum += term(w, pdf);
        let w = ltc_sample(m, u1, u2);
        sum += term(w, lobe_pdf(lobe, w));
    }
    sum / (2 * pts.len()) as f64
}

/// The density of [`Lobe::sample`] at `wi`: D(h)(n·h) / (4 |wo·h|), h the
/// half vector (zero when h is below the horizon: never sampled).
fn lobe_pdf(lobe: &Lobe, wi: V3<f64>) -> f64 {
    reflected_pdf(lobe.wo, wi, |h| {
        let a2 = lobe.alpha * lobe.alpha;
        let c2 = h.z * h.z;
        let d = a2 / (PI * (c2 * (a2 - 1.0) + 1.0).powi(2));
        d * h.z
    })
}

struct Problem<'a> {
    lobe: &'a Lobe,
    pts: &'a [(f64, f64)],
}

/// M's (a, b, c, d) from a cosine's fitted parameters (ln a, ln c, b, d).
pub(crate) fn params_to_m(p: &[f64]) -> [f64; 4] {
    [p[0].exp(), p[2], p[1].exp(), p[3]]
}

/// Whether a cosine's parameters (ln a, ln c, b, d) leave the region the
/// fit searches: a or c beyond e^±12, |b| > 1e4, or det M ≤ 0. The costs
/// return 1e9 there, keeping the simplex out of absurd transforms.
pub(crate) fn outside_search(p: &[f64]) -> bool {
    let m = params_to_m(p);
    p[0].abs() > 12.0 || p[1].abs() > 12.0 || p[2].abs() > 1e4 || m[0] - m[1] * m[3] <= 1e-9
}

/// Nelder–Mead from `x0` with the simplex's other points at x0 + step(k)
/// along each axis k, at most `iters` iterations; the best point and its
/// cost.
pub(crate) fn nelder_mead<P>(
    problem: P,
    x0: &[f64],
    step: impl Fn(usize) -> f64,
    iters: u64,
) -> (Vec<f64>, f64)
where
    P: CostFunction<Param = Vec<f64>, Output = f64>,
{
    let mut simplex = vec![x0.to_vec()];
    for k in 0..x0.len() {
        let mut x = x0.to_vec();
        x[k] += step(k);
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

/// The fitters' progress on stderr (progress.rs; nothing when not
/// `show`).
pub(crate) fn cell_progress(name: &str, cells: usize, show: bool) -> Progress {
    Progress::new(name, "cells", cells as u64, show)
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, p: &Vec<f64>) -> Result<f64, Error> {
        if outside_search(p) {
            return Ok(1e9);
        }
        Ok(l1_error(self.lobe, params_to_m(p), self.pts))
    }
}

/// The initial simplex step of a cosine's parameter k (ln a, ln c, b, d)
/// from `x0`.
pub(crate) fn cosine_step(x0: &[f64], k: usize) -> f64 {
    match k {
        2 => 0.1 * (1.0 + x0[2].abs()),
        3 => 0.1,
        _ => 0.15,
    }
}

/// Fits one cell from a starting M; returns the cell and its L1 error.
pub(crate) fn fit_cell(alpha: f64, mu_o: f64, start: [f64; 4], pts: &[(f64, f64)]) -> (Cell, f64) {
    let lobe = Lobe::new(alpha, mu_o);
    let x0 = [start[0].ln(), start[2].ln(), start[1], start[3]];
    let (best, err) = nelder_mead(
        Problem { lobe: &lobe, pts },
        &x0,
        |k| cosine_step(&x0, k),
        600,
    );
    let m = params_to_m(&best);
    (
        Cell {
            a: m[0],
            b: m[1],
            c: m[2],
            d: m[3],
            n: lobe.n,
            n_w: lobe.n_w,
        },
        err,
    )
}

/// α and μo of node (i, j).
pub(crate) fn node(i: usize, j: usize) -> (f64, f64) {
    let r = X_AXIS.node(i);
    let t = Y_AXIS.node(j);
    (r * r, 1.0 - t * t)
}

/// The whole table, rows in y (view), with each cell's L1 error; progress
/// on stderr when `progress` (a bar on a terminal, else plain lines).
pub(crate) fn fit_table(progress: bool) -> (Vec<Vec<Cell>>, Vec<Vec<f64>>) {
    let pts = points();
    let bar = cell_progress("fit-ltc", N * N, progress);
    // The α = 1 row (x = N − 1), from the normal view outward.
    let mut start = [1.0, 0.0, 1.0, 0.0];
    let mut top = Vec::with_capacity(N);
    for j in 0..N {
        let (alpha, mu) = node(N - 1, j);
        let (cell, err) = fit_cell(alpha, mu, start, &pts);
        start = [cell.a, cell.b, cell.c, cell.d];
        top.push((cell, err));
        bar.inc();
    }
    // Each view column from α = 1 down.
    let columns: Vec<Vec<(Cell, f64)>> = (0..N)
        .into_par_iter()
        .map(|j| {
            let mut col = vec![top[j]; N];
            let mut s = [top[j].0.a, top[j].0.b, top[j].0.c, top[j].0.d];
            for i in (0..N - 1).rev() {
                let (alpha, mu) = node(i, j);
                let r = fit_cell(alpha, mu, s, &pts);
                s = [r.0.a, r.0.b, r.0.c, r.0.d];
                col[i] = r;
                bar.inc();
            }
            col
        })
        .collect();
    bar.finish();
    let cells = (0..N)
        .map(|j| (0..N).map(|i| columns[j][i].0).collect())
        .collect();
    let errs = (0..N)
        .map(|j| (0..N).map(|i| columns[j][i].1).collect())
        .collect();
    (cells, errs)
}

/// The fit's L1 distances over all cells as one header line: median, p90
/// and max.
pub(crate) fn error_summary(errs: &[Vec<f64>]) -> String {
    let mut all: Vec<f64> = errs.iter().flatten().copied().collect();
    all.sort_by(f64::total_cmp);
    let q = |f: f64| all[((all.len() - 1) as f64 * f) as usize];
    format!(
        "L1 distance of the fit over the {} cells: median {:.4}, p90 {:.4}, max {:.4}",
        all.len(),
        q(0.5),
        q(0.9),
        q(1.0)
    )
}

/// What `fit-ltc` does besides fitting the whole table.
pub(crate) struct Options {
    /// Measure this table file instead of fitting.
    pub(crate) check: Option<std::path::PathBuf>,
}

/// The per-pixel error under a small light and the view sweep's kinks of
/// `table` (specula_core::small_light), one line per roughness.
pub(crate) fn check_lines(table: &Table2<6>) -> Vec<String> {
    let alphas = [0.2, 0.3, 0.4, 0.5];
    let y_hi = (1.0 - 85f64.to_radians().cos()).sqrt();
    alphas
        .par_iter()
        .map(|&alpha| {
            let s = small_light::pixel_error(table, alpha, Scene::Sphere, 32, small_light::LIT);
            let f = small_light::pixel_error(table, alpha, Scene::Floor, 32, small_light::LIT);
            let s1 = small_light::pixel_error(table, alpha, Scene::Sphere, 32, 0.01);
            let f1 = small_light::pixel_error(table, alpha, Scene::Floor, 32, 0.01);
            let k = small_light::kinks(table, alpha, 0.0, y_hi);
            let max = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            format!(
                "alpha {alpha}: sphere mean {:.2}% worst {:.1}% w {:.2}%, floor mean {:.2}% worst {:.1}% w {:.2}%; \
                 sweep second difference across rows rms {:.2e} max {:.2e}, within rms {:.2e} max {:.2e}",
                100.0 * s.mean,
                100.0 * s.worst,
                100.0 * s.weighted,
                100.0 * f.mean,
                100.0 * f.worst,
                100.0 * f.weighted,
                k.across_rms(),
                max(&k.across),
                k.within_rms(),
                max(&k.within)
            ) + &format!(
                "\n  pixels >= 1 %: sphere mean {:.2}% weighted {:.2}%, floor mean {:.2}% weighted {:.2}%\n  \
                 worst pixels [theta_o, theta_l, phi_l, LTC, reference]: sphere {:.3?}, floor {:.3?}",
                100.0 * s1.mean,
                100.0 * s1.weighted,
                100.0 * f1.mean,
                100.0 * f1.weighted,
                s.worst_at,
                f.worst_at
            )
        })
        .collect()
}

/// Fits the table and writes it to `out` (atomically), with the command,
/// the axes and the error summary in its header; or measures a table file
/// (`opts.check`).
pub(crate) fn run(out: &std::path::Path, opts: &Options) -> Result<(), String> {
    if let Some(path) = &opts.check {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let t = specula_core::ltc::ggx::decode(&bytes)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        for line in check_lines(&t) {
            println!("{line}");
        }
        return Ok(());
    }
    specula::output_plan::check_early("--output", out)?;
    let t = std::time::Instant::now();
    let (cells, errs) = fit_table(true);
    let summary = error_summary(&errs);
    eprintln!("{summary} ({:.0} s)", t.elapsed().as_secs_f64());
    let comments = vec![
        format!("written by `specula fit-ltc --output {}`", out.display()),
        "GGX, height-correlated Smith, F = 1; M = [[a,0,b],[0,c,0],[d,0,1]], view in the xz-plane".into(),
        "x = sqrt(alpha): 64 nodes on [sqrt(0.001), 1], ends; y = sqrt(1 - mu_o): 64 nodes on [0, 1], ends".into(),
        "per node, f32 LE: c M^-1 entries m00 m02 m20 m22, n, n_w; rows in y, x inside a row".into(),
        summary,
    ];
    write_table(out, &specula_core::ltc::ggx::encode(&cells, &comments))
}

/// Writes a fitted table's bytes to `out`, checked and written like every
/// output (output_plan.rs): no device or link is replaced, the write is atomic.
pub(crate) fn write_table(out: &std::path::Path, bytes: &[u8]) -> Result<(), String> {
    let sink = specula::output_plan::Output {
        flag: "--output".into(),
        path: out.to_path_buf(),
        sink: specula::output_plan::resolve(out, false)?,
    };
    sink.write(bytes)?;
    eprintln!("wrote {}", out.display());
    Ok(())
}

/// ∫ f over the unit sphere by the midpoint rule in (z, φ), `nt` × `np`
/// cells (uniform in z = cos θ: equal areas): the fitters' tests'
/// independent check of their L1 estimates.
#[cfg(test)]
pub(crate) fn sphere_midpoint(nt: usize, np: usize, f: impl Fn(V3<f64>) -> f64) -> f64 {
    let mut q = 0.0;
    for a in 0..nt {
        let z = -1.0 + 2.0 * (a as f64 + 0.5) / nt as f64;
        let r = (1.0 - z * z).sqrt();
        for b in 0..np {
            let phi = 2.0 * PI * (b as f64 + 0.5) / np as f64;
            q += f(V3::new(r * phi.cos(), r * phi.sin(), z));
        }
    }
    q * (4.0 * PI / (nt * np) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use specula_core::ltc::ggx::table;

    /// M's (a, b, c, d) from a stored node (c M⁻¹ with m11 = 1; M is
    /// proportional to its inverse, normalized to M₂₂ = 1).
    fn stored(i: usize, j: usize) -> ([f64; 4], [f32; 6]) {
        let m = table().node_value(i, j);
        let (m00, m02, m20, m22) = (m[0] as f64, m[1] as f64, m[2] as f64, m[3] as f64);
        let det = m00 * m22 - m02 * m20;
        let (a, b, d, e) = (m22 / det, -m02 / det, -m20 / det, m00 / det);
        ([a / e, b / e, 1.0 / e, d / e], m)
    }

    #[test]
    fn refitting_cells_from_their_stored_neighbours_matches_the_committed_table() {
        let pts = points();
        // (i = roughness node, j = view node): smooth, rough, grazing.
        for (i, j) in [(10, 5), (40, 30), (62, 50), (25, 60)] {
            // The fit of (i, j) warm-starts from (i + 1, j) (the rougher
            // neighbour); the α = 1 row is not refitted here.
            let (start, _) = stored(i + 1, j);
            let (alpha, mu) = node(i, j);
            let (cell, err) = fit_cell(alpha, mu, start, &pts);
            let got = cell.channels();
            let (m, want) = stored(i, j);
            let lobe = Lobe::new(alpha, mu);
            let stored_err = l1_error(&lobe, m, &pts);
            eprintln!("cell ({i}, {j}): refit L1 {err:.5}, stored L1 {stored_err:.5}");
            // The cost at the stored M (rounded to f32) and at the refit.
            assert!(
                (err - stored_err).abs() < 1e-3 * stored_err.max(0.01),
                "({i}, {j}): {err} vs {stored_err}"
            );
            for c in 0..6 {
                // Channels 4 and 5 are n and n_w, from the albedo
                // quadrature: as close as its absolute tolerance (1e-5).
                let tol = if c < 4 { 2e-3 } else { 1e-5 };
                assert!(
                    (got[c] - want[c]).abs() <= tol * want[c].abs().max(1.0),
                    "({i}, {j}) channel {c}: refit {} vs stored {}",
                    got[c],
                    want[c]
                );
            }
        }
    }

    #[test]
    fn the_l1_estimate_matches_quadrature() {
        // An independent check of the MIS estimate: ∫ |D − p| by a plain
        // midpoint rule in (cos θ, φ) on a fine grid, for a rough lobe.
        let lobe = Lobe::new(0.6, 0.7);
        let m = [0.9, -0.3, 0.8, 0.05];
        let est = l1_error(&lobe, m, &points());
        let q = sphere_midpoint(800, 800, |w| {
            let p = if w.z > 0.0 { lobe.p(w) } else { 0.0 };
            (ltc_density(m, w) - p).abs()
        });
        assert!((est - q).abs() < 0.01 * q, "MIS {est} vs quadrature {q}");
    }
}
