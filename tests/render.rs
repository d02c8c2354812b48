//! Whole frames of the benchmark scene and the demo: the SIMD and scalar
//! shading paths agree, and the bytes do not depend on the thread count.

mod common;

use common::{fixtures, temp_dir};
use specula::render::{render_scene, RenderSettings};
use specula::scene::{load_scene, LoadedScene};
use specula::{demo, image_file};
use specula_raster::frame::ShadePath;
use specula_raster::post::PostOutput;

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
    let (a, b) = (&simd.frame.buffers.color, &scalar.frame.buffers.color);
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
        image_file::write_png(&png, r.width, r.height, r.ldr.clone()).expect("png");
        image_file::write_exr(&exr, r.width, r.height, &r.hdr()).expect("exr");
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

#[test]
fn simd_and_scalar_agree_on_every_microfacet_variant() {
    let mut toml = String::from(
        r#"
[camera]
eye = [0.0, 2.0, 7.0]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 50.0
[output]
width = 320
height = 180
[environment]
uniform = [0.2, 0.25, 0.3]
[[light]]
type = "point"
position = [3.0, 4.0, 5.0]
intensity = [40.0, 40.0, 40.0]
"#,
    );
    let variants = [
        "ndf = \"ggx\"\nalpha = 0.2\nfresnel = { type = \"schlick\", f0 = [0.9, 0.6, 0.3] }",
        "ndf = \"beckmann\"\nalpha = 0.4\nsmith = \"separable\"\ndiffuse = [0.3, 0.1, 0.1]\nfresnel = { type = \"dielectric\", ior = 1.5 }",
        "ndf = \"gtr\"\ngamma = 1.0\nalpha = 0.3\nfresnel = { type = \"conductor\", eta = [0.18, 0.42, 1.37], k = [3.42, 2.35, 1.77] }",
        "ndf = \"gtr\"\ngamma = 3.0\nalpha = 0.6\nfresnel = { type = \"dielectric\", ior = 1.33 }",
    ];
    for (i, v) in variants.iter().enumerate() {
        let x = -3.0 + 2.0 * i as f32;
        toml += &format!(
            "[[mesh]]\nsphere = {{ radius = 0.8, segments = 32, rings = 16 }}\nmaterial = \"m{i}\"\ntranslate = [{x}, 0.0, 0.0]\n[materials.m{i}]\nmodel = \"microfacet\"\n{v}\n"
        );
    }
    let scene = common::scene(&toml, &[]);
    let (worst, shaded) = simd_vs_scalar(&scene);
    assert!(shaded > 1000);
    assert!(worst < 1e-5, "worst relative difference {worst:e}");
}

/// fixtures/scenes/furnace.toml: under a uniform white environment the
/// compensated spheres reflect what they receive (they vanish into the
/// background); the single-scattering ones are visibly darker when rough.
#[test]
fn furnace_scene_compensated_spheres_vanish() {
    let scene = load_scene(&fixtures().join("scenes/furnace.toml")).expect("furnace scene");
    let mut s = RenderSettings::from_scene(&scene);
    s.width = 500;
    s.height = 220;
    let r = render_scene(&scene, &s, 0.0).expect("render");
    let t = &r.frame.target;
    let ids = t.to_row_major(&r.frame.visibility.vis.id);
    let hdr = r.hdr();
    let mut worst = 0.0f32;
    let (mut rough_sum, mut rough_n) = (0.0f64, 0usize);
    for (i, &id) in ids.iter().enumerate() {
        if id == specula_raster::MISS {
            assert!(
                (hdr[i][0] - 1.0).abs() < 1e-6,
                "background is the environment"
            );
            continue;
        }
        let name = &scene.data.materials[scene.data.tri_material[id as usize] as usize].name;
        if name.starts_with("comp_") {
            worst = worst.max((hdr[i][0] - 1.0).abs());
        } else if name == "single_4" {
            rough_sum += hdr[i][0] as f64;
            rough_n += 1;
        }
    }
    eprintln!("worst |L − 1| on compensated spheres: {worst:.2e}");
    assert!(
        worst < 3e-3,
        "compensated spheres differ from the environment by {worst}"
    );
    assert!(
        rough_n > 100 && rough_sum / (rough_n as f64) < 0.8,
        "the α = 1 single-scattering sphere should be darker"
    );
}

#[test]
fn benchmark_with_a_microfacet_row_renders_and_paths_agree() {
    let mut scene =
        load_scene(&fixtures().join("scenes/sphere-grid-materials.toml")).expect("scene");
    scene.output.width = 480;
    scene.output.height = 270;
    let (worst, shaded) = simd_vs_scalar(&scene);
    assert_eq!(shaded, 480 * 270);
    assert!(worst < 1e-5, "worst relative difference {worst:e}");
}

/// Frames drawn one after another reuse the previous frame's buffers (the
/// setup and bin chunks, the 8-bit output): a frame drawn into buffers that
/// a larger scene used, and its post pass writing over a longer, dirty
/// output vector, give the bytes a fresh frame gives.
#[test]
fn a_frame_drawn_into_reused_buffers_equals_a_fresh_one() {
    use specula_raster::frame::{render, render_into};
    let big = benchmark();
    let small = demo::demo_scene().expect("demo");
    let target = specula_raster::Target::new(480, 270).expect("target");
    let fresh = render(&small.data, target, ShadePath::Simd);
    let mut reused = render(&big.data, target, ShadePath::Simd);
    render_into(&small.data, &mut reused, ShadePath::Simd);
    assert!(reused.visibility.vis.id == fresh.visibility.vis.id, "ids");
    assert!(reused.buffers.color == fresh.buffers.color, "colour");
    assert_eq!(reused.stats.counts, fresh.stats.counts);
    assert_eq!(reused.stats.raster_triangles, fresh.stats.raster_triangles);

    let mut settings = RenderSettings::from_scene(&small);
    settings.ssaa = 1;
    let mut post = settings.post();
    let expected = post.run(&fresh.buffers).expect("post").ldr;
    let dirty = PostOutput {
        ldr: Some(vec![0xA5u8; 480 * 270 * 3 + 1000]),
        ..PostOutput::default()
    };
    let got = post.run_reusing(&fresh.buffers, dirty).expect("post").ldr;
    assert!(got == expected, "8-bit output");
}

/// The 8-bit image encoded inside the shading pass (no HDR output kept)
/// is the post pass's, byte for byte: an odd size (partial packets and
/// tiles), every tone curve, exposures, both shading paths, 1 and 3
/// threads, and a second frame drawn into the first one's buffers.
#[test]
fn encoding_in_the_shading_pass_gives_the_post_pass_bytes() {
    use specula_raster::post::Tonemap;
    let scene = benchmark();
    for (tonemap, exposure) in [
        (Tonemap::Clamp, 0.0),
        (Tonemap::Reinhard, 1.7),
        (Tonemap::Aces, -2.3),
    ] {
        for path in [ShadePath::Simd, ShadePath::Scalar] {
            for threads in [1, 3] {
                let mut s = RenderSettings::from_scene(&scene);
                (s.width, s.height, s.ssaa) = (203, 67, 1);
                (s.tonemap, s.exposure, s.path) = (tonemap, exposure, path);
                s.threads = Some(threads);
                s.repeat = 2;
                let want = render_scene(&scene, &s, 0.0).expect("post pass");
                assert!(!want.stats.post_in_shading);
                s.keep_hdr = false;
                let got = render_scene(&scene, &s, 0.0).expect("in shading");
                let case = format!("{tonemap:?} {exposure} {path:?} {threads} threads");
                assert!(got.stats.post_in_shading, "{case}: not encoded in shading");
                assert!(got.frame.buffers.color.is_empty(), "{case}: colour kept");
                assert_eq!(got.ldr.len(), 203 * 67 * 3, "{case}");
                assert!(got.ldr == want.ldr, "{case}: bytes differ");
            }
        }
    }
    // The benchmark frame itself, and a list with supersampling, which
    // stays in the post pass.
    let mut s = RenderSettings::from_scene(&scene);
    let want = render_scene(&scene, &s, 0.0).expect("post pass");
    s.keep_hdr = false;
    let got = render_scene(&scene, &s, 0.0).expect("in shading");
    assert!(got.stats.post_in_shading && got.ldr == want.ldr);
    // A frame drawn to 8 bits, then again the usual way into its buffers:
    // the colour planes come back and hold the frame.
    use specula_raster::frame::{render, render_into, render_ldr};
    let target = specula_raster::Target::new(160, 90).expect("target");
    let enc = s.post().ldr_in_shading().expect("the default list");
    let mut bytes = Vec::new();
    let mut f = render_ldr(
        &scene.data,
        target,
        ShadePath::Simd,
        Default::default(),
        enc,
        &mut bytes,
    );
    assert!(f.buffers.color.is_empty());
    render_into(&scene.data, &mut f, ShadePath::Simd);
    let fresh = render(&scene.data, target, ShadePath::Simd);
    assert!(
        f.buffers.color == fresh.buffers.color,
        "colour after an 8-bit frame"
    );
    s.ssaa = 2;
    s.width = 320;
    s.height = 180;
    assert!(!render_scene(&scene, &s, 0.0).unwrap().stats.post_in_shading);
}
