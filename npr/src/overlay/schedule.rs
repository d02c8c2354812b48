//! How a frame's strokes are spread over threads and blended over the
//! image, with the same bytes whatever the thread count.
//!
//! The image's rows are cut into [`BANDS`] bands where the draws cost
//! least ([`band_rows`]: the cut depends on the draws alone); each band,
//! in parallel, draws every draw that reaches its rows, in drawing order,
//! on a surface of its own rows and a [`MARGIN`] (`draw_band`), then
//! blends its rows over the image. A draw over two bands is drawn by both,
//! each keeping its own rows.

use super::skia::{draw_band, draws, Draw};
use super::StrokeStyle;
use crate::edges::Polyline;
use rayon::prelude::*;
use specula_raster::buffers::prefetch;
use specula_raster::post::HdrImage;

/// How many bands of rows a frame's strokes are drawn in: a constant, so
/// the bytes do not depend on the thread count, and enough for the
/// threads of a desktop to share them out however the strokes lie.
const BANDS: usize = 8;

/// Rows a band's surface has beyond the rows it keeps, above and below: a
/// path crossing the surface's edge is clipped there, and the rows next to
/// a cut are where the coverage strays most from the whole image's (a
/// supersample or so, as `the_banded_stroke_drawing_is_close_to_one_surface_and_alike_for_any_thread_count`
/// in tests/lines.rs measures).
const MARGIN: usize = 2;

/// The band surfaces' bytes, kept from frame to frame (their allocations:
/// each is cleared before a frame draws on it).
#[derive(Debug, Default)]
pub struct Canvases {
    bands: Vec<Vec<u8>>,
}

impl Canvases {
    /// Draws `lines` in `style` over `img`: c = c·(1 − a) + colour·a with
    /// a the strokes' alpha, in bands of rows drawn in parallel.
    pub fn blend(&mut self, lines: &[Polyline], style: &StrokeStyle, img: &mut HdrImage) {
        let (w, h) = (img.width as usize, img.height as usize);
        if lines.is_empty() || w == 0 || h == 0 {
            return;
        }
        let draws = draws(lines, style, w, h);
        if draws.is_empty() {
            return;
        }
        let rows = band_rows(&draws, h, BANDS);
        self.bands.resize_with(rows.len() - 1, Vec::new);
        let color = style.color;
        split_bands(self.bands.iter_mut(), &rows, img)
            .into_par_iter()
            .for_each(|(kept, lo, hi, [r, g, b])| {
                let in_band = || draws.iter().filter(|d| d.rect[2] < hi && d.rect[3] > lo);
                // The rows the band's draws may change.
                let (y0, y1) = in_band().fold((hi, lo), |(y0, y1), d| {
                    (y0.min(d.rect[2]), y1.max(d.rect[3]))
                });
                let (y0, y1) = (y0.max(lo), y1.min(hi));
                if y0 >= y1 {
                    return;
                }
                // The surface: those rows and a margin, where tiny-skia's
                // clipping at the surface's edges leaves its marks.
                let (s0, s1) = (y0.saturating_sub(MARGIN), (y1 + MARGIN).min(h));
                let mut bytes = std::mem::take(kept);
                bytes.clear();
                bytes.resize(w * (s1 - s0), 0);
                let bytes = draw_band(bytes, w, s0..s1, in_band());
                if bytes.len() == w * (s1 - s0) {
                    let own = &bytes[(y0 - s0) * w..(y1 - s0) * w];
                    blend_rows(own, w, y0 - lo, [r, g, b], color);
                }
                *kept = bytes;
            });
    }
}

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

/// How many rows ahead [`blend_rows`] asks for the colour planes' lines.
const PREFETCH_ROWS: usize = 2;

/// Pixels a run of [`nonzero_runs`]: 64 bytes tested at once.
const RUN: usize = 64;

/// The runs of [`RUN`] pixels of a row of alpha holding a pixel with
/// coverage, as their first pixel.
fn nonzero_runs(row: &[u8]) -> impl Iterator<Item = usize> + '_ {
    row.chunks(RUN)
        .enumerate()
        .filter(|(_, px)| px.iter().fold(0, |acc, &a| acc | a) != 0)
        .map(|(i, _)| i * RUN)
}

/// c = c·(1 − a) + colour·a over the rows of `alpha` (`w` pixels a
/// row; the coverage, as [`draw`](super::draw)'s), which are the rows of
/// the colour planes from `first`. Only the runs with coverage are
/// blended, and the colour planes' lines under a later row's runs are
/// asked for ahead: they come from memory.
fn blend_rows(alpha: &[u8], w: usize, first: usize, [r, g, b]: [&mut [f32]; 3], color: [f32; 3]) {
    // a = alpha / 255, looked up: the same bits as the division.
    let unit: [f32; 256] = std::array::from_fn(|a| a as f32 / 255.0);
    let rows: Vec<&[u8]> = alpha.chunks_exact(w).collect();
    for (y, row) in rows.iter().enumerate() {
        if let Some(ahead) = rows.get(y + PREFETCH_ROWS) {
            let at = (first + y + PREFETCH_ROWS) * w;
            for x in nonzero_runs(ahead) {
                let px = at + x..at + (x + RUN).min(w);
                prefetch(&r[px.clone()]);
                prefetch(&g[px.clone()]);
                prefetch(&b[px]);
            }
        }
        let at = (first + y) * w;
        for x0 in nonzero_runs(row) {
            for (i, &c) in row[x0..(x0 + RUN).min(w)].iter().enumerate() {
                if c != 0 {
                    let (a, x) = (unit[c as usize], at + x0 + i);
                    r[x] = r[x] * (1.0 - a) + color[0] * a;
                    g[x] = g[x] * (1.0 - a) + color[1] * a;
                    b[x] = b[x] * (1.0 - a) + color[2] * a;
                }
            }
        }
    }
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
