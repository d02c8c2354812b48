//! The two in-process ratios on the benchmark frame, timed in
//! alternation (`specula_bench::paired`) so that the host's phases move
//! both sides of each ratio alike (the `frame` criterion bench times the
//! same calls one benchmark after the other):
//! - visibility: Embree 3's 8-ray packets over our geometry passes
//!   (`visibility/embree_packet8` / `visibility/raster`);
//! - shading: the scalar twin over the f32x8 path
//!   (`shade/metallic_roughness/scalar` / `.../simd`), on one visibility
//!   buffer, into reused frame buffers; and over the SIMD path as a
//!   frame runs it, which where the processor has AVX-512 shades the
//!   lights two per register (`ShadePath::Simd`; the same pixels).
//!
//! Per thread count, each round times the five calls (each the median of
//! `K`); printed are the median times and the median per-round ratios with
//! their quartiles.
//!
//! ```text
//! cargo run --release -p specula-bench --example aims -- [ROUNDS] [K]
//! ```
//! Defaults: 30 rounds, K = 1 (a round then takes ~0.3 s at 2 threads).

use specula_bench::embree::EmbreeScene;
use specula_bench::paired::{arg, quartiles, ratios, rounds};
use specula_bench::{benchmark_scene, pool};
use specula_raster::frame::{shade_into, visibility, visibility_into, FrameStats, ShadePath};
use specula_raster::{BufferSet, FrameBuffers};

fn main() {
    let usage = "usage: aims [ROUNDS] [K]";
    let n_rounds = arg(1, 30, usage).max(1);
    let k = arg(2, 1, usage);
    let scene = benchmark_scene();
    let data = &scene.data;
    let target = specula::render::RenderSettings::from_scene(&scene)
        .target()
        .expect("benchmark target");
    let (near, far) = (data.camera.near, data.camera.far);
    for threads in [1, 2] {
        let p = pool(threads);
        let mut vis = p.install(|| visibility(data, &target, &mut FrameStats::default()));
        // Our own visibility buffer for the shading calls, so that the
        // raster calls do not write the one being shaded.
        let shaded = p.install(|| visibility(data, &target, &mut FrameStats::default()));
        let embree = EmbreeScene::new(data, threads).expect("Embree scene");
        let mut color = FrameBuffers::new(&target, BufferSet::default());
        let mut color_scalar = FrameBuffers::new(&target, BufferSet::default());
        let mut color_pairs = FrameBuffers::new(&target, BufferSet::default());
        let shade = |path: ShadePath, out: &mut FrameBuffers| {
            let mut st = FrameStats::default();
            p.install(|| shade_into(data, &target, &shaded, path, out, &mut st));
        };
        let view = vis.view.clone();
        let t = rounds(
            n_rounds,
            k,
            &mut [
                &mut || {
                    p.install(|| {
                        visibility_into(data, &target, &mut vis, &mut FrameStats::default())
                    })
                },
                &mut || {
                    p.install(|| embree.trace_packet8(&view, near, far));
                },
                &mut || shade(ShadePath::SimdAvx2, &mut color),
                &mut || shade(ShadePath::Scalar, &mut color_scalar),
                &mut || shade(ShadePath::Simd, &mut color_pairs),
            ],
        );
        println!(
            "{threads} thread(s), {n_rounds} rounds, the median of {k} call(s) an item a round"
        );
        let names = [
            "raster",
            "embree_packet8",
            "shade f32x8",
            "shade scalar",
            "shade simd",
        ];
        for (name, v) in names.iter().zip(&t) {
            let (lo, mid, hi) = quartiles(v);
            println!("{name:>27}: {mid:8.2} ms  (quartiles {lo:.2}, {hi:.2})");
        }
        let pairs = specula_raster::frame::shades_packet_pairs(data);
        let simd = if pairs {
            "scalar / SIMD (packet pairs)"
        } else {
            "scalar / SIMD"
        };
        for (name, num, den) in [
            ("Embree / raster", 1, 0),
            ("scalar / f32x8", 3, 2),
            (simd, 3, 4),
        ] {
            let (lo, mid, hi) = quartiles(&ratios(&t[num], &t[den]));
            println!("{name:>27}: {mid:6.2}×  (quartiles {lo:.2}, {hi:.2})");
        }
    }
}
