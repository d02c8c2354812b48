//! After shading: supersampling resolve (box filter, in linear HDR), then
//! exposure, tone mapping and the one sRGB encode at the very end.

use crate::shade::ColorBuffer;
use crate::target::{Target, TILE};
use rayon::prelude::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Tonemap {
    /// Clamp each channel to [0, 1].
    #[default]
    Clamp,
    /// x / (1 + x) per channel.   [Reinhard02]
    Reinhard,
    /// Narkowicz's fit of the ACES filmic curve.   [Narkowicz15]
    Aces,
}

impl Tonemap {
    #[inline]
    pub fn apply(self, x: f32) -> f32 {
        // NaN and negatives become 0, so no NaN reaches the encoder; every
        // curve is within 1e-18 of 1 past 1e18, and capping there keeps x²
        // (ACES) and 1 + x (Reinhard) finite for +inf.
        let x = if x > 0.0 { x.min(1e18) } else { 0.0 };
        match self {
            Tonemap::Clamp => x.min(1.0),
            Tonemap::Reinhard => x / (1.0 + x),
            Tonemap::Aces => {
                ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
            }
        }
    }
}

/// The sRGB transfer function (IEC 61966-2-1), in f64.
pub fn srgb_curve(v: f64) -> f64 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Inverse of [`srgb_curve`].
fn srgb_curve_inverse(s: f64) -> f64 {
    if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

/// `THRESHOLDS[k]`: the smallest linear value that encodes to k + 1 or
/// more, i.e. the f64 curve's (k + ½)/255 crossing; a last +inf sentinel.
fn thresholds() -> &'static [f32; 256] {
    static T: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    T.get_or_init(|| {
        let mut t = [f32::INFINITY; 256];
        for (k, v) in t.iter_mut().take(255).enumerate() {
            // Round up so every f32 ≥ the threshold encodes to ≥ k + 1.
            let x = srgb_curve_inverse((k as f64 + 0.5) / 255.0);
            let mut f = x as f32;
            if (f as f64) < x {
                f = f32::from_bits(f.to_bits() + 1);
            }
            *v = f;
        }
        t
    })
}

/// Bins of the coarse lookup in [`srgb_encode`]. The curve's steepest slope
/// is 12.92·255 ≈ 3295 codes per unit at 0, under one code per 1/4096 bin,
/// so a bin contains at most one threshold.
const SRGB_BINS: usize = 4096;

/// `START[i]`: the code of the bin start i / SRGB_BINS.
fn bin_start_codes() -> &'static [u8; SRGB_BINS + 1] {
    static T: std::sync::OnceLock<[u8; SRGB_BINS + 1]> = std::sync::OnceLock::new();
    T.get_or_init(|| {
        let t = thresholds();
        std::array::from_fn(|i| {
            let v = i as f32 / SRGB_BINS as f32;
            t.iter().take_while(|&&th| th <= v).count() as u8
        })
    })
}

/// Linear [0, 1] → sRGB-encoded 8-bit: round(255 · srgb(v)) of the exact
/// curve. The bin of v gives the code at the bin start; one comparison with
/// the next threshold finishes it (a `powf` per channel, or a branchy binary
/// search, cost more than the rest of tone mapping).
#[derive(Clone, Copy)]
pub struct SrgbEncoder {
    start: &'static [u8; SRGB_BINS + 1],
    thresholds: &'static [f32; 256],
}

impl SrgbEncoder {
    pub fn new() -> SrgbEncoder {
        SrgbEncoder {
            start: bin_start_codes(),
            thresholds: thresholds(),
        }
    }

    #[inline(always)]
    pub fn encode(&self, v: f32) -> u8 {
        // NaN → 0 (clamp keeps NaN; the cast saturates it to bin 0, and the
        // comparison with a threshold is false).
        let v = v.clamp(0.0, 1.0);
        let code = self.start[(v * SRGB_BINS as f32) as usize];
        code + (v >= self.thresholds[code as usize]) as u8
    }
}

impl Default for SrgbEncoder {
    fn default() -> Self {
        Self::new()
    }
}

/// [`SrgbEncoder::encode`] for one value.
pub fn srgb_encode(v: f32) -> u8 {
    SrgbEncoder::new().encode(v)
}

/// Sum of the ssaa² samples of output pixel (x, y), in sample order.
#[inline]
fn box_sum(target: &Target, color: &ColorBuffer, ssaa: u32, x: u32, y: u32) -> [f32; 3] {
    let mut s = [0.0f32; 3];
    for sy in 0..ssaa {
        for sx in 0..ssaa {
            let i = target.index(x * ssaa + sx, y * ssaa + sy);
            s[0] += color.r[i];
            s[1] += color.g[i];
            s[2] += color.b[i];
        }
    }
    s
}

/// Row-major linear HDR image of `width × height` (supersampled target size
/// divided by `ssaa`), each output pixel the mean of its ssaa² samples.
pub fn downsample(target: &Target, color: &ColorBuffer, ssaa: u32) -> (u32, u32, Vec<[f32; 3]>) {
    let (w, h) = (target.width / ssaa, target.height / ssaa);
    if ssaa == 1 {
        let (r, g, b) = (
            target.to_row_major(&color.r),
            target.to_row_major(&color.g),
            target.to_row_major(&color.b),
        );
        let rgb = r
            .iter()
            .zip(&g)
            .zip(&b)
            .map(|((r, g), b)| [*r, *g, *b])
            .collect();
        return (w, h, rgb);
    }
    let scale = 1.0 / (ssaa * ssaa) as f32;
    let mut out = vec![[0.0f32; 3]; (w * h) as usize];
    out.par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                *px = box_sum(target, color, ssaa, x as u32, y as u32).map(|c| c * scale);
            }
        });
    (w, h, out)
}

/// Supersampling resolve, exposure (in stops), tone mapping and sRGB
/// encoding in one pass over the tiles: 8-bit RGB, row-major, of
/// (width / ssaa) × (height / ssaa). Equal to `encode_ldr(downsample(..))`
/// (a test checks it) without the full-size HDR copy in between.
pub fn resolve_ldr(
    target: &Target,
    color: &ColorBuffer,
    ssaa: u32,
    tonemap: Tonemap,
    exposure: f32,
) -> Vec<u8> {
    // One monomorphized loop per curve: no match per channel.
    match tonemap {
        Tonemap::Clamp => {
            resolve_ldr_with(target, color, ssaa, exposure, |x| Tonemap::Clamp.apply(x))
        }
        Tonemap::Reinhard => resolve_ldr_with(target, color, ssaa, exposure, |x| {
            Tonemap::Reinhard.apply(x)
        }),
        Tonemap::Aces => {
            resolve_ldr_with(target, color, ssaa, exposure, |x| Tonemap::Aces.apply(x))
        }
    }
}

fn resolve_ldr_with(
    target: &Target,
    color: &ColorBuffer,
    ssaa: u32,
    exposure: f32,
    curve: impl Fn(f32) -> f32 + Sync,
) -> Vec<u8> {
    let (w, h) = (target.width / ssaa, target.height / ssaa);
    // The same products, in the same order, as downsample then encode_ldr.
    let (inv_n, k) = (1.0 / (ssaa * ssaa) as f32, exposure.exp2());
    let enc = SrgbEncoder::new();
    let encode = |px: &mut [u8], s: [f32; 3]| {
        for c in 0..3 {
            px[c] = enc.encode(curve(s[c] * inv_n * k));
        }
    };
    let mut out = vec![0u8; w as usize * h as usize * 3];
    out.par_chunks_mut(3 * w as usize)
        .enumerate()
        .for_each(|(y, row)| {
            if ssaa == 1 {
                // Whole tile rows are contiguous in the tile-major planes.
                for x0 in (0..w).step_by(TILE) {
                    let at = target.index(x0, y as u32);
                    let n = (w - x0).min(TILE as u32) as usize;
                    let px = &mut row[3 * x0 as usize..3 * (x0 as usize + n)];
                    for (i, px) in px.chunks_exact_mut(3).enumerate() {
                        encode(px, [color.r[at + i], color.g[at + i], color.b[at + i]]);
                    }
                }
                return;
            }
            for (x, px) in row.chunks_exact_mut(3).enumerate() {
                encode(px, box_sum(target, color, ssaa, x as u32, y as u32));
            }
        });
    out
}

/// Exposure (in stops), tone mapping and sRGB encoding: 8-bit RGB, row-major.
pub fn encode_ldr(hdr: &[[f32; 3]], tonemap: Tonemap, exposure: f32) -> Vec<u8> {
    let k = exposure.exp2();
    let enc = SrgbEncoder::new();
    let mut out = vec![0u8; hdr.len() * 3];
    out.par_chunks_mut(3 * 4096)
        .zip(hdr.par_chunks(4096))
        .for_each(|(o, h)| {
            for (o, px) in o.chunks_exact_mut(3).zip(h) {
                for c in 0..3 {
                    o[c] = enc.encode(tonemap.apply(px[c] * k));
                }
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_table_equals_rounding_the_f64_curve() {
        // Every 4096th f32 in [0, 1], plus the neighbours of each threshold.
        let mut checked = 0;
        let mut check = |v: f32| {
            let want = (srgb_curve(v as f64) * 255.0 + 0.5).floor() as u8;
            let got = srgb_encode(v);
            // Exactly at a rounding boundary the f64 curve and its inverse
            // may disagree by one code; nothing else may.
            let s = srgb_curve(v as f64) * 255.0;
            if (s - s.floor() - 0.5).abs() > 1e-9 {
                assert_eq!(got, want, "v = {v:e}");
            }
            checked += 1;
        };
        let mut b = 0u32;
        while b <= 1.0f32.to_bits() {
            check(f32::from_bits(b));
            b += 4096;
        }
        for k in 0..255 {
            let t = thresholds()[k];
            for v in [
                f32::from_bits(t.to_bits() - 1),
                t,
                f32::from_bits(t.to_bits() + 1),
            ] {
                check(v);
            }
            assert_eq!(srgb_encode(t) as usize, k + 1);
            assert_eq!(srgb_encode(f32::from_bits(t.to_bits() - 1)) as usize, k);
        }
        assert!(checked > 200_000);
    }

    #[test]
    fn srgb_matches_the_standard_at_known_points() {
        assert_eq!(srgb_encode(0.0), 0);
        assert_eq!(srgb_encode(1.0), 255);
        // 0.5 linear is 0.7354 encoded: 187.5 → 188.
        assert_eq!(srgb_encode(0.5), 188);
        assert_eq!(srgb_encode(0.0031308), 10);
    }

    #[test]
    fn fused_resolve_equals_downsample_then_encode() {
        let t = Target::new(150, 90).unwrap();
        let n = t.buffer_len();
        let f = |i: usize, c: f32| ((i as f32 * 0.37 + c).sin() * 2.0).max(0.0);
        let color = ColorBuffer {
            r: (0..n).map(|i| f(i, 0.0)).collect(),
            g: (0..n).map(|i| f(i, 1.0)).collect(),
            b: (0..n).map(|i| f(i, 2.0)).collect(),
        };
        for ssaa in [1, 3] {
            let (_, _, hdr) = downsample(&t, &color, ssaa);
            assert_eq!(
                resolve_ldr(&t, &color, ssaa, Tonemap::Aces, 0.5),
                encode_ldr(&hdr, Tonemap::Aces, 0.5)
            );
        }
    }

    #[test]
    fn tonemaps_send_nan_to_black_and_stay_in_range() {
        for op in [Tonemap::Clamp, Tonemap::Reinhard, Tonemap::Aces] {
            assert_eq!(op.apply(f32::NAN), 0.0);
            for x in [0.0, 0.1, 1.0, 10.0, 1e30, f32::INFINITY] {
                let y = op.apply(x);
                assert!((0.0..=1.0).contains(&y), "{op:?}({x}) = {y}");
            }
        }
    }
}
