//! `specula diff` from the command line: exit statuses, outputs, and the
//! errors for pairs that cannot be compared.

mod common;

use common::{fixtures, specula, temp_dir};

fn run(args: &[&str]) -> (Option<i32>, String, String) {
    let out = specula(args, &fixtures().join("flip"));
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn equal_images_pass_and_bounds_set_the_status() {
    let (code, out, _) = run(&["diff", "ldr-ref.png", "ldr-identical.png"]);
    assert_eq!(code, Some(0), "{out}");
    assert!(out.contains("inf (equal)") && out.contains("pass"), "{out}");
    let (code, out, _) = run(&[
        "diff",
        "ldr-ref.png",
        "ldr-noise.png",
        "--fail-above",
        "flip_mean=0.05",
    ]);
    assert_eq!(code, Some(1), "{out}");
    assert!(out.contains("FAILED     flip_mean"), "{out}");
    let (code, out, _) = run(&[
        "diff",
        "ldr-ref.png",
        "ldr-noise.png",
        "--fail-above",
        "flip_mean=0.2",
        "--fail-below",
        "psnr=20",
    ]);
    assert_eq!(code, Some(0), "{out}");
}

#[test]
fn heat_map_and_json_are_written() {
    let dir = temp_dir("diff-outputs");
    let heat = dir.join("heat.png");
    let json = dir.join("report.json");
    let (code, out, err) = run(&[
        "diff",
        "ldr-ref.png",
        "ldr-shift.png",
        "--heatmap",
        heat.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{out}{err}");
    let img = image::open(&heat).unwrap();
    // Three panels side by side, enlarged to at least 192 pixels each.
    assert!(img.width() >= 3 * 192, "{}", img.width());
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["flip"], "ldr");
    assert_eq!(v["metrics"]["pixels"], 64 * 48);
    assert!(v["metrics"]["flip_mean"].as_f64().unwrap() > 0.1);
}

#[test]
fn pairs_that_cannot_be_compared_are_errors_naming_the_file() {
    let dir = temp_dir("diff-errors");
    let small = dir.join("small.png");
    image::RgbImage::new(8, 8).save(&small).unwrap();
    let (code, _, err) = run(&["diff", "ldr-ref.png", small.to_str().unwrap()]);
    assert_eq!(code, Some(2));
    assert!(
        err.contains("size mismatch") && err.contains("small.png"),
        "{err}"
    );

    let gray = dir.join("gray.png");
    image::GrayImage::new(64, 48).save(&gray).unwrap();
    let (code, _, err) = run(&["diff", "ldr-ref.png", gray.to_str().unwrap()]);
    assert_eq!(code, Some(2));
    assert!(
        err.contains("channel mismatch") && err.contains("gray.png"),
        "{err}"
    );

    let nan = dir.join("nan.exr");
    let mut px = vec![0.5f32; 4 * 4 * 3];
    px[3 * 5 + 1] = f32::NAN;
    image::Rgb32FImage::from_raw(4, 4, px)
        .unwrap()
        .save(&nan)
        .unwrap();
    let (code, _, err) = run(&["diff", nan.to_str().unwrap(), nan.to_str().unwrap()]);
    assert_eq!(code, Some(2));
    assert!(
        err.contains("nan.exr") && err.contains("pixel (1, 1)"),
        "{err}"
    );

    let (code, _, err) = run(&["diff", "ldr-ref.png", "hdr-ref.pfm"]);
    assert_eq!(code, Some(2));
    assert!(err.contains("hdr-ref.pfm"), "{err}");

    let (code, _, err) = run(&[
        "diff",
        "ldr-ref.png",
        "ldr-ref.png",
        "--fail-above",
        "flop=1",
    ]);
    assert_eq!(code, Some(2));
    assert!(err.contains("unknown metric \"flop\""), "{err}");
}

#[test]
fn hdr_images_use_hdr_flip() {
    let dir = temp_dir("diff-hdr");
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    let px: Vec<f32> = (0..32 * 32 * 3)
        .map(|i| 0.1 + (i % 17) as f32 * 0.5)
        .collect();
    image::Rgb32FImage::from_raw(32, 32, px.clone())
        .unwrap()
        .save(&a)
        .unwrap();
    let brighter: Vec<f32> = px.iter().map(|v| v * 1.25).collect();
    image::Rgb32FImage::from_raw(32, 32, brighter)
        .unwrap()
        .save(&b)
        .unwrap();
    let (code, out, err) = run(&["diff", a.to_str().unwrap(), b.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{out}{err}");
    assert!(
        out.contains("HDR-FLIP") && out.contains("exposures"),
        "{out}"
    );
    // A mostly black reference has no automatic range: the error says what to give.
    let dark = dir.join("dark.exr");
    let mut d = vec![0.0f32; 32 * 32 * 3];
    d[..30].fill(2.0);
    image::Rgb32FImage::from_raw(32, 32, d)
        .unwrap()
        .save(&dark)
        .unwrap();
    let (code, _, err) = run(&["diff", dark.to_str().unwrap(), dark.to_str().unwrap()]);
    assert_eq!(code, Some(2));
    assert!(err.contains("--exposures="), "{err}");
    let (code, out, _) = run(&[
        "diff",
        dark.to_str().unwrap(),
        dark.to_str().unwrap(),
        "--exposures=-3:2",
    ]);
    assert_eq!(code, Some(0), "{out}");
}

/// Every flag of `specula diff` is checked before any image is read, with
/// an error naming the flag (exit status 2), and no output may replace an
/// image or mask it compares.
#[test]
fn diff_flags_are_range_checked_and_inputs_never_overwritten() {
    let dir = temp_dir("diff-flags");
    for f in ["ldr-ref.png", "ldr-shift.png"] {
        std::fs::copy(fixtures().join("flip").join(f), dir.join(f)).unwrap();
    }
    let run_here = |extra: &[&str]| {
        let mut args = vec!["diff", "ldr-ref.png", "ldr-shift.png"];
        args.extend_from_slice(extra);
        let out = specula(&args, &dir);
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    for (extra, needle) in [
        (&["--ppd", "0"][..], "--ppd 0"),
        (&["--ppd=-3"], "--ppd -3"),
        (&["--ppd", "nan"], "--ppd NaN"),
        (&["--ppd", "inf"], "--ppd inf"),
        (&["--ppd", "1e9"], "--ppd 1000000000"),
        (&["--exposures", "5:1"], "--exposures 5:1"),
        (&["--exposures", "a:b"], "--exposures a:b"),
        (&["--exposures", "1"], "--exposures 1"),
        (&["--exposures", "1:2:3:4"], "--exposures 1:2:3:4"),
        (&["--exposures", "1:2:1"], "--exposures 1:2:1"),
        (&["--exposures", "1:2:65"], "--exposures 1:2:65"),
        (&["--exposures", "nan:1"], "--exposures nan:1"),
        (&["--exposures", "-inf:1"], "--exposures -inf:1"),
        (&["--tonemap", "filmic"], "--tonemap filmic"),
        (&["--fail-above", "flip_mean"], "expected METRIC=VALUE"),
        (&["--fail-above", "flip_mean=nan"], "not a finite number"),
        (&["--fail-below", "psnr=inf"], "not a finite number"),
        (&["--fail-below", "psnr="], "not a finite number"),
        (&["--fail-above", "=1"], "unknown metric"),
    ] {
        let (code, err) = run_here(extra);
        assert_eq!(code, Some(2), "{extra:?}: {err}");
        assert!(err.contains(needle), "{extra:?}: {err}");
    }
    // Outputs over the images compared or the mask are refused, the
    // files untouched.
    let before = std::fs::read(dir.join("ldr-ref.png")).unwrap();
    std::fs::copy(dir.join("ldr-ref.png"), dir.join("mask.png")).unwrap();
    for extra in [
        &["--heatmap", "ldr-ref.png"][..],
        &["--json", "ldr-shift.png"],
        &["--mask", "mask.png", "--heatmap", "mask.png"],
        &["--heatmap", "h.png", "--json", "h.png"],
    ] {
        let (code, err) = run_here(extra);
        assert_eq!(code, Some(2), "{extra:?}: {err}");
        assert!(
            err.contains("refusing to overwrite") || err.contains("the same file"),
            "{extra:?}: {err}"
        );
    }
    assert_eq!(std::fs::read(dir.join("ldr-ref.png")).unwrap(), before);
    assert_eq!(std::fs::read(dir.join("mask.png")).unwrap(), before);
    assert!(!dir.join("h.png").exists());
}
