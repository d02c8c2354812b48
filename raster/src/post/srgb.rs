//! The sRGB transfer function (IEC 61966-2-1) and its 8-bit encoders:
//! the threshold tables built from the exact curve, the scalar encoder
//! ([`SrgbEncoder`]) and the 8-lane one ([`SrgbEncoderX8`]) whose codes
//! equal it.

use specula_core::{f32x8, Real};
use wide::i32x8;

/// The sRGB transfer function (IEC 61966-2-1), in f64.
#[cfg(test)]
fn srgb_curve(v: f64) -> f64 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Inverse of `srgb_curve`: sRGB-encoded [0, 1] to linear.
pub fn srgb_curve_inverse(s: f64) -> f64 {
    if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

/// `THRESHOLDS[k]`: the smallest linear value that encodes to k + 1 or
/// more, i.e. the f64 curve's (k + ½)/255 crossing; a last +inf sentinel.
pub(super) fn thresholds() -> &'static [f32; 256] {
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
pub(crate) struct SrgbEncoder {
    start: &'static [u8; SRGB_BINS + 1],
    thresholds: &'static [f32; 256],
}

impl SrgbEncoder {
    pub(crate) fn new() -> SrgbEncoder {
        SrgbEncoder {
            start: bin_start_codes(),
            thresholds: thresholds(),
        }
    }

    #[inline(always)]
    pub(crate) fn encode(&self, v: f32) -> u8 {
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

/// Low bits of an f32 below a cell of [`SrgbEncoderX8`]'s table: a cell
/// is the floats sharing their top 17 bits (1/256 of a binade).
const CELL_BITS: u32 = 15;
/// Smallest value the cells cover (2⁻¹³, below the first threshold ≈
/// 1.5e-4); every float under it encodes to 0.
const CELL_FLOOR: f32 = 1.0 / 8192.0;
/// Threshold position of a cell that holds none (above every low part).
const NO_THRESHOLD: u32 = 1 << CELL_BITS;

/// Per cell of the float line from [`CELL_FLOOR`] to 1: the code of its
/// first float, plus (shifted by 8) the low [`CELL_BITS`] bits of the one
/// threshold inside it, or [`NO_THRESHOLD`]. Cells are 1/256 of their
/// binade wide and thresholds are at least 0.89 % apart (relative; at
/// v = 1, the curve's flattest), so a cell holds one at most; building the
/// table checks it.
fn srgb_cells() -> &'static [i32] {
    static T: std::sync::OnceLock<Vec<i32>> = std::sync::OnceLock::new();
    T.get_or_init(|| {
        let t = thresholds();
        // Number of thresholds ≤ v: the scalar encoder's code of v.
        let code = |v: f32| t.partition_point(|&th| th <= v);
        let first = CELL_FLOOR.to_bits() >> CELL_BITS;
        let last = 1.0f32.to_bits() >> CELL_BITS;
        // Floats below the floor read cell 0: it must say code 0 with no
        // threshold, as every one of them encodes to 0.
        let end_of_first = f32::from_bits(((first + 1) << CELL_BITS) - 1);
        assert_eq!(
            code(end_of_first),
            0,
            "the first sRGB cell holds a threshold"
        );
        (first..=last)
            .map(|cell| {
                let lo = f32::from_bits(cell << CELL_BITS);
                let hi = f32::from_bits(((cell + 1) << CELL_BITS) - 1);
                let (c, inside) = (code(lo), code(hi) - code(lo));
                assert!(inside <= 1, "sRGB cell at {lo:e} holds {inside} thresholds");
                let pos = if inside == 1 {
                    t[c].to_bits() & (NO_THRESHOLD - 1)
                } else {
                    NO_THRESHOLD
                };
                (c as u32 | pos << 8) as i32
            })
            .collect()
    })
}

/// [`SrgbEncoder`] on 8 values at once, with one table read per value
/// instead of two: the float's top bits pick a cell (`srgb_cells`), and
/// an integer comparison of its low bits with the cell's threshold adds
/// the last code. Its codes equal the scalar encoder's (a test checks every
/// threshold, cell edge and a sweep). The two dependent reads per value
/// (bin start, then threshold) were most of the fused post pass, and a
/// hardware gather is slow on the machines measured.
#[derive(Clone, Copy)]
pub(crate) struct SrgbEncoderX8 {
    cells: &'static [i32],
}

impl SrgbEncoderX8 {
    pub(crate) fn new() -> SrgbEncoderX8 {
        SrgbEncoderX8 {
            cells: srgb_cells(),
        }
    }

    /// The codes 0..=255 as i32 lanes.
    #[inline(always)]
    pub(crate) fn encode_i32(&self, v: f32x8) -> i32x8 {
        // NaN → 0 like the scalar encoder (Real::clamp maps NaN to 0).
        let v = Real::clamp(v, f32x8::ZERO, f32x8::ONE);
        let bits: i32x8 = bytemuck::cast(v);
        let first = i32x8::splat((CELL_FLOOR.to_bits() >> CELL_BITS) as i32);
        let last = i32x8::splat(self.cells.len() as i32 - 1);
        // v ∈ [0, 1]: below the floor, cell 0 (code 0, no threshold).
        let top: i32x8 = bits >> CELL_BITS as i32;
        let cell = (top - first).max(i32x8::ZERO).min(last);
        let e = gather_i32(self.cells, cell);
        let low = bits & i32x8::splat(NO_THRESHOLD as i32 - 1);
        // −1 where v is below the cell's threshold, else 0.
        let threshold: i32x8 = e >> 8;
        let below = threshold.simd_gt(low);
        (e & i32x8::splat(0xFF)) + i32x8::splat(1) + below
    }
}

/// 8 reads of `table` at indices already in `0..table.len()`.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
fn gather_i32(table: &[i32], i: i32x8) -> i32x8 {
    use core::arch::x86_64::{__m256i, _mm256_i32gather_epi32};
    assert!(!table.is_empty());
    debug_assert!(i.to_array().iter().all(|&k| (k as usize) < table.len()));
    let iv: __m256i = bytemuck::cast(i);
    // SAFETY: AVX2 is enabled (cfg); the caller clamps every index lane
    // into 0..table.len(), so each read is in bounds.
    bytemuck::cast(unsafe { _mm256_i32gather_epi32::<4>(table.as_ptr(), iv) })
}

/// Per-lane fallback of the gather above.
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
#[inline(always)]
fn gather_i32(table: &[i32], i: i32x8) -> i32x8 {
    let i = i.to_array();
    i32x8::new(core::array::from_fn(|l| table[i[l] as usize]))
}

impl Default for SrgbEncoderX8 {
    fn default() -> Self {
        Self::new()
    }
}

/// `SrgbEncoder::encode` for one value.
pub fn srgb_encode(v: f32) -> u8 {
    SrgbEncoder::new().encode(v)
}

#[cfg(test)]
mod tests {
    use super::super::Tonemap;
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
    fn eight_lane_curves_and_encoder_equal_the_scalar_ones() {
        // Every threshold and its neighbours, the bin edges, and a sweep
        // over [−1, 4] plus the special values.
        let mut vals: Vec<f32> = vec![f32::NAN, f32::INFINITY, -0.0, 1e30, 1e18, 2e18];
        for t in thresholds().iter().take(255) {
            vals.extend([
                f32::from_bits(t.to_bits() - 1),
                *t,
                f32::from_bits(t.to_bits() + 1),
            ]);
        }
        vals.extend((0..=SRGB_BINS).map(|i| i as f32 / SRGB_BINS as f32));
        vals.extend((0..50_000).map(|i| i as f32 * 1e-4 - 1.0));
        // The vector encoder's cells: each one's first and last float and
        // their outer neighbours, and a sweep over the bit patterns of
        // [0, 1] with an odd stride (every exponent, every cell).
        let first = CELL_FLOOR.to_bits() >> CELL_BITS;
        for cell in first..=(1.0f32.to_bits() >> CELL_BITS) {
            let lo = cell << CELL_BITS;
            let hi = lo + (1 << CELL_BITS) - 1;
            vals.extend([lo - 1, lo, hi, hi + 1].map(f32::from_bits));
        }
        vals.extend((0..=1.0f32.to_bits()).step_by(997).map(f32::from_bits));
        vals.resize(vals.len().div_ceil(8) * 8, 0.5);
        let (enc, enc8) = (SrgbEncoder::new(), SrgbEncoderX8::new());
        for chunk in vals.chunks_exact(8) {
            let v = f32x8::from(<[f32; 8]>::try_from(chunk).unwrap());
            let codes = enc8.encode_i32(v).to_array();
            for (lane, &x) in chunk.iter().enumerate() {
                assert_eq!(codes[lane], enc.encode(x) as i32, "encode({x:e})");
            }
            for op in [Tonemap::Clamp, Tonemap::Reinhard, Tonemap::Aces] {
                let y = op.apply_x8(v).to_array();
                for (lane, &x) in chunk.iter().enumerate() {
                    assert_eq!(y[lane].to_bits(), op.apply(x).to_bits(), "{op:?}({x:e})");
                }
            }
        }
    }
}
