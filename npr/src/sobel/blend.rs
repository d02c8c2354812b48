//! The line over the image: the marks widened to the line's coverage
//! (by [`crate::dilate`]) and blended in the outline colour, row by row
//! in bands of rows straight into the image.

use super::{prefetch, Buffers, RowsScratch, Sobel};
use crate::dilate::{dilate, dilate_row, dilate_row_lanes, Cover, EdgeMask, Ink, BOUNDED_RADIUS};
use crate::outline::{blend, blend_row, composite, sum_samples};
use rayon::prelude::*;
use specula_raster::post::HdrImage;
use specula_raster::FrameBuffers;
use wide::f32x8;

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

/// Output rows a blend task takes at once.
const BLEND_ROWS: usize = 8;

impl Sobel {
    /// [`PostStage::apply`](specula_raster::post::PostStage::apply) with the
    /// stage's buffers `b`.
    pub(super) fn blend(
        &self,
        img: &mut HdrImage,
        frame: &FrameBuffers,
        ssaa: usize,
        b: &mut Buffers,
    ) {
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
