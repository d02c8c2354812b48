//! The shading pass of the benchmark frame (sphere-grid, 1920×1080, SIMD,
//! 2 threads) under polygon lights, against its own 4 point lights:
//! - `area_lights/point/4`: the scene as it is (4 point lights);
//! - `area_lights/quad/N`, N = 1, 4, 16: the point lights replaced by N
//!   quads at the same height (a 1 × 1 quad over the grid's centre; the 4
//!   point lights' positions; a 4 × 4 grid), integrated by LTC.
//!
//! The aim: 4 quads cost at most 3× 4 point lights (read
//! `quad/4` over `point/4` from one run). Run:
//! `cargo bench -p specula-bench --bench area_lights`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use specula::render::RenderSettings;
use specula_bench::{benchmark_scene, pool};
use specula_core::light::{AreaMethod, Light};
use specula_raster::frame::{shade_into, visibility, FrameStats, ShadePath};
use specula_raster::{BufferSet, FrameBuffers};

/// A square of side `s` centred at (x, y, z), facing −z (counter-clockwise
/// seen from below).
fn quad(x: f32, y: f32, z: f32, s: f32, radiance: f32) -> Light {
    let h = s / 2.0;
    Light::Polygon {
        vertices: vec![
            [x - h, y - h, z],
            [x - h, y + h, z],
            [x + h, y + h, z],
            [x + h, y - h, z],
        ],
        radiance: [radiance; 3],
        two_sided: false,
        method: AreaMethod::Ltc,
    }
}

fn benches(c: &mut Criterion) {
    let scene = benchmark_scene();
    let settings = RenderSettings::from_scene(&scene);
    let target = settings.target().expect("benchmark target");
    let mut g = c.benchmark_group("area_lights");
    g.throughput(Throughput::Elements(target.pixel_count() as u64));
    g.sample_size(10);
    let p = pool(2);
    let vis = p.install(|| visibility(&scene.data, &target, &mut FrameStats::default()));
    let mut color = FrameBuffers::new(&target, BufferSet::default());
    let with = |lights: Vec<Light>| {
        let mut d = scene.data.clone().into_parts();
        d.lights = lights;
        specula_raster::SceneData::new(d).expect("the lit materials take polygon lights")
    };
    let grid16 = (0..16)
        .map(|k| {
            quad(
                -3.0 + 2.0 * (k % 4) as f32,
                -3.0 + 2.0 * (k / 4) as f32,
                5.0,
                0.5,
                15.0,
            )
        })
        .collect();
    let cases = [
        ("point", 4, scene.data.clone()),
        ("quad", 1, with(vec![quad(0.0, 0.0, 5.0, 1.0, 40.0)])),
        (
            "quad",
            4,
            with(
                [(-4.0, -4.0), (4.0, -4.0), (-4.0, 4.0), (4.0, 4.0)]
                    .iter()
                    .map(|&(x, y)| quad(x, y, 5.0, 1.0, 20.0))
                    .collect(),
            ),
        ),
        ("quad", 16, with(grid16)),
    ];
    for (kind, n, data) in &cases {
        g.bench_function(BenchmarkId::new(*kind, n), |b| {
            b.iter(|| {
                let mut st = FrameStats::default();
                p.install(|| shade_into(data, &target, &vis, ShadePath::Simd, &mut color, &mut st))
            })
        });
    }
    g.finish();
}

criterion_group!(area_lights, benches);
criterion_main!(area_lights);
