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
pub mod gltf_doc;
