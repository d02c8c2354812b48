//! Outline by image: edges in the frame buffers (`detect_edges`), widened
//! to the line width by a Euclidean distance transform (`dilate`), and
//! blended over the image (as `crate::outline::composite` does).
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
//! The stage allocates nothing in a steady frame (whole-frame buffers
//! would cost a kernel page fault on each of their pages):
//! - 1/w, the material labels and the luminance are computed per band of
//!   `BAND_ROWS` rows (and the row above and below it) inside the
//!   detection, not as whole-frame buffers;
//! - the marks are bits (`EdgeMask`), kept in the stage with the other
//!   scratch ([`Scratch`]) from frame to frame;
//! - the line is widened row by row (`dilate_row`) straight into the
//!   blend, and only near marks: rows with no mark within the line's
//!   reach and 64-sample words with none are skipped, so there is no
//!   frame-size coverage map either; a line at most 2 samples wide inks
//!   only the marks (`Cover::marks_only`) and skips the dilation.
//!
//! Memory bounds it as much as arithmetic (the frame's depth, normals
//! and ids are far larger than the caches; profiles put most of the time
//! on the first read of each row and on the blend's reads of the image),
//! so the detection reads each field row once: every source's measure 8
//! samples at a time in one pass (`detect_block`),
//! the frame's normals prefetched two rows ahead; and the blend prefetches
//! the image lines near the marks two rows ahead. A block of 64 samples
//! first drops every source whose measure a bound over the block's values
//! keeps under its threshold (`block_sources`):
//! flat ground and the insides of large faces are not measured.
//!
//! The files, in the order of the data flow:
//! - `inputs`: the per-sample values the detection reads (`EdgeInput`):
//!   1/w, material labels, luminance;
//! - `measure`: the scalar reference of each source's measure (`measure`);
//! - `detect`: the edge marks, row by row and band by band, 8 samples at a
//!   time through every source at once (`detect_row`, `detect_edges`);
//! - `block`: the per-block bounds that skip sources which cannot mark;
//! - `blend`: the line's coverage and its blend over the image, in bands
//!   of rows (the dilation itself is `crate::dilate`);
//! - this file: the stage, its [`PostStage`] impl and its scratch buffers.

mod blend;
mod block;
mod detect;
mod inputs;
mod measure;
#[cfg(test)]
mod tests;

use crate::outline::{ssaa_of, Selection};
use specula_raster::post::{HdrImage, PostStage};
use specula_raster::{BufferSet, FrameBuffers};

use crate::dilate::{EdgeMask, Pool, RowScratch};

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
    /// The id source's label of each id (`material_labels`).
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
pub(crate) const BAND_ROWS: usize = 32;

impl Sobel {
    fn has(&self, s: Source) -> bool {
        self.sources.iter().any(|(t, _)| *t == s)
    }
}

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
    /// The blend is `outline::composite`'s: the same
    /// coverage per sample, summed in the same order, the same products.
    /// It is skipped where the coverage is 0 (no mark within the line's
    /// reach), where composite's
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
