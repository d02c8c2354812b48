//! The command line driven as a user would: scene files written into a
//! fresh folder, `specula` run there, its failure and what it left
//! behind checked.

use super::{specula, temp_dir};
use std::path::Path;
use std::process::Output;

/// A camera, a small image and one point light: a scene's first tables.
pub const CAMERA: &str = r#"
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

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Writes `files` into a fresh folder and runs specula there.
pub fn run_in(name: &str, files: &[(&str, &[u8])], args: &[&str]) -> (Output, std::path::PathBuf) {
    let dir = temp_dir(name);
    for (n, b) in files {
        std::fs::write(dir.join(n), b).unwrap();
    }
    (specula(args, &dir), dir)
}

/// The folder's entries other than `files`, sorted.
pub fn left_behind(dir: &Path, files: &[&str]) -> Vec<String> {
    let mut left: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !files.contains(&n.as_str()))
        .collect();
    left.sort();
    left
}

/// Expects exit status 1 without a panic, every needle in stderr, and no
/// file left in the folder other than `files`.
pub fn expect_error(
    name: &str,
    files: &[(&str, &[u8])],
    args: &[&str],
    needles: &[&str],
) -> String {
    let (out, dir) = run_in(name, files, args);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{name}: exit code: {err}");
    assert!(!err.contains("panicked"), "{name}: panicked: {err}");
    for n in needles {
        assert!(err.contains(n), "{name}: stderr lacks {n:?}: {err}");
    }
    let names: Vec<&str> = files.iter().map(|(f, _)| *f).collect();
    let left = left_behind(&dir, &names);
    assert!(left.is_empty(), "{name}: left files behind: {left:?}");
    err
}

pub fn no_files(_: &Path) -> std::io::Result<Vec<u8>> {
    Err(std::io::ErrorKind::NotFound.into())
}

pub fn load_err(toml: &str) -> String {
    match specula::scene::load_scene_str(Path::new("s.toml"), toml, &no_files) {
        Ok(_) => panic!("accepted:\n{toml}"),
        Err(e) => e.to_string(),
    }
}
