//! Edge marks one bit a sample ([`EdgeMask`]) and their widening into
//! lines: the exact Euclidean distance transform ([`distance`]) and the
//! bounded search that gives the same coverage for narrow lines
//! ([`dilate`], [`dilate_row`]), which the Sobel outline
//! ([`crate::sobel`]) runs row by row straight into the blend.

use rayon::prelude::*;
use std::sync::Mutex;
use wide::{f32x8, i32x8};

/// Marked samples of a `width × height` image, one bit a sample: sample
/// (x, y) is bit x % 64 of word `y·words + x/64`, with `words` =
/// ⌈width/64⌉ a row, so rows start on a word and are written by one task
/// each. Bits past a row's end are 0. 2 MB of booleans at 1920 × 1080
/// are 259 KB here, and 64 samples with no mark are one zero word.
#[derive(Clone, Debug, Default)]
pub(crate) struct EdgeMask {
    width: usize,
    height: usize,
    words: usize,
    bits: Vec<u64>,
}

impl EdgeMask {
    /// An empty mask.
    pub(crate) fn new(width: usize, height: usize) -> EdgeMask {
        let mut m = EdgeMask::default();
        m.resize(width, height);
        m
    }

    /// Sizes the mask for `width × height`, keeping its allocation (a
    /// steady frame reuses it). The contents are unspecified: every
    /// writer sets whole rows.
    pub(crate) fn resize(&mut self, width: usize, height: usize) {
        self.width = width;
        self.height = height;
        self.words = width.div_ceil(64);
        self.bits.resize(self.words * height, 0);
    }

    pub(crate) fn from_bools(mask: &[bool], width: usize, height: usize) -> EdgeMask {
        let mut m = EdgeMask::new(width, height);
        for (y, row) in m.rows_mut().enumerate() {
            row.fill(0);
            for x in 0..width {
                if mask[y * width + x] {
                    row[x / 64] |= 1 << (x % 64);
                }
            }
        }
        m
    }

    pub(crate) fn to_bools(&self) -> Vec<bool> {
        (0..self.width * self.height)
            .map(|i| self.get(i % self.width, i / self.width))
            .collect()
    }

    #[inline]
    pub(crate) fn get(&self, x: usize, y: usize) -> bool {
        self.row(y)[x / 64] >> (x % 64) & 1 != 0
    }

    pub(crate) fn width(&self) -> usize {
        self.width
    }

    pub(crate) fn height(&self) -> usize {
        self.height
    }

    /// Words a row.
    pub(crate) fn words(&self) -> usize {
        self.words
    }

    #[inline]
    pub(crate) fn row(&self, y: usize) -> &[u64] {
        &self.bits[y * self.words..(y + 1) * self.words]
    }

    /// The words of all rows, row after row (for writers that split them
    /// into bands of whole rows).
    pub(crate) fn bits_mut(&mut self) -> &mut [u64] {
        &mut self.bits
    }

    fn rows_mut(&mut self) -> impl Iterator<Item = &mut [u64]> {
        self.bits.chunks_mut(self.words.max(1))
    }

    /// Whether each row holds a mark, into `out` (reused).
    pub(crate) fn rows_marked(&self, out: &mut Vec<bool>) {
        out.clear();
        out.extend((0..self.height).map(|y| self.row(y).iter().any(|&b| b != 0)));
    }
}

/// Scratch values of one type shared by the tasks of a parallel loop and
/// kept across frames: a task takes one (or a new default one), uses it and
/// puts it back. Nothing is carried from one use to the next: every user
/// writes what it reads.
#[derive(Debug, Default)]
pub(crate) struct Pool<T>(Mutex<Vec<T>>);

impl<T: Default> Pool<T> {
    pub(crate) fn with<R>(&self, f: impl FnOnce(&mut T) -> R) -> R {
        // A panic elsewhere while the lock was held cannot leave the list
        // in a state that matters (its values are scratch).
        let take = || self.0.lock().unwrap_or_else(|e| e.into_inner()).pop();
        let mut t = take().unwrap_or_default();
        let r = f(&mut t);
        self.0.lock().unwrap_or_else(|e| e.into_inner()).push(t);
        r
    }
}

/// Squared distance transform in one dimension \[Felzenszwalb12\]: d[q] =
/// min_p (q − p)² + f[p], by the lower envelope of parabolas.
///
/// The parabola intersections are in f64: q² of a supersampled row
/// (7680² at 1920 × ssaa 4) is past f32's exact integers.
fn edt_1d(f: &[f32], d: &mut [f32], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    if n == 0 {
        return;
    }
    let mut k = 0;
    v[0] = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        loop {
            let p = v[k];
            let s = ((f[q] as f64 + (q * q) as f64) - (f[p] as f64 + (p * p) as f64))
                / (2.0 * (q - p) as f64);
            if s <= z[k] && k > 0 {
                k -= 1;
                continue;
            }
            if s <= z[k] {
                // k == 0 and the new parabola is below everywhere left.
                v[0] = q;
                z[0] = f64::NEG_INFINITY;
                z[1] = f64::INFINITY;
                break;
            }
            k += 1;
            v[k] = q;
            z[k] = s;
            z[k + 1] = f64::INFINITY;
            break;
        }
    }
    k = 0;
    for (q, dq) in d.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        let dx = q as f64 - p as f64;
        *dq = (dx * dx + f[p] as f64) as f32;
    }
}

/// "Infinitely" far, squared: finite so the parabola algebra stays finite.
const FAR2: f32 = 1e20;

/// Euclidean distance from every sample to the nearest marked one
/// (`FAR2.sqrt()` when there is none): columns, then rows.
pub(crate) fn distance(mask: &[bool], w: usize, h: usize) -> Vec<f32> {
    // Columns: the mask is binary, so its 1-D transform is the squared
    // distance to the nearest mark above or below (two sweeps).
    let mut cols = vec![0.0f32; w * h]; // column-major
    cols.par_chunks_mut(h.max(1))
        .enumerate()
        .for_each(|(x, out)| {
            let mut last: Option<usize> = None;
            for (y, o) in out.iter_mut().enumerate() {
                if mask[y * w + x] {
                    last = Some(y);
                }
                *o = last.map_or(FAR2, |l| ((y - l) as f32).powi(2));
            }
            let mut next: Option<usize> = None;
            for (y, o) in out.iter_mut().enumerate().rev() {
                if mask[y * w + x] {
                    next = Some(y);
                }
                if let Some(n) = next {
                    *o = o.min(((n - y) as f32).powi(2));
                }
            }
        });
    let mut d = vec![0.0f32; w * h];
    d.par_chunks_mut(w.max(1)).enumerate().for_each_init(
        || (vec![0.0f32; w], vec![0usize; w], vec![0.0f64; w + 1]),
        |(f, v, z), (y, out)| {
            for x in 0..w {
                f[x] = cols[x * h + y];
            }
            edt_1d(f, out, v, z);
            for o in out.iter_mut() {
                *o = o.sqrt();
            }
        },
    );
    d
}

/// Coverage of a sample at distance d from the marked band for a line
/// `width` samples wide (module docs of [`crate::sobel`]): clamp(W/2 − d,
/// 0, 1) anti-aliased, else 1 where d ≤ W/2 − ½.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cover {
    half: f32,
    antialias: bool,
}

impl Cover {
    pub(crate) fn new(width: f32, antialias: bool) -> Cover {
        Cover {
            half: width * 0.5,
            antialias,
        }
    }

    #[inline]
    pub(crate) fn at(self, d: f32) -> f32 {
        if self.antialias {
            (self.half - d).clamp(0.0, 1.0)
        } else if d <= (self.half - 0.5).max(0.0) {
            1.0
        } else {
            0.0
        }
    }

    /// [`Cover::at`] on 8 lanes, bit for bit (the same comparisons and
    /// the one subtraction; clamp as its two selects).
    #[inline(always)]
    pub(crate) fn at8(self, d: f32x8) -> f32x8 {
        let (zero, one) = (f32x8::ZERO, f32x8::ONE);
        if self.antialias {
            let v = f32x8::splat(self.half) - d;
            let v = v.simd_lt(zero).select(zero, v);
            v.simd_gt(one).select(one, v)
        } else {
            let limit = f32x8::splat((self.half - 0.5).max(0.0));
            d.simd_le(limit).select(one, zero)
        }
    }

    /// Whether only the marked samples themselves get ink: every other
    /// sample is at distance ≥ 1 from a mark, where the coverage (never
    /// increasing with d) is 0 if it is 0 at d = 1. True for lines up to 2
    /// samples wide anti-aliased, under 3 aliased.
    pub(crate) fn marks_only(self) -> bool {
        self.at(1.0) == 0.0
    }

    /// The search radius r = ⌈W/2⌉: a mark farther than r gives no ink.
    pub(crate) fn radius(self) -> usize {
        self.half.ceil().max(0.0) as usize
    }
}

/// Coverage of a line `width` samples wide around the marked band (module
/// docs of [`crate::sobel`]), for the whole image: [`dilate_row`] on every
/// row up to [`BOUNDED_RADIUS`], the distance transform past it.
pub(crate) fn dilate(mask: &[bool], w: usize, h: usize, width: f32, antialias: bool) -> Vec<f32> {
    let cover = Cover::new(width, antialias);
    if cover.radius() > BOUNDED_RADIUS {
        return distance(mask, w, h)
            .into_par_iter()
            .map(|d| cover.at(d))
            .collect();
    }
    let mask = EdgeMask::from_bools(mask, w, h);
    let mut marked = Vec::new();
    mask.rows_marked(&mut marked);
    let mut out = vec![0.0f32; w * h];
    let pool = Pool::default();
    out.par_chunks_mut(w.max(1))
        .enumerate()
        .for_each(|(y, row)| {
            pool.with(|s| dilate_row(&mask, &marked, y, cover, s, |x, c| row[x] = c));
        });
    out
}

/// Widest half line (samples) [`dilate_row`] searches for marks around
/// each sample directly; wider lines use the distance transform.
pub(crate) const BOUNDED_RADIUS: usize = 16;

/// A task's scratch for [`dilate_row`] (kept across rows and frames).
#[derive(Debug, Default)]
pub(crate) struct RowScratch {
    /// within[k]: the row's samples with a mark within k rows (bit mask).
    within: Vec<u64>,
    /// Words with a mark within r columns of one of their samples.
    active: Vec<bool>,
    /// Squared vertical distance to the nearest mark within r rows (or
    /// (r + 1)²), padded by r on both sides.
    sq: Vec<u32>,
}

/// The coverage of row `y`'s samples within r = [`Cover::radius`] ≤
/// [`BOUNDED_RADIUS`] of a mark, as `ink(x, coverage)` calls in increasing
/// x; every other sample has coverage 0 (the caller's fill). `marked` is
/// [`EdgeMask::rows_marked`].
///
/// Only samples within half the width of a mark get ink, so the distance
/// is searched for in the window of radius r around each sample: the
/// vertical distance to the nearest mark in each column of the rows y ± r
/// (the least k whose "within k rows" bit mask has the column), then the
/// least dx² + dy² along the row within ±r. Within the window that is the
/// exact Euclidean distance (in f32 integers, as the transform's), and a
/// mark outside it is farther than r ≥ width/2, where both give no ink:
/// the coverage is the transform's bit for bit (tested). Work is skipped
/// where the mask is empty: rows with no mark within r rows, and 64-sample
/// words with no mark within r columns.
pub(crate) fn dilate_row(
    mask: &EdgeMask,
    marked: &[bool],
    y: usize,
    cover: Cover,
    s: &mut RowScratch,
    mut ink: impl FnMut(usize, f32),
) {
    dilate_row_lanes(mask, marked, y, cover, s, |x, lanes| match lanes {
        Ink::Eight(inked, c) => {
            let (inked, c) = (inked.to_bitmask(), c.to_array());
            for (i, &c) in c.iter().enumerate() {
                if inked >> i & 1 != 0 {
                    ink(x + i, c);
                }
            }
        }
        Ink::One(c) => ink(x, c),
    });
}

/// What [`dilate_row_lanes`] inks at x.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Ink {
    /// Samples x..x+8 (x + 8 ≤ width), at least one with ink: the lane
    /// mask of those with ink, and the coverage of each lane.
    Eight(f32x8, f32x8),
    /// Sample x, with this coverage.
    One(f32),
}

/// [`dilate_row`] 8 samples at a time: `ink(x, Ink::Eight(inked,
/// coverage))` for the samples x..x+8 (x + 8 ≤ width) that hold a sample
/// with ink, whose lanes `inked` are those [`dilate_row`] calls its `ink`
/// for, with the same coverage bit for bit; a word's last n % 8 samples
/// (the row's last word, when width % 8 ≠ 0) one by one, `Ink::One`.
/// Calls in increasing x.
pub(crate) fn dilate_row_lanes(
    mask: &EdgeMask,
    marked: &[bool],
    y: usize,
    cover: Cover,
    s: &mut RowScratch,
    mut ink: impl FnMut(usize, Ink),
) {
    let (w, h, words) = (mask.width(), mask.height(), mask.words());
    let r = cover.radius();
    debug_assert!(r <= BOUNDED_RADIUS);
    if !marked[y.saturating_sub(r)..(y + r + 1).min(h)].contains(&true) {
        return; // no mark within r rows
    }
    // within[k] = within[k − 1] | row y − k | row y + k.
    s.within.clear();
    s.within.extend_from_slice(mask.row(y));
    for k in 1..=r {
        for j in 0..words {
            let mut v = s.within[(k - 1) * words + j];
            if y >= k {
                v |= mask.row(y - k)[j];
            }
            if y + k < h {
                v |= mask.row(y + k)[j];
            }
            s.within.push(v);
        }
    }
    let top = &s.within[r * words..];
    // Word j is active when a mark lies within r columns of its samples:
    // in it, or in the r columns of each neighbour next to it.
    s.active.clear();
    s.active.extend((0..words).map(|j| {
        let left = j > 0 && r > 0 && top[j - 1] >> (64 - r) != 0;
        let right = j + 1 < words && r > 0 && top[j + 1] & ((1u64 << r) - 1) != 0;
        top[j] != 0 || left || right
    }));
    // Past r: "no mark within the window", far = r + 1. The padding of r
    // on each side lets the row search run without bounds.
    let far = r as u32 + 1;
    let far2 = far * far;
    s.sq.resize(w + 2 * r, far2);
    s.sq[..r].fill(far2);
    s.sq[r + w..].fill(far2);
    // The squared column distances of every word an active word reads
    // (itself and its two neighbours); the others are never read.
    for j in 0..words {
        let needed =
            s.active[j] || (j > 0 && s.active[j - 1]) || (j + 1 < words && s.active[j + 1]);
        if !needed {
            continue;
        }
        let x0 = 64 * j;
        let sq = &mut s.sq[r + x0..r + (x0 + 64).min(w)];
        sq.fill(far2);
        // Each column's least k: the bits first reached at k.
        let mut seen = 0u64;
        for k in 0..=r {
            let v = s.within[k * words + j];
            let mut new = v & !seen;
            seen = v;
            let k2 = (k * k) as u32;
            while new != 0 {
                sq[new.trailing_zeros() as usize] = k2;
                new &= new - 1;
            }
        }
    }
    let mut d2 = [0u32; 64];
    for j in (0..words).filter(|&j| s.active[j]) {
        let x0 = 64 * j;
        let n = (w - x0).min(64);
        let d2 = &mut d2[..n];
        // d² = min over the window's columns of dx² + dy²; sq is offset
        // by r, so column x + k − r is sq[x + k].
        for k in 0..=2 * r {
            let dx2 = (k.abs_diff(r) * k.abs_diff(r)) as u32;
            let sq = &s.sq[x0 + k..x0 + k + n];
            if k == 0 {
                for (d, &c) in d2.iter_mut().zip(sq) {
                    *d = dx2 + c;
                }
            } else {
                for (d, &c) in d2.iter_mut().zip(sq) {
                    *d = (*d).min(dx2 + c);
                }
            }
        }
        // d² ≥ (r + 1)² is past half the width: no ink. The squares are
        // integers below 2²⁴, exact in f32.
        let full = n / 8 * 8;
        let far2_8 = f32x8::splat(far2 as f32);
        for (c, d) in d2[..full].chunks_exact(8).enumerate() {
            let d = <[u32; 8]>::try_from(d).unwrap_or_default();
            let d = i32x8::new(d.map(|v| v as i32)).round_float();
            let inked = d.simd_lt(far2_8);
            if inked.any() {
                ink(x0 + 8 * c, Ink::Eight(inked, cover.at8(d.sqrt())));
            }
        }
        for (i, &d) in d2.iter().enumerate().skip(full) {
            if d < far2 {
                ink(x0 + i, Ink::One(cover.at((d as f32).sqrt())));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distance_transform_equals_brute_force() {
        let (w, h) = (37, 23);
        let mask: Vec<bool> = (0..w * h).map(|i| (i * 7919) % 97 == 3).collect();
        let d = distance(&mask, w, h);
        for (i, di) in d.iter().enumerate() {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            let best = (0..w * h)
                .filter(|&j| mask[j])
                .map(|j| {
                    let (a, b) = ((j % w) as f32, (j / w) as f32);
                    ((x - a).powi(2) + (y - b).powi(2)).sqrt()
                })
                .fold(f32::INFINITY, f32::min);
            assert!((di - best).abs() < 1e-4, "{i}: {di} vs {best}");
        }
    }

    #[test]
    fn a_dilated_line_has_the_requested_width() {
        // A vertical step marked on columns 49 and 50: the line of width W
        // is centred on x = 50 (between them) and its ink sums to W per row.
        let (w, h) = (100, 8);
        let mask: Vec<bool> = (0..w * h).map(|i| i % w == 49 || i % w == 50).collect();
        for width in [2.0f32, 3.0, 4.5, 8.0] {
            let c = dilate(&mask, w, h, width, true);
            let ink: f32 = c[3 * w..4 * w].iter().sum();
            assert!((ink - width).abs() < 1e-5, "width {width}: {ink}");
            let hard = dilate(&mask, w, h, width, false);
            let ink: f32 = hard[3 * w..4 * w].iter().sum();
            assert!((ink - width).abs() <= 1.0, "width {width} aliased: {ink}");
        }
    }

    #[test]
    fn bounded_dilation_equals_the_distance_transform_bit_for_bit() {
        let (w, h) = (53, 31);
        for density in [3usize, 17, 101] {
            let mask: Vec<bool> = (0..w * h)
                .map(|i| (i * 7919 + density) % density == 0)
                .collect();
            let d = distance(&mask, w, h);
            for width in [0.5f32, 1.0, 2.0, 3.0, 4.5, 8.0, 13.0, 32.0] {
                for aa in [true, false] {
                    let half = width * 0.5;
                    let want: Vec<f32> = d
                        .iter()
                        .map(|&d| {
                            if aa {
                                (half - d).clamp(0.0, 1.0)
                            } else if d <= (half - 0.5).max(0.0) {
                                1.0
                            } else {
                                0.0
                            }
                        })
                        .collect();
                    let got = dilate(&mask, w, h, width, aa);
                    for i in 0..w * h {
                        assert_eq!(
                            got[i].to_bits(),
                            want[i].to_bits(),
                            "{density} {width} {aa} {i}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_line_of_marks_only_inks_no_other_sample() {
        // An unmarked sample lies √k from the nearest mark, k ≥ 1 an
        // integer: marks_only says that every such sample has coverage 0.
        for i in 0..=24 {
            let width = i as f32 * 0.25;
            for aa in [true, false] {
                let c = Cover::new(width, aa);
                let off = (1..200).all(|k| c.at((k as f32).sqrt()) == 0.0);
                assert_eq!(c.marks_only(), off, "width {width} aa {aa}");
            }
        }
        // The limits its docs name.
        assert!(Cover::new(2.0, true).marks_only() && !Cover::new(2.01, true).marks_only());
        assert!(Cover::new(2.99, false).marks_only() && !Cover::new(3.0, false).marks_only());
    }

    #[test]
    fn dilation_across_mask_words_equals_the_distance_transform() {
        // Rows of several 64-sample words with lone marks just before and
        // after word boundaries (and at the ends), so that ink reaches into
        // words holding no mark of their own, and rows with none.
        let (w, h) = (197, 29);
        let cols = [0usize, 3, 62, 63, 64, 66, 127, 128, 150, 191, 192, 196];
        let widths = [0.5f32, 1.0, 2.0, 3.0, 4.5, 8.0, 13.0, 32.0];
        // One mark every other row, alone in its row; and sparse noise,
        // whose rows leave the scratch of a task holding distances that
        // the next row must not read.
        let lone = |k: usize, i: usize| {
            let (x, y) = (i % w, i / w);
            y % 2 == k % 2 && x == cols[(y / 2 + k) % cols.len()]
        };
        let noise = |k: usize, i: usize| (i * 7919 + k * 31).is_multiple_of(60 + 40 * (k % 3));
        let cases = widths
            .iter()
            .enumerate()
            .flat_map(|(k, &width)| [(k, width, false), (k, width, true)]);
        for (k, width, noisy) in cases {
            let mask: Vec<bool> = (0..w * h)
                .map(|i| if noisy { noise(k, i) } else { lone(k, i) })
                .collect();
            assert!(mask.contains(&true));
            let d = distance(&mask, w, h);
            for aa in [true, false] {
                let want: Vec<u32> = d
                    .iter()
                    .map(|&d| Cover::new(width, aa).at(d).to_bits())
                    .collect();
                let got: Vec<u32> = dilate(&mask, w, h, width, aa)
                    .iter()
                    .map(|v| v.to_bits())
                    .collect();
                assert!(got == want, "width {width} aa {aa}");
                // Row by row with one scratch, the rows out of order: each
                // row must not read what another left in it.
                let bits = EdgeMask::from_bools(&mask, w, h);
                let mut marked = Vec::new();
                bits.rows_marked(&mut marked);
                let mut s = RowScratch::default();
                for y in (0..h).map(|k| (k * 11 + 5) % h) {
                    let mut row = vec![0.0f32; w];
                    dilate_row(&bits, &marked, y, Cover::new(width, aa), &mut s, |x, c| {
                        row[x] = c
                    });
                    let row: Vec<u32> = row.iter().map(|v| v.to_bits()).collect();
                    assert!(
                        row == want[y * w..(y + 1) * w],
                        "width {width} aa {aa} row {y}"
                    );
                }
            }
        }
    }
}
