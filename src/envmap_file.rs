//! Environment map files: Radiance RGBE (`.hdr`) and OpenEXR, decoded by
//! `image` into linear RGB, with the checks that keep a bad file from
//! costing memory or reaching a pixel as NaN:
//!
//! - the format is sniffed from the bytes: anything but Radiance HDR or
//!   OpenEXR is refused;
//! - the size is read from the header and checked before any texel is
//!   decoded: at least 2×2, at most `MAX_SIDE` per side, and the
//!   decoded map with its derived data within the memory budget
//!   (memory.rs);
//! - a truncated or corrupt file is the decoder's error, with the file
//!   named;
//! - texels: NaN and negative values become 0, values above
//!   [`specula_raster::equirect::MAX_TEXEL`] (and +inf) become that
//!   (envmap.rs), so every derived sum stays finite.
//!
//! The derived data (the sun taken out of the map, the prefiltered chain
//! and SH irradiance of the rest: raster's envmap_sun.rs and envmap.rs)
//! is kept in the table cache (table_cache.rs), keyed by a hash of the file's bytes and
//! the settings it depends on.

use specula_raster::envmap::{EnvMap, IblMethod, PREFILTER_LEVELS};
use specula_raster::equirect::Equirect;
use std::io::Cursor;

/// An environment map file refused; each message starts with the name
/// the caller gave the file.
#[derive(Debug, thiserror::Error)]
pub enum EnvMapError {
    /// The bytes cannot be sniffed for a format.
    #[error("{name}: {source}")]
    Sniff {
        name: String,
        source: std::io::Error,
    },
    /// An image, but not of linear radiance.
    #[error("{name}: a {format:?} image; an environment map is a Radiance HDR (.hdr) or OpenEXR (.exr) file of linear radiance")]
    NotRadiance {
        name: String,
        format: image::ImageFormat,
    },
    /// No image format recognised.
    #[error("{name}: not a Radiance HDR (.hdr) or OpenEXR (.exr) file")]
    Unknown { name: String },
    /// The header cannot be read.
    #[error("{name}: cannot read the header: {source}")]
    Header {
        name: String,
        source: image::ImageError,
    },
    /// Fewer than 2×2 texels.
    #[error("{name}: the map is {width}×{height}: an environment map needs at least 2×2 texels")]
    TooSmall {
        name: String,
        width: u32,
        height: u32,
    },
    /// A side above `MAX_SIDE`.
    #[error("{name}: the header says {width}×{height}: an environment map is at most {MAX_SIDE} texels on a side")]
    TooLarge {
        name: String,
        width: u32,
        height: u32,
    },
    /// The memory budget refused the map (the message names the file).
    #[error(transparent)]
    Memory(#[from] crate::memory::OverBudget),
    /// A truncated or corrupt file (the decoder's message).
    #[error("{name}: {source}")]
    Decode {
        name: String,
        source: image::ImageError,
    },
    /// The decoded texels refused as a map.
    #[error("{name}: {source}")]
    Map {
        name: String,
        source: specula_raster::envmap::EnvMapError,
    },
}

/// The seam for the callers whose errors are still `String`s: `?` turns
/// the error into its message.
impl From<EnvMapError> for String {
    fn from(e: EnvMapError) -> String {
        e.to_string()
    }
}

/// Largest side of a map: 32768 texels.
pub(crate) const MAX_SIDE: u32 = 32768;

/// Bytes per source texel from decode to the end of a frame: the decoded
/// RGBA f32 image, our RGB copy, its mips, the sampling distribution.
const TEXEL_BYTES: u64 = 16 + 12 + 4 + 12;

/// Bytes of the prefiltered chain at its largest (1024² level 0).
const PREFILTER_BYTES: u64 = 1024 * 1024 * 12 * 4 / 3 + (1 << 20);

/// What a map of `w`×`h` texels costs in memory.
pub(crate) fn env_map_bytes(w: u64, h: u64) -> u64 {
    w.saturating_mul(h)
        .saturating_mul(TEXEL_BYTES)
        .saturating_add(PREFILTER_BYTES)
}

/// The settings of a map besides its file.
pub struct EnvSettings {
    pub intensity: f32,
    pub rotate_deg: f32,
    pub visible: bool,
    pub method: IblMethod,
}

/// Decodes an environment map file's bytes (`name` in messages).
pub fn decode_equirect(name: &str, bytes: &[u8]) -> Result<Equirect, EnvMapError> {
    let reader = || {
        image::ImageReader::new(Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|source| EnvMapError::Sniff {
                name: name.to_string(),
                source,
            })
    };
    match reader()?.format() {
        Some(image::ImageFormat::Hdr | image::ImageFormat::OpenExr) => {}
        Some(format) => {
            return Err(EnvMapError::NotRadiance {
                name: name.to_string(),
                format,
            })
        }
        None => {
            return Err(EnvMapError::Unknown {
                name: name.to_string(),
            })
        }
    }
    let (w, h) = reader()?
        .into_dimensions()
        .map_err(|source| EnvMapError::Header {
            name: name.to_string(),
            source,
        })?;
    if w < 2 || h < 2 {
        return Err(EnvMapError::TooSmall {
            name: name.to_string(),
            width: w,
            height: h,
        });
    }
    if w > MAX_SIDE || h > MAX_SIDE {
        return Err(EnvMapError::TooLarge {
            name: name.to_string(),
            width: w,
            height: h,
        });
    }
    crate::memory::reserve(
        &format!("environment map {name} ({w}×{h})"),
        env_map_bytes(w as u64, h as u64),
    )?;
    let mut r = reader()?;
    r.no_limits();
    let img = r
        .decode()
        .map_err(|source| EnvMapError::Decode {
            name: name.to_string(),
            source,
        })?
        .into_rgb32f();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let texels = img
        .into_raw()
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    Ok(Equirect {
        width: w,
        height: h,
        texels,
    })
}

/// The map from a file's bytes (decoded and checked by
/// [`decode_equirect`], texels clamped and scaled by the settings), its
/// derived data not yet built ([`EnvMap::prepare`]).
pub(crate) fn new_env_map(
    name: &str,
    bytes: &[u8],
    s: &EnvSettings,
) -> Result<EnvMap, EnvMapError> {
    let source = decode_equirect(name, bytes)?;
    EnvMap::new(source, s.intensity, s.rotate_deg, s.visible, s.method).map_err(|source| {
        EnvMapError::Map {
            name: name.to_string(),
            source,
        }
    })
}

/// The map from a file's bytes with its derived data: from the table
/// cache when it holds them, else built (with a progress bar on stderr
/// for maps of a million texels and more) and stored there.
pub fn load_env_map(name: &str, bytes: &[u8], s: &EnvSettings) -> Result<EnvMap, EnvMapError> {
    let mut map = new_env_map(name, bytes, s)?;
    let texels = map.source.width * map.source.height;
    let key = cache_key(bytes, s.intensity);
    if let Some(derived) = load_cached(&key) {
        if map.set_derived(derived) {
            return Ok(map);
        }
    }
    if texels >= 1 << 20 {
        let bar = indicatif::ProgressBar::new(1);
        bar.set_style(
            indicatif::ProgressStyle::with_template("prefiltering {msg} {bar:30} {percent}%")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar.set_message(name.to_string());
        map.prepare(&|done, total| {
            bar.set_length(total);
            bar.set_position(done);
        });
        bar.finish_and_clear();
    } else {
        map.prepare(&|_, _| {});
    }
    store_cached(&key, &map);
    Ok(map)
}

/// The cache name of a map's derived data: the prefilter format's
/// version, a hash of the file and the intensity (the rotation and the
/// rest are applied at lookup). The version names how the data are
/// computed, not only how they are stored: any change to the SH, the
/// chain's sampling or the sun's extraction bumps it, or a cache written
/// by the code before (a user's, a developer's) is read as if current.
fn cache_key(bytes: &[u8], intensity: f32) -> String {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    h.update(bytes);
    h.update(intensity.to_le_bytes());
    let d = h.finalize();
    let hex: String = d[..12].iter().map(|b| format!("{b:02x}")).collect();
    format!("envmap-v6-{hex}")
}

/// Layout of a cached file (f32 little-endian): the 27 SH values, a flag
/// (1: the map has a sun) and the sun's 7 values (zeros without one),
/// then per level its side and its three planes.
fn load_cached(key: &str) -> Option<specula_raster::envmap::Derived> {
    let dir = crate::table_cache::cache_dir()?;
    let bytes = std::fs::read(dir.join(format!("{key}.f32"))).ok()?;
    if bytes.len() % 4 != 0 {
        return None;
    }
    let v: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    if v.iter().any(|x| !x.is_finite()) || v.len() < 35 {
        return None;
    }
    let sh = std::array::from_fn(|k| [v[3 * k], v[3 * k + 1], v[3 * k + 2]]);
    let sun = match v[27] {
        0.0 => None,
        1.0 => Some(specula_raster::envmap_sun::Sun::from_values(&v[28..35])?),
        _ => return None,
    };
    let mut at = 35;
    let mut levels = Vec::new();
    for _ in 0..PREFILTER_LEVELS {
        let n = *v.get(at)? as usize;
        at += 1;
        let len = n.checked_mul(n)?;
        let plane = |at: usize| v.get(at..at + len).map(<[f32]>::to_vec);
        let rgb = [plane(at)?, plane(at + len)?, plane(at + 2 * len)?];
        at += 3 * len;
        levels.push((n, rgb));
    }
    (at == v.len()).then_some((sh, levels, sun))
}

fn store_cached(key: &str, map: &EnvMap) {
    let Some(dir) = crate::table_cache::cache_dir() else {
        return;
    };
    let (sh, levels, sun) = map.derived();
    let mut v: Vec<f32> = sh.iter().flatten().copied().collect();
    v.push(if sun.is_some() { 1.0 } else { 0.0 });
    v.extend_from_slice(&sun.map_or([0.0; 7], |s| s.to_values()));
    for (n, rgb) in &levels {
        v.push(*n as f32);
        for p in rgb {
            v.extend_from_slice(p);
        }
    }
    use specula_core::kulla_conty::TableStore;
    crate::table_cache::DirStore { dir }.save(key, &v);
}
