//! Replays the committed fuzz corpus (fixtures/fuzz/<target>/: the
//! minimized corpus of each cargo-fuzz target and every input that once
//! crashed it, `crash-*`) through the same entry points the fuzzer ran
//! (specula::fuzzing), on stable, so CI keeps every case found. A broken
//! guarantee panics inside the entry point; the test names the file.
//! See docs/ROBUSTNESS.md for how the corpus is made and extended.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The scene targets share the process-wide memory budget: one at a time.
static BUDGET: Mutex<()> = Mutex::new(());

fn corpus(target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/fuzz")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    assert!(!files.is_empty(), "{}: no corpus", dir.display());
    files
}

/// Runs every corpus file of `target` through `f`, naming the file of
/// the first broken guarantee; prints how many were accepted.
fn replay(target: &str, f: fn(&[u8]) -> Result<(), String>) {
    let files = corpus(target);
    let mut accepted = 0;
    for p in &files {
        let data = std::fs::read(p).unwrap();
        match std::panic::catch_unwind(|| f(&data)) {
            Ok(r) => accepted += usize::from(r.is_ok()),
            Err(_) => panic!(
                "{target}: {} breaks a guarantee (the panic above says which); reproduce with \
                 `cargo +nightly fuzz run {target} {}` or this test",
                p.display(),
                p.display()
            ),
        }
    }
    eprintln!(
        "{target}: {} inputs, {accepted} accepted, the others refused with a message",
        files.len()
    );
}

#[test]
fn scene_toml_corpus() {
    let _one = BUDGET.lock().unwrap_or_else(|e| e.into_inner());
    replay("scene_toml", specula::fuzzing::scene_toml);
}

#[test]
fn obj_mtl_corpus() {
    let _one = BUDGET.lock().unwrap_or_else(|e| e.into_inner());
    replay("obj_mtl", specula::fuzzing::obj_mtl);
}

#[test]
fn gltf_corpus() {
    let _one = BUDGET.lock().unwrap_or_else(|e| e.into_inner());
    replay("gltf", specula::fuzzing::gltf);
}

#[test]
fn eval_line_corpus() {
    replay("eval_line", specula::fuzzing::eval_line);
}

#[test]
fn raster_corpus() {
    replay("raster", specula::fuzzing::raster);
}
