//! Robustness on bad input (issue 13): every case here once crashed, lost a
//! file, or was accepted silently. Each expects a clear message naming the
//! file and line or field, a non-zero exit, no panic, and no stray files.

mod common;

use common::temp_dir;
use std::path::Path;
use std::process::{Command, Output};

fn specula(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_specula"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run specula")
}

const CAMERA: &str = r#"
[camera]
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
fov_y = 45.0
near = 0.1
far = 10.0

[output]
width = 32
height = 24

[[light]]
type = "point"
position = [2.0, 2.0, 2.0]
intensity = [10.0, 10.0, 10.0]
"#;

/// Writes `files` into a fresh folder and runs specula there.
fn run_in(name: &str, files: &[(&str, &[u8])], args: &[&str]) -> (Output, std::path::PathBuf) {
    let dir = temp_dir(name);
    for (n, b) in files {
        std::fs::write(dir.join(n), b).unwrap();
    }
    (specula(args, &dir), dir)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Expects failure without a panic, with every needle in stderr, and no
/// file in the folder other than `files`.
fn expect_error(name: &str, files: &[(&str, &[u8])], args: &[&str], needles: &[&str]) -> String {
    let (out, dir) = run_in(name, files, args);
    let err = stderr(&out);
    assert!(!out.status.success(), "{name}: expected failure: {err}");
    assert_eq!(out.status.code(), Some(1), "{name}: exit code: {err}");
    assert!(!err.contains("panicked"), "{name}: panicked: {err}");
    for n in needles {
        assert!(err.contains(n), "{name}: stderr lacks {n:?}: {err}");
    }
    let mut left: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !files.iter().any(|(f, _)| f == n))
        .collect();
    left.sort();
    assert!(left.is_empty(), "{name}: left files behind: {left:?}");
    err
}

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
