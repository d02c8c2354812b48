//! Disney materials in scenes: the sweep fixture renders with the SIMD and
//! scalar paths agreeing and its labels on the image; bad fields are
//! errors naming the file and field, out-of-range-but-meaningful ones are
//! warnings.

mod common;

use common::fixtures;
use specula::render::{render_scene, RenderSettings};
use specula::scene::{load_scene, load_scene_str};
use specula_raster::frame::ShadePath;
use std::path::Path;

#[test]
fn sweep_fixture_renders_with_labels_and_paths_agree() {
    let scene = load_scene(&fixtures().join("scenes/disney-sweep.toml")).expect("sweep scene");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    // Half size: labels scale with it.
    let mut s = RenderSettings::from_scene(&scene);
    s.width /= 2;
    s.height /= 2;
    s.ssaa = 1;
    let simd = render_scene(&scene, &s, 0.0).expect("simd");
    s.path = ShadePath::Scalar;
    let scalar = render_scene(&scene, &s, 0.0).expect("scalar");
    let (a, b) = (&simd.frame.buffers.color, &scalar.frame.buffers.color);
    let mut worst = 0.0f64;
    for (x, y) in
        a.r.iter()
            .chain(&a.g)
            .chain(&a.b)
            .zip(b.r.iter().chain(&b.g).chain(&b.b))
    {
        let (x, y) = (*x as f64, *y as f64);
        assert!(x.is_finite() && y.is_finite() && x >= 0.0);
        worst = worst.max((x - y).abs() / x.abs().max(y.abs()).max(1e-3));
    }
    assert!(worst < 1e-5, "worst relative difference {worst:e}");
    // The row names sit left of the spheres, over the background: the first
    // (metallic) label's box must hold near-white text pixels.
    let label = &scene
        .output
        .labels
        .iter()
        .find(|l| l.text == "metallic")
        .unwrap();
    let (w, ldr) = (s.width as usize, &simd.ldr);
    let (x0, y0) = ((label.at[0] / 2.0) as usize, (label.at[1] / 2.0) as usize);
    let bright = (y0..y0 + 12)
        .flat_map(|y| (x0..x0 + 40).map(move |x| (x, y)))
        .filter(|&(x, y)| ldr[(y * w + x) * 3] > 120)
        .count();
    assert!(bright > 10, "{bright} text pixels");
}

fn load(material: &str) -> Result<specula::scene::LoadedScene, String> {
    let toml = format!(
        "[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\nfov_y = 30\nnear = 1\nfar = 10\n\
         [[mesh]]\nsphere = {{ radius = 1 }}\nmaterial = \"d\"\n\
         [[light]]\ntype = \"directional\"\ndirection = [0, 0, -1]\nirradiance = [1, 1, 1]\n\
         [materials.d]\nmodel = \"disney\"\n{material}\n"
    );
    let read = |_: &Path| -> std::io::Result<Vec<u8>> { Err(std::io::ErrorKind::NotFound.into()) };
    load_scene_str(Path::new("sweep.toml"), &toml, &read).map_err(|e| e.to_string())
}

#[test]
fn bad_fields_are_errors_and_wide_ones_warnings() {
    for (field, line) in [
        ("roughness", "roughness = nan"),
        ("roughness", "roughness = -0.5"),
        ("metallic", "metallic = 1.5"),
        ("clearcoat_gloss", "clearcoat_gloss = 2.0"),
        ("specular", "specular = 13.0"),
        ("base_color", "base_color = [0.5, -1, 0.5]"),
        ("sheen", "sheen = inf"),
    ] {
        let e = load(line)
            .err()
            .unwrap_or_else(|| panic!("{line} was accepted"));
        assert!(
            e.starts_with("sweep.toml") && e.contains(field),
            "{line}: {e}"
        );
    }
    let s =
        load("specular = 2.0\nsheen = 3.0\nroughness = 1.2\nclearcoat = 1.5").expect("accepted");
    for field in ["specular", "sheen", "roughness", "clearcoat"] {
        assert_eq!(
            s.warnings.iter().filter(|w| w.contains(field)).count(),
            1,
            "one warning for {field}: {:?}",
            s.warnings
        );
    }
    assert!(load("").expect("defaults").warnings.is_empty());
}

/// A mesh without uvs has no tangent direction: anisotropic Disney falls
/// back to the frame around the normal alone, and still shades every pixel
/// finite, with SIMD and scalar agreeing.
#[test]
fn anisotropic_disney_on_a_mesh_without_uvs() {
    let toml = "[camera]\neye = [0, 0.4, 3]\ntarget = [0, 0.4, 0]\nfov_y = 30\nnear = 0.5\nfar = 10\n\
                [output]\nwidth = 160\nheight = 120\n\
                [environment]\nuniform = [0.2, 0.2, 0.2]\n\
                [[light]]\ntype = \"point\"\nposition = [2, 3, 3]\nintensity = [20, 20, 20]\n\
                [[mesh]]\nobj = \"bunny.obj\"\nmaterial = \"brushed\"\n\
                [materials.brushed]\nmodel = \"disney\"\nmetallic = 1\nroughness = 0.4\nanisotropic = 1\nclearcoat = 1\n";
    let bunny = std::fs::read(fixtures().join("models/bunny.obj")).unwrap();
    let read = move |p: &Path| -> std::io::Result<Vec<u8>> {
        if p == Path::new("bunny.obj") {
            Ok(bunny.clone())
        } else {
            Err(std::io::ErrorKind::NotFound.into())
        }
    };
    let scene = load_scene_str(Path::new("nouv.toml"), toml, &read).expect("scene");
    assert!(scene.data.uvs.is_empty(), "the bunny has no uvs");
    let mut s = RenderSettings::from_scene(&scene);
    let simd = render_scene(&scene, &s, 0.0).expect("simd");
    s.path = ShadePath::Scalar;
    let scalar = render_scene(&scene, &s, 0.0).expect("scalar");
    assert!(simd.stats.pixels_shaded > 1000);
    let (a, b) = (&simd.frame.buffers.color, &scalar.frame.buffers.color);
    for (x, y) in
        a.r.iter()
            .chain(&a.g)
            .chain(&a.b)
            .zip(b.r.iter().chain(&b.g).chain(&b.b))
    {
        assert!(x.is_finite() && *x >= 0.0);
        assert!(
            (x - y).abs() <= 1e-5 * x.abs().max(y.abs()).max(1e-3),
            "{x} vs {y}"
        );
    }
}
