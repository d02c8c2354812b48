//! Whole frames of the benchmark scene and the demo: the SIMD and scalar
//! shading paths agree, and the bytes do not depend on the thread count.

mod common;

use common::{fixtures, temp_dir};
use specula::render::{render_scene, RenderSettings};
use specula::scene::{load_scene, LoadedScene};
use specula::{demo, output};
use specula_raster::frame::ShadePath;

fn benchmark() -> LoadedScene {
    load_scene(&fixtures().join("scenes/sphere-grid.toml")).expect("benchmark scene")
}

/// Largest relative difference between the two paths' HDR pixels, with the
/// relative error measured against max(|a|, |b|, 1e-3) so pixels that are
/// nearly black are compared absolutely at that floor.
fn simd_vs_scalar(scene: &LoadedScene) -> (f64, usize) {
    let mut s = RenderSettings::from_scene(scene);
    s.ssaa = 1;
    let simd = render_scene(scene, &s, 0.0).expect("simd");
    s.path = ShadePath::Scalar;
    let scalar = render_scene(scene, &s, 0.0).expect("scalar");
    let (a, b) = (&simd.frame.color, &scalar.frame.color);
    let mut worst = 0.0f64;
    for (x, y) in
        a.r.iter()
            .chain(&a.g)
            .chain(&a.b)
            .zip(b.r.iter().chain(&b.g).chain(&b.b))
    {
        let (x, y) = (*x as f64, *y as f64);
        assert!(x.is_finite() && y.is_finite());
        worst = worst.max((x - y).abs() / x.abs().max(y.abs()).max(1e-3));
    }
    (worst, simd.stats.pixels_shaded as usize)
}

#[test]
fn simd_and_scalar_shading_agree_on_the_benchmark_scene() {
    let (worst, shaded) = simd_vs_scalar(&benchmark());
    assert_eq!(shaded, 1920 * 1080, "the ground covers every pixel");
    assert!(worst < 1e-5, "worst relative difference {worst:e}");
}

#[test]
fn simd_and_scalar_shading_agree_on_the_demo() {
    let (worst, shaded) = simd_vs_scalar(&demo::demo_scene().expect("demo"));
    assert!(shaded > 0);
    assert!(worst < 1e-5, "worst relative difference {worst:e}");
}

#[test]
fn benchmark_scene_bytes_do_not_depend_on_the_thread_count() {
    let scene = benchmark();
    let dir = temp_dir("determinism");
    let mut files = Vec::new();
    for threads in [1, 2, 8] {
        let mut s = RenderSettings::from_scene(&scene);
        s.threads = Some(threads);
        let r = render_scene(&scene, &s, 0.0).expect("render");
        let png = dir.join(format!("t{threads}.png"));
        let exr = dir.join(format!("t{threads}.exr"));
        output::write_png(&png, r.width, r.height, r.ldr.clone()).expect("png");
        output::write_exr(&exr, r.width, r.height, &r.hdr()).expect("exr");
        files.push((std::fs::read(png).unwrap(), std::fs::read(exr).unwrap()));
    }
    for (i, f) in files.iter().enumerate().skip(1) {
        assert!(
            f.0 == files[0].0,
            "PNG bytes differ between 1 thread and run {i}"
        );
        assert!(
            f.1 == files[0].1,
            "EXR bytes differ between 1 thread and run {i}"
        );
    }
}
