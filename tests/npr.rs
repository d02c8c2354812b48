//! NPR styles end to end, from scene files: posterization, hard (toon)
//! shading, hatching and textured base colours.

mod common;

use common::scene;
use specula::render::{render_scene, RenderSettings};
use specula_raster::frame::ShadePath;
use std::collections::BTreeSet;

const SPHERE_SCENE: &str = r#"
[camera]
eye = [0.0, 0.0, 4.0]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 10.0

[output]
width = 96
height = 96

[[mesh]]
sphere = { radius = 1.0, segments = 96, rings = 48 }
material = "m"

[[light]]
type = "directional"
direction = [-0.5, -0.4, -1.0]
irradiance = [3.0, 3.0, 3.0]
"#;

#[test]
fn posterized_scene_has_at_most_levels_codes_per_channel() {
    for (levels, mode) in [(3, "rgb"), (5, "luminance")] {
        let toml = format!(
            "{SPHERE_SCENE}\n[materials.m]\nmodel = \"lambert\"\nbase_color = [0.8, 0.5, 0.2]\n\n[posterize]\nlevels = {levels}\nmode = \"{mode}\"\n"
        );
        let s = scene(&toml, &[]);
        let r = render_scene(&s, &RenderSettings::from_scene(&s), 0.0).unwrap();
        if mode == "rgb" {
            for c in 0..3 {
                let codes: BTreeSet<u8> = r.ldr.iter().skip(c).step_by(3).copied().collect();
                assert!(codes.len() <= levels, "channel {c}: {codes:?}");
                assert!(codes.len() >= 2, "channel {c}: {codes:?}");
            }
        } else {
            // Hue kept: every pixel's colour is a multiple of the base colour,
            // so the number of distinct colours is the number of levels hit.
            let colours: BTreeSet<[u8; 3]> =
                r.ldr.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
            assert!(colours.len() <= levels, "{colours:?}");
        }
    }
    let bad = format!("{SPHERE_SCENE}\n[materials.m]\nmodel = \"lambert\"\nbase_color = [1, 1, 1]\n[posterize]\nlevels = 1\n");
    let err = specula::scene::load_scene_str(std::path::Path::new("p.toml"), &bad, &|_| {
        Err(std::io::ErrorKind::NotFound.into())
    })
    .err()
    .unwrap()
    .to_string();
    assert!(err.contains("posterize.levels"), "{err}");
}

/// Reads files from a list of (name, bytes).
fn files(list: Vec<(String, Vec<u8>)>) -> impl Fn(&std::path::Path) -> std::io::Result<Vec<u8>> {
    move |p| {
        list.iter()
            .find(|(n, _)| std::path::Path::new(n) == p)
            .map(|(_, b)| b.clone())
            .ok_or_else(|| std::io::ErrorKind::NotFound.into())
    }
}

fn load(
    toml: &str,
    read: &dyn Fn(&std::path::Path) -> std::io::Result<Vec<u8>>,
) -> Result<specula::scene::LoadedScene, String> {
    specula::scene::load_scene_str(std::path::Path::new("t.toml"), toml, read)
        .map_err(|e| e.to_string())
}

fn png(w: u32, h: u32, px: impl Fn(u32, u32) -> [u8; 3]) -> Vec<u8> {
    let mut img = image::RgbImage::new(w, h);
    for (x, y, p) in img.enumerate_pixels_mut() {
        *p = image::Rgb(px(x, y));
    }
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// Primary ray through the centre of pixel (x, y) of a w × h image
/// (row 0 at the top), camera at `eye` looking down −z with vertical
/// field of view `fov_y` degrees: the D3D-style pinhole DESIGN.md states.
fn ray(x: u32, y: u32, w: u32, h: u32, fov_y: f64) -> [f64; 3] {
    let ty = (fov_y.to_radians() / 2.0).tan();
    let tx = ty * w as f64 / h as f64;
    let nx = (x as f64 + 0.5) * 2.0 / w as f64 - 1.0;
    let ny = 1.0 - (y as f64 + 0.5) * 2.0 / h as f64;
    let d = [nx * tx, ny * ty, -1.0];
    let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    d.map(|v| v / l)
}

fn toon_sphere(material: &str, size: u32) -> (Vec<[f32; 3]>, [f64; 3]) {
    let toml = format!(
        r#"
[camera]
eye = [0.0, 0.0, 4.0]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 10.0

[output]
width = {size}
height = {size}

[[mesh]]
sphere = {{ radius = 1.0, segments = 256, rings = 128 }}
material = "m"

[[light]]
type = "directional"
direction = [-1.0, -0.3, -0.4]
irradiance = [3.14159265, 3.14159265, 3.14159265]

[materials.m]
{material}
"#
    );
    let s = scene(&toml, &[]);
    let r = render_scene(&s, &RenderSettings::from_scene(&s), 0.0).unwrap();
    let d = [1.0f64, 0.3, 0.4];
    let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    (r.hdr(), d.map(|v| v / l))
}

/// n·l at the analytic unit sphere's hit of pixel (x, y), and n·v, or None.
fn sphere_cos(x: u32, y: u32, size: u32, to_light: [f64; 3]) -> Option<(f64, f64)> {
    let d = ray(x, y, size, size, 40.0);
    let o = [0.0, 0.0, 4.0];
    let b = o[0] * d[0] + o[1] * d[1] + o[2] * d[2];
    let c = 16.0 - 1.0;
    let disc = b * b - c;
    if disc < 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    let n = [o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]];
    let cos_l = n[0] * to_light[0] + n[1] * to_light[1] + n[2] * to_light[2];
    let cos_v = -(n[0] * d[0] + n[1] * d[1] + n[2] * d[2]);
    Some((cos_l, cos_v))
}

/// Renders a toon sphere and checks every pixel away from the requested
/// edges (by `margin` in n·l) and the silhouette against `expect(n·l)`.
fn check_bands(material: &str, edges: &[f64], expect: impl Fn(f64) -> f64) {
    let size = 200;
    let (hdr, l) = toon_sphere(material, size);
    let margin = 0.01;
    let mut checked = vec![0usize; edges.len() + 1];
    for y in 0..size {
        for x in 0..size {
            let Some((cos, cos_v)) = sphere_cos(x, y, size, l) else {
                continue;
            };
            if cos_v < 0.15 || edges.iter().any(|e| (cos - e).abs() < margin) {
                continue;
            }
            let got = hdr[(y * size + x) as usize][0] as f64;
            let want = expect(cos);
            assert!(
                (got - want).abs() < 1e-4,
                "{material}: pixel ({x}, {y}) n·l = {cos:.4}: {got} vs {want}"
            );
            checked[edges.iter().filter(|e| cos >= **e).count()] += 1;
        }
    }
    assert!(
        checked.iter().all(|&n| n > 100),
        "pixels per band {checked:?}"
    );
}

#[test]
fn toon_band_edges_sit_at_the_requested_n_dot_l() {
    // 4 bands: edges at n·l = 0, ¼, ½, ¾; band k shows (k + 1)/4 of
    // base · E / π = 1.
    check_bands(
        "model = \"toon\"\nbase_color = [1, 1, 1]\nbands = 4",
        &[0.0, 0.25, 0.5, 0.75],
        |c| {
            if c <= 0.0 {
                0.0
            } else {
                ((c * 4.0).floor() + 1.0).min(4.0) / 4.0
            }
        },
    );
    // An explicit ramp with uneven edges.
    check_bands(
        "model = \"toon\"\nbase_color = [1, 1, 1]\nramp = [[-0.2, [0.1, 0.1, 0.1]], [0.3, [0.5, 0.5, 0.5]], [0.8, [1, 1, 1]]]",
        &[-0.2, 0.3, 0.8],
        |c| {
            if c >= 0.8 {
                1.0
            } else if c >= 0.3 {
                0.5
            } else if c >= -0.2 {
                0.1
            } else {
                0.0
            }
        },
    );
}

#[test]
fn toon_highlight_and_rim_are_hard() {
    let size = 200;
    let (hdr, l) = toon_sphere(
        "model = \"toon\"\nbase_color = [0, 0, 0]\nspecular_threshold = 0.98\nspecular_color = [1, 0, 0]\nrim_threshold = 0.7\nrim_color = [0, 0, 2]",
        size,
    );
    let (mut spec, mut rim) = (0, 0);
    for y in 0..size {
        for x in 0..size {
            let Some((cos, cos_v)) = sphere_cos(x, y, size, l) else {
                continue;
            };
            let d = ray(x, y, size, size, 40.0);
            // n·h with h = (l + v)/|l + v|; n from the analytic hit.
            let o = [0.0, 0.0, 4.0];
            let b = o[2] * d[2];
            let t = -b - (b * b - 15.0).sqrt();
            let n = [t * d[0], t * d[1], 4.0 + t * d[2]];
            let h = [l[0] - d[0], l[1] - d[1], l[2] - d[2]];
            let hl = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
            let nh = (n[0] * h[0] + n[1] * h[1] + n[2] * h[2]) / hl;
            let px = hdr[(y * size + x) as usize];
            if (nh - 0.98).abs() > 0.003 && cos > 0.0 {
                let want = if nh >= 0.98 { 1.0 } else { 0.0 };
                assert!(
                    (px[0] as f64 - want).abs() < 1e-4,
                    "({x}, {y}) n·h {nh}: {px:?}"
                );
                spec += (nh >= 0.98) as usize;
            }
            if ((1.0 - cos_v) - 0.7).abs() > 0.01 {
                let want = if 1.0 - cos_v >= 0.7 { 2.0 } else { 0.0 };
                assert!(
                    (px[2] as f64 - want).abs() < 1e-4,
                    "({x}, {y}) n·v {cos_v}: {px:?}"
                );
                rim += (1.0 - cos_v >= 0.7) as usize;
            }
        }
    }
    assert!(spec > 20 && rim > 100, "{spec} highlight, {rim} rim pixels");
}

const PLANE_CAMERA: &str = r#"
[camera]
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 10.0

[output]
width = 128
height = 128

[[light]]
type = "directional"
direction = [0.0, 0.0, -1.0]
irradiance = [3.14159265, 3.14159265, 3.14159265]
"#;

/// 32 × 32 texels in 8 × 8 cells of 4 × 4: red = cell column / 7, green =
/// cell row (from the top of the picture) / 7, blue = checker parity, so
/// a flip or a swap of u and v shows.
fn checker_texel(col: u32, row_top: u32) -> [u8; 3] {
    let (cx, cy) = (col / 4, row_top / 4);
    [
        (cx * 255 / 7) as u8,
        (cy * 255 / 7) as u8,
        if (cx + cy) % 2 == 0 { 255 } else { 0 },
    ]
}

fn srgb_decode(b: u8) -> f64 {
    let s = b as f64 / 255.0;
    if s <= 0.04045 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

#[test]
fn textured_checker_plane_matches_its_analytic_uv() {
    let tex = png(32, 32, checker_texel);
    let read = files(vec![("checker.png".into(), tex)]);
    // The XZ plane turned to face the camera: object (x, y, z) → world
    // (x, −z, y); mesh.rs gives u = (z + 1)/2, v = (x + 1)/2, so a world
    // point (X, Y, 0) has u = (1 − Y)/2, v = (X + 1)/2.
    let toml = format!(
        "{PLANE_CAMERA}\n[[mesh]]\nplane = {{ size = [2.0, 2.0] }}\nrotate = [90.0, 0.0, 0.0]\nmaterial = \"m\"\n\n[materials.m]\nmodel = \"lambert\"\nbase_color = [1, 1, 1]\nbase_color_texture = \"checker.png\"\n"
    );
    let s = load(&toml, &read).unwrap();
    for path in [ShadePath::Simd, ShadePath::Scalar] {
        let mut settings = RenderSettings::from_scene(&s);
        settings.path = path;
        let r = render_scene(&s, &settings, 0.0).unwrap();
        let hdr = r.hdr();
        let mut checked = 0;
        for y in 0..128 {
            for x in 0..128 {
                let d = ray(x, y, 128, 128, 40.0);
                let t = 3.0 / -d[2];
                let (wx, wy) = (t * d[0], t * d[1]);
                let (u, v) = ((1.0 - wy) / 2.0, (wx + 1.0) / 2.0);
                if !(0.0..1.0).contains(&u) || !(0.0..1.0).contains(&v) {
                    continue;
                }
                // Away from cell borders by over a texel, bilinear filtering
                // returns the cell's colour itself.
                let (tu, tv) = (u * 32.0, v * 32.0);
                let near_edge = |t: f64| {
                    let f = t / 4.0 - (t / 4.0).floor();
                    f * 4.0 < 1.2 || f * 4.0 > 2.8
                };
                if near_edge(tu) || near_edge(tv) {
                    continue;
                }
                // OBJ convention: v = 0 is the bottom row of the picture.
                let texel = checker_texel(tu as u32, 31 - tv as u32);
                let got = hdr[(y * 128 + x) as usize];
                for c in 0..3 {
                    let want = srgb_decode(texel[c]);
                    assert!(
                        (got[c] as f64 - want).abs() < 2e-4,
                        "{path:?} pixel ({x}, {y}) uv ({u:.3}, {v:.3}) channel {c}: {} vs {want}",
                        got[c]
                    );
                }
                checked += 1;
            }
        }
        assert!(checked > 1500, "{checked} pixels checked");
    }
}

#[test]
fn textured_metallic_roughness_equals_the_model_at_the_texel_colour() {
    // A uniform texture t: the textured material must equal the plain one
    // with base_color ⊙ decode(t), under every light kind but polygons.
    let t = [200u8, 90, 30];
    let tex = png(4, 4, |_, _| t);
    let read = files(vec![("t.png".into(), tex)]);
    let base = [0.9f64, 0.7, 0.5];
    let eff: Vec<f64> = (0..3).map(|c| base[c] * srgb_decode(t[c])).collect();
    let lights = "[[light]]\ntype = \"point\"\nposition = [1.5, 1.0, 2.0]\nintensity = [5, 4, 3]\n\n[environment]\nuniform = [0.2, 0.25, 0.3]\n";
    for (metallic, roughness) in [(0.0, 0.5), (1.0, 0.3), (0.4, 0.8)] {
        let mesh = "[[mesh]]\nsphere = { radius = 0.8 }\nmaterial = \"m\"\n";
        let textured = format!(
            "{PLANE_CAMERA}{lights}{mesh}[materials.m]\nmodel = \"metallic_roughness\"\nbase_color = {base:?}\nroughness = {roughness}\nmetallic = {metallic}\nbase_color_texture = \"t.png\"\n"
        );
        let plain = format!(
            "{PLANE_CAMERA}{lights}{mesh}[materials.m]\nmodel = \"metallic_roughness\"\nbase_color = {eff:?}\nroughness = {roughness}\nmetallic = {metallic}\n"
        );
        let a = load(&textured, &read).unwrap();
        let b = load(&plain, &read).unwrap();
        let ra = render_scene(&a, &RenderSettings::from_scene(&a), 0.0)
            .unwrap()
            .hdr();
        let rb = render_scene(&b, &RenderSettings::from_scene(&b), 0.0)
            .unwrap()
            .hdr();
        let mut worst = 0.0f64;
        for (p, q) in ra.iter().zip(&rb) {
            for c in 0..3 {
                let (p, q) = (p[c] as f64, q[c] as f64);
                worst = worst.max((p - q).abs() / q.abs().max(0.05));
            }
        }
        assert!(
            worst < 1e-4,
            "metallic {metallic}: relative difference {worst}"
        );
    }
}

#[test]
fn textured_material_on_a_mesh_without_uvs_is_named() {
    let tex = png(2, 2, |_, _| [255, 255, 255]);
    let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec();
    let read = files(vec![("t.png".into(), tex), ("tri.obj".into(), obj)]);
    let toml = format!(
        "{PLANE_CAMERA}\n[[mesh]]\nobj = \"tri.obj\"\nmaterial = \"m\"\n\n[materials.m]\nmodel = \"lambert\"\nbase_color = [1, 1, 1]\nbase_color_texture = \"t.png\"\n"
    );
    let err = load(&toml, &read).err().unwrap();
    assert!(
        err.contains("mesh[0].obj") && err.contains("tri.obj") && err.contains("vt"),
        "{err}"
    );
    let missing = toml.replace("t.png", "nope.png");
    let err = load(&missing, &read).err().unwrap();
    assert!(
        err.contains("materials.m.base_color_texture") && err.contains("nope.png"),
        "{err}"
    );
    let hatch = format!("{PLANE_CAMERA}\n[[mesh]]\nobj = \"tri.obj\"\nmaterial = \"h\"\n\n[materials.h]\nmodel = \"hatching\"\n");
    let err = load(&hatch, &read).err().unwrap();
    assert!(err.contains("vt") && err.contains("\"h\""), "{err}");
}

#[test]
fn hatching_reproduces_the_shaded_tone_on_average() {
    // A plane facing the camera under a light giving it luminance Y: the
    // mean of the hatched pixels (ink 0, paper 1) is 1 − D for the tone
    // blend's darkness D = 1 − Y, within the map's darkness tolerance and
    // the sampling of a window that is not a whole number of tiles
    // (measured: within 0.017);
    // darker than the darkest tone (0.8) draws the darkest tone.
    for y_target in [0.85f64, 0.6, 0.35, 0.1] {
        let want = y_target.max(1.0 - specula_npr::tam::MAX_DARKNESS);
        let e = y_target * std::f64::consts::PI;
        let toml = format!(
            r#"
[camera]
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 10.0

[output]
width = 160
height = 160

[[light]]
type = "directional"
direction = [0.0, 0.0, -1.0]
irradiance = [{e}, {e}, {e}]

[[mesh]]
plane = {{ size = [2.0, 2.0] }}
rotate = [90.0, 0.0, 0.0]
material = "h"

[materials.h]
model = "hatching"
ink = [0, 0, 0]
paper = [1, 1, 1]
scale = 2.0
"#
        );
        let s = load(&toml, &|_| Err(std::io::ErrorKind::NotFound.into())).unwrap();
        for path in [ShadePath::Simd, ShadePath::Scalar] {
            let mut settings = RenderSettings::from_scene(&s);
            settings.path = path;
            let hdr = render_scene(&s, &settings, 0.0).unwrap().hdr();
            // The plane covers the central ±(2/2)/(3 tan 20°) of the view.
            let (mut sum, mut n) = (0.0f64, 0usize);
            for y in 30..130 {
                for x in 30..130 {
                    sum += hdr[y * 160 + x][0] as f64;
                    n += 1;
                }
            }
            let mean = sum / n as f64;
            assert!(
                (mean - want).abs() < 0.03,
                "{path:?} Y {y_target}: mean brightness {mean:.4}, want {want}"
            );
        }
    }
}

#[test]
fn npr_fixture_scenes_render_and_shading_paths_agree() {
    for name in ["npr-tones.toml", "npr-posterize.toml"] {
        let path = common::fixtures().join("scenes").join(name);
        let s = specula::scene::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
        let mut settings = RenderSettings::from_scene(&s);
        (settings.width, settings.height) = (320, 180);
        let simd = render_scene(&s, &settings, 0.0).unwrap();
        settings.path = ShadePath::Scalar;
        let scalar = render_scene(&s, &settings, 0.0).unwrap();
        let (a, b) = (simd.hdr(), scalar.hdr());
        let mut worst = 0.0f64;
        let mut off = 0;
        for (p, q) in a.iter().zip(&b) {
            for c in 0..3 {
                let d = (p[c] as f64 - q[c] as f64).abs() / (q[c] as f64).abs().max(0.05);
                worst = worst.max(d);
                off += (d > 1e-3) as usize;
            }
            assert!(p.iter().all(|v| v.is_finite()), "{name}: non-finite pixel");
        }
        // Hard edges (bands, hatching tone steps) may flip a pixel where
        // f32x8 and f32 round n·l differently on the edge itself.
        assert!(
            off * 2000 < a.len() * 3,
            "{name}: {off} values differ (worst {worst})"
        );
    }
}

#[test]
fn bad_npr_materials_are_named() {
    let none = |_: &std::path::Path| -> std::io::Result<Vec<u8>> {
        Err(std::io::ErrorKind::NotFound.into())
    };
    let cases = [
        (
            "model = \"toon\"\nbase_color = [1, 1, 1]\nbands = 3\nramp = [[0.0, [1, 1, 1]]]",
            "materials.m.bands / ramp",
        ),
        (
            "model = \"toon\"\nbase_color = [1, 1, 1]\nbands = 0",
            "materials.m.bands",
        ),
        (
            "model = \"toon\"\nbase_color = [1, 1, 1]\nramp = [[0.5, [1, 1, 1]], [0.2, [1, 1, 1]]]",
            "materials.m.ramp[1]",
        ),
        (
            "model = \"toon\"\nbase_color = [1, 1, 1]\nspecular_threshold = 2.0",
            "materials.m.specular_threshold",
        ),
        ("model = \"hatching\"\nscale = 0.0", "materials.m.scale"),
        (
            "model = \"hatching\"\ntam = \"missing\"",
            "materials.m.tam: missing/tam.json",
        ),
        ("model = \"hatching\"\nink = [-1, 0, 0]", "materials.m.ink"),
    ];
    for (body, want) in cases {
        let toml = format!(
            "{PLANE_CAMERA}\n[[mesh]]\nsphere = {{}}\nmaterial = \"m\"\n\n[materials.m]\n{body}\n"
        );
        let err = load(&toml, &none)
            .err()
            .unwrap_or_else(|| panic!("{body}: loaded"));
        assert!(err.contains(want), "{body}: {err}");
    }
    // eval refuses stylized and textured materials with a reason.
    let mut cache = specula::eval::Cache::default();
    let line = r#"{"material": {"model": "toon", "base_color": [1, 1, 1]}, "wi": [0, 0, 1], "wo": [0, 0, 1]}"#;
    let out = specula::eval::eval_line(line, 1, &mut cache);
    assert!(out.contains("error") && out.contains("toon"), "{out}");
}
