//! specula's FLIP against the authors' implementation: the mean FLIP of
//! each pair in fixtures/flip/ must agree within 1e-5 with the value the
//! `flip-evaluator` package gave (fixtures/flip/reference.json, written by
//! fixtures/flip/flip_reference.py; provenance in the file).

use serde_json::Value;
use specula::diff::flip::{self, default_ppd, ToneCurve};
use specula::diff::load::{load, DiffImage, Encoding};
use specula::diff::{compare, FlipSettings};
use std::path::{Path, PathBuf};

const DIR: &str = "fixtures/flip";
const TOLERANCE: f64 = 1e-5;

/// Reads a little-endian PFM (rows bottom to top) as top-first RGB.
fn read_pfm(path: &Path) -> DiffImage {
    let b = std::fs::read(path).unwrap();
    let mut lines = 0;
    let mut at = 0;
    while lines < 3 {
        if b[at] == b'\n' {
            lines += 1;
        }
        at += 1;
    }
    let head = std::str::from_utf8(&b[..at]).unwrap();
    let mut it = head.split_whitespace();
    assert_eq!(it.next(), Some("PF"));
    let w: usize = it.next().unwrap().parse().unwrap();
    let h: usize = it.next().unwrap().parse().unwrap();
    assert_eq!(it.next(), Some("-1.0"), "little-endian");
    let floats: Vec<f32> = b[at..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(floats.len(), w * h * 3);
    let mut rgb = Vec::with_capacity(w * h);
    for y in (0..h).rev() {
        for x in 0..w {
            let i = (y * w + x) * 3;
            rgb.push([floats[i], floats[i + 1], floats[i + 2]]);
        }
    }
    DiffImage {
        path: path.to_path_buf(),
        width: w,
        height: h,
        channels: 3,
        alpha: false,
        encoding: Encoding::Linear,
        rgb,
    }
}

fn reference() -> Value {
    let text = std::fs::read_to_string(Path::new(DIR).join("reference.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

#[test]
fn mean_flip_agrees_with_the_authors_implementation() {
    let r = reference();
    let settings = FlipSettings {
        ppd: default_ppd(),
        exposures: None,
        curve: ToneCurve::Aces,
    };
    let mut worst = 0.0f64;
    for pair in r["pairs"].as_array().unwrap() {
        let name = pair["name"].as_str().unwrap();
        let file = |k: &str| PathBuf::from(DIR).join(pair[k].as_str().unwrap());
        let (a, b) = match pair["kind"].as_str().unwrap() {
            "ldr" => (
                load(&file("reference")).unwrap(),
                load(&file("test")).unwrap(),
            ),
            _ => (read_pfm(&file("reference")), read_pfm(&file("test"))),
        };
        if a.encoding == Encoding::Linear {
            let e = flip::auto_exposures(&a.rgb, ToneCurve::Aces).unwrap();
            let want = |k: &str| pair[k].as_f64().unwrap();
            assert!(
                (e.start as f64 - want("start_exposure")).abs() < 1e-4,
                "{name}: {e:?}"
            );
            assert!(
                (e.stop as f64 - want("stop_exposure")).abs() < 1e-4,
                "{name}: {e:?}"
            );
            assert_eq!(e.count as f64, want("exposures"), "{name}");
        }
        let report = compare(a, b, settings, None, false).unwrap();
        let want = pair["mean_flip"].as_f64().unwrap();
        let got = report.metrics.flip_mean;
        let d = (got - want).abs();
        worst = worst.max(d);
        eprintln!("| {name} | {want:.6} | {got:.6} | {d:.1e} |");
        assert!(
            d <= TOLERANCE,
            "{name}: specula {got:.6}, flip-evaluator {want:.6}"
        );
    }
    eprintln!("largest difference from flip-evaluator: {worst:.2e}");
}

#[test]
fn the_reference_file_says_where_it_came_from() {
    let r = reference();
    let p = &r["provenance"];
    assert!(p["tool"].as_str().unwrap().starts_with("flip-evaluator"));
    assert_eq!(p["script"], "fixtures/flip/flip_reference.py");
    assert!(r["pairs"].as_array().unwrap().len() >= 8);
}
