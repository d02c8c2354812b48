//! Shared setup for specula's criterion benchmarks and measuring examples:
//! the benchmark scene (fixtures/scenes/sphere-grid.toml, 1920×1080) and
//! its variants, explicit thread pools, Embree's visibility (`embree`), the
//! NPR line passes on the benchmark frame (`lines`), and timing in
//! alternation for ratios on a noisy host (`paired`).

use specula::scene::{load_scene, LoadedScene};
use std::path::PathBuf;

/// The repository's fixtures folder.
pub fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fixtures")
}

/// The benchmark scene every performance figure uses.
pub fn benchmark_scene() -> LoadedScene {
    let path = fixtures().join("scenes/sphere-grid.toml");
    load_scene(&path).unwrap_or_else(|e| panic!("benchmark scene: {e}"))
}

/// The benchmark scene with every sphere's metallic-roughness material
/// replaced by the microfacet model (GGX, height-correlated Smith, exact
/// conductor Fresnel with gold's η and κ, roughness mapped α = r²): the
/// same frame and lights, a heavier BRDF.
pub fn benchmark_scene_microfacet() -> LoadedScene {
    use specula_core::models::{Fresnel, Microfacet, MicrofacetParams, Ndf, Smith};
    use specula_core::Model;
    use specula_raster::Lit;
    let mut s = benchmark_scene();
    let mut parts = s.data.into_parts();
    for m in &mut parts.materials {
        let Some(lit) = m.shader.as_any().downcast_ref::<Lit>() else {
            continue;
        };
        if let Model::MetallicRoughness(mr) = lit.model() {
            let params = MicrofacetParams {
                ndf: Ndf::Ggx,
                alpha: mr.alpha(),
                smith: Smith::HeightCorrelated,
                fresnel: Fresnel::Conductor {
                    eta: [0.18, 0.42, 1.37],
                    k: [3.42, 2.35, 1.77],
                },
                diffuse: mr.diffuse_color(),
                gtr_lambda: Default::default(),
            };
            let model = Model::Microfacet(Microfacet::new(params, None));
            *m = specula_raster::Material::new(&m.name, Lit::new(model), m.double_sided);
        }
    }
    s.data = specula_raster::SceneData::new(parts).expect("the same scene, other materials");
    s
}

/// The benchmark scene with every sphere's metallic-roughness material
/// replaced by the Disney model with every lobe on: the same base colour,
/// roughness and metallic, plus subsurface 0.3, anisotropic 0.5, sheen 0.5,
/// clearcoat 0.5 (so no lobe is skipped by a zero weight; the kernels
/// evaluate every lobe anyway).
pub fn benchmark_scene_disney() -> LoadedScene {
    use specula_core::models::{Disney, DisneyParams};
    use specula_core::Model;
    use specula_raster::Lit;
    let mut s = benchmark_scene();
    let mut parts = s.data.into_parts();
    for m in &mut parts.materials {
        let Some(lit) = m.shader.as_any().downcast_ref::<Lit>() else {
            continue;
        };
        if let Model::MetallicRoughness(mr) = lit.model() {
            let params = DisneyParams {
                base_color: mr.base_color,
                roughness: mr.roughness,
                metallic: mr.metallic,
                subsurface: 0.3,
                anisotropic: 0.5,
                sheen: 0.5,
                clearcoat: 0.5,
                ..DisneyParams::default()
            };
            let model = Model::Disney(Disney::new(params, false));
            *m = specula_raster::Material::new(&m.name, Lit::new(model), m.double_sided);
        }
    }
    s.data = specula_raster::SceneData::new(parts).expect("the same scene, other materials");
    s
}

/// A rayon pool of exactly `n` threads.
pub fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .expect("thread pool")
}

pub mod embree;
pub mod lines;
pub mod paired;
