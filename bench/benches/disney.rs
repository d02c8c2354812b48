//! The shading pass of the benchmark scene (1920×1080) with every sphere
//! a Disney material (`specula_bench::benchmark_scene_disney`): resolve +
//! shading of the same visibility buffer, 8 pixels per packet (`simd`) vs
//! one pixel at a time (`scalar`), 1 and 2 threads. Compare with
//! `shade/metallic_roughness/*` of the `frame` bench for the cost of the
//! model. Run: `cargo bench -p specula-bench --bench disney`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use specula::render::RenderSettings;
use specula_bench::{benchmark_scene_disney, pool};
use specula_raster::frame::{shade_into, visibility, FrameStats, ShadePath};
use specula_raster::{BufferSet, FrameBuffers};

fn benches(c: &mut Criterion) {
    let scene = benchmark_scene_disney();
    let target = RenderSettings::from_scene(&scene)
        .target()
        .expect("benchmark target");
    let mut g = c.benchmark_group("shade");
    g.throughput(Throughput::Elements(target.pixel_count() as u64));
    g.sample_size(10);
    for threads in [1, 2] {
        let p = pool(threads);
        let vis = p.install(|| visibility(&scene.data, &target, &mut FrameStats::default()));
        // Steady state: the frame buffers are reused.
        let mut color = FrameBuffers::new(&target, BufferSet::default());
        for (name, path) in [("simd", ShadePath::Simd), ("scalar", ShadePath::Scalar)] {
            g.bench_function(BenchmarkId::new(format!("disney/{name}"), threads), |b| {
                b.iter(|| {
                    let mut st = FrameStats::default();
                    p.install(|| shade_into(&scene.data, &target, &vis, path, &mut color, &mut st))
                })
            });
        }
    }
    g.finish();
}

criterion_group!(disney, benches);
criterion_main!(disney);
