//! A memory budget: what a run will allocate is estimated before it is
//! allocated, and refused with a clear error over the limit, instead of
//! the allocator aborting (SIGABRT) or the machine swapping.
//!
//! The costs below were measured (peak RSS, `/usr/bin/time -f %M`, one
//! thread): a cube of 512 and 1024 segments per side (3.1 M and 12.6 M
//! triangles) peaked at 379 MB and 1347 MB, about 102 bytes per triangle
//! with its half vertex; images of 1024², 2048², 4096² samples at 30, 101,
//! 384 MB, about 22.5 bytes per sample; EXR plus three AOVs added about 51
//! bytes per sample at 2048². The constants round these up.

use std::sync::atomic::{AtomicU64, Ordering};

/// Bytes per mesh vertex and per triangle, from load to the end of a frame
/// (mesh arrays, scene copies, clip-space vertices, setup and bins).
const VERTEX_BYTES: u64 = 64;
const TRIANGLE_BYTES: u64 = 72;
/// Bytes per vertex of a glTF mesh with vertex colours, on top of
/// [`mesh_bytes`]: its RGBA (4 f32) in the mesh and in the scene.
pub(crate) const COLOR_VERTEX_BYTES: u64 = 32;
/// Bytes per OBJ byte while tobj parses it (text, parsed arrays, our copy).
const OBJ_BYTES_PER_BYTE: u64 = 8;
/// Bytes per supersample: visibility buffer, colour, resolve.
const SAMPLE_BYTES: u64 = 24;
/// Bytes per supersample for each AOV (its buffer and encoded copy).
const AOV_SAMPLE_BYTES: u64 = 20;
/// Bytes per output pixel of an HDR image (resolved colour, encoded copy).
const HDR_PIXEL_BYTES: u64 = 28;
/// The program and its tables before any scene.
const BASE_BYTES: u64 = 16 << 20;

static LIMIT: AtomicU64 = AtomicU64::new(u64::MAX);
static RESERVED: AtomicU64 = AtomicU64::new(BASE_BYTES);

/// Sets the budget for the rest of the run (the default is no limit, for
/// library users; the CLI sets [`default_limit`] or `--max-memory`).
pub fn set_limit(bytes: u64) {
    LIMIT.store(bytes, Ordering::Relaxed);
}

/// Forgets everything reserved so far, for a process that loads one
/// scene after another (the fuzz targets, `fuzzing.rs`); the CLI loads
/// one scene per run and never calls it.
pub(crate) fn reset_reserved() {
    RESERVED.store(BASE_BYTES, Ordering::Relaxed);
}

/// A reservation the budget refused: what asked, for how many bytes, on
/// top of how many already planned, against which limit.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "{what} needs about {} of memory, and with what is already planned ({}) that exceeds the limit of {} (set it with --max-memory)",
    show(*.bytes),
    show(*.planned),
    show(*.limit)
)]
pub struct OverBudget {
    pub(crate) what: String,
    pub(crate) bytes: u64,
    pub(crate) planned: u64,
    pub(crate) limit: u64,
}

/// The seam for the callers whose errors are still `String`s: `?` turns
/// the refusal into its message.
impl From<OverBudget> for String {
    fn from(e: OverBudget) -> String {
        e.to_string()
    }
}

/// Counts `bytes` against the budget, or refuses them naming `what`.
pub fn reserve(what: &str, bytes: u64) -> Result<(), OverBudget> {
    let limit = LIMIT.load(Ordering::Relaxed);
    let before = RESERVED.fetch_add(bytes, Ordering::Relaxed);
    let after = before.saturating_add(bytes);
    if after > limit {
        RESERVED.fetch_sub(bytes, Ordering::Relaxed);
        return Err(OverBudget {
            what: what.to_string(),
            bytes,
            planned: before,
            limit,
        });
    }
    Ok(())
}

/// Estimated bytes of a mesh of `vertices` and `triangles`.
pub(crate) fn mesh_bytes(vertices: u64, triangles: u64) -> u64 {
    vertices
        .saturating_mul(VERTEX_BYTES)
        .saturating_add(triangles.saturating_mul(TRIANGLE_BYTES))
}

/// Estimated bytes of an OBJ file of `len` bytes while and after it loads.
pub(crate) fn obj_bytes(len: u64) -> u64 {
    len.saturating_mul(OBJ_BYTES_PER_BYTE)
}

/// Estimated bytes of rendering `samples` supersamples with `aovs` AOVs
/// and `hdr_images` HDR outputs of `pixels` pixels each.
pub fn image_bytes(samples: u64, pixels: u64, aovs: u64, hdr_images: u64) -> u64 {
    samples
        .saturating_mul(SAMPLE_BYTES + aovs * AOV_SAMPLE_BYTES)
        .saturating_add(pixels.saturating_mul(hdr_images * HDR_PIXEL_BYTES))
}

/// The default budget: three quarters of the machine's memory, or of the
/// control group's limit when that is lower; no limit if neither is known.
pub fn default_limit() -> u64 {
    let total = std::fs::read_to_string("/proc/meminfo").ok().and_then(|m| {
        let line = m.lines().find(|l| l.starts_with("MemTotal:"))?;
        let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kb * 1024)
    });
    let cgroup = std::fs::read_to_string("/sys/fs/cgroup/memory.max")
        .ok()
        .and_then(|s| s.trim().parse::<u64>().ok());
    match (total, cgroup) {
        (Some(t), Some(c)) => t.min(c) / 4 * 3,
        (Some(v), None) | (None, Some(v)) => v / 4 * 3,
        (None, None) => u64::MAX,
    }
}

/// A `--max-memory` value that is not a size (the text as given).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SizeError {
    #[error("{0:?}: unknown unit (K, M, G, T)")]
    UnknownUnit(String),
    #[error("{0:?}: not a size (e.g. 4G, 512M, 1000000)")]
    NotASize(String),
    #[error("{0:?}: must be a positive size")]
    NotPositive(String),
}

/// Parses a size: bytes, or a number with K, M, G or T (powers of 1024,
/// an optional trailing B or iB).
pub fn parse_size(s: &str) -> Result<u64, SizeError> {
    let t = s.trim();
    let t = t
        .strip_suffix("iB")
        .or_else(|| t.strip_suffix('B'))
        .unwrap_or(t);
    let (num, shift) = match t.chars().last() {
        Some(c) if c.is_ascii_alphabetic() => {
            let shift = match c.to_ascii_uppercase() {
                'K' => 10,
                'M' => 20,
                'G' => 30,
                'T' => 40,
                _ => return Err(SizeError::UnknownUnit(s.to_string())),
            };
            (&t[..t.len() - 1], shift)
        }
        _ => (t, 0),
    };
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| SizeError::NotASize(s.to_string()))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(SizeError::NotPositive(s.to_string()));
    }
    Ok((v * (1u64 << shift) as f64).min(u64::MAX as f64) as u64)
}

/// A size for messages: "3.5 GB" (powers of 1024).
fn show(bytes: u64) -> String {
    if bytes == u64::MAX {
        return "no limit".into();
    }
    let units = ["B", "KB", "MB", "GB", "TB", "PB", "EB"];
    let mut v = bytes as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    format!("{v:.1} {}", units[u])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_units() {
        assert_eq!(parse_size("4G").unwrap(), 4 << 30);
        assert_eq!(parse_size("512MiB").unwrap(), 512 << 20);
        assert_eq!(parse_size("1.5k").unwrap(), 1536);
        assert_eq!(parse_size("1000").unwrap(), 1000);
        assert!(parse_size("-1G").is_err());
        assert!(parse_size("4X").is_err());
        assert_eq!(show(3 << 29), "1.5 GB");
    }

    /// Each refusal is its own kind, and prints the text the CLI always
    /// printed for it.
    #[test]
    fn size_errors_name_the_text_given() {
        assert_eq!(parse_size("4X"), Err(SizeError::UnknownUnit("4X".into())));
        assert_eq!(
            parse_size("4X").unwrap_err().to_string(),
            "\"4X\": unknown unit (K, M, G, T)"
        );
        assert_eq!(
            parse_size("lots"),
            Err(SizeError::UnknownUnit("lots".into()))
        );
        assert_eq!(
            parse_size("1.2.3").unwrap_err().to_string(),
            "\"1.2.3\": not a size (e.g. 4G, 512M, 1000000)"
        );
        assert_eq!(
            parse_size("0").unwrap_err().to_string(),
            "\"0\": must be a positive size"
        );
    }

    /// A refusal carries the sizes it compared and prints them in units.
    #[test]
    fn over_budget_prints_its_sizes() {
        let e = OverBudget {
            what: "a mesh".into(),
            bytes: 3 << 29,
            planned: 1 << 20,
            limit: u64::MAX,
        };
        assert_eq!(
            e.to_string(),
            "a mesh needs about 1.5 GB of memory, and with what is already planned (1.0 MB) \
             that exceeds the limit of no limit (set it with --max-memory)"
        );
    }
}
