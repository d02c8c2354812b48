//! Helpers shared by the end-to-end tests.
#![allow(dead_code)]

use specula::scene::{load_scene_str, LoadedScene};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Loads a scene from TOML text; `files` supplies the files it names.
pub fn scene(toml: &str, files: &[(&str, &str)]) -> LoadedScene {
    let files: Vec<(String, String)> = files
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    let read = move |p: &Path| -> std::io::Result<Vec<u8>> {
        files
            .iter()
            .find(|(n, _)| Path::new(n) == p)
            .map(|(_, b)| b.clone().into_bytes())
            .ok_or_else(|| std::io::ErrorKind::NotFound.into())
    };
    load_scene_str(Path::new("test.toml"), toml, &read).unwrap_or_else(|e| panic!("{e}"))
}

pub fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures")
}

/// A fresh empty folder under the target directory.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// Runs the `specula` binary of this build with `args` in `dir`.
pub fn specula(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_specula"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run specula")
}
pub mod cli;

/// Runs `specula eval` on `input` (any bytes): whether it exited with
/// success, its stderr, and its answer lines, each parsed as one JSON
/// object. The input is written from its own thread, so a long one
/// cannot stall on a full output pipe.
pub fn eval_bytes(input: &[u8]) -> (bool, String, Vec<serde_json::Value>) {
    use std::io::Write;
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_specula"))
        .arg("eval")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run specula eval");
    let mut stdin = child.stdin.take().expect("a stdin pipe");
    let input = input.to_vec();
    let writer = std::thread::spawn(move || stdin.write_all(&input));
    let out = child.wait_with_output().expect("specula eval ends");
    // A write error (eval gone) shows in the status and answers instead.
    let _ = writer.join();
    let lines = String::from_utf8(out.stdout)
        .expect("answers are UTF-8")
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
        lines,
    )
}

/// Runs `specula eval` on `input`, which must exit with success: its
/// answer lines.
pub fn eval(input: &str) -> Vec<serde_json::Value> {
    let (ok, stderr, lines) = eval_bytes(input.as_bytes());
    assert!(ok, "specula eval failed: {stderr}");
    lines
}
pub mod gltf_doc;
pub mod mutate;
