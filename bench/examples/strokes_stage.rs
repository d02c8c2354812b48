//! Wall time of the stroke overlay stage alone on a rendered frame, as a
//! frame after the first runs it (the stage's canvases kept), split into
//! its two halves: the polylines (visibility against the depth buffer and
//! chaining) and the drawing + blend. Prints the minimum and the median of
//! `N` calls per thread count; the minimum is the figure least moved by
//! other work on a shared machine.
//!
//! With `--cold` (anywhere in the arguments) a 64 MB buffer is written
//! before each call, as the frame's other passes do between two runs of
//! the stage: its buffers (canvases, image, depth) then come from memory,
//! as in a frame, instead of staying in the cache of a tight loop.
//!
//! ```text
//! cargo run --release -p specula-bench --example strokes_stage -- \
//!     fixtures/scenes/sphere-grid-strokes.toml 50 1 2 [--cold]
//! ```

use specula::render::{median, render_scene, RenderSettings};
use specula_npr::overlay::{Canvases, Strokes};
use specula_raster::post::{HdrImage, PostStage};
use std::time::Instant;

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let cold = args.iter().any(|a| a == "--cold");
    args.retain(|a| a != "--cold");
    let mut evict = vec![0u8; if cold { 64 << 20 } else { 0 }];
    let (Some(path), Some(n)) = (args.first(), args.get(1).and_then(|n| n.parse().ok())) else {
        eprintln!("usage: strokes_stage SCENE.toml N THREADS...");
        std::process::exit(2);
    };
    let n: usize = n;
    let scene =
        specula::scene::load_scene(std::path::Path::new(path)).unwrap_or_else(|e| panic!("{e}"));
    // The scene's stage as a run of frames uses it (canvases of its own).
    let mut stage = Strokes::clone(
        scene
            .lines
            .strokes
            .as_deref()
            .unwrap_or_else(|| panic!("{path} has no [strokes]")),
    );
    let r = render_scene(&scene, &RenderSettings::from_scene(&scene), 0.0).expect("render");
    let ssaa = r.ssaa as usize;
    let img = HdrImage {
        width: r.width,
        height: r.height,
        rgb: specula_raster::post::downsample(
            &r.frame.buffers.color,
            r.frame.buffers.width,
            r.frame.buffers.height,
            r.ssaa,
        )
        .rgb,
    };
    // What a frame draws: the stage's edges, the visible polylines and
    // their segments (one per visible piece of an edge).
    let lines = stage.polylines(&r.frame.buffers, ssaa);
    let segments: usize = lines
        .iter()
        .map(|l| l.points.len() - 1 + usize::from(l.closed))
        .sum();
    println!("{stage:?}: {} polylines, {segments} segments", lines.len());
    for t in args[2..]
        .iter()
        .map(|t| t.parse::<usize>().expect("threads"))
    {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .expect("pool");
        let mut im = img.clone();
        let mut canvases = Canvases::default();
        let (mut stage_ms, mut lines_ms, mut draw_ms) = (Vec::new(), Vec::new(), Vec::new());
        pool.install(|| {
            for k in 0..n + 1 {
                let mut flush = || {
                    evict.fill(k as u8);
                    std::hint::black_box(&evict);
                };
                flush();
                let t0 = Instant::now();
                stage.apply(&mut im, &r.frame.buffers);
                stage_ms.push(t0.elapsed().as_secs_f64() * 1e3);
                // The same two halves, timed apart.
                flush();
                let t1 = Instant::now();
                let lines = stage.polylines(&r.frame.buffers, ssaa);
                let t2 = Instant::now();
                canvases.blend(&lines, &stage.style, &mut im);
                let t3 = Instant::now();
                lines_ms.push((t2 - t1).as_secs_f64() * 1e3);
                draw_ms.push((t3 - t2).as_secs_f64() * 1e3);
            }
        });
        // The first call of each builds the canvases: not a steady frame.
        for v in [&mut stage_ms, &mut lines_ms, &mut draw_ms] {
            v.remove(0);
        }
        let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        println!(
            "{t} thread(s), {n} calls: stage min {:.2} ms, median {:.2}; polylines min {:.2}, median {:.2}; draw + blend min {:.2}, median {:.2}",
            min(&stage_ms),
            median(&stage_ms),
            min(&lines_ms),
            median(&lines_ms),
            min(&draw_ms),
            median(&draw_ms),
        );
    }
}
