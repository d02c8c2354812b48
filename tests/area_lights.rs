//! Polygon lights end to end: scenes (`two_sided`, `visible`,
//! `[render] area_lights`), renders by LTC against the reference renders
//! and the analytic form factor, and `specula eval`'s `"light"` lines.

mod common;

use common::{eval, scene};
use specula::render::{render_scene, RenderSettings};
use specula_raster::frame::ShadePath;
use specula_raster::MISS;
use std::f64::consts::PI;

/// Form factor from a point with normal n to the rectangle [0, a] × [0, b]
/// in the parallel plane at distance c, n through a corner
/// [Howell, config. B-3].
fn corner(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
}

const FLOOR: &str = r#"
[camera]
eye = [0.0, 6.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov_y = 40.0
near = 0.1
far = 50.0
[output]
width = 120
height = 120
[[mesh]]
plane = { size = [4.0, 4.0] }
material = "floor"
[materials.floor]
model = "lambert"
base_color = [0.5, 0.25, 1.0]
[[light]]
type = "polygon"
vertices = [[-0.5, 1.5, -0.5], [0.5, 1.5, -0.5], [0.5, 1.5, 0.5], [-0.5, 1.5, 0.5]]
radiance = [2.0, 2.0, 2.0]
"#;

fn render(text: &str, path: ShadePath) -> (Vec<[f32; 3]>, Vec<u32>) {
    let s = scene(text, &[]);
    let mut set = RenderSettings::from_scene(&s);
    set.path = path;
    set.buffers.id = true;
    let r = render_scene(&s, &set, 0.0).unwrap();
    let b = &r.frame.buffers;
    (
        (0..b.id.len()).map(|i| b.color.get(i)).collect(),
        b.id.clone(),
    )
}

#[test]
fn lambert_under_a_quad_matches_the_reference_render_and_the_form_factor() {
    let (ltc, id) = render(FLOOR, ShadePath::Simd);
    let (ltc1, _) = render(FLOOR, ShadePath::Scalar);
    let reference = FLOOR.to_string() + "[render]\narea_lights = \"reference\"\n";
    let (refr, _) = render(&reference, ShadePath::Simd);
    let mut worst = 0.0f64;
    let mut seen = 0;
    for i in 0..id.len() {
        if id[i] == MISS {
            continue;
        }
        seen += 1;
        for c in 0..3 {
            let (a, b) = (ltc[i][c] as f64, refr[i][c] as f64);
            assert!(b > 0.0, "pixel {i} is lit");
            worst = worst.max((a / b - 1.0).abs());
            assert!(
                (ltc1[i][c] as f64 / a - 1.0).abs() < 1e-5,
                "scalar vs simd, pixel {i}"
            );
        }
    }
    eprintln!(
        "lambert floor, LTC vs reference render: worst relative {worst:e} over {seen} pixels"
    );
    assert!(
        seen > 5000 && worst < 2e-3,
        "{seen} pixels, worst {worst:e}"
    );
    // The centre of the image sees the floor under the light's centre:
    // radiance ρ L F, F = 4 × corner(0.5, 0.5, 1.5). (The pixel centre is
    // half a pixel off the axis; F is flat there to ~1e-5.)
    let centre = 60 * 120 + 60;
    let f = 4.0 * corner(0.5, 0.5, 1.5);
    for (c, rho) in [0.5, 0.25, 1.0].iter().enumerate() {
        let want = rho * 2.0 * f;
        let got = ltc[centre][c] as f64;
        assert!(
            (got / want - 1.0).abs() < 1e-3,
            "channel {c}: {got} vs {want}"
        );
    }
}

/// World points are bounded (±1e9) for polygon lights as for every other
/// point; up to that bound a light far away and huge is integrated like a
/// near one: a square of half-size 1e9 at height 1e8 over the floor gives
/// ρ L F with F = 4 × corner(1e9, 1e9, 1e8).
#[test]
fn polygon_lights_up_to_the_world_bound_are_integrated_and_beyond_it_refused() {
    let huge = |s: f64, h: f64| {
        FLOOR.replace(
            "vertices = [[-0.5, 1.5, -0.5], [0.5, 1.5, -0.5], [0.5, 1.5, 0.5], [-0.5, 1.5, 0.5]]\nradiance = [2.0, 2.0, 2.0]",
            &format!(
                "vertices = [[-{s:e}, {h:e}, -{s:e}], [{s:e}, {h:e}, -{s:e}], [{s:e}, {h:e}, {s:e}], [-{s:e}, {h:e}, {s:e}]]\nradiance = [2.0, 2.0, 2.0]\nvisible = false"
            ),
        )
    };
    let text = huge(1e9, 1e8);
    assert_ne!(text, FLOOR);
    let (img, _) = render(&text, ShadePath::Simd);
    let centre = 60 * 120 + 60;
    let f = 4.0 * corner(1e9, 1e9, 1e8);
    for (c, rho) in [0.5, 0.25, 1.0].iter().enumerate() {
        let want = rho * 2.0 * f;
        let got = img[centre][c] as f64;
        assert!(
            (got / want - 1.0).abs() < 1e-3,
            "channel {c}: {got} vs {want}"
        );
    }
    let read = |_: &std::path::Path| -> std::io::Result<Vec<u8>> {
        Err(std::io::ErrorKind::NotFound.into())
    };
    for s in [2e9, 1e20] {
        let e =
            specula::scene::load_scene_str(std::path::Path::new("s.toml"), &huge(s, 1e8), &read)
                .err()
                .unwrap_or_else(|| panic!("corners at ±{s:e} accepted"))
                .to_string();
        assert!(
            e.contains("light[0].vertices[0]") && e.contains("1e9"),
            "{e}"
        );
    }
}

#[test]
fn a_visible_light_is_drawn_with_its_radiance_from_its_front_only() {
    let below = FLOOR
        .replace("eye = [0.0, 6.0, 0.0]", "eye = [0.0, -3.0, 0.0]")
        .replace("target = [0.0, 0.0, 0.0]", "target = [0.0, 1.5, 0.0]")
        .replace(
            "plane = { size = [4.0, 4.0] }",
            "plane = { size = [4.0, 4.0] }\ntranslate = [0.0, -9.0, 0.0]",
        );
    for (text, front) in [
        (below.clone(), true),
        (
            below.replace(
                "radiance = [2.0, 2.0, 2.0]",
                "radiance = [2.0, 2.0, 2.0]\nvisible = false",
            ),
            false,
        ),
        // From above, a one-sided light shows its culled back; two-sided, its radiance.
        (FLOOR.to_string(), false),
        (
            FLOOR.replace(
                "radiance = [2.0, 2.0, 2.0]",
                "radiance = [2.0, 2.0, 2.0]\ntwo_sided = true",
            ),
            true,
        ),
    ] {
        let s = scene(&text, &[]);
        let light_tris: Vec<usize> = (0..s.data.triangles.len())
            .filter(|&t| s.data.materials[s.data.tri_material[t] as usize].name == "light[0]")
            .collect();
        let (col, id) = render(&text, ShadePath::Simd);
        let lit = id
            .iter()
            .enumerate()
            .filter(|(_, &t)| t != MISS && light_tris.contains(&(t as usize)))
            .map(|(i, _)| i)
            .collect::<Vec<_>>();
        if front {
            assert!(lit.len() > 200, "{} light pixels", lit.len());
            for i in lit {
                assert_eq!(col[i], [2.0; 3]);
            }
        } else {
            assert!(lit.is_empty(), "{} light pixels seen", lit.len());
        }
    }
    // Two-sided lights light surfaces behind them as well.
    let flipped = FLOOR.replace(
        "[[-0.5, 1.5, -0.5], [0.5, 1.5, -0.5], [0.5, 1.5, 0.5], [-0.5, 1.5, 0.5]]",
        "[[-0.5, 1.5, 0.5], [0.5, 1.5, 0.5], [0.5, 1.5, -0.5], [-0.5, 1.5, -0.5]]",
    );
    let (dark, id) = render(&flipped, ShadePath::Simd);
    let (two, _) = render(
        &flipped.replace(
            "radiance = [2.0, 2.0, 2.0]",
            "radiance = [2.0, 2.0, 2.0]\ntwo_sided = true",
        ),
        ShadePath::Simd,
    );
    let (one, _) = render(FLOOR, ShadePath::Simd);
    for i in 0..id.len() {
        if id[i] != MISS && id[i] < 2 {
            assert_eq!(dark[i], [0.0; 3]);
            for c in 0..3 {
                assert!((two[i][c] / one[i][c] - 1.0).abs() < 1e-6, "pixel {i}");
            }
        }
    }
}

#[test]
fn bad_polygon_lights_and_render_tables_are_clear_errors() {
    let read = |_: &std::path::Path| -> std::io::Result<Vec<u8>> {
        Err(std::io::ErrorKind::NotFound.into())
    };
    for (bad, needle) in [
        (
            FLOOR.to_string() + "[render]\narea_lights = \"exact\"\n",
            "area_lights",
        ),
        (
            FLOOR.replace(
                "radiance = [2.0, 2.0, 2.0]",
                "radiance = [2.0, 2.0, 2.0]\ntwo_sided = 1",
            ),
            "expected a boolean",
        ),
        (
            FLOOR.replace(
                "[0.5, 1.5, 0.5], [-0.5, 1.5, 0.5]",
                "[-0.5, 1.5, 0.5], [0.8, 1.5, 0.9]",
            ),
            "not simple",
        ),
    ] {
        let e = specula::scene::load_scene_str(std::path::Path::new("s.toml"), &bad, &read)
            .err()
            .unwrap_or_else(|| panic!("must fail: {bad}"))
            .to_string();
        assert!(e.contains("s.toml") && e.contains(needle), "{e}");
    }
}

fn rgb(v: &serde_json::Value, key: &str) -> [f64; 3] {
    let a = v[key].as_array().unwrap_or_else(|| panic!("no {key}: {v}"));
    [0, 1, 2].map(|i| a[i].as_f64().unwrap())
}

#[test]
fn eval_answers_light_lines_by_ltc_and_by_reference() {
    let quad = "[[0, 0, 2], [0, 1, 2], [3, 1, 2], [3, 0, 2]]";
    let lam = r#"{"model": "lambert", "base_color": [1, 0.5, 0.25]}"#;
    let lines = [
        format!(
            r#"{{"material": {lam}, "wo": [0.2, 0.1, 1], "light": {{"polygon": {quad}, "radiance": [2, 2, 2]}}}}"#
        ),
        format!(
            r#"{{"material": {lam}, "wo": [0.2, 0.1, 1], "light": {{"polygon": {quad}, "radiance": [2, 2, 2]}}, "method": "reference"}}"#
        ),
        // Its back, one- and two-sided.
        format!(
            r#"{{"material": {lam}, "wo": [0, 0, 1], "light": {{"polygon": [[3, 0, 2], [3, 1, 2], [0, 1, 2], [0, 0, 2]], "radiance": [2, 2, 2]}}}}"#
        ),
        format!(
            r#"{{"material": {lam}, "wo": [0, 0, 1], "light": {{"polygon": [[3, 0, 2], [3, 1, 2], [0, 1, 2], [0, 0, 2]], "radiance": [2, 2, 2], "two_sided": true}}}}"#
        ),
        format!(
            r#"{{"material": {lam}, "wo": [0, 0, 1], "wi": [0, 0, 1], "light": {{"polygon": {quad}, "radiance": [1, 1, 1]}}}}"#
        ),
        format!(
            r#"{{"material": {lam}, "wo": [0, 0, 1], "light": {{"polygon": [[0, 0, 2], [0, 1, 2], [3, 1, 3]], "radiance": [1, 1, 1]}}, "method": "exact"}}"#
        ),
        format!(
            r#"{{"material": {lam}, "wo": [0, 0, 1], "light": {{"polygon": [[0, 0, 2], [0, 1, 2], [3, 1, 2], [3, 0, 5]], "radiance": [1, 1, 1]}}}}"#
        ),
        // Radiance capped as in scene files.
        format!(
            r#"{{"material": {lam}, "wo": [0, 0, 1], "light": {{"polygon": {quad}, "radiance": [1e308, 1, 1]}}}}"#
        ),
        // Lines 8-11: the quad of line 0 scaled by 1e-8 and 1e-15, by both
        // methods: the same directions, the same answer.
        format!(
            r#"{{"material": {lam}, "wo": [0.2, 0.1, 1], "light": {{"polygon": [[0, 0, 2e-8], [0, 1e-8, 2e-8], [3e-8, 1e-8, 2e-8], [3e-8, 0, 2e-8]], "radiance": [2, 2, 2]}}}}"#
        ),
        format!(
            r#"{{"material": {lam}, "wo": [0.2, 0.1, 1], "light": {{"polygon": [[0, 0, 2e-15], [0, 1e-15, 2e-15], [3e-15, 1e-15, 2e-15], [3e-15, 0, 2e-15]], "radiance": [2, 2, 2]}}}}"#
        ),
        format!(
            r#"{{"material": {lam}, "wo": [0.2, 0.1, 1], "light": {{"polygon": [[0, 0, 2e-8], [0, 1e-8, 2e-8], [3e-8, 1e-8, 2e-8], [3e-8, 0, 2e-8]], "radiance": [2, 2, 2]}}, "method": "reference"}}"#
        ),
        format!(
            r#"{{"material": {lam}, "wo": [0.2, 0.1, 1], "light": {{"polygon": [[0, 0, 2e-15], [0, 1e-15, 2e-15], [3e-15, 1e-15, 2e-15], [3e-15, 0, 2e-15]], "radiance": [2, 2, 2]}}, "method": "reference"}}"#
        ),
    ];
    let out = eval(&(lines.join("\n") + "\n"));
    assert_eq!(out.len(), lines.len());
    let f = corner(3.0, 1.0, 2.0);
    let ltc = rgb(&out[0], "radiance");
    let reference = rgb(&out[1], "radiance");
    let err = rgb(&out[1], "error");
    for (c, rho) in [1.0, 0.5, 0.25].iter().enumerate() {
        let want = 2.0 * rho * f;
        assert!((ltc[c] - want).abs() < 1e-12, "ltc {} vs {want}", ltc[c]);
        assert!(
            (reference[c] - want).abs() <= err[c].max(1e-12) && err[c] < 1e-5 * 2.0 * f,
            "reference {} ± {} vs {want}",
            reference[c],
            err[c]
        );
    }
    assert_eq!(rgb(&out[2], "radiance"), [0.0; 3]);
    assert!((rgb(&out[3], "radiance")[0] - 2.0 * f).abs() < 1e-12);
    assert!(
        out[4]["error"].as_str().unwrap().contains("exactly one"),
        "{}",
        out[4]
    );
    assert!(
        out[5]["error"]
            .as_str()
            .unwrap()
            .contains("expected `ltc` or `reference`"),
        "{}",
        out[5]
    );
    assert!(
        out[6]["error"].as_str().unwrap().contains("not planar"),
        "{}",
        out[6]
    );
    assert!(
        out[7]["error"].as_str().unwrap().contains("light.radiance"),
        "{}",
        out[7]
    );
    for (k, base) in [(8, &ltc), (9, &ltc), (10, &reference), (11, &reference)] {
        let got = rgb(&out[k], "radiance");
        for c in 0..3 {
            assert!(
                (got[c] / base[c] - 1.0).abs() < 1e-6,
                "line {k}: {got:?} vs scale 1: {base:?}"
            );
        }
    }
}

#[test]
fn non_ggx_microfacet_materials_refuse_polygon_lights() {
    let read = |_: &std::path::Path| -> std::io::Result<Vec<u8>> {
        Err(std::io::ErrorKind::NotFound.into())
    };
    let text = FLOOR.replace(
        "model = \"lambert\"\nbase_color = [0.5, 0.25, 1.0]",
        "model = \"microfacet\"\nndf = \"beckmann\"\nalpha = 0.3\nfresnel = { type = \"schlick\", f0 = [0.9, 0.9, 0.9] }",
    );
    let e = specula::scene::load_scene_str(std::path::Path::new("s.toml"), &text, &read)
        .err()
        .expect("must fail")
        .to_string();
    assert!(
        e.contains("light[0]") && e.contains("\"floor\"") && e.contains("ggx"),
        "{e}"
    );
}

/// fixtures/scenes/`name` (which says `area_lights = "ltc"`) with its
/// area lights integrated by `method` ("ltc" or "reference").
fn load_fixture(name: &str, method: &str) -> specula::scene::LoadedScene {
    let dir = common::fixtures().join("scenes");
    let text = std::fs::read_to_string(dir.join(name)).unwrap();
    assert!(text.contains("area_lights = \"ltc\""), "{name}");
    let text = text.replace(
        "area_lights = \"ltc\"",
        &format!("area_lights = \"{method}\""),
    );
    let read = |p: &std::path::Path| std::fs::read(dir.join(p));
    specula::scene::load_scene_str(std::path::Path::new(name), &text, &read)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// `scene` at 192×108 on `path`: each pixel's colour and id.
fn shoot(scene: &specula::scene::LoadedScene, path: ShadePath) -> (Vec<[f32; 3]>, Vec<u32>) {
    let mut set = RenderSettings::from_scene(scene);
    set.width = 192;
    set.height = 108;
    set.ssaa = 1;
    set.path = path;
    set.buffers.id = true;
    let r = render_scene(scene, &set, 0.0).unwrap();
    let b = &r.frame.buffers;
    let c: Vec<[f32; 3]> = (0..b.id.len()).map(|i| b.color.get(i)).collect();
    (c, b.id.clone())
}

#[test]
fn the_area_lights_fixture_renders_by_ltc_close_to_its_reference() {
    let (ltc, id) = shoot(&load_fixture("area-lights.toml", "ltc"), ShadePath::Simd);
    let (reference, _) = shoot(
        &load_fixture("area-lights.toml", "reference"),
        ShadePath::Simd,
    );
    // Per pixel: |LTC − reference| relative to the reference's brightest
    // channel (the lights themselves are unlit in both, so equal).
    let mut errs = Vec::new();
    for i in 0..id.len() {
        assert!(ltc[i].iter().chain(&reference[i]).all(|c| c.is_finite()));
        if id[i] == MISS {
            continue;
        }
        let peak = reference[i].iter().fold(0.0f32, |m, c| m.max(*c)).max(1e-3);
        let d = (0..3).fold(0.0f32, |m, c| m.max((ltc[i][c] - reference[i][c]).abs()));
        errs.push((d / peak) as f64);
    }
    errs.sort_by(f64::total_cmp);
    let q = |f: f64| errs[((errs.len() - 1) as f64 * f) as usize];
    eprintln!(
        "area-lights fixture, LTC vs reference per pixel (relative): median {:.4}, p90 {:.4}, p99 {:.4}, max {:.4} over {} pixels",
        q(0.5),
        q(0.9),
        q(0.99),
        q(1.0),
        errs.len()
    );
    assert!(
        q(0.5) < 0.002 && q(0.9) < 0.015 && q(0.99) < 0.35,
        "median {}, p90 {}, p99 {}",
        q(0.5),
        q(0.9),
        q(0.99)
    );
    // Measured at 192 × 108: median 0.0000 (floor and walls: Lambert is
    // exact), p90 0.0067, p99 0.22, max 1.19; the tail is on the spheres'
    // silhouettes, at grazing views, where the pixel's own radiance is
    // small.
}

#[test]
fn a_concave_16_vertex_light_and_a_light_in_the_floor_plane_shade_finitely() {
    // A 16-point star (concave) over the floor, two-sided, and a quad lying
    // in the floor's own plane (every floor point sees it edge-on).
    let star: Vec<String> = (0..16)
        .map(|k| {
            let phi = std::f64::consts::TAU * k as f64 / 16.0;
            let r = if k % 2 == 0 { 0.8 } else { 0.35 };
            format!("[{:.4}, 1.2, {:.4}]", r * phi.sin(), r * phi.cos())
        })
        .collect();
    let text = FLOOR.replace(
        "[[-0.5, 1.5, -0.5], [0.5, 1.5, -0.5], [0.5, 1.5, 0.5], [-0.5, 1.5, 0.5]]",
        &format!("[{}]", star.join(", ")),
    ) + "two_sided = true\n[[light]]\ntype = \"polygon\"\nvertices = [[-0.3, 0.0, -0.3], [0.3, 0.0, -0.3], [0.3, 0.0, 0.3], [-0.3, 0.0, 0.3]]\nradiance = [1.0, 1.0, 1.0]\n";
    let (ltc, id) = render(&text, ShadePath::Simd);
    let (reference, _) = render(
        &(text.clone() + "[render]\narea_lights = \"reference\"\n"),
        ShadePath::Simd,
    );
    let (scalar, _) = render(&text, ShadePath::Scalar);
    let mut worst = 0.0f64;
    for i in 0..id.len() {
        assert!(ltc[i]
            .iter()
            .chain(&reference[i])
            .chain(&scalar[i])
            .all(|c| c.is_finite()));
        if id[i] == MISS || id[i] >= 2 {
            continue; // only the floor's two triangles
        }
        let (a, b) = (ltc[i][0] as f64, reference[i][0] as f64);
        worst = worst.max((a - b).abs() / b.max(1e-3));
    }
    eprintln!("16-vertex star over a Lambert floor: worst relative LTC vs reference {worst:e}");
    assert!(worst < 2e-3, "{worst:e}");
}

#[test]
fn eval_answers_light_lines_on_disney_materials() {
    // Every lobe on; the LTC against the reference (Disney's measured
    // error tables are in core/tests/disney_ltc.rs) and against the core
    // model's own f64 LTC integral (the wiring).
    let mat = r#"{"model": "disney", "base_color": [0.8, 0.5, 0.3], "roughness": 0.4, "anisotropic": 0.5, "clearcoat": 1, "sheen": 0.5, "subsurface": 0.3}"#;
    // Counter-clockwise seen from the shading point below it: its front.
    let quad = "[[-0.4, 0.5, 1.5], [0.8, 0.5, 1.5], [0.8, -0.6, 1.5], [-0.4, -0.6, 1.5]]";
    let wo = [0.3f64, 0.1, 1.0];
    let lines = [
        format!(
            r#"{{"material": {mat}, "wo": {wo:?}, "light": {{"polygon": {quad}, "radiance": [1, 2, 3]}}, "method": "ltc"}}"#
        ),
        format!(
            r#"{{"material": {mat}, "wo": {wo:?}, "light": {{"polygon": {quad}, "radiance": [1, 2, 3]}}, "method": "reference"}}"#
        ),
        // Its back faces the point: one-sided gives 0.
        format!(
            r#"{{"material": {mat}, "wo": {wo:?}, "light": {{"polygon": [[-0.4, -0.6, 1.5], [0.8, -0.6, 1.5], [0.8, 0.5, 1.5], [-0.4, 0.5, 1.5]], "radiance": [1, 2, 3]}}}}"#
        ),
    ];
    let out = eval(&(lines.join("\n") + "\n"));
    let ltc = rgb(&out[0], "radiance");
    let reference = rgb(&out[1], "radiance");
    let err = rgb(&out[1], "error");
    assert_eq!(rgb(&out[2], "radiance"), [0.0; 3]);

    use specula_core::light::{PolygonLocal, MAX_POLYGON_VERTICES};
    use specula_core::models::disney::{Disney, DisneyParams};
    use specula_core::{Brdf, V3};
    let m = Disney::new_without_table(
        DisneyParams {
            base_color: [0.8, 0.5, 0.3],
            roughness: 0.4,
            anisotropic: 0.5,
            clearcoat: 1.0,
            sheen: 0.5,
            subsurface: 0.3,
            ..DisneyParams::default()
        },
        false,
    );
    let q = [
        [-0.4, 0.5, 1.5],
        [0.8, 0.5, 1.5],
        [0.8, -0.6, 1.5],
        [-0.4, -0.6, 1.5],
    ];
    let mut poly = PolygonLocal {
        vertices: [V3::new(0.0f64, 0.0, 0.0); MAX_POLYGON_VERTICES],
        len: 4,
        two_sided: false,
    };
    for (k, p) in q.iter().enumerate() {
        poly.vertices[k] = V3::new(p[0], p[1], p[2]);
    }
    let n = (wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2]).sqrt();
    let e = m.polygon_local(&m.prepare(V3::new(wo[0] / n, wo[1] / n, wo[2] / n)), &poly);
    for (c, (want, l)) in [e.x, e.y, e.z].iter().zip([1.0, 2.0, 3.0]).enumerate() {
        assert!(
            (ltc[c] / (want * l) - 1.0).abs() < 1e-6,
            "channel {c}: eval {} vs core {}",
            ltc[c],
            want * l
        );
        assert!(err[c] < 1e-4 * reference[c], "reference ± {}", err[c]);
        let rel = (ltc[c] / reference[c] - 1.0).abs();
        eprintln!(
            "disney eval, channel {c}: LTC {} vs reference {} ({rel:.4})",
            ltc[c], reference[c]
        );
        assert!(
            rel < 0.06,
            "channel {c}: LTC {} vs reference {}",
            ltc[c],
            reference[c]
        );
    }
}

#[test]
fn the_disney_area_lights_fixture_renders_by_ltc_close_to_its_reference() {
    let scene = load_fixture("disney-area-lights.toml", "ltc");
    let (ltc, id) = shoot(&scene, ShadePath::Simd);
    let (scalar, _) = shoot(&scene, ShadePath::Scalar);
    let (reference, _) = shoot(
        &load_fixture("disney-area-lights.toml", "reference"),
        ShadePath::Simd,
    );
    let mut errs = Vec::new();
    let mut simd_vs_scalar = 0.0f32;
    for i in 0..id.len() {
        assert!(ltc[i]
            .iter()
            .chain(&reference[i])
            .chain(&scalar[i])
            .all(|c| c.is_finite()));
        for c in 0..3 {
            simd_vs_scalar =
                simd_vs_scalar.max((ltc[i][c] - scalar[i][c]).abs() / ltc[i][c].abs().max(1e-3));
        }
        if id[i] == MISS {
            continue;
        }
        let peak = reference[i].iter().fold(0.0f32, |m, c| m.max(*c)).max(1e-3);
        let d = (0..3).fold(0.0f32, |m, c| m.max((ltc[i][c] - reference[i][c]).abs()));
        errs.push((d / peak) as f64);
    }
    // Per material, to see where the error is.
    {
        let mut per: std::collections::BTreeMap<String, Vec<f64>> = Default::default();
        for (&t, &e) in id.iter().filter(|&&t| t != MISS).zip(&errs) {
            let m = &scene.data.materials[scene.data.tri_material[t as usize] as usize].name;
            per.entry(m.clone()).or_default().push(e);
        }
        for (m, mut e) in per {
            e.sort_by(f64::total_cmp);
            let n = e.len();
            eprintln!(
                "{m}: median {:.4} p90 {:.4} p99 {:.4} max {:.4} ({n})",
                e[n / 2],
                e[n * 9 / 10],
                e[n * 99 / 100],
                e[n - 1]
            );
            // Isotropic lobes err per pixel like the microfacet spheres of
            // area-lights.toml (p90 up to 0.33 there, 0.25 here on the
            // rough metal, relative to the pixel's own radiance); the
            // brushed spheres far more (p90 0.9 and 4.2: the LTC draws
            // the anisotropic lobe's curved band as a straight one).
            if !m.starts_with("brushed") {
                assert!(e[n * 9 / 10] < 0.3, "{m}: p90 {}", e[n * 9 / 10]);
            }
        }
    }
    errs.sort_by(f64::total_cmp);
    let q = |f: f64| errs[((errs.len() - 1) as f64 * f) as usize];
    eprintln!(
        "disney-area-lights fixture, LTC vs reference per pixel (relative): median {:.4}, p90 {:.4}, p99 {:.4}, max {:.4} over {} pixels; SIMD vs scalar {simd_vs_scalar:e}",
        q(0.5),
        q(0.9),
        q(0.99),
        q(1.0),
        errs.len()
    );
    assert!(simd_vs_scalar < 1e-4, "{simd_vs_scalar:e}");
    // Measured at 192 × 108: median 0.0000 (the Lambert floor), p90
    // 0.038, p99 1.0, max 12 (on the brushed spheres).
    assert!(
        q(0.5) < 0.002 && q(0.9) < 0.05 && q(0.99) < 1.2,
        "median {}, p90 {}, p99 {}",
        q(0.5),
        q(0.9),
        q(0.99)
    );
}

/// `"method": "reference"` finds a lobe far narrower than the light: a
/// near-mirror conductor (F0 = 1, α = 0.001) under a light that fills
/// nearly the whole hemisphere reflects nearly all of it, since D
/// integrates to 1 over the projected half vectors and G → 1 as α → 0
/// (exactly 1 for α → 0; within 1 % here). Adaptive refinement alone
/// answered ~1e-9 with an error estimate claiming convergence.
#[test]
fn eval_reference_finds_a_narrow_lobe_under_a_large_light() {
    // ±100 at height 0.001: up to 89.9994° from the normal.
    let big = "[[-100, -100, 0.001], [100, -100, 0.001], [100, 100, 0.001], [-100, 100, 0.001]]";
    let mirror = |ndf: &str| {
        format!(
            r#"{{"model": "microfacet", "ndf": {ndf}, "alpha": 0.001, "fresnel": {{"type": "schlick", "f0": [1, 1, 1]}}}}"#
        )
    };
    let lines: Vec<String> = [
        (mirror("\"ggx\""), "[0, 0, 1]"),
        (mirror("\"ggx\""), "[0.3, -0.2, 0.9]"),
        (mirror("\"beckmann\""), "[0.3, 0, 0.95]"),
        (mirror("\"gtr\", \"gamma\": 1e6"), "[0.3, 0, 0.95]"),
    ]
    .iter()
    .map(|(m, wo)| {
        format!(
            r#"{{"material": {m}, "wo": {wo}, "light": {{"polygon": {big}, "radiance": [1, 1, 1], "two_sided": true}}, "method": "reference"}}"#
        )
    })
    .collect();
    let out = eval(&(lines.join("\n") + "\n"));
    assert_eq!(out.len(), lines.len());
    for (k, a) in out.iter().enumerate() {
        let l = rgb(a, "radiance");
        let e = rgb(a, "error");
        for c in 0..3 {
            assert!(
                (l[c] - 1.0).abs() < 0.01 && e[c] < 0.01,
                "line {k}: {l:?} ± {e:?}: {}",
                lines[k]
            );
        }
    }
}
