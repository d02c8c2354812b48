//! Robustness, second round: accepted ranges of the material core, memory
//! budgeted before decoding, oversized OBJ faces, outputs left whole by a
//! failure or an interrupt, and errors that name the field's line. Each
//! case once hung, rendered NaN, ran out of memory, lost a file, or
//! pointed at the wrong line.

mod common;

use common::cli::{expect_error, left_behind, load_err, no_files, run_in, stderr, CAMERA};
use common::{eval, specula, temp_dir};
use std::path::Path;

fn material_scene(material: &str) -> String {
    format!(
        "{CAMERA}\n[[mesh]]\nsphere = {{ radius = 1.0, segments = 32, rings = 16 }}\nmaterial = \"m\"\n[materials.m]\n{material}\n"
    )
}

/// Non-finite pixels of the scene's linear image, f32x8 and f32 paths.
fn non_finite_pixels(toml: &str) -> usize {
    let scene = specula::scene::load_scene_str(Path::new("s.toml"), toml, &no_files)
        .unwrap_or_else(|e| panic!("{e}\n{toml}"));
    [false, true]
        .into_iter()
        .map(|scalar| {
            let mut settings = specula::render::RenderSettings::from_scene(&scene);
            settings.threads = Some(1);
            if scalar {
                settings.path = specula::raster::frame::ShadePath::Scalar;
            }
            let r = specula::render::render_scene(&scene, &settings, 0.0).expect("renders");
            r.hdr()
                .iter()
                .filter(|p| !p.iter().all(|c| c.is_finite()))
                .count()
        })
        .sum()
}

fn gtr(gamma: &str, alpha: &str, exact: bool) -> String {
    let lambda = if exact {
        "gtr_lambda = \"exact\"\n"
    } else {
        ""
    };
    format!(
        "model = \"microfacet\"\nndf = \"gtr\"\ngamma = {gamma}\nalpha = {alpha}\nenergy_compensation = true\n{lambda}fresnel = {{ type = \"schlick\", f0 = [1, 1, 1] }}"
    )
}

#[test]
fn gtr_gamma_outside_its_range_is_refused_and_its_ends_render_finite() {
    for gamma in ["1e10", "1e30", "1e6001", "0", "-1", "nan"] {
        let e = load_err(&material_scene(&gtr(gamma, "1", false)));
        assert!(e.contains("gamma") && e.contains("1e6"), "{gamma}: {e}");
    }
    for gamma in ["1e6", "999999", "1e-3"] {
        for alpha in ["1", "0.5", "0.001"] {
            let toml = material_scene(&gtr(gamma, alpha, false));
            assert_eq!(non_finite_pixels(&toml), 0, "γ {gamma} α {alpha}");
        }
    }
}

#[test]
fn eval_refuses_gtr_gamma_outside_its_range_and_answers_at_its_ends() {
    let line = |gamma: &str, alpha: &str, exact: bool| {
        let lambda = if exact {
            r#","gtr_lambda":"exact""#
        } else {
            ""
        };
        format!(
            r#"{{"material":{{"model":"microfacet","ndf":"gtr","gamma":{gamma},"alpha":{alpha},"energy_compensation":true{lambda},"fresnel":{{"type":"schlick","f0":[1,1,1]}}}},"wi":[0.3,0,1],"wo":[-0.3,0,1]}}"#
        )
    };
    let mut input = String::new();
    for gamma in ["1e10", "1e30"] {
        for exact in [false, true] {
            input += &line(gamma, "1", exact);
            input.push('\n');
        }
    }
    let ends = [
        ("1e6", "1"),
        ("1e6", "0.5"),
        ("1e-3", "0.5"),
        ("1e-3", "0.001"),
    ];
    for (gamma, alpha) in ends {
        input += &line(gamma, alpha, true);
        input.push('\n');
    }
    let answers = eval(&input);
    assert_eq!(answers.len(), 4 + ends.len());
    for a in &answers[..4] {
        let e = a["error"].as_str().unwrap_or_else(|| panic!("{a}"));
        assert!(e.contains("gamma") && e.contains("1e6"), "{e}");
    }
    for a in &answers[4..] {
        let f = a["f"].as_array().unwrap_or_else(|| panic!("{a}"));
        assert!(
            f.iter()
                .all(|v| v.as_f64().is_some_and(|x| x.is_finite() && x >= 0.0)),
            "{a}"
        );
    }
}

fn disney(fields: &str) -> String {
    format!("model = \"disney\"\nbase_color = [0.8, 0.5, 0.3]\n{fields}")
}

#[test]
fn disney_roughness_sheen_and_clearcoat_have_upper_bounds_and_render_finite_at_them() {
    for (field, bad) in [
        ("roughness", "1e30"),
        ("roughness", "10.5"),
        ("sheen", "1e7"),
        ("clearcoat", "1e30"),
    ] {
        let e = load_err(&material_scene(&disney(&format!("{field} = {bad}"))));
        assert!(
            e.contains(field) && e.contains("must be ≤"),
            "{field} {bad}: {e}"
        );
    }
    for fields in [
        "roughness = 10.0",
        "roughness = 10.0\nanisotropic = 1.0",
        "roughness = 10.0\nsheen = 1e6\nclearcoat = 1e6\nclearcoat_gloss = 1.0",
        "roughness = 0.0\nsheen = 1e6\nclearcoat = 1e6",
    ] {
        let toml = material_scene(&disney(fields));
        assert_eq!(non_finite_pixels(&toml), 0, "{fields}");
    }
}

/// A PNG that is only a signature, a header (IHDR) of `w`×`h` RGB8 and an
/// empty IDAT: enough for a reader to learn the size, nothing to decode.
fn png_header_only(w: u32, h: u32) -> Vec<u8> {
    fn crc32(bytes: &[u8]) -> u32 {
        let mut c = !0u32;
        for &b in bytes {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }
    let mut chunk = b"IHDR".to_vec();
    chunk.extend(w.to_be_bytes());
    chunk.extend(h.to_be_bytes());
    chunk.extend([8, 2, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(13u32.to_be_bytes());
    png.extend(&chunk);
    png.extend(crc32(&chunk).to_be_bytes());
    for empty in [b"IDAT", b"IEND"] {
        png.extend(0u32.to_be_bytes());
        png.extend(empty);
        png.extend(crc32(empty).to_be_bytes());
    }
    png
}

#[test]
fn textures_are_sized_and_budgeted_from_their_header_before_decoding() {
    // Only headers: decoding either would fail with another message.
    let huge = png_header_only(8192, 8192);
    let big = png_header_only(2048, 2048);
    let scene = |file: &str| {
        material_scene(&format!(
            "model = \"lambert\"\nbase_color = [1, 1, 1]\nbase_color_texture = \"{file}\""
        ))
    };
    let args = |limit| {
        [
            "render",
            "scene.toml",
            "-o",
            "out.png",
            "--max-memory",
            limit,
        ]
    };
    expect_error(
        "limits-texture-too-large",
        &[
            ("scene.toml", scene("huge.png").as_bytes()),
            ("huge.png", &huge),
        ],
        &args("256M"),
        &["huge.png", "8192×8192", "too large"],
    );
    expect_error(
        "limits-texture-budget",
        &[
            ("scene.toml", scene("big.png").as_bytes()),
            ("big.png", &big),
        ],
        &args("64M"),
        &["big.png (2048×2048)", "--max-memory"],
    );
    // The same through an MTL's map_Kd.
    let obj = b"mtllib m.mtl\nv -1 -1 0\nv 1 -1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl a\nf 1/1 2/2 3/3\n";
    let mtl = b"newmtl a\nKd 1 1 1\nmap_Kd big.png\n";
    let scene = format!("{CAMERA}\n[[mesh]]\nobj = \"m.obj\"\n");
    expect_error(
        "limits-mtl-texture-budget",
        &[
            ("scene.toml", scene.as_bytes()),
            ("m.obj", obj),
            ("m.mtl", mtl),
            ("big.png", &big),
        ],
        &args("64M"),
        &["big.png (2048×2048)", "--max-memory"],
    );
}

#[test]
fn a_tonal_art_map_is_budgeted_from_its_manifest_before_any_image_is_read() {
    let dir = temp_dir("limits-tam-budget");
    std::fs::create_dir(dir.join("tam")).unwrap();
    let tones = 64;
    let darkness: Vec<f64> = (1..=tones).map(|t| t as f64 / tones as f64).collect();
    let manifest = serde_json::json!({
        "tones": tones,
        "levels": 1,
        "sizes": [8192],
        "darkness": darkness,
        "measured": vec![vec![0.5]; tones],
        "seed": 1,
        "stroke_width_px": 1.0,
    });
    std::fs::write(dir.join("tam/tam.json"), manifest.to_string()).unwrap();
    // Only headers: reading any image in full would fail differently.
    for t in 0..tones {
        std::fs::write(
            dir.join(format!("tam/tam_t{t}_l0.png")),
            png_header_only(8192, 8192),
        )
        .unwrap();
    }
    let scene = material_scene("model = \"hatching\"\ntam = \"tam\"");
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let out = specula(
        &[
            "render",
            "scene.toml",
            "-o",
            "out.png",
            "--max-memory",
            "1G",
        ],
        &dir,
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("tonal art map")
            && err.contains("64 tones of 8192×8192")
            && err.contains("--max-memory"),
        "{err}"
    );
    assert!(!dir.join("out.png").exists());
}

/// An OBJ of one polygon with `n` corners on a circle, visited `turns`
/// times (turns > 1 makes it self-intersecting).
fn ngon_obj(n: usize, turns: usize) -> String {
    let mut s = String::new();
    for k in 0..n {
        let a = std::f64::consts::TAU * (k * turns) as f64 / n as f64 + k as f64 * 1e-4;
        s += &format!("v {} {} 0\n", a.cos(), a.sin());
    }
    s += "f";
    for k in 1..=n {
        s += &format!(" {k}");
    }
    s.push('\n');
    s
}

#[test]
fn oversized_obj_faces_are_refused_naming_the_line_and_the_largest_loads() {
    let max = specula::objcheck::MAX_FACE_CORNERS;
    let scene = format!("{CAMERA}\n[[mesh]]\nobj = \"m.obj\"\n");
    for n in [max + 1, 1_000_000] {
        let obj = ngon_obj(n, 1);
        let line = format!("line {}", n + 1);
        expect_error(
            &format!("limits-face-{n}"),
            &[("scene.toml", scene.as_bytes()), ("m.obj", obj.as_bytes())],
            &["render", "scene.toml", "-o", "out.png"],
            &["m.obj", &line, &format!("{n} corners"), &max.to_string()],
        );
    }
    // The largest accepted face, convex and self-intersecting, loads.
    for turns in [1, 7] {
        let obj = ngon_obj(max, turns);
        let (out, dir) = run_in(
            &format!("limits-face-max-{turns}"),
            &[("scene.toml", scene.as_bytes()), ("m.obj", obj.as_bytes())],
            &["render", "scene.toml", "-o", "out.png"],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        assert!(dir.join("out.png").exists());
    }
}

const SPHERE: &str = "\n[[mesh]]\nsphere = { radius = 1.0, segments = 16, rings = 8 }\n";

#[test]
fn a_failing_later_output_leaves_the_earlier_files_as_they_were() {
    if !Path::new("/dev/full").exists() {
        return;
    }
    let scene = format!("{CAMERA}{SPHERE}");
    for extra in [
        &["--stats-json", "/dev/full"][..],
        &["--exr", "/dev/full"][..],
        &["--aov", "depth=/dev/full"][..],
    ] {
        let dir = temp_dir("limits-full-later");
        std::fs::write(dir.join("scene.toml"), &scene).unwrap();
        std::fs::write(dir.join("out.png"), b"previous").unwrap();
        let mut args = vec!["render", "scene.toml", "-o", "out.png"];
        args.extend_from_slice(extra);
        let out = specula(&args, &dir);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{extra:?}: {err}");
        assert!(err.contains("/dev/full"), "{err}");
        assert_eq!(
            std::fs::read(dir.join("out.png")).unwrap(),
            b"previous",
            "{extra:?} replaced -o"
        );
        assert_eq!(
            left_behind(&dir, &["scene.toml", "out.png"]),
            Vec::<String>::new()
        );
    }
}

#[test]
fn a_dangling_symlink_output_gets_its_target_written_and_stays_a_link() {
    let dir = temp_dir("limits-dangling-link");
    std::fs::write(dir.join("scene.toml"), format!("{CAMERA}{SPHERE}")).unwrap();
    std::fs::create_dir(dir.join("sub")).unwrap();
    // Relative targets are taken from the link's folder, through a chain.
    std::os::unix::fs::symlink("sub/hop.png", dir.join("link.png")).unwrap();
    std::os::unix::fs::symlink("real.png", dir.join("sub/hop.png")).unwrap();
    let out = specula(&["render", "scene.toml", "-o", "link.png"], &dir);
    assert!(out.status.success(), "{}", stderr(&out));
    for link in ["link.png", "sub/hop.png"] {
        assert!(std::fs::symlink_metadata(dir.join(link))
            .unwrap()
            .file_type()
            .is_symlink());
    }
    let png = std::fs::read(dir.join("sub/real.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG"));
    // A loop is refused, not followed forever.
    std::os::unix::fs::symlink("b.png", dir.join("a.png")).unwrap();
    std::os::unix::fs::symlink("a.png", dir.join("b.png")).unwrap();
    let out = specula(&["render", "scene.toml", "-o", "a.png"], &dir);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("symbolic link"), "{}", stderr(&out));
}

#[test]
fn sigint_while_writing_outputs_leaves_no_temporary_file() {
    use std::process::{Command, Stdio};
    let dir = temp_dir("limits-sigint");
    std::fs::write(dir.join("scene.toml"), format!("{CAMERA}{SPHERE}")).unwrap();
    let hidden = |dir: &Path| -> Vec<String> {
        left_behind(dir, &["scene.toml"])
            .into_iter()
            .filter(|n| n.starts_with('.'))
            .collect()
    };
    let mut caught = 0;
    for _ in 0..5 {
        let mut child = Command::new(env!("CARGO_BIN_EXE_specula"))
            .args([
                "render",
                "scene.toml",
                "-o",
                "out.png",
                "--exr",
                "out.exr",
                "--aov",
                "depth=depth.exr",
                "--aov",
                "normal=normal.exr",
                "--width",
                "2048",
                "--height",
                "2048",
                "--threads",
                "1",
            ])
            .current_dir(&dir)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Wait for a temporary output file to appear, then interrupt.
        let seen = loop {
            if !hidden(&dir).is_empty() {
                break true;
            }
            if child.try_wait().unwrap().is_some() {
                break false;
            }
            std::thread::sleep(std::time::Duration::from_micros(200));
        };
        if seen {
            let _ = Command::new("kill")
                .args(["-INT", &child.id().to_string()])
                .status();
        }
        let status = child.wait().unwrap();
        if seen && status.code() == Some(130) {
            caught += 1;
        }
        assert_eq!(hidden(&dir), Vec::<String>::new(), "after {status:?}");
    }
    assert!(caught > 0, "no run was interrupted while writing");
}

fn field_error(toml: &str, needles: &[&str]) {
    let e = load_err(toml);
    for n in needles {
        assert!(e.contains(n), "lacks {n:?}:\n{e}");
    }
}

/// The 1-based line of `text` that starts with `start` (the last such).
fn line_of(text: &str, start: &str) -> String {
    let n = text
        .lines()
        .collect::<Vec<_>>()
        .iter()
        .rposition(|l| l.starts_with(start))
        .expect("line present");
    format!("line {}", n + 1)
}

#[test]
fn errors_inside_materials_and_lights_name_the_field_and_its_line() {
    for (material, field) in [
        (disney("roughness = \"rough\""), "roughness"),
        (disney("rougness = 0.5"), "rougness"),
        (gtr("[2]", "0.5", false), "gamma"),
        (
            "model = \"lambert\"\nbase_color = [1, 1]".to_string(),
            "base_color",
        ),
        (
            "model = \"toon\"\nbase_color = [1, 1, 1]\nbands = -3".to_string(),
            "bands",
        ),
    ] {
        let toml = material_scene(&material);
        let line = line_of(&toml, field);
        field_error(&toml, &[&line, &format!("materials.m.{field}")]);
    }
    for (light, field) in [
        (
            "type = \"point\"\nposition = [1, 2]\nintensity = [1, 1, 1]",
            "position",
        ),
        (
            "type = \"spot\"\nposition = [0, 0, 2]\ndirection = [0, 0, -1]\nintensity = [1, 1, 1]\nouter_cone = \"wide\"",
            "outer_cone",
        ),
        (
            "type = \"directional\"\ndirection = [0, 0, -1]\nirradiance = [1, 1, 1]\ncolour = [1, 1, 1]",
            "colour",
        ),
    ] {
        let toml = format!("{CAMERA}{SPHERE}\n[[light]]\n{light}\n");
        let line = line_of(&toml, field);
        field_error(&toml, &[&line, &format!("light[1].{field}")]);
    }
    // A missing field stays at the table's header, naming the table.
    let toml = material_scene("model = \"microfacet\"\nndf = \"ggx\"");
    field_error(&toml, &["missing field `alpha`", "materials.m"]);
}

#[test]
fn reference_area_lights_take_beckmann_and_gtr_which_ltc_refuses() {
    let light = "\n[[light]]\ntype = \"polygon\"\nvertices = [[-1, 2, -1], [1, 2, -1], [1, 2, 1], [-1, 2, 1]]\nradiance = [1, 1, 1]\nvisible = false\n";
    for ndf in ["ndf = \"beckmann\"", "ndf = \"gtr\"\ngamma = 3"] {
        let material = format!(
            "model = \"microfacet\"\n{ndf}\nalpha = 0.3\nfresnel = {{ type = \"schlick\", f0 = [0.9, 0.9, 0.9] }}"
        );
        let base = format!("{}{light}", material_scene(&material));
        let e = load_err(&base);
        assert!(e.contains("ndf = \"ggx\""), "{e}");
        let reference = format!("{base}\n[render]\narea_lights = \"reference\"\n");
        assert_eq!(non_finite_pixels(&reference), 0, "{ndf}");
    }
}

#[test]
fn sigint_while_a_tonal_art_map_is_made_leaves_no_staging_folder() {
    use std::process::{Command, Stdio};
    let dir = temp_dir("limits-sigint-tam");
    let mut child = Command::new(env!("CARGO_BIN_EXE_specula"))
        .args(["tam", "-o", "map", "--tones", "6", "--size", "512"])
        .current_dir(&dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let seen = loop {
        if !left_behind(&dir, &[]).is_empty() {
            break true;
        }
        if child.try_wait().unwrap().is_some() {
            break false;
        }
        std::thread::sleep(std::time::Duration::from_micros(200));
    };
    assert!(seen, "the staging folder never appeared");
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let status = child.wait().unwrap();
    let left = left_behind(&dir, &[]);
    // Interrupted while generating (130), or done just before: then only
    // the finished map is there.
    match status.code() {
        Some(130) => assert_eq!(left, Vec::<String>::new()),
        _ => assert_eq!(left, ["map"], "{status:?}"),
    }
}

/// A tonal art map's files are inputs of the render: `-o`, `--stats-json`
/// or an AOV naming one is refused, and the map still loads afterwards.
#[test]
fn outputs_may_not_overwrite_a_tonal_art_map() {
    let dir = temp_dir("limits-tam-inputs");
    let made = specula(&["tam", "-o", "map", "--tones", "4", "--size", "64"], &dir);
    assert!(made.status.success(), "{}", stderr(&made));
    std::fs::write(
        dir.join("scene.toml"),
        material_scene("model = \"hatching\"\ntam = \"map\""),
    )
    .unwrap();
    let snapshot = |d: &Path| -> Vec<(String, Vec<u8>)> {
        let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(d.join("map"))
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                (
                    e.file_name().to_string_lossy().into_owned(),
                    std::fs::read(e.path()).unwrap(),
                )
            })
            .collect();
        v.sort();
        v
    };
    let before = snapshot(&dir);
    let tone = before
        .iter()
        .map(|(n, _)| n.clone())
        .find(|n| n.ends_with(".png"))
        .expect("a tone image");
    let tone = format!("map/{tone}");
    for args in [
        vec!["render", "scene.toml", "-o", tone.as_str()],
        vec![
            "render",
            "scene.toml",
            "-o",
            "out.png",
            "--stats-json",
            "map/tam.json",
        ],
        vec![
            "render",
            "scene.toml",
            "-o",
            "out.png",
            "--exr",
            tone.as_str(),
        ],
    ] {
        let out = specula(&args, &dir);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains("refusing to overwrite"), "{args:?}: {err}");
        assert_eq!(snapshot(&dir), before, "{args:?} changed the map");
    }
    let ok = specula(&["render", "scene.toml", "-o", "out.png"], &dir);
    assert!(ok.status.success(), "the map still loads: {}", stderr(&ok));
}
