//! Where output files go, checked before any work is done.
//!
//! Every output path of a run is resolved once ([`plan`]): a regular file
//! (or a name that does not exist yet) is written to a temporary file in the
//! same folder and renamed into place, so a failed run never leaves a
//! half-written file; a device or FIFO (`/dev/null`, `/dev/stdout`, a named
//! pipe) is written through, never replaced; a symlink is followed and its
//! target handled the same way, so the link stays; `-` is standard output.
//! Folders and sockets are refused. Two outputs naming the same file, or an
//! output naming one of the run's input files, are refused, and the folder
//! of each new file is checked to be writable, all before rendering.

use image::ImageFormat;
use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Why a path cannot take an output (each message starts with the path).
#[derive(Debug, thiserror::Error)]
pub enum ResolveError {
    /// `-` for an output that cannot go to standard output.
    #[error("-: standard output is only available for the main image (-o -)")]
    StdoutNotAllowed,
    /// A path without a file name (`..`, `/`).
    #[error("{}: not a file path", .path.display())]
    NotAFilePath { path: PathBuf },
    /// The file system refused to describe the path (its message).
    #[error("{}: {source}", .path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A new file whose folder is something else.
    #[error("{}: {} is not a folder", .path.display(), .folder.display())]
    FolderNotAFolder { path: PathBuf, folder: PathBuf },
    /// A new file whose folder cannot be reached.
    #[error("{}: cannot write into {}: {source}", .path.display(), .folder.display())]
    FolderUnusable {
        path: PathBuf,
        folder: PathBuf,
        source: std::io::Error,
    },
    /// A symbolic link whose target cannot be resolved.
    #[error("{}: a symbolic link whose target cannot be used: {source}", .path.display())]
    BadLink {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A folder.
    #[error("{}: is a folder", .path.display())]
    IsAFolder { path: PathBuf },
    /// A socket or another kind of file that is not written.
    #[error("{}: not a regular file, device or pipe; refusing to write it", .path.display())]
    NotWritable { path: PathBuf },
}

/// An output that cannot be planned or written; messages start with the
/// flag that named it where one did.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// A path of a flag that cannot take an output (checked early).
    #[error("{flag} {}: {source}", .path.display())]
    Early {
        flag: String,
        path: PathBuf,
        source: ResolveError,
    },
    /// A path of a flag that cannot take an output (planned).
    #[error("{flag} {source}")]
    Resolve { flag: String, source: ResolveError },
    /// A path that cannot take an output (no flag to name).
    #[error(transparent)]
    Path(#[from] ResolveError),
    /// A new file's folder that takes no file.
    #[error("{flag} {}: cannot write into its folder: {source}", .path.display())]
    FolderNotWritable {
        flag: String,
        path: PathBuf,
        source: std::io::Error,
    },
    /// An output that cannot be opened for writing, found before any work.
    #[error("{flag} {}: cannot write: {source}", .path.display())]
    NotWritable {
        flag: String,
        path: PathBuf,
        source: std::io::Error,
    },
    /// Writing (or putting in place) the bytes failed.
    #[error("{}: cannot write: {source}", .path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A file name without an extension, so no image format.
    #[error("{flag} {}: no file extension to tell the image format (use .png or .exr)", .path.display())]
    NoExtension { flag: String, path: PathBuf },
    /// A PNM name other than `.ppm` / `.pnm`.
    #[error("{flag} {}: .{extension} is not written (colour PNM images are .ppm)", .path.display())]
    NotPpm {
        flag: String,
        path: PathBuf,
        extension: String,
    },
    /// An extension of no format this build writes.
    #[error("{flag} {}: cannot write {extension:?} images (writable: {})", .path.display(), writable_extensions().join(", "))]
    Unwritable {
        flag: String,
        path: PathBuf,
        extension: String,
    },
    /// An output that is one of the run's input files.
    #[error("{flag} {}: is an input of this run; refusing to overwrite it", .path.display())]
    IsInput { flag: String, path: PathBuf },
    /// Two outputs that name the same file.
    #[error("{flag} {}: the same file as {other_flag} {}; give each output its own path", .path.display(), .other_path.display())]
    SameFile {
        flag: String,
        path: PathBuf,
        other_flag: String,
        other_path: PathBuf,
    },
}

/// The seam for the callers whose errors are still `String`s: `?` turns
/// the error into its message.
impl From<OutputError> for String {
    fn from(e: OutputError) -> String {
        e.to_string()
    }
}

/// The seam for the callers whose errors are still `String`s.
impl From<ResolveError> for String {
    fn from(e: ResolveError) -> String {
        e.to_string()
    }
}

/// Where one output's bytes go.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Sink {
    /// Standard output (`-`).
    Stdout,
    /// An existing device or FIFO, opened and written in place.
    Direct(PathBuf),
    /// A regular file (existing or new): temporary file + rename.
    Atomic(PathBuf),
}

/// One output of a run: the flag that named it (for messages), the path as
/// given, and where it resolves to.
#[derive(Clone, Debug)]
pub struct Output {
    pub flag: String,
    pub path: PathBuf,
    pub sink: Sink,
}

/// Checks, before a long computation, that `path` can take its output:
/// it resolves (a file in an existing folder, a device, a link to either)
/// and its folder takes a new file (a temporary one, removed at once).
pub fn check_early(flag: &str, path: &Path) -> Result<(), OutputError> {
    let sink = resolve(path, false).map_err(|source| OutputError::Early {
        flag: flag.to_string(),
        path: path.to_path_buf(),
        source,
    })?;
    match sink {
        Sink::Atomic(p) => tempfile::NamedTempFile::new_in(folder(&p))
            .map(drop)
            .map_err(|source| OutputError::FolderNotWritable {
                flag: flag.to_string(),
                path: path.to_path_buf(),
                source,
            }),
        Sink::Direct(p) => OpenOptions::new()
            .write(true)
            .open(&p)
            .map(drop)
            .map_err(|source| OutputError::NotWritable {
                flag: flag.to_string(),
                path: path.to_path_buf(),
                source,
            }),
        Sink::Stdout => Ok(()),
    }
}

impl Output {
    /// The output `flag` names at `path` (standard output refused).
    pub fn new(flag: &str, path: &Path) -> Result<Output, OutputError> {
        let sink = resolve(path, false).map_err(|source| OutputError::Resolve {
            flag: flag.to_string(),
            source,
        })?;
        Ok(Output {
            flag: flag.to_string(),
            path: path.to_path_buf(),
            sink,
        })
    }

    /// Writes `bytes` to the output.
    pub fn write(&self, bytes: &[u8]) -> Result<(), OutputError> {
        write_sink(&self.sink, bytes).map_err(|source| self.write_error(source))
    }

    fn write_error(&self, source: std::io::Error) -> OutputError {
        OutputError::Write {
            path: self.path.clone(),
            source,
        }
    }

    /// Writes `bytes` to a temporary file beside a regular file's
    /// destination without replacing it yet (see [`Staged`]); a device or
    /// standard output is written now. A run with several outputs stages
    /// them all before committing any, so a failure in one (a full disk)
    /// leaves every previous file as it was.
    pub fn stage(&self, bytes: &[u8]) -> Result<Staged, OutputError> {
        let fail = |source| self.write_error(source);
        let file = match &self.sink {
            Sink::Atomic(p) => {
                let mut temp = TempFile::create(p).map_err(fail)?;
                temp.fill(bytes).map_err(fail)?;
                Some((temp, p.clone()))
            }
            sink => {
                write_sink(sink, bytes).map_err(fail)?;
                None
            }
        };
        Ok(Staged {
            file,
            shown: self.path.clone(),
        })
    }

    /// The image format its name asks for (`-`, devices and FIFOs without an
    /// extension get `default`); refuses names this build cannot write.
    pub fn image_format(&self, default: ImageFormat) -> Result<ImageFormat, OutputError> {
        let Some(ext) = self.path.extension() else {
            return match self.sink {
                Sink::Atomic(_) => Err(OutputError::NoExtension {
                    flag: self.flag.clone(),
                    path: self.path.clone(),
                }),
                _ => Ok(default),
            };
        };
        let lower = ext.to_string_lossy().to_ascii_lowercase();
        match ImageFormat::from_extension(ext) {
            // The PNM family is written as a colour PPM (`P6`): a name that
            // promises a bitmap, a grey map or PAM would be a lie.
            Some(ImageFormat::Pnm) if lower != "ppm" && lower != "pnm" => {
                Err(OutputError::NotPpm {
                    flag: self.flag.clone(),
                    path: self.path.clone(),
                    extension: lower,
                })
            }
            Some(f) if f.writing_enabled() => Ok(f),
            _ => Err(OutputError::Unwritable {
                flag: self.flag.clone(),
                path: self.path.clone(),
                extension: ext.to_string_lossy().into_owned(),
            }),
        }
    }
}

/// Extensions of every image format this build can write.
pub(crate) fn writable_extensions() -> Vec<&'static str> {
    ImageFormat::all()
        .filter(|f| f.writing_enabled())
        .filter_map(|f| match f {
            ImageFormat::Pnm => Some("ppm"),
            _ => f.extensions_str().first().copied(),
        })
        .collect()
}

/// `path`'s folder, `.` for a bare file name.
fn folder(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Resolves an output path to where its bytes will go.
pub fn resolve(path: &Path, allow_stdout: bool) -> Result<Sink, ResolveError> {
    let io = |source| ResolveError::Io {
        path: path.to_path_buf(),
        source,
    };
    if path.as_os_str() == "-" {
        return if allow_stdout {
            Ok(Sink::Stdout)
        } else {
            Err(ResolveError::StdoutNotAllowed)
        };
    }
    if path.file_name().is_none() {
        return Err(ResolveError::NotAFilePath {
            path: path.to_path_buf(),
        });
    }
    let meta = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let dir = folder(path);
            return match std::fs::metadata(dir) {
                Ok(m) if m.is_dir() => {
                    let dir = std::fs::canonicalize(dir).map_err(|source| ResolveError::Io {
                        path: dir.to_path_buf(),
                        source,
                    })?;
                    Ok(Sink::Atomic(dir.join(path.file_name().expect("checked"))))
                }
                Ok(_) => Err(ResolveError::FolderNotAFolder {
                    path: path.to_path_buf(),
                    folder: dir.to_path_buf(),
                }),
                Err(source) => Err(ResolveError::FolderUnusable {
                    path: path.to_path_buf(),
                    folder: dir.to_path_buf(),
                    source,
                }),
            };
        }
        Err(e) => return Err(io(e)),
    };
    let ft = meta.file_type();
    if ft.is_symlink() {
        // Follow the link and write its target; the link itself stays. A
        // link to a file not made yet (dangling) gets that file.
        let target = match std::fs::canonicalize(path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => link_target(path),
            r => r,
        }
        .map_err(|source| ResolveError::BadLink {
            path: path.to_path_buf(),
            source,
        })?;
        return resolve(&target, false);
    }
    if ft.is_dir() {
        return Err(ResolveError::IsAFolder {
            path: path.to_path_buf(),
        });
    }
    if ft.is_file() {
        return Ok(Sink::Atomic(std::fs::canonicalize(path).map_err(io)?));
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_char_device() || ft.is_block_device() || ft.is_fifo() {
            return Ok(Sink::Direct(path.to_path_buf()));
        }
    }
    Err(ResolveError::NotWritable {
        path: path.to_path_buf(),
    })
}

/// Where a chain of symbolic links ends when its last target does not
/// exist (yet): each relative target is taken from its link's folder.
fn link_target(path: &Path) -> std::io::Result<PathBuf> {
    let mut p = path.to_path_buf();
    // Linux's own limit on links followed in one lookup.
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let target = std::fs::read_link(&p)?;
                p = folder(&p).join(target);
            }
            Ok(_) => return Ok(p),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(p),
            Err(e) => return Err(e),
        }
    }
    Err(std::io::Error::other("too many levels of symbolic links"))
}

/// Resolves every `(flag, path)` of a run and checks them together: no two
/// name the same file, none is one of `inputs`, and each new file's folder
/// takes a file. `allow_stdout` is the flag that may be `-`.
pub fn plan(
    outputs: &[(&str, &Path)],
    inputs: &[PathBuf],
    allow_stdout: Option<&str>,
) -> Result<Vec<Output>, OutputError> {
    let inputs: Vec<PathBuf> = inputs
        .iter()
        .filter_map(|p| std::fs::canonicalize(p).ok())
        .collect();
    let mut planned: Vec<Output> = Vec::new();
    for &(flag, path) in outputs {
        let sink =
            resolve(path, allow_stdout == Some(flag)).map_err(|source| OutputError::Resolve {
                flag: flag.to_string(),
                source,
            })?;
        if let Sink::Direct(p) | Sink::Atomic(p) = &sink {
            let canon = std::fs::canonicalize(p).unwrap_or_else(|_| p.clone());
            if inputs.contains(&canon) {
                return Err(OutputError::IsInput {
                    flag: flag.to_string(),
                    path: path.to_path_buf(),
                });
            }
        }
        if let Some(prev) = planned.iter().find(|o| o.sink == sink) {
            return Err(OutputError::SameFile {
                flag: flag.to_string(),
                path: path.to_path_buf(),
                other_flag: prev.flag.clone(),
                other_path: prev.path.clone(),
            });
        }
        if let Sink::Atomic(p) = &sink {
            // Fails now, not after rendering, if the folder takes no files.
            TempFile::create(p).map_err(|source| OutputError::NotWritable {
                flag: flag.to_string(),
                path: path.to_path_buf(),
                source,
            })?;
        }
        planned.push(Output {
            flag: flag.to_string(),
            path: path.to_path_buf(),
            sink,
        });
    }
    Ok(planned)
}

/// The temporary files that exist right now (created, not yet renamed or
/// removed), for [`remove_temporaries`].
static TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn temporaries() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner())
}

/// Temporary folders (a tonal art map being written), likewise.
static TEMPORARY_DIRS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn temporary_dirs() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    TEMPORARY_DIRS.lock().unwrap_or_else(|e| e.into_inner())
}

/// Removes every temporary output file and folder that exists right now.
/// For a signal handler (SIGINT, SIGTERM) that then ends the process,
/// where destructors do not run; a file being renamed at the same moment
/// is either removed or already in place.
pub fn remove_temporaries() {
    for p in temporaries().drain(..) {
        let _ = std::fs::remove_file(p);
    }
    for p in temporary_dirs().drain(..) {
        let _ = std::fs::remove_dir_all(p);
    }
}

/// Lists a temporary folder for [`remove_temporaries`] while the guard
/// lives; its owner removes it on every other path (`tempfile::TempDir`).
pub struct TemporaryDir(PathBuf);

impl TemporaryDir {
    pub fn track(path: &Path) -> TemporaryDir {
        temporary_dirs().push(path.to_path_buf());
        TemporaryDir(path.to_path_buf())
    }
}

impl Drop for TemporaryDir {
    fn drop(&mut self) {
        temporary_dirs().retain(|p| *p != self.0);
    }
}

/// A temporary file beside its destination (`tempfile`'s `NamedTempFile`),
/// removed when dropped unless renamed into place: no error path (or panic)
/// leaves it behind, and while it exists its path is listed for
/// [`remove_temporaries`].
struct TempFile(Option<tempfile::NamedTempFile>);

impl Drop for TempFile {
    fn drop(&mut self) {
        let mut list = temporaries();
        if let Some(f) = &self.0 {
            list.retain(|p| p != f.path());
        }
    }
}

impl TempFile {
    fn create(dest: &Path) -> std::io::Result<TempFile> {
        let name = dest
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let prefix = format!(".{name}.");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        // tempfile's default mode is 0600; an output is an ordinary file,
        // so it gets what creating it in place would give (0666 less the
        // umask).
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let mut list = temporaries();
        let file = builder.tempfile_in(folder(dest))?;
        list.push(file.path().to_path_buf());
        Ok(TempFile(Some(file)))
    }

    fn file(&mut self) -> &mut tempfile::NamedTempFile {
        self.0
            .as_mut()
            .expect("a TempFile holds its file until placed")
    }

    /// Writes all of `bytes` and makes sure they reached the disk (a full
    /// disk may only show at sync).
    fn fill(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        let f = self.file().as_file_mut();
        f.write_all(bytes)?;
        f.sync_all()
    }

    /// Renames the file to `dest`.
    fn place(mut self, dest: &Path) -> std::io::Result<()> {
        let path = self.file().path().to_path_buf();
        let file = self.0.take().expect("held until placed");
        // On failure the error owns the temporary file and removes it.
        let placed = file.persist(dest).map(drop).map_err(|e| e.error);
        temporaries().retain(|p| *p != path);
        placed
    }
}

/// An output whose bytes are written but not yet in place: a regular
/// file's temporary file, renamed by `Staged::commit` (and removed if
/// dropped uncommitted); devices and standard output are written by
/// [`Output::stage`] itself and have nothing left to do.
pub struct Staged {
    file: Option<(TempFile, PathBuf)>,
    shown: PathBuf,
}

impl Staged {
    /// Puts the file in place.
    pub(crate) fn commit(self) -> Result<(), OutputError> {
        match self.file {
            Some((temp, dest)) => temp.place(&dest).map_err(|source| OutputError::Write {
                path: self.shown,
                source,
            }),
            None => Ok(()),
        }
    }
}

/// Commits every staged output, in order. Each is a rename within its
/// folder, so after the first the rest fail only if a folder changes
/// underneath the run.
pub fn commit_all(staged: Vec<Staged>) -> Result<(), OutputError> {
    staged.into_iter().try_for_each(Staged::commit)
}

fn write_sink(sink: &Sink, bytes: &[u8]) -> std::io::Result<()> {
    match sink {
        Sink::Stdout => {
            let mut out = std::io::stdout().lock();
            out.write_all(bytes)?;
            out.flush()
        }
        Sink::Direct(p) => {
            let mut f = OpenOptions::new().write(true).open(p)?;
            f.write_all(bytes)?;
            f.flush()
        }
        Sink::Atomic(p) => {
            let mut temp = TempFile::create(p)?;
            temp.fill(bytes)?;
            temp.place(p)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("specula-outputs-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn devices_are_written_through_and_a_full_disk_is_reported() {
        let sink = resolve(Path::new("/dev/null"), false).unwrap();
        assert_eq!(sink, Sink::Direct("/dev/null".into()));
        write_sink(&sink, b"x").unwrap();
        if Path::new("/dev/full").exists() {
            let e = write_sink(&resolve(Path::new("/dev/full"), false).unwrap(), b"x").unwrap_err();
            assert_eq!(e.raw_os_error(), Some(28), "ENOSPC, got {e}");
        }
    }

    #[test]
    fn symlinks_are_followed_and_kept() {
        let d = dir("link");
        std::fs::write(d.join("real.png"), b"old").unwrap();
        std::os::unix::fs::symlink(d.join("real.png"), d.join("link.png")).unwrap();
        let plan = plan(&[("-o", &d.join("link.png"))], &[], None).unwrap();
        plan[0].write(b"new").unwrap();
        assert!(std::fs::symlink_metadata(d.join("link.png"))
            .unwrap()
            .is_symlink());
        assert_eq!(std::fs::read(d.join("real.png")).unwrap(), b"new");
        let names: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 2, "no temporary file is left: {names:?}");
    }

    #[test]
    fn duplicates_inputs_and_missing_folders_are_refused() {
        let d = dir("dup");
        let a = d.join("a.exr");
        let e = plan(
            &[("-o", &a), ("--exr", &d.join(".").join("a.exr"))],
            &[],
            None,
        )
        .unwrap_err();
        assert!(matches!(&e, OutputError::SameFile { flag, other_flag, .. }
            if flag == "--exr" && other_flag == "-o"));
        let e = e.to_string();
        assert!(
            e.contains("--exr") && e.contains("the same file as -o"),
            "{e}"
        );
        std::fs::write(d.join("m.mtl"), b"").unwrap();
        let e = plan(
            &[("--stats-json", &d.join("m.mtl"))],
            &[d.join("m.mtl")],
            None,
        )
        .unwrap_err();
        assert!(matches!(e, OutputError::IsInput { .. }), "{e}");
        assert!(e.to_string().contains("input"), "{e}");
        // A folder this test owns and never makes, so it is missing on
        // any machine.
        let missing = d.join("missing-folder").join("s.json");
        let e = plan(&[("--stats-json", &missing)], &[], None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("--stats-json") && e.contains("missing-folder"),
            "{e}"
        );
        let e = plan(&[("-o", &d)], &[], None).unwrap_err();
        assert!(
            matches!(
                &e,
                OutputError::Resolve {
                    source: ResolveError::IsAFolder { .. },
                    ..
                }
            ),
            "{e}"
        );
        assert_eq!(e.to_string(), format!("-o {}: is a folder", d.display()));
        assert!(
            std::fs::read_dir(&d).unwrap().count() == 1,
            "the probe left nothing"
        );
    }

    #[test]
    fn a_temporary_file_never_outlives_a_failed_write() {
        let d = dir("tmp");
        // Renaming onto a non-empty folder fails after the bytes are written.
        std::fs::create_dir_all(d.join("busy.png").join("x")).unwrap();
        let e = write_sink(&Sink::Atomic(d.join("busy.png")), b"bytes").unwrap_err();
        assert!(e.to_string().to_lowercase().contains("directory"), "{e}");
        let names: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("busy.png")]);
        drop(TempFile::create(&d.join("a.png")).unwrap());
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
    }
}
