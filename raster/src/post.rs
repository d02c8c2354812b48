//! After shading: a list of named post stages ([`Post`]) over the frame
//! buffers: supersampling resolve (box filter, in linear HDR), exposure,
//! tone mapping and the one sRGB encode at the very end, plus any custom
//! image-space stage ([`PostStage`]) where the list puts it. The standard
//! list runs fused in one pass over the samples ([`resolve_ldr`]).

use crate::buffers::{BufferSet, FrameBuffers, Planes3};
use rayon::prelude::*;
use specula_core::{f32x8, Real};
use wide::i32x8;

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

    /// [`Tonemap::apply`] on 8 values: the same IEEE operations in the same
    /// order (no fused multiply-adds), so every lane equals the scalar
    /// result bit for bit (a test checks it).
    #[inline(always)]
    pub fn apply_x8(self, x: f32x8) -> f32x8 {
        let c = |v: f32| f32x8::splat(v);
        let x = Real::select(x.gt(f32x8::ZERO), Real::min(x, c(1e18)), f32x8::ZERO);
        match self {
            Tonemap::Clamp => Real::min(x, c(1.0)),
            Tonemap::Reinhard => x / (c(1.0) + x),
            Tonemap::Aces => {
                let num = x * (c(2.51) * x + c(0.03));
                let den = x * (c(2.43) * x + c(0.59)) + c(0.14);
                Real::clamp(num / den, f32x8::ZERO, c(1.0))
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

/// Inverse of [`srgb_curve`]: sRGB-encoded [0, 1] to linear.
pub fn srgb_curve_inverse(s: f64) -> f64 {
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
/// instead of two: the float's top bits pick a cell ([`srgb_cells`]), and
/// an integer comparison of its low bits with the cell's threshold adds
/// the last code. Its codes equal the scalar encoder's (a test checks every
/// threshold, cell edge and a sweep). The two dependent reads per value
/// (bin start, then threshold) were most of the fused post pass: a
/// hardware gather costs ~17 cycles here.
#[derive(Clone, Copy)]
pub struct SrgbEncoderX8 {
    cells: &'static [i32],
}

impl SrgbEncoderX8 {
    pub fn new() -> SrgbEncoderX8 {
        SrgbEncoderX8 {
            cells: srgb_cells(),
        }
    }

    /// The codes 0..=255 as i32 lanes.
    #[inline(always)]
    pub fn encode_i32(&self, v: f32x8) -> i32x8 {
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

/// [`SrgbEncoder::encode`] for one value.
pub fn srgb_encode(v: f32) -> u8 {
    SrgbEncoder::new().encode(v)
}

/// Sum of the ssaa² samples of output pixel (x, y), in sample order.
#[inline]
fn box_sum(color: &Planes3, width: usize, ssaa: usize, x: usize, y: usize) -> [f32; 3] {
    let mut s = [0.0f32; 3];
    for sy in 0..ssaa {
        let row = (y * ssaa + sy) * width + x * ssaa;
        for i in row..row + ssaa {
            s[0] += color.r[i];
            s[1] += color.g[i];
            s[2] += color.b[i];
        }
    }
    s
}

/// A linear HDR image between post stages: row-major planes.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrImage {
    pub width: u32,
    pub height: u32,
    pub rgb: Planes3,
}

impl HdrImage {
    /// Interleaved [r, g, b] per pixel, row-major (for image writers).
    pub fn interleaved(&self) -> Vec<[f32; 3]> {
        (0..self.rgb.len()).map(|i| self.rgb.get(i)).collect()
    }
}

/// The supersampling resolve: each output pixel the mean of its ssaa²
/// samples of `color` (`width × height` samples).
pub fn downsample(color: &Planes3, width: u32, height: u32, ssaa: u32) -> HdrImage {
    let (w, h) = (width / ssaa, height / ssaa);
    if ssaa == 1 {
        return HdrImage {
            width: w,
            height: h,
            rgb: color.clone(),
        };
    }
    let scale = 1.0 / (ssaa * ssaa) as f32;
    let mut rgb = Planes3::new((w * h) as usize);
    rgb.r
        .par_chunks_mut(w as usize)
        .zip(rgb.g.par_chunks_mut(w as usize))
        .zip(rgb.b.par_chunks_mut(w as usize))
        .enumerate()
        .for_each(|(y, ((r, g), b))| {
            for x in 0..w as usize {
                let s = box_sum(color, width as usize, ssaa as usize, x, y);
                r[x] = s[0] * scale;
                g[x] = s[1] * scale;
                b[x] = s[2] * scale;
            }
        });
    HdrImage {
        width: w,
        height: h,
        rgb,
    }
}

/// An image-space stage from outside this crate (npr's Sobel outlines,
/// posterization, ...). It runs where the post list puts it: on the
/// supersampled image before [`Stage::Resolve`], on the output image after
/// it (`img.width` tells), in linear HDR before [`Stage::Tonemap`] and in
/// tone-mapped [0, 1] values after it.
pub trait PostStage: std::fmt::Debug + Send + Sync {
    fn name(&self) -> &str;
    /// The frame buffers the stage reads (colour is always there).
    fn buffers(&self) -> BufferSet {
        BufferSet::default()
    }
    /// Transforms `img`; `frame` holds the shading pass's buffers at the
    /// supersampled size.
    fn apply(&self, img: &mut HdrImage, frame: &FrameBuffers);
}

/// One named step of the post list.
#[derive(Clone, Debug)]
pub enum Stage {
    /// Box-filters ssaa × ssaa samples into one pixel (linear HDR).
    Resolve {
        ssaa: u32,
    },
    /// Multiplies radiance by 2^stops.
    Exposure {
        stops: f32,
    },
    /// Per channel tone curve into [0, 1]; NaN and negatives become 0.
    Tonemap(Tonemap),
    /// sRGB encoding to 8 bits; the last stage when present.
    Encode,
    Custom(std::sync::Arc<dyn PostStage>),
}

impl Stage {
    pub fn name(&self) -> &str {
        match self {
            Stage::Resolve { .. } => "resolve",
            Stage::Exposure { .. } => "exposure",
            Stage::Tonemap(_) => "tonemap",
            Stage::Encode => "encode",
            Stage::Custom(s) => s.name(),
        }
    }
}

/// What the post list produced: the final HDR image (after the last stage
/// before `Encode`) unless the fused path ran, and the 8-bit sRGB pixels
/// (RGB, row-major) if the list encodes.
#[derive(Debug, Default)]
pub struct PostOutput {
    pub width: u32,
    pub height: u32,
    pub hdr: Option<HdrImage>,
    pub ldr: Option<Vec<u8>>,
}

/// The post stages of a frame, in order.
#[derive(Clone, Debug)]
pub struct Post {
    pub stages: Vec<Stage>,
    /// Run [`resolve_ldr`] (one pass over the samples, no HDR image in
    /// between) when the list is exactly resolve, exposure, tone map,
    /// encode. Off only to measure what fusing is worth.
    pub fuse: bool,
}

impl Post {
    /// The default list: resolve, exposure, tone map, encode.
    pub fn standard(ssaa: u32, stops: f32, tonemap: Tonemap) -> Post {
        Post {
            stages: vec![
                Stage::Resolve { ssaa },
                Stage::Exposure { stops },
                Stage::Tonemap(tonemap),
                Stage::Encode,
            ],
            fuse: true,
        }
    }

    /// The optional frame buffers the stages read.
    pub fn buffers(&self) -> BufferSet {
        self.stages
            .iter()
            .fold(BufferSet::default(), |acc, s| match s {
                Stage::Custom(c) => acc.union(c.buffers()),
                _ => acc,
            })
    }

    /// Checks the list: `Encode` only last, one `Resolve` at most, whose
    /// factor divides the frame size.
    pub fn validate(&self, width: u32, height: u32) -> Result<(), String> {
        let n = self.stages.len();
        let mut resolves = 0;
        for (i, s) in self.stages.iter().enumerate() {
            match s {
                Stage::Encode if i + 1 != n => {
                    return Err("post: \"encode\" must be the last stage".into())
                }
                Stage::Resolve { ssaa } => {
                    resolves += 1;
                    if *ssaa == 0 || !width.is_multiple_of(*ssaa) || !height.is_multiple_of(*ssaa) {
                        return Err(format!(
                            "post: resolve factor {ssaa} does not divide the {width}×{height} frame"
                        ));
                    }
                }
                _ => {}
            }
        }
        if resolves > 1 {
            return Err("post: more than one resolve stage".into());
        }
        Ok(())
    }

    /// The fused form's parameters, if the list has that shape.
    fn fused_form(&self) -> Option<(u32, f32, Tonemap)> {
        match self.stages.as_slice() {
            [Stage::Resolve { ssaa }, Stage::Exposure { stops }, Stage::Tonemap(t), Stage::Encode]
                if self.fuse =>
            {
                Some((*ssaa, *stops, *t))
            }
            _ => None,
        }
    }

    /// The list as an encoding the shading pass can run itself: the fused
    /// standard list at ssaa 1 (no supersampling resolve, no custom stage).
    pub fn ldr_in_shading(&self) -> Option<LdrEncoding> {
        match self.fused_form()? {
            (1, stops, tonemap) => Some(LdrEncoding::new(tonemap, stops)),
            _ => None,
        }
    }

    /// The fused head's parameters when the list starts resolve, exposure,
    /// tone map (custom stages and the encode after them).
    fn fused_head(&self) -> Option<(u32, f32, Tonemap)> {
        match self.stages.as_slice() {
            [Stage::Resolve { ssaa }, Stage::Exposure { stops }, Stage::Tonemap(t), ..]
                if self.fuse =>
            {
                Some((*ssaa, *stops, *t))
            }
            _ => None,
        }
    }

    /// Runs the stages over the frame's colour.
    pub fn run(&self, frame: &FrameBuffers) -> Result<PostOutput, String> {
        self.run_reusing(frame, PostOutput::default())
    }

    /// [`Post::run`] writing into the buffers of `recycled`, an earlier
    /// frame's output, whose allocations are reused (their contents are
    /// all overwritten): a fresh 1080p frame's 8-bit pixels (6 MB) and HDR
    /// planes (25 MB) are ~7,600 pages, each a page fault in which the
    /// kernel zeroes what the post then overwrites anyway (the Sobel
    /// outline frame: 12.6k -> 6.1k faults a frame, `perf stat -e
    /// page-faults` over `--repeat 10`).
    ///
    /// With `fuse` set, the standard list runs as one pass over the samples
    /// ([`resolve_ldr`]), and a list that starts with resolve, exposure and
    /// tone map and then has custom stages runs that head as one pass into
    /// the HDR image ([`resolve_hdr_into`]); both give the bytes of the
    /// stage-by-stage list (tested).
    pub fn run_reusing(
        &self,
        frame: &FrameBuffers,
        recycled: PostOutput,
    ) -> Result<PostOutput, String> {
        self.validate(frame.width, frame.height)?;
        let mut ldr_buf = recycled.ldr.unwrap_or_default();
        if let Some((ssaa, stops, tonemap)) = self.fused_form() {
            resolve_ldr_into(frame, ssaa, tonemap, stops, &mut ldr_buf);
            return Ok(PostOutput {
                width: frame.width / ssaa,
                height: frame.height / ssaa,
                hdr: None,
                ldr: Some(ldr_buf),
            });
        }
        let mut rgb = recycled.hdr.map(|h| h.rgb).unwrap_or_default();
        let (mut img, rest) = match self.fused_head() {
            Some((ssaa, stops, tonemap)) => {
                resolve_hdr_into(frame, ssaa, tonemap, stops, &mut rgb);
                let img = HdrImage {
                    width: frame.width / ssaa,
                    height: frame.height / ssaa,
                    rgb,
                };
                (img, &self.stages[3..])
            }
            None => {
                copy_planes(&frame.color, &mut rgb);
                let img = HdrImage {
                    width: frame.width,
                    height: frame.height,
                    rgb,
                };
                (img, &self.stages[..])
            }
        };
        let mut ldr = None;
        for s in rest {
            match s {
                Stage::Resolve { ssaa: 1 } => {}
                Stage::Resolve { ssaa } => img = downsample(&img.rgb, img.width, img.height, *ssaa),
                Stage::Exposure { stops } => {
                    let k = stops.exp2();
                    for p in [&mut img.rgb.r, &mut img.rgb.g, &mut img.rgb.b] {
                        p.par_iter_mut().for_each(|v| *v *= k);
                    }
                }
                Stage::Tonemap(t) => {
                    let t = *t;
                    for p in [&mut img.rgb.r, &mut img.rgb.g, &mut img.rgb.b] {
                        p.par_iter_mut().for_each(|v| *v = t.apply(*v));
                    }
                }
                Stage::Encode => {
                    encode_ldr_into(&img.rgb, &mut ldr_buf);
                    ldr = Some(std::mem::take(&mut ldr_buf));
                }
                Stage::Custom(c) => c.apply(&mut img, frame),
            }
        }
        Ok(PostOutput {
            width: img.width,
            height: img.height,
            hdr: Some(img),
            ldr,
        })
    }
}

/// Copies `src` into `dst`, reusing `dst`'s allocations.
fn copy_planes(src: &Planes3, dst: &mut Planes3) {
    for (d, s) in [
        (&mut dst.r, &src.r),
        (&mut dst.g, &src.g),
        (&mut dst.b, &src.b),
    ] {
        d.clear();
        d.extend_from_slice(s);
    }
}

/// Supersampling resolve, exposure (in stops) and tone mapping in one pass
/// over the samples, into `out` (planes of (width / ssaa) × (height /
/// ssaa), their allocations reused): the values the three stages give one
/// after the other (the same products in the same order), without the
/// copies and passes in between. The head of a post list with custom
/// stages.
pub fn resolve_hdr_into(
    frame: &FrameBuffers,
    ssaa: u32,
    tonemap: Tonemap,
    exposure: f32,
    out: &mut Planes3,
) {
    match tonemap {
        Tonemap::Clamp => resolve_hdr_with::<0>(frame, ssaa, exposure, out),
        Tonemap::Reinhard => resolve_hdr_with::<1>(frame, ssaa, exposure, out),
        Tonemap::Aces => resolve_hdr_with::<2>(frame, ssaa, exposure, out),
    }
}

fn resolve_hdr_with<const CURVE: u8>(
    frame: &FrameBuffers,
    ssaa: u32,
    exposure: f32,
    out: &mut Planes3,
) {
    let curve = curve_of::<CURVE>();
    let (sw, ssaa) = (frame.width as usize, ssaa as usize);
    let (w, h) = (sw / ssaa, frame.height as usize / ssaa);
    let color = &frame.color;
    let (inv_n, k) = (1.0 / (ssaa * ssaa) as f32, exposure.exp2());
    for p in [&mut out.r, &mut out.g, &mut out.b] {
        // Every value is written below: zeros only where the plane grows.
        p.truncate(w * h);
        p.resize(w * h, 0.0);
    }
    let full = w / 8 * 8;
    out.r
        .par_chunks_mut(w.max(1))
        .zip(out.g.par_chunks_mut(w.max(1)))
        .zip(out.b.par_chunks_mut(w.max(1)))
        .enumerate()
        .for_each(|(y, ((r, g), b))| {
            for x0 in (0..full).step_by(8) {
                let s = sums8(color, sw, ssaa, x0, y);
                let mapped = |ch: f32x8| {
                    let v = ch * f32x8::splat(inv_n) * f32x8::splat(k);
                    curve.apply_x8(v).to_array()
                };
                r[x0..x0 + 8].copy_from_slice(&mapped(s[0]));
                g[x0..x0 + 8].copy_from_slice(&mapped(s[1]));
                b[x0..x0 + 8].copy_from_slice(&mapped(s[2]));
            }
            for x in full..w {
                let s = sum1(color, sw, ssaa, x, y);
                r[x] = curve.apply(s[0] * inv_n * k);
                g[x] = curve.apply(s[1] * inv_n * k);
                b[x] = curve.apply(s[2] * inv_n * k);
            }
        });
}

/// The tone curve a monomorphized post loop was built for.
fn curve_of<const CURVE: u8>() -> Tonemap {
    match CURVE {
        0 => Tonemap::Clamp,
        1 => Tonemap::Reinhard,
        _ => Tonemap::Aces,
    }
}

/// Supersampling resolve, exposure (in stops), tone mapping and sRGB
/// encoding in one pass over the samples: 8-bit RGB, row-major, of
/// (width / ssaa) × (height / ssaa). Equal to the unfused stage list (a
/// test checks it) without the HDR images in between.
pub fn resolve_ldr(frame: &FrameBuffers, ssaa: u32, tonemap: Tonemap, exposure: f32) -> Vec<u8> {
    let mut out = Vec::new();
    resolve_ldr_into(frame, ssaa, tonemap, exposure, &mut out);
    out
}

/// [`resolve_ldr`] into `out`, resized to the output (its earlier bytes
/// are all overwritten, so an allocation from an earlier frame is reused
/// as it is).
pub fn resolve_ldr_into(
    frame: &FrameBuffers,
    ssaa: u32,
    tonemap: Tonemap,
    exposure: f32,
    out: &mut Vec<u8>,
) {
    // One monomorphized loop per curve: no match per pixel.
    match tonemap {
        Tonemap::Clamp => resolve_ldr_with::<0>(frame, ssaa, exposure, out),
        Tonemap::Reinhard => resolve_ldr_with::<1>(frame, ssaa, exposure, out),
        Tonemap::Aces => resolve_ldr_with::<2>(frame, ssaa, exposure, out),
    }
}

/// Sizes `out` to `len` bytes, writing zeros only where it grows (every
/// caller overwrites all of it).
fn size_output(out: &mut Vec<u8>, len: usize) {
    out.truncate(len);
    out.resize(len, 0);
}

fn resolve_ldr_with<const CURVE: u8>(
    frame: &FrameBuffers,
    ssaa: u32,
    exposure: f32,
    out: &mut Vec<u8>,
) {
    let (sw, ssaa) = (frame.width as usize, ssaa as usize);
    let (w, h) = (sw / ssaa, frame.height as usize / ssaa);
    let color = &frame.color;
    // The same products, in the same order, as the unfused stages.
    let (inv_n, k) = (1.0 / (ssaa * ssaa) as f32, exposure.exp2());
    size_output(out, w * h * 3);
    out.par_chunks_mut(3 * w).enumerate().for_each(|(y, row)| {
        if ssaa == 1 {
            // The shading pass's encode (LdrEncoding), on the row's slices.
            let i = y * sw;
            let [r, g, b] = [&color.r, &color.g, &color.b].map(|p| &p[i..i + w]);
            encode_planes::<CURVE>(r, g, b, k, row);
        } else {
            encode_pixels::<CURVE>(
                row,
                inv_n,
                k,
                |x0| sums8(color, sw, ssaa, x0, y),
                |x| sum1(color, sw, ssaa, x, y),
            );
        }
    });
}

/// [`encode_pixels`] of one sample a pixel from the slices `r`, `g`, `b`
/// (n = 1: the resolve's × (1/n) is × 1).
#[inline(always)]
fn encode_planes<const CURVE: u8>(r: &[f32], g: &[f32], b: &[f32], k: f32, out: &mut [u8]) {
    let n = r.len();
    assert!(g.len() == n && b.len() == n && out.len() == 3 * n);
    let eight = |x0| [load8(r, x0), load8(g, x0), load8(b, x0)];
    encode_pixels::<CURVE>(out, 1.0, k, eight, |x| [r[x], g[x], b[x]]);
}

/// Sample sum × (1/n) × k, tone curve and sRGB code of a run of pixels
/// into `out` (3 bytes a pixel): `sums8(x0)` gives pixels x0..x0 + 8 per
/// channel, `sum1(x)` pixel x. The resolve's loop and the shading pass's
/// ([`LdrEncoding::encode_row`]), so both give the same bytes.
#[inline(always)]
fn encode_pixels<const CURVE: u8>(
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
    // two table reads) was ~50 cycles a pixel.
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
/// back (see [`Post::ldr_in_shading`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LdrEncoding {
    tonemap: Tonemap,
    /// 2^exposure, as the resolve computes it (once here, not per row).
    k: f32,
}

impl LdrEncoding {
    /// Exposure `stops`, then `tonemap`, then the sRGB encode.
    pub fn new(tonemap: Tonemap, stops: f32) -> LdrEncoding {
        LdrEncoding {
            tonemap,
            k: stops.exp2(),
        }
    }

    /// Codes of the pixels with linear colours `r[i]`, `g[i]`, `b[i]` into
    /// `out[3i..3i + 3]`: the bytes [`resolve_ldr`] gives for them.
    pub fn encode_row(&self, r: &[f32], g: &[f32], b: &[f32], out: &mut [u8]) {
        match self.tonemap {
            Tonemap::Clamp => encode_planes::<0>(r, g, b, self.k, out),
            Tonemap::Reinhard => encode_planes::<1>(r, g, b, self.k, out),
            Tonemap::Aces => encode_planes::<2>(r, g, b, self.k, out),
        }
    }
}

/// The sample sums of output pixels (x0.., y), 8 of them, per channel:
/// the samples themselves at ssaa 1.
#[inline(always)]
fn sums8(color: &Planes3, sw: usize, ssaa: usize, x0: usize, y: usize) -> [f32x8; 3] {
    if ssaa == 1 {
        let i = y * sw + x0;
        [load8(&color.r, i), load8(&color.g, i), load8(&color.b, i)]
    } else {
        let sums: [[f32; 3]; 8] =
            std::array::from_fn(|lane| box_sum(color, sw, ssaa, x0 + lane, y));
        [0, 1, 2].map(|c| f32x8::from(sums.map(|v| v[c])))
    }
}

/// [`sums8`] for one pixel.
#[inline(always)]
fn sum1(color: &Planes3, sw: usize, ssaa: usize, x: usize, y: usize) -> [f32; 3] {
    if ssaa == 1 {
        color.get(y * sw + x)
    } else {
        box_sum(color, sw, ssaa, x, y)
    }
}

/// p[i..i + 8] as one vector load (filling an array lane by lane and
/// reading it back stalls on store forwarding).
#[inline(always)]
fn load8(p: &[f32], i: usize) -> f32x8 {
    f32x8::from(<[f32; 8]>::try_from(&p[i..i + 8]).unwrap())
}

/// Writes eight pixels' sRGB codes (0..=255 per lane) as 24 bytes of RGB:
/// r | g << 8 | b << 16 is each pixel's three bytes in one little-endian
/// word; one byte shuffle packs each 128-bit half's four words into 12
/// bytes, stored as 8 + 4 (4 stores for 8 pixels instead of 8 word
/// extracts and 8 stores: ~18 instructions fewer per 8 pixels).
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
/// three). A cast to u8 per channel was ~40 % of the fused pass.
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

/// [`encode_ldr`] into `out` (see [`resolve_ldr_into`]).
pub fn encode_ldr_into(rgb: &Planes3, out: &mut Vec<u8>) {
    let enc = SrgbEncoder::new();
    let enc8 = SrgbEncoderX8::new();
    size_output(out, rgb.len() * 3);
    out.par_chunks_mut(3 * 4096)
        .enumerate()
        .for_each(|(chunk, o)| {
            // Eight pixels at a time with the vector encoder (its codes are
            // the scalar encoder's): the scalar loop was ~85 instructions a
            // pixel, 2.4 times the whole fused post list, and ran whenever
            // a custom stage unfuses the list (the outlines, strokes).
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
    fn fused_post_equals_the_stage_list() {
        let t = crate::Target::new(150, 90).unwrap();
        let mut fb = FrameBuffers::new(&t, BufferSet::default());
        // Values across the curves' whole range, negatives, NaN and inf
        // included; 150 and 50 pixels wide exercise the 8-pixel path and
        // its scalar tail.
        let f = |i: usize, c: f32| match i % 97 {
            0 => f32::NAN,
            1 => f32::INFINITY,
            2 => -1.0,
            _ => ((i as f32 * 0.37 + c).sin() * 2.0).max(0.0) * (1 + i % 5) as f32,
        };
        for i in 0..fb.color.len() {
            fb.color.r[i] = f(i, 0.0);
            fb.color.g[i] = f(i, 1.0);
            fb.color.b[i] = f(i, 2.0);
        }
        for ssaa in [1, 3] {
            for tonemap in [Tonemap::Clamp, Tonemap::Reinhard, Tonemap::Aces] {
                let fused = Post::standard(ssaa, 0.5, tonemap);
                let mut staged = fused.clone();
                staged.fuse = false;
                let (a, b) = (fused.run(&fb).unwrap(), staged.run(&fb).unwrap());
                assert!(a.hdr.is_none() && b.hdr.is_some());
                assert_eq!((a.width, a.height), (150 / ssaa, 90 / ssaa));
                assert_eq!(a.ldr, b.ldr, "ssaa {ssaa} {tonemap:?}");
            }
        }
    }

    /// A custom stage for the tests: scales each pixel by a factor that
    /// depends on its position, so a stage that saw the wrong image, size
    /// or stale values would change the output.
    #[derive(Debug)]
    struct Ramp;

    impl PostStage for Ramp {
        fn name(&self) -> &str {
            "ramp"
        }

        fn apply(&self, img: &mut HdrImage, _frame: &FrameBuffers) {
            let w = img.width as usize;
            for p in [&mut img.rgb.r, &mut img.rgb.g, &mut img.rgb.b] {
                for (i, v) in p.iter_mut().enumerate() {
                    *v *= 0.5 + (i % w) as f32 / w as f32;
                }
            }
        }
    }

    #[test]
    fn fused_head_equals_the_stage_list_and_reuses_dirty_buffers() {
        let t = crate::Target::new(150, 90).unwrap();
        let mut fb = FrameBuffers::new(&t, BufferSet::default());
        for i in 0..fb.color.len() {
            let v = |c: f32| match i % 89 {
                0 => f32::NAN,
                1 => f32::INFINITY,
                2 => -0.5,
                _ => ((i as f32 * 0.23 + c).cos() * 1.7).abs() * (1 + i % 3) as f32,
            };
            fb.color.r[i] = v(0.0);
            fb.color.g[i] = v(1.0);
            fb.color.b[i] = v(2.0);
        }
        for ssaa in [1, 3] {
            for tonemap in [Tonemap::Clamp, Tonemap::Reinhard, Tonemap::Aces] {
                let mut fused = Post::standard(ssaa, -0.75, tonemap);
                let encode = fused.stages.pop().unwrap();
                fused.stages.push(Stage::Custom(std::sync::Arc::new(Ramp)));
                fused.stages.push(encode);
                let mut staged = fused.clone();
                staged.fuse = false;
                let want = staged.run(&fb).unwrap();
                // Buffers of another size full of garbage, as a recycled
                // frame of a different scene would leave.
                let dirty = || PostOutput {
                    width: 7,
                    height: 3,
                    hdr: Some(HdrImage {
                        width: 7,
                        height: 3,
                        rgb: Planes3 {
                            r: vec![9.0; 60_000],
                            g: vec![f32::NAN; 21],
                            b: vec![],
                        },
                    }),
                    ldr: Some(vec![0x5A; 100]),
                };
                for got in [
                    fused.run(&fb).unwrap(),
                    fused.run_reusing(&fb, dirty()).unwrap(),
                ] {
                    let tag = format!("ssaa {ssaa} {tonemap:?}");
                    assert_eq!((got.width, got.height), (150 / ssaa, 90 / ssaa), "{tag}");
                    assert!(got.hdr == want.hdr, "HDR image, {tag}");
                    assert!(got.ldr == want.ldr, "8-bit image, {tag}");
                }
                let staged_reused = staged.run_reusing(&fb, dirty()).unwrap();
                assert!(staged_reused.hdr == want.hdr && staged_reused.ldr == want.ldr);
            }
        }
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

    #[test]
    fn post_lists_are_checked() {
        let t = crate::Target::new(150, 90).unwrap();
        let fb = FrameBuffers::new(&t, BufferSet::default());
        let mut p = Post::standard(4, 0.0, Tonemap::Clamp);
        assert!(p.run(&fb).unwrap_err().contains("does not divide"));
        p.stages = vec![Stage::Encode, Stage::Tonemap(Tonemap::Clamp)];
        assert!(p.run(&fb).unwrap_err().contains("last"));
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
