//! Everything the overlay asks of tiny-skia: the strokes of a polyline,
//! the draws they make and the rows each may change, the plain drawing
//! [`draw`], and (in `band`) a band of rows filled on a mask; `stroker`
//! makes the outline of a gentle polyline itself. The only module of the
//! overlay that names tiny-skia types; [`LineCap`] and [`LineJoin`] are
//! re-exported as the style's.
//!
//! Only tiny-skia's documented operations are used: `Path::stroke` (the
//! outline of a stroke), `Mask::fill_path` and translations. Every stroke,
//! however thin, is filled as its outline, so its coverage is the area
//! it covers (tiny-skia's `stroke_path` would draw one of at most 1 px as
//! a hairline, another way). Which bytes tiny-skia writes is its own
//! affair: nothing here assumes two ways of drawing give the same bytes.
//! A band of rows is drawn on a surface of its own with the paths moved
//! up, so the overlay's bytes depend on where the bands are cut
//! (`schedule`), which depends on the draws alone, never on the thread
//! count. The one geometric assumption, that an anti-aliased fill changes
//! no pixel its path does not overlap, picks the draws a band draws
//! ([`Draw::rect`]); `a_draw_changes_only_pixels_within_its_rectangle`
//! checks it.

mod band;
mod stroker;

pub(super) use band::draw_band;
use stroker::gentle_outline;

use super::StrokeStyle;
use crate::edges::Polyline;
use rayon::prelude::*;
pub use tiny_skia::{LineCap, LineJoin};
use tiny_skia::{Path, PathBuilder, Stroke};

/// The tiny-skia strokes that draw `line`, in order: the whole polyline,
/// or with a taper one round-capped segment at a time, each at the width
/// of its middle's distance (along the line) from the nearer end.
pub(super) fn strokes_of(line: &Polyline, style: &StrokeStyle) -> Vec<(Path, Stroke)> {
    let stroke = |w: f32| Stroke {
        width: w,
        line_cap: style.cap,
        line_join: style.join,
        ..Stroke::default()
    };
    let mut out = Vec::new();
    if line.points.len() < 2 {
        return out;
    }
    if style.taper > 0.0 && !line.closed {
        let seg_len =
            |a: [f32; 2], b: [f32; 2]| ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        let total: f32 = line.points.windows(2).map(|w| seg_len(w[0], w[1])).sum();
        let mut s = 0.0;
        for w in line.points.windows(2) {
            let len = seg_len(w[0], w[1]);
            let mid = s + len * 0.5;
            s += len;
            let u = if total > 0.0 {
                (mid.min(total - mid) / (total * 0.5)).clamp(0.0, 1.0)
            } else {
                1.0
            };
            let wd = style.width * ((1.0 - style.taper) + style.taper * u);
            let mut pb = PathBuilder::new();
            pb.move_to(w[0][0], w[0][1]);
            pb.line_to(w[1][0], w[1][1]);
            if let (Some(path), true) = (pb.finish(), wd > 0.0) {
                let mut st = stroke(wd);
                st.line_cap = LineCap::Round;
                out.push((path, st));
            }
        }
        return out;
    }
    // (Sized up front: the verbs are a move, the lines and a close.)
    let mut pb = PathBuilder::with_capacity(line.points.len() + 1, line.points.len());
    pb.move_to(line.points[0][0], line.points[0][1]);
    for p in &line.points[1..] {
        pb.line_to(p[0], p[1]);
    }
    if line.closed {
        pb.close();
    }
    if let Some(path) = pb.finish() {
        out.push((path, stroke(style.width)));
    }
    out
}

/// Stroke coverage (alpha in [0, 1]) of `lines` on a `width × height`
/// image, row-major: every stroke's outline filled in order on one mask
/// of the whole image, as a band fills them, with the image as its one
/// band. The plain form of what [`Strokes`](super::Strokes) draws, which
/// cuts the image into bands.
pub fn draw(lines: &[Polyline], style: &StrokeStyle, width: u32, height: u32) -> Vec<f32> {
    let (w, h) = (width as usize, height as usize);
    let draws = draws(lines, style, w, h);
    let bytes = draw_band(vec![0; w * h], w, 0..h, &draws);
    if bytes.len() != w * h {
        return vec![0.0; w * h];
    }
    bytes.iter().map(|&a| a as f32 / 255.0).collect()
}

/// One tiny-skia draw of the overlay and the pixels it may change.
pub(super) struct Draw {
    /// The stroke's outline ([`outline_of`]), filled with the winding rule.
    pub(super) outline: Path,
    /// [x0, x1) × [y0, y1) within the image, holding every pixel the draw
    /// can change: the outline's bounds rounded out and widened by a pixel.
    /// (Not w/2 about the centre line: a miter-clip join can reach far
    /// beyond it.)
    pub(super) rect: [usize; 4],
    /// A drawing cost estimate: the points tiny-skia scans and the rows.
    pub(super) cost: f64,
}

/// The draws of `lines` in drawing order (outlines stroked in parallel,
/// each on its own) on a `w × h` image; draws that cannot touch the image
/// are left out.
pub(super) fn draws(lines: &[Polyline], style: &StrokeStyle, w: usize, h: usize) -> Vec<Draw> {
    let per_line: Vec<Vec<Draw>> = lines
        .par_iter()
        .map(|l| {
            strokes_of(l, style)
                .into_iter()
                .filter_map(|(centre, stroke)| draw_of(centre, stroke, w, h))
                .collect()
        })
        .collect();
    per_line.into_iter().flatten().collect()
}

/// The draw of one stroke on a `w × h` image (the outline stroked), None
/// if it cannot touch the image.
pub(super) fn draw_of(centre: Path, stroke: Stroke, w: usize, h: usize) -> Option<Draw> {
    let outline = outline_of(&centre, &stroke)?;
    let b = outline.bounds();
    let clamp = |v: f32, hi: usize| (v.max(0.0) as usize).min(hi);
    let rect = [
        clamp((b.left() - 1.0).floor(), w),
        clamp((b.right() + 1.0).ceil(), w),
        clamp((b.top() - 1.0).floor(), h),
        clamp((b.bottom() + 1.0).ceil(), h),
    ];
    (rect[0] < rect[1] && rect[2] < rect[3]).then(|| Draw {
        cost: (outline.len() + rect[3] - rect[2]) as f64,
        outline,
        rect,
    })
}

/// The outline a stroke is filled as: a polyline whose turns are all
/// gentle, [`gentle_outline`]; any other, tiny-skia's stroker
/// (`Path::stroke` at resolution scale 1: a unit is a pixel).
fn outline_of(centre: &Path, stroke: &Stroke) -> Option<Path> {
    gentle_outline(centre, stroke).or_else(|| centre.stroke(stroke, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::edges::EdgeKind;

    /// Floats in [0, 1) from a xorshift* generator seeded with `state`:
    /// the tests' random strokes and polygons, the same on every machine.
    pub(super) fn unit_floats(mut state: u64) -> impl FnMut() -> f32 {
        move || {
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// A polyline of 2 to 1 + `count` points from a point in the `size`
    /// box, each step short or long (`steps`) at random, so sharp turns
    /// and long runs mix.
    fn random_walk(
        next: &mut impl FnMut() -> f32,
        size: [f32; 2],
        count: f32,
        steps: [f32; 2],
    ) -> Vec<[f32; 2]> {
        let mut p = [next() * size[0], next() * size[1]];
        (0..2 + (next() * count) as usize)
            .map(|_| {
                let step = if next() < 0.5 { steps[0] } else { steps[1] };
                p = [p[0] + (next() - 0.5) * step, p[1] + (next() - 0.5) * step];
                p
            })
            .collect()
    }

    /// Distance from `p` to the segment a–b.
    pub(super) fn to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let l2 = dx * dx + dy * dy;
        let t = if l2 > 0.0 {
            (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
    }

    #[test]
    fn a_draw_changes_only_pixels_within_its_rectangle() {
        // Random walks (sharp turns and long runs) in every join, cap and
        // width, thin ones and tapers included, many running off the
        // image: each draw drawn alone on a surface of the whole image
        // changes no pixel outside its `rect`, so a band that leaves out
        // the draws whose rectangle misses its rows loses nothing.
        let mut next = unit_floats(0x9e37_79b9_7f4a_7c15u64);
        let (w, h) = (120usize, 90usize);
        let (mut drawn, mut outside_rows) = (0, 0);
        for case in 0..96 {
            let style = StrokeStyle {
                width: [0.6, 1.0, 1.5, 2.5, 6.0, 13.0][case % 6],
                color: [0.0; 3],
                taper: if case % 5 == 0 { 0.7 } else { 0.0 },
                join: [
                    LineJoin::Round,
                    LineJoin::Bevel,
                    LineJoin::Miter,
                    LineJoin::MiterClip,
                ][case / 6 % 4],
                cap: [LineCap::Butt, LineCap::Round, LineCap::Square][case / 24 % 3],
            };
            let points = random_walk(&mut next, [w as f32, h as f32], 12.0, [2.0, 60.0]);
            let line = Polyline {
                kind: EdgeKind::Silhouette,
                points,
                closed: case % 4 == 1,
            };
            for d in draws(&[line], &style, w, h) {
                let bytes = draw_band(vec![0; w * h], w, 0..h, [&d]);
                let [x0, x1, y0, y1] = d.rect;
                outside_rows += h - (y1 - y0);
                for (i, &a) in bytes.iter().enumerate() {
                    let (x, y) = (i % w, i / w);
                    drawn += usize::from(a != 0);
                    assert!(
                        a == 0 || (x0..x1).contains(&x) && (y0..y1).contains(&y),
                        "case {case}: pixel ({x}, {y}) outside {:?}",
                        d.rect
                    );
                }
            }
        }
        // Many pixels drawn, and rectangles that leave out many rows.
        assert!(
            drawn > 20_000 && outside_rows > 2_000,
            "{drawn} drawn, {outside_rows} rows left out"
        );
    }
}
