//! How a frame's strokes are spread over threads and blended over the
//! image, with the same bytes whatever the thread count.
//!
//! With no hairline, every draw is filled on its own ([`raster`]: a worker
//! per canvas takes the costliest polyline left) and the coverages are
//! composed row by row in drawing order ([`compose_bands`]); with
//! hairlines, bands of rows each draw every draw that reaches them on
//! their own canvas ([`draw_bands`], the bands cut by [`band_rows`]).
//! Either way a pixel's alpha is the sequence of draws over it on one
//! surface, so the bytes are those of [`draw`](super::draw).

use super::coverage::{runs, Coverage};
use super::skia::{
    draw_of, draws, fill_local, lerp_alpha, no_hairlines, strokes_of, white, Canvas, Draw,
};
use super::StrokeStyle;
use crate::edges::Polyline;
use rayon::prelude::*;
use specula_raster::buffers::prefetch;
use specula_raster::post::HdrImage;
use std::sync::atomic::{AtomicUsize, Ordering};

/// How many rows ahead the blend asks for the colour planes' lines.
const PREFETCH_ROWS: usize = 2;

/// At most this many workers fill draws ([`raster`]) or bands of rows are
/// composed or drawn ([`compose_bands`], [`draw_bands`]) in parallel: a
/// canvas each, so at most this many image-sized canvases are kept.
const MAX_BANDS: usize = 4;

/// Splits rows `0..h` into at most `k` bands (returns the boundaries,
/// from 0 to h) so that the largest band cost is least, a band's cost
/// being that of every draw reaching its rows (a draw over two bands is
/// drawn by both).
fn band_rows(draws: &[Draw], h: usize, k: usize) -> Vec<usize> {
    // starts[y]: cost of the draws beginning above row y; ends[y]: of those
    // ending at or above it. A band [lo, hi) costs starts[hi] − ends[lo].
    let (mut starts, mut ends) = (vec![0.0f64; h + 1], vec![0.0f64; h + 1]);
    for d in draws {
        starts[d.rect[2] + 1] += d.cost;
        ends[d.rect[3]] += d.cost;
    }
    for y in 1..=h {
        starts[y] += starts[y - 1];
        ends[y] += ends[y - 1];
    }
    // Greedy bands of cost at most c: each as tall as fits (at least a
    // row); bisect on c for the least that needs at most k bands.
    let split = |c: f64| {
        let mut bounds = vec![0];
        let mut lo = 0;
        while lo < h {
            let fits = starts[lo + 1..=h].partition_point(|s| s - ends[lo] <= c);
            lo += fits.max(1);
            bounds.push(lo);
        }
        bounds
    };
    let (mut lo, mut hi) = (0.0, starts[h]);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if split(mid).len() <= k + 1 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    split(hi)
}

/// c = c·(1 − a) + colour·a over one span of pixels, a from the alpha
/// bytes of `px` (`BPP` bytes a pixel, alpha last; straight: the same a as
/// [`draw`](super::draw)'s), skipping the 8-pixel groups with no coverage.
fn blend_span<const BPP: usize>(
    px: &[u8],
    r: &mut [f32],
    g: &mut [f32],
    b: &mut [f32],
    color: [f32; 3],
) {
    let groups = px
        .chunks(8 * BPP)
        .zip(r.chunks_mut(8))
        .zip(g.chunks_mut(8))
        .zip(b.chunks_mut(8));
    for (((px, r), g), b) in groups {
        // A transparent (premultiplied) pixel is all zero bytes.
        if px.iter().fold(0, |acc, &byte| acc | byte) == 0 {
            continue;
        }
        for (((p, r), g), b) in px.chunks_exact(BPP).zip(r).zip(g).zip(b) {
            let alpha = p[BPP - 1];
            if alpha != 0 {
                let a = alpha as f32 / 255.0;
                *r = *r * (1.0 - a) + color[0] * a;
                *g = *g * (1.0 - a) + color[1] * a;
                *b = *b * (1.0 - a) + color[2] * a;
            }
        }
    }
}

/// [`blend_span`] over a row of alpha bytes, without branches (so it runs
/// 8 pixels at a time): where the alpha is 0 the pixel is kept as it is
/// (a select, not c·1 + colour·0, which would turn −0 into +0).
fn blend_alpha(px: &[u8], r: &mut [f32], g: &mut [f32], b: &mut [f32], color: [f32; 3]) {
    for (((&alpha, r), g), b) in px.iter().zip(r).zip(g).zip(b) {
        let a = alpha as f32 / 255.0;
        let keep = alpha == 0;
        let (nr, ng, nb) = (
            *r * (1.0 - a) + color[0] * a,
            *g * (1.0 - a) + color[1] * a,
            *b * (1.0 - a) + color[2] * a,
        );
        *r = if keep { *r } else { nr };
        *g = if keep { *g } else { ng };
        *b = if keep { *b } else { nb };
    }
}

/// The image-sized canvases the overlay draws on, kept from frame to
/// frame and transparent between frames.
#[derive(Debug, Default)]
pub struct Canvases {
    canvases: Vec<Canvas>,
    /// A worker's mask for the draws filled at their own size
    /// ([`fill_local`]).
    locals: Vec<Vec<u8>>,
}

impl Canvases {
    /// Draws `lines` in `style` over `img`: c = c·(1 − a) + colour·a with
    /// a the strokes' alpha, the same bytes as blending [`draw`](super::draw)'s
    /// coverage (see `draw_bands`).
    pub fn blend(&mut self, lines: &[Polyline], style: &StrokeStyle, img: &mut HdrImage) {
        let (w, h) = (img.width as usize, img.height as usize);
        if lines.is_empty() || w == 0 || h == 0 {
            return;
        }
        let k = rayon::current_num_threads().clamp(1, MAX_BANDS);
        if no_hairlines(style) {
            if !self.keep_canvases(k, img.width, img.height, false) {
                return;
            }
            let coverage = raster(&mut self.canvases, &mut self.locals, lines, style, w, h);
            compose_bands(k, &coverage, img, style.color);
        } else {
            let draws = draws(lines, style, w, h);
            if draws.is_empty() {
                return;
            }
            let rows = band_rows(&draws, h, k);
            let hairlines = draws.iter().any(|d| d.outline.is_none());
            if !self.keep_canvases(rows.len() - 1, img.width, img.height, hairlines) {
                return;
            }
            draw_bands(&mut self.canvases, &draws, &rows, img, style.color);
        }
    }

    /// Keeps `k` canvases of `w × h` pixels, pixmaps if `hairlines` else
    /// masks (the canvas's `Surface`); false if they cannot be made.
    fn keep_canvases(&mut self, k: usize, w: u32, h: u32, hairlines: bool) -> bool {
        let canvases = &mut self.canvases;
        canvases.retain(|c| c.surface.size() == (w, h) && c.surface.hairlines() == hairlines);
        while canvases.len() < k {
            let Some(c) = Canvas::new(w, h, hairlines) else {
                return false;
            };
            canvases.push(c);
        }
        canvases.truncate(k);
        true
    }
}

/// Strokes and fills every draw of `lines` in `style` (no hairline:
/// [`no_hairlines`]) on a `w × h` image on its own, in parallel, each on
/// a transparent mask, and returns their coverage in drawing order. A
/// worker per canvas takes the next polyline, costliest first (its points
/// and rows), until none is left: no draw is filled twice, and which
/// worker fills a draw does not change its bytes.
///
/// A fill blends each pixel at most once (tiny-skia's supersampling
/// blitter flushes a pixel row once, one run per pixel; its non-AA and
/// tiled paths write disjoint spans), so on a transparent mask it leaves
/// the pixel's coverage c itself: lerp(0, 255, c) = ⌊255·(c + 1)/256⌋ = c
/// for c < 255, and 255 for c = 255 ([`lerp_alpha`]).
fn raster(
    canvases: &mut [Canvas],
    locals: &mut Vec<Vec<u8>>,
    lines: &[Polyline],
    style: &StrokeStyle,
    w: usize,
    h: usize,
) -> Vec<Coverage> {
    let cost = |l: &Polyline| {
        let (lo, hi) = l
            .points
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p[1]), hi.max(p[1]))
            });
        l.points.len() as f32 + (hi - lo).clamp(0.0, h as f32)
    };
    let costs: Vec<f32> = lines.iter().map(cost).collect();
    let mut order: Vec<usize> = (0..lines.len()).collect();
    order.sort_by(|&a, &b| costs[b].total_cmp(&costs[a]).then(a.cmp(&b)));
    let next = AtomicUsize::new(0);
    let paint = white();
    locals.resize_with(canvases.len(), Vec::new);
    let filled: Vec<Vec<(usize, Vec<Coverage>)>> = canvases
        .par_iter_mut()
        .zip(locals.par_iter_mut())
        .map(|(canvas, local)| {
            let mut out = Vec::new();
            while let Some(&j) = order.get(next.fetch_add(1, Ordering::Relaxed)) {
                let mut of_line = Vec::new();
                for (centre, stroke) in strokes_of(&lines[j], style) {
                    debug_assert!(stroke.width > 1.0, "a hairline on masks");
                    let Some(d) = draw_of(centre, stroke, w, h) else {
                        continue;
                    };
                    of_line.push(if d.local {
                        fill_local(&d, local)
                    } else {
                        canvas.draw(&d, &paint);
                        canvas.take()
                    });
                }
                out.push((j, of_line));
            }
            out
        })
        .collect();
    let mut by_line: Vec<Vec<Coverage>> = (0..lines.len()).map(|_| Vec::new()).collect();
    for (j, c) in filled.into_iter().flatten() {
        by_line[j] = c;
    }
    by_line.into_iter().flatten().collect()
}

/// Blends `coverage` (the draws' own, [`raster`], in drawing order) over
/// `img` in `color`.
///
/// Row by row, in bands of rows run in parallel: a row's coverage spans
/// are lerped, draw after draw in drawing order, into a row of alpha
/// ([`lerp_alpha`], the very step the fill would have done on one mask),
/// whose touched 8-pixel chunks are then blended and cleared. A pixel's
/// alpha is then the sequence of draws over it on one mask, whatever the
/// bands; and a row of alpha stays in cache, where an image-sized one
/// would bring in a line per row.
fn compose_bands(k: usize, coverage: &[Coverage], img: &mut HdrImage, color: [f32; 3]) {
    let (w, h) = (img.width as usize, img.height as usize);
    // The spans as (draw, span) by row, each row's in drawing order: a
    // counting sort on the row; and the rows' bytes, to cut the bands.
    let mut start = vec![0usize; h + 2];
    let mut bytes = vec![0usize; h + 1];
    for c in coverage {
        for (y, _, a) in c.rows(0, h) {
            start[y + 2] += 1;
            bytes[y + 1] += a.len();
        }
    }
    for y in 1..=h {
        start[y + 1] += start[y];
        bytes[y] += bytes[y - 1];
    }
    let mut by_row = vec![(0u32, 0u32); start[h + 1]];
    for (j, c) in coverage.iter().enumerate() {
        for (i, s) in c.spans.iter().enumerate() {
            let y = s[0] as usize;
            if y < h {
                by_row[start[y + 1]] = (j as u32, i as u32);
                start[y + 1] += 1;
            }
        }
    }
    // Now row y's spans are by_row[start[y]..start[y + 1]].
    let rows: Vec<usize> = (0..=k)
        .map(|i| match i {
            0 => 0,
            _ if i == k => h,
            _ => bytes.partition_point(|&b| b * k < bytes[h] * i).min(h),
        })
        .collect();
    let words = w.div_ceil(8).div_ceil(64);
    split_bands(0..k, &rows, img)
        .into_par_iter()
        .for_each(|(_, lo, hi, [r, g, b])| {
            let (mut alpha, mut marks) = (vec![0u8; w], vec![0u64; words]);
            // The spans of the row at hand, looked up once.
            let mut here: Vec<(usize, &[u8])> = Vec::new();
            let spans = |y: usize| {
                by_row[start[y]..start[y + 1]].iter().map(|&(j, i)| {
                    let c = &coverage[j as usize];
                    let [_, x, at] = c.spans[i as usize];
                    let end = c
                        .spans
                        .get(i as usize + 1)
                        .map_or(c.alpha.len(), |s| s[2] as usize);
                    (x as usize, &c.alpha[at as usize..end])
                })
            };
            for y in lo..hi {
                // The colour planes' lines of a later row, ahead: they
                // come from memory, one row crossing of a line at a time.
                let ahead = y + PREFETCH_ROWS;
                // A span's first and last pixels' lines (most spans are a
                // few pixels of a ring's side; the hardware prefetcher
                // follows the long ones).
                if ahead < hi {
                    let at = (ahead - lo) * w;
                    for (x, a) in spans(ahead) {
                        let (first, last) = (at + x, at + x + a.len().max(1) - 1);
                        for p in [&r[..], &g[..], &b[..]] {
                            prefetch(&p[first]);
                            prefetch(&p[last]);
                        }
                    }
                }
                let row = (y - lo) * w;
                here.clear();
                here.extend(spans(y));
                // The spans' 8-pixel chunks marked; whether two spans share
                // a chunk.
                let mut shared = false;
                for &(x, a) in &here {
                    for c in x / 8..(x + a.len()).div_ceil(8) {
                        shared |= marks[c / 64] & 1 << (c % 64) != 0;
                        marks[c / 64] |= 1 << (c % 64);
                    }
                }
                // Spans that share no chunk (most rows: the sides of the
                // rings a row crosses) share no pixel, and a pixel under one
                // span only has that span's coverage as its alpha
                // (lerp_alpha(0, c) = c): they blend straight from their
                // own bytes, without the row of alpha and its clearing.
                if !shared {
                    for &(x, a) in &here {
                        let px = row + x..row + x + a.len();
                        let (r, g, b) = (&mut r[px.clone()], &mut g[px.clone()], &mut b[px]);
                        blend_alpha(a, r, g, b, color);
                    }
                    marks.fill(0);
                    continue;
                }
                for &(x, a) in &here {
                    lerp_alpha(&mut alpha[x..x + a.len()], a);
                }
                for x in runs(&marks, w) {
                    let (r, g, b) = (
                        &mut r[row + x.start..row + x.end],
                        &mut g[row + x.start..row + x.end],
                        &mut b[row + x.start..row + x.end],
                    );
                    blend_alpha(&alpha[x.clone()], r, g, b, color);
                    alpha[x].fill(0);
                }
                marks.fill(0);
            }
        });
}

/// The items paired with consecutive bands of rows (`rows`, from 0 to the
/// height) and those rows of `img`'s colour planes.
#[allow(clippy::type_complexity)]
fn split_bands<'b, T>(
    items: impl IntoIterator<Item = T>,
    rows: &[usize],
    img: &'b mut HdrImage,
) -> Vec<(T, usize, usize, [&'b mut [f32]; 3])> {
    let w = img.width as usize;
    let mut bands = Vec::with_capacity(rows.len() - 1);
    let (mut r, mut g, mut b) = (&mut img.rgb.r[..], &mut img.rgb.g[..], &mut img.rgb.b[..]);
    for (i, item) in items.into_iter().enumerate().take(rows.len() - 1) {
        let n = (rows[i + 1] - rows[i]) * w;
        let (r0, r1) = std::mem::take(&mut r).split_at_mut(n);
        let (g0, g1) = std::mem::take(&mut g).split_at_mut(n);
        let (b0, b1) = std::mem::take(&mut b).split_at_mut(n);
        (r, g, b) = (r1, g1, b1);
        bands.push((item, rows[i], rows[i + 1], [r0, g0, b0]));
    }
    bands
}

/// Draws `draws` (hairlines among them) in bands of rows (`rows`)
/// drawn in parallel, each on its own image-sized canvas: a band draws,
/// in order, every draw that reaches its rows, at the draw's own image
/// coordinates (so tiny-skia sees the very same paths and clip as on one
/// pixmap), then blends its own rows. A pixel's alpha is then the same
/// sequence of draws over it as on one pixmap, whatever the bands: the
/// bytes do not depend on the thread count. A draw that spans two bands is
/// drawn by both; the bands are cut where that costs least
/// ([`band_rows`]).
fn draw_bands(
    canvases: &mut [Canvas],
    draws: &[Draw],
    rows: &[usize],
    img: &mut HdrImage,
    color: [f32; 3],
) {
    let paint = white();
    split_bands(canvases.iter_mut(), rows, img)
        .into_par_iter()
        .for_each(|(canvas, lo, hi, planes)| {
            for d in draws.iter().filter(|d| d.rect[2] < hi && d.rect[3] > lo) {
                canvas.draw(d, &paint);
            }
            blend_band(canvas, lo, hi, planes, color);
        });
}

/// Blends the alpha of `canvas`'s marked chunks in rows [lo, hi) over
/// those rows of the colour planes (`[r, g, b]`, the band's rows only),
/// clearing the canvas as it goes (and, after, any marks outside the rows:
/// a draw over two bands is drawn whole by each).
fn blend_band(
    canvas: &mut Canvas,
    lo: usize,
    hi: usize,
    [r, g, b]: [&mut [f32]; 3],
    color: [f32; 3],
) {
    let w = canvas.surface.size().0 as usize;
    let bpp = canvas.surface.bpp();
    let [y0, y1] = [canvas.rows[0].max(lo), canvas.rows[1].min(hi)];
    for y in y0..y1 {
        // The colour planes' lines of a later row, ahead: they come
        // from memory, one row crossing of a line at a time.
        let ahead = y + PREFETCH_ROWS;
        if ahead < y1 {
            for x in canvas.spans(ahead) {
                let at = (ahead - lo) * w;
                prefetch(&r[at + x.start..at + x.end]);
                prefetch(&g[at + x.start..at + x.end]);
                prefetch(&b[at + x.start..at + x.end]);
            }
        }
        canvas.take_marks(y);
        let data = canvas.surface.data_mut();
        let row = (y - lo) * w;
        for x in runs(&canvas.row, w) {
            let (r, g, b) = (
                &mut r[row + x.start..row + x.end],
                &mut g[row + x.start..row + x.end],
                &mut b[row + x.start..row + x.end],
            );
            let px = &mut data[(y * w + x.start) * bpp..(y * w + x.end) * bpp];
            match bpp {
                4 => blend_span::<4>(px, r, g, b, color),
                _ => blend_span::<1>(px, r, g, b, color),
            }
            px.fill(0);
        }
    }
    let [r0, r1] = canvas.rows;
    canvas.clear_rows(r0..y0.max(r0));
    canvas.clear_rows(y1.max(r0)..r1);
    canvas.rows = [canvas.surface.size().1 as usize, 0];
}
