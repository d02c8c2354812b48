//! `specula batch`: renders a set of scenes into one folder with a
//! manifest, resumably, optionally one shard of the set.
//!
//! **Manifest.** JSON Lines, one [`Record`] per scene, sorted by scene
//! name: the scene, every file its load read with the SHA-256 of the
//! bytes read (the scene, meshes, MTLs, textures, tonal art maps), the
//! render settings, the output file and the SHA-256 of its bytes, the
//! frame time and specula's version. An unsharded run writes
//! `manifest.jsonl`, shard I of N `manifest-I-of-N.jsonl`; concatenating
//! the shards' manifests gives the unsharded one's records (in shard
//! order rather than name order).
//!
//! **Shards.** Scenes are sorted by name (the file stem, which also names
//! the output) and scene k goes to shard k mod N, so every machine given
//! the same list and its own I renders a disjoint part and together they
//! render each scene once.
//!
//! **Resumption.** A scene whose record in the folder's manifest still
//! matches (same settings and version, every input file hashing as
//! recorded, the output file present with the recorded hash) is skipped.
//!
//! Output bytes depend only on the scene and the settings, not on
//! `--jobs` or the thread count; `frame_ms` is the one field that varies
//! between runs.

use crate::render::{render_scene, RenderSettings};
use crate::scene::load_scene_str;
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use specula_raster::frame::ShadePath;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

#[derive(clap::Args, Debug, Clone)]
pub struct BatchArgs {
    /// Scene files (TOML).
    #[arg(required = true)]
    pub scenes: Vec<PathBuf>,
    /// Output folder (created if missing): SCENE.png per scene and the manifest.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Render only shard I of N (I from 0 to N−1), e.g. --shard $SLURM_ARRAY_TASK_ID/4.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// Scenes rendered at the same time (the cores are divided among them).
    #[arg(long, default_value_t = 1)]
    pub jobs: usize,
    /// Image width for every scene (default: each scene's own).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height for every scene (default: each scene's own).
    #[arg(long)]
    pub height: Option<u32>,
    /// Shade one pixel at a time in f32 (`render --scalar`).
    #[arg(long)]
    pub scalar: bool,
}

/// One file a scene read, with the SHA-256 of its bytes (hex).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputFile {
    pub path: String,
    pub(crate) sha256: String,
}

/// One line of the manifest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Record {
    /// The scene's name: its file stem, unique in a batch.
    pub scene: String,
    /// The scene file as given on the command line.
    pub(crate) scene_path: String,
    /// Every file the load read, scene file first, in the order read.
    pub inputs: Vec<InputFile>,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) ssaa: u32,
    /// "simd" or "scalar".
    pub(crate) shading: String,
    /// The image, relative to the batch folder.
    pub output: String,
    pub output_sha256: String,
    /// Wall time of the frame (vertex through post), milliseconds.
    pub(crate) frame_ms: f64,
    pub(crate) specula_version: String,
}

impl Record {
    /// Whether two records describe the same render (all but `frame_ms`).
    pub fn same_render(&self, o: &Record) -> bool {
        Record {
            frame_ms: 0.0,
            ..self.clone()
        } == Record {
            frame_ms: 0.0,
            ..o.clone()
        }
    }
}

/// What can go wrong in a batch run: its arguments, its manifest, a
/// scene's file, load, render or image, and the outputs. Messages name
/// the file (and line, for the manifest).
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    /// A `--shard` that is not `I/N` with 0 ≤ I < N.
    #[error("--shard {0}: expected I/N with 0 ≤ I < N (e.g. 0/4)")]
    Shard(String),
    /// `--jobs 0`.
    #[error("--jobs must be at least 1")]
    Jobs,
    /// The output folder cannot be made.
    #[error("-o {}: cannot create the folder: {source}", .path.display())]
    OutputFolder {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A manifest that cannot be read.
    #[error("{}: {source}", .path.display())]
    ReadManifest {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A manifest line that is not a record.
    #[error("{}: line {line}: {source}", .path.display())]
    ManifestLine {
        path: PathBuf,
        line: usize,
        source: serde_json::Error,
    },
    /// A record that cannot be written as JSON.
    #[error("{0}")]
    ManifestJson(serde_json::Error),
    /// A scene file whose stem is not UTF-8 text.
    #[error("{}: a scene file needs a UTF-8 name", .path.display())]
    SceneName { path: PathBuf },
    /// Two scene files whose images would have the same name.
    #[error("{} and {} are both named {name:?}: their images would have the same name", .first.display(), .second.display())]
    SameName {
        first: PathBuf,
        second: PathBuf,
        name: String,
    },
    /// A scene file that cannot be read.
    #[error("{}: cannot read: {source}", .path.display())]
    ReadScene {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A scene file that is not UTF-8 text.
    #[error("{}: not UTF-8 text", .path.display())]
    NotUtf8 { path: PathBuf },
    /// A scene that does not load (its message names the file).
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    /// A scene that cannot be rendered at its settings (the renderer's
    /// message).
    #[error("{}: {source}", .path.display())]
    Render {
        path: PathBuf,
        source: crate::render::RenderError,
    },
    /// An image that cannot be encoded.
    #[error(transparent)]
    Image(#[from] crate::image_file::ImageFileError),
    /// An output that cannot be planned or written.
    #[error(transparent)]
    Output(#[from] crate::output_plan::OutputError),
}

/// The seam for the callers whose errors are still `String`s: `?` turns
/// the error into its message.
impl From<BatchError> for String {
    fn from(e: BatchError) -> String {
        e.to_string()
    }
}

/// SHA-256 of `bytes` in lower-case hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// `I/N` → (I, N), 0 ≤ I < N.
pub(crate) fn parse_shard(s: &str) -> Result<(usize, usize), BatchError> {
    let bad = || BatchError::Shard(s.to_string());
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (i, n): (usize, usize) = (
        i.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if n == 0 || i >= n {
        return Err(bad());
    }
    Ok((i, n))
}

/// The manifest's file name for a run.
pub(crate) fn manifest_name(shard: Option<(usize, usize)>) -> String {
    match shard {
        None => "manifest.jsonl".into(),
        Some((i, n)) => format!("manifest-{i}-of-{n}.jsonl"),
    }
}

/// Reads a manifest; errors name the file and line.
pub fn read_manifest(path: &Path) -> Result<Vec<Record>, BatchError> {
    let text = std::fs::read_to_string(path).map_err(|source| BatchError::ReadManifest {
        path: path.to_path_buf(),
        source,
    })?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str(l).map_err(|source| BatchError::ManifestLine {
                path: path.to_path_buf(),
                line: i + 1,
                source,
            })
        })
        .collect()
}

/// The scenes of one run: (name, path), sorted by name; names must be unique.
pub(crate) fn scene_list(
    scenes: &[PathBuf],
    shard: Option<(usize, usize)>,
) -> Result<Vec<(String, PathBuf)>, BatchError> {
    let mut named: Vec<(String, PathBuf)> = Vec::new();
    for p in scenes {
        let name = p
            .file_stem()
            .and_then(|s| s.to_str())
            .filter(|s| !s.is_empty())
            .ok_or_else(|| BatchError::SceneName { path: p.clone() })?
            .to_string();
        if let Some((_, q)) = named.iter().find(|(n, _)| *n == name) {
            return Err(BatchError::SameName {
                first: q.clone(),
                second: p.clone(),
                name,
            });
        }
        named.push((name, p.clone()));
    }
    named.sort();
    Ok(match shard {
        None => named,
        Some((i, n)) => named
            .into_iter()
            .enumerate()
            .filter(|(k, _)| k % n == i)
            .map(|(_, s)| s)
            .collect(),
    })
}

/// Whether a previous record still describes the scene's render.
fn still_current(rec: &Record, path: &Path, settings: &Record, out_dir: &Path) -> bool {
    rec.scene_path == path.to_string_lossy()
        && rec.width == settings.width
        && rec.height == settings.height
        && rec.shading == settings.shading
        && rec.specula_version == settings.specula_version
        && rec
            .inputs
            .iter()
            .all(|f| std::fs::read(&f.path).is_ok_and(|b| sha256_hex(&b) == f.sha256))
        && std::fs::read(out_dir.join(&rec.output))
            .is_ok_and(|b| sha256_hex(&b) == rec.output_sha256)
}

/// Loads and renders one scene, writes its image; the record.
fn render_one(
    name: &str,
    path: &Path,
    a: &BatchArgs,
    threads: usize,
) -> Result<Record, BatchError> {
    let text_bytes = std::fs::read(path).map_err(|source| BatchError::ReadScene {
        path: path.to_path_buf(),
        source,
    })?;
    let text = String::from_utf8(text_bytes.clone()).map_err(|_| BatchError::NotUtf8 {
        path: path.to_path_buf(),
    })?;
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let read_log: Mutex<Vec<InputFile>> = Mutex::new(vec![InputFile {
        path: path.to_string_lossy().into_owned(),
        sha256: sha256_hex(&text_bytes),
    }]);
    let read = |p: &Path| -> std::io::Result<Vec<u8>> {
        let full = dir.join(p);
        let bytes = std::fs::read(&full)?;
        let entry = InputFile {
            path: full.to_string_lossy().into_owned(),
            sha256: sha256_hex(&bytes),
        };
        let mut log = read_log.lock().expect("no panic holds the lock");
        if !log.contains(&entry) {
            log.push(entry);
        }
        Ok(bytes)
    };
    let t = Instant::now();
    let scene = load_scene_str(path, &text, &read)?;
    let load_ms = t.elapsed().as_secs_f64() * 1e3;
    let mut settings = RenderSettings::from_scene(&scene);
    settings.width = a.width.unwrap_or(settings.width);
    settings.height = a.height.unwrap_or(settings.height);
    settings.threads = Some(threads);
    settings.keep_hdr = false;
    settings.path = if a.scalar {
        ShadePath::Scalar
    } else {
        ShadePath::Simd
    };
    let render = |source| BatchError::Render {
        path: path.to_path_buf(),
        source,
    };
    settings.target().map_err(render)?;
    let mut r = render_scene(&scene, &settings, load_ms).map_err(render)?;
    let png = crate::image_file::encode_ldr(
        r.width,
        r.height,
        std::mem::take(&mut r.ldr),
        image::ImageFormat::Png,
    )?;
    let output = format!("{name}.png");
    let out_path = a.output.join(&output);
    let inputs = read_log.into_inner().expect("no panic holds the lock");
    let input_paths: Vec<PathBuf> = inputs.iter().map(|f| PathBuf::from(&f.path)).collect();
    let plan = crate::output_plan::plan(&[("-o", &out_path)], &input_paths, None)?;
    plan[0].write(&png)?;
    Ok(Record {
        scene: name.to_string(),
        scene_path: path.to_string_lossy().into_owned(),
        inputs,
        width: settings.width,
        height: settings.height,
        ssaa: settings.ssaa,
        shading: r.stats.shading.to_string(),
        output,
        output_sha256: sha256_hex(&png),
        frame_ms: r.stats.frame_ms[0],
        specula_version: env!("CARGO_PKG_VERSION").to_string(),
    })
}

/// What a run did.
#[derive(Debug, Default)]
pub struct BatchOutcome {
    pub rendered: Vec<String>,
    pub skipped: Vec<String>,
    /// (scene, error).
    pub failed: Vec<(String, BatchError)>,
    pub manifest: PathBuf,
}

fn write_manifest(path: &Path, records: &[Record]) -> Result<(), BatchError> {
    let mut text = String::new();
    for r in records {
        text += &serde_json::to_string(r).map_err(BatchError::ManifestJson)?;
        text += "\n";
    }
    let plan = crate::output_plan::plan(&[("manifest", path)], &[], None)?;
    plan[0].write(text.as_bytes())?;
    Ok(())
}

/// Runs a batch: renders what is not current, writes the manifest after
/// every scene (so an interrupted run resumes where it stopped).
pub fn run(a: &BatchArgs, progress: bool) -> Result<BatchOutcome, BatchError> {
    let shard = a.shard.as_deref().map(parse_shard).transpose()?;
    if a.jobs == 0 {
        return Err(BatchError::Jobs);
    }
    let list = scene_list(&a.scenes, shard)?;
    std::fs::create_dir_all(&a.output).map_err(|source| BatchError::OutputFolder {
        path: a.output.clone(),
        source,
    })?;
    let manifest = a.output.join(manifest_name(shard));
    let previous = if manifest.exists() {
        read_manifest(&manifest)?
    } else {
        Vec::new()
    };
    let wanted = Record {
        scene: String::new(),
        scene_path: String::new(),
        inputs: Vec::new(),
        width: a.width.unwrap_or(0),
        height: a.height.unwrap_or(0),
        ssaa: 0,
        shading: if a.scalar { "scalar" } else { "simd" }.into(),
        output: String::new(),
        output_sha256: String::new(),
        frame_ms: 0.0,
        specula_version: env!("CARGO_PKG_VERSION").to_string(),
    };
    let mut out = BatchOutcome {
        manifest: manifest.clone(),
        ..Default::default()
    };
    // Records of this run's scenes, by position in `list`.
    let records: Mutex<Vec<Option<Record>>> = Mutex::new(vec![None; list.len()]);
    let mut todo = Vec::new();
    for (k, (name, path)) in list.iter().enumerate() {
        let prev = previous.iter().find(|r| r.scene == *name);
        let current = prev.is_some_and(|r| {
            let mut w = wanted.clone();
            // A scene's own size counts as current when no override is given.
            w.width = a.width.unwrap_or(r.width);
            w.height = a.height.unwrap_or(r.height);
            still_current(r, path, &w, &a.output)
        });
        if current {
            records.lock().expect("no panic holds the lock")[k] = prev.cloned();
            out.skipped.push(name.clone());
        } else {
            todo.push(k);
        }
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs = a.jobs.min(todo.len().max(1));
    let threads = (cores / jobs).max(1);
    let bar = if progress {
        ProgressBar::new(todo.len() as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} scenes, {elapsed} {msg}")
            .expect("the template parses"),
    );
    let next = AtomicUsize::new(0);
    let failed: Mutex<Vec<(usize, BatchError)>> = Mutex::new(Vec::new());
    let write_lock = Mutex::new(());
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(&k) = todo.get(i) else { break };
                let (name, path) = &list[k];
                bar.set_message(name.clone());
                match render_one(name, path, a, threads) {
                    Ok(rec) => {
                        records.lock().expect("no panic holds the lock")[k] = Some(rec);
                        let _guard = write_lock.lock().expect("no panic holds the lock");
                        let done: Vec<Record> = records
                            .lock()
                            .expect("no panic holds the lock")
                            .iter()
                            .flatten()
                            .cloned()
                            .collect();
                        if let Err(e) = write_manifest(&manifest, &done) {
                            failed.lock().expect("no panic holds the lock").push((k, e));
                        }
                    }
                    Err(e) => failed.lock().expect("no panic holds the lock").push((k, e)),
                }
                bar.inc(1);
            });
        }
    });
    bar.finish_and_clear();
    let records = records.into_inner().expect("no panic holds the lock");
    let done: Vec<Record> = records.iter().flatten().cloned().collect();
    write_manifest(&manifest, &done)?;
    let mut failed = failed.into_inner().expect("no panic holds the lock");
    failed.sort_by_key(|(k, _)| *k);
    out.failed = failed
        .into_iter()
        .map(|(k, e)| (list[k].0.clone(), e))
        .collect();
    out.rendered = todo
        .iter()
        .filter(|&&k| records[k].is_some())
        .map(|&k| list[k].0.clone())
        .collect();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_sorted_list() {
        let scenes: Vec<PathBuf> = ["c.toml", "a.toml", "d/e.toml", "b.toml", "f.toml"]
            .iter()
            .map(PathBuf::from)
            .collect();
        let all = scene_list(&scenes, None).unwrap();
        let names = |l: Vec<(String, PathBuf)>| l.into_iter().map(|(n, _)| n).collect::<Vec<_>>();
        assert_eq!(names(all), ["a", "b", "c", "e", "f"]);
        assert_eq!(
            names(scene_list(&scenes, Some((0, 2))).unwrap()),
            ["a", "c", "f"]
        );
        assert_eq!(
            names(scene_list(&scenes, Some((1, 2))).unwrap()),
            ["b", "e"]
        );
    }

    #[test]
    fn shard_syntax_is_checked() {
        assert_eq!(parse_shard("1/4").unwrap(), (1, 4));
        for bad in ["4/4", "1", "a/2", "0/0", "-1/2"] {
            let e = parse_shard(bad).unwrap_err();
            assert!(matches!(&e, BatchError::Shard(s) if s == bad), "{bad}: {e}");
            assert_eq!(
                e.to_string(),
                format!("--shard {bad}: expected I/N with 0 ≤ I < N (e.g. 0/4)")
            );
        }
    }

    #[test]
    fn equal_stems_are_refused() {
        let scenes = [PathBuf::from("a/x.toml"), PathBuf::from("b/x.toml")];
        let e = scene_list(&scenes, None).unwrap_err();
        assert!(
            matches!(&e, BatchError::SameName { name, .. } if name == "x"),
            "{e}"
        );
        let e = e.to_string();
        assert!(e.contains("a/x.toml") && e.contains("b/x.toml"), "{e}");
    }

    #[test]
    fn sha256_of_abc_is_the_fips_example() {
        // FIPS 180-2, appendix B.1.
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
