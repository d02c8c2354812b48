//! NPR shading cost: the shading pass (resolve + shade) of
//! fixtures/scenes/npr-tones.toml at 1920×1080 with every material
//! replaced by one model — `metallic_roughness` (the reference),
//! `toon` (3 bands, a hard highlight) and `hatching` (the built-in tonal
//! art map, two trilinear tone lookups per pixel) — 8 pixels per packet
//! (`simd`) vs one at a time (`scalar`), on 1 and 2 threads.
//!
//! Throughput is reported in pixels. Run: `cargo bench -p specula-bench --bench npr`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use specula::render::RenderSettings;
use specula::scene::{load_scene, LoadedScene};
use specula_bench::{fixtures, pool};
use specula_core::models::MetallicRoughness;
use specula_core::Model;
use specula_npr::hatching::{builtin_tam, Hatching};
use specula_npr::toon::{Hard, Ramp, Toon};
use specula_raster::frame::{shade_into, visibility, FrameStats, ShadePath};
use specula_raster::{BufferSet, FrameBuffers, Lit, Material};

/// The scene with every material replaced by `make()`.
fn with_all(scene: &LoadedScene, make: &dyn Fn(&str) -> Material) -> LoadedScene {
    let path = fixtures().join("scenes/npr-tones.toml");
    let mut s = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    let mut parts = s.data.into_parts();
    parts.materials = scene.data.materials.iter().map(|m| make(&m.name)).collect();
    s.data = specula_raster::SceneData::new(parts).expect("the same scene, other materials");
    s
}

fn benches(c: &mut Criterion) {
    let path = fixtures().join("scenes/npr-tones.toml");
    let scene = load_scene(&path).unwrap_or_else(|e| panic!("npr-tones: {e}"));
    let target = RenderSettings::from_scene(&scene)
        .target()
        .expect("1920×1080 target");
    let pixels = target.pixel_count() as u64;
    let mr = with_all(&scene, &|n| {
        let model = Model::MetallicRoughness(MetallicRoughness {
            base_color: [0.8, 0.5, 0.3],
            roughness: 0.4,
            metallic: 0.0,
        });
        Material::new(n, Lit::new(model), false)
    });
    let toon = with_all(&scene, &|n| {
        let shader = Toon {
            base_color: [0.8, 0.5, 0.3],
            maps: Default::default(),
            ramp: Ramp::bands(3).expect("3 bands"),
            specular: Some(Hard {
                threshold: 0.98,
                color: [1.0; 3],
            }),
            rim: None,
        };
        Material::new(n, shader, false)
    });
    let tam = builtin_tam().expect("built-in TAM");
    let hatching = with_all(&scene, &|n| {
        let shader = Hatching {
            tam: tam.clone(),
            ink: [0.02; 3],
            paper: [1.0; 3],
            scale: 4.0,
        };
        Material::new(n, shader, false)
    });

    let mut g = c.benchmark_group("npr_shade");
    g.throughput(Throughput::Elements(pixels));
    g.sample_size(10);
    for threads in [1, 2] {
        let p = pool(threads);
        let vis = p.install(|| visibility(&scene.data, &target, &mut FrameStats::default()));
        let mut color = FrameBuffers::new(&target, BufferSet::default());
        for (model, sc) in [
            ("metallic_roughness", &mr),
            ("toon", &toon),
            ("hatching", &hatching),
        ] {
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
}

criterion_group!(npr, benches);
criterion_main!(npr);
