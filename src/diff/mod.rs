//! `specula diff`: how far a test image is from a reference, in the
//! numbers image comparisons use (PSNR, RMSE, absolute and relative
//! errors, pixel shares over thresholds) and in FLIP, the perceptual
//! difference (`flip.rs`); a heat map (`heatmap.rs`), a JSON report, and
//! bounds that set the exit status. `--dir` compares two `specula batch`
//! folders scene by scene (`dir.rs`).

pub(crate) mod dir;
mod error;
pub mod flip;
pub(crate) mod heatmap;
pub mod load;
pub(crate) mod magma;
pub(crate) mod metrics;

pub(crate) use error::DiffError;
use load::{DiffImage, Encoding};
use metrics::Metrics;
use serde::Serialize;
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug, Clone)]
pub struct DiffArgs {
    /// Reference image (with --dir: the reference batch folder).
    pub(crate) reference: PathBuf,
    /// Test image (with --dir: the test batch folder).
    pub(crate) test: PathBuf,
    /// Compare every scene of two `specula batch` folders (their manifests).
    #[arg(long)]
    pub(crate) dir: bool,
    /// Write the heat map PNG here (with --dir: a folder, one PNG per scene).
    #[arg(long, value_name = "PATH")]
    pub(crate) heatmap: Option<PathBuf>,
    /// Write the metrics as JSON here.
    #[arg(long, value_name = "PATH")]
    pub(crate) json: Option<PathBuf>,
    /// Exit with status 1 when METRIC exceeds VALUE (e.g. flip_mean=0.01); repeatable.
    #[arg(long, value_name = "METRIC=VALUE")]
    pub(crate) fail_above: Vec<String>,
    /// Exit with status 1 when METRIC is below VALUE (e.g. psnr=40); repeatable.
    #[arg(long, value_name = "METRIC=VALUE")]
    pub(crate) fail_below: Vec<String>,
    /// Compare only the pixels this image marks (non-zero in any channel).
    #[arg(long, value_name = "PATH", conflicts_with = "ignore_background")]
    pub(crate) mask: Option<PathBuf>,
    /// Leave out pixels that are exactly black in both images (nothing drawn).
    #[arg(long)]
    pub(crate) ignore_background: bool,
    /// FLIP's viewing condition in pixels per degree (default: 67, a 3840-pixel
    /// 0.7 m wide monitor seen from 0.7 m).
    #[arg(long, value_name = "PPD")]
    pub(crate) ppd: Option<f32>,
    /// HDR-FLIP's exposure range in stops, START:STOP or START:STOP:COUNT
    /// (default: from the reference's largest and median luminance).
    #[arg(long, value_name = "START:STOP", allow_hyphen_values = true)]
    pub(crate) exposures: Option<String>,
    /// The tone curve HDR-FLIP assumes: aces, hable or reinhard.
    #[arg(long, default_value = "aces")]
    pub(crate) tonemap: String,
}

/// Which side of a bound fails.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum Fails {
    /// The value exceeds the bound (`--fail-above`).
    Above,
    /// The value falls under the bound (`--fail-below`).
    Below,
}

/// A bound on one metric.
#[derive(Clone, Debug, Serialize)]
pub(crate) struct Bound {
    pub(crate) metric: String,
    pub(crate) fails: Fails,
    pub(crate) value: f64,
}

fn parse_bounds(a: &DiffArgs) -> Result<Vec<Bound>, DiffError> {
    let mut out = Vec::new();
    for (flag, list, fails) in [
        ("--fail-above", &a.fail_above, Fails::Above),
        ("--fail-below", &a.fail_below, Fails::Below),
    ] {
        for s in list {
            let (m, v) = s.split_once('=').ok_or_else(|| DiffError::BoundSyntax {
                flag,
                text: s.clone(),
            })?;
            if !metrics::NAMES.contains(&m) {
                return Err(DiffError::UnknownMetric {
                    flag,
                    text: s.clone(),
                    metric: m.to_string(),
                });
            }
            let value: f64 = v
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .ok_or_else(|| DiffError::BoundValue {
                    flag,
                    text: s.clone(),
                    value: v.to_string(),
                })?;
            out.push(Bound {
                metric: m.to_string(),
                fails,
                value,
            });
        }
    }
    Ok(out)
}

/// The FLIP settings of a run.
#[derive(Clone, Copy, Debug)]
pub struct FlipSettings {
    pub ppd: f32,
    pub exposures: Option<flip::Exposures>,
    pub curve: flip::ToneCurve,
}

fn parse_flip(a: &DiffArgs) -> Result<FlipSettings, DiffError> {
    let ppd = a.ppd.unwrap_or_else(flip::default_ppd);
    if !(ppd.is_finite() && ppd > 0.0 && ppd <= 1000.0) {
        return Err(DiffError::Ppd(ppd));
    }
    let curve = match a.tonemap.to_ascii_lowercase().as_str() {
        "aces" => flip::ToneCurve::Aces,
        "hable" => flip::ToneCurve::Hable,
        "reinhard" => flip::ToneCurve::Reinhard,
        t => return Err(DiffError::Tonemap(t.to_string())),
    };
    let exposures = match &a.exposures {
        None => None,
        Some(s) => {
            let parts: Vec<&str> = s.split(':').collect();
            let bad = || DiffError::Exposures(s.clone());
            if parts.len() < 2 || parts.len() > 3 {
                return Err(bad());
            }
            let start: f32 = parts[0].parse().map_err(|_| bad())?;
            let stop: f32 = parts[1].parse().map_err(|_| bad())?;
            if !(start.is_finite() && stop.is_finite() && start <= stop) {
                return Err(bad());
            }
            let count = match parts.get(2) {
                Some(c) => c.parse().map_err(|_| bad())?,
                None => ((stop - start).ceil().max(2.0)) as usize,
            };
            if !(2..=64).contains(&count) {
                return Err(bad());
            }
            Some(flip::Exposures { start, stop, count })
        }
    };
    Ok(FlipSettings {
        ppd,
        exposures,
        curve,
    })
}

/// The result of comparing one pair.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub(crate) reference: PathBuf,
    pub(crate) test: PathBuf,
    pub(crate) width: usize,
    pub(crate) height: usize,
    pub(crate) encoding: Encoding,
    /// "ldr" or "hdr".
    pub(crate) flip: &'static str,
    pub(crate) ppd: f32,
    /// HDR-FLIP's exposures (start, stop, count), when used.
    pub(crate) exposures: Option<[f32; 3]>,
    /// Which pixels were compared: "all", "mask PATH", "not black in both".
    pub(crate) compared: String,
    pub metrics: Metrics,
    /// The bounds that failed, as text.
    pub(crate) failed: Vec<String>,
    #[serde(skip)]
    pub(crate) flip_map: Vec<f32>,
    #[serde(skip)]
    pub(crate) images: Option<(DiffImage, DiffImage)>,
}

/// Compares two images already loaded.
pub fn compare(
    r: DiffImage,
    t: DiffImage,
    settings: FlipSettings,
    mask: Option<&Path>,
    ignore_background: bool,
) -> Result<Report, DiffError> {
    load::check_pair(&r, &t)?;
    let (w, h) = (r.width, r.height);
    let (keep, compared) = match (mask, ignore_background) {
        (Some(p), _) => (
            Some(load::load_mask(p, w, h)?),
            format!("mask {}", p.display()),
        ),
        (None, true) => {
            let k: Vec<bool> = r
                .rgb
                .iter()
                .zip(&t.rgb)
                .map(|(a, b)| *a != [0.0; 3] || *b != [0.0; 3])
                .collect();
            if !k.iter().any(|&b| b) {
                return Err(DiffError::BothBlack {
                    reference: r.path.clone(),
                    test: t.path.clone(),
                });
            }
            (Some(k), "not black in both".to_string())
        }
        (None, false) => (None, "all".to_string()),
    };
    let (flip_map, kind, exposures) = match r.encoding {
        Encoding::Display => {
            let lin = |img: &DiffImage| -> Vec<[f32; 3]> {
                img.rgb
                    .iter()
                    .map(|c| c.map(flip::srgb_to_linear))
                    .collect()
            };
            (
                flip::ldr_flip(&lin(&r), &lin(&t), w, h, settings.ppd),
                "ldr",
                None,
            )
        }
        Encoding::Linear => {
            let e = match settings.exposures {
                Some(e) => e,
                None => flip::auto_exposures(&r.rgb, settings.curve).map_err(|source| {
                    DiffError::Exposure {
                        path: r.path.clone(),
                        source,
                    }
                })?,
            };
            (
                flip::hdr_flip(&r.rgb, &t.rgb, w, h, settings.ppd, e, settings.curve),
                "hdr",
                Some([e.start, e.stop, e.count as f32]),
            )
        }
    };
    let metrics = metrics::compute(&r.rgb, &t.rgb, w, &flip_map, keep.as_deref(), r.encoding);
    Ok(Report {
        reference: r.path.clone(),
        test: t.path.clone(),
        width: w,
        height: h,
        encoding: r.encoding,
        flip: kind,
        ppd: settings.ppd,
        exposures,
        compared,
        metrics,
        failed: Vec::new(),
        flip_map,
        images: Some((r, t)),
    })
}

/// Checks the bounds; fills `report.failed`.
pub(crate) fn apply_bounds(report: &mut Report, bounds: &[Bound]) {
    for b in bounds {
        let v = report
            .metrics
            .get(&b.metric)
            .expect("bound names are checked");
        let (fails, side) = match b.fails {
            Fails::Above => (v > b.value, "above"),
            Fails::Below => (v < b.value, "below"),
        };
        if fails {
            report.failed.push(format!(
                "{} = {} is {side} {}",
                b.metric,
                fmt_num(v),
                b.value
            ));
        }
    }
}

fn fmt_num(v: f64) -> String {
    if v.is_infinite() {
        "inf".into()
    } else if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e5) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}

/// The one-screen text summary.
pub(crate) fn summary(r: &Report) -> String {
    let m = &r.metrics;
    let mut s = String::new();
    let kind = match r.encoding {
        Encoding::Display => "display (sRGB)",
        Encoding::Linear => "linear HDR",
    };
    s += &format!("reference  {}\n", r.reference.display());
    s += &format!(
        "test       {}\n           {}×{}, {kind}; {} pixels compared ({})\n",
        r.test.display(),
        r.width,
        r.height,
        m.pixels,
        r.compared
    );
    s += &format!(
        "PSNR       {} (peak {})   RMSE {}\n",
        m.psnr
            .map_or("inf (equal)".to_string(), |p| format!("{p:.2} dB")),
        fmt_num(m.peak),
        fmt_num(m.rmse)
    );
    s += &format!(
        "abs error  mean {}   max {}\n",
        fmt_num(m.mean_abs),
        fmt_num(m.max_abs)
    );
    s += &format!(
        "rel error  mean {}   max {}   (|t − r| / (r + {}))\n",
        fmt_num(m.mean_rel),
        fmt_num(m.max_rel),
        metrics::REL_EPSILON
    );
    let unit = match r.encoding {
        Encoding::Display => "abs",
        Encoding::Linear => "rel",
    };
    let shares: Vec<String> = m
        .over
        .iter()
        .map(|o| {
            format!(
                "{unit} > {}: {:.2} %",
                fmt_num(o.threshold),
                100.0 * o.share
            )
        })
        .collect();
    s += &format!("pixels     {}\n", shares.join("   "));
    let flip_name = if r.flip == "hdr" {
        "HDR-FLIP"
    } else {
        "LDR-FLIP"
    };
    s += &format!(
        "{flip_name:<10} mean {}   median {}   p99 {}   max {} at ({}, {})\n",
        fmt_num(m.flip_mean),
        fmt_num(m.flip_median),
        fmt_num(m.flip_p99),
        fmt_num(m.flip_max),
        m.flip_worst[0],
        m.flip_worst[1]
    );
    s += &format!("           {:.1} pixels per degree", r.ppd);
    if let Some(e) = r.exposures {
        s += &format!(
            ", exposures {:.3} to {:.3} in {} steps",
            e[0], e[1], e[2] as usize
        );
    }
    s += "\n";
    if r.failed.is_empty() {
        s += "result     pass\n";
    } else {
        for f in &r.failed {
            s += &format!("FAILED     {f}\n");
        }
    }
    s
}

/// The heat map PNG of a report.
pub fn heatmap_png(r: &Report) -> Result<Vec<u8>, DiffError> {
    let (ri, ti) = r.images.as_ref().ok_or(DiffError::NoImages)?;
    let label = format!("{}-FLIP", r.flip.to_uppercase());
    let (w, h, px) = heatmap::render(
        &ri.rgb,
        &ti.rgb,
        &r.flip_map,
        r.width,
        r.height,
        r.encoding,
        &label,
    );
    Ok(crate::image_file::encode_ldr(
        w,
        h,
        px,
        image::ImageFormat::Png,
    )?)
}

/// Whether all bounds held.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Pass,
    Fail,
}

/// `specula diff` as the command line runs it: prints the summary, writes
/// the requested files; `Err` is a usage or input error (exit status 2).
pub fn run(a: &DiffArgs) -> Result<Verdict, DiffError> {
    let bounds = parse_bounds(a)?;
    let settings = parse_flip(a)?;
    if a.dir {
        return dir::run(a, &bounds, settings);
    }
    let mut outs: Vec<(&str, &Path)> = Vec::new();
    outs.extend(a.heatmap.as_deref().map(|p| ("--heatmap", p)));
    outs.extend(a.json.as_deref().map(|p| ("--json", p)));
    let mut inputs = vec![a.reference.clone(), a.test.clone()];
    inputs.extend(a.mask.clone());
    let plan = crate::output_plan::plan(&outs, &inputs, None)?;
    let r = load::load(&a.reference)?;
    let t = load::load(&a.test)?;
    let mut report = compare(r, t, settings, a.mask.as_deref(), a.ignore_background)?;
    apply_bounds(&mut report, &bounds);
    print!("{}", summary(&report));
    for o in &plan {
        match o.flag.as_str() {
            "--heatmap" => o.write(&heatmap_png(&report)?)?,
            _ => {
                let json = serde_json::to_string_pretty(&report).map_err(DiffError::Json)?;
                o.write(json.as_bytes())?
            }
        }
    }
    Ok(if report.failed.is_empty() {
        Verdict::Pass
    } else {
        Verdict::Fail
    })
}
