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
//!   tiny-skia stroking and filling, each draw once on its own mask by
//!   parallel workers, and the coverage composed and blended row by row);
//!   `lines/strokes_one_pixmap` the same lines drawn the plain way (one
//!   fresh pixmap, a coverage image); `lines/strokes_topology` the
//!   once-per-scene edge table.
//!
//! - `lines/frame`: the benchmark frame itself, steady (buffers reused, the
//!   8-bit encode inside the shading pass, no PNG compression), as
//!   `--stats --repeat` and the llvmpipe ratio time it, in the same run,
//!   so each pass reads as a fraction of it.
//!
//! The aim is each pass at most 15 % of the benchmark frame's time.
//! Run: `cargo bench -p specula-bench --bench lines`. Wall times on the
//! shared machines move by ±10 % between runs; docs/PERFORMANCE.md gives
//! the same fractions as callgrind instruction counts, which do not.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use specula::render::RenderSettings;
use specula_bench::{benchmark_scene, pool};
use specula_npr::edges::{EdgeKind, MeshEdges};
use specula_npr::extrude::{extrusion_passes, Extrude};
use specula_npr::outline::id_materials;
use specula_npr::outline::Selection;
use specula_npr::overlay::{draw, LineCap, LineJoin, StrokeStyle, Strokes};
use specula_npr::sobel::{Sobel, Source};
use specula_raster::frame::{
    render_ldr, render_ldr_into, render_with, visibility, visibility_into, FrameStats, ShadePath,
};
use specula_raster::post::{HdrImage, PostStage};
use specula_raster::{BufferSet, Material, Target, Unlit};
use std::sync::Arc;

fn benches(c: &mut Criterion) {
    let scene = benchmark_scene();
    let plain = scene.data.clone();
    let mut outlined = scene.data.clone();
    let m = outlined.materials.len() as u32;
    outlined.materials.push(Material::new(
        "outline",
        Unlit {
            color: [0.0; 3],
            intensity: 1.0,
        },
        true,
    ));
    let stage = Arc::new(Extrude::new(&outlined, 2.0));
    let base = outlined.triangles.len() as u32;
    let passes = extrusion_passes(&outlined, stage, m, base, &|_| true);
    outlined.geometry.extend(passes);
    outlined.validate().expect("outlined scene");
    let target = Target::new(1920, 1080).expect("1080p");
    let p = pool(2);

    let mut g = c.benchmark_group("lines");
    g.sample_size(10);
    // The steady frame, as `--stats --repeat` and the llvmpipe ratio time
    // it: the previous frame's buffers reused and the 8-bit encode inside
    // the shading pass (a PNG output). A first frame (`render_scene` once)
    // also pays the buffers' page faults and the thread pool's start, and
    // read about twice as long: no fair measure to take fractions of.
    let settings = RenderSettings {
        threads: Some(2),
        keep_hdr: false,
        ..RenderSettings::from_scene(&scene)
    };
    let enc = settings
        .ldr_in_shading()
        .expect("a PNG output encodes inside the shading pass");
    let set = settings.buffers.union(settings.post().buffers());
    let mut ldr = Vec::new();
    let mut steady = p.install(|| render_ldr(&plain, target, ShadePath::Simd, set, enc, &mut ldr));
    g.bench_function("frame", |b| {
        b.iter(|| {
            p.install(|| render_ldr_into(&plain, &mut steady, ShadePath::Simd, enc, &mut ldr))
        })
    });
    // Steady frames, as `--stats` and the llvmpipe ratio run them: the
    // visibility buffers (and the extrusion stage's per-view vectors) of
    // the previous iteration are reused.
    for (name, data) in [("plain", &plain), ("extrusion", &outlined)] {
        let mut vis = p.install(|| visibility(data, &target, &mut FrameStats::default()));
        g.bench_function(format!("visibility/{name}"), |b| {
            b.iter(|| {
                p.install(|| visibility_into(data, &target, &mut vis, &mut FrameStats::default()))
            })
        });
    }

    let set = BufferSet {
        depth: true,
        normal: true,
        id: true,
    };
    let frame = p.install(|| render_with(&plain, target, ShadePath::Simd, set));
    let img = HdrImage {
        width: 1920,
        height: 1080,
        rgb: frame.buffers.color.clone(),
    };
    let sobel = Sobel {
        sources: vec![
            (Source::Depth, 0.1),
            (Source::Normal, 0.4),
            (Source::Id, 0.3),
        ],
        width: 2.0,
        color: [0.0; 3],
        antialias: true,
        id_material: id_materials(&plain),
        selection: Selection::all(),
        scratch: Default::default(),
    };
    // The image is copied outside the timed part (a 25 MB clone per
    // iteration is not the stage's work).
    g.bench_function("sobel", |b| {
        b.iter_batched_ref(
            || img.clone(),
            |im| p.install(|| sobel.apply(im, &frame.buffers)),
            BatchSize::LargeInput,
        )
    });

    let kinds = [EdgeKind::Silhouette, EdgeKind::Crease, EdgeKind::Boundary];
    g.bench_function("strokes_topology", |b| {
        b.iter(|| MeshEdges::from_scene(&plain, &kinds, 60.0))
    });
    let strokes = Strokes::new(
        MeshEdges::from_scene(&plain, &kinds, 60.0),
        plain.camera.clone(),
        StrokeStyle {
            width: 1.5,
            color: [0.0; 3],
            taper: 0.0,
            join: LineJoin::Round,
            cap: LineCap::Round,
        },
    );
    // The stage as a frame runs it: one image kept across iterations (the
    // strokes blend over it again; the cost does not depend on its values)
    // and the stage's canvases kept, as from frame to frame.
    let mut im = img.clone();
    g.bench_function("strokes", |b| {
        b.iter(|| p.install(|| strokes.apply(&mut im, &frame.buffers)))
    });
    // Before the banded drawing: the same polylines drawn on one fresh
    // pixmap, turned into a coverage image (what `lines/strokes` measured
    // until 2026-12-01's second session).
    g.bench_function("strokes_one_pixmap", |b| {
        b.iter(|| {
            p.install(|| {
                let lines = strokes.polylines(&frame.buffers, 1);
                draw(&lines, &strokes.style, 1920, 1080)
            })
        })
    });
    g.finish();
}

criterion_group!(lines, benches);
criterion_main!(lines);
