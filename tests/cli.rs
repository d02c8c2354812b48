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
fn counts_and_repeated_outputs_are_checked() {
    let small = ["--width", "16", "--height", "16"];
    fails(
        "cli-repeat-zero",
        GOOD,
        &[&small[..], &["--repeat", "0"]].concat(),
        &["--repeat"],
    );
    fails(
        "cli-threads-zero",
        GOOD,
        &[&small[..], &["--threads", "0"]].concat(),
        &["--threads"],
    );
    fails(
        "cli-aov-twice",
        GOOD,
        &[
            &small[..],
            &["--aov", "depth=a.exr", "--aov", "depth=b.exr"],
        ]
        .concat(),
        &["--aov depth", "a.exr", "b.exr"],
    );
}

/// More threads than a 16 × 16 frame has tiles are not started: the run
/// succeeds (what it would cost to start them is not asserted here).
#[test]
fn many_threads_on_a_small_frame_render() {
    let dir = temp_dir("cli-many-threads");
    std::fs::write(dir.join("scene.toml"), GOOD).unwrap();
    let args = [
        "render",
        "scene.toml",
        "-o",
        "out.png",
        "--width",
        "16",
        "--height",
        "16",
    ];
    let out = specula(
        &[&args[..], &["--threads", "10000", "--stats"]].concat(),
        &dir,
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    assert!(
        text.contains(&format!("{cores} thread(s)")),
        "expected {cores} threads: {text}"
    );
}

#[test]
fn a_scene_without_light_says_so() {
    let dir = temp_dir("cli-no-light");
    let dark = GOOD.split("[[light]]").next().unwrap();
    std::fs::write(dir.join("scene.toml"), dark).unwrap();
    let args = [
        "render",
        "scene.toml",
        "-o",
        "out.png",
        "--width",
        "16",
        "--height",
        "16",
    ];
    let out = specula(&args, &dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("warning: the scene has no [[light]] and no [environment]"),
        "{err}"
    );
    std::fs::write(dir.join("scene.toml"), GOOD).unwrap();
    let out = specula(&args, &dir);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("no [[light]]"));
}

/// Colours are bounded so that no sum of lights × BRDF × supersamples
/// overflows f32: a huge component is refused by name, in every model and
/// in the stylized shaders' colours, used or not.
#[test]
fn huge_or_invalid_colours_are_refused_by_name() {
    let material = |body: &str| {
        let head = GOOD.split("[materials.m]").next().unwrap();
        let light = GOOD.split("[[light]]").nth(1).unwrap();
        format!("{head}[materials.m]\n{body}\n[[light]]{light}")
    };
    for (name, body, field) in [
        (
            "mr",
            "model = \"metallic_roughness\"\nroughness = 0.5\nbase_color = [3e38, 1, 1]",
            "base_color",
        ),
        (
            "lambert",
            "model = \"lambert\"\nbase_color = [1, 2e6, 1]",
            "base_color",
        ),
        (
            "disney",
            "model = \"disney\"\nbase_color = [1e19, 1, 1]",
            "base_color",
        ),
        (
            "toon-spec",
            "model = \"toon\"\nbase_color = [0.5, 0.5, 0.5]\nspecular_color = [nan, -1, inf]",
            "specular_color",
        ),
        (
            "toon-rim",
            "model = \"toon\"\nbase_color = [0.5, 0.5, 0.5]\nrim_color = [1e30, 0, 0]",
            "rim_color",
        ),
        (
            "toon-ramp",
            "model = \"toon\"\nbase_color = [0.5, 0.5, 0.5]\nramp = [[-1.0, [0.1, 0.1, 0.1]], [0.5, [1e7, 1, 1]]]",
            "ramp[1]",
        ),
        (
            "hatching",
            "model = \"hatching\"\npaper = [1e9, 1, 1]",
            "paper",
        ),
        (
            "unlit",
            "model = \"unlit\"\ncolor = [1, 1, 1]\nintensity = 1e30",
            "intensity",
        ),
    ] {
        fails(
            &format!("cli-colour-{name}"),
            &material(body),
            &["--width", "8", "--height", "8"],
            &[field],
        );
    }
}

#[test]
fn pnm_names_other_than_ppm_are_refused() {
    for ext in ["pgm", "pbm", "pam"] {
        let dir = temp_dir(&format!("cli-pnm-{ext}"));
        std::fs::write(dir.join("scene.toml"), GOOD).unwrap();
        let out_name = format!("out.{ext}");
        let out = specula(&["render", "scene.toml", "-o", &out_name], &dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{ext}: {err}");
        assert!(
            err.contains(&out_name) && err.contains(".ppm"),
            "{ext}: {err}"
        );
        assert!(!dir.join(&out_name).exists());
    }
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

/// A texture named only by an MTL (not by the scene) is an input too: no
/// output may replace it.
#[test]
fn refuses_to_overwrite_a_texture_named_by_an_mtl() {
    let dir = temp_dir("cli-overwrite-mtl-texture");
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl t\nf 1/1 2/2 3/3\n";
    std::fs::write(dir.join("m.obj"), obj).unwrap();
    std::fs::write(dir.join("m.mtl"), "newmtl t\nKd 1 1 1\nmap_Kd tex.png\n").unwrap();
    image::RgbImage::from_pixel(2, 2, image::Rgb([200, 100, 50]))
        .save(dir.join("tex.png"))
        .unwrap();
    let texture = std::fs::read(dir.join("tex.png")).unwrap();
    let scene = GOOD.replace(
        "sphere = { radius = 1.0, segments = 16, rings = 8 }\nmaterial = \"m\"",
        "obj = \"m.obj\"",
    );
    assert_ne!(scene, GOOD);
    std::fs::write(dir.join("scene.toml"), &scene).unwrap();
    for args in [
        &["-o", "tex.png"][..],
        &["-o", "out.png", "--exr", "tex.png"],
        &["-o", "out.png", "--aov", "id=tex.png"],
    ] {
        let mut all = vec!["render", "scene.toml", "--width", "8", "--height", "8"];
        all.extend_from_slice(args);
        let out = specula(&all, &dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}: {err}");
        assert!(
            err.contains("refusing to overwrite") && err.contains("tex.png"),
            "{args:?}: {err}"
        );
        assert_eq!(
            std::fs::read(dir.join("tex.png")).unwrap(),
            texture,
            "{args:?}"
        );
    }
}

/// `tam` checks its folder before generating, refuses a file or a folder
/// of other files, and replaces an earlier map whole.
#[test]
fn tam_checks_its_folder_first_and_replaces_a_map_whole() {
    let dir = temp_dir("cli-tam-folder");
    let small = ["--tones", "2", "--size", "32"];
    let tam = |out: &str| {
        let mut args = vec!["tam", "-o", out];
        args.extend_from_slice(&small);
        specula(&args, &dir)
    };
    std::fs::write(dir.join("grid.png"), b"not a map").unwrap();
    let out = tam("grid.png");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("not a folder"),
        "{err}"
    );
    assert_eq!(std::fs::read(dir.join("grid.png")).unwrap(), b"not a map");

    std::fs::create_dir(dir.join("mine")).unwrap();
    std::fs::write(dir.join("mine/notes.txt"), b"keep").unwrap();
    let out = tam("mine");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("refusing to replace"),
        "{err}"
    );
    assert_eq!(std::fs::read(dir.join("mine/notes.txt")).unwrap(), b"keep");

    let out = tam("no/such/folder/map");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("cannot write into"),
        "{err}"
    );

    // A map, then another over it: the second's files, nothing left over.
    assert!(tam("map").status.success());
    std::fs::write(dir.join("map/tam_t9_l0.png"), b"stale").unwrap();
    assert!(tam("map").status.success());
    assert!(!dir.join("map/tam_t9_l0.png").exists());
    assert!(dir.join("map/tam.json").exists());
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".specula"))
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

/// The table generators check their output before computing for minutes.
#[test]
fn table_generators_refuse_an_unwritable_output_at_once() {
    let dir = temp_dir("cli-generators-output");
    for cmd in ["kc-tables", "fit-ltc", "fit-ltc-coat"] {
        let out = specula(&[cmd, "--output", "no/such/folder/t.bin"], &dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{cmd}: {err}");
        assert!(
            err.contains("--output no/such/folder/t.bin"),
            "{cmd}: {err}"
        );
    }
}

/// Off a terminal (stderr piped, as into a log) each generator prints
/// plain progress lines, the first one when its first step is done. The
/// run is stopped at that line: the whole work takes minutes.
#[test]
fn table_generators_print_progress_lines_off_a_terminal() {
    use std::io::BufRead;
    use std::process::{Command, Stdio};
    let dir = temp_dir("cli-generators-progress");
    for (cmd, first) in [
        ("kc-tables", "kc-tables: 1/116 tables (0 %), "),
        ("fit-ltc", "fit-ltc: 1/4096 cells (0 %), "),
        ("fit-ltc-coat", "fit-ltc-coat: 1/384 cells (0 %), "),
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_specula"))
            .args([cmd, "--output", "t.bin"])
            .current_dir(&dir)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("run specula");
        let stderr = child.stderr.take().unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        let reader = std::thread::spawn(move || {
            for line in std::io::BufReader::new(stderr).lines() {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        // A guard against a run that never reports, not a timing check.
        let mut seen = Vec::new();
        let found = loop {
            match rx.recv_timeout(std::time::Duration::from_secs(600)) {
                Ok(line) if line.starts_with(first) => break Some(line),
                Ok(line) => seen.push(line),
                Err(_) => break None,
            }
        };
        child.kill().unwrap();
        child.wait().unwrap();
        drop(rx);
        reader.join().unwrap();
        let line = found.unwrap_or_else(|| panic!("{cmd}: no progress line in {seen:?}"));
        assert!(
            line.contains(" s, about ") && line.ends_with(" s left"),
            "{cmd}: {line}"
        );
        assert!(
            !dir.join("t.bin").exists(),
            "{cmd}: an output before the end"
        );
    }
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

/// `specula sky` refuses a width it cannot make and an output that is a
/// folder, before computing anything, and writes nothing in either case.
#[test]
fn sky_refuses_bad_widths_and_folders() {
    let dir = temp_dir("sky-refusals");
    for (args, needle) in [
        (
            &["sky", "-o", "s.hdr", "--width", "5"][..],
            "--width must be even",
        ),
        (&["sky", "-o", "s.hdr", "--width", "2"][..], "got 2"),
        (&["sky", "-o", ".", "--width", "8"][..], "--output"),
    ] {
        let out = specula(args, &dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    assert!(!dir.join("s.hdr").exists());
    let out = specula(&["sky", "-o", "s.hdr", "--width", "8"], &dir);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let map = image::open(dir.join("s.hdr")).unwrap();
    assert_eq!((map.width(), map.height()), (8, 4));
}
