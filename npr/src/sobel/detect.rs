//! Detection: the edge marks of a frame, row by row (`detect_row`) in
//! bands of [`BAND_ROWS`] rows whose inputs each band computes itself
//! (`Sobel::detect`). A row's interior goes 8 samples at a time through
//! every source at once (`detect_lanes`), 64 at a time where the block
//! bounds allow ([`detect_block`]); its ends through the clamped scalar
//! measure.

use super::block::{detect_block, BLOCK};
use super::inputs::{inverse_depth_into, label_of_id, labels_into, luma_into, EdgeInput};
use super::measure::{measure_at, W};
use super::{prefetch, Buffers, Sobel, Source, BAND_ROWS};
#[cfg(test)]
use crate::dilate::EdgeMask;
use rayon::prelude::*;
use specula_core::{Mask, Real};
use specula_raster::FrameBuffers;
use wide::f32x8;

/// Marks edge samples (1) in a `width × height` mask; see [`crate::sobel`].
/// `keep(i)` says whether sample i may carry a line (material selection).
/// [`detect_row`] on every row of the whole-frame `input`.
#[cfg(test)]
pub(crate) fn detect_edges(
    input: &EdgeInput,
    sources: &[(Source, f32)],
    keep: &(dyn Fn(usize) -> bool + Sync),
) -> Vec<bool> {
    let (w, h) = (input.width, input.height);
    let mut mask = EdgeMask::new(w, h);
    let words = mask.words();
    mask.bits_mut()
        .par_chunks_mut(words.max(1))
        .enumerate()
        .for_each(|(y, out)| {
            let rows = [y.saturating_sub(1), y, (y + 1).min(h - 1)].map(|r| r * w);
            detect_row(input, sources, rows, &|x| keep(y * w + x), out);
        });
    mask.to_bools()
}

/// Marks the edge samples of one row into its mask words `out` (every
/// word written). `rows` are the offsets in `input`'s slices of the row
/// above, the row and the row below (clamped by the caller at the image's
/// top and bottom); `keep(x)` says whether sample x of the row may carry
/// a line.
///
/// A sample is marked when any source's measure exceeds its threshold and
/// `keep` allows it (asked only where a source does: most samples have no
/// edge). The row's interior goes 8 samples at a time through every
/// source at once (`detect_lanes`); its first and last sample (and every
/// sample of a row under `FUSED_MIN_WIDTH`) through the clamped scalar
/// `measure_at` (`mark_clamped`).
#[cfg(test)]
pub(crate) fn detect_row(
    input: &EdgeInput,
    sources: &[(Source, f32)],
    rows: [usize; 3],
    keep: &dyn Fn(usize) -> bool,
    out: &mut [u64],
) {
    detect_row_ahead(input, sources, rows, None, keep, out);
}

/// `detect_row`, prefetching the normals of the row starting at
/// `ahead` (an offset in `input`'s slices) as it goes.
fn detect_row_ahead(
    input: &EdgeInput,
    sources: &[(Source, f32)],
    rows: [usize; 3],
    ahead: Option<usize>,
    keep: &dyn Fn(usize) -> bool,
    out: &mut [u64],
) {
    let w = input.width;
    out.fill(0);
    if w < FUSED_MIN_WIDTH {
        for x in 0..w {
            mark_clamped(input, sources, rows, x, out);
        }
    } else {
        let t = Thresholds::new(sources);
        let f = fields(input);
        let used = [
            t.depth.is_some(),
            t.normal.is_some(),
            t.normal.is_some(),
            t.normal.is_some(),
            t.id.is_some(),
            t.color.is_some(),
        ];
        // Blocks of 64 samples x..x+64 with x = 1, 65, …, then one more
        // ending at w − 2, overlapping the one before (its marks are the
        // same bits again); rows too narrow for a block in chunks of 8 up
        // to w − 2, the last one overlapping likewise.
        let block = |x: usize, out: &mut [u64]| {
            if let Some(a) = ahead {
                for f in input.normal {
                    for k in (0..BLOCK).step_by(16) {
                        prefetch(f, a + x + k);
                    }
                }
            }
            let bits = detect_block(&f, used, &t, rows, x);
            let (j, sh) = (x / 64, x % 64);
            out[j] |= bits << sh;
            if sh > 0 {
                out[j + 1] |= bits >> (64 - sh);
            }
        };
        let mut x = 1;
        while x + BLOCK < w {
            block(x, out);
            x += BLOCK;
        }
        if x > 1 {
            if x < w - 1 {
                block(w - 1 - BLOCK, out);
            }
        } else {
            let last = w - 9;
            for x in (1..last).step_by(8).chain(std::iter::once(last)) {
                if let Some(a) = ahead {
                    for f in input.normal {
                        prefetch(f, a + x);
                    }
                }
                let bits = u64::from(detect_lanes(&t, |k| around8(f[k as usize], rows, x)));
                let (j, sh) = (x / 64, x % 64);
                out[j] |= bits << sh;
                if sh > 56 {
                    out[j + 1] |= bits >> (64 - sh);
                }
            }
        }
        mark_clamped(input, sources, rows, 0, out);
        mark_clamped(input, sources, rows, w - 1, out);
    }
    for (j, word) in out.iter_mut().enumerate() {
        let mut set = *word;
        while set != 0 {
            let b = set.trailing_zeros() as usize;
            if !keep(64 * j + b) {
                *word &= !(1 << b);
            }
            set &= set - 1;
        }
    }
}

/// Rows narrower than this (no interior chunk of 8 samples with its
/// neighbours) are measured sample by sample (`mark_clamped`).
const FUSED_MIN_WIDTH: usize = 10;

/// Marks sample x of a row (`rows` as in `detect_row`) if any source's
/// clamped scalar `measure_at` exceeds its threshold.
fn mark_clamped(
    input: &EdgeInput,
    sources: &[(Source, f32)],
    rows: [usize; 3],
    x: usize,
    out: &mut [u64],
) {
    let w = input.width;
    let xs = [x.saturating_sub(1), x, (x + 1).min(w - 1)];
    let nb = rows.map(|r| xs.map(|x| r + x));
    for &(s, t) in sources {
        if measure_at(input, s, &nb) > t {
            out[x / 64] |= 1 << (x % 64);
        }
    }
}

/// Each source's threshold for `detect_lanes`, `None` when it is not a
/// source. A source listed twice marks where its measure exceeds either
/// threshold, i.e. the lesser (a NaN threshold marks nothing: dropped).
#[derive(Clone, Copy)]
pub(super) struct Thresholds {
    pub(super) depth: Option<f32x8>,
    pub(super) normal: Option<f32x8>,
    pub(super) id: Option<f32x8>,
    pub(super) color: Option<f32x8>,
}

impl Thresholds {
    pub(super) fn new(sources: &[(Source, f32)]) -> Thresholds {
        let least = |s: Source| {
            sources
                .iter()
                .filter(|&&(t, v)| t == s && !v.is_nan())
                .map(|&(_, v)| v)
                .reduce(f32::min)
                .map(f32x8::splat)
        };
        // The gradients' thresholds apply to the squared magnitude.
        let squared = |s| least(s).map(|t| f32x8::splat(below_sqrt(t.as_array()[0])));
        Thresholds {
            depth: least(Source::Depth),
            normal: squared(Source::Normal),
            id: least(Source::Id),
            color: squared(Source::Color),
        }
    }
}

/// The threshold on g² ≥ 0 that says what `√g² > t` says, without the
/// square root: the largest x with √x ≤ t (f32, correctly rounded √ as
/// the lanes' and measure_at's), so √g² > t ⟺ g² > x (√ is monotone; a
/// NaN g² is neither). Every g² ≥ 0 has √ > t < 0: x = −1 then.
pub(super) fn below_sqrt(t: f32) -> f32 {
    if t < 0.0 {
        return -1.0;
    }
    if t == f32::INFINITY {
        return t;
    }
    // t² is within a few ulps of x: step to it.
    let mut x = t * t;
    while x.sqrt() > t {
        x = x.next_down();
    }
    while x < f32::INFINITY && x.next_up().sqrt() <= t {
        x = x.next_up();
    }
    x
}

/// The fields a detection reads, indices into [`fields`].
#[derive(Clone, Copy)]
pub(super) enum Field {
    InvDepth,
    NormalX,
    NormalY,
    NormalZ,
    Label,
    Luma,
}

/// `input`'s fields in [`Field`]'s order.
fn fields<'a>(input: &EdgeInput<'a>) -> [&'a [f32]; 6] {
    let [nx, ny, nz] = input.normal;
    [input.inv_depth, nx, ny, nz, input.material, input.luma]
}

/// `s` (8 values) as one vector load (zeros if `s` is not 8 long).
#[inline(always)]
pub(super) fn load8(s: &[f32]) -> f32x8 {
    f32x8::from(<[f32; 8]>::try_from(s).unwrap_or_default())
}

/// The 3×3 neighbourhoods of field `f` at the 8 samples x..x+8 of a row
/// (`rows` as in `detect_row`; 1 ≤ x, x + 9 ≤ width): `[r][c]` holds
/// the row r (0 above), column offset c − 1. One bounds check a row.
#[inline(always)]
fn around8(f: &[f32], rows: [usize; 3], x: usize) -> [[f32x8; 3]; 3] {
    // No array `map` here: it was left as a call copying the arrays.
    #[inline(always)]
    fn row(f: &[f32], r: usize, x: usize) -> [f32x8; 3] {
        let s = &f[r + x - 1..r + x + 9];
        [load8(&s[..8]), load8(&s[1..9]), load8(&s[2..])]
    }
    [row(f, rows[0], x), row(f, rows[1], x), row(f, rows[2], x)]
}

/// Sobel gradient (Gx, Gy) over a neighbourhood,
/// [`gradient`](super::measure::gradient)'s sums in its order but for its
/// leading 0 + (see `detect_lanes`): for squaring.
#[inline(always)]
fn gradient8(n: &[[f32x8; 3]; 3]) -> (f32x8, f32x8) {
    let w = W.map(f32x8::splat);
    let gx = w[0] * (n[0][2] - n[0][0]) + w[1] * (n[1][2] - n[1][0]) + w[2] * (n[2][2] - n[2][0]);
    let gy = w[0] * (n[2][0] - n[0][0]) + w[1] * (n[2][1] - n[0][1]) + w[2] * (n[2][2] - n[0][2]);
    (gx, gy)
}

/// Whether the 8 samples x..x+8 of a row (bit i: sample x + i) exceed any
/// source's threshold: every source's measure at once, each `measure_at`'s
/// operations in its order (no FMA) but for the leading 0 + of its sums
/// (0 + p is p but for a zero's sign, which the squares and |·| drop),
/// so the same values bit for bit
/// (tested), from one read of the neighbourhood of each field.
#[inline(always)]
pub(super) fn detect_lanes(t: &Thresholds, around: impl Fn(Field) -> [[f32x8; 3]; 3]) -> u32 {
    let zero = f32x8::ZERO;
    let mut hit = zero;
    if let Some(td) = t.depth {
        let n = around(Field::InvDepth);
        let two = f32x8::splat(2.0);
        let w = W.map(f32x8::splat);
        let ddx = |k: usize| w[k] * (n[k][2] + n[k][0] - two * n[k][1]);
        let ddy = |k: usize| w[k] * (n[2][k] + n[0][k] - two * n[1][k]);
        let (dxx, dyy) = (ddx(0) + ddx(1) + ddx(2), ddy(0) + ddy(1) + ddy(2));
        // measure_at's maxima in its order, less its leading max(0, ·):
        // that changes q_max only where every q ≤ 0 (or from a NaN on),
        // and there q_max > 0 fails both ways (1/w is ≥ 0 anyway).
        let mut qmax = n[0][0];
        for (k, nk) in n.iter().enumerate() {
            for (c, &v) in nk.iter().enumerate() {
                if k + c > 0 {
                    qmax = Real::max(qmax, v);
                }
            }
        }
        // Lanes with q_max = 0 divide 0 by 0; the select drops them.
        let d = Real::max(dxx.abs(), dyy.abs()) / qmax;
        hit |= qmax.simd_gt(zero).select(d, zero).simd_gt(td);
    }
    if let Some(tn) = t.normal {
        let mut g2 = zero;
        for f in [Field::NormalX, Field::NormalY, Field::NormalZ] {
            let (gx, gy) = gradient8(&around(f));
            g2 += gx * gx + gy * gy;
        }
        hit |= g2.simd_gt(tn); // √g² > t (Thresholds)
    }
    if let Some(ti) = t.id {
        // Labels are never NaN: the unordered ≠ is measure_at's !=. The
        // sums are of small integers, exact in any order; the centre
        // never differs.
        let n = around(Field::Label);
        let centre = n[1][1];
        let mut f = zero;
        for (r, nr) in n.iter().enumerate() {
            for (c, &o) in nr.iter().enumerate() {
                if r != 1 || c != 1 {
                    let weight = f32x8::splat(if r == 1 || c == 1 { 2.0 } else { 1.0 });
                    f += o.simd_ne(centre) & weight;
                }
            }
        }
        hit |= (f / f32x8::splat(12.0)).simd_gt(ti);
    }
    if let Some(tc) = t.color {
        let (gx, gy) = gradient8(&around(Field::Luma));
        hit |= (gx * gx + gy * gy).simd_gt(tc); // √ as above
    }
    hit.bits()
}

impl Sobel {
    /// Marks the frame's edge samples into `mask`: `detect_row` on
    /// bands of [`BAND_ROWS`] rows, each band computing its own 1/w,
    /// labels and luminance (rows of the band and one each side).
    pub(super) fn detect(&self, frame: &FrameBuffers, b: &mut Buffers) {
        let (w, h) = (frame.width as usize, frame.height as usize);
        b.mask.resize(w, h);
        let words = b.mask.words();
        let (depth, normal, id, color) = (
            self.has(Source::Depth),
            self.has(Source::Normal),
            self.has(Source::Id),
            self.has(Source::Color),
        );
        if id {
            label_of_id(&self.id_material, &mut b.label_of_id);
        }
        let (of_id, pool) = (&b.label_of_id, &b.bands);
        let ids = &frame.id;
        let needs_ids = self.selection.needs_ids();
        b.mask
            .bits_mut()
            .par_chunks_mut((words * BAND_ROWS).max(1))
            .enumerate()
            .for_each(|(band, out)| {
                let y0 = band * BAND_ROWS;
                let y1 = (y0 + BAND_ROWS).min(h);
                let (ya, yb) = (y0.saturating_sub(1), (y1 + 1).min(h));
                let range = ya * w..yb * w;
                let n = range.len();
                // The normals' slices reach two rows past the band, for
                // the prefetch.
                let yn = (yb + 2).min(h);
                pool.with(|s| {
                    if depth {
                        s.inv_depth.resize(n, 0.0);
                        inverse_depth_into(&frame.depth[range.clone()], &mut s.inv_depth[..n]);
                    }
                    if id {
                        s.material.resize(n, 0.0);
                        labels_into(&frame.id[range.clone()], of_id, &mut s.material[..n]);
                    }
                    if color {
                        s.luma.resize(n, 0.0);
                        luma_into(&frame.color, range.clone(), &mut s.luma[..n]);
                    }
                    let nrm = &frame.normal;
                    let input = EdgeInput {
                        width: w,
                        height: yb - ya,
                        inv_depth: part(depth, &s.inv_depth, 0..n),
                        normal: [&nrm.r, &nrm.g, &nrm.b].map(|c| part(normal, c, ya * w..yn * w)),
                        material: part(id, &s.material, 0..n),
                        luma: part(color, &s.luma, 0..n),
                    };
                    for (y, out) in (y0..y1).zip(out.chunks_mut(words.max(1))) {
                        let rows = [y.saturating_sub(1), y, (y + 1).min(h - 1)];
                        let rows = rows.map(|r| (r - ya) * w);
                        let keep = |x: usize| !needs_ids || self.selection.contains(ids[y * w + x]);
                        // The normals are read from the frame, two rows
                        // ahead of their first use (the band's other
                        // inputs were just computed and are in cache).
                        let ahead = (normal && y + 2 < yn).then(|| (y + 2 - ya) * w);
                        detect_row_ahead(&input, &self.sources, rows, ahead, &keep, out);
                    }
                });
            });
        b.mask.rows_marked(&mut b.marked);
    }
}

/// `v[range]` for a source in use, else empty (its buffer may be absent).
fn part(on: bool, v: &[f32], range: std::ops::Range<usize>) -> &[f32] {
    if on {
        &v[range]
    } else {
        &[]
    }
}
