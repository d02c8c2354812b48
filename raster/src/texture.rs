//! Textures and their sampler: images of any channel count stored as linear
//! f32 with a mip chain, looked up for f32, f64 and f32x8 lanes from one
//! source through [`Real::gather`] (the same memory read the tables use).
//!
//! Conventions (the same for every user: base-colour maps, tonal art maps):
//! - texel (i, j) of a w × h level has its centre at uv = ((i + ½)/w,
//!   (j + ½)/h); row j = 0 is v = 0. Loaders of images stored top row first
//!   decide which way v runs (scene files use the OBJ convention, v = 0 at
//!   the bottom of the picture, see `src/material_desc.rs`);
//! - texels are linear values: 8-bit colour is decoded from sRGB (channels
//!   0–2; alpha stays linear) or read as linear ([`Encoding`]) when the
//!   texture is made, so filtering happens in linear space;
//! - level l + 1 is max(1, ⌊w_l/2⌋) × max(1, ⌊h_l/2⌋), down to 1 × 1. Each
//!   texel of it is the area average of the level-l texels under its
//!   footprint (a box filter of exact area: for odd sizes a source texel is
//!   split between two targets by how much of it each covers), so every
//!   level keeps the mean of level 0;
//! - level of detail λ = ½ log₂ max(|∂(uw, vh)/∂x|², |∂(uw, vh)/∂y|²) in
//!   level-0 texels per pixel (the larger axis of the footprint, as
//!   OpenGL's scale factor ρ), clamped to [0, levels − 1];
//! - filters: [`Filter::Nearest`] and [`Filter::Bilinear`] read level 0,
//!   [`Filter::Trilinear`] blends the bilinear values of levels ⌊λ⌋ and
//!   ⌊λ⌋ + 1 by the fraction of λ;
//! - [`Filter::Anisotropic`] with at most N taps, as GPUs do
//!   (EXT_texture_filter_anisotropic): the footprint's axes are the texel
//!   vectors a = ∂(uw, vh)/∂x and b = ∂(uw, vh)/∂y; with P_max and P_min
//!   their longer and shorter lengths, the lane takes
//!   n = min(⌈P_max / P_min⌉, N) trilinear taps at λ = log₂(P_max / n),
//!   at uv + d·((i + ½)/n − ½), i = 0..n, where d is the longer axis in
//!   uv units, and averages them. N = 1 is trilinear.
//!
//! Every input is safe: a NaN or infinite uv reads texel 0 and a NaN
//! derivative level 0; the result is always finite for finite texels.
//! The one source serves f32x8 and the scalar twin (f32, f64); tests check
//! them lane by lane against each other and against plain f64 formulas.

use specula_core::Real;

/// What happens to uv outside [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Wrap {
    /// Tiles: u and u + 1 read the same texel.
    #[default]
    Repeat,
    /// The edge texels extend outward.
    Clamp,
    /// Tiles with every other copy mirrored: u and 2 − u read the same texel.
    Mirror,
}

/// How texels are combined; see the module docs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Filter {
    /// The texel of level 0 containing uv.
    Nearest,
    /// The four nearest texel centres of level 0, bilinearly weighted.
    Bilinear,
    /// Bilinear on the two levels around λ, blended linearly.
    #[default]
    Trilinear,
    /// Up to N trilinear taps (1 ≤ N ≤ `MAX_ANISOTROPY`) spread along
    /// the major axis of the pixel's footprint, averaged; see the module
    /// docs.
    Anisotropic(u8),
}

/// Most taps [`Filter::Anisotropic`] takes (what GPUs offer: 16×).
pub(crate) const MAX_ANISOTROPY: u8 = 16;

/// A texture filter's name that [`Filter`]'s `FromStr` does not know.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("expected nearest, bilinear, trilinear, anisotropic or anisotropic:N (N in 1..={MAX_ANISOTROPY}), got {0:?}")]
pub struct FilterParseError(pub(crate) String);

/// Why a texture could not be made from the texels given.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TextureError {
    #[error("texture size {width}×{height} with {channels} channels: all must be ≥ 1")]
    Empty {
        width: usize,
        height: usize,
        channels: usize,
    },
    #[error("texture size {width}×{height} overflows")]
    Overflow { width: usize, height: usize },
    #[error("texture too large: {width}×{height}×{channels} values, at most {MAX_VALUES}")]
    TooLarge {
        width: usize,
        height: usize,
        channels: usize,
    },
    #[error("texture too large: {width}×{height} with {channels} channels needs more than {MAX_VALUES} values with its mip chain")]
    ChainTooLarge {
        width: usize,
        height: usize,
        channels: usize,
    },
    #[error("texture too large: {0} values with its mip chain, at most {MAX_VALUES}")]
    LevelsTooLarge(usize),
    #[error("{len} values given for a {width}×{height} texture of {channels} channels ({expected} expected)")]
    Length {
        len: usize,
        width: usize,
        height: usize,
        channels: usize,
        expected: usize,
    },
    #[error("texel value {index} is not finite ({value}); textures hold finite values")]
    NotFinite { index: usize, value: f32 },
    #[error("a texture needs at least one level")]
    NoLevels,
    #[error("level {level} is {width}×{height}; after level 0 of {first_width}×{first_height} it must be {want_width}×{want_height}")]
    LevelSize {
        level: usize,
        width: usize,
        height: usize,
        first_width: usize,
        first_height: usize,
        want_width: usize,
        want_height: usize,
    },
    #[error("level {level}: {error}")]
    Level {
        level: usize,
        error: Box<TextureError>,
    },
    #[error("level {0}: texel values must be finite")]
    LevelNotFinite(usize),
}

impl core::str::FromStr for Filter {
    type Err = FilterParseError;

    /// "nearest", "bilinear", "trilinear", "anisotropic" (16 taps) or
    /// "anisotropic:N" with N in 1..=16.
    fn from_str(s: &str) -> Result<Filter, FilterParseError> {
        let bad = || FilterParseError(s.to_string());
        Ok(match s {
            "nearest" => Filter::Nearest,
            "bilinear" => Filter::Bilinear,
            "trilinear" => Filter::Trilinear,
            "anisotropic" => Filter::Anisotropic(MAX_ANISOTROPY),
            _ => {
                let n = s.strip_prefix("anisotropic:").ok_or_else(bad)?;
                match n.parse::<u8>() {
                    Ok(n) if (1..=MAX_ANISOTROPY).contains(&n) => Filter::Anisotropic(n),
                    _ => return Err(bad()),
                }
            }
        })
    }
}

/// Wrap modes along u and v, and the filter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Sampler {
    pub wrap_u: Wrap,
    pub wrap_v: Wrap,
    pub filter: Filter,
}

impl Sampler {
    pub fn new(wrap: Wrap, filter: Filter) -> Sampler {
        Sampler {
            wrap_u: wrap,
            wrap_v: wrap,
            filter,
        }
    }
}

/// How 8-bit texels encode their values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// Colour channels (0–2) are sRGB-encoded (IEC 61966-2-1) and decoded
    /// to linear; a fourth channel (alpha) is linear.
    Srgb,
    /// Every channel is value / 255.
    Linear,
}

/// Largest number of f32 values all levels together may hold: an f32 lane
/// indexes exactly up to 2²⁴ (the gather's contract).
pub(crate) const MAX_VALUES: usize = 1 << 24;

/// Checks that a `width` × `height` texture of `channels` channels with its
/// whole mip chain stays within the 2²⁴ values a texture holds, from its
/// size alone (an image's header), before its texels are decoded.
pub fn check_mip_chain_size(
    width: usize,
    height: usize,
    channels: usize,
) -> Result<(), TextureError> {
    let (mut w, mut h) = (width.max(1), height.max(1));
    let mut total = 0usize;
    loop {
        total = total.saturating_add(w.saturating_mul(h).saturating_mul(channels));
        if (w, h) == (1, 1) || total > MAX_VALUES {
            break;
        }
        (w, h) = next_level_size(w, h);
    }
    if total > MAX_VALUES {
        return Err(TextureError::ChainTooLarge {
            width,
            height,
            channels,
        });
    }
    Ok(())
}

/// Where a level lives in [`Texture`]'s data.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Level {
    width: usize,
    height: usize,
    offset: usize,
}

/// Per-level values the lanes gather when each lane reads its own level.
const META: usize = 3;

/// A mip-mapped image of `channels` linear f32 values per texel; see the
/// module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    channels: usize,
    levels: Vec<Level>,
    /// Every level, row-major, channels interleaved: value c of texel
    /// (x, y) of level l at `offset_l + (y · w_l + x) · channels + c`.
    data: Vec<f32>,
    /// Per level: offset, width, height (as f32, exact).
    meta: Vec<f32>,
}

/// The size of the level below a w × h one.
pub(crate) fn next_level_size(w: usize, h: usize) -> (usize, usize) {
    ((w / 2).max(1), (h / 2).max(1))
}

/// Area weights of a 1-D box resampling from `n` to `m` < n texels: for
/// each target, the (source index, weight) pairs, weights summing to 1.
fn box_weights(n: usize, m: usize) -> Vec<Vec<(usize, f64)>> {
    let scale = n as f64 / m as f64;
    (0..m)
        .map(|i| {
            let (a, b) = (i as f64 * scale, (i + 1) as f64 * scale);
            let mut w = Vec::new();
            let mut j = a.floor() as usize;
            while (j as f64) < b && j < n {
                let overlap = (b.min(j as f64 + 1.0) - a.max(j as f64)).max(0.0);
                if overlap > 0.0 {
                    w.push((j, overlap / scale));
                }
                j += 1;
            }
            w
        })
        .collect()
}

/// The area-average of a w × h image (c channels) at (w2, h2): separable,
/// rows first, in f64.
fn downsample(src: &[f32], w: usize, h: usize, c: usize, w2: usize, h2: usize) -> Vec<f32> {
    let wx = if w2 == w {
        (0..w).map(|i| vec![(i, 1.0)]).collect()
    } else {
        box_weights(w, w2)
    };
    let wy = if h2 == h {
        (0..h).map(|j| vec![(j, 1.0)]).collect()
    } else {
        box_weights(h, h2)
    };
    let mut rows = vec![0.0f64; w2 * h * c];
    for y in 0..h {
        for (x2, taps) in wx.iter().enumerate() {
            for &(x, k) in taps {
                for ch in 0..c {
                    rows[(y * w2 + x2) * c + ch] += k * src[(y * w + x) * c + ch] as f64;
                }
            }
        }
    }
    let mut out = vec![0.0f64; w2 * h2 * c];
    for (y2, taps) in wy.iter().enumerate() {
        for &(y, k) in taps {
            for i in 0..w2 * c {
                out[y2 * w2 * c + i] += k * rows[y * w2 * c + i];
            }
        }
    }
    out.into_iter().map(|v| v as f32).collect()
}

/// One lane value per level field, for the lanes of one lookup.
#[derive(Clone, Copy)]
struct LevelLanes<R> {
    offset: R,
    width: R,
    height: R,
}

#[inline(always)]
fn lerp<R: Real>(a: R, b: R, t: R) -> R {
    a + (b - a) * t
}

/// u reduced to the wrap's period ([0, 1) for repeat, [0, 2) for mirror,
/// [−1, 2] for clamp, where anything beyond reads the edge anyway) so
/// texel coordinates stay small; a NaN or infinite u becomes 0.
#[inline(always)]
fn reduce<R: Real>(mode: Wrap, u: R) -> R {
    let u = R::select(u.is_finite(), u, R::ZERO);
    match mode {
        Wrap::Repeat => u - u.floor(),
        Wrap::Mirror => u - (u * R::HALF).floor() * R::splat(2.0),
        Wrap::Clamp => u.clamp(-R::ONE, R::splat(2.0)),
    }
}

/// Texel index i (integral, within one period of the reduced range) wrapped
/// into [0, n − 1]. The last clamp also catches the rounding of `reduce`
/// (u − ⌊u⌋ can round up to exactly 1).
#[inline(always)]
fn wrap_index<R: Real>(mode: Wrap, i: R, n: R) -> R {
    let last = n - R::ONE;
    let r = match mode {
        Wrap::Clamp => i,
        Wrap::Repeat => {
            let r = R::select(i.lt(R::ZERO), i + n, i);
            R::select(r.ge(n), r - n, r)
        }
        Wrap::Mirror => {
            let n2 = n + n;
            let r = R::select(i.lt(R::ZERO), i + n2, i);
            let r = R::select(r.ge(n2), r - n2, r);
            R::select(r.ge(n), n2 - R::ONE - r, r)
        }
    };
    r.clamp(R::ZERO, last)
}

impl Texture {
    /// A texture from level-0 texels (`width · height · channels` values,
    /// row-major, channels interleaved), with its mip chain.
    pub fn from_f32(
        width: usize,
        height: usize,
        channels: usize,
        texels: Vec<f32>,
    ) -> Result<Texture, TextureError> {
        check_size(width, height, channels, texels.len())?;
        if let Some(index) = texels.iter().position(|v| !v.is_finite()) {
            let value = texels[index];
            return Err(TextureError::NotFinite { index, value });
        }
        let mut levels = vec![(width, height, texels)];
        while let Some((w, h, d)) = levels.last() {
            if *w == 1 && *h == 1 {
                break;
            }
            let (w2, h2) = next_level_size(*w, *h);
            let next = downsample(d, *w, *h, channels, w2, h2);
            levels.push((w2, h2, next));
        }
        Self::assemble(channels, levels)
    }

    /// A texture from 8-bit texels (`width · height · channels` bytes,
    /// row-major, channels interleaved), decoded per `encoding`.
    pub fn from_u8(
        width: usize,
        height: usize,
        channels: usize,
        bytes: &[u8],
        encoding: Encoding,
    ) -> Result<Texture, TextureError> {
        check_size(width, height, channels, bytes.len())?;
        let srgb: [f32; 256] =
            core::array::from_fn(|k| crate::post::srgb_curve_inverse(k as f64 / 255.0) as f32);
        let texels = bytes
            .iter()
            .enumerate()
            .map(|(i, &b)| match encoding {
                Encoding::Srgb if i % channels < 3 => srgb[b as usize],
                _ => b as f32 / 255.0,
            })
            .collect();
        Self::from_f32(width, height, channels, texels)
    }

    /// A texture whose mip levels are given, level 0 first (e.g. a tonal art
    /// map, each level drawn at its own size): each (width, height, texels)
    /// as in [`Texture::from_f32`], sizes halving as `next_level_size`.
    /// The chain may stop before 1 × 1; lookups clamp λ to the levels given.
    pub fn from_levels(
        channels: usize,
        levels: Vec<(usize, usize, Vec<f32>)>,
    ) -> Result<Texture, TextureError> {
        let Some(first) = levels.first() else {
            return Err(TextureError::NoLevels);
        };
        let (mut w, mut h) = (first.0, first.1);
        for (l, (lw, lh, d)) in levels.iter().enumerate() {
            if l > 0 {
                (w, h) = next_level_size(w, h);
            }
            if (*lw, *lh) != (w, h) {
                return Err(TextureError::LevelSize {
                    level: l,
                    width: *lw,
                    height: *lh,
                    first_width: first.0,
                    first_height: first.1,
                    want_width: w,
                    want_height: h,
                });
            }
            check_size(w, h, channels, d.len()).map_err(|e| TextureError::Level {
                level: l,
                error: Box::new(e),
            })?;
            if d.iter().any(|v| !v.is_finite()) {
                return Err(TextureError::LevelNotFinite(l));
            }
        }
        Self::assemble(channels, levels)
    }

    fn assemble(
        channels: usize,
        levels: Vec<(usize, usize, Vec<f32>)>,
    ) -> Result<Texture, TextureError> {
        let total: usize = levels.iter().map(|l| l.2.len()).sum();
        if total > MAX_VALUES {
            return Err(TextureError::LevelsTooLarge(total));
        }
        let mut t = Texture {
            channels,
            levels: Vec::with_capacity(levels.len()),
            data: Vec::with_capacity(total),
            meta: Vec::new(),
        };
        for (width, height, d) in levels {
            let offset = t.data.len();
            t.levels.push(Level {
                width,
                height,
                offset,
            });
            t.meta.extend([offset as f32, width as f32, height as f32]);
            t.data.extend(d);
        }
        Ok(t)
    }

    pub(crate) fn channels(&self) -> usize {
        self.channels
    }

    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// (width, height) of level `l`.
    pub fn level_size(&self, l: usize) -> (usize, usize) {
        (self.levels[l].width, self.levels[l].height)
    }

    /// Channel `c` of texel (x, y) of level `l`.
    pub fn texel(&self, l: usize, x: usize, y: usize, c: usize) -> f32 {
        let lv = &self.levels[l];
        self.data[lv.offset + (y * lv.width + x) * self.channels + c]
    }

    #[inline(always)]
    fn level0<R: Real>(&self) -> LevelLanes<R> {
        let l = &self.levels[0];
        LevelLanes {
            offset: R::ZERO,
            width: R::splat(l.width as f64),
            height: R::splat(l.height as f64),
        }
    }

    /// Each lane's level `l` (integral, in range).
    #[inline(always)]
    fn level_lanes<R: Real>(&self, l: R) -> LevelLanes<R> {
        let base = l * R::splat(META as f64);
        LevelLanes {
            offset: R::gather(&self.meta, base),
            width: R::gather(&self.meta, base + R::ONE),
            height: R::gather(&self.meta, base + R::splat(2.0)),
        }
    }

    /// λ from the screen derivatives of uv (module docs), clamped to the
    /// levels there are; NaN derivatives give 0.
    #[inline(always)]
    pub fn lod<R: Real>(&self, duv_dx: [R; 2], duv_dy: [R; 2]) -> R {
        let (w, h) = (
            R::splat(self.levels[0].width as f64),
            R::splat(self.levels[0].height as f64),
        );
        let (ax, ay) = (duv_dx[0] * w, duv_dx[1] * h);
        let (bx, by) = (duv_dy[0] * w, duv_dy[1] * h);
        let rho2 = (ax * ax + ay * ay).max(bx * bx + by * by);
        // ½ log₂ ρ² = ln ρ² / (2 ln 2); ρ² = 0 gives −inf and NaN stays
        // NaN: the clamp sends both to 0.
        let lambda = rho2.ln() * R::splat(0.5 / core::f64::consts::LN_2);
        lambda.clamp(R::ZERO, R::splat((self.levels.len() - 1) as f64))
    }

    /// Index of channel 0 of the four bilinear taps of `lv` at reduced
    /// (u, v), and the weights of the second column and row.
    #[inline(always)]
    fn taps<R: Real>(&self, s: &Sampler, lv: &LevelLanes<R>, u: R, v: R) -> ([R; 4], R, R) {
        let x = u * lv.width - R::HALF;
        let y = v * lv.height - R::HALF;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let xa = wrap_index(s.wrap_u, x0, lv.width);
        let xb = wrap_index(s.wrap_u, x0 + R::ONE, lv.width);
        let ya = wrap_index(s.wrap_v, y0, lv.height);
        let yb = wrap_index(s.wrap_v, y0 + R::ONE, lv.height);
        let c = R::splat(self.channels as f64);
        let at = |x: R, y: R| (y * lv.width + x).mul_add(c, lv.offset);
        ([at(xa, ya), at(xb, ya), at(xa, yb), at(xb, yb)], fx, fy)
    }

    /// Index of channel 0 of the level-0 texel holding reduced (u, v).
    #[inline(always)]
    fn nearest<R: Real>(&self, s: &Sampler, u: R, v: R) -> R {
        let lv = self.level0::<R>();
        let x = wrap_index(s.wrap_u, (u * lv.width).floor(), lv.width);
        let y = wrap_index(s.wrap_v, (v * lv.height).floor(), lv.height);
        (y * lv.width + x) * R::splat(self.channels as f64)
    }

    /// `fetch` bilinearly filtered over the four taps of `lv` at (u, v).
    #[inline(always)]
    fn quad<R: Real, T: Copy>(
        &self,
        s: &Sampler,
        lv: &LevelLanes<R>,
        u: R,
        v: R,
        fetch: &impl Fn(R) -> T,
        mix: &impl Fn(T, T, R) -> T,
    ) -> T {
        let (t, fx, fy) = self.taps(s, lv, u, v);
        mix(
            mix(fetch(t[0]), fetch(t[1]), fx),
            mix(fetch(t[2]), fetch(t[3]), fx),
            fy,
        )
    }

    /// The one filter walk every lookup shares: `fetch` reads whatever a
    /// texel holds from its channel-0 index (one channel, two blended, or
    /// C of them), `mix` interpolates two such values. Nearest fetches one
    /// texel, bilinear four, trilinear four on each of the two levels
    /// around `lod` (clamped here to the levels there are).
    #[inline(always)]
    fn filtered<R: Real, T: Copy>(
        &self,
        s: &Sampler,
        uv: [R; 2],
        lod: R,
        fetch: impl Fn(R) -> T,
        mix: impl Fn(T, T, R) -> T,
    ) -> T {
        let u = reduce(s.wrap_u, uv[0]);
        let v = reduce(s.wrap_v, uv[1]);
        let quad = |lv: &LevelLanes<R>| self.quad(s, lv, u, v, &fetch, &mix);
        match s.filter {
            Filter::Nearest => fetch(self.nearest(s, u, v)),
            Filter::Bilinear => quad(&self.level0()),
            Filter::Trilinear | Filter::Anisotropic(_) => {
                self.trilinear(s, u, v, lod, &fetch, &mix)
            }
        }
    }

    /// Bilinear on the two levels around `lod` (clamped to the levels
    /// there are), blended, at reduced (u, v).
    #[inline(always)]
    fn trilinear<R: Real, T: Copy>(
        &self,
        s: &Sampler,
        u: R,
        v: R,
        lod: R,
        fetch: &impl Fn(R) -> T,
        mix: &impl Fn(T, T, R) -> T,
    ) -> T {
        let last = R::splat((self.levels.len() - 1) as f64);
        let lod = lod.clamp(R::ZERO, last);
        let l0 = lod.floor();
        let l1 = (l0 + R::ONE).min(last);
        let a = self.quad(s, &self.level_lanes(l0), u, v, fetch, mix);
        let b = self.quad(s, &self.level_lanes(l1), u, v, fetch, mix);
        mix(a, b, lod - l0)
    }

    /// The footprint of [`Filter::Anisotropic`] with at most `max_taps`
    /// taps (module docs): per lane the tap count n, the level of detail
    /// and the major axis in uv. NaN derivatives give one tap at level 0.
    #[inline(always)]
    pub fn anisotropic_footprint<R: Real>(
        &self,
        duv_dx: [R; 2],
        duv_dy: [R; 2],
        max_taps: u8,
    ) -> (R, R, [R; 2]) {
        let (w, h) = (
            R::splat(self.levels[0].width as f64),
            R::splat(self.levels[0].height as f64),
        );
        let (ax, ay) = (duv_dx[0] * w, duv_dx[1] * h);
        let (bx, by) = (duv_dy[0] * w, duv_dy[1] * h);
        let (pa2, pb2) = (ax * ax + ay * ay, bx * bx + by * by);
        let x_major = pa2.ge(pb2);
        let pmax2 = pa2.max(pb2);
        // A footprint degenerate along one axis (P_min = 0) gets the most
        // taps; the floor keeps the ratio finite.
        let pmin2 = pa2.min(pb2).max(R::splat(1e-30));
        let ratio = (pmax2 / pmin2).sqrt();
        let max = R::splat(max_taps.clamp(1, MAX_ANISOTROPY) as f64);
        // ⌈ratio⌉ as −⌊−ratio⌋; NaN (NaN derivatives) becomes one tap.
        let n = (-(-ratio).floor()).clamp(R::ONE, max);
        let n = R::select(n.is_finite(), n, R::ONE);
        // λ = ½ log₂(P_max² / n²); P_max² = 0 or NaN give −inf or NaN,
        // which `trilinear` clamps to level 0 (and +inf to the last).
        let lambda = (pmax2 / (n * n)).ln() * R::splat(0.5 / core::f64::consts::LN_2);
        let axis = [
            R::select(x_major, duv_dx[0], duv_dy[0]),
            R::select(x_major, duv_dx[1], duv_dy[1]),
        ];
        let axis = axis.map(|a| R::select(a.is_finite(), a, R::ZERO));
        (n, lambda, axis)
    }

    /// [`Filter::Anisotropic`] at uv: the running mean of the lane's n
    /// taps (lanes with fewer taps than the packet's most keep their mean:
    /// a blend weight of 0 leaves it exactly as it was).
    #[inline(always)]
    fn anisotropic<R: Real, T: Copy>(
        &self,
        s: &Sampler,
        uv: [R; 2],
        footprint: (R, R, [R; 2]),
        fetch: impl Fn(R) -> T,
        mix: impl Fn(T, T, R) -> T,
    ) -> T {
        let (n, lod, axis) = footprint;
        let taps = (0..R::LANES)
            .map(|i| n.lane(i))
            .fold(1.0f64, f64::max)
            .min(MAX_ANISOTROPY as f64) as usize;
        let inv_n = R::ONE / n;
        let mut acc = None;
        for i in 0..taps {
            // Offset (i + ½)/n − ½ along the axis, in [−½, ½].
            let t = (R::splat(i as f64 + 0.5) * inv_n) - R::HALF;
            let u = reduce(s.wrap_u, axis[0].mul_add(t, uv[0]));
            let v = reduce(s.wrap_v, axis[1].mul_add(t, uv[1]));
            let tap = self.trilinear(s, u, v, lod, &fetch, &mix);
            acc = Some(match acc {
                None => tap,
                Some(a) => {
                    let k = R::splat(i as f64 + 1.0);
                    let w = R::select(k.le(n), R::ONE / k, R::ZERO);
                    mix(a, tap, w)
                }
            });
        }
        acc.expect("at least one tap")
    }

    /// The value of each lane's channel `ch` (integral lane values, clamped
    /// to the channels there are) at uv, level of detail `lod` (used by
    /// [`Filter::Trilinear`] and [`Filter::Anisotropic`], which takes one
    /// trilinear tap here; clamp it with [`Texture::lod`]).
    #[inline(always)]
    pub fn sample_channel<R: Real>(&self, s: &Sampler, uv: [R; 2], lod: R, ch: R) -> R {
        let ch = ch.clamp(R::ZERO, R::splat((self.channels - 1) as f64));
        self.filtered(s, uv, lod, |i| R::gather(&self.data, i + ch), lerp)
    }

    /// (1 − w)·channel `ch` + w·channel `ch + 1` per lane: two channels
    /// blended, with the taps (and level lookups) computed once. Equal to
    /// blending two [`Texture::sample_channel`] calls (tested).
    #[inline(always)]
    pub fn sample_channel_blend<R: Real>(&self, s: &Sampler, uv: [R; 2], lod: R, ch: R, w: R) -> R {
        let top = R::splat((self.channels - 1) as f64);
        let c0 = ch.clamp(R::ZERO, top);
        let c1 = (ch + R::ONE).clamp(R::ZERO, top);
        let fetch = |i: R| {
            lerp(
                R::gather(&self.data, i + c0),
                R::gather(&self.data, i + c1),
                w,
            )
        };
        self.filtered(s, uv, lod, fetch, lerp)
    }

    /// Channels 0..C (C ≤ `Texture::channels`; later ones repeat the
    /// last channel) at uv with the level of detail from its derivatives.
    #[inline(always)]
    pub fn sample<R: Real, const C: usize>(
        &self,
        s: &Sampler,
        uv: [R; 2],
        duv_dx: [R; 2],
        duv_dy: [R; 2],
    ) -> [R; C] {
        let lod = match s.filter {
            Filter::Trilinear => self.lod(duv_dx, duv_dy),
            Filter::Anisotropic(max) => {
                let footprint = self.anisotropic_footprint(duv_dx, duv_dy, max);
                let (fetch, mix) = self.channels_fetch::<R, C>();
                let uv = [reduce(s.wrap_u, uv[0]), reduce(s.wrap_v, uv[1])];
                return self.anisotropic(s, uv, footprint, fetch, mix);
            }
            _ => R::ZERO,
        };
        self.sample_lod(s, uv, lod)
    }

    /// What [`Texture::sample_lod`] fetches and blends: channels 0..C.
    #[inline(always)]
    #[allow(clippy::type_complexity)]
    fn channels_fetch<'a, R: Real + 'a, const C: usize>(
        &'a self,
    ) -> (
        impl Fn(R) -> [R; C] + 'a,
        impl Fn([R; C], [R; C], R) -> [R; C],
    ) {
        let ch: [R; C] = core::array::from_fn(|c| R::splat(c.min(self.channels - 1) as f64));
        let fetch = move |i: R| ch.map(|c| R::gather(&self.data, i + c));
        let mix = |a: [R; C], b: [R; C], t: R| core::array::from_fn(|c| lerp(a[c], b[c], t));
        (fetch, mix)
    }

    /// [`Texture::sample`] at a given level of detail ([`Filter::Anisotropic`]
    /// then takes one trilinear tap: the footprint needs the derivatives).
    #[inline(always)]
    pub fn sample_lod<R: Real, const C: usize>(&self, s: &Sampler, uv: [R; 2], lod: R) -> [R; C] {
        let (fetch, mix) = self.channels_fetch::<R, C>();
        self.filtered(s, uv, lod, fetch, mix)
    }
}

fn check_size(
    width: usize,
    height: usize,
    channels: usize,
    len: usize,
) -> Result<(), TextureError> {
    if width == 0 || height == 0 || channels == 0 {
        return Err(TextureError::Empty {
            width,
            height,
            channels,
        });
    }
    match width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(channels))
    {
        Some(n) if n == len => Ok(()),
        Some(n) if n > MAX_VALUES => Err(TextureError::TooLarge {
            width,
            height,
            channels,
        }),
        Some(expected) => Err(TextureError::Length {
            len,
            width,
            height,
            channels,
            expected,
        }),
        None => Err(TextureError::Overflow { width, height }),
    }
}
