//! The 8-bit encode at the end of the post list: exposure, tone curve and
//! sRGB code per pixel, eight pixels at a time ([`LdrEncoding`], which the
//! shading pass runs on its rows, and the loop the fused downsample shares),
//! and the encode of already tone-mapped planes ([`encode_ldr`]).

use super::srgb::{SrgbEncoder, SrgbEncoderX8};
use super::tonemap::{curve_of, Tonemap};
use crate::buffers::Planes3;
use rayon::prelude::*;
use specula_core::f32x8;
use wide::i32x8;

/// [`encode_pixels`] of one sample a pixel from the slices `r`, `g`, `b`
/// (n = 1: the downsample's × (1/n) is × 1).
#[inline(always)]
pub(super) fn encode_planes<const CURVE: u8>(
    r: &[f32],
    g: &[f32],
    b: &[f32],
    k: f32,
    out: &mut [u8],
) {
    let n = r.len();
    assert!(g.len() == n && b.len() == n && out.len() == 3 * n);
    let eight = |x0| [load8(r, x0), load8(g, x0), load8(b, x0)];
    encode_pixels::<CURVE>(out, 1.0, k, eight, |x| [r[x], g[x], b[x]]);
}

/// Sample sum × (1/n) × k, tone curve and sRGB code of a run of pixels
/// into `out` (3 bytes a pixel): `sums8(x0)` gives pixels x0..x0 + 8 per
/// channel, `sum1(x)` pixel x. The downsample's loop and the shading pass's
/// ([`LdrEncoding::encode_row`]), so both give the same bytes.
#[inline(always)]
pub(super) fn encode_pixels<const CURVE: u8>(
    out: &mut [u8],
    inv_n: f32,
    k: f32,
    sums8: impl Fn(usize) -> [f32x8; 3],
    sum1: impl Fn(usize) -> [f32; 3],
) {
    let curve = curve_of::<CURVE>();
    let (enc, enc8) = (SrgbEncoder::new(), SrgbEncoderX8::new());
    let full = out.len() / 3 / 8 * 8;
    // Eight pixels at a time: the per-channel scalar chain (scale, curve,
    // two table reads) was the pass's cost.
    for (x0, px8) in (0..full).step_by(8).zip(out.chunks_exact_mut(24)) {
        let s = sums8(x0);
        let code = |ch| ldr_code(&enc8, curve, ch, inv_n, k);
        store_rgb8(px8, [code(s[0]), code(s[1]), code(s[2])]);
    }
    for (x, px) in out.chunks_exact_mut(3).enumerate().skip(full) {
        let s = sum1(x);
        for c in 0..3 {
            px[c] = enc.encode(curve.apply(s[c] * inv_n * k));
        }
    }
}

/// The standard post list at ssaa 1 (exposure, tone map, sRGB encode) as
/// the shading pass can run it on each tile row while the row is in
/// cache, instead of writing linear colour planes for the post to read
/// back (see [`Post::ldr_in_shading`](super::Post::ldr_in_shading)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LdrEncoding {
    tonemap: Tonemap,
    /// 2^exposure, as the downsample computes it (once here, not per row).
    k: f32,
}

impl LdrEncoding {
    /// Exposure `stops`, then `tonemap`, then the sRGB encode.
    pub(crate) fn new(tonemap: Tonemap, stops: f32) -> LdrEncoding {
        LdrEncoding {
            tonemap,
            k: stops.exp2(),
        }
    }

    /// Codes of the pixels with linear colours `r[i]`, `g[i]`, `b[i]` into
    /// `out[3i..3i + 3]`: the bytes [`downsample_ldr_into`](super::downsample_ldr_into) gives for them.
    pub(crate) fn encode_row(&self, r: &[f32], g: &[f32], b: &[f32], out: &mut [u8]) {
        match self.tonemap {
            Tonemap::Clamp => encode_planes::<0>(r, g, b, self.k, out),
            Tonemap::Reinhard => encode_planes::<1>(r, g, b, self.k, out),
            Tonemap::Aces => encode_planes::<2>(r, g, b, self.k, out),
        }
    }
}

/// Sizes `out` to `len` bytes, writing zeros only where it grows (every
/// caller overwrites all of it).
pub(super) fn size_output(out: &mut Vec<u8>, len: usize) {
    out.truncate(len);
    crate::buffers::resize_zeroed(out, len);
}

/// p[i..i + 8] as one vector load (filling an array lane by lane and
/// reading it back stalls on store forwarding).
#[inline(always)]
pub(super) fn load8(p: &[f32], i: usize) -> f32x8 {
    f32x8::from(<[f32; 8]>::try_from(&p[i..i + 8]).unwrap())
}

/// Writes eight pixels' sRGB codes (0..=255 per lane) as 24 bytes of RGB:
/// r | g << 8 | b << 16 is each pixel's three bytes in one little-endian
/// word; one byte shuffle packs each 128-bit half's four words into 12
/// bytes, stored as 8 + 4 (4 stores for 8 pixels instead of 8 word
/// extracts and 8 stores).
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
fn store_rgb8(px8: &mut [u8], [r, g, b]: [i32x8; 3]) {
    use core::arch::x86_64::{
        __m256i, _mm256_castsi256_si128, _mm256_extracti128_si256, _mm256_setr_epi8,
        _mm256_shuffle_epi8, _mm_cvtsi128_si64, _mm_extract_epi32,
    };
    let word: __m256i = bytemuck::cast(r | (g << 8) | (b << 16));
    // SAFETY: AVX2 is enabled (cfg); these are register operations only.
    let (lo, hi) = unsafe {
        let pack = _mm256_setr_epi8(
            0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1, //
            0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1,
        );
        let packed = _mm256_shuffle_epi8(word, pack);
        let (lo, hi) = (
            _mm256_castsi256_si128(packed),
            _mm256_extracti128_si256::<1>(packed),
        );
        (
            (_mm_cvtsi128_si64(lo), _mm_extract_epi32::<2>(lo)),
            (_mm_cvtsi128_si64(hi), _mm_extract_epi32::<2>(hi)),
        )
    };
    let out: &mut [u8; 24] = px8.try_into().expect("24 bytes for 8 pixels");
    for ((first8, next4), at) in [(lo, 0), (hi, 12)] {
        out[at..at + 8].copy_from_slice(&first8.to_le_bytes());
        out[at + 8..at + 12].copy_from_slice(&next4.to_le_bytes());
    }
}

/// The portable form of the store above: each pixel's word stored at
/// 3 × lane (the next lane overwrites its fourth byte; the last writes
/// three). A cast to u8 per channel was a large share of the fused pass.
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
#[inline(always)]
fn store_rgb8(px8: &mut [u8], [r, g, b]: [i32x8; 3]) {
    let word: i32x8 = r | (g << 8) | (b << 16);
    let rgb = word.to_array();
    for (lane, w) in rgb.iter().enumerate().take(7) {
        px8[3 * lane..3 * lane + 4].copy_from_slice(&w.to_le_bytes());
    }
    px8[21..24].copy_from_slice(&rgb[7].to_le_bytes()[..3]);
}

/// One channel of eight pixels: sample sum × (1/n) × 2^exposure, tone
/// curve, sRGB code.
#[inline(always)]
fn ldr_code(enc8: &SrgbEncoderX8, curve: Tonemap, ch: f32x8, inv_n: f32, k: f32) -> i32x8 {
    let v = ch * f32x8::splat(inv_n) * f32x8::splat(k);
    enc8.encode_i32(curve.apply_x8(v))
}

/// sRGB encoding of tone-mapped values: 8-bit RGB, row-major.
pub fn encode_ldr(rgb: &Planes3) -> Vec<u8> {
    let mut out = Vec::new();
    encode_ldr_into(rgb, &mut out);
    out
}

/// [`encode_ldr`] into `out` (see [`downsample_ldr_into`](super::downsample_ldr_into)).
pub(crate) fn encode_ldr_into(rgb: &Planes3, out: &mut Vec<u8>) {
    let enc = SrgbEncoder::new();
    let enc8 = SrgbEncoderX8::new();
    size_output(out, rgb.len() * 3);
    out.par_chunks_mut(3 * 4096)
        .enumerate()
        .for_each(|(chunk, o)| {
            // Eight pixels at a time with the vector encoder (its codes are
            // the scalar encoder's): the scalar loop cost more than the
            // whole fused post list, and ran whenever a custom stage
            // unfuses the list (the outlines, strokes).
            let n = o.len() / 3;
            let full = n / 8 * 8;
            let base = chunk * 4096;
            for (j, px8) in o[..full * 3].chunks_exact_mut(24).enumerate() {
                let i = base + j * 8;
                let code = |p: &[f32]| enc8.encode_i32(load8(p, i));
                store_rgb8(px8, [code(&rgb.r), code(&rgb.g), code(&rgb.b)]);
            }
            for (j, px) in o.chunks_exact_mut(3).enumerate().skip(full) {
                let i = base + j;
                px[0] = enc.encode(rgb.r[i]);
                px[1] = enc.encode(rgb.g[i]);
                px[2] = enc.encode(rgb.b[i]);
            }
        });
}

#[cfg(test)]
mod tests {
    use super::super::srgb::thresholds;
    use super::*;

    #[test]
    fn encode_ldr_packets_equal_the_scalar_encoder() {
        // Each threshold and its neighbours, out-of-range values, NaN and
        // infinities, over more than one 4096-pixel chunk and a tail.
        let mut v = vec![
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -1.0,
            -0.0,
            0.0,
            1.0,
            2.0,
        ];
        for &t in thresholds().iter().filter(|t| t.is_finite()) {
            v.extend([t.next_down(), t, t.next_up()]);
        }
        while v.len() < 9003 {
            v.push((v.len() as f32 * 0.618034).fract());
        }
        let n = v.len();
        let rot = |k: usize| (0..n).map(|i| v[(i + k) % n]).collect::<Vec<f32>>();
        let rgb = Planes3 {
            r: rot(0),
            g: rot(1),
            b: rot(2),
        };
        let out = encode_ldr(&rgb);
        let enc = SrgbEncoder::new();
        for i in 0..n {
            let want = [
                enc.encode(rgb.r[i]),
                enc.encode(rgb.g[i]),
                enc.encode(rgb.b[i]),
            ];
            assert_eq!(out[3 * i..3 * i + 3], want, "pixel {i}: {}", rgb.r[i]);
        }
    }
}
