//! `specula diff --dir REFDIR TESTDIR`: every scene of two `specula
//! batch` folders, paired by scene name through their manifests
//! (`manifest.jsonl`, or the shards' `manifest-I-of-N.jsonl` together), a
//! table worst first (by mean FLIP), one exit status. A test folder with
//! no manifest (images another renderer wrote) is read by the reference's
//! file names: REFDIR's `SCENE.png` against TESTDIR's `SCENE.png`.

use super::{
    apply_bounds, compare, heatmap_png, load, Bound, DiffArgs, DiffError, FlipSettings, Verdict,
};
use crate::batch::{read_manifest, Record};
use std::path::{Path, PathBuf};

/// Whether a folder holds a batch manifest.
fn has_manifest(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|rd| {
        rd.filter_map(|e| e.ok()).any(|e| {
            e.file_name().to_str().is_some_and(|n| {
                n == "manifest.jsonl" || (n.starts_with("manifest-") && n.ends_with(".jsonl"))
            })
        })
    })
}

/// The manifest files of a batch folder (none when it cannot be read).
fn manifests(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| {
                    p.file_name().and_then(|n| n.to_str()).is_some_and(|n| {
                        n == "manifest.jsonl"
                            || (n.starts_with("manifest-") && n.ends_with(".jsonl"))
                    })
                })
                .collect()
        })
        .unwrap_or_default()
}

/// The records of a batch folder: `manifest.jsonl` when present, else every
/// shard manifest; a scene listed twice is an error.
pub(crate) fn folder_records(dir: &Path) -> Result<Vec<Record>, DiffError> {
    let whole = dir.join("manifest.jsonl");
    let files: Vec<PathBuf> = if whole.exists() {
        vec![whole]
    } else {
        let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(|source| DiffError::ReadFolder {
                path: dir.to_path_buf(),
                source,
            })?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with("manifest-") && n.ends_with(".jsonl"))
            })
            .collect();
        v.sort();
        v
    };
    if files.is_empty() {
        return Err(DiffError::NotBatchFolder {
            path: dir.to_path_buf(),
        });
    }
    let mut out: Vec<Record> = Vec::new();
    for f in files {
        for r in read_manifest(&f)? {
            if out.iter().any(|o| o.scene == r.scene) {
                return Err(DiffError::SceneTwice {
                    manifest: f,
                    scene: r.scene,
                });
            }
            out.push(r);
        }
    }
    Ok(out)
}

struct Row {
    scene: String,
    flip_mean: f64,
    psnr: Option<f64>,
    max_abs: f64,
    status: String,
}

pub(crate) fn run(
    a: &DiffArgs,
    bounds: &[Bound],
    settings: FlipSettings,
) -> Result<Verdict, DiffError> {
    let refs = folder_records(&a.reference)?;
    let tests = if a.test.is_dir() && !has_manifest(&a.test) {
        // Images from another renderer: the reference's names.
        refs.clone()
    } else {
        folder_records(&a.test)?
    };
    if a.mask.is_some() {
        return Err(DiffError::MaskWithDir);
    }
    if let Some(h) = &a.heatmap {
        std::fs::create_dir_all(h).map_err(|source| DiffError::HeatmapFolder {
            path: h.clone(),
            source,
        })?;
    }
    let mut rows = Vec::new();
    let mut reports = Vec::new();
    let mut errors = 0usize;
    let mut failures = 0usize;
    let mut names: Vec<&str> = refs.iter().map(|r| r.scene.as_str()).collect();
    for t in &tests {
        if !names.contains(&t.scene.as_str()) {
            names.push(&t.scene);
        }
    }
    names.sort();
    // Every output is checked before any image is compared: none may be
    // an image or manifest of either folder, nor two the same file.
    let mut inputs: Vec<PathBuf> = refs
        .iter()
        .map(|r| a.reference.join(&r.output))
        .chain(tests.iter().map(|t| a.test.join(&t.output)))
        .collect();
    inputs.extend(manifests(&a.reference));
    inputs.extend(manifests(&a.test));
    let heat_paths: Vec<PathBuf> = match &a.heatmap {
        Some(h) => names.iter().map(|n| h.join(format!("{n}.png"))).collect(),
        None => Vec::new(),
    };
    let mut outs: Vec<(&str, &Path)> = heat_paths
        .iter()
        .map(|p| ("--heatmap", p.as_path()))
        .collect();
    outs.extend(a.json.as_deref().map(|j| ("--json", j)));
    let plan = crate::output_plan::plan(&outs, &inputs, None)?;
    let (heat_plan, json_plan) = plan.split_at(heat_paths.len());
    for (k, name) in names.into_iter().enumerate() {
        let r = refs.iter().find(|r| r.scene == name);
        let t = tests.iter().find(|r| r.scene == name);
        let (r, t) = match (r, t) {
            (Some(r), Some(t)) => (r, t),
            (r, _) => {
                errors += 1;
                let missing = if r.is_none() { &a.reference } else { &a.test };
                rows.push(Row {
                    scene: name.to_string(),
                    flip_mean: f64::INFINITY,
                    psnr: None,
                    max_abs: f64::NAN,
                    status: format!("ERROR: not in {}", missing.display()),
                });
                continue;
            }
        };
        let result = load::load(&a.reference.join(&r.output))
            .map_err(DiffError::from)
            .and_then(|ri| {
                let ti = load::load(&a.test.join(&t.output))?;
                compare(ri, ti, settings, None, a.ignore_background)
            });
        match result {
            Ok(mut rep) => {
                apply_bounds(&mut rep, bounds);
                if let Some(out) = heat_plan.get(k) {
                    out.write(&heatmap_png(&rep)?)?;
                }
                let status = if rep.failed.is_empty() {
                    "pass".to_string()
                } else {
                    failures += 1;
                    format!("FAILED: {}", rep.failed.join("; "))
                };
                rows.push(Row {
                    scene: name.to_string(),
                    flip_mean: rep.metrics.flip_mean,
                    psnr: rep.metrics.psnr,
                    max_abs: rep.metrics.max_abs,
                    status,
                });
                rep.images = None;
                reports.push(rep);
            }
            Err(e) => {
                errors += 1;
                rows.push(Row {
                    scene: name.to_string(),
                    flip_mean: f64::INFINITY,
                    psnr: None,
                    max_abs: f64::NAN,
                    status: format!("ERROR: {e}"),
                });
            }
        }
    }
    // Worst first: errors, then by mean FLIP, ties by name.
    rows.sort_by(|x, y| {
        y.flip_mean
            .total_cmp(&x.flip_mean)
            .then_with(|| x.scene.cmp(&y.scene))
    });
    let wide = rows.iter().map(|r| r.scene.len()).max().unwrap_or(5).max(5);
    println!(
        "{:<wide$}  {:>9}  {:>9}  {:>9}  status",
        "scene", "FLIP mean", "PSNR dB", "max abs"
    );
    for r in &rows {
        let flip = if r.flip_mean.is_finite() {
            format!("{:.5}", r.flip_mean)
        } else {
            "-".into()
        };
        let psnr = match (r.psnr, r.status.starts_with("ERROR")) {
            (_, true) => "-".into(),
            (Some(p), _) => format!("{p:.2}"),
            (None, _) => "inf".into(),
        };
        let max_abs = if r.max_abs.is_nan() {
            "-".into()
        } else {
            format!("{:.4}", r.max_abs)
        };
        println!(
            "{:<wide$}  {flip:>9}  {psnr:>9}  {max_abs:>9}  {}",
            r.scene, r.status
        );
    }
    println!(
        "{} scene(s): {} failed a bound, {} error(s)",
        rows.len(),
        failures,
        errors
    );
    if let Some(out) = json_plan.first() {
        let json = serde_json::to_string_pretty(&reports).map_err(DiffError::Json)?;
        out.write(json.as_bytes())?;
    }
    if errors > 0 {
        return Err(DiffError::Uncompared(errors));
    }
    Ok(if failures > 0 {
        Verdict::Fail
    } else {
        Verdict::Pass
    })
}
