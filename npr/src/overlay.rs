//! Stroke overlays: the polylines of [`crate::edges`] drawn with tiny-skia
//! over the image, and written as SVG. (The only place tiny-skia draws
//! lines over a rendered frame.)
//!
//! The overlay is a post stage after the tone map, before the sRGB encode:
//! the strokes are rasterized anti-aliased into an alpha mask at the output
//! size (widths in output pixels whatever the supersampling), and the
//! stroke colour is blended over the tone-mapped image in **linear**
//! values, c = c·(1 − a) + colour·a; the encode then writes sRGB. The SVG
//! has the same polylines (one `<path>` per polyline, in one `<g>` per
//! edge kind) with the colour sRGB-encoded, as SVG colours are; a taper,
//! which one SVG stroke cannot vary, is left out of the SVG.

use crate::edges::{chain, visible_pieces, DepthView, EdgeKind, MeshEdges, Polyline};
use crate::outline::ssaa_of;
use rayon::prelude::*;
use specula_raster::buffers::prefetch;
use specula_raster::post::{srgb_encode, HdrImage, PostStage};
use specula_raster::{BufferSet, Camera, FrameBuffers};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use tiny_skia::{FillRule, Mask, Paint, Path, PathBuilder, PathSegment, Pixmap, Stroke, Transform};
pub use tiny_skia::{LineCap, LineJoin};

/// How strokes look.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrokeStyle {
    /// Output pixels.
    pub width: f32,
    /// Display-linear RGB in [0, 1].
    pub color: [f32; 3],
    /// 0: constant width; 1: the width falls linearly to 0 at both ends of
    /// an open polyline (over each half of its length).
    pub taper: f32,
    pub join: LineJoin,
    pub cap: LineCap,
}

/// The stroke overlay stage. Built once per scene ([`Strokes::new`]): the
/// edges and the camera are fixed, so which edges are drawn (silhouettes
/// included) is found once; a frame tests their visibility, chains and
/// draws them.
pub struct Strokes {
    edges: Arc<MeshEdges>,
    camera: Camera,
    pub style: StrokeStyle,
    /// [`MeshEdges::classify`] from the camera's eye.
    drawn: Arc<Vec<(u32, u32, EdgeKind)>>,
    /// Kept from frame to frame by the post list's instance of the stage.
    canvases: Canvases,
}

/// A clone shares the edges and starts with no canvases.
impl Clone for Strokes {
    fn clone(&self) -> Strokes {
        Strokes {
            edges: self.edges.clone(),
            camera: self.camera.clone(),
            style: self.style,
            drawn: self.drawn.clone(),
            canvases: Canvases::default(),
        }
    }
}

impl std::fmt::Debug for Strokes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Strokes")
            .field("edges", &self.edges.edge_count())
            .field("camera", &self.camera)
            .field("style", &self.style)
            .field("drawn", &self.drawn.len())
            .finish()
    }
}

impl Strokes {
    pub fn new(edges: MeshEdges, camera: Camera, style: StrokeStyle) -> Strokes {
        let drawn = edges.classify(camera.eye);
        Strokes {
            edges: Arc::new(edges),
            camera,
            style,
            drawn: Arc::new(drawn),
            canvases: Canvases::default(),
        }
    }

    pub fn edges(&self) -> &MeshEdges {
        &self.edges
    }

    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The visible polylines of a frame (whose buffers hold depth), in
    /// output pixels of a `ssaa`-times smaller image.
    pub fn polylines(&self, frame: &FrameBuffers, ssaa: usize) -> Vec<Polyline> {
        let view = self.camera.view(frame.width, frame.height);
        let depth = DepthView {
            depth: &frame.depth,
            width: frame.width as usize,
            height: frame.height as usize,
            ssaa,
        };
        let pieces = visible_pieces(&self.edges, &self.drawn, &view, self.camera.near, &depth);
        chain(&pieces)
    }
}

/// The tiny-skia strokes that draw `line`, in order: the whole polyline,
/// or with a taper one round-capped segment at a time, each at the width
/// of its middle's distance (along the line) from the nearer end.
fn strokes_of(line: &Polyline, style: &StrokeStyle) -> Vec<(Path, Stroke)> {
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
fn white() -> Paint<'static> {
    let mut paint = Paint::default();
    paint.set_color_rgba8(255, 255, 255, 255);
    paint.anti_alias = true;
    paint
}

/// Stroke coverage (alpha in [0, 1]) of `lines` on a `width × height`
/// image, row-major: every stroke drawn in order on one fresh pixmap with
/// `Pixmap::stroke_path`, or, for a polyline of gentle turns, its
/// [`gentle_outline`] filled. The plain form of what [`Strokes`] draws (the
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
struct Draw {
    /// The stroke's centre line.
    centre: Path,
    stroke: Stroke,
    /// For a stroke wider than 1 px, the outline path `Pixmap::stroke_path`
    /// turns it into (no transform, so resolution scale 1) and fills with
    /// the winding rule; [`Canvas::draw`] does the same two steps. None for
    /// a stroke of at most 1 px, which tiny-skia draws as a
    /// (coverage-modulated) hairline: drawn with `stroke_path` itself.
    outline: Option<Path>,
    /// [x0, x1) × [y0, y1) within the image, holding every pixel the draw
    /// can change.
    rect: [usize; 4],
    /// With round or bevel joins, the distance from the centre line's
    /// segments within which every pixel the draw can change lies
    /// ([`Canvas::mark`]): a far tighter set than `rect` for a ring around
    /// an object. None with miter joins (whole `rect`).
    reach: Option<f32>,
    /// The outline lies within the image with a pixel to spare all round
    /// (so tiny-skia neither clips it nor tiles the image): it can be
    /// filled on a mask of `rect`'s size, moved by `rect`'s corner, for the
    /// same bytes ([`fill_local`]).
    local: bool,
    /// A drawing cost estimate: the points tiny-skia scans and the rows.
    cost: f64,
}

/// The draws of `lines` in drawing order (outlines stroked in parallel,
/// each on its own) on a `w × h` image; draws that cannot touch the image
/// are left out.
fn draws(lines: &[Polyline], style: &StrokeStyle, w: usize, h: usize) -> Vec<Draw> {
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
fn draw_of(centre: Path, stroke: Stroke, w: usize, h: usize) -> Option<Draw> {
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
/// boundary moved by ≤ 1/64 px (±16/255, rarely 32/255, on about 1 % of
/// the stroke's pixels); bounded by the same test.
fn gentle_outline(centre: &Path, stroke: &Stroke) -> Option<Path> {
    // (A stroke of at most 1 px is a hairline to tiny-skia: no outline.)
    if stroke.width.is_nan() || stroke.width <= 1.0 {
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

/// Whether every stroke of `style` is wider than 1 px, so that none is a
/// hairline ([`strokes_of`]: a taper's widths are at least
/// width·(1 − taper)).
fn no_hairlines(style: &StrokeStyle) -> bool {
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
fn fill_local(d: &Draw, buf: &mut Vec<u8>) -> Coverage {
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

/// Appends the nonzero stretches of `row` (image row `y`, starting at
/// pixel `x0`) to `c`: runs of 8-byte chunks holding a nonzero byte,
/// trimmed to their first and last nonzero bytes; and clears them, leaving
/// `row` all zero.
fn push_runs(c: &mut Coverage, row: &mut [u8], y: u32, x0: u32) {
    // A whole chunk read as one u64 (the last, short one byte by byte).
    let nonzero = |row: &[u8], k: usize| match row.get(k * 8..k * 8 + 8) {
        Some(chunk) => u64::from_ne_bytes(chunk.try_into().unwrap_or([0; 8])) != 0,
        None => row[k * 8..].iter().any(|&a| a != 0),
    };
    let chunks = row.len().div_ceil(8);
    let mut k = 0;
    while k < chunks {
        if !nonzero(row, k) {
            k += 1;
            continue;
        }
        let start = k;
        while k < chunks && nonzero(row, k) {
            k += 1;
        }
        let end = (k * 8).min(row.len());
        let run = &mut row[start * 8..end];
        let first = run.iter().position(|&a| a != 0).unwrap_or(0);
        let last = run.iter().rposition(|&a| a != 0).unwrap_or(first);
        c.spans
            .push([y, x0 + (start * 8 + first) as u32, c.alpha.len() as u32]);
        c.alpha.extend_from_slice(&run[first..=last]);
        run.fill(0);
    }
}

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
enum Surface {
    Rgba(Pixmap),
    Alpha(Mask),
}

impl Surface {
    fn new(w: u32, h: u32, hairlines: bool) -> Option<Surface> {
        Some(if hairlines {
            Surface::Rgba(Pixmap::new(w, h)?)
        } else {
            Surface::Alpha(Mask::new(w, h)?)
        })
    }

    fn size(&self) -> (u32, u32) {
        match self {
            Surface::Rgba(p) => (p.width(), p.height()),
            Surface::Alpha(m) => (m.width(), m.height()),
        }
    }

    fn hairlines(&self) -> bool {
        matches!(self, Surface::Rgba(_))
    }

    /// Bytes per pixel; a pixel's alpha is its last byte.
    fn bpp(&self) -> usize {
        match self {
            Surface::Rgba(_) => 4,
            Surface::Alpha(_) => 1,
        }
    }

    fn data(&self) -> &[u8] {
        match self {
            Surface::Rgba(p) => p.data(),
            Surface::Alpha(m) => m.data(),
        }
    }

    fn data_mut(&mut self) -> &mut [u8] {
        match self {
            Surface::Rgba(p) => p.data_mut(),
            Surface::Alpha(m) => m.data_mut(),
        }
    }

    fn draw(&mut self, d: &Draw, paint: &Paint) {
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
struct Canvas {
    surface: Surface,
    /// One bit per 8-pixel chunk of a row, `words` u64 a row.
    touched: Vec<u64>,
    words: usize,
    /// Rows that may hold touched chunks.
    rows: [usize; 2],
    /// One row's marks, taken off `touched` while the row is cleared.
    row: Vec<u64>,
}

impl Canvas {
    fn new(w: u32, h: u32, hairlines: bool) -> Option<Canvas> {
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
    fn draw(&mut self, d: &Draw, paint: &Paint) {
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
    fn spans(&self, y: usize) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
        let w = self.surface.size().0 as usize;
        runs(&self.touched[y * self.words..][..self.words], w)
    }

    /// Row `y`'s marks, moved into `self.row` (cleared on the canvas).
    fn take_marks(&mut self, y: usize) {
        let marks = &mut self.touched[y * self.words..][..self.words];
        self.row.clear();
        self.row.extend_from_slice(marks);
        marks.fill(0);
    }

    /// Clears the marked chunks of `rows` and their marks.
    fn clear_rows(&mut self, rows: std::ops::Range<usize>) {
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
    fn take(&mut self) -> Coverage {
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

/// The runs of set bits of a row's chunk marks (`row`, 64 chunks a word)
/// as pixel ranges of a `w`-pixel row, left to right.
fn runs(row: &[u64], w: usize) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
    // Runs of set bits within each word, as chunk ranges.
    let (mut k, mut bits) = (0, row.first().copied().unwrap_or(0));
    let mut runs = std::iter::from_fn(move || loop {
        if bits != 0 {
            let c0 = bits.trailing_zeros() as usize;
            let len = (bits >> c0).trailing_ones() as usize;
            bits &= !(u64::MAX >> (64 - len) << c0);
            return Some((k * 64 + c0, k * 64 + c0 + len));
        }
        k += 1;
        bits = *row.get(k)?;
    })
    .peekable();
    // Joined where a run goes on into the next word.
    std::iter::from_fn(move || {
        let (c0, mut c1) = runs.next()?;
        while let Some((_, end)) = runs.next_if(|r| r.0 == c1) {
            c1 = end;
        }
        Some(c0 * 8..(c1 * 8).min(w))
    })
}

/// c = c·(1 − a) + colour·a over one span of pixels, a from the alpha
/// bytes of `px` (`BPP` bytes a pixel, alpha last; straight: the same a as
/// [`draw`]'s), skipping the 8-pixel groups with no coverage.
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
    /// a the strokes' alpha, the same bytes as blending [`draw`]'s
    /// coverage (see [`draw_bands`]).
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
    /// masks ([`Surface`]); false if they cannot be made.
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

/// One draw's coverage: the alpha bytes its fill leaves on a transparent
/// mask, over the pixels it changed, as row spans (rows ascending).
#[derive(Debug, Default)]
struct Coverage {
    /// Per span: its row, its first pixel, and where its bytes start in
    /// `alpha` (they end where the next span's start).
    spans: Vec<[u32; 3]>,
    alpha: Vec<u8>,
}

impl Coverage {
    /// The spans of rows [lo, hi): (row, first pixel, alpha bytes).
    fn rows(&self, lo: usize, hi: usize) -> impl Iterator<Item = (usize, usize, &[u8])> + '_ {
        let first = self.spans.partition_point(|s| (s[0] as usize) < lo);
        let last = self.spans.partition_point(|s| (s[0] as usize) < hi);
        (first..last).map(move |i| {
            let [y, x, at] = self.spans[i];
            let end = self
                .spans
                .get(i + 1)
                .map_or(self.alpha.len(), |s| s[2] as usize);
            (y as usize, x as usize, &self.alpha[at as usize..end])
        })
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

/// tiny-skia's blend of an opaque white source into a mask's alpha `dst`
/// at coverage `c` (its `lowp` pipeline: load the destination, lerp by the
/// coverage, store): dst = div255(dst·(255 − c) + 255·c), with div255(v) =
/// (v + 255) >> 8 as in `lowp`. (A fully covered run, which tiny-skia
/// stores as 255 without the lerp, gives 255 here too.)
fn lerp_alpha(dst: &mut [u8], cov: &[u8]) {
    for (d, &c) in dst.iter_mut().zip(cov) {
        let (d16, c16) = (*d as u16, c as u16);
        *d = ((d16 * (255 - c16) + 255 * c16 + 255) >> 8) as u8;
    }
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

impl PostStage for Strokes {
    fn name(&self) -> &str {
        "strokes"
    }

    fn buffers(&self) -> BufferSet {
        BufferSet {
            depth: true,
            ..BufferSet::default()
        }
    }

    fn instance(&self) -> Box<dyn PostStage> {
        Box::new(self.clone())
    }

    fn apply(&mut self, img: &mut HdrImage, frame: &FrameBuffers) {
        let lines = self.polylines(frame, ssaa_of(img, frame));
        self.canvases.blend(&lines, &self.style, img);
    }
}

/// The polylines as an SVG document of `width × height` pixels: one
/// `<g id="kind">` per edge kind present (in [`EdgeKind`] order) holding
/// one `<path>` per polyline.
pub fn svg(lines: &[Polyline], style: &StrokeStyle, width: u32, height: u32) -> String {
    use std::fmt::Write;
    let c = style.color.map(srgb_encode);
    let join = match style.join {
        LineJoin::Miter | LineJoin::MiterClip => "miter",
        LineJoin::Round => "round",
        LineJoin::Bevel => "bevel",
    };
    let cap = match style.cap {
        LineCap::Butt => "butt",
        LineCap::Round => "round",
        LineCap::Square => "square",
    };
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}">"#
    );
    for kind in EdgeKind::ALL {
        let of_kind: Vec<&Polyline> = lines.iter().filter(|l| l.kind == kind).collect();
        if of_kind.is_empty() {
            continue;
        }
        let _ = writeln!(
            s,
            r#"<g id="{}" fill="none" stroke="rgb({},{},{})" stroke-width="{}" stroke-linejoin="{join}" stroke-linecap="{cap}">"#,
            kind.name(),
            c[0],
            c[1],
            c[2],
            style.width
        );
        for l in of_kind {
            let mut d = String::new();
            for (i, p) in l.points.iter().enumerate() {
                let _ = write!(
                    d,
                    "{}{:.3} {:.3}",
                    if i == 0 { "M" } else { " L" },
                    p[0],
                    p[1]
                );
            }
            if l.closed {
                d.push_str(" Z");
            }
            let _ = writeln!(s, r#"<path d="{d}"/>"#);
        }
        let _ = writeln!(s, "</g>");
    }
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Floats in [0, 1) from a xorshift* generator seeded with `state`:
    /// the tests' random strokes and polygons, the same on every machine.
    fn unit_floats(mut state: u64) -> impl FnMut() -> f32 {
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
    fn to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
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
        // supersampling gives (29 here: runs of partial rows add up).
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
