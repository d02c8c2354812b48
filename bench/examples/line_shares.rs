//! Each NPR line pass's share of the benchmark frame's time, with the
//! frame and the passes timed in alternation (`specula_bench::paired`), so
//! that the host's phases move both sides of each ratio alike. The `lines`
//! criterion bench times the same work (`specula_bench::lines`), one
//! benchmark after the other.
//!
//! Each round times the steady frame, the geometry passes without and with
//! the extrusion outline, the Sobel stage and the stroke stage (each the
//! median of `K` calls). A pass's share in a round is its time over the
//! frame's (the extrusion pass: extrusion minus plain). Printed: the median
//! time of each item, and the median share over the rounds with its
//! quartiles.
//!
//! ```text
//! cargo run --release -p specula-bench --example line_shares -- [ROUNDS] [THREADS] [K]
//! ```
//! Defaults: 200 rounds, 2 threads, K = 1 (a round then takes ~50 ms).

use specula_bench::lines::LinePasses;
use specula_bench::paired::{arg, quartiles, ratios, rounds};
use specula_bench::pool;

fn main() {
    let usage = "usage: line_shares [ROUNDS] [THREADS] [K]";
    let n_rounds = arg(1, 200, usage).max(1);
    let threads = arg(2, 2, usage).max(1);
    let k = arg(3, 1, usage);
    let p = pool(threads);
    let lp = p.install(LinePasses::new);
    let mut steady = p.install(|| lp.first_frame());
    let mut vis_plain = p.install(|| lp.first_visibility(&lp.plain));
    let mut vis_outlined = p.install(|| lp.first_visibility(&lp.outlined));
    let mut sobel_img = lp.image.clone();
    let mut strokes_img = lp.image.clone();
    let (mut sobel, mut strokes) = (lp.sobel.clone(), lp.strokes.clone());

    let names = ["frame", "vis plain", "vis extrusion", "sobel", "strokes"];
    let t = rounds(
        n_rounds,
        k,
        &mut [
            &mut || p.install(|| lp.frame_again(&mut steady)),
            &mut || p.install(|| lp.visibility_again(&lp.plain, &mut vis_plain)),
            &mut || p.install(|| lp.visibility_again(&lp.outlined, &mut vis_outlined)),
            // Both stages draw over their image again each call: their
            // cost does not depend on its values (neither reads colour).
            &mut || p.install(|| lp.run_sobel(&mut sobel, &mut sobel_img)),
            &mut || p.install(|| lp.run_strokes(&mut strokes, &mut strokes_img)),
        ],
    );

    println!("{n_rounds} rounds, {threads} thread(s), the median of {k} call(s) an item a round");
    for (name, v) in names.iter().zip(&t) {
        let (lo, mid, hi) = quartiles(v);
        println!("{name:>14}: {mid:7.2} ms  (quartiles {lo:.2}, {hi:.2})");
    }
    let extrusion: Vec<f64> = t[2].iter().zip(&t[1]).map(|(e, p)| e - p).collect();
    println!("share of the frame, per round (the aim: each at most 15 %):");
    for (name, pass) in [
        ("extrusion", &extrusion),
        ("sobel", &t[3]),
        ("strokes", &t[4]),
    ] {
        let shares: Vec<f64> = ratios(pass, &t[0]).iter().map(|r| 100.0 * r).collect();
        let (lo, mid, hi) = quartiles(&shares);
        let over = shares.iter().filter(|&&s| s > 15.0).count();
        println!(
            "{name:>14}: {mid:5.1} %  (quartiles {lo:.1}, {hi:.1}; over 15 % in {over} of {n_rounds} rounds)"
        );
    }
}
