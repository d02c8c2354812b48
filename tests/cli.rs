//! The `specula` binary on bad input: a clear message naming the file and
//! line or field, a non-zero exit, no panic, and no output file left behind.

mod common;

use common::{specula, temp_dir};
use std::path::PathBuf;

const GOOD: &str = r#"
[camera]
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
fov_y = 45.0
near = 0.1
far = 10.0

[[mesh]]
sphere = { radius = 1.0, segments = 16, rings = 8 }
material = "m"

[materials.m]
model = "metallic_roughness"
base_color = [0.8, 0.2, 0.2]
roughness = 0.4

[[light]]
type = "point"
position = [2.0, 2.0, 2.0]
intensity = [10.0, 10.0, 10.0]
"#;

/// Runs `render scene.toml -o out.png extra…` on `toml` and expects failure
/// with every one of `needles` in stderr.
fn fails(name: &str, toml: &str, extra: &[&str], needles: &[&str]) {
    let dir = temp_dir(name);
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    let mut args = vec!["render", "scene.toml", "-o", "out.png"];
    args.extend_from_slice(extra);
    let out = specula(&args, &dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success(),
        "{name}: expected failure, stderr: {err}"
    );
    assert!(!err.contains("panicked"), "{name}: panicked: {err}");
    for n in needles {
        assert!(err.contains(n), "{name}: stderr lacks {n:?}: {err}");
    }
    let left: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| !p.ends_with("scene.toml"))
        .collect();
    assert!(left.is_empty(), "{name}: left files behind: {left:?}");
}

#[test]
fn good_scene_renders_and_writes_every_output() {
    let dir = temp_dir("cli-good");
    std::fs::write(dir.join("scene.toml"), GOOD).unwrap();
    let out = specula(
        &[
            "render",
            "scene.toml",
            "-o",
            "out.png",
            "--width",
            "64",
            "--height",
            "48",
            "--exr",
            "out.exr",
            "--aov",
            "depth=d.exr",
            "--aov",
            "normal=n.exr",
            "--aov",
            "id=ids.bin",
            "--stats",
            "--stats-json",
            "s.json",
            "--repeat",
            "2",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    for k in [
        "vertex",
        "clip+setup",
        "bin",
        "raster",
        "shade",
        "post",
        "encode",
        "Mpixel/s",
        "culled",
    ] {
        assert!(stdout.contains(k), "--stats lacks {k}: {stdout}");
    }
    let png = image::open(dir.join("out.png")).unwrap();
    assert_eq!((png.width(), png.height()), (64, 48));
    let exr = image::open(dir.join("out.exr")).unwrap().into_rgb32f();
    assert_eq!(exr.dimensions(), (64, 48));
    let (w, h, ids) = specula::image_file::read_ids(&dir.join("ids.bin")).unwrap();
    assert_eq!((w, h), (64, 48));
    assert_eq!(ids[0], u32::MAX, "corner is background");
    assert_ne!(
        ids[(24 * 64 + 32) as usize],
        u32::MAX,
        "centre is the sphere"
    );
    let depth = image::open(dir.join("d.exr")).unwrap().into_rgb32f();
    let centre = depth.get_pixel(32, 24)[0];
    assert!(
        (centre - 2.0).abs() < 0.02,
        "view depth at the sphere's front is 3 − 1 = 2, got {centre}"
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("s.json")).unwrap()).unwrap();
    assert_eq!(json["frame_ms"].as_array().unwrap().len(), 2);
    assert!(json["frames"][0]["raster"].as_f64().is_some());
    // No temporary files are left behind.
    let stray: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .filter(|n| n.to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(stray.is_empty(), "{stray:?}");
}

#[test]
fn missing_obj() {
    let toml = GOOD.replace(
        "sphere = { radius = 1.0, segments = 16, rings = 8 }",
        "obj = \"nowhere/missing.obj\"",
    );
    fails(
        "cli-missing-obj",
        &toml,
        &[],
        &["scene.toml", "mesh[0].obj", "missing.obj"],
    );
}

#[test]
fn malformed_toml_names_line_and_column() {
    let toml = GOOD.replace("fov_y = 45.0", "fov_y = = 45.0");
    fails(
        "cli-bad-toml",
        &toml,
        &[],
        &["scene.toml", "line 5", "column"],
    );
}

#[test]
fn unknown_material_field() {
    let toml = GOOD.replace("roughness = 0.4", "roughness = 0.4\nshininess = 3.0");
    fails(
        "cli-unknown-field",
        &toml,
        &[],
        &["scene.toml", "shininess"],
    );
}

#[test]
fn out_of_range_material_value_names_the_field() {
    let toml = GOOD.replace("roughness = 0.4", "roughness = 1.5");
    fails(
        "cli-bad-value",
        &toml,
        &[],
        &["scene.toml", "materials.m.roughness", "1.5"],
    );
}

#[test]
fn bad_resolutions_fail_before_allocating() {
    fails("cli-zero-width", GOOD, &["--width", "0"], &["width"]);
    fails("cli-negative-height", GOOD, &["--height=-5"], &["height"]);
    fails(
        "cli-huge",
        GOOD,
        &["--width", "4000000000", "--height", "4000000000"],
        &["out of range"],
    );
    fails(
        "cli-huge-ssaa",
        GOOD,
        &["--width", "8000", "--ssaa", "4"],
        &["out of range"],
    );
}

#[test]
fn unwritable_output_leaves_nothing() {
    let dir = temp_dir("cli-unwritable");
    std::fs::write(dir.join("scene.toml"), GOOD).unwrap();
    let out = specula(
        &[
            "render",
            "scene.toml",
            "-o",
            "no/such/folder/out.png",
            "--width",
            "32",
            "--height",
            "32",
        ],
        &dir,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("out.png") && err.contains("cannot write"),
        "{err}"
    );
    assert!(!err.contains("panicked"));
}

#[test]
fn refuses_to_overwrite_the_scene_file() {
    let dir = temp_dir("cli-overwrite");
    std::fs::write(dir.join("scene.toml"), GOOD).unwrap();
    let out = specula(&["render", "scene.toml", "-o", "scene.toml"], &dir);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("refusing to overwrite"));
    assert_eq!(
        std::fs::read_to_string(dir.join("scene.toml")).unwrap(),
        GOOD
    );
}

#[test]
fn furnace_prints_compensated_albedo_near_one_and_plots() {
    let dir = temp_dir("cli-furnace");
    let out = specula(&["furnace", "--alpha", "0.2,0.6,1", "-o", "plot.png"], &dir);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split('\t').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 3 * 40);
    for r in &rows {
        // alpha, mu, E rgb, E compensated rgb; F = 1 so E ≤ 1 and E_c ≈ 1.
        assert!(r[2] <= 1.0 + 1e-3, "{r:?}");
        assert!((r[5] - 1.0).abs() < 2e-3, "{r:?}");
    }
    let png = image::open(dir.join("plot.png")).unwrap();
    assert_eq!((png.width(), png.height()), (900, 600));
    let bad = specula(
        &[
            "furnace",
            "--material",
            r#"{"model": "lambert", "base_color": [1, 1, 1]}"#,
        ],
        &dir,
    );
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("microfacet"));
}
