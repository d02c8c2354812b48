//! The image-sized tiny-skia surfaces the overlay draws on, and which of
//! their 8-pixel row chunks a frame's draws may have touched.

use super::Draw;
use crate::overlay::coverage::{runs, Coverage};
use specula_raster::buffers::prefetch;
use tiny_skia::{FillRule, Mask, Paint, PathSegment, Pixmap, Transform};

/// What a canvas stores: tiny-skia's RGBA pixmap, whose alpha is the
/// coverage, or an alpha-only mask (a quarter of the bytes to bring in,
/// blend and clear), which takes only filled paths: a frame with a
/// hairline (a stroke of at most 1 px, which tiny-skia draws without
/// filling an outline) uses the pixmap. A mask's `fill_path` runs the same
/// lerp on the alpha channel as the pixmap's (load, lerp by coverage,
/// store: `lowp` stages in both, the same `div255`), so the alpha bytes
/// are the same; checked by the banded-drawing test, which has frames of
/// both kinds.
#[derive(Debug)]
pub(in crate::overlay) enum Surface {
    Rgba(Pixmap),
    Alpha(Mask),
}

impl Surface {
    pub(in crate::overlay) fn new(w: u32, h: u32, hairlines: bool) -> Option<Surface> {
        Some(if hairlines {
            Surface::Rgba(Pixmap::new(w, h)?)
        } else {
            Surface::Alpha(Mask::new(w, h)?)
        })
    }

    pub(in crate::overlay) fn size(&self) -> (u32, u32) {
        match self {
            Surface::Rgba(p) => (p.width(), p.height()),
            Surface::Alpha(m) => (m.width(), m.height()),
        }
    }

    pub(in crate::overlay) fn hairlines(&self) -> bool {
        matches!(self, Surface::Rgba(_))
    }

    /// Bytes per pixel; a pixel's alpha is its last byte.
    pub(in crate::overlay) fn bpp(&self) -> usize {
        match self {
            Surface::Rgba(_) => 4,
            Surface::Alpha(_) => 1,
        }
    }

    pub(in crate::overlay) fn data(&self) -> &[u8] {
        match self {
            Surface::Rgba(p) => p.data(),
            Surface::Alpha(m) => m.data(),
        }
    }

    pub(in crate::overlay) fn data_mut(&mut self) -> &mut [u8] {
        match self {
            Surface::Rgba(p) => p.data_mut(),
            Surface::Alpha(m) => m.data_mut(),
        }
    }

    pub(in crate::overlay) fn draw(&mut self, d: &Draw, paint: &Paint) {
        let id = Transform::identity();
        match (self, &d.outline) {
            (Surface::Rgba(pm), Some(p)) => pm.fill_path(p, paint, FillRule::Winding, id, None),
            (Surface::Alpha(m), Some(p)) => m.fill_path(p, FillRule::Winding, true, id),
            (Surface::Rgba(pm), None) => pm.stroke_path(&d.centre, paint, &d.stroke, id, None),
            // A frame with hairlines draws on pixmaps (`draw_bands`).
            (Surface::Alpha(_), None) => {}
        }
    }
}

/// An image-sized surface the overlay draws on, transparent between
/// frames, and which of its 8-pixel row chunks a frame's draws may have
/// touched ([`Canvas::mark`]).
#[derive(Debug)]
pub(in crate::overlay) struct Canvas {
    pub(in crate::overlay) surface: Surface,
    /// One bit per 8-pixel chunk of a row, `words` u64 a row.
    touched: Vec<u64>,
    words: usize,
    /// Rows that may hold touched chunks.
    pub(in crate::overlay) rows: [usize; 2],
    /// One row's marks, taken off `touched` while the row is cleared.
    pub(in crate::overlay) row: Vec<u64>,
}

impl Canvas {
    pub(in crate::overlay) fn new(w: u32, h: u32, hairlines: bool) -> Option<Canvas> {
        let words = (w as usize).div_ceil(8).div_ceil(64);
        Some(Canvas {
            surface: Surface::new(w, h, hairlines)?,
            touched: vec![0; words * h as usize],
            words,
            rows: [h as usize, 0],
            row: Vec::with_capacity(words),
        })
    }

    /// Marks the chunks `d` may change ([`Canvas::mark`]), asking the cache
    /// for their pixels, and draws `d`.
    pub(in crate::overlay) fn draw(&mut self, d: &Draw, paint: &Paint) {
        self.mark(d);
        self.surface.draw(d, paint);
    }

    /// Marks the chunks of `d`'s rectangle that `d` can change: with a
    /// known reach, per row those within `reach` of a centre-line segment
    /// (the segment's part in the rows within `reach` of the row, widened
    /// by `reach`), else the whole rectangle.
    fn mark(&mut self, d: &Draw) {
        let [x0, x1, y0, y1] = d.rect;
        self.rows = [self.rows[0].min(y0), self.rows[1].max(y1)];
        let finite = d.centre.bounds().left().is_finite() && d.centre.bounds().right().is_finite();
        let Some(reach) = d.reach.filter(|_| finite) else {
            for y in y0..y1 {
                self.mark_row(y, x0, x1);
            }
            return;
        };
        let clamp = |v: f32, lo: usize, hi: usize| (v.max(lo as f32) as usize).clamp(lo, hi);
        let (mut start, mut last) = (None, tiny_skia::Point::zero());
        for seg in d.centre.segments() {
            let (a, b) = match seg {
                PathSegment::MoveTo(p) => {
                    (start, last) = (Some(p), p);
                    continue;
                }
                PathSegment::LineTo(p) => (last, p),
                PathSegment::Close => match start {
                    Some(s) => (last, s),
                    None => continue,
                },
                // Not made by `strokes_of`; whole rectangle to be safe.
                _ => {
                    for y in y0..y1 {
                        self.mark_row(y, x0, x1);
                    }
                    return;
                }
            };
            last = b;
            let (lo, hi) = (a.y.min(b.y), a.y.max(b.y));
            for y in clamp((lo - reach).floor(), y0, y1)..clamp((hi + reach).ceil() + 1.0, y0, y1) {
                // The segment's x extent over the rows [y − reach, y + 1 + reach].
                let (s0, s1) = (y as f32 - reach, y as f32 + 1.0 + reach);
                let (t0, t1) = if b.y != a.y {
                    let (u, v) = ((s0 - a.y) / (b.y - a.y), (s1 - a.y) / (b.y - a.y));
                    (u.min(v).max(0.0), u.max(v).min(1.0))
                } else {
                    (0.0, 1.0)
                };
                if t0 > t1 {
                    continue;
                }
                let (xa, xb) = (a.x + (b.x - a.x) * t0, a.x + (b.x - a.x) * t1);
                self.mark_row(
                    y,
                    clamp((xa.min(xb) - reach).floor(), x0, x1),
                    clamp((xa.max(xb) + reach).ceil(), x0, x1),
                );
            }
        }
    }

    /// Marks the chunks holding pixels [x0, x1) of row `y` and asks the
    /// cache for their pixels: the canvas is cold when a frame starts
    /// (the frame's other passes evicted it), and tiny-skia reads each
    /// pixel it blends into one run at a time, so its loads from memory
    /// would otherwise come one after the other.
    fn mark_row(&mut self, y: usize, x0: usize, x1: usize) {
        if x0 >= x1 {
            return;
        }
        let row = &mut self.touched[y * self.words..][..self.words];
        for c in x0 / 8..x1.div_ceil(8) {
            row[c / 64] |= 1 << (c % 64);
        }
        let (w, bpp) = (self.surface.size().0 as usize, self.surface.bpp());
        prefetch(&self.surface.data()[(y * w + x0) * bpp..(y * w + x1) * bpp]);
    }

    /// The touched pixels of row `y` as ranges, left to right: runs of
    /// touched chunks.
    pub(in crate::overlay) fn spans(
        &self,
        y: usize,
    ) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
        let w = self.surface.size().0 as usize;
        runs(&self.touched[y * self.words..][..self.words], w)
    }

    /// Row `y`'s marks, moved into `self.row` (cleared on the canvas).
    pub(in crate::overlay) fn take_marks(&mut self, y: usize) {
        let marks = &mut self.touched[y * self.words..][..self.words];
        self.row.clear();
        self.row.extend_from_slice(marks);
        marks.fill(0);
    }

    /// Clears the marked chunks of `rows` and their marks.
    pub(in crate::overlay) fn clear_rows(&mut self, rows: std::ops::Range<usize>) {
        let (w, bpp) = (self.surface.size().0 as usize, self.surface.bpp());
        for y in rows {
            self.take_marks(y);
            let data = self.surface.data_mut();
            for r in runs(&self.row, w) {
                data[(y * w + r.start) * bpp..(y * w + r.end) * bpp].fill(0);
            }
        }
    }

    /// The alpha of the marked chunks as a [`Coverage`] (each span trimmed
    /// to its nonzero bytes), leaving the canvas transparent and unmarked.
    /// (A mask's: one byte a pixel.)
    pub(in crate::overlay) fn take(&mut self) -> Coverage {
        let w = self.surface.size().0 as usize;
        let mut c = Coverage::default();
        for y in self.rows[0]..self.rows[1] {
            self.take_marks(y);
            let data = self.surface.data_mut();
            for r in runs(&self.row, w) {
                let px = &mut data[y * w + r.start..y * w + r.end];
                if let Some(first) = px.iter().position(|&a| a != 0) {
                    let last = px.iter().rposition(|&a| a != 0).unwrap_or(first);
                    c.spans
                        .push([y as u32, (r.start + first) as u32, c.alpha.len() as u32]);
                    c.alpha.extend_from_slice(&px[first..=last]);
                    px[first..=last].fill(0);
                }
            }
        }
        self.rows = [self.surface.size().1 as usize, 0];
        c
    }
}
