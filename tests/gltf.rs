//! `gltf` materials in scenes and in `specula eval`: the sweep fixture
//! renders finite with the SIMD and scalar paths agreeing; bad fields are
//! errors naming the file and the field; `eval` answers the glTF formula
//! at normal incidence and refuses what the model cannot do.

mod common;

use common::{eval, fixtures};
use specula::render::{render_scene, RenderSettings};
use specula::scene::{load_scene, load_scene_str};
use specula_raster::frame::ShadePath;
use std::f64::consts::PI;
use std::path::Path;

#[test]
fn sweep_fixture_renders_finite_and_paths_agree() {
    let scene = load_scene(&fixtures().join("scenes/gltf-materials.toml")).expect("gltf scene");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let mut s = RenderSettings::from_scene(&scene);
    s.width /= 2;
    s.height /= 2;
    s.ssaa = 1;
    let simd = render_scene(&scene, &s, 0.0).expect("simd");
    s.path = ShadePath::Scalar;
    let scalar = render_scene(&scene, &s, 0.0).expect("scalar");
    let (a, b) = (&simd.frame.buffers.color, &scalar.frame.buffers.color);
    let mut worst = 0.0f64;
    let mut lit = 0usize;
    for (x, y) in
        a.r.iter()
            .chain(&a.g)
            .chain(&a.b)
            .zip(b.r.iter().chain(&b.g).chain(&b.b))
    {
        let (x, y) = (*x as f64, *y as f64);
        assert!(x.is_finite() && y.is_finite() && x >= 0.0 && y >= 0.0);
        lit += (x > 0.01) as usize;
        worst = worst.max((x - y).abs() / x.abs().max(y.abs()).max(1e-3));
    }
    assert!(lit > 10_000, "{lit} lit samples");
    assert!(worst < 1e-4, "worst relative difference {worst:e}");
}

fn load(material: &str) -> Result<specula::scene::LoadedScene, String> {
    let toml = format!(
        "[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\nfov_y = 30\nnear = 1\nfar = 10\n\
         [[mesh]]\nsphere = {{ radius = 1 }}\nmaterial = \"g\"\n\
         [materials.g]\nmodel = \"gltf\"\n{material}\n"
    );
    let read = |_: &Path| -> std::io::Result<Vec<u8>> { Err(std::io::ErrorKind::NotFound.into()) };
    load_scene_str(Path::new("sweep.toml"), &toml, &read).map_err(|e| e.to_string())
}

#[test]
fn bad_fields_are_errors_naming_the_field() {
    assert!(load("").is_ok(), "the defaults load");
    assert!(load("ior = 0").is_ok(), "ior 0 is the infinite IOR");
    assert!(load("specular_color_factor = [2, 1.5, 0]").is_ok());
    for (field, line) in [
        ("base_color_factor", "base_color_factor = [0.5, 1.5, 0.5]"),
        ("metallic_factor", "metallic_factor = -0.1"),
        ("roughness_factor", "roughness_factor = nan"),
        ("ior", "ior = 0.5"),
        ("ior", "ior = inf"),
        ("specular_factor", "specular_factor = 2"),
        (
            "specular_color_factor",
            "specular_color_factor = [1, -1, 1]",
        ),
        ("clearcoat_factor", "clearcoat_factor = 1.01"),
        (
            "clearcoat_roughness_factor",
            "clearcoat_roughness_factor = -1",
        ),
        ("sheen_color_factor", "sheen_color_factor = [0, 0, 2]"),
        ("sheen_roughness_factor", "sheen_roughness_factor = inf"),
        ("fresnel", "fresnel = \"exact\""),
        ("shine", "shine = 1"),
    ] {
        let e = load(line)
            .err()
            .unwrap_or_else(|| panic!("{line} was accepted"));
        assert!(e.contains(field), "{line}: {e}");
        assert!(e.contains("sweep.toml"), "{line}: {e}");
    }
    // Sheen has no polygon-light integral.
    let e = load(
        "sheen_color_factor = [1, 1, 1]\n\
         [[light]]\ntype = \"polygon\"\nvertices = [[-1, 3, -1], [1, 3, -1], [1, 3, 1], [-1, 3, 1]]\nradiance = [1, 1, 1]",
    )
    .err()
    .expect("sheen under a polygon light");
    assert!(e.contains("sheen"), "{e}");
}

#[test]
fn eval_values_and_errors() {
    let out = eval(concat!(
        // 1, 2: the context's material at normal incidence, both options.
        r#"{"material":{"model":"gltf","base_color_factor":[1,0.766,0.336],"metallic_factor":0.5,"roughness_factor":0.5},"wi":[0,0,1],"wo":[0,0,1]}"#,
        "\n",
        r#"{"material":{"model":"gltf","base_color_factor":[1,0.766,0.336],"metallic_factor":0.5,"roughness_factor":0.5,"fresnel":"simplified"},"wi":[0,0,1],"wo":[0,0,1]}"#,
        "\n",
        // 3: a bad IOR.
        r#"{"material":{"model":"gltf","ior":0.9},"wi":[0,0,1],"wo":[0,0,1]}"#,
        "\n",
        // 4: sheen under a polygon light by LTC.
        r#"{"material":{"model":"gltf","sheen_color_factor":[1,1,1]},"wo":[0,0,1],"light":{"polygon":[[-1,-1,2],[1,-1,2],[1,1,2],[-1,1,2]],"radiance":[1,1,1]}}"#,
        "\n",
        // 5: the same by the reference quadrature is answered.
        r#"{"material":{"model":"gltf","sheen_color_factor":[1,1,1],"sheen_roughness_factor":0.5},"wo":[0,0,1],"light":{"polygon":[[-1,-1,2],[1,-1,2],[1,1,2],[-1,1,2]],"radiance":[1,1,1]},"method":"reference"}"#,
        "\n",
    ));
    assert_eq!(out.len(), 5, "{out:?}");
    // At w = 0, h = n: D(n) = 1/(π α²), the visibility 1/4 (α = 0.25).
    let base = [1.0, 0.766, 0.336];
    let dv = 1.0 / (PI * 0.0625) / 4.0;
    let m = 0.5;
    let get = |v: &serde_json::Value| {
        let a = v["f"].as_array().unwrap_or_else(|| panic!("{v}"));
        [0, 1, 2].map(|i| a[i].as_f64().unwrap())
    };
    let (norm, simp) = (get(&out[0]), get(&out[1]));
    for c in 0..3 {
        let f0 = (1.0 - m) * 0.04 + m * base[c];
        let spec = f0 * dv;
        let want_norm = spec + (1.0 - m) * (1.0 - 0.04) * base[c] / PI;
        let want_simp = spec + (1.0 - f0) * (1.0 - m) * base[c] / PI;
        // The factors are f32: 0.766 and 0.336 round at 3e-8.
        assert!((norm[c] - want_norm).abs() < 1e-6 * want_norm, "{norm:?}");
        assert!((simp[c] - want_simp).abs() < 1e-6 * want_simp, "{simp:?}");
    }
    let err = |v: &serde_json::Value| v["error"].as_str().unwrap_or_default().to_string();
    assert!(err(&out[2]).contains("material.ior"), "{}", out[2]);
    assert!(err(&out[3]).contains("sheen"), "{}", out[3]);
    assert!(out[4]["radiance"].is_array(), "{}", out[4]);
}
