//! What can go wrong in `specula diff`: a flag's value, an image that
//! cannot be read or compared (`load.rs`), a batch folder, the outputs.
//! Every variant is a usage or input error (exit status 2); the messages
//! name the flag or the file.

use super::load::DiffImageError;
use std::path::PathBuf;

/// A usage or input error of `specula diff`.
#[derive(Debug, thiserror::Error)]
pub enum DiffError {
    /// A `--fail-above` / `--fail-below` without `=`.
    #[error("{flag} {text}: expected METRIC=VALUE")]
    BoundSyntax { flag: &'static str, text: String },
    /// A bound on a metric that is not reported.
    #[error("{flag} {text}: unknown metric {metric:?} (one of {})", super::metrics::NAMES.join(", "))]
    UnknownMetric {
        flag: &'static str,
        text: String,
        metric: String,
    },
    /// A bound whose value is not a finite number.
    #[error("{flag} {text}: {value:?} is not a finite number")]
    BoundValue {
        flag: &'static str,
        text: String,
        value: String,
    },
    /// `--ppd` out of range.
    #[error("--ppd {0}: must be in (0, 1000]")]
    Ppd(f32),
    /// `--tonemap` of no known curve.
    #[error("--tonemap {0}: one of aces, hable, reinhard")]
    Tonemap(String),
    /// `--exposures` that is not a range.
    #[error("--exposures {0}: expected START:STOP or START:STOP:COUNT with START ≤ STOP and COUNT in 2..=64")]
    Exposures(String),
    /// `--ignore-background` on two black images.
    #[error("--ignore-background: {} and {} are both entirely black: nothing to compare", .reference.display(), .test.display())]
    BothBlack { reference: PathBuf, test: PathBuf },
    /// A reference with no exposure range for HDR-FLIP.
    #[error("{}: {source}", .path.display())]
    Exposure {
        path: PathBuf,
        source: super::flip::ExposureError,
    },
    /// An image that cannot be read or compared.
    #[error(transparent)]
    Image(#[from] DiffImageError),
    /// A heat map asked of a report that dropped its images.
    #[error("the images were not kept")]
    NoImages,
    /// A heat map that cannot be encoded.
    #[error(transparent)]
    Encode(#[from] crate::image_file::ImageFileError),
    /// An output that cannot be planned or written.
    #[error(transparent)]
    Output(#[from] crate::output_plan::OutputError),
    /// A report that cannot be written as JSON.
    #[error("{0}")]
    Json(serde_json::Error),
    /// A batch folder's manifest that cannot be read.
    #[error(transparent)]
    Manifest(#[from] crate::batch::BatchError),
    /// A folder that cannot be listed.
    #[error("{}: {source}", .path.display())]
    ReadFolder {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A folder without a batch manifest.
    #[error("{}: no manifest.jsonl or manifest-I-of-N.jsonl (not a `specula batch` folder)", .path.display())]
    NotBatchFolder { path: PathBuf },
    /// A scene in two manifests of one folder.
    #[error("{}: scene {scene:?} is listed twice", .manifest.display())]
    SceneTwice { manifest: PathBuf, scene: String },
    /// `--mask` with `--dir`.
    #[error("--mask: not with --dir (one mask cannot fit every scene); compare the pairs one by one, or give --ignore-background")]
    MaskWithDir,
    /// A heat map folder that cannot be made.
    #[error("--heatmap {}: cannot create the folder: {source}", .path.display())]
    HeatmapFolder {
        path: PathBuf,
        source: std::io::Error,
    },
    /// Scenes of a folder run that could not be compared.
    #[error("{0} scene(s) could not be compared (see the table)")]
    Uncompared(usize),
}

/// The seam for the callers whose errors are still `String`s: `?` turns
/// the error into its message.
impl From<DiffError> for String {
    fn from(e: DiffError) -> String {
        e.to_string()
    }
}
