//! `specula batch`: shards merge into the unsharded result, resumption
//! skips what is current and redoes what changed, and `diff --dir` pairs
//! two batch folders.

mod common;

use common::{fixtures, specula, temp_dir};
use specula::batch::{read_manifest, run, BatchArgs, Record};
use std::path::{Path, PathBuf};

fn fixture_scenes() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(fixtures().join("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    v
}

fn args(scenes: Vec<PathBuf>, out: &Path, shard: Option<&str>, jobs: usize) -> BatchArgs {
    BatchArgs {
        scenes,
        output: out.to_path_buf(),
        shard: shard.map(str::to_string),
        jobs,
        width: Some(96),
        height: Some(54),
        scalar: false,
    }
}

fn by_scene(mut v: Vec<Record>) -> Vec<Record> {
    v.sort_by(|a, b| a.scene.cmp(&b.scene));
    v
}

#[test]
fn two_shards_merged_equal_an_unsharded_batch() {
    let whole = temp_dir("batch-whole");
    let sharded = temp_dir("batch-sharded");
    let scenes = fixture_scenes();
    let o = run(&args(scenes.clone(), &whole, None, 1), false).unwrap();
    assert!(o.failed.is_empty(), "{:?}", o.failed);
    assert_eq!(o.rendered.len(), scenes.len());
    // Two machines (here: one after the other, two jobs each) with the same list.
    for i in 0..2 {
        let o = run(
            &args(scenes.clone(), &sharded, Some(&format!("{i}/2")), 2),
            false,
        )
        .unwrap();
        assert!(o.failed.is_empty(), "{:?}", o.failed);
    }
    let a = read_manifest(&whole.join("manifest.jsonl")).unwrap();
    let s0 = read_manifest(&sharded.join("manifest-0-of-2.jsonl")).unwrap();
    let s1 = read_manifest(&sharded.join("manifest-1-of-2.jsonl")).unwrap();
    assert!(!s0.is_empty() && !s1.is_empty());
    let merged: Vec<Record> = s0.into_iter().chain(s1).collect();
    let (a, merged) = (by_scene(a), by_scene(merged));
    assert_eq!(a.len(), scenes.len());
    assert_eq!(a.len(), merged.len());
    for (x, y) in a.iter().zip(&merged) {
        assert!(x.same_render(y), "{x:?}\n{y:?}");
        let bx = std::fs::read(whole.join(&x.output)).unwrap();
        let by = std::fs::read(sharded.join(&y.output)).unwrap();
        assert_eq!(bx, by, "{}", x.scene);
        assert_eq!(specula::batch::sha256_hex(&bx), x.output_sha256);
        assert!(x.inputs[0].path.ends_with(&format!("{}.toml", x.scene)));
    }
    // The manifest lists every file a load reads: the bunny's OBJ, the
    // checker texture.
    let bunny = a.iter().find(|r| r.scene == "bunny").unwrap();
    assert!(
        bunny.inputs.iter().any(|f| f.path.ends_with(".obj")),
        "{bunny:?}"
    );
}

#[test]
fn a_rerun_skips_current_scenes_and_redoes_changed_ones() {
    let dir = temp_dir("batch-resume");
    let src = std::fs::read_to_string(fixtures().join("scenes/furnace.toml")).unwrap();
    let scene = dir.join("furnace.toml");
    std::fs::write(&scene, &src).unwrap();
    let other = dir.join("second.toml");
    std::fs::write(&other, &src).unwrap();
    let out = dir.join("out");
    let a = args(vec![scene.clone(), other.clone()], &out, None, 1);
    let first = run(&a, false).unwrap();
    assert_eq!(first.rendered, ["furnace", "second"]);
    let again = run(&a, false).unwrap();
    assert!(again.rendered.is_empty(), "{again:?}");
    assert_eq!(again.skipped, ["furnace", "second"]);
    // An edited scene and a missing image are redone; nothing else is.
    std::fs::write(&scene, format!("{src}\n# edited\n")).unwrap();
    std::fs::remove_file(out.join("second.png")).unwrap();
    let third = run(&a, false).unwrap();
    assert_eq!(third.rendered, ["furnace", "second"]);
    // Other settings are another render.
    let mut b = a.clone();
    b.width = Some(64);
    assert_eq!(run(&b, false).unwrap().rendered.len(), 2);
}

#[test]
fn diff_dir_compares_two_batches_with_one_exit_status() {
    let dir = temp_dir("batch-diff-dir");
    let scenes = vec![
        fixtures().join("scenes/furnace.toml"),
        fixtures().join("scenes/sphere-grid.toml"),
    ];
    let (a, b) = (dir.join("a"), dir.join("b"));
    run(&args(scenes.clone(), &a, None, 1), false).unwrap();
    let mut scalar = args(scenes, &b, None, 1);
    scalar.scalar = true;
    run(&scalar, false).unwrap();
    let out = specula(
        &["diff", "--dir", "a", "b", "--fail-above", "flip_mean=0.01"],
        &dir,
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains("furnace") && text.contains("sphere-grid"),
        "{text}"
    );
    // Another renderer's images, no manifest: paired by the reference's names.
    let c = dir.join("c");
    std::fs::create_dir_all(&c).unwrap();
    for f in ["furnace.png", "sphere-grid.png"] {
        std::fs::copy(b.join(f), c.join(f)).unwrap();
    }
    let out = specula(&["diff", "--dir", "a", "c"], &dir);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    // A scene missing from one side is an error (status 2) named in the table.
    std::fs::remove_file(b.join("manifest.jsonl")).unwrap();
    run(
        &args(vec![fixtures().join("scenes/furnace.toml")], &b, None, 1),
        false,
    )
    .unwrap();
    let out = specula(&["diff", "--dir", "a", "b"], &dir);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(2), "{text}");
    assert!(
        text.contains("sphere-grid") && text.contains("not in b"),
        "{text}"
    );
}

/// `diff --dir`: a mask is refused (one mask cannot fit every scene), and
/// a heat map folder or JSON file over either batch folder's images or
/// manifests is refused before anything is compared, the files untouched.
#[test]
fn diff_dir_refuses_a_mask_and_outputs_over_its_inputs() {
    let dir = temp_dir("batch-diff-dir-outputs");
    let scenes = vec![fixtures().join("scenes/furnace.toml")];
    for side in ["a", "b"] {
        run(&args(scenes.clone(), &dir.join(side), None, 1), false).unwrap();
    }
    let diff = |extra: &[&str]| {
        let mut a = vec!["diff", "--dir", "a", "b"];
        a.extend_from_slice(extra);
        let out = specula(&a, &dir);
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let (code, err) = diff(&[]);
    assert_eq!(code, Some(0), "{err}");
    let image = std::fs::read(dir.join("a/furnace.png")).unwrap();
    let manifest = std::fs::read(dir.join("b/manifest.jsonl")).unwrap();
    for (extra, needle) in [
        (&["--mask", "a/furnace.png"][..], "--mask"),
        (&["--heatmap", "a"], "refusing to overwrite"),
        (&["--json", "b/manifest.jsonl"], "refusing to overwrite"),
        (&["--json", "b/furnace.png"], "refusing to overwrite"),
    ] {
        let (code, err) = diff(extra);
        assert_eq!(code, Some(2), "{extra:?}: {err}");
        assert!(err.contains(needle), "{extra:?}: {err}");
    }
    assert_eq!(std::fs::read(dir.join("a/furnace.png")).unwrap(), image);
    assert_eq!(
        std::fs::read(dir.join("b/manifest.jsonl")).unwrap(),
        manifest
    );
}
