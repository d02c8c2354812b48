//! Tonal art maps \[Praun01\]: a tone × mip-level set of hatching textures,
//! drawn with tiny-skia strokes.
//!
//! - Tones run from light to dark; tone t's target mean darkness (ink
//!   coverage, 0 = paper, 1 = ink everywhere) is
//!   `MAX_DARKNESS · (t + 1) / tones`.
//! - Nesting in tone: tone t + 1 starts from every stroke of tone t and
//!   adds its own, so a pixel is never lighter in a darker tone.
//! - Nesting in resolution, and the same stroke width at every level: for
//!   each tone the levels are filled coarsest first; a stroke added while a
//!   level is being filled is drawn on it and on every finer level, at the
//!   same place in texture space and the same width in *pixels*
//!   (`STROKE_WIDTH_PX`). A coarse level therefore gets fewer, relatively
//!   thicker strokes and is exactly as dark as a fine one, not denser — the
//!   point of a TAM over mip-mapping one drawing.
//! - A level is done when its darkness is within `TOLERANCE` below the
//!   target; a stroke that would take it more than `TOLERANCE` past the
//!   target is halved in length until it fits (or is one pixel long).
//! - Light tones hatch along u (within ±`ANGLE_JITTER`); tones in the
//!   darker half add strokes along v (cross-hatching). Strokes wrap around
//!   the texture edges, so the maps tile.
//! - Seeded (ChaCha8): the same parameters give the same bytes.
//!
//! Files (`specula tam`): `tam_t{tone}_l{level}.png`, 8-bit grey, value =
//! paper brightness as linear coverage (255 paper, 0 ink), level 0 the
//! largest, plus `tam.json` ([`Manifest`]).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use specula_raster::texture::Texture;
use std::path::{Path, PathBuf};
use tiny_skia::{LineCap, Paint, PathBuilder, Pixmap, Stroke, Transform};

/// Darkness of the darkest tone.
pub const MAX_DARKNESS: f64 = 0.8;
/// Width of every stroke, in pixels of the level it is drawn on.
pub(crate) const STROKE_WIDTH_PX: f32 = 1.25;
/// How close to its target a level's darkness is brought (both ways).
pub(crate) const TOLERANCE: f64 = 0.005;
/// Largest deviation of a stroke from its tone's direction, radians.
pub(crate) const ANGLE_JITTER: f64 = 0.12;
/// Stroke lengths are drawn from this range, in texture units.
const LENGTH: (f64, f64) = (0.2, 0.5);
/// Smallest level size: at 16 × 16 a one-pixel stroke moves the darkness
/// by well under the tolerance of the tests (0.02).
pub(crate) const MIN_LEVEL_SIZE: u32 = 16;
/// Strokes tried per tone and level before giving up (never reached for
/// valid parameters; a guard against looping forever).
const MAX_STROKES: usize = 200_000;

/// What can go wrong generating, writing or reading a tonal art map. Each
/// message names the option, tone and level, or file it is about.
#[derive(Debug, thiserror::Error)]
pub enum TamError {
    /// A generation option out of range.
    #[error("{option}: {reason}")]
    Option {
        option: &'static str,
        reason: String,
    },
    /// A tone whose darkness the stroke budget could not reach.
    #[error("tone {tone} level {level}: darkness {reached:.3} did not reach {target:.3} in {MAX_STROKES} strokes")]
    Unreachable {
        tone: usize,
        level: usize,
        reached: f64,
        target: f64,
    },
    /// Reading or writing a file of the map.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// `tam.json` is not a manifest.
    #[error("{}: {source}", path.display())]
    Manifest {
        path: PathBuf,
        source: serde_json::Error,
    },
    /// An image of the map could not be decoded or encoded.
    #[error("{}: {source}", path.display())]
    Image {
        path: PathBuf,
        source: image::ImageError,
    },
    /// A file whose content disagrees with the manifest or the limits.
    #[error("{}: {reason}", path.display())]
    Invalid { path: PathBuf, reason: String },
    /// Tones, levels and darkness values that do not make a map.
    #[error("{0}")]
    Layout(String),
    /// The drawn levels refused as a texture.
    #[error(transparent)]
    Texture(#[from] specula_raster::texture::TextureError),
    /// The caller's memory budget refused the map (its message).
    #[error("{0}")]
    Budget(String),
}

impl TamError {
    fn io(path: &Path) -> impl FnOnce(std::io::Error) -> TamError + '_ {
        move |source| TamError::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    fn image(path: &Path) -> impl FnOnce(image::ImageError) -> TamError + '_ {
        move |source| TamError::Image {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// What `specula tam` takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct TamParams {
    pub tones: usize,
    pub levels: usize,
    /// Width and height of level 0, a power of two.
    pub size: u32,
    pub seed: u64,
}

impl TamParams {
    /// `tones` tones of `size` with as many levels as fit down to
    /// `MIN_LEVEL_SIZE`.
    pub fn new(tones: usize, size: u32, seed: u64) -> TamParams {
        TamParams {
            tones,
            levels: Self::max_levels(size),
            size,
            seed,
        }
    }

    /// Levels from `size` down to [`MIN_LEVEL_SIZE`] (at least 1).
    pub(crate) fn max_levels(size: u32) -> usize {
        let mut n = 1;
        let mut s = size;
        while s / 2 >= MIN_LEVEL_SIZE {
            s /= 2;
            n += 1;
        }
        n
    }

    /// Checks the ranges; the error names the option.
    pub(crate) fn validate(&self) -> Result<(), TamError> {
        if !(1..=16).contains(&self.tones) {
            return Err(TamError::Option {
                option: "tones",
                reason: format!("must be in 1..=16, got {}", self.tones),
            });
        }
        if !self.size.is_power_of_two() || !(MIN_LEVEL_SIZE..=4096).contains(&self.size) {
            return Err(TamError::Option {
                option: "size",
                reason: format!(
                    "must be a power of two in {MIN_LEVEL_SIZE}..=4096, got {}",
                    self.size
                ),
            });
        }
        let max = Self::max_levels(self.size);
        if !(1..=max).contains(&self.levels) {
            return Err(TamError::Option {
                option: "levels",
                reason: format!(
                    "must be in 1..={max} for size {} (the smallest level is at least {MIN_LEVEL_SIZE}×{MIN_LEVEL_SIZE}), got {}",
                    self.size, self.levels
                ),
            });
        }
        Ok(())
    }

    /// Target darkness of tone `t`.
    pub(crate) fn target(&self, t: usize) -> f64 {
        MAX_DARKNESS * (t + 1) as f64 / self.tones as f64
    }

    /// Width (= height) of level `l`.
    pub(crate) fn level_size(&self, l: usize) -> u32 {
        self.size >> l
    }
}

/// One generated map: `images[tone][level]`, each `size_l²` bytes row-major
/// (255 paper, 0 ink).
#[derive(Clone, Debug, PartialEq)]
pub struct Tam {
    pub params: TamParams,
    /// Target darkness per tone.
    pub darkness: Vec<f64>,
    pub images: Vec<Vec<Vec<u8>>>,
}

/// A straight stroke in texture space ([0, 1]², wrapping).
#[derive(Clone, Copy, Debug)]
struct StrokeUv {
    start: (f64, f64),
    angle: f64,
    length: f64,
}

/// Draws `s` on a level of `n` pixels, with copies shifted by ±n wherever
/// it crosses an edge.
fn draw(pix: &mut Pixmap, s: &StrokeUv, n: u32) {
    let nf = n as f64;
    let (x0, y0) = (s.start.0 * nf, s.start.1 * nf);
    let (x1, y1) = (
        x0 + s.angle.cos() * s.length * nf,
        y0 + s.angle.sin() * s.length * nf,
    );
    let paint = Paint {
        anti_alias: true,
        ..Paint::default()
    }; // default colour: opaque black
    let stroke = Stroke {
        width: STROKE_WIDTH_PX,
        line_cap: LineCap::Butt,
        ..Stroke::default()
    };
    let pad = STROKE_WIDTH_PX as f64;
    let range = |a: f64, b: f64| {
        let (lo, hi) = (a.min(b) - pad, a.max(b) + pad);
        [-1i32, 0, 1]
            .into_iter()
            .filter(move |k| hi + *k as f64 * nf > 0.0 && lo + *k as f64 * nf < nf)
    };
    for kx in range(x0, x1) {
        for ky in range(y0, y1) {
            let (dx, dy) = (kx as f64 * nf, ky as f64 * nf);
            let mut pb = PathBuilder::new();
            pb.move_to((x0 + dx) as f32, (y0 + dy) as f32);
            pb.line_to((x1 + dx) as f32, (y1 + dy) as f32);
            if let Some(path) = pb.finish() {
                pix.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
            }
        }
    }
}

/// Mean ink coverage of an opaque pixmap drawn black on white.
fn darkness(pix: &Pixmap) -> f64 {
    let sum: u64 = pix.data().chunks_exact(4).map(|p| p[0] as u64).sum();
    1.0 - sum as f64 / (255.0 * (pix.width() * pix.height()) as f64)
}

/// Mean darkness of a grey image as [`Tam`] stores it.
pub fn grey_darkness(img: &[u8]) -> f64 {
    1.0 - img.iter().map(|&v| v as u64).sum::<u64>() as f64 / (255.0 * img.len() as f64)
}

/// Generates a map; see the module docs.
pub fn generate(params: TamParams) -> Result<Tam, TamError> {
    params.validate()?;
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let sizes: Vec<u32> = (0..params.levels).map(|l| params.level_size(l)).collect();
    let mut pix: Vec<Pixmap> = sizes
        .iter()
        .map(|&n| {
            let mut p = Pixmap::new(n, n).expect("sizes are validated");
            p.fill(tiny_skia::Color::WHITE);
            p
        })
        .collect();
    let mut images = Vec::with_capacity(params.tones);
    let mut dark = vec![0.0f64; params.levels];
    for t in 0..params.tones {
        let target = params.target(t);
        let cross = 2 * t >= params.tones && params.tones > 1;
        for l in (0..params.levels).rev() {
            let n = sizes[l];
            let mut tries = 0;
            while dark[l] < target - TOLERANCE {
                tries += 1;
                if tries > MAX_STROKES {
                    return Err(TamError::Unreachable {
                        tone: t,
                        level: l,
                        reached: dark[l],
                        target,
                    });
                }
                let along_v = cross && rng.random_bool(0.5);
                let base = if along_v {
                    std::f64::consts::FRAC_PI_2
                } else {
                    0.0
                };
                let mut s = StrokeUv {
                    start: (rng.random::<f64>(), rng.random::<f64>()),
                    angle: base + rng.random_range(-ANGLE_JITTER..=ANGLE_JITTER),
                    length: rng.random_range(LENGTH.0..LENGTH.1),
                };
                let (trial, d) = loop {
                    let mut trial = pix[l].clone();
                    draw(&mut trial, &s, n);
                    let d = darkness(&trial);
                    if d <= target + TOLERANCE || s.length * n as f64 <= 1.0 {
                        break (trial, d);
                    }
                    s.length *= 0.5;
                };
                pix[l] = trial;
                dark[l] = d;
                for f in 0..l {
                    draw(&mut pix[f], &s, sizes[f]);
                    dark[f] = darkness(&pix[f]);
                }
            }
        }
        images.push(
            pix.iter()
                .map(|p| p.data().chunks_exact(4).map(|c| c[0]).collect())
                .collect(),
        );
    }
    Ok(Tam {
        darkness: (0..params.tones).map(|t| params.target(t)).collect(),
        params,
        images,
    })
}

/// `tam.json`: what a directory of maps holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    pub(crate) tones: usize,
    pub(crate) levels: usize,
    /// Level sizes, level 0 first.
    pub sizes: Vec<u32>,
    /// Target darkness per tone, light to dark.
    pub darkness: Vec<f64>,
    /// Measured mean darkness, `[tone][level]`.
    pub measured: Vec<Vec<f64>>,
    pub(crate) seed: u64,
    pub(crate) stroke_width_px: f32,
}

/// Peak bytes of reading the map `m` describes: per texel of every level,
/// each tone's 8-bit image, and the f32 channels (paper and one per tone)
/// twice (the levels and the texture they are assembled into); plus one
/// decoded image of level 0 (up to 8 bytes a texel) at a time.
fn manifest_bytes(m: &Manifest) -> u64 {
    let texels: u64 = m.sizes.iter().map(|&n| n as u64 * n as u64).sum();
    let per_texel = m.tones as u64 + (m.tones as u64 + 1) * 8;
    let first = m.sizes[0] as u64 * m.sizes[0] as u64;
    texels
        .saturating_mul(per_texel)
        .saturating_add(first.saturating_mul(8))
}

/// File name of tone t, level l.
pub(crate) fn file_name(t: usize, l: usize) -> String {
    format!("tam_t{t}_l{l}.png")
}

impl Tam {
    pub fn manifest(&self) -> Manifest {
        let p = &self.params;
        Manifest {
            tones: p.tones,
            levels: p.levels,
            sizes: (0..p.levels).map(|l| p.level_size(l)).collect(),
            darkness: self.darkness.clone(),
            measured: self
                .images
                .iter()
                .map(|tone| tone.iter().map(|img| grey_darkness(img)).collect())
                .collect(),
            seed: p.seed,
            stroke_width_px: STROKE_WIDTH_PX,
        }
    }

    /// Writes the PNGs and `tam.json` into `dir` (created if missing).
    pub fn write_dir(&self, dir: &Path) -> Result<(), TamError> {
        std::fs::create_dir_all(dir).map_err(TamError::io(dir))?;
        for (t, tone) in self.images.iter().enumerate() {
            for (l, img) in tone.iter().enumerate() {
                let n = self.params.level_size(l);
                let path = dir.join(file_name(t, l));
                image::save_buffer(&path, img, n, n, image::ExtendedColorType::L8)
                    .map_err(TamError::image(&path))?;
            }
        }
        let path = dir.join("tam.json");
        let json = serde_json::to_string_pretty(&self.manifest()).map_err(|source| {
            TamError::Manifest {
                path: path.clone(),
                source,
            }
        })?;
        std::fs::write(&path, json + "\n").map_err(TamError::io(&path))
    }
}

/// A map ready for the hatching shader: one texture whose channel 0 is
/// paper (1 everywhere) and channel t + 1 tone t's brightness (linear,
/// 1 paper, 0 ink), with the tones' darkness (channel 0's is 0).
#[derive(Clone, Debug, PartialEq)]
pub struct TamTexture {
    pub(crate) texture: Texture,
    /// Darkness of each channel: 0 for paper, then the tones' (increasing).
    pub(crate) darkness: Vec<f32>,
}

impl TamTexture {
    /// From tones × levels of grey images (`images[t][l]`, 255 paper) with
    /// level 0 `size` wide, and each tone's darkness.
    pub(crate) fn new(
        images: &[Vec<Vec<u8>>],
        size: u32,
        darkness: &[f64],
    ) -> Result<TamTexture, TamError> {
        let tones = images.len();
        if tones == 0 || darkness.len() != tones {
            return Err(TamError::Layout(format!(
                "a tonal art map needs at least one tone and one darkness per tone ({tones} tones, {} darkness values)",
                darkness.len()
            )));
        }
        if darkness.windows(2).any(|w| w[1] <= w[0])
            || darkness.iter().any(|d| !(*d > 0.0 && *d <= 1.0))
        {
            return Err(TamError::Layout(format!(
                "tone darkness must increase strictly within (0, 1], got {darkness:?}"
            )));
        }
        let levels = images[0].len();
        if images.iter().any(|t| t.len() != levels) || levels == 0 {
            return Err(TamError::Layout(
                "every tone needs the same number of levels (≥ 1)".into(),
            ));
        }
        let c = tones + 1;
        let mut out = Vec::with_capacity(levels);
        for l in 0..levels {
            let n = (size >> l).max(1) as usize;
            let mut data = vec![1.0f32; n * n * c];
            for (t, tone) in images.iter().enumerate() {
                let img = &tone[l];
                if img.len() != n * n {
                    return Err(TamError::Layout(format!(
                        "tone {t} level {l}: {} pixels, expected {n}×{n}",
                        img.len()
                    )));
                }
                for (i, &v) in img.iter().enumerate() {
                    data[i * c + t + 1] = v as f32 / 255.0;
                }
            }
            out.push((n, n, data));
        }
        Ok(TamTexture {
            texture: Texture::from_levels(c, out)?,
            darkness: std::iter::once(0.0)
                .chain(darkness.iter().map(|&d| d as f32))
                .collect(),
        })
    }

    pub fn from_tam(tam: &Tam) -> Result<TamTexture, TamError> {
        TamTexture::new(&tam.images, tam.params.size, &tam.darkness)
    }

    /// Reads a directory written by [`Tam::write_dir`]; errors name the file.
    pub fn read_dir(dir: &Path) -> Result<TamTexture, TamError> {
        TamTexture::read_with(dir, &|p: &Path| std::fs::read(p))
    }

    /// [`TamTexture::read_dir`] with the files supplied by `read` (scene
    /// loaders resolve paths against the scene's folder).
    pub(crate) fn read_with(
        dir: &Path,
        read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    ) -> Result<TamTexture, TamError> {
        TamTexture::read_with_budget(dir, read, &|_, _| Ok(()))
    }

    /// `TamTexture::read_with` that first asks `reserve` for the bytes
    /// the map will need (named by its folder), from `tam.json` alone, and
    /// checks each image's size in its header before decoding it: a map too
    /// large for the caller's memory budget is refused before any image is
    /// decoded.
    pub fn read_with_budget(
        dir: &Path,
        read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
        reserve: &dyn Fn(&str, u64) -> Result<(), String>,
    ) -> Result<TamTexture, TamError> {
        let path = dir.join("tam.json");
        let bytes = read(&path).map_err(TamError::io(&path))?;
        let m: Manifest = serde_json::from_slice(&bytes).map_err(|source| TamError::Manifest {
            path: path.clone(),
            source,
        })?;
        let invalid = |path: &Path, reason: String| TamError::Invalid {
            path: path.to_path_buf(),
            reason,
        };
        if m.sizes.len() != m.levels || m.darkness.len() != m.tones || m.levels == 0 {
            return Err(invalid(
                &path,
                format!(
                    "sizes must list the {} levels and darkness the {} tones",
                    m.levels, m.tones
                ),
            ));
        }
        if m.tones > 64 || m.sizes.iter().any(|&n| n == 0 || n > 8192) {
            return Err(invalid(
                &path,
                "at most 64 tones of at most 8192×8192".into(),
            ));
        }
        reserve(
            &format!(
                "the tonal art map {} ({} tones of {}×{})",
                dir.display(),
                m.tones,
                m.sizes[0],
                m.sizes[0]
            ),
            manifest_bytes(&m),
        )
        .map_err(TamError::Budget)?;
        let mut images = Vec::with_capacity(m.tones);
        for t in 0..m.tones {
            let mut tone = Vec::with_capacity(m.levels);
            for (l, &n) in m.sizes.iter().enumerate() {
                let p = dir.join(file_name(t, l));
                let bytes = read(&p).map_err(TamError::io(&p))?;
                let header = image::ImageReader::new(std::io::Cursor::new(&bytes))
                    .with_guessed_format()
                    .map_err(TamError::io(&p))?
                    .into_dimensions()
                    .map_err(TamError::image(&p))?;
                let wrong_size =
                    |(w, h): (u32, u32)| invalid(&p, format!("is {w}×{h}, tam.json says {n}×{n}"));
                if header != (n, n) {
                    return Err(wrong_size(header));
                }
                let img = image::load_from_memory(&bytes)
                    .map_err(TamError::image(&p))?
                    .to_luma8();
                if img.dimensions() != (n, n) {
                    return Err(wrong_size(img.dimensions()));
                }
                tone.push(img.into_raw());
            }
            images.push(tone);
        }
        TamTexture::new(&images, m.sizes[0], &m.darkness).map_err(|e| invalid(dir, e.to_string()))
    }
}
