//! The stroke outline of a polyline whose turns are all gentle, made here
//! instead of by tiny-skia's stroker: about 2 edges a vertex against its 5
//! (see [`gentle_outline`]).

use tiny_skia::{LineCap, LineJoin, Path, PathBuilder, PathSegment, Stroke};

/// How far (px) [`gentle_outline`] may put its edge beyond the stroke with
/// the requested joins and caps: a sixteenth of tiny-skia's ¼-px
/// supersampling step. Checked by
/// `a_gentle_outline_is_the_stroke_within_its_bound`.
const GENTLE_EXCESS: f64 = 1.0 / 64.0;

/// The stroke outline of a polyline (`centre`: a move and lines, closed or
/// not) with round or bevel joins (and round caps if open), as one
/// polygon per side: the points pᵢ ± r·mᵢ, with r the half width and
/// mᵢ = (nₐ + n_b)/(1 + nₐ·n_b) the miter vector of the unit normals of
/// the segments meeting at pᵢ (so mᵢ·nₐ = mᵢ·n_b = 1: each offset edge
/// lies on its segment's offset line), the ends' points offset along their
/// segment's normal. A closed line gives the two polygons, an open one a
/// single contour with a half circle of quadratic arcs at each end. Filled
/// with the winding rule, that is the union of the segments' rectangles,
/// the ends' half discs and, at each vertex, the miter wedge of its outer
/// side: the round-joined stroke plus at most r·(sec(θ/2) − 1) beyond
/// each join's arc (θ the turn; the bevel-joined one plus
/// r·(sec(θ/2) − cos(θ/2))), and the arcs at most r·((cos(φ/2) +
/// sec(φ/2))/2 − 1) outside the caps' circle (φ the angle of one arc).
/// Used only where each of those is at most [`GENTLE_EXCESS`], and every
/// segment is longer than the inner side's cut-back at its two ends,
/// r·(tan(θₐ/2) + tan(θ_b/2)) (so each segment's quadrilateral between
/// the two sides is a proper trapezoid, and the winding rule counts every
/// covered point at least once); else None (tiny-skia's stroker).
///
/// tiny-skia strokes a silhouette (turns of a few degrees) with a conic
/// per round join on the outer side and two lines through the vertex on
/// the inner one: about 5 edges a vertex, against 2 here. The coverage
/// moves where a supersample of its 4×4 grid falls on the other side of a
/// boundary moved by ≤ 1/64 px: a supersample or two at a pixel, on few
/// of the stroke's pixels; bounded by the same test.
pub(super) fn gentle_outline(centre: &Path, stroke: &Stroke) -> Option<Path> {
    if stroke.width.is_nan() || stroke.width <= 0.0 {
        return None;
    }
    let bevel = match stroke.line_join {
        LineJoin::Round => false,
        LineJoin::Bevel => true,
        _ => return None,
    };
    let p = centre.points();
    let n = p.len();
    let mut segments = centre.segments();
    let lines = n >= 2
        && matches!(segments.next(), Some(PathSegment::MoveTo(_)))
        && (1..n).all(|_| matches!(segments.next(), Some(PathSegment::LineTo(_))));
    let closed = match segments.next() {
        None => false,
        Some(PathSegment::Close) => segments.next().is_none() && n >= 3,
        Some(_) => return None,
    };
    if !lines || !(closed || stroke.line_cap == LineCap::Round) {
        return None;
    }
    let r = 0.5 * stroke.width as f64;
    // Segment i runs from p[i] to p[i + 1] (p[n − 1] to p[0] last if
    // closed): its unit direction and length, in f64.
    let segs = if closed { n } else { n - 1 };
    let seg: Vec<([f64; 2], f64)> = (0..segs)
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % n]);
            let d = [(b.x - a.x) as f64, (b.y - a.y) as f64];
            let len = d[0].hypot(d[1]);
            ([d[0] / len, d[1] / len], len)
        })
        .collect();
    // At each vertex: the offset vector (normals (−dy, dx)) and
    // tan(θ/2); an open line's ends are offset along their segment's
    // normal.
    let mut offset = Vec::with_capacity(n);
    let mut tan_half = Vec::with_capacity(n);
    for i in 0..n {
        let (da, db) = match (closed, i) {
            (false, 0) => (seg[0].0, seg[0].0),
            (false, _) if i == n - 1 => (seg[i - 1].0, seg[i - 1].0),
            _ => (seg[(i + segs - 1) % segs].0, seg[i].0),
        };
        let cos = da[0] * db[0] + da[1] * db[1];
        // cos(θ/2) and the excess beyond the stroke; a NaN (a zero-length
        // segment) fails the test.
        let cos_half = (0.5 * (1.0 + cos)).max(0.0).sqrt();
        let excess = r * (1.0 / cos_half - if bevel { cos_half } else { 1.0 });
        if excess.is_nan() || excess > GENTLE_EXCESS {
            return None;
        }
        offset.push([
            -(da[1] + db[1]) / (1.0 + cos),
            (da[0] + db[0]) / (1.0 + cos),
        ]);
        tan_half.push(((1.0 - cos) / (1.0 + cos)).max(0.0).sqrt());
    }
    for (i, s) in seg.iter().enumerate() {
        let cut = r * (tan_half[i] + tan_half[(i + 1) % n]);
        let longer = s.1.partial_cmp(&(cut + GENTLE_EXCESS)) == Some(std::cmp::Ordering::Greater);
        if !longer {
            return None;
        }
    }
    // The caps' half circles: `arcs` quadratic arcs of φ = π/arcs each,
    // the control point on the tangents' meeting, r·sec(φ/2) out.
    let arc_excess = |k: usize| {
        let half = std::f64::consts::PI / (2 * k) as f64;
        r * (0.5 * (half.cos() + 1.0 / half.cos()) - 1.0)
    };
    let arcs = if closed {
        0
    } else {
        (2..=64).find(|&k| arc_excess(k) <= GENTLE_EXCESS)?
    };
    let point = |i: usize, side: f64| {
        [
            p[i].x as f64 + side * r * offset[i][0],
            p[i].y as f64 + side * r * offset[i][1],
        ]
    };
    // Half circle about p[i] from its side `side` (u = side·n) through
    // the direction `ahead` to the other side.
    let cap = |pb: &mut PathBuilder, i: usize, side: f64, ahead: [f64; 2]| {
        let u = [side * offset[i][0], side * offset[i][1]];
        let c = [p[i].x as f64, p[i].y as f64];
        let phi = std::f64::consts::PI / arcs as f64;
        let at = |t: f64, k: f64| {
            let (cs, sn) = (t.cos(), t.sin());
            [
                c[0] + k * r * (u[0] * cs + ahead[0] * sn),
                c[1] + k * r * (u[1] * cs + ahead[1] * sn),
            ]
        };
        for j in 0..arcs {
            let t = j as f64 * phi;
            let (ctrl, end) = (at(t + 0.5 * phi, 1.0 / (0.5 * phi).cos()), at(t + phi, 1.0));
            pb.quad_to(ctrl[0] as f32, ctrl[1] as f32, end[0] as f32, end[1] as f32);
        }
    };
    let mut pb = PathBuilder::with_capacity(2 * n + 2 * arcs + 4, 2 * n + 4 * arcs + 2);
    let start = point(0, 1.0);
    pb.move_to(start[0] as f32, start[1] as f32);
    for i in 1..n {
        let q = point(i, 1.0);
        pb.line_to(q[0] as f32, q[1] as f32);
    }
    if closed {
        pb.close();
        let q = point(n - 1, -1.0);
        pb.move_to(q[0] as f32, q[1] as f32);
    } else {
        cap(&mut pb, n - 1, 1.0, seg[n - 2].0);
    }
    for i in (0..n - 1).rev() {
        let q = point(i, -1.0);
        pb.line_to(q[0] as f32, q[1] as f32);
    }
    if !closed {
        let back = seg[0].0;
        cap(&mut pb, 0, -1.0, [-back[0], -back[1]]);
    }
    pb.close();
    pb.finish()
}

#[cfg(test)]
mod tests {
    use super::super::tests::{to_segment, unit_floats};
    use super::*;
    use tiny_skia::{FillRule, Mask, Transform};

    /// Winding number of `q` about the closed contours of `path` (lines
    /// and quads), in f64: a signed count of the edges crossing the ray to +x.
    fn winding(path: &Path, q: [f64; 2]) -> i32 {
        let mut w = 0;
        let (mut first, mut last) = ([0.0; 2], [0.0; 2]);
        let mut edge = |a: [f64; 2], b: [f64; 2]| {
            if a[1] <= q[1] && b[1] > q[1] {
                if (b[0] - a[0]) * (q[1] - a[1]) - (q[0] - a[0]) * (b[1] - a[1]) > 0.0 {
                    w += 1;
                }
            } else if a[1] > q[1]
                && b[1] <= q[1]
                && (b[0] - a[0]) * (q[1] - a[1]) - (q[0] - a[0]) * (b[1] - a[1]) < 0.0
            {
                w -= 1;
            }
        };
        let f = |p: tiny_skia::Point| [p.x as f64, p.y as f64];
        for seg in path.segments() {
            match seg {
                PathSegment::MoveTo(p) => (first, last) = (f(p), f(p)),
                PathSegment::LineTo(p) => {
                    edge(last, f(p));
                    last = f(p);
                }
                PathSegment::QuadTo(c, p) => {
                    // 32 chords (a cap's arc of ≤ 90°: each within
                    // 0.001 px of the curve, on its inner side).
                    let (a, c, p) = (last, f(c), f(p));
                    for k in 1..=32 {
                        let t = k as f64 / 32.0;
                        let u = 1.0 - t;
                        let q = [
                            u * u * a[0] + 2.0 * u * t * c[0] + t * t * p[0],
                            u * u * a[1] + 2.0 * u * t * c[1] + t * t * p[1],
                        ];
                        edge(last, q);
                        last = q;
                    }
                }
                PathSegment::Close => {
                    edge(last, first);
                    last = first;
                }
                _ => unreachable!("an outline of lines and quads"),
            }
        }
        w
    }

    #[test]
    fn a_gentle_outline_is_the_stroke_within_its_bound() {
        // Random smooth rings and arcs of them (wobbly circles of 4 to 70
        // px, 12 to 160 points, widths 1.5 to 6 px, round and bevel joins;
        // the arcs with round caps, some with butt caps), like the
        // silhouettes of round objects. (1) The region: a point within
        // r − 0.01 of the polyline (f64, every segment) is inside the
        // outline (winding ≠ 0, f64), one beyond r + GENTLE_EXCESS + 0.01
        // outside it: points on both sides of every segment's, vertex's
        // and end's stroke boundary. (2) The coverage against tiny-skia's
        // own stroke of the same line: at most 2 supersamples of its 4×4
        // grid (32/255) at a pixel, on at most 2 % of the stroke's
        // pixels, and the total coverage within 0.1 %. Sharp polygons and
        // butt caps are left to tiny-skia's stroker.
        let mut next = unit_floats(0x51_7cc1_b727_220au64);
        let (w, h) = (200u32, 160u32);
        let (mut rings, mut arcs, mut left, mut tested) = (0, 0, 0, 0usize);
        let (mut stroke_px, mut changed, mut worst) = (0usize, 0usize, 0u8);
        let (mut sum_ours, mut sum_theirs) = (0u64, 0u64);
        for case in 0..120 {
            let open = case % 3 == 1;
            let stroke = Stroke {
                width: [1.5, 2.0, 3.0, 6.0][case % 4],
                line_join: [LineJoin::Round, LineJoin::Bevel][case / 4 % 2],
                line_cap: if open && case % 7 == 1 {
                    LineCap::Butt
                } else {
                    LineCap::Round
                },
                ..Stroke::default()
            };
            let a = 4.0 + next() * 66.0;
            let (b, k, phase) = (next() * 0.35, 2.0 + (next() * 2.0).floor(), next() * 6.3);
            let c = [
                a * 1.4 + next() * (w as f32 - a * 2.8),
                a * 1.4 + next() * (h as f32 - a * 2.8),
            ];
            // Every 10th a sharp polygon (5 to 8 corners); arcs cover 30
            // to 100 % of the way round.
            let n = if case % 10 == 9 {
                5 + case % 4
            } else {
                12 + (next() * 148.0) as usize
            };
            let span = if open { 0.3 + 0.7 * next() } else { 1.0 };
            let mut pb = PathBuilder::new();
            for i in 0..n {
                let phi =
                    span * (i as f32 + 0.3 * (next() - 0.5)) * std::f32::consts::TAU / n as f32;
                let rad = a * (1.0 + b * (k * phi + phase).cos());
                let (x, y) = (c[0] + rad * phi.cos(), c[1] + rad * phi.sin());
                if i == 0 {
                    pb.move_to(x, y);
                } else {
                    pb.line_to(x, y);
                }
            }
            if !open {
                pb.close();
            }
            let centre = pb.finish().unwrap();
            let Some(outline) = gentle_outline(&centre, &stroke) else {
                left += 1;
                continue;
            };
            assert!(stroke.line_cap == LineCap::Round || !open, "case {case}");
            if open {
                arcs += 1;
            } else {
                rings += 1;
            }
            let pts: Vec<[f64; 2]> = centre
                .points()
                .iter()
                .map(|p| [p.x as f64, p.y as f64])
                .collect();
            let segs = if open { n - 1 } else { n };
            let dist = |q: [f64; 2]| {
                (0..segs)
                    .map(|i| to_segment(q, pts[i], pts[(i + 1) % n]))
                    .fold(f64::INFINITY, f64::min)
            };
            let r = 0.5 * stroke.width as f64;
            let (inner, outer) = (r - 0.01, r + GENTLE_EXCESS + 0.01);
            let mut probe = |q: [f64; 2]| {
                let d = dist(q);
                let inside = winding(&outline, q) != 0;
                assert!(
                    if inside { d < outer } else { d > inner },
                    "case {case}: {q:?} at {d} from the line (r {r}), inside: {inside}"
                );
                tested += usize::from(d <= inner || d >= outer);
            };
            for i in 0..n {
                if i < segs {
                    let (p, q) = (pts[i], pts[(i + 1) % n]);
                    let len = (q[0] - p[0]).hypot(q[1] - p[1]);
                    let nrm = [-(q[1] - p[1]) / len, (q[0] - p[0]) / len];
                    for _ in 0..2 {
                        let t = next() as f64;
                        for s in [-outer, -inner, inner, outer] {
                            probe([
                                p[0] + t * (q[0] - p[0]) + s * nrm[0],
                                p[1] + t * (q[1] - p[1]) + s * nrm[1],
                            ]);
                        }
                    }
                }
                let p = pts[i];
                let round = if open && (i == 0 || i == n - 1) {
                    24
                } else {
                    8
                };
                for j in 0..round {
                    let ang = (j as f64 + 0.5) * std::f64::consts::TAU / round as f64;
                    for s in [inner, outer] {
                        probe([p[0] + s * ang.cos(), p[1] + s * ang.sin()]);
                    }
                }
            }
            // The coverage, against tiny-skia's stroke of the same line.
            let id = Transform::identity();
            let mut ours = Mask::new(w, h).unwrap();
            ours.fill_path(&outline, FillRule::Winding, true, id);
            let mut theirs = Mask::new(w, h).unwrap();
            let stroked = centre.stroke(&stroke, 1.0).unwrap();
            theirs.fill_path(&stroked, FillRule::Winding, true, id);
            for (&x, &y) in ours.data().iter().zip(theirs.data()) {
                stroke_px += usize::from(y != 0);
                changed += usize::from(x != y);
                worst = worst.max(x.abs_diff(y));
                (sum_ours, sum_theirs) = (sum_ours + x as u64, sum_theirs + y as u64);
            }
        }
        let total = (sum_ours as f64 - sum_theirs as f64).abs() / sum_theirs as f64;
        eprintln!(
            "{rings} rings and {arcs} arcs ({left} left to the stroker), {tested} points; \
             {changed} of {stroke_px} stroke pixels changed, by up to {worst}; total {total}"
        );
        assert!(
            worst <= 32 && changed * 50 <= stroke_px && total <= 1e-3,
            "{changed} of {stroke_px} stroke pixels changed, by up to {worst}; total {total}"
        );
        assert!(
            rings >= 40 && arcs >= 20 && left >= 15 && tested > 50_000,
            "{rings} rings, {arcs} arcs, {left} left to the stroker, {tested} points"
        );
    }
}
