//! The benchmark scene at 1920×1080 with 1 and 2 threads:
//! - `visibility/raster`: vertex through visibility buffer;
//! - `visibility/embree_packet8`, `visibility/embree_single`: the same
//!   frame's primary rays through Embree 3 (same ids; checked by
//!   tests/embree_crosscheck.rs), 8-ray packets and single rays;
//! - `shade/<model>/simd`, `shade/<model>/scalar`: resolve + shading of the
//!   same visibility buffer, 8 pixels per packet vs one pixel at a time, for
//!   metallic_roughness (the scene's own) and microfacet (GGX + conductor);
//! - `post/fused`, `post/stages`: the standard post list (resolve, exposure,
//!   tone map, sRGB encode) in one fused pass vs stage by stage;
//! - `frame/full`: the whole frame, tone mapping and PNG encode included,
//!   as the CLI renders a PNG (the 8-bit encode inside the shading pass).
//!
//! Throughput is reported in pixels. Run: `cargo bench -p specula-bench`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use specula::render::{render_scene, RenderSettings};
use specula_bench::embree::EmbreeScene;
use specula_bench::{benchmark_scene, benchmark_scene_microfacet, pool};
use specula_raster::frame::{
    render, shade_into, visibility, visibility_into, FrameStats, ShadePath,
};
use specula_raster::post::Post;
use specula_raster::{BufferSet, FrameBuffers};

fn benches(c: &mut Criterion) {
    let scene = benchmark_scene();
    let settings = RenderSettings::from_scene(&scene);
    let target = settings.target().expect("benchmark target");
    let pixels = target.pixel_count() as u64;

    let mut g = c.benchmark_group("visibility");
    g.throughput(Throughput::Elements(pixels));
    g.sample_size(20);
    let cam = &scene.data.camera;
    for threads in [1, 2] {
        let p = pool(threads);
        // Steady state: the buffers of the previous frame are reused.
        let mut vis = p.install(|| visibility(&scene.data, &target, &mut FrameStats::default()));
        g.bench_function(BenchmarkId::new("raster", threads), |b| {
            b.iter(|| {
                p.install(|| {
                    visibility_into(&scene.data, &target, &mut vis, &mut FrameStats::default())
                })
            })
        });
        // Embree's BVH build uses as many threads as the benchmark.
        let embree = EmbreeScene::new(&scene.data, threads).expect("Embree scene");
        g.bench_function(BenchmarkId::new("embree_packet8", threads), |b| {
            b.iter(|| p.install(|| embree.trace_packet8(&vis.view, cam.near, cam.far)))
        });
        g.bench_function(BenchmarkId::new("embree_single", threads), |b| {
            b.iter(|| p.install(|| embree.trace_single(&vis.view, cam.near, cam.far)))
        });
    }
    g.finish();

    let mut g = c.benchmark_group("shade");
    g.throughput(Throughput::Elements(pixels));
    g.sample_size(10);
    let microfacet = benchmark_scene_microfacet();
    for threads in [1, 2] {
        let p = pool(threads);
        let vis = p.install(|| visibility(&scene.data, &target, &mut FrameStats::default()));
        // Steady state: the frame buffers are reused.
        let mut color = FrameBuffers::new(&target, BufferSet::default());
        for (model, sc) in [("metallic_roughness", &scene), ("microfacet", &microfacet)] {
            for (name, path) in [("simd", ShadePath::Simd), ("scalar", ShadePath::Scalar)] {
                let id = BenchmarkId::new(format!("{model}/{name}"), threads);
                g.bench_function(id, |b| {
                    b.iter(|| {
                        let mut st = FrameStats::default();
                        p.install(|| shade_into(&sc.data, &target, &vis, path, &mut color, &mut st))
                    })
                });
            }
        }
    }
    g.finish();

    let mut g = c.benchmark_group("post");
    g.throughput(Throughput::Elements(pixels));
    g.sample_size(20);
    let p = pool(2);
    let frame = p.install(|| render(&scene.data, target, ShadePath::Simd));
    let fused = settings.post();
    let staged = Post {
        fuse: false,
        ..fused.clone()
    };
    for (name, mut post) in [("fused", fused), ("stages", staged)] {
        g.bench_function(BenchmarkId::new(name, 2), |b| {
            b.iter(|| p.install(|| post.run(&frame.buffers).expect("post")))
        });
    }
    g.finish();

    let mut g = c.benchmark_group("frame");
    g.throughput(Throughput::Elements(pixels));
    g.sample_size(10);
    for threads in [1, 2] {
        // As the CLI renders a PNG: no HDR output, so the 8-bit encode
        // runs inside the shading pass.
        let s = RenderSettings {
            threads: Some(threads),
            keep_hdr: false,
            ..settings.clone()
        };
        g.bench_function(BenchmarkId::new("full", threads), |b| {
            b.iter(|| {
                let r = render_scene(&scene, &s, 0.0).expect("render");
                let mut png = Vec::new();
                image::ImageEncoder::write_image(
                    image::codecs::png::PngEncoder::new(&mut png),
                    &r.ldr,
                    r.width,
                    r.height,
                    image::ExtendedColorType::Rgb8,
                )
                .expect("png");
                png.len()
            })
        });
    }
    g.finish();
}

criterion_group!(frame, benches);
criterion_main!(frame);
