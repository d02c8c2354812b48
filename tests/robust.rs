//! Robustness on bad input: every case here once crashed, lost a
//! file, or was accepted silently. Each expects a clear message naming the
//! file and line or field, a non-zero exit, no panic, and no stray files.

mod common;

use common::cli::{expect_error, load_err, run_in, stderr, CAMERA};
use common::{eval_bytes, specula, temp_dir};
use std::path::Path;
use std::process::Command;

fn obj_scene() -> String {
    format!("{CAMERA}\n[[mesh]]\nobj = \"m.obj\"\n")
}

const TRI_OBJ: &[u8] = b"mtllib m.mtl\nv -1 -1 0\nv 1 -1 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";

#[test]
fn short_mtl_colour_is_an_error_naming_the_mtl_line() {
    for (i, bad) in ["Kd 0.5", "Ka 1 1", "Kd", "Ke 0.1"].iter().enumerate() {
        // The bad colour sits in a material the OBJ does not even use.
        let mtl = format!("newmtl a\nKd 0.5 0.5 0.5\nnewmtl unused\n{bad}\n");
        let scene = obj_scene();
        expect_error(
            &format!("robust-mtl-{i}"),
            &[
                ("scene.toml", scene.as_bytes()),
                ("m.obj", TRI_OBJ),
                ("m.mtl", mtl.as_bytes()),
            ],
            &["render", "scene.toml", "-o", "out.png"],
            &[
                "scene.toml",
                "m.mtl",
                "line 4",
                bad.split(' ').next().unwrap(),
            ],
        );
    }
}

fn sphere_scene() -> String {
    format!("{CAMERA}\n[[mesh]]\nsphere = {{ radius = 1.0, segments = 16, rings = 8 }}\n")
}

const MTL: &[u8] = b"newmtl a\nKd 0.5 0.5 0.5\n";

#[test]
fn outputs_may_not_overwrite_the_mtl() {
    let scene = obj_scene();
    for (i, args) in [
        ["-o", "m.mtl"].as_slice(),
        &["-o", "out.png", "--stats-json", "m.mtl"],
        &["-o", "out.png", "--aov", "id=./m.mtl"],
    ]
    .iter()
    .enumerate()
    {
        let mut all = vec!["render", "scene.toml"];
        all.extend_from_slice(args);
        let name = format!("robust-mtl-out-{i}");
        expect_error(
            &name,
            &[
                ("scene.toml", scene.as_bytes()),
                ("m.obj", TRI_OBJ),
                ("m.mtl", MTL),
            ],
            &all,
            &["m.mtl", "input"],
        );
        let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(&name);
        assert_eq!(std::fs::read(dir.join("m.mtl")).unwrap(), MTL);
    }
}

#[test]
fn two_outputs_with_one_path_are_refused() {
    let scene = sphere_scene();
    expect_error(
        "robust-dup-out",
        &[("scene.toml", scene.as_bytes())],
        &[
            "render",
            "scene.toml",
            "-o",
            "a.exr",
            "--exr",
            "a.exr",
            "--aov",
            "depth=a.exr",
        ],
        &["--exr a.exr", "same file as -o a.exr"],
    );
}

#[test]
fn every_output_path_is_checked_before_rendering() {
    let scene = sphere_scene();
    expect_error(
        "robust-stats-nowhere",
        &[("scene.toml", scene.as_bytes())],
        &[
            "render",
            "scene.toml",
            "-o",
            "out.png",
            "--stats-json",
            "missing-folder/s.json",
        ],
        &["--stats-json", "missing-folder"],
    );
}

#[test]
fn a_symlinked_output_is_written_through_and_kept() {
    let scene = sphere_scene();
    let dir = temp_dir("robust-symlink");
    std::fs::write(dir.join("scene.toml"), &scene).unwrap();
    std::fs::write(dir.join("real.png"), b"old").unwrap();
    std::os::unix::fs::symlink("real.png", dir.join("link.png")).unwrap();
    let out = specula(&["render", "scene.toml", "-o", "link.png"], &dir);
    assert!(out.status.success(), "{}", stderr(&out));
    let meta = std::fs::symlink_metadata(dir.join("link.png")).unwrap();
    assert!(meta.is_symlink(), "the link was replaced by a file");
    let png = image::open(dir.join("real.png")).expect("the target holds the image");
    assert_eq!((png.width(), png.height()), (32, 24));
}

#[test]
fn a_fifo_output_is_written_through_and_kept() {
    use std::io::Read;
    use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
    let scene = sphere_scene();
    let dir = temp_dir("robust-fifo");
    std::fs::write(dir.join("scene.toml"), &scene).unwrap();
    let fifo = dir.join("pipe.png");
    let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
    assert!(made.success());
    // Open the reading end without blocking (O_NONBLOCK = 0o4000 on Linux), so
    // specula's open for writing finds a reader; the image (a few kB) fits
    // in the pipe's buffer.
    let mut reader = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(0o4000)
        .open(&fifo)
        .unwrap();
    let out = specula(&["render", "scene.toml", "-o", "pipe.png"], &dir);
    assert!(out.status.success(), "{}", stderr(&out));
    let ft = std::fs::symlink_metadata(&fifo).unwrap().file_type();
    assert!(ft.is_fifo(), "the FIFO was replaced");
    let mut bytes = Vec::new();
    let _ = reader.read_to_end(&mut bytes);
    let png = image::load_from_memory(&bytes).expect("a PNG came through the pipe");
    assert_eq!((png.width(), png.height()), (32, 24));
}

#[test]
fn a_full_device_reports_no_space() {
    if !Path::new("/dev/full").exists() {
        return;
    }
    let scene = sphere_scene();
    let err = expect_error(
        "robust-dev-full",
        &[("scene.toml", scene.as_bytes())],
        &["render", "scene.toml", "-o", "/dev/full"],
        &["/dev/full", "cannot write", "space"],
    );
    let meta = std::fs::symlink_metadata("/dev/full").unwrap();
    use std::os::unix::fs::FileTypeExt;
    assert!(meta.file_type().is_char_device(), "{err}");
}

#[test]
fn the_extension_names_the_format_or_is_refused() {
    let scene = sphere_scene();
    let dir = temp_dir("robust-ext");
    std::fs::write(dir.join("scene.toml"), &scene).unwrap();
    for (name, format) in [
        ("out.jpg", image::ImageFormat::Jpeg),
        ("out.tiff", image::ImageFormat::Tiff),
        ("out.bmp", image::ImageFormat::Bmp),
    ] {
        let out = specula(&["render", "scene.toml", "-o", name], &dir);
        assert!(out.status.success(), "{name}: {}", stderr(&out));
        let bytes = std::fs::read(dir.join(name)).unwrap();
        assert_eq!(image::guess_format(&bytes).unwrap(), format, "{name}");
    }
    expect_error(
        "robust-ext-unknown",
        &[("scene.toml", scene.as_bytes())],
        &["render", "scene.toml", "-o", "out.xyz"],
        &["-o out.xyz", "cannot write", "png"],
    );
    expect_error(
        "robust-ext-exr-flag",
        &[("scene.toml", scene.as_bytes())],
        &["render", "scene.toml", "-o", "out.png", "--exr", "hdr.png"],
        &["--exr hdr.png", ".exr"],
    );
    expect_error(
        "robust-ext-furnace",
        &[],
        &["furnace", "--alpha", "0.5", "-o", "plot.exr"],
        &["plot.exr", ".png"],
    );
}

#[test]
fn dash_writes_png_to_standard_output() {
    let scene = sphere_scene();
    let (out, dir) = run_in(
        "robust-stdout",
        &[("scene.toml", scene.as_bytes())],
        &["render", "scene.toml", "-o", "-", "--stats"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let png = image::load_from_memory_with_format(&out.stdout, image::ImageFormat::Png)
        .expect("stdout is one PNG");
    assert_eq!((png.width(), png.height()), (32, 24));
    assert!(
        stderr(&out).contains("pass times"),
        "--stats goes to stderr"
    );
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        1,
        "no file named -"
    );
}

fn load_ok(toml: &str) -> specula::scene::LoadedScene {
    let read = |_: &Path| -> std::io::Result<Vec<u8>> { Err(std::io::ErrorKind::NotFound.into()) };
    specula::scene::load_scene_str(Path::new("s.toml"), toml, &read)
        .unwrap_or_else(|e| panic!("{e}\n{toml}"))
}

#[test]
fn shape_sizes_fov_and_transforms_are_checked() {
    let mesh = |m: &str| format!("{CAMERA}\n[[mesh]]\n{m}\n");
    for (m, field) in [
        ("sphere = { radius = nan }", "mesh[0].sphere.radius"),
        ("sphere = { radius = inf }", "mesh[0].sphere.radius"),
        ("sphere = { radius = 0.0 }", "mesh[0].sphere.radius"),
        ("sphere = { radius = -1.0 }", "mesh[0].sphere.radius"),
        ("plane = { size = [nan, 1.0] }", "mesh[0].plane.size[0]"),
        ("plane = { size = [1.0, -2.0] }", "mesh[0].plane.size[1]"),
        ("cube = { size = nan }", "mesh[0].cube.size"),
        ("cube = { size = 0.0 }", "mesh[0].cube.size"),
        ("cube = { size = -1.0 }", "mesh[0].cube.size"),
        (
            "cube = {}\ntranslate = [1e30, 0.0, 0.0]",
            "mesh[0].translate",
        ),
        ("cube = {}\nscale = 1e30", "mesh[0].scale"),
        ("cube = {}\nscale = 1e10", "mesh[0].translate / scale"),
        ("cube = {}\nscale = 1e-40", "mesh[0].scale"),
        ("cube = {}\nscale = [1.0, 1e13, 1.0]", "mesh[0].scale"),
    ] {
        let e = load_err(&mesh(m));
        assert!(e.contains("s.toml") && e.contains(field), "{m}: {e}");
    }
    let e = load_err(&CAMERA.replace("fov_y = 45.0", "fov_y = 1e-30"));
    assert!(
        e.contains("camera.fov_y") && e.contains("[0.001, 179]"),
        "{e}"
    );
    let e = load_err(&CAMERA.replace("[2.0, 2.0, 2.0]", "[1e20, 4.0, 3.0]"));
    assert!(e.contains("light[0].position") && e.contains("1e9"), "{e}");
    // In range: accepted.
    load_ok(&mesh("cube = { size = 2.0 }\ntranslate = [1e6, 0.0, 0.0]"));
}

#[test]
fn huge_finite_directions_are_accepted() {
    let toml = format!(
        "{CAMERA}\n[[light]]\ntype = \"directional\"\ndirection = [3e38, -3e38, 0.0]\nirradiance = [1.0, 1.0, 1.0]\n"
    );
    let s = load_ok(&toml);
    let specula::core::light::Light::Directional { to_light, .. } = s.data.lights[1] else {
        panic!("a directional light");
    };
    let h = std::f32::consts::FRAC_1_SQRT_2;
    assert!(
        (to_light[0] + h).abs() < 1e-6 && (to_light[1] - h).abs() < 1e-6,
        "{to_light:?}"
    );
}

const LAMBERT: &str =
    r#"{"material":{"model":"lambert","base_color":[1,1,1]},"wi":[0,0,1],"wo":[0,0,1]}"#;

#[test]
fn eval_answers_a_non_utf8_line_and_goes_on() {
    let mut input = Vec::new();
    input.extend_from_slice(LAMBERT.as_bytes());
    input.extend_from_slice(b"\n\xff\xfe{\"wi\": \xc3\n\x00\x01\x02\r\n");
    input.extend_from_slice(LAMBERT.as_bytes());
    input.push(b'\n');
    let (ok, _, lines) = eval_bytes(&input);
    assert!(ok);
    assert_eq!(lines.len(), 4, "{lines:?}");
    let e = lines[1]["error"].as_str().expect("an error");
    assert!(e.starts_with("line 2:") && e.contains("UTF-8"), "{e}");
    assert!(lines[2]["error"].as_str().unwrap().starts_with("line 3:"));
    let f = lines[3]["f"][0].as_f64().unwrap();
    assert!(
        (f - std::f64::consts::FRAC_1_PI).abs() < 1e-12,
        "line 4 is answered: {f}"
    );
}

fn ggx(alpha: &str) -> String {
    format!(
        r#"{{"material":{{"model":"microfacet","ndf":"ggx","alpha":{alpha},"fresnel":{{"type":"schlick","f0":[1,1,1]}}}},"wi":[0.3,0,1],"wo":[-0.3,0,1]}}"#
    )
}

#[test]
fn eval_warns_about_a_clamped_alpha_and_refuses_a_negative_one() {
    let input = [
        ggx("0"),
        ggx("1e-30"),
        ggx("1e30"),
        ggx("0.5"),
        ggx("-1"),
        ggx("0"),
    ]
    .join("\n");
    let (ok, _, lines) = eval_bytes(input.as_bytes());
    assert!(ok);
    for (i, want) in [
        (0, "clamped to 0.001"),
        (1, "clamped to 0.001"),
        (2, "clamped to 1 "),
        (5, "clamped to 0.001"),
    ] {
        let w = lines[i]["warning"]
            .as_str()
            .unwrap_or_else(|| panic!("line {}: {}", i + 1, lines[i]));
        assert!(w.starts_with("material.alpha") && w.contains(want), "{w}");
        assert!(lines[i]["f"].is_array());
    }
    assert!(lines[3].get("warning").is_none(), "{}", lines[3]);
    let e = lines[4]["error"].as_str().unwrap();
    assert!(
        e.contains("line 5") && e.contains("alpha") && e.contains("≥ 0"),
        "{e}"
    );
}

#[test]
fn furnace_refuses_a_negative_alpha_and_labels_a_clamped_one() {
    let dir = temp_dir("robust-furnace-alpha");
    let out = specula(&["furnace", "--alpha=-1"], &dir);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(err.contains("--alpha -1") && err.contains("≥ 0"), "{err}");
    assert!(out.stdout.is_empty(), "no rows for a refused alpha");
    let out = specula(&["furnace", "--alpha=0"], &dir);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("clamped"), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    let row = text.lines().nth(1).unwrap();
    assert!(
        row.starts_with("0.001\t"),
        "rows carry the α they were computed at: {row}"
    );
}

#[test]
fn obj_and_mtl_errors_name_file_and_line() {
    let scene = obj_scene();
    for (i, (obj, needle)) in [
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5\nf 1 2 3\n",
            "vt needs two numbers",
        ),
        ("v 0 0 0\nv 1 0 0 0\nv 0 1 0\nf 1 2 3\n", "weight w"),
        (
            "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0\nf 1 2 3\n",
            "vertex colour",
        ),
    ]
    .iter()
    .enumerate()
    {
        let line = if i == 0 {
            "line 4"
        } else if i == 1 {
            "line 2"
        } else {
            "line 3"
        };
        expect_error(
            &format!("robust-obj-line-{i}"),
            &[("scene.toml", scene.as_bytes()), ("m.obj", obj.as_bytes())],
            &["render", "scene.toml", "-o", "out.png"],
            &["scene.toml", "mesh[0].obj", "m.obj", line, needle],
        );
    }
    expect_error(
        "robust-mtl-line",
        &[
            ("scene.toml", scene.as_bytes()),
            ("m.obj", TRI_OBJ),
            ("m.mtl", b"newmtl a\nKd 1 1 1\n\nillum two\n"),
        ],
        &["render", "scene.toml", "-o", "out.png"],
        &["m.mtl", "line 4", "illum"],
    );
}

#[test]
fn dropped_point_and_line_faces_are_reported() {
    let scene = obj_scene();
    let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\nf 1\nf 1 2 3\n";
    let (out, _) = run_in(
        "robust-dropped-faces",
        &[("scene.toml", scene.as_bytes()), ("m.obj", obj)],
        &["render", "scene.toml", "-o", "out.png"],
    );
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("warning")
            && err.contains("m.obj")
            && err.contains("2 faces with fewer than 3 corners"),
        "{err}"
    );
}

#[test]
fn image_size_errors_name_the_file_field_or_flag() {
    let scene = sphere_scene().replace("width = 32", "width = 100000");
    expect_error(
        "robust-width-scene",
        &[("scene.toml", scene.as_bytes())],
        &["render", "scene.toml", "-o", "out.png"],
        &["scene.toml", "output.width", "100000"],
    );
    let scene = sphere_scene();
    expect_error(
        "robust-width-flag",
        &[("scene.toml", scene.as_bytes())],
        &["render", "scene.toml", "-o", "out.png", "--width", "100000"],
        &["--width 100000", "scene.toml: output.height"],
    );
}

#[test]
fn a_huge_bad_value_is_not_echoed_whole() {
    let big = "x".repeat(5 << 20);
    let scene = sphere_scene().replace(
        "height = 24\n",
        &format!("height = 24\ntonemap = \"{big}\"\n"),
    );
    let err = expect_error(
        "robust-huge-echo",
        &[("scene.toml", scene.as_bytes())],
        &["render", "scene.toml", "-o", "out.png"],
        &["scene.toml", "tonemap"],
    );
    assert!(err.len() < 20_000, "stderr is {} bytes", err.len());
    let line = format!("{{\"material\":{{\"model\":\"{big}\"}},\"wi\":[0,0,1],\"wo\":[0,0,1]}}\n");
    let (ok, _, lines) = eval_bytes(line.as_bytes());
    assert!(ok);
    let e = lines[0]["error"].as_str().unwrap();
    assert!(
        e.starts_with("line 1:") && e.len() < 5_000,
        "{} bytes",
        e.len()
    );
}

/// Renders `toml` through the library (SIMD or scalar path) and counts the
/// non-finite values of the linear HDR image.
fn non_finite_pixels(toml: &str, scalar: bool, ssaa: u32) -> usize {
    use specula::raster::frame::ShadePath;
    let scene = load_ok(toml);
    let mut settings = specula::render::RenderSettings::from_scene(&scene);
    settings.ssaa = ssaa;
    settings.threads = Some(1);
    settings.path = if scalar {
        ShadePath::Scalar
    } else {
        ShadePath::Simd
    };
    let r = specula::render::render_scene(&scene, &settings, 0.0).expect("renders");
    r.hdr()
        .iter()
        .filter(|p| !p.iter().all(|c| c.is_finite()))
        .count()
}

fn material_scene(material: &str) -> String {
    format!(
        "{}\n[[mesh]]\nsphere = {{ radius = 1.0, segments = 32, rings = 16 }}\nmaterial = \"m\"\n[materials.m]\n{material}\n",
        CAMERA.replace("width = 32\nheight = 24", "width = 64\nheight = 48")
    )
}

#[test]
fn extreme_materials_render_finite_or_are_refused() {
    for gamma in ["40", "100", "1e6"] {
        let toml = material_scene(&format!(
            "model = \"microfacet\"\nndf = \"gtr\"\ngamma = {gamma}\nalpha = 0.5\nfresnel = {{ type = \"schlick\", f0 = [1, 1, 1] }}"
        ));
        for scalar in [false, true] {
            let bad = non_finite_pixels(&toml, scalar, 1);
            assert_eq!(
                bad, 0,
                "GTR gamma {gamma} (scalar {scalar}): {bad} non-finite pixels"
            );
        }
    }
    for (eta, k) in [
        ("[1e10, 1.0, 1.0]", "[1.0, 1.0, 1.0]"),
        ("[1.0, 1.0, 1.0]", "[1.0, 1e10, 1.0]"),
    ] {
        let toml = material_scene(&format!(
            "model = \"microfacet\"\nndf = \"ggx\"\nalpha = 0.5\nfresnel = {{ type = \"conductor\", eta = {eta}, k = {k} }}"
        ));
        let e = load_err(&toml);
        assert!(e.contains("fresnel.") && e.contains("1e4"), "{e}");
    }
    // The largest accepted values render finite, in f32 and f32x8.
    for fresnel in [
        "{ type = \"conductor\", eta = [1e4, 1.0, 1.0], k = [1.0, 1e4, 0.0] }",
        "{ type = \"dielectric\", ior = 1e4 }",
    ] {
        let toml = material_scene(&format!(
            "model = \"microfacet\"\nndf = \"ggx\"\nalpha = 0.5\nfresnel = {fresnel}"
        ));
        for scalar in [false, true] {
            let bad = non_finite_pixels(&toml, scalar, 1);
            assert_eq!(bad, 0, "{fresnel}: {bad} non-finite pixels");
        }
    }
    let toml = material_scene(
        "model = \"microfacet\"\nndf = \"ggx\"\nalpha = 0.5\nfresnel = { type = \"dielectric\", ior = 1e20 }",
    );
    assert!(load_err(&toml).contains("fresnel.ior"));
}

#[test]
fn eval_is_finite_for_extreme_gamma_and_nearly_opposite_grazing_directions() {
    let materials = [
        r#"{"model":"microfacet","ndf":"ggx","alpha":0.5,"fresnel":{"type":"schlick","f0":[1,1,1]}}"#,
        r#"{"model":"microfacet","ndf":"beckmann","alpha":0.5,"smith":"separable","fresnel":{"type":"dielectric","ior":1.5}}"#,
        r#"{"model":"microfacet","ndf":"gtr","gamma":1e6,"alpha":0.5,"fresnel":{"type":"conductor","eta":[0.2,0.9,1.1],"k":[3,2.5,2.2]}}"#,
        r#"{"model":"microfacet","ndf":"gtr","gamma":500,"alpha":0.5,"fresnel":{"type":"schlick","f0":[1,1,1]}}"#,
        r#"{"model":"microfacet","ndf":"gtr","gamma":40,"alpha":0.01,"fresnel":{"type":"schlick","f0":[1,1,1]}}"#,
        r#"{"model":"metallic_roughness","base_color":[1,0.5,0.2],"roughness":0.5,"metallic":1}"#,
    ];
    let dirs = [
        ("[0.3, 0, 1]", "[-0.2, 0.1, 1]"),
        ("[1, 0, 1e-155]", "[-1, 0, 1e-155]"),
        ("[1, 0, 1e-300]", "[-1, 1e-300, 1e-300]"),
        ("[1, 0, 1e-20]", "[-1, 0, 1e-20]"),
    ];
    let mut input = String::new();
    for m in materials {
        for (wi, wo) in dirs {
            input += &format!("{{\"material\":{m},\"wi\":{wi},\"wo\":{wo}}}\n");
        }
    }
    let (ok, _, lines) = eval_bytes(input.as_bytes());
    assert!(ok);
    assert_eq!(lines.len(), materials.len() * dirs.len());
    for (i, l) in lines.iter().enumerate() {
        let f = l["f"]
            .as_array()
            .unwrap_or_else(|| panic!("line {}: {l}", i + 1));
        assert!(
            f.iter()
                .all(|v| v.as_f64().is_some_and(|x| x.is_finite() && x >= 0.0)),
            "line {}: {l}",
            i + 1
        );
    }
}

#[test]
fn huge_radiometric_values_are_refused_and_the_largest_accepted_stay_finite() {
    let sphere = "\n[[mesh]]\nsphere = { radius = 1.0, segments = 16, rings = 8 }\n";
    let env = |v: &str| format!("{CAMERA}{sphere}\n[environment]\nuniform = [{v}, {v}, {v}]\n");
    let e = load_err(&env("3e38"));
    assert!(
        e.contains("environment.uniform") && e.contains("1e20"),
        "{e}"
    );
    let bad = non_finite_pixels(&env("1e20"), false, 4);
    assert_eq!(bad, 0, "environment 1e20, ssaa 4");
    let light = CAMERA.replace("[10.0, 10.0, 10.0]", "[1e20, 1e20, 1e20]");
    assert_eq!(non_finite_pixels(&format!("{light}{sphere}"), false, 4), 0);
    let far = CAMERA.replace("[2.0, 2.0, 2.0]", "[1e9, 4.0, 3.0]");
    assert_eq!(
        non_finite_pixels(&format!("{far}{sphere}"), false, 1),
        0,
        "light at 1e9"
    );
    let e = load_err(&CAMERA.replace("[10.0, 10.0, 10.0]", "[1e21, 0.0, 0.0]"));
    assert!(e.contains("light[0].intensity"), "{e}");
}

#[test]
fn memory_estimates_refuse_what_exceeds_the_limit() {
    let cube = format!("{CAMERA}\n[[mesh]]\ncube = {{ size = 1.0, segments = 4096 }}\n");
    expect_error(
        "robust-mem-cube",
        &[("scene.toml", cube.as_bytes())],
        &[
            "render",
            "scene.toml",
            "-o",
            "out.png",
            "--max-memory",
            "4G",
        ],
        &[
            "scene.toml",
            "mesh[0].cube (4096 segments)",
            "limit of 4.0 GB",
            "--max-memory",
        ],
    );
    let scene = sphere_scene();
    expect_error(
        "robust-mem-image",
        &[("scene.toml", scene.as_bytes())],
        &[
            "render",
            "scene.toml",
            "-o",
            "out.png",
            "--width",
            "16384",
            "--height",
            "16384",
            "--max-memory",
            "4G",
        ],
        &["16384×16384 image", "limit of 4.0 GB"],
    );
    let (out, _) = run_in(
        "robust-mem-bad-size",
        &[("scene.toml", scene.as_bytes())],
        &[
            "render",
            "scene.toml",
            "-o",
            "out.png",
            "--max-memory",
            "4X",
        ],
    );
    assert!(!out.status.success());
    assert!(stderr(&out).contains("--max-memory") && stderr(&out).contains("unit"));
    // Within the limit: renders.
    let (out, _) = run_in(
        "robust-mem-ok",
        &[("scene.toml", scene.as_bytes())],
        &[
            "render",
            "scene.toml",
            "-o",
            "out.png",
            "--max-memory",
            "256M",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
}
