//! Environment maps end to end: the `[environment] map` fields, the bad
//! files a map may be (each a clear error or the documented clamping,
//! never a NaN pixel), the background, and the two lighting methods on
//! rendered frames.

mod common;

use specula::envmap_file::{decode_equirect, load_env_map, EnvMapError, EnvSettings};
use specula::render::{render_scene, RenderSettings};
use specula::scene::{load_scene_str, LoadedScene};
use specula_raster::envmap::IblMethod;
use specula_raster::equirect::MAX_TEXEL;
use std::io::Cursor;
use std::path::Path;

/// A Radiance HDR file of `w`×`h` texels from `f(i, j)`.
fn hdr_bytes(w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 3]) -> Vec<u8> {
    let px: Vec<image::Rgb<f32>> = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| image::Rgb(f(i, j)))
        .collect();
    let mut out = Vec::new();
    image::codecs::hdr::HdrEncoder::new(&mut out)
        .encode(&px, w as usize, h as usize)
        .unwrap();
    out
}

/// An OpenEXR file of `w`×`h` texels from `f(i, j)` (any f32, NaN too).
fn exr_bytes(w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 3]) -> Vec<u8> {
    let data: Vec<f32> = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .flat_map(|(i, j)| f(i, j))
        .collect();
    let img = image::Rgb32FImage::from_raw(w, h, data).unwrap();
    let mut out = Cursor::new(Vec::new());
    image::DynamicImage::ImageRgb32F(img)
        .write_to(&mut out, image::ImageFormat::OpenExr)
        .unwrap();
    out.into_inner()
}

fn settings(method: IblMethod) -> EnvSettings {
    EnvSettings {
        intensity: 1.0,
        rotate_deg: 0.0,
        visible: true,
        method,
    }
}

/// Loads a scene whose files are given as bytes.
fn scene_with(toml: &str, files: Vec<(&'static str, Vec<u8>)>) -> Result<LoadedScene, String> {
    let read = move |p: &Path| -> std::io::Result<Vec<u8>> {
        files
            .iter()
            .find(|(n, _)| Path::new(n) == p)
            .map(|(_, b)| b.clone())
            .ok_or_else(|| std::io::ErrorKind::NotFound.into())
    };
    load_scene_str(Path::new("test.toml"), toml, &read).map_err(|e| e.to_string())
}

/// A sphere in front of the camera (looking down −Z) under `environment`.
fn sphere_scene(environment: &str, material: &str) -> String {
    format!(
        r#"
[camera]
eye = [0.0, 0.0, 4.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 40.0
near = 0.1
far = 50.0

[output]
width = 48
height = 32

[environment]
{environment}

[materials.m]
{material}

[[mesh]]
sphere = {{ radius = 1.0, segments = 32, rings = 16 }}
material = "m"
"#
    )
}

fn render_hdr(scene: &LoadedScene) -> Vec<[f32; 3]> {
    let mut s = RenderSettings::from_scene(scene);
    s.keep_hdr = true;
    let r = render_scene(scene, &s, 0.0).unwrap_or_else(|e| panic!("{e}"));
    r.hdr()
}

#[test]
fn truncated_hdr_is_an_error() {
    let bytes = hdr_bytes(64, 32, |i, j| [i as f32, j as f32, 1.0]);
    let e = decode_equirect("sky.hdr", &bytes[..bytes.len() / 2]).unwrap_err();
    assert!(matches!(e, EnvMapError::Decode { .. }), "{e}");
    let e = e.to_string();
    assert!(e.starts_with("sky.hdr: "), "{e}");
}

#[test]
fn a_png_is_not_an_environment_map() {
    let img = image::RgbImage::new(8, 4);
    let mut png = Cursor::new(Vec::new());
    img.write_to(&mut png, image::ImageFormat::Png).unwrap();
    let e = decode_equirect("sky.png", png.get_ref()).unwrap_err();
    assert!(
        matches!(
            e,
            EnvMapError::NotRadiance {
                format: image::ImageFormat::Png,
                ..
            }
        ),
        "{e}"
    );
    let e = e.to_string();
    assert!(e.contains("Radiance HDR") && e.contains("sky.png"), "{e}");
    let e = decode_equirect("noise.hdr", b"hello, not an image").unwrap_err();
    assert!(matches!(e, EnvMapError::Unknown { .. }), "{e}");
    assert!(e.to_string().contains("noise.hdr"), "{e}");
}

#[test]
fn one_by_one_is_refused() {
    let e = decode_equirect("dot.hdr", &hdr_bytes(1, 1, |_, _| [1.0; 3])).unwrap_err();
    assert!(
        matches!(
            e,
            EnvMapError::TooSmall {
                width: 1,
                height: 1,
                ..
            }
        ),
        "{e}"
    );
    let e = e.to_string();
    assert!(e.contains("1×1") && e.contains("2×2"), "{e}");
}

#[test]
fn zero_height_header_is_refused() {
    let bytes = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 0 +X 16\n".to_vec();
    let e = decode_equirect("flat.hdr", &bytes).unwrap_err().to_string();
    assert!(e.contains("flat.hdr"), "{e}");
}

/// 65536 × 32768 in the header and no texels: refused from the header,
/// before anything of that size is allocated.
#[test]
fn huge_header_is_refused_before_decoding() {
    let bytes = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 32768 +X 65536\n".to_vec();
    let e = decode_equirect("huge.hdr", &bytes).unwrap_err();
    assert!(
        matches!(
            e,
            EnvMapError::TooLarge {
                width: 65536,
                height: 32768,
                ..
            }
        ),
        "{e}"
    );
    let e = e.to_string();
    assert_eq!(
        e,
        "huge.hdr: the header says 65536×32768: an environment map is at most 32768 texels on a side"
    );
}

/// NaN and negative texels become 0, +inf and huge ones the documented
/// ceiling; the frame has no NaN anywhere, under both methods.
#[test]
fn bad_texels_are_clamped_and_never_reach_a_pixel() {
    let bad = [f32::NAN, -1.0, f32::INFINITY, 1e30, f32::NEG_INFINITY, 0.5];
    let exr = exr_bytes(16, 8, |i, j| {
        let k = (i + j) as usize;
        [bad[k % 6], bad[(k + 1) % 6], bad[(k + 2) % 6]]
    });
    let map = load_env_map("bad.exr", &exr, &settings(IblMethod::SplitSum)).unwrap();
    assert!(map
        .source
        .texels
        .iter()
        .flatten()
        .all(|&c| (0.0..=MAX_TEXEL).contains(&c)));
    for ibl in ["split_sum", "reference"] {
        let env = format!("map = \"bad.exr\"\nibl = \"{ibl}\"\nibl_samples = 4");
        let toml = sphere_scene(
            &env,
            "model = \"metallic_roughness\"\nbase_color = [0.8, 0.8, 0.8]\nroughness = 0.5",
        );
        let scene = scene_with(&toml, vec![("bad.exr", exr.clone())]).unwrap();
        let img = render_hdr(&scene);
        assert!(
            img.iter().flatten().all(|c| c.is_finite()),
            "{ibl}: NaN or inf pixel"
        );
    }
}

#[test]
fn environment_fields_are_checked() {
    let hdr = hdr_bytes(8, 4, |_, _| [1.0; 3]);
    let m = "model = \"lambert\"\nbase_color = [0.5, 0.5, 0.5]";
    let cases = [
        ("uniform = [1.0, 1.0, 1.0]\nmap = \"sky.hdr\"", "not both"),
        ("intensity = 2.0", "give uniform"),
        (
            "map = \"sky.hdr\"\nintensity = -1.0",
            "environment.intensity",
        ),
        ("map = \"sky.hdr\"\nrotate = nan", "environment.rotate"),
        (
            "map = \"sky.hdr\"\nibl_samples = 0",
            "environment.ibl_samples",
        ),
        ("map = \"sky.hdr\"\nibl = \"magic\"", "ibl"),
        (
            "map = \"missing.hdr\"",
            "environment.map: cannot read missing.hdr",
        ),
    ];
    for (env, want) in cases {
        let e = scene_with(&sphere_scene(env, m), vec![("sky.hdr", hdr.clone())])
            .err()
            .unwrap_or_else(|| panic!("{env}: accepted"));
        assert!(e.contains(want), "{env}: {e}");
    }
}

/// Where no triangle is, the pixel is the map's radiance along its
/// primary ray: a map bright above the horizon and dark below shows so
/// above and below the sphere; `visible = false` shows the background.
#[test]
fn the_map_is_the_background() {
    let hdr = hdr_bytes(64, 32, |_, j| {
        if j < 16 {
            [2.0, 1.0, 0.5]
        } else {
            [0.0, 0.1, 0.2]
        }
    });
    let m = "model = \"lambert\"\nbase_color = [0.5, 0.5, 0.5]";
    let scene = scene_with(
        &sphere_scene("map = \"sky.hdr\"", m),
        vec![("sky.hdr", hdr.clone())],
    )
    .unwrap();
    let img = render_hdr(&scene);
    let (top, bottom) = (img[1], img[img.len() - 2]);
    let close = |a: [f32; 3], b: [f32; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 0.02);
    assert!(close(top, [2.0, 1.0, 0.5]), "{top:?}");
    assert!(close(bottom, [0.0, 0.1, 0.2]), "{bottom:?}");
    let scene = scene_with(
        &sphere_scene("map = \"sky.hdr\"\nvisible = false", m),
        vec![("sky.hdr", hdr)],
    )
    .unwrap();
    assert_eq!(render_hdr(&scene)[1], [0.0; 3]);
}

/// Every background pixel is the map read bilinearly (wrapping across
/// the seam, clamped at the poles) where its primary ray points, computed
/// here in f64 from the camera's definition, the map's `rotate` (the map
/// turned about +Y, so a ray reads it turned back) and the
/// equirectangular convention (u = 1/2 + atan2(x, −z)/2π,
/// v = acos(y)/π), on a map that varies in both axes: relative 1e-4. The
/// image is 45 pixels wide, so a tile row ends in a part of eight.
#[test]
fn the_background_is_the_map_along_each_primary_ray() {
    let (w, h) = (64u32, 32u32);
    let hdr = hdr_bytes(w, h, |i, j| {
        let (x, y) = (i as f32 / w as f32, j as f32 / h as f32);
        [0.2 + x, 0.3 + y * y, 1.5 - x * y]
    });
    let map = decode_equirect("sky.hdr", &hdr).unwrap();
    let m = "model = \"lambert\"\nbase_color = [0.5, 0.5, 0.5]";
    let rotate = 30f64;
    let load = |env: &str| {
        let toml = sphere_scene(&format!("{env}\nrotate = {rotate:.1}"), m)
            .replace("width = 48", "width = 45");
        let scene = scene_with(&toml, vec![("sky.hdr", hdr.clone())]).unwrap();
        render_hdr(&scene)
    };
    let (shown, hidden) = (
        load("map = \"sky.hdr\""),
        load("map = \"sky.hdr\"\nvisible = false"),
    );
    let (cos, sin) = (rotate.to_radians().cos(), rotate.to_radians().sin());
    // The scene's camera: at +4 Z looking down −Z, +Y up, 40° vertically,
    // 45 × 32 pixels.
    let (pw, ph) = (45usize, 32usize);
    let tan_y = 20f64.to_radians().tan();
    let tan_x = tan_y * pw as f64 / ph as f64;
    let texel = |i: i64, j: i64| {
        let i = i.rem_euclid(map.width as i64) as usize;
        let j = j.clamp(0, map.height as i64 - 1) as usize;
        map.texels[j * map.width + i].map(f64::from)
    };
    let mut background = 0;
    for y in 0..ph {
        for x in 0..pw {
            let k = y * pw + x;
            if hidden[k] != [0.0; 3] {
                continue;
            }
            background += 1;
            let nx = (x as f64 + 0.5) * 2.0 / pw as f64 - 1.0;
            let ny = 1.0 - (y as f64 + 0.5) * 2.0 / ph as f64;
            let world = [nx * tan_x, ny * tan_y, -1.0];
            // Turned by −rotate about +Y into the map's frame.
            let d = [
                cos * world[0] - sin * world[2],
                world[1],
                sin * world[0] + cos * world[2],
            ];
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let u = 0.5 + d[0].atan2(-d[2]) / std::f64::consts::TAU;
            let v = (d[1] / len).acos() / std::f64::consts::PI;
            let (fx, fy) = (u * map.width as f64 - 0.5, v * map.height as f64 - 0.5);
            let (i, j) = (fx.floor() as i64, fy.floor() as i64);
            let (ax, ay) = (fx - fx.floor(), fy - fy.floor());
            for (c, &got) in shown[k].iter().enumerate() {
                let top = texel(i, j)[c] * (1.0 - ax) + texel(i + 1, j)[c] * ax;
                let bottom = texel(i, j + 1)[c] * (1.0 - ax) + texel(i + 1, j + 1)[c] * ax;
                let want = top * (1.0 - ay) + bottom * ay;
                let got = got as f64;
                assert!(
                    (got - want).abs() <= 1e-4 * want.abs(),
                    "pixel ({x}, {y}) channel {c}: {got} against {want}"
                );
            }
        }
    }
    assert!(background > pw * ph / 2, "{background} background pixels");
}

/// A uniform map through either method lights a sphere as the uniform
/// environment does: split sum within 1 % (its prefiltering and SH are
/// exact for a constant), the reference within its Monte Carlo error.
#[test]
fn uniform_map_renders_like_the_uniform_environment() {
    let hdr = hdr_bytes(32, 16, |_, _| [1.0, 1.0, 1.0]);
    let materials = [
        "model = \"lambert\"\nbase_color = [0.5, 0.6, 0.7]",
        "model = \"metallic_roughness\"\nbase_color = [0.9, 0.6, 0.3]\nroughness = 0.4\nmetallic = 1.0",
        "model = \"metallic_roughness\"\nbase_color = [0.3, 0.6, 0.9]\nroughness = 0.7",
    ];
    for m in materials {
        let uniform =
            render_hdr(&scene_with(&sphere_scene("uniform = [1.0, 1.0, 1.0]", m), vec![]).unwrap());
        for (ibl, tol) in [("split_sum", 0.01), ("reference", 0.05)] {
            let env =
                format!("map = \"sky.hdr\"\nibl = \"{ibl}\"\nibl_samples = 256\nvisible = false");
            let scene = scene_with(&sphere_scene(&env, m), vec![("sky.hdr", hdr.clone())]).unwrap();
            let img = render_hdr(&scene);
            let (mut sum_u, mut sum_m) = (0.0f64, 0.0f64);
            // Covered pixels: the map is not visible, so the rest is 0.
            for (a, b) in uniform.iter().zip(&img) {
                if b[1] > 0.0 {
                    sum_u += a[1] as f64;
                    sum_m += b[1] as f64;
                }
            }
            let rel = (sum_m - sum_u).abs() / sum_u;
            assert!(rel < tol, "{m} {ibl}: mean relative difference {rel}");
        }
    }
}

/// `--env` lights a glTF file rendered on its own; a TOML scene refuses
/// it (its map is `[environment] map`).
#[test]
fn env_flag_lights_a_gltf_file() {
    let dir = common::temp_dir("env-flag");
    std::fs::write(
        dir.join("sky.hdr"),
        hdr_bytes(32, 16, |_, j| [1.0, 1.0, 0.5 + j as f32]),
    )
    .unwrap();
    let glb = common::fixtures().join("models/gltf/BoxTextured-plain.glb");
    let out = common::specula(
        &[
            "render",
            glb.to_str().unwrap(),
            "--env",
            "sky.hdr",
            "-o",
            "box.png",
            "--width",
            "64",
            "--height",
            "48",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let toml = common::fixtures().join("scenes/furnace.toml");
    let out = common::specula(
        &[
            "render",
            toml.to_str().unwrap(),
            "--env",
            "sky.hdr",
            "-o",
            "f.png",
        ],
        &dir,
    );
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--env"));
}
