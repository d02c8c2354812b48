//! Shared setup for specula's criterion benchmarks: the benchmark scene
//! (fixtures/scenes/sphere-grid.toml, 1920×1080) and explicit thread pools.

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

/// A rayon pool of exactly `n` threads.
pub fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .expect("thread pool")
}

pub mod embree;
