//! Outline by image: edges in the frame buffers (`detect_edges`), widened
//! to the line width by a Euclidean distance transform (`dilate`), and
//! blended over the image (as [`crate::outline::composite`] does).
//!
//! Each source has its own measure and threshold; a sample is on an edge
//! when any source's measure exceeds its threshold. With the Sobel weights
//! w = (1, 2, 1)/4 across the derivative's direction:
//! - **depth**: the Sobel-smoothed *second* difference of q = 1/w (0 where
//!   nothing is hit), divided by the largest q of the 3×3 neighbourhood:
//!   max(|Σ w_k (q(x+1) + q(x−1) − 2q(x))|, the same along y) / q_max.
//!   1/w is affine in screen space across any plane, so a flat floor
//!   however slanted gives 0 (the first derivative, plain Sobel, is
//!   constant and non-zero there and would draw it); a step from depth w₁
//!   to w₂ > w₁ gives 1 − w₁/w₂ on both sides of the step.
//! - **normal**: Sobel gradient of the three normal components,
//!   √(Σ Gx² + Gy²); two faces at angle θ give 2 sin(θ/2) along their
//!   edge (0.25 ≈ 14°), a surface against the background 1.
//! - **id**: material edges. Ids are labels, whose gradient means nothing:
//!   the measure is the Sobel-weighted fraction (corner 1, side 2, of 12)
//!   of the eight neighbours showing another material (or nothing): 1/3
//!   along a straight boundary.
//! - **color**: Sobel gradient magnitude of the luminance of the linear
//!   colour clamped to [0, 1]; a step of Δ gives Δ.
//!
//! A step marks the samples on both sides, a band two samples wide whose
//! middle is the step. The line of width W (output pixels × ssaa samples)
//! covers the samples within W/2 of that middle: coverage
//! clamp(W/2 − d, 0, 1) with d the distance to the nearest marked sample
//! (anti-aliased), or 1 where d ≤ W/2 − ½ (aliased). Every stage works on
//! rows or columns in parallel, each written by one task, so the result
//! does not depend on the thread count.
//!
//! The stage allocates nothing in a steady frame (a 1080p frame's
//! whole-frame buffers were 26 MB, each page of them a kernel page fault):
//! - 1/w, the material labels and the luminance are computed per band of
//!   [`BAND_ROWS`] rows (and the row above and below it) inside the
//!   detection, not as whole-frame buffers;
//! - the marks are bits ([`EdgeMask`]), kept in the stage with the other
//!   scratch ([`Scratch`]) from frame to frame;
//! - the line is widened row by row ([`dilate_row`]) straight into the
//!   blend, and only near marks: rows with no mark within the line's
//!   reach and 64-sample words with none are skipped, so there is no
//!   frame-size coverage map either; a line at most 2 samples wide inks
//!   only the marks ([`Cover::marks_only`]) and skips the dilation.
//!
//! Memory bounds it as much as arithmetic (a 1080p frame's depth, normals
//! and ids are ~41 MB; perf annotate put most of the time on the first
//! read of each row and on the blend's reads of the image), so the
//! detection reads each field row once: every source's measure 8 samples
//! at a time in one pass ([`detect_block`]), the frame's normals
//! prefetched two rows ahead; and the blend prefetches the image lines
//! near the marks two rows ahead. A block of 64
//! samples first drops every source whose measure a bound over the
//! block's values keeps under its threshold ([`block_sources`]): flat
//! ground and the insides of large faces are not measured.

use crate::outline::{blend, blend_row, composite, ssaa_of, sum_samples, Selection};
use rayon::prelude::*;
use specula_core::{Mask, Real};
use specula_raster::post::{HdrImage, PostStage};
use specula_raster::target::MISS;
use specula_raster::{BufferSet, FrameBuffers, Planes3};
use wide::{f32x8, i32x8, u32x8};

pub use crate::dilate::{
    dilate, dilate_row, dilate_row_lanes, distance, Cover, EdgeMask, Ink, Pool, RowScratch,
    BOUNDED_RADIUS,
};

/// What a Sobel outline looks at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    Depth,
    Normal,
    Id,
    Color,
}

/// The post stage.
#[derive(Clone, Debug)]
pub struct Sobel {
    /// Each source with its threshold.
    pub sources: Vec<(Source, f32)>,
    /// Line width in output pixels.
    pub width: f32,
    pub color: [f32; 3],
    pub antialias: bool,
    /// Material of each visibility-buffer id (for the id source).
    pub id_material: Vec<u32>,
    pub selection: Selection,
    /// Buffers kept from frame to frame (`Scratch::default()`).
    pub scratch: Scratch,
}

/// The buffers a [`Sobel`] stage keeps from frame to frame, so that a
/// steady frame neither allocates nor touches fresh pages. None carries a
/// value from one frame to the next: each is written before it is read,
/// so the output is that of fresh buffers. A clone starts empty.
#[derive(Default)]
pub struct Scratch(Buffers);

#[derive(Default)]
struct Buffers {
    mask: EdgeMask,
    marked: Vec<bool>,
    /// The id source's label of each id ([`material_labels`]).
    label_of_id: Vec<f32>,
    bands: Pool<BandScratch>,
    rows: Pool<RowsScratch>,
}

impl Clone for Scratch {
    fn clone(&self) -> Scratch {
        Scratch::default()
    }
}

impl std::fmt::Debug for Scratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Scratch")
    }
}

/// A detection task's per-band inputs (rows of the band and its halo).
#[derive(Default)]
struct BandScratch {
    inv_depth: Vec<f32>,
    material: Vec<f32>,
    luma: Vec<f32>,
}

/// A blend task's scratch: the dilation's, and at ssaa > 1 the coverage
/// of a pixel row's sample rows and their sums.
#[derive(Default)]
struct RowsScratch {
    dilate: RowScratch,
    coverage: Vec<f32>,
    acc: Vec<f32>,
}

/// Rows a detection task reads its inputs for at once: 1/w, labels and
/// luminance of BAND_ROWS + 2 rows (with the halo rows above and below,
/// read and recomputed by both neighbouring bands: 2/32 more of that
/// work) stay in the core's cache (250 KB each at 1920 wide) while the
/// band's three-row windows read them; 34 tasks at 1080p.
pub const BAND_ROWS: usize = 32;

/// Read-only views of the buffers a detection reads, at frame size (or a
/// band's rows of them: the detection only reads the rows it is given).
pub struct EdgeInput<'a> {
    pub width: usize,
    pub height: usize,
    /// 1/w of the view depth w, 0 where nothing is hit ([`inverse_depth`];
    /// empty if depth is not a source).
    pub inv_depth: &'a [f32],
    pub normal: [&'a [f32]; 3],
    /// Material index per sample as a number (exact: indices are below
    /// 2²⁴), −1 where nothing is hit ([`material_labels`]).
    pub material: &'a [f32],
    /// Luminance per sample.
    pub luma: &'a [f32],
}

const W: [f32; 3] = [0.25, 0.5, 0.25];

/// q = 1/w per sample, 0 where nothing is hit (w infinite, NaN or ≤ 0).
pub fn inverse_depth(depth: &[f32]) -> Vec<f32> {
    let mut q = vec![0.0f32; depth.len()];
    q.par_chunks_mut(4096)
        .zip(depth.par_chunks(4096))
        .for_each(|(q, d)| inverse_depth_into(d, q));
    q
}

/// [`inverse_depth`] into `q` (same length).
pub fn inverse_depth_into(depth: &[f32], q: &mut [f32]) {
    // A plain loop (a select per sample) vectorizes.
    for (q, &d) in q.iter_mut().zip(depth) {
        *q = if d.is_finite() && d > 0.0 {
            1.0 / d
        } else {
            0.0
        };
    }
}

/// The id source's labels: the material index of each sample's id as a
/// number (exact below 2²⁴ materials), −1 where nothing is hit or the id
/// has no material.
pub fn material_labels(ids: &[u32], id_material: &[u32]) -> Vec<f32> {
    let mut of_id = Vec::new();
    label_of_id(id_material, &mut of_id);
    let mut labels = vec![-1.0f32; ids.len()];
    labels
        .par_chunks_mut(4096)
        .zip(ids.par_chunks(4096))
        .for_each(|(labels, ids)| labels_into(ids, &of_id, labels));
    labels
}

/// The label of each id once (ids are far fewer than samples), into `out`,
/// then −1 once more: the label of every id past the table (MISS, u32::MAX,
/// among them).
fn label_of_id(id_material: &[u32], out: &mut Vec<f32>) {
    out.clear();
    // In parallel: ~200k ids a benchmark frame, before any band starts.
    out.par_extend(id_material.par_iter().enumerate().map(|(id, &m)| {
        if id as u32 != MISS && m != u32::MAX {
            m as f32
        } else {
            -1.0
        }
    }));
    out.push(-1.0);
}

/// [`material_labels`] with the per-id labels `of_id` ([`label_of_id`]),
/// into `labels`: a table read a sample, ids past the table clamped to
/// its last entry (−1), so the loop has no branch and no bounds check.
fn labels_into(ids: &[u32], of_id: &[f32], labels: &mut [f32]) {
    let last = of_id.len() - 1;
    let table = &of_id[..=last];
    let mut done = 0;
    // 8 at a time by the hardware gather ([`Real::gather`], whose f32
    // index lanes are exact below 2²⁴ ids): ~10 instructions a sample
    // scalar, the largest part of the stage's preparation.
    if last < 1 << 24 {
        let last8 = u32x8::splat(last as u32);
        for (l, i) in labels.chunks_exact_mut(8).zip(ids.chunks_exact(8)) {
            let i = u32x8::new(<[u32; 8]>::try_from(i).unwrap_or_default()).min(last8);
            // Eight samples of one triangle (most chunks: the ground,
            // sphere interiors) read the table once; a gather costs
            // ~3.6 ns on the benchmark machine.
            let first = i.to_array()[0];
            if i.simd_eq(u32x8::splat(first)).all() {
                f32x8::splat(table[first as usize]).store(l);
            } else {
                let index = i32x8::new(i.to_array().map(|v| v as i32)).round_float();
                <f32x8 as Real>::gather(table, index).store(l);
            }
            done += 8;
        }
    }
    for (l, &id) in labels[done..].iter_mut().zip(&ids[done..]) {
        *l = table[(id as usize).min(last)];
    }
}

/// The colour source's luminance of samples `range` of `color` into `out`:
/// each channel clamped to [0, 1] (NaN to 0), Rec. 709 weights.
fn luma_into(color: &Planes3, range: std::ops::Range<usize>, out: &mut [f32]) {
    let clamp = |v: f32| if v > 0.0 { v.min(1.0) } else { 0.0 };
    let (r, g, b) = (
        &color.r[range.clone()],
        &color.g[range.clone()],
        &color.b[range],
    );
    for (((o, &r), &g), &b) in out.iter_mut().zip(r).zip(g).zip(b) {
        *o = 0.2126 * clamp(r) + 0.7152 * clamp(g) + 0.0722 * clamp(b);
    }
}

/// Marks edge samples (1) in a `width × height` mask; see the module docs.
/// `keep(i)` says whether sample i may carry a line (material selection).
/// [`detect_row`] on every row of the whole-frame `input`.
pub fn detect_edges(
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
/// source at once ([`detect_lanes`]); its first and last sample (and every
/// sample of a row under [`FUSED_MIN_WIDTH`]) through the clamped scalar
/// [`measure_at`] ([`mark_clamped`]).
pub fn detect_row(
    input: &EdgeInput,
    sources: &[(Source, f32)],
    rows: [usize; 3],
    keep: &dyn Fn(usize) -> bool,
    out: &mut [u64],
) {
    detect_row_ahead(input, sources, rows, None, keep, out);
}

/// [`detect_row`], prefetching the normals of the row starting at
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
/// neighbours) are measured sample by sample ([`mark_clamped`]).
const FUSED_MIN_WIDTH: usize = 10;

/// Marks sample x of a row (`rows` as in [`detect_row`]) if any source's
/// clamped scalar [`measure_at`] exceeds its threshold.
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

/// Each source's threshold for [`detect_lanes`], `None` when it is not a
/// source. A source listed twice marks where its measure exceeds either
/// threshold, i.e. the lesser (a NaN threshold marks nothing: dropped).
#[derive(Clone, Copy)]
struct Thresholds {
    depth: Option<f32x8>,
    normal: Option<f32x8>,
    id: Option<f32x8>,
    color: Option<f32x8>,
}

impl Thresholds {
    fn new(sources: &[(Source, f32)]) -> Thresholds {
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
fn below_sqrt(t: f32) -> f32 {
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
enum Field {
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

/// Samples [`detect_block`] takes at once.
const BLOCK: usize = 64;

/// [`detect_lanes`] on the 64 samples x..x+64 of a row (bit i: sample
/// x + i; 1 ≤ x, x + 65 ≤ width). Each field row's 66 values are sliced
/// once, and the eight chunks read them at constant offsets: no bounds
/// checks inside (the chunk-by-chunk slicing was ~40 % of the detection's
/// instructions).
#[inline(never)]
fn detect_block(
    f: &[&[f32]; 6],
    used: [bool; 6],
    t: &Thresholds,
    rows: [usize; 3],
    x: usize,
) -> u64 {
    const UNUSED: [f32; BLOCK + 2] = [0.0; BLOCK + 2];
    let row = |k: usize, r: usize| -> &[f32; BLOCK + 2] {
        if used[k] {
            <&[f32; BLOCK + 2]>::try_from(&f[k][rows[r] + x - 1..rows[r] + x + BLOCK + 1])
                .unwrap_or(&UNUSED)
        } else {
            &UNUSED
        }
    };
    // Written out: an array `map` here was left as a call (~8 M
    // instructions a frame).
    let rows3 = |k: usize| [row(k, 0), row(k, 1), row(k, 2)];
    let a = [rows3(0), rows3(1), rows3(2), rows3(3), rows3(4), rows3(5)];
    let Some(t) = block_sources(t, &a) else {
        return 0;
    };
    let t = &t;
    let mut bits = 0u64;
    for i in 0..BLOCK / 8 {
        let o = 8 * i;
        let at = |f: Field| {
            let a = &a[f as usize];
            let load = |r: usize, c: usize| {
                f32x8::from(<[f32; 8]>::try_from(&a[r][o + c..o + c + 8]).unwrap_or_default())
            };
            [
                [load(0, 0), load(0, 1), load(0, 2)],
                [load(1, 0), load(1, 1), load(1, 2)],
                [load(2, 0), load(2, 1), load(2, 2)],
            ]
        };
        bits |= u64::from(detect_lanes(t, at)) << o;
    }
    bits
}

/// A block's three rows of one field ([`detect_block`]).
type BlockRows<'a> = [&'a [f32; BLOCK + 2]; 3];

/// The sources of `t` that may mark a sample of a block whose field rows
/// are `a` (`None`: none may, the block has no mark). A source is dropped
/// where a bound over the whole block shows that its measure, as
/// [`detect_lanes`] rounds it, cannot exceed its threshold at any sample:
/// a flat floor, the inside of a large face. The sources are tested in the
/// order id, normal, depth, colour (cheapest and most often failing
/// first), up to the first that may mark: the rest are kept untested.
#[inline(always)]
fn block_sources(t: &Thresholds, a: &[BlockRows; 6]) -> Option<Thresholds> {
    let lane0 = |v: f32x8| v.as_array()[0];
    let mut out = *t;
    'tests: {
        if let Some(ti) = t.id {
            if !(one_label(&a[Field::Label as usize]) && lane0(ti) >= 0.0) {
                break 'tests;
            }
            out.id = None; // every measure is 0, not above ti ≥ 0
        }
        if let Some(tn) = t.normal {
            let mut g2 = 0.0f32;
            for f in [Field::NormalX, Field::NormalY, Field::NormalZ] {
                let b = gradient_bound(&a[f as usize]);
                g2 += b * b + b * b; // detect_lanes' sum: increasing in each term
                let under = g2 <= lane0(tn); // false for a NaN bound
                if !under {
                    break 'tests;
                }
            }
            out.normal = None;
        }
        if let Some(td) = t.depth {
            let under = depth_bound(&a[Field::InvDepth as usize]) <= lane0(td);
            if !under {
                break 'tests;
            }
            out.depth = None;
        }
        if let Some(tc) = t.color {
            let b = gradient_bound(&a[Field::Luma as usize]);
            let under = b * b + b * b <= lane0(tc);
            if !under {
                break 'tests;
            }
            out.color = None;
        }
    }
    let any = out.depth.is_some() || out.normal.is_some() || out.id.is_some();
    (any || out.color.is_some()).then_some(out)
}

/// Offsets of the 8-value loads that cover a block row's BLOCK + 2 values.
const COVER8: [usize; BLOCK / 8 + 1] = {
    let mut o = [BLOCK + 2 - 8; BLOCK / 8 + 1];
    let mut k = 0;
    while k < BLOCK / 8 {
        o[k] = 8 * k;
        k += 1;
    }
    o
};

/// The least and greatest value of a block's rows, NaNs left out (+∞, −∞
/// if every value is NaN). [`Real::min`] and `max` give their second
/// operand when the first is NaN, and the running extremes never are.
#[inline(always)]
fn block_range(rows: &BlockRows) -> (f32, f32) {
    let mut lo = f32x8::splat(f32::INFINITY);
    let mut hi = f32x8::splat(f32::NEG_INFINITY);
    for row in rows {
        for o in COVER8 {
            let v = load8(&row[o..o + 8]);
            lo = Real::min(v, lo);
            hi = Real::max(v, hi);
        }
    }
    let lo = lo
        .as_array()
        .iter()
        .fold(f32::INFINITY, |m, &v| Real::min(v, m));
    let hi = hi
        .as_array()
        .iter()
        .fold(f32::NEG_INFINITY, |m, &v| Real::max(v, m));
    (lo, hi)
}

/// Whether every label of a block's rows is the first (a NaN label is
/// unequal to all, as in [`detect_lanes`]' unordered ≠).
#[inline(always)]
fn one_label(rows: &BlockRows) -> bool {
    let first = f32x8::splat(rows[0][0]);
    let mut differ = f32x8::ZERO;
    for row in rows {
        for o in COVER8 {
            let v = load8(&row[o..o + 8]);
            differ |= v.simd_ne(first);
        }
    }
    !differ.any()
}

/// An upper bound of |Gx| and |Gy| ([`gradient8`]) at every sample of a
/// block, as rounded in f32 (NaN or +∞ when none can be given): with the
/// values in [lo, hi] each difference is at most D = hi − lo in magnitude
/// (rounding is monotone), so each Sobel sum is at most its sum with D in
/// every difference, rounded in the same order. NaN values are left out:
/// a difference with one is NaN, and a NaN g² is above no threshold.
#[inline(always)]
fn gradient_bound(rows: &BlockRows) -> f32 {
    let (lo, hi) = block_range(rows);
    let d = hi - lo; // −∞ if every value is NaN: its square +∞ tests false
    W[0] * d + W[1] * d + W[2] * d
}

/// An upper bound of the depth measure ([`detect_lanes`]) at every sample
/// of a block, as rounded in f32 (NaN or +∞ when none can be given).
/// With q in [lo, hi] each second difference q₊ + q₋ − 2q is at most
/// E = 2hi − 2lo in magnitude, so |dxx| and |dyy| are at most their sums
/// with E (rounding is monotone), and a sample's q_max is ≥ lo: the
/// measure is ≤ that bound / lo when lo > 0, and 0 (q_max ≤ 0) when
/// hi ≤ 0. NaN values are left out as in [`gradient_bound`]: a q_max is
/// NaN (no mark) or one of the others, ≥ lo.
#[inline(always)]
fn depth_bound(rows: &BlockRows) -> f32 {
    let (lo, hi) = block_range(rows);
    if hi <= 0.0 {
        return 0.0;
    }
    let e = (hi + hi) - 2.0 * lo;
    let b = W[0] * e + W[1] * e + W[2] * e;
    if lo > 0.0 {
        b / lo
    } else {
        f32::NAN
    }
}

/// `s` (8 values) as one vector load (zeros if `s` is not 8 long).
#[inline(always)]
fn load8(s: &[f32]) -> f32x8 {
    f32x8::from(<[f32; 8]>::try_from(s).unwrap_or_default())
}

/// The 3×3 neighbourhoods of field `f` at the 8 samples x..x+8 of a row
/// (`rows` as in [`detect_row`]; 1 ≤ x, x + 9 ≤ width): `[r][c]` holds
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

/// Sobel gradient (Gx, Gy) over a neighbourhood, [`gradient`]'s sums in
/// its order but for its leading 0 + (see [`detect_lanes`]): for squaring.
#[inline(always)]
fn gradient8(n: &[[f32x8; 3]; 3]) -> (f32x8, f32x8) {
    let w = W.map(f32x8::splat);
    let gx = w[0] * (n[0][2] - n[0][0]) + w[1] * (n[1][2] - n[1][0]) + w[2] * (n[2][2] - n[2][0]);
    let gy = w[0] * (n[2][0] - n[0][0]) + w[1] * (n[2][1] - n[0][1]) + w[2] * (n[2][2] - n[0][2]);
    (gx, gy)
}

/// Whether the 8 samples x..x+8 of a row (bit i: sample x + i) exceed any
/// source's threshold: every source's measure at once, each [`measure_at`]'s
/// operations in its order (no FMA) but for the leading 0 + of its sums
/// (0 + p is p but for a zero's sign, which the squares and |·| drop),
/// so the same values bit for bit
/// (tested), from one read of the neighbourhood of each field.
#[inline(always)]
fn detect_lanes(t: &Thresholds, around: impl Fn(Field) -> [[f32x8; 3]; 3]) -> u32 {
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

/// The lane form of [`measure`] (the tests check the two agree): the
/// measure of source `s` at the `R::LANES` samples (x.., y) whose
/// neighbourhood rows start at `rows` (above, at, below; clamped by the
/// caller), for 1 ≤ x and x + LANES < width (no clamping along x). The
/// same operations in the same order as [`measure_at`].
#[cfg(test)]
#[inline(always)]
fn measure_lanes<R: Real>(input: &EdgeInput, s: Source, rows: [usize; 3], x: usize) -> R {
    // The 3×3 neighbourhood of f, [row][column offset + 1] (row 0 above,
    // 2 below): one slice of LANES + 2 per row, each of the nine loads
    // once, so the bounds checks are three per field.
    let around = |f: &[f32]| {
        let mut n = [[R::ZERO; 3]; 3];
        for (r, nr) in n.iter_mut().enumerate() {
            let s = &f[rows[r] + x - 1..rows[r] + x + 1 + R::LANES];
            for (c, v) in nr.iter_mut().enumerate() {
                *v = R::load(&s[c..]);
            }
        }
        n
    };
    let wk = W.map(|v| R::splat(v as f64));
    let gradient = |f: &[f32]| {
        let n = around(f);
        let at = |r: usize, c: usize| n[r][c];
        let (mut gx, mut gy) = (R::ZERO, R::ZERO);
        for (k, &w) in wk.iter().enumerate() {
            gx += w * (at(k, 2) - at(k, 0));
            gy += w * (at(2, k) - at(0, k));
        }
        (gx, gy)
    };
    match s {
        Source::Depth => {
            let n = around(input.inv_depth);
            let at = |r: usize, c: usize| n[r][c];
            let two = R::splat(2.0);
            let (mut dxx, mut dyy, mut qmax) = (R::ZERO, R::ZERO, R::ZERO);
            for (k, &w) in wk.iter().enumerate() {
                dxx += w * (at(k, 2) + at(k, 0) - two * at(k, 1));
                dyy += w * (at(2, k) + at(0, k) - two * at(1, k));
                qmax = qmax.max(at(k, 0)).max(at(k, 1)).max(at(k, 2));
            }
            // Lanes with q_max = 0 divide 0 by 0; the select drops them.
            R::select(qmax.gt(R::ZERO), dxx.abs().max(dyy.abs()) / qmax, R::ZERO)
        }
        Source::Normal => {
            let mut g2 = R::ZERO;
            for c in input.normal {
                let (gx, gy) = gradient(c);
                g2 += gx * gx + gy * gy;
            }
            g2.sqrt()
        }
        Source::Id => {
            let n = around(input.material);
            let m = n[1][1];
            let mut f = R::ZERO;
            for (r, nr) in n.iter().enumerate() {
                for (c, &o) in nr.iter().enumerate() {
                    let weight = R::splat(if r == 1 || c == 1 { 2.0 } else { 1.0 });
                    f += R::select(o.lt(m) | o.gt(m), weight, R::ZERO);
                }
            }
            f / R::splat(12.0)
        }
        Source::Color => {
            let (gx, gy) = gradient(input.luma);
            (gx * gx + gy * gy).sqrt()
        }
    }
}

/// Sample indices of the 3×3 neighbourhood of (x, y), `[dy + 1][dx + 1]`,
/// clamped to the image.
#[inline]
fn neighbours(input: &EdgeInput, x: usize, y: usize) -> [[usize; 3]; 3] {
    let w = input.width;
    let xs = [x.saturating_sub(1), x, (x + 1).min(w - 1)];
    let ys = [y.saturating_sub(1), y, (y + 1).min(input.height - 1)];
    ys.map(|yy| xs.map(|xx| yy * w + xx))
}

/// Sobel gradient (Gx, Gy) of `f` over the neighbourhood `nb`, weights
/// (1, 2, 1)/4 across: a step of Δ gives Δ.
#[inline]
fn gradient(f: &[f32], nb: &[[usize; 3]; 3]) -> (f32, f32) {
    let (mut gx, mut gy) = (0.0, 0.0);
    for (k, wk) in W.iter().enumerate() {
        gx += wk * (f[nb[k][2]] - f[nb[k][0]]);
        gy += wk * (f[nb[2][k]] - f[nb[0][k]]);
    }
    (gx, gy)
}

/// The measure of one source at (x, y); see the module docs. The scalar
/// reference of the detection's row kernels (and of the lane form the
/// tests keep).
pub fn measure(input: &EdgeInput, s: Source, x: usize, y: usize) -> f32 {
    measure_at(input, s, &neighbours(input, x, y))
}

#[inline]
fn measure_at(input: &EdgeInput, s: Source, nb: &[[usize; 3]; 3]) -> f32 {
    match s {
        Source::Depth => {
            let q = input.inv_depth;
            let (mut dxx, mut dyy, mut qmax) = (0.0f32, 0.0f32, 0.0f32);
            for (k, wk) in W.iter().enumerate() {
                dxx += wk * (q[nb[k][2]] + q[nb[k][0]] - 2.0 * q[nb[k][1]]);
                dyy += wk * (q[nb[2][k]] + q[nb[0][k]] - 2.0 * q[nb[1][k]]);
                // Real::max (a NaN self gives the other), as the lanes.
                qmax = Real::max(
                    Real::max(Real::max(qmax, q[nb[k][0]]), q[nb[k][1]]),
                    q[nb[k][2]],
                );
            }
            if qmax > 0.0 {
                Real::max(dxx.abs(), dyy.abs()) / qmax
            } else {
                0.0
            }
        }
        Source::Normal => {
            let mut g2 = 0.0;
            for c in input.normal {
                let (gx, gy) = gradient(c, nb);
                g2 += gx * gx + gy * gy;
            }
            g2.sqrt()
        }
        Source::Id => {
            let mat = input.material;
            let m = mat[nb[1][1]];
            let mut f = 0.0;
            for (r, row) in nb.iter().enumerate() {
                for (c, &i) in row.iter().enumerate() {
                    // Sides weigh 2, corners 1 (the centre never differs).
                    let weight = if r == 1 || c == 1 { 2.0 } else { 1.0 };
                    if mat[i] != m {
                        f += weight;
                    }
                }
            }
            f / 12.0
        }
        Source::Color => {
            let (gx, gy) = gradient(input.luma, nb);
            (gx * gx + gy * gy).sqrt()
        }
    }
}

impl Sobel {
    fn has(&self, s: Source) -> bool {
        self.sources.iter().any(|(t, _)| *t == s)
    }

    /// Marks the frame's edge samples into `mask`: [`detect_row`] on
    /// bands of [`BAND_ROWS`] rows, each band computing its own 1/w,
    /// labels and luminance (rows of the band and one each side).
    fn detect(&self, frame: &FrameBuffers, b: &mut Buffers) {
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

    /// Per-sample coverage over `frame` for a stage at supersampling `ssaa`
    /// (in buffers of its own: the stage's scratch is its instance's).
    pub fn coverage_map(&self, frame: &FrameBuffers, ssaa: usize) -> Vec<f32> {
        let mut b = Buffers::default();
        self.detect(frame, &mut b);
        let cover = Cover::new(self.width * ssaa as f32, self.antialias);
        let (w, h) = (frame.width as usize, frame.height as usize);
        if cover.radius() > BOUNDED_RADIUS {
            return dilate(
                &b.mask.to_bools(),
                w,
                h,
                self.width * ssaa as f32,
                self.antialias,
            );
        }
        let mut out = vec![0.0f32; w * h];
        let (mask, marked, pool) = (&b.mask, &b.marked, &b.rows);
        out.par_chunks_mut(w.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                pool.with(|s| dilate_row(mask, marked, y, cover, &mut s.dilate, |x, c| row[x] = c));
            });
        out
    }
}

/// A hint that the cache line of `v[i]` will be read soon (nothing past
/// `v`'s end). No effect on results.
#[inline(always)]
fn prefetch(v: &[f32], i: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(p) = v.get(i) {
        // SAFETY: a prefetch is a hint that never faults; the address is
        // an element of `v`.
        unsafe {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            _mm_prefetch::<_MM_HINT_T0>(p as *const f32 as *const i8);
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (v, i);
}

/// Prefetches the cache lines of row `y` of the image planes `rgb` (at
/// the mask's size) that the line can ink: 16-sample lines with a mark
/// within `reach` rows and (inside its 64-sample word) `reach` columns.
/// A hint only: ink reaching across a word's edge is not looked for.
fn prefetch_inked(mask: &EdgeMask, marked: &[bool], y: usize, reach: usize, rgb: [&[f32]; 3]) {
    let h = mask.height();
    let near = y.saturating_sub(reach)..(y + reach + 1).min(h);
    if !marked[near.clone()].contains(&true) {
        return;
    }
    for j in 0..mask.words() {
        let v = near
            .clone()
            .filter(|&yy| marked[yy])
            .fold(0u64, |v, yy| v | mask.row(yy)[j]);
        if v == 0 {
            continue;
        }
        for k in 0..4usize {
            let lo = (16 * k).saturating_sub(reach);
            let hi = (16 * k + 15 + reach).min(63);
            let span = (u64::MAX >> (63 - hi)) & (u64::MAX << lo);
            if v & span != 0 {
                // Both ends of the 16 samples: the planes need not start
                // on a cache line (a large Vec's does not: it is 16 bytes
                // past a page), and then the 16 straddle two lines.
                for p in rgb {
                    prefetch(p, 64 * j + 16 * k);
                    prefetch(p, 64 * j + 16 * k + 15);
                }
            }
        }
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

/// Output rows a blend task takes at once.
const BLEND_ROWS: usize = 8;

impl PostStage for Sobel {
    fn name(&self) -> &str {
        "outline-sobel"
    }

    fn buffers(&self) -> BufferSet {
        BufferSet {
            depth: self.has(Source::Depth),
            normal: self.has(Source::Normal),
            id: self.has(Source::Id) || self.selection.needs_ids(),
        }
    }

    /// Detection, then the dilation row by row straight into the blend.
    /// The blend is [`composite`]'s: the same coverage per sample, summed
    /// in the same order, the same products. It is skipped where the
    /// coverage is 0 (no mark within the line's reach), where composite's
    /// c·(1 − 0) + colour·0 gives back c: the same value, and the same
    /// bits except that −0 would become +0 (the tone map, before this
    /// stage, writes no −0; and either encodes to code 0).
    fn instance(&self) -> Box<dyn PostStage> {
        Box::new(self.clone())
    }

    fn apply(&mut self, img: &mut HdrImage, frame: &FrameBuffers) {
        let ssaa = ssaa_of(img, frame);
        // Taken out for the call (so `self` stays readable), put back at
        // the end.
        let mut scratch = std::mem::take(&mut self.scratch);
        self.blend(img, frame, ssaa, &mut scratch.0);
        self.scratch = scratch;
    }
}

impl Sobel {
    /// [`PostStage::apply`] with the stage's buffers `b`.
    fn blend(&self, img: &mut HdrImage, frame: &FrameBuffers, ssaa: usize, b: &mut Buffers) {
        self.detect(frame, b);
        let cover = Cover::new(self.width * ssaa as f32, self.antialias);
        if cover.radius() > BOUNDED_RADIUS {
            let (w, h) = (frame.width as usize, frame.height as usize);
            let cov = dilate(
                &b.mask.to_bools(),
                w,
                h,
                self.width * ssaa as f32,
                self.antialias,
            );
            composite(img, frame, &cov, self.color);
            return;
        }
        let (w, sw) = (img.width as usize, frame.width as usize);
        let inv = 1.0 / (ssaa * ssaa) as f32;
        let color = self.color;
        let (mask, marked, pool) = (&b.mask, &b.marked, &b.rows);
        // A line at most 2 samples wide (anti-aliased; 3 aliased) inks
        // only the marks: every other sample is at least 1 from one.
        let marks_only = cover.marks_only();
        let on_mark = cover.at(0.0) * inv;
        let band = (w * BLEND_ROWS).max(1);
        let p = &mut img.rgb;
        p.r.par_chunks_mut(band)
            .zip(p.g.par_chunks_mut(band))
            .zip(p.b.par_chunks_mut(band))
            .enumerate()
            .for_each(|(k, ((r, g), b))| {
                pool.with(|s| {
                    let n = r.len() / w.max(1);
                    if ssaa == 1 {
                        // The image lines the blend will read, two rows
                        // ahead (the band's first two rows at its start):
                        // they are far apart and come from memory.
                        let reach = if marks_only { 0 } else { cover.radius() };
                        let ahead = |r: &[f32], g: &[f32], b: &[f32], i: usize| {
                            if i < n {
                                let planes = [r, g, b].map(|p| &p[i * w..(i + 1) * w]);
                                prefetch_inked(mask, marked, k * BLEND_ROWS + i, reach, planes);
                            }
                        };
                        ahead(r, g, b, 0);
                        ahead(r, g, b, 1);
                        for i in 0..n {
                            ahead(r, g, b, i + 2);
                            let y = k * BLEND_ROWS + i;
                            let row = i * w..(i + 1) * w;
                            let (r, g, b) = (&mut r[row.clone()], &mut g[row.clone()], &mut b[row]);
                            if marks_only {
                                // The ink of the marks alone: blend's
                                // products on each, as below at d = 0.
                                let words = if marked[y] { mask.row(y) } else { &[] };
                                for (j, &word) in words.iter().enumerate() {
                                    let mut set = word;
                                    while set != 0 {
                                        let x = 64 * j + set.trailing_zeros() as usize;
                                        blend([&mut r[x], &mut g[x], &mut b[x]], on_mark, color);
                                        set &= set - 1;
                                    }
                                }
                                continue;
                            }
                            // blend's products 8 samples at a time, the
                            // samples without ink selected back unchanged.
                            let (inv8, col8) = (f32x8::splat(inv), color.map(f32x8::splat));
                            dilate_row_lanes(mask, marked, y, cover, &mut s.dilate, |x, ink| {
                                match ink {
                                    Ink::Eight(inked, c) => {
                                        let a = c * inv8;
                                        let keep = f32x8::ONE - a;
                                        for (p, col) in
                                            [&mut *r, &mut *g, &mut *b].into_iter().zip(col8)
                                        {
                                            let p = &mut p[x..x + 8];
                                            let v = <[f32; 8]>::try_from(&*p).unwrap_or_default();
                                            let v = f32x8::from(v);
                                            let v = inked.select(v * keep + col * a, v);
                                            p.copy_from_slice(v.as_array());
                                        }
                                    }
                                    Ink::One(c) => {
                                        blend([&mut r[x], &mut g[x], &mut b[x]], c * inv, color)
                                    }
                                }
                            });
                        }
                        return;
                    }
                    let rows = r.chunks_mut(w).zip(g.chunks_mut(w)).zip(b.chunks_mut(w));
                    for (y, ((r, g), b)) in (k * BLEND_ROWS..).zip(rows) {
                        // The row's ssaa sample rows' coverage, then
                        // composite's sums and blend.
                        let RowsScratch {
                            dilate,
                            coverage,
                            acc,
                        } = s;
                        coverage.clear();
                        coverage.resize(ssaa * sw, 0.0);
                        let mut ink = false;
                        for (sy, row) in coverage.chunks_mut(sw).enumerate() {
                            dilate_row(mask, marked, y * ssaa + sy, cover, dilate, |x, c| {
                                row[x] = c;
                                ink = true;
                            });
                        }
                        if ink {
                            sum_samples(acc, w, ssaa, |sy| &coverage[sy * sw..][..w * ssaa]);
                            blend_row([r, g, b], acc, inv, color);
                        }
                    }
                });
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Depth of a plane seen by a pinhole camera at pixel (x, y): the ray
    /// through the pixel centre hits n·p = c at t, w = t · (ray · forward),
    /// written here independently of the detector.
    fn plane_depth(x: usize, y: usize, w: usize, h: usize, n: [f64; 3], c: f64) -> f32 {
        let tan = (30f64.to_radians()).tan();
        let nx = (2.0 * (x as f64 + 0.5) / w as f64 - 1.0) * tan * w as f64 / h as f64;
        let ny = (1.0 - 2.0 * (y as f64 + 0.5) / h as f64) * tan;
        let d = [nx, ny, -1.0]; // camera at the origin looking down −z
        let t = c / (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]);
        t as f32 // w = t · (d · forward) with d · forward = 1
    }

    fn edges_of_depth(depth: &[f32], w: usize, h: usize, t: f32) -> Vec<bool> {
        let inv = inverse_depth(depth);
        let input = EdgeInput {
            width: w,
            height: h,
            inv_depth: &inv,
            normal: [&[], &[], &[]],
            material: &[],
            luma: &[],
        };
        detect_edges(&input, &[(Source::Depth, t)], &|_| true)
    }

    #[test]
    fn a_slanted_floor_gives_no_depth_line_and_a_step_does() {
        let (w, h) = (96, 64);
        // A floor y = −1 seen at a grazing angle: depth from ~1 at the
        // bottom rows to ~60 near the horizon, its first derivative large.
        let n = [0.02, 1.0, 0.0f64];
        let n_len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let n = n.map(|v| v / n_len);
        let floor: Vec<f32> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if y < h / 2 + 2 {
                    f32::INFINITY // sky above the horizon
                } else {
                    plane_depth(x, y, w, h, n, -1.0 / n_len)
                }
            })
            .collect();
        assert!(floor[(h - 1) * w] < 2.0 && floor[(h / 2 + 2) * w] > 10.0);
        // Plain Sobel's first derivative of depth is large on the floor.
        let first = (floor[(h / 2 + 6) * w + 5] - floor[(h / 2 + 8) * w + 5]).abs();
        assert!(first > 1.0, "{first}");
        let e = edges_of_depth(&floor, w, h, 0.05);
        let on_floor = (h / 2 + 4..h).flat_map(|y| (0..w).map(move |x| (x, y)));
        let lines: Vec<_> = on_floor.filter(|(x, y)| e[y * w + x]).collect();
        assert!(lines.is_empty(), "lines on the floor at {lines:?}");

        // A box in front of a wall: depth 2 inside x in [30, 60), 4 outside.
        let step: Vec<f32> = (0..w * h)
            .map(|i| {
                if (30..60).contains(&(i % w)) {
                    2.0
                } else {
                    4.0
                }
            })
            .collect();
        let e = edges_of_depth(&step, w, h, 0.25);
        for y in 0..h {
            let row: Vec<usize> = (0..w).filter(|x| e[y * w + x]).collect();
            // 1 − 2/4 = 0.5 > 0.25 on both sides of each step; nothing else.
            assert_eq!(row, vec![29, 30, 59, 60], "row {y}");
        }
        // Above the measure (0.5), the step draws nothing.
        assert!(!edges_of_depth(&step, w, h, 0.55).contains(&true));
    }

    #[test]
    fn normal_and_id_measures_match_their_formulas() {
        let (w, h) = (20, 10);
        // Two faces meeting at x = 10 with normals 90° apart.
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let nx: Vec<f32> = (0..w * h)
            .map(|i| if i % w < 10 { -s } else { s })
            .collect();
        let ny = vec![0.0; w * h];
        let nz = vec![s; w * h];
        let mat: Vec<f32> = (0..w * h).map(|i| (i % w >= 10) as u32 as f32).collect();
        let input = EdgeInput {
            width: w,
            height: h,
            inv_depth: &[],
            normal: [&nx, &ny, &nz],
            material: &mat,
            luma: &[],
        };
        let want = 2.0 * (std::f32::consts::FRAC_PI_4).sin(); // 2 sin(θ/2)
        assert!((measure(&input, Source::Normal, 9, 5) - want).abs() < 1e-6);
        assert!((measure(&input, Source::Normal, 10, 5) - want).abs() < 1e-6);
        assert_eq!(measure(&input, Source::Normal, 8, 5), 0.0);
        assert!((measure(&input, Source::Id, 9, 5) - 1.0 / 3.0).abs() < 1e-6);
        assert_eq!(measure(&input, Source::Id, 3, 5), 0.0);
    }

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

    /// A 24-bit hash of (i, k): the tests' noise.
    fn hash(i: usize, k: u32) -> u32 {
        let v = (i as u32)
            .wrapping_mul(2654435761)
            .wrapping_add(k.wrapping_mul(97));
        (v ^ (v >> 13)).wrapping_mul(1274126177) >> 8
    }

    /// [`hash`] as a value in [0, 1).
    fn unit(i: usize, k: u32) -> f32 {
        hash(i, k) as f32 / (1u32 << 24) as f32
    }

    /// Noisy frame fields for the row-kernel tests: misses (q = 0) and
    /// noise, plus (`patchy`) flat patches, steps and repeated labels.
    struct Fields {
        width: usize,
        height: usize,
        inv: Vec<f32>,
        normal: [Vec<f32>; 3],
        mat: Vec<f32>,
        luma: Vec<f32>,
    }

    impl Fields {
        fn noisy(width: usize, height: usize, patchy: bool) -> Fields {
            let n = width * height;
            let depth: Vec<f32> = (0..n)
                .map(|i| match hash(i, 1) % 5 {
                    0 => f32::INFINITY,
                    1 if patchy => 2.0,
                    _ => 1.0 + 4.0 * unit(i, 2),
                })
                .collect();
            // Patches: normals shared by 3 samples, labels by 2, of 4.
            let (normal_run, label_run, labels) = if patchy { (3, 2, 4) } else { (1, 1, 3) };
            Fields {
                width,
                height,
                inv: inverse_depth(&depth),
                normal: [0, 1, 2].map(|c| {
                    (0..n)
                        .map(|i| unit(i / normal_run, 10 + c) * 2.0 - 1.0)
                        .collect()
                }),
                mat: (0..n)
                    .map(|i| (hash(i / label_run, 5) % labels) as f32 - 1.0)
                    .collect(),
                luma: (0..n).map(|i| unit(i, 7)).collect(),
            }
        }

        fn input(&self) -> EdgeInput<'_> {
            let [nx, ny, nz] = &self.normal;
            EdgeInput {
                width: self.width,
                height: self.height,
                inv_depth: &self.inv,
                normal: [nx, ny, nz],
                material: &self.mat,
                luma: &self.luma,
            }
        }
    }

    /// Labels by chunks (one table read for a chunk of one id, a gather
    /// otherwise) against a per-sample look-up: runs of one id across and
    /// inside chunks, mixed chunks, misses and ids past the table.
    #[test]
    fn labels_by_chunks_equal_a_look_up_per_sample() {
        let id_material = [0u32, 3, u32::MAX, 1, 2];
        let mut of_id = Vec::new();
        label_of_id(&id_material, &mut of_id);
        let ids: Vec<u32> = (0..203)
            .map(|i| match i / 8 % 4 {
                0 => 1,                   // a chunk of one id
                1 => (i % 3) as u32,      // mixed
                2 => [MISS, 7, 4][i % 3], // a miss, past the table, the last
                _ => {
                    if i % 16 < 12 {
                        3
                    } else {
                        2
                    }
                } // a run ending inside a chunk
            })
            .collect();
        let mut labels = vec![f32::NAN; ids.len()];
        labels_into(&ids, &of_id, &mut labels);
        for (i, (&id, &l)) in ids.iter().zip(&labels).enumerate() {
            let want = match id_material.get(id as usize) {
                Some(&m) if m != u32::MAX => m as f32,
                _ => -1.0,
            };
            assert_eq!(l.to_bits(), want.to_bits(), "sample {i}, id {id}");
        }
    }

    #[test]
    fn packets_give_the_scalar_measure_bit_for_bit() {
        // Noisy buffers with flat patches, steps, misses (q = 0) and
        // repeated labels, at widths around the packet size.
        for (w, h) in [(37, 9), (10, 4), (9, 3), (64, 5)] {
            let fields = Fields::noisy(w, h, true);
            let input = fields.input();
            let all = [Source::Depth, Source::Normal, Source::Id, Source::Color];
            for s in all {
                for y in 0..h {
                    let rows = [y.saturating_sub(1) * w, y * w, (y + 1).min(h - 1) * w];
                    for x in 1..w.saturating_sub(8) {
                        let lanes = measure_lanes::<f32x8>(&input, s, rows, x);
                        for l in 0..8 {
                            let one = measure(&input, s, x + l, y);
                            let lane = lanes.as_array()[l];
                            assert_eq!(lane.to_bits(), one.to_bits(), "{s:?} ({}, {y})", x + l);
                            let f = measure_lanes::<f32>(&input, s, rows, x + l);
                            assert_eq!(f.to_bits(), one.to_bits());
                        }
                    }
                }
                // The mask against the scalar measure at every sample,
                // at thresholds around the measures' values.
                for t in [0.05f32, 0.2, 0.4, 0.7] {
                    let e = detect_edges(&input, &[(s, t)], &|i| i % 11 != 4);
                    for y in 0..h {
                        for x in 0..w {
                            let want = measure(&input, s, x, y) > t && (y * w + x) % 11 != 4;
                            assert_eq!(e[y * w + x], want, "{s:?} t {t} ({x}, {y})");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn rows_mark_exactly_where_the_scalar_measure_exceeds_a_threshold_at_it() {
        // Thresholds equal to measures at chosen samples and one float
        // below: a sample whose measure is the threshold is unmarked, one
        // float less marks it, so every bit of the row kernels' values is
        // checked there. Widths put 8-sample chunks across 64-sample words
        // and an overlapping last chunk (and rows too narrow for a chunk);
        // a source listed twice marks above the lesser threshold.
        for (w, h) in [(2, 3), (9, 4), (10, 3), (37, 5), (130, 6), (203, 4)] {
            let fields = Fields::noisy(w, h, false);
            let input = fields.input();
            let all = [Source::Depth, Source::Normal, Source::Id, Source::Color];
            for s in all {
                for k in 0..6 {
                    let (x, y) = ((k * 29 + 3) % w, k % h);
                    let at = measure(&input, s, x, y);
                    for t in [at, at.next_down()] {
                        let sources = [(s, t + 0.25), (s, t)];
                        let e = detect_edges(&input, &sources, &|_| true);
                        for yy in 0..h {
                            for xx in 0..w {
                                let want = measure(&input, s, xx, yy) > t;
                                assert_eq!(e[yy * w + xx], want, "{w} {s:?} t {t} ({xx}, {yy})");
                            }
                        }
                        assert_eq!(e[y * w + x], t < at);
                    }
                }
            }
        }
    }

    /// The fields of one block (3 rows of BLOCK + 2 samples) for the block
    /// bound tests: `pattern` over a base value per field, with amplitude
    /// `eps`: 0 noise, 1 a step across the rows, 2 a diagonal step, 3 a
    /// ridge every other column (the largest second difference), 4 one
    /// sample off the base and a NaN after it (in the order block_range
    /// reads them: a NaN must not drop what came before), 5 noise with a
    /// +∞, 6 noise with misses (q = 0) in the first columns, 7 all 0.
    fn block_fields(pattern: u32, eps: f32) -> [Vec<f32>; 6] {
        const N: usize = BLOCK + 2;
        [0u32, 1, 2, 3, 4, 5].map(|f| {
            // q small enough that a block's largest can be under 0.1.
            let base = if f == 0 { 0.05 } else { 0.3 + 0.1 * f as f32 };
            (0..3 * N)
                .map(|i| {
                    let (x, r) = (i % N, i / N);
                    let noise = base + eps * unit(i, f);
                    let v = match pattern {
                        1 => base + if x >= 33 { eps } else { 0.0 },
                        2 => base + if x + r >= 34 { eps } else { 0.0 },
                        3 => base + if x % 2 == 0 { eps } else { 0.0 },
                        4 if (x, r) == (8, 0) => base + eps,
                        4 if (x, r) == (40, 1) => f32::NAN,
                        4 => base,
                        5 if (x, r) == (20, 0) => f32::INFINITY,
                        6 if f == Field::InvDepth as u32 && x < 10 => 0.0,
                        7 => 0.0,
                        _ => noise,
                    };
                    if f == Field::Label as u32 {
                        // Labels (never NaN, EdgeInput): one, or two where
                        // the pattern leaves the base.
                        (v != base) as u32 as f32
                    } else {
                        v
                    }
                })
                .collect()
        })
    }

    #[test]
    fn a_source_dropped_from_a_block_marks_none_of_its_samples() {
        // The bounds of block_sources against the scalar measure of every
        // sample of the block: a source is dropped only where no measure
        // exceeds its threshold, thresholds from below 0 to just under and
        // at the block's largest measure (a bound smaller than it fails
        // there); the patterns include the ones that reach the bounds
        // (steps, ridges) and NaN, ∞ and missed samples. The mask of
        // detect_edges equals the scalar measure's everywhere.
        const N: usize = BLOCK + 2;
        let all = [Source::Depth, Source::Normal, Source::Id, Source::Color];
        let mut dropped = [0usize; 4];
        for pattern in 0..8 {
            for eps in [0.0f32, 1e-3, 1e-2, 0.1, 0.5] {
                let fields = block_fields(pattern, eps);
                let [q, nx, ny, nz, labels, luma] = &fields;
                let input = EdgeInput {
                    width: N,
                    height: 3,
                    inv_depth: q,
                    normal: [nx, ny, nz],
                    material: labels,
                    luma,
                };
                let a: [BlockRows; 6] = std::array::from_fn(|k| {
                    [0, 1, 2].map(|r| <&[f32; N]>::try_from(&fields[k][r * N..][..N]).unwrap())
                });
                let measures =
                    |s| -> Vec<f32> { (1..=BLOCK).map(|x| measure(&input, s, x, 1)).collect() };
                let thresholds = |s| -> Vec<f32> {
                    let most = measures(s).into_iter().fold(0.0f32, f32::max);
                    let ts = [-0.5, 0.0, most.next_down(), most, most * 1.01, most * 3.0];
                    ts.into_iter().chain([0.4, f32::INFINITY]).collect()
                };
                for (k, &s) in all.iter().enumerate() {
                    for t in thresholds(s) {
                        let out = block_sources(&Thresholds::new(&[(s, t)]), &a);
                        let kept = out.is_some_and(|o| match s {
                            Source::Depth => o.depth.is_some(),
                            Source::Normal => o.normal.is_some(),
                            Source::Id => o.id.is_some(),
                            Source::Color => o.color.is_some(),
                        });
                        if !kept {
                            dropped[k] += 1;
                            let over: Vec<f32> =
                                measures(s).into_iter().filter(|&m| m > t).collect();
                            assert!(over.is_empty(), "{s:?} {pattern} {eps} t {t}: {over:?}");
                        }
                        let e = detect_edges(&input, &[(s, t)], &|_| true);
                        for x in 0..N {
                            let want = measure(&input, s, x, 1) > t;
                            assert_eq!(e[N + x], want, "{s:?} {pattern} {eps} t {t} x {x}");
                        }
                    }
                }
                // All sources at once: the tests stop at the first source
                // that may mark; whatever is dropped marks nothing.
                let ts: Vec<Vec<f32>> = all.iter().map(|&s| thresholds(s)).collect();
                for i in 0..ts[0].len() {
                    let sources: Vec<(Source, f32)> =
                        all.iter().zip(&ts).map(|(&s, t)| (s, t[i])).collect();
                    let out = block_sources(&Thresholds::new(&sources), &a);
                    for (&(s, t), kept) in sources.iter().zip(out.map_or([false; 4], |o| {
                        [
                            o.depth.is_some(),
                            o.normal.is_some(),
                            o.id.is_some(),
                            o.color.is_some(),
                        ]
                    })) {
                        let none = !measures(s).iter().any(|&m| m > t);
                        assert!(kept || none, "{s:?} {pattern} {eps}");
                    }
                }
            }
        }
        // Every source was dropped somewhere (the bounds are not vacuous).
        assert!(dropped.iter().all(|&d| d > 0), "{dropped:?}");
    }

    #[test]
    fn blocks_of_one_label_mark_as_the_scalar_id_measure() {
        // Wide runs of one label (whole 64-sample blocks of one label and
        // their neighbour rows, where every measure is 0), a few single
        // samples of another, a run boundary in mid-block, and a row band
        // of another label; thresholds below 0 mark every sample.
        let (w, h) = (203, 9);
        let mat: Vec<f32> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if (x, y) == (100, 4) || (x, y) == (170, 1) {
                    7.0
                } else if y >= 7 {
                    -1.0
                } else {
                    (x / 90) as f32
                }
            })
            .collect();
        let input = EdgeInput {
            width: w,
            height: h,
            inv_depth: &[],
            normal: [&[], &[], &[]],
            material: &mat,
            luma: &[],
        };
        for t in [-0.5f32, -0.0, 0.0, 0.1, 1.0 / 3.0, 0.9] {
            let e = detect_edges(&input, &[(Source::Id, t)], &|_| true);
            for y in 0..h {
                for x in 0..w {
                    let want = measure(&input, Source::Id, x, y) > t;
                    assert_eq!(e[y * w + x], want, "t {t} ({x}, {y})");
                }
            }
            assert_eq!(e.iter().all(|&m| m), t < 0.0, "t {t}");
        }
    }

    #[test]
    fn the_squared_threshold_says_what_the_square_root_says() {
        // Around each threshold's square, f32 by f32, and at the ends.
        for t in [0.0f32, 1e-20, 0.1, 0.25, 0.4, 0.6, 1.0, 3.7, 1e19, 3e19] {
            let x = below_sqrt(t);
            let mut g2 = (t * t).max(f32::MIN_POSITIVE);
            for _ in 0..8 {
                g2 = g2.next_down();
            }
            for _ in 0..16 {
                assert_eq!(g2.sqrt() > t, g2 > x, "t {t} g² {g2}");
                g2 = g2.next_up();
            }
            for g2 in [0.0, f32::MIN_POSITIVE, f32::MAX, f32::INFINITY, f32::NAN] {
                assert_eq!(g2.sqrt() > t, g2 > x, "t {t} g² {g2}");
            }
        }
        for t in [-1.0f32, f32::INFINITY] {
            for g2 in [0.0, 1.0, f32::MAX, f32::INFINITY, f32::NAN] {
                assert_eq!(g2.sqrt() > t, g2 > below_sqrt(t), "t {t} g² {g2}");
            }
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
    fn labels_read_the_material_of_each_id_and_minus_one_past_the_table() {
        // Materials with holes (u32::MAX: no pass writes the id), ids past
        // the table and MISS, at lengths around the 8-lane packets.
        let id_material: Vec<u32> = (0..37u32)
            .map(|i| if i % 5 == 3 { u32::MAX } else { i % 4 })
            .collect();
        for n in [0usize, 1, 7, 8, 9, 23, 64, 65] {
            let ids: Vec<u32> = (0..n as u32)
                .map(|i| match i % 6 {
                    0 => MISS,
                    1 => 37 + i, // past the table
                    _ => (i * 7) % 37,
                })
                .collect();
            let got = material_labels(&ids, &id_material);
            for (k, &id) in ids.iter().enumerate() {
                let want = match id_material.get(id as usize) {
                    Some(&m) if m != u32::MAX => m as f32,
                    _ => -1.0,
                };
                assert_eq!(got[k], want, "n {n} id {id}");
            }
        }
    }

    /// A frame of noisy patches: depth steps and misses, normals, ids whose
    /// materials change across patches (some with none), and colour.
    fn patchy_frame(w: usize, h: usize) -> (FrameBuffers, Vec<u32>) {
        // Patches of 16 × 12 samples share their values.
        let patch = |i: usize| (i % w) / 16 + 1000 * ((i / w) / 12);
        let n = w * h;
        let plane = |k: u32| -> Vec<f32> { (0..n).map(|i| unit(patch(i), k)).collect() };
        let depth = (0..n)
            .map(|i| match hash(patch(i), 1) % 7 {
                0 => f32::INFINITY,
                1 => 2.0,
                _ => 1.0 + 4.0 * unit(patch(i), 2),
            })
            .collect();
        let ids: Vec<u32> = (0..n)
            .map(|i| match hash(patch(i), 3) % 9 {
                0 => MISS,
                k => k * 3 + (i % 3) as u32, // three ids a patch, one material
            })
            .collect();
        let id_material = (0..40u32)
            .map(|id| if id % 11 == 7 { u32::MAX } else { id / 3 % 4 })
            .collect();
        let rgb = |k: u32| Planes3 {
            r: plane(k),
            g: plane(k + 1),
            b: plane(k + 2),
        };
        let frame = FrameBuffers {
            width: w as u32,
            height: h as u32,
            color: rgb(10),
            depth,
            normal: rgb(20),
            id: ids,
        };
        (frame, id_material)
    }

    #[test]
    fn the_stage_equals_its_parts_composited_bit_for_bit_for_any_thread_count() {
        // The stage (bands with their own 1/w, labels and luminance; the
        // dilation per row straight into a sparse blend; buffers kept from
        // call to call) against the whole-frame parts: detect_edges on
        // whole-frame inputs, dilate, composite.
        let sources = vec![
            (Source::Depth, 0.1),
            (Source::Normal, 0.6),
            (Source::Id, 0.3),
            (Source::Color, 0.45),
        ];
        let pools: Vec<rayon::ThreadPool> = [1, 3]
            .iter()
            .map(|&n| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .unwrap()
            })
            .collect();
        for (w, h, ssaa) in [(131, 70, 1), (130, 72, 2), (99, 69, 3)] {
            let (frame, id_material) = patchy_frame(w, h);
            let (iw, ih) = (w / ssaa, h / ssaa);
            let image = |k: usize| -> Vec<f32> {
                (0..iw * ih)
                    .map(|i| ((i * 37 + k) % 101) as f32 / 100.0)
                    .collect()
            };
            let img0 = HdrImage {
                width: iw as u32,
                height: ih as u32,
                rgb: Planes3 {
                    r: image(1),
                    g: image(2),
                    b: image(3),
                },
            };
            let inv = inverse_depth(&frame.depth);
            let mat = material_labels(&frame.id, &id_material);
            let c = &frame.color;
            let clamp = |v: f32| if v > 0.0 { v.min(1.0) } else { 0.0 };
            let luma: Vec<f32> = (0..w * h)
                .map(|i| 0.2126 * clamp(c.r[i]) + 0.7152 * clamp(c.g[i]) + 0.0722 * clamp(c.b[i]))
                .collect();
            let input = EdgeInput {
                width: w,
                height: h,
                inv_depth: &inv,
                normal: [&frame.normal.r, &frame.normal.g, &frame.normal.b],
                material: &mat,
                luma: &luma,
            };
            let selections = [
                Selection::all(),
                Selection::materials(&id_material, &[1, 2]),
            ];
            for selection in selections {
                for width in [1.0f32, 2.0, 3.5, 9.0, 40.0] {
                    for antialias in [true, false] {
                        let mut stage = Sobel {
                            sources: sources.clone(),
                            width,
                            color: [0.1, 0.2, 0.9],
                            antialias,
                            id_material: id_material.clone(),
                            selection: selection.clone(),
                            scratch: Scratch::default(),
                        };
                        let keep =
                            |i: usize| !selection.needs_ids() || selection.contains(frame.id[i]);
                        let mask = detect_edges(&input, &sources, &keep);
                        let cov = dilate(&mask, w, h, width * ssaa as f32, antialias);
                        let mut want = img0.clone();
                        composite(&mut want, &frame, &cov, stage.color);
                        // Ink somewhere, and narrow lines leave samples
                        // without (the blend skips them).
                        assert!(cov.iter().any(|&c| c > 0.0));
                        assert!(width * ssaa as f32 > 4.0 || cov.contains(&0.0));
                        for pool in &pools {
                            // Twice: the second call reuses the buffers.
                            for _ in 0..2 {
                                let mut got = img0.clone();
                                pool.install(|| stage.apply(&mut got, &frame));
                                let planes = |i: &HdrImage| {
                                    [&i.rgb.r, &i.rgb.g, &i.rgb.b]
                                        .map(|p| p.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
                                };
                                assert!(
                                    planes(&got) == planes(&want),
                                    "{w}×{h} ssaa {ssaa} width {width} aa {antialias}"
                                );
                            }
                        }
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
