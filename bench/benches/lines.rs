//! NPR line passes on the benchmark frame (fixtures/scenes/sphere-grid.toml,
//! 1920×1080, 194k triangles), each next to what it adds to:
//! - `lines/visibility/{plain,extrusion}`: the geometry passes without and
//!   with the extrusion outline pass (back faces pushed 2 px), steady
//!   frames (buffers reused);
//! - `lines/sobel`: the Sobel outline stage (depth, normal, id; edge
//!   detection, distance-transform dilation, blend) on the frame buffers;
//! - `lines/strokes`: the stroke overlay stage of a steady frame
//!   (silhouette + crease + boundary edges of the view, found once per
//!   scene; per frame their visibility against the depth buffer, chaining,
//!   tiny-skia stroking, and the outlines filled in bands of rows, each on
//!   a mask of its own, in parallel, and blended);
//!   `lines/strokes_one_mask` the same lines drawn the plain way (one
//!   fresh mask of the whole image, a coverage image);
//!   `lines/strokes_topology` the once-per-scene edge table.
//!
//! - `lines/frame`: the benchmark frame itself, steady (buffers reused, the
//!   8-bit encode inside the shading pass, no PNG compression), as
//!   `--stats --repeat` and the llvmpipe ratio time it.
//!
//! The aim is each pass at most 15 % of the benchmark frame's time.
//! Run: `cargo bench -p specula-bench --bench lines`. The calls are
//! `specula_bench::lines`'. Criterion times one benchmark after the other,
//! and the project's machines run in phases whose speeds differ by up to
//! ~35 %, so a pass over the frame from two benchmarks can be off by that
//! much: the `line_shares` example times the same calls in alternation and
//! takes the share per round (docs/PERFORMANCE.md).

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use specula_bench::lines::{LinePasses, STROKE_KINDS};
use specula_bench::pool;
use specula_npr::edges::MeshEdges;
use specula_npr::overlay::draw;

fn benches(c: &mut Criterion) {
    let p = pool(2);
    let lp = p.install(LinePasses::new);

    let mut g = c.benchmark_group("lines");
    g.sample_size(10);
    // The steady frame, as `--stats --repeat` and the llvmpipe ratio time
    // it: the previous frame's buffers reused and the 8-bit encode inside
    // the shading pass (a PNG output). A first frame also pays the
    // buffers' page faults and the thread pool's start, and read about
    // twice as long: no fair measure to take fractions of.
    let mut steady = p.install(|| lp.first_frame());
    g.bench_function("frame", |b| {
        b.iter(|| p.install(|| lp.frame_again(&mut steady)))
    });
    // Steady frames, as `--stats` and the llvmpipe ratio run them: the
    // visibility buffers (and the extrusion stage's per-view vectors) of
    // the previous iteration are reused.
    for (name, data) in [("plain", &lp.plain), ("extrusion", &lp.outlined)] {
        let mut vis = p.install(|| lp.first_visibility(data));
        g.bench_function(format!("visibility/{name}"), |b| {
            b.iter(|| p.install(|| lp.visibility_again(data, &mut vis)))
        });
    }

    // The image is copied outside the timed part (a 25 MB clone per
    // iteration is not the stage's work).
    let mut sobel = lp.sobel.clone();
    g.bench_function("sobel", |b| {
        b.iter_batched_ref(
            || lp.image.clone(),
            |im| p.install(|| lp.run_sobel(&mut sobel, im)),
            BatchSize::LargeInput,
        )
    });

    g.bench_function("strokes_topology", |b| {
        b.iter(|| MeshEdges::from_scene(&lp.plain, &STROKE_KINDS, 60.0))
    });
    // The stage as a frame runs it: one image kept across iterations (the
    // strokes blend over it again; the cost does not depend on its values)
    // and the stage's canvases kept, as from frame to frame.
    let mut im = lp.image.clone();
    let mut strokes = lp.strokes.clone();
    g.bench_function("strokes", |b| {
        b.iter(|| p.install(|| lp.run_strokes(&mut strokes, &mut im)))
    });
    // The same polylines drawn on one fresh mask of the whole image, on
    // one thread, turned into a coverage image: what the bands save.
    g.bench_function("strokes_one_mask", |b| {
        b.iter(|| {
            p.install(|| {
                let lines = lp.strokes.polylines(&lp.frame.buffers, 1);
                draw(&lines, &lp.strokes.style, 1920, 1080)
            })
        })
    });
    g.finish();
}

criterion_group!(lines, benches);
criterion_main!(lines);
