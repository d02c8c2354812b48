//! Everything the overlay asks of tiny-skia: the strokes of a polyline,
//! the draws they make and the pixels each may change, the reference
//! drawing [`draw`], fills at a draw's own size, and (in `canvas`) the
//! pixmaps and masks drawn on; `stroker` makes the outline of a gentle
//! polyline itself. The only module of the overlay that names tiny-skia
//! types; [`LineCap`] and [`LineJoin`] are re-exported as the style's.
//!
//! The byte-exact drawing elsewhere (fills at their own size, coverages
//! composed in another order, bands) rests on tiny-skia behaviour that is
//! not part of its documented API, read from its source (0.12):
//! - `Pixmap::stroke_path` with the identity transform fills, with the
//!   winding rule, the outline `Path::stroke` makes at resolution scale 1
//!   when the stroke is wider than 1 px, and draws a coverage-modulated
//!   hairline otherwise ([`Draw::outline`], [`no_hairlines`]). Pinned by
//!   `the_banded_stroke_drawing_gives_the_bytes_of_one_pixmap_for_any_thread_count`
//!   (tests/lines.rs), which compares outline fills with `stroke_path`.
//! - A fill writes only within the path's bounds rounded out, and a
//!   hairline within 1 px of its line ([`Draw::rect`], [`reach`]). Pinned by
//!   `a_draw_changes_only_pixels_within_its_reach_of_the_centre_line` and
//!   the banded-drawing test.
//! - Fixed-point rounding: points become fixed point by a power-of-two
//!   scale and truncation, and the edges are then stepped in integers
//!   relative to their ends, so a path moved by whole pixels fills the
//!   same bytes, moved ([`fill_local`]). Pinned by
//!   `a_local_fill_gives_the_bytes_of_the_image_sized_fill`.
//! - `DrawTiler`: a target 8192 px or more wide or tall (its supersampled
//!   fixed point would overflow) is filled in tiles that each clip the
//!   path, so fills at their own size are kept to smaller images
//!   ([`TILED`]). No test pins this threshold: none draws an image that
//!   large.
//! - A fill blends each pixel at most once, and the `lowp` pipeline's
//!   blend is a lerp with div255(v) = (v + 255) >> 8 ([`lerp_alpha`]), so
//!   fills made each on a transparent mask and composed in order give the
//!   bytes of one mask. Pinned by
//!   `fills_composed_from_their_own_coverage_give_the_bytes_of_one_mask`.
//! - A mask's `fill_path` leaves the alpha bytes a pixmap's does (the same
//!   `lowp` stages; `canvas`'s `Surface`). Pinned by the banded-drawing
//!   test, which has frames drawn on both.

mod canvas;
mod stroker;

pub(super) use canvas::Canvas;
use stroker::gentle_outline;

use super::coverage::{push_runs, Coverage};
use super::StrokeStyle;
use crate::edges::Polyline;
use rayon::prelude::*;
use tiny_skia::{FillRule, Mask, Paint, Path, PathBuilder, Pixmap, Stroke, Transform};
pub use tiny_skia::{LineCap, LineJoin};

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

/// Opaque white, anti-aliased: the strokes' alpha is their coverage.
pub(super) fn white() -> Paint<'static> {
    let mut paint = Paint::default();
    paint.set_color_rgba8(255, 255, 255, 255);
    paint.anti_alias = true;
    paint
}

/// Stroke coverage (alpha in [0, 1]) of `lines` on a `width × height`
/// image, row-major: every stroke drawn in order on one fresh pixmap with
/// `Pixmap::stroke_path`, or, for a polyline of gentle turns, its
/// `gentle_outline` filled. The plain form of what [`Strokes`](super::Strokes) draws (the
/// reference its banded drawing is tested against).
pub fn draw(lines: &[Polyline], style: &StrokeStyle, width: u32, height: u32) -> Vec<f32> {
    let Some(mut pm) = Pixmap::new(width.max(1), height.max(1)) else {
        return vec![0.0; (width * height) as usize];
    };
    let paint = white();
    let id = Transform::identity();
    for l in lines {
        for (path, stroke) in strokes_of(l, style) {
            // (`stroke_path` for a stroke wider than 1 px fills the outline
            // tiny-skia's stroker makes; a gentle polyline's is made here.)
            match gentle_outline(&path, &stroke) {
                Some(o) => pm.fill_path(&o, &paint, FillRule::Winding, id, None),
                None => pm.stroke_path(&path, &paint, &stroke, id, None),
            }
        }
    }
    pm.pixels()
        .iter()
        .map(|p| p.alpha() as f32 / 255.0)
        .collect()
}

/// One tiny-skia draw of the overlay and the pixels it may change.
pub(super) struct Draw {
    /// The stroke's centre line.
    pub(super) centre: Path,
    pub(super) stroke: Stroke,
    /// For a stroke wider than 1 px, the outline path `Pixmap::stroke_path`
    /// turns it into (no transform, so resolution scale 1) and fills with
    /// the winding rule; [`Canvas::draw`] does the same two steps. None for
    /// a stroke of at most 1 px, which tiny-skia draws as a
    /// (coverage-modulated) hairline: drawn with `stroke_path` itself.
    pub(super) outline: Option<Path>,
    /// [x0, x1) × [y0, y1) within the image, holding every pixel the draw
    /// can change.
    pub(super) rect: [usize; 4],
    /// With round or bevel joins, the distance from the centre line's
    /// segments within which every pixel the draw can change lies
    /// ([`Canvas::mark`]): a far tighter set than `rect` for a ring around
    /// an object. None with miter joins (whole `rect`).
    pub(super) reach: Option<f32>,
    /// The outline lies within the image with a pixel to spare all round
    /// (so tiny-skia neither clips it nor tiles the image): it can be
    /// filled on a mask of `rect`'s size, moved by `rect`'s corner, for the
    /// same bytes ([`fill_local`]).
    pub(super) local: bool,
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
    // tiny-skia's own test (treat_as_hairline with the identity transform
    // and anti-aliasing).
    let (outline, bounds, margin) = if stroke.width <= 1.0 {
        // A hairline's coverage stays within 1 px of the line, caps (½ px)
        // included.
        (None, centre.bounds(), 3.0)
    } else {
        // The scan converter writes only within the filled path's bounds,
        // rounded out. (Not the stroke's theoretical reach from the centre
        // line: with miter-clip joins tiny-skia can draw spikes far beyond
        // it.)
        let outline = outline_of(&centre, &stroke)?;
        let b = outline.bounds();
        (Some(outline), b, 1.0)
    };
    let clamp = |v: f32, hi: usize| (v.max(0.0) as usize).min(hi);
    let edges = [
        (bounds.left() - margin).floor(),
        (bounds.right() + margin).ceil(),
        (bounds.top() - margin).floor(),
        (bounds.bottom() + margin).ceil(),
    ];
    let rect = [
        clamp(edges[0], w),
        clamp(edges[1], w),
        clamp(edges[2], h),
        clamp(edges[3], h),
    ];
    // (Each edge an integer in f32, so the comparisons are exact; a NaN
    // bound fails them.)
    let local = outline.is_some()
        && w.max(h) < TILED
        && edges[0] >= 0.0
        && edges[2] >= 0.0
        && edges[1] <= w as f32
        && edges[3] <= h as f32;
    let points = outline.as_ref().unwrap_or(&centre).len();
    let reach = reach(&stroke);
    (rect[0] < rect[1] && rect[2] < rect[3]).then_some(Draw {
        centre,
        stroke,
        outline,
        rect,
        reach,
        local,
        cost: (points + rect[3] - rect[2]) as f64,
    })
}

/// The outline a stroke wider than 1 px is filled as: a polyline whose
/// turns are all gentle, [`gentle_outline`]; any other, tiny-skia's own
/// stroker (`Path::stroke`, resolution scale 1, as `stroke_path`).
fn outline_of(centre: &Path, stroke: &Stroke) -> Option<Path> {
    gentle_outline(centre, stroke).or_else(|| centre.stroke(stroke, 1.0))
}

/// Whether every stroke of `style` is wider than 1 px, so that none is a
/// hairline ([`strokes_of`]: a taper's widths are at least
/// width·(1 − taper)).
pub(super) fn no_hairlines(style: &StrokeStyle) -> bool {
    if style.taper > 0.0 {
        style.width * (1.0 - style.taper) > 1.0
    } else {
        style.width > 1.0
    }
}

/// How far from its centre line's segments a stroke can change pixels,
/// if that is known: with round joins (arcs about the vertex) and bevel
/// joins (within the two segments' ends there) the stroke lies within
/// w/2 of a segment, a square cap within w/2·√2 of the end point, and a
/// hairline (w ≤ 1) within 1 px of its line with a ½ px cap. The 2 px
/// added cover anti-aliasing (a pixel is changed when its square meets the
/// path, ≤ 1 px further), the quadratic approximation of the joins' arcs
/// (≤ ¼ px) and fixed-point rounding. Miter joins reach up to the miter
/// limit, and tiny-skia's miter-clip joins further (see [`Draw::rect`]):
/// None, for the whole rectangle.
fn reach(stroke: &Stroke) -> Option<f32> {
    if matches!(stroke.line_join, LineJoin::Miter | LineJoin::MiterClip) {
        return None;
    }
    let half = if stroke.width <= 1.0 {
        1.5
    } else {
        0.5 * stroke.width
    };
    let cap = if stroke.line_cap == LineCap::Square {
        std::f32::consts::SQRT_2
    } else {
        1.0
    };
    Some(half * cap + 2.0)
}

/// tiny-skia fills a mask this wide or tall in tiles, each clipping the
/// path (its `DrawTiler`: 8192 supersampled by 4 overflows its fixed
/// point): such images keep the image-sized fills.
const TILED: usize = 8192;

/// Fills `d` (an outline within the image, [`Draw::local`]) on a
/// transparent mask of its rectangle's size held in `buf`, the outline
/// moved by the rectangle's corner (−x0, −y0), and returns its coverage in
/// image coordinates.
///
/// The same bytes as the fill on an image-sized mask: the move is exact
/// (an integer subtracted from a float at least as large, below 2²⁴),
/// tiny-skia turns points into fixed point by scaling by a power of two
/// and truncating (a floor, the points being positive both ways) and then
/// works in integers relative to the edges' ends, and the outline lies
/// within both masks, so neither clips it. Checked by
/// `a_local_fill_gives_the_bytes_of_the_image_sized_fill`.
pub(super) fn fill_local(d: &Draw, buf: &mut Vec<u8>) -> Coverage {
    let [x0, x1, y0, y1] = d.rect;
    let (w, h) = (x1 - x0, y1 - y0);
    let mut c = Coverage::default();
    let (Some(outline), Some(size)) = (&d.outline, tiny_skia::IntSize::from_wh(w as u32, h as u32))
    else {
        return c;
    };
    // `buf` is all zero between fills (each fill's runs are cleared
    // below), so it needs no clearing whatever its last shape: only the
    // bytes it gains are written (zeros).
    buf.resize(w * h, 0);
    let Some(mut mask) = Mask::from_vec(std::mem::take(buf), size) else {
        return c;
    };
    let to_local = Transform::from_translate(-(x0 as f32), -(y0 as f32));
    mask.fill_path(outline, FillRule::Winding, true, to_local);
    for (y, row) in mask.data_mut().chunks_exact_mut(w).enumerate() {
        push_runs(&mut c, row, (y0 + y) as u32, x0 as u32);
    }
    *buf = mask.take();
    c
}

/// tiny-skia's blend of an opaque white source into a mask's alpha `dst`
/// at coverage `c` (its `lowp` pipeline: load the destination, lerp by the
/// coverage, store): dst = div255(dst·(255 − c) + 255·c), with div255(v) =
/// (v + 255) >> 8 as in `lowp`. (A fully covered run, which tiny-skia
/// stores as 255 without the lerp, gives 255 here too.)
pub(super) fn lerp_alpha(dst: &mut [u8], cov: &[u8]) {
    for (d, &c) in dst.iter_mut().zip(cov) {
        let (d16, c16) = (*d as u16, c as u16);
        *d = ((d16 * (255 - c16) + 255 * c16 + 255) >> 8) as u8;
    }
}

#[cfg(test)]
mod tests {
    use super::canvas::Surface;
    use super::*;
    use crate::edges::EdgeKind;
    use tiny_skia::PathSegment;

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
    fn a_draw_changes_only_pixels_within_its_reach_of_the_centre_line() {
        // Every pixel a draw changes (drawn alone on a fresh pixmap) has
        // its centre within `reach` of a segment of its centre line, so
        // the chunks `Canvas::mark` keeps hold it; and the reach is not
        // much more than needed.
        let mut next = unit_floats(0x9e37_79b9_7f4a_7c15u64);
        let (w, h) = (120u32, 90u32);
        let mut worst: f64 = f64::NEG_INFINITY;
        for case in 0..48 {
            let style = StrokeStyle {
                width: [0.6, 1.0, 1.5, 2.5, 6.0, 13.0][case % 6],
                color: [0.0; 3],
                taper: if case % 5 == 0 { 0.7 } else { 0.0 },
                join: [LineJoin::Round, LineJoin::Bevel][case / 6 % 2],
                cap: [LineCap::Butt, LineCap::Round, LineCap::Square][case / 12 % 3],
            };
            let points = random_walk(&mut next, [w as f32, h as f32], 12.0, [2.0, 40.0]);
            let line = Polyline {
                kind: EdgeKind::Silhouette,
                points,
                closed: case % 4 == 1,
            };
            for d in draws(&[line], &style, w as usize, h as usize) {
                let reach = reach(&d.stroke).expect("round and bevel joins") as f64;
                let half = if d.stroke.width <= 1.0 {
                    0.5
                } else {
                    0.5 * d.stroke.width as f64
                };
                let mut segs = Vec::new();
                let (mut first, mut last) = ([0.0; 2], [0.0; 2]);
                for s in d.centre.segments() {
                    match s {
                        PathSegment::MoveTo(p) => (first, last) = ([p.x, p.y], [p.x, p.y]),
                        PathSegment::LineTo(p) => {
                            segs.push((last, [p.x, p.y]));
                            last = [p.x, p.y];
                        }
                        PathSegment::Close => segs.push((last, first)),
                        _ => unreachable!(),
                    }
                }
                let mut pm = Surface::new(w, h, true).unwrap();
                pm.draw(&d, &white());
                for (i, px) in pm.data().chunks(4).enumerate() {
                    if px[3] == 0 {
                        continue;
                    }
                    let c = [(i as u32 % w) as f64 + 0.5, (i as u32 / w) as f64 + 0.5];
                    let dist = segs
                        .iter()
                        .map(|(a, b)| {
                            let f = |q: [f32; 2]| [q[0] as f64, q[1] as f64];
                            to_segment(c, f(*a), f(*b))
                        })
                        .fold(f64::INFINITY, f64::min);
                    assert!(
                        dist <= reach,
                        "case {case}: pixel {c:?} at {dist} > reach {reach}"
                    );
                    let cap = if d.stroke.line_cap == LineCap::Square {
                        2f64.sqrt()
                    } else {
                        1.0
                    };
                    worst = worst.max(dist - half * cap);
                }
            }
        }
        // A changed pixel's centre lies at most ~1 px beyond the stroke:
        // the 2 px margin is ample but not wildly so.
        assert!(worst > 0.5 && worst < 1.25, "worst {worst}");
    }

    #[test]
    fn fills_composed_from_their_own_coverage_give_the_bytes_of_one_mask() {
        // Random overlapping polygons (sharp and thin ones, curves, both
        // fill rules): filled in order on one mask, against each filled
        // on a transparent mask and lerped in order (`lerp_alpha`) from
        // those bytes alone. Holds if a fill leaves its coverage itself on
        // a transparent mask (each pixel blended once) and `lerp_alpha`
        // is tiny-skia's blend.
        let mut next = unit_floats(0x2545_f491_4f6c_dd1du64);
        let (w, h) = (64u32, 48u32);
        let (mut overlapped, mut levels) = (0usize, [false; 256]);
        for case in 0..300 {
            let mut one = Mask::new(w, h).unwrap();
            let mut composed = vec![0u8; (w * h) as usize];
            for _ in 0..2 + case % 4 {
                let mut pb = PathBuilder::new();
                let c = [next() * w as f32, next() * h as f32];
                let r = 1.0 + next() * 20.0;
                pb.move_to(c[0] + r, c[1]);
                for k in 1..3 + (next() * 9.0) as usize {
                    let (a, rr) = (k as f32 * 2.4, r * (0.2 + next()));
                    let p = [c[0] + rr * a.cos(), c[1] + rr * a.sin()];
                    if k % 3 == 0 {
                        pb.quad_to(c[0] + next() * 30.0 - 15.0, c[1], p[0], p[1]);
                    } else {
                        pb.line_to(p[0], p[1]);
                    }
                }
                pb.close();
                let Some(path) = pb.finish() else { continue };
                let rule = [FillRule::Winding, FillRule::EvenOdd][case % 2];
                let id = Transform::identity();
                one.fill_path(&path, rule, true, id);
                let mut alone = Mask::new(w, h).unwrap();
                alone.fill_path(&path, rule, true, id);
                for (&d, &a) in composed.iter().zip(alone.data()) {
                    overlapped += usize::from(d != 0 && a != 0);
                    levels[a as usize] = true;
                }
                lerp_alpha(&mut composed, alone.data());
            }
            assert_eq!(one.data(), &composed[..], "case {case}");
        }
        // Many pixels blended over others, at every coverage level the 4×4
        // supersampling gives (runs of partial rows add up).
        let seen = levels.iter().filter(|&&l| l).count();
        assert!(
            overlapped > 5_000 && seen > 20,
            "{overlapped} overlapped, {seen} levels"
        );
    }

    #[test]
    fn a_local_fill_gives_the_bytes_of_the_image_sized_fill() {
        // Random strokes (round, bevel and miter joins, every cap, widths
        // from 1.5 to 13 px, tapers), each filled on an image-sized mask
        // and at its own size (`fill_local`): the same alpha at every
        // pixel, and draws near the edges are left to the image-sized way.
        let mut next = unit_floats(0x9e37_79b9_7f4a_7c15u64);
        let (w, h) = (173usize, 131usize);
        let (mut local, mut edge) = (0, 0);
        let mut buf = Vec::new();
        for case in 0..240 {
            let style = StrokeStyle {
                width: [1.5, 2.5, 6.0, 13.0, 3.7][case % 5],
                color: [0.0; 3],
                taper: if case % 7 == 0 { 0.6 } else { 0.0 },
                join: [LineJoin::Round, LineJoin::Bevel, LineJoin::Miter][case / 5 % 3],
                cap: [LineCap::Butt, LineCap::Round, LineCap::Square][case / 15 % 3],
            };
            let points = random_walk(&mut next, [w as f32, h as f32], 20.0, [3.0, 50.0]);
            let line = Polyline {
                kind: EdgeKind::Silhouette,
                points,
                closed: case % 3 == 1,
            };
            for d in draws(&[line], &style, w, h) {
                if !d.local {
                    edge += 1;
                    continue;
                }
                local += 1;
                let mut whole = Mask::new(w as u32, h as u32).unwrap();
                let outline = d.outline.as_ref().unwrap();
                whole.fill_path(outline, FillRule::Winding, true, Transform::identity());
                let mut got = vec![0u8; w * h];
                let c = fill_local(&d, &mut buf);
                for (y, x, a) in c.rows(0, h) {
                    got[y * w + x..y * w + x + a.len()].copy_from_slice(a);
                }
                assert_eq!(whole.data(), &got[..], "case {case}");
            }
        }
        assert!(
            local > 200 && edge > 20,
            "{local} local, {edge} near the edges"
        );
    }
}
