//! Line extraction from mesh topology, for stroke overlays: which edges to
//! draw (silhouette, crease, boundary, material), which parts of them the
//! eye sees (the depth buffer), and how they chain into polylines.
//!
//! - Topology ([`MeshEdges::new`], once per scene): vertices are welded by
//!   position (quantized to 1e-6 of the scene's extent, so split normals
//!   and uv seams do not cut the mesh), each undirected edge records its
//!   faces. Triangles that weld to zero area are left out.
//! - Kinds: **boundary** (one face), **material** (two faces of different
//!   materials), **crease** (face normals more than `crease_angle` apart),
//!   all fixed; **silhouette** (one face toward the eye, the other away)
//!   per view. An edge that is several kinds is drawn once, as the first
//!   of silhouette, boundary, material, crease that is asked for.
//! - Visibility (`visible_pieces`): points every sample along the
//!   projected edge are compared with the depth buffer; a point is seen
//!   when its view depth is at most (1 + `DEPTH_BIAS`) times the largest
//!   depth of the samples within one output pixel (ssaa samples) around it
//!   (3×3 without supersampling). The largest of the neighbourhood,
//!   not the sample's own, is what keeps a silhouette (whose neighbours
//!   show the background) and an edge where two objects touch (whose
//!   neighbours show the edge's own faces) from being eaten by the bias.
//! - Chaining ([`chain`]): the visible pieces of edges of one kind are
//!   joined where they reach a shared vertex into polylines, going on
//!   through a vertex along the unused piece that turns least on screen; a
//!   piece end that stops short of its vertex (hidden beyond it) ends its
//!   polyline, and a chain that comes back to its start is closed. So a
//!   silhouette partly hidden behind another object is one polyline per
//!   visible run, not one per edge.

use glam::{Vec3, Vec4};
use rayon::prelude::*;
use specula_raster::buffers::prefetch;
use specula_raster::camera::View;
use specula_raster::SceneData;
use std::collections::HashMap;

/// What an edge is drawn as; the order is the drawing and SVG group order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum EdgeKind {
    Silhouette,
    Boundary,
    Material,
    Crease,
}

impl EdgeKind {
    pub(crate) const ALL: [EdgeKind; 4] = [
        EdgeKind::Silhouette,
        EdgeKind::Boundary,
        EdgeKind::Material,
        EdgeKind::Crease,
    ];

    pub(crate) fn name(self) -> &'static str {
        match self {
            EdgeKind::Silhouette => "silhouette",
            EdgeKind::Boundary => "boundary",
            EdgeKind::Material => "material",
            EdgeKind::Crease => "crease",
        }
    }
}

/// Relative depth tolerance of the visibility test (module docs).
pub(crate) const DEPTH_BIAS: f32 = 0.01;

const NO_FACE: u32 = u32::MAX;

#[derive(Clone, Copy, Debug)]
struct Edge {
    /// Welded vertex indices, a < b.
    a: u32,
    b: u32,
    faces: [u32; 2],
    /// The fixed kind (boundary, material, crease) asked for, if any.
    fixed: Option<EdgeKind>,
}

/// The scene's edges, welded; see the module docs.
#[derive(Clone, Debug)]
pub struct MeshEdges {
    /// Welded vertex positions.
    pub points: Vec<Vec3>,
    edges: Vec<Edge>,
    face_normal: Vec<Vec3>,
    face_point: Vec<Vec3>,
    silhouettes: bool,
}

impl MeshEdges {
    /// Topology of `triangles` (indices into `positions`) with per-triangle
    /// `materials`; `kinds` are the kinds to draw, `crease_angle_deg` the
    /// crease threshold.
    pub fn new(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        materials: &[u32],
        kinds: &[EdgeKind],
        crease_angle_deg: f32,
    ) -> MeshEdges {
        // Weld on a grid of 1e-6 of the extent.
        let extent = positions
            .iter()
            .filter(|p| p.is_finite())
            .fold(0.0f32, |m, p| m.max(p.abs().max_element()));
        let q = (extent * 1e-6).max(f32::MIN_POSITIVE);
        let mut index: HashMap<[i64; 3], u32> = HashMap::new();
        let mut points = Vec::new();
        let mut weld = vec![u32::MAX; positions.len()];
        for (i, p) in positions.iter().enumerate() {
            if !p.is_finite() {
                continue;
            }
            let key = (*p / q).round().to_array().map(|c| c as i64);
            weld[i] = *index.entry(key).or_insert_with(|| {
                points.push(*p);
                points.len() as u32 - 1
            });
        }
        let mut face_normal = Vec::with_capacity(triangles.len());
        let mut face_point = Vec::with_capacity(triangles.len());
        let mut map: HashMap<(u32, u32), usize> = HashMap::new();
        let mut edges: Vec<Edge> = Vec::new();
        let mut extra_faces = vec![0u8; 0];
        for (f, t) in triangles.iter().enumerate() {
            let w = t.map(|v| weld.get(v as usize).copied().unwrap_or(u32::MAX));
            let ok = !w.contains(&u32::MAX) && w[0] != w[1] && w[1] != w[2] && w[0] != w[2];
            let n = if ok {
                let [a, b, c] = w.map(|v| points[v as usize]);
                (b - a).cross(c - a).try_normalize()
            } else {
                None
            };
            face_normal.push(n.unwrap_or(Vec3::ZERO));
            face_point.push(positions[t[0] as usize]);
            if n.is_none() {
                continue;
            }
            for k in 0..3 {
                let (u, v) = (w[k], w[(k + 1) % 3]);
                let key = (u.min(v), u.max(v));
                match map.get(&key) {
                    Some(&e) => {
                        if edges[e].faces[1] == NO_FACE {
                            edges[e].faces[1] = f as u32;
                        } else {
                            // A third face: a non-manifold edge; drawn as a
                            // boundary (it bounds a sheet).
                            extra_faces[e] = 1;
                        }
                    }
                    None => {
                        map.insert(key, edges.len());
                        edges.push(Edge {
                            a: key.0,
                            b: key.1,
                            faces: [f as u32, NO_FACE],
                            fixed: None,
                        });
                        extra_faces.push(0);
                    }
                }
            }
        }
        let cos_crease = crease_angle_deg.to_radians().cos();
        for (e, extra) in edges.iter_mut().zip(&extra_faces) {
            let [f0, f1] = e.faces;
            let boundary = f1 == NO_FACE || *extra > 0;
            let (material, crease) = if boundary {
                (false, false)
            } else {
                let (f0, f1) = (f0 as usize, f1 as usize);
                (
                    materials[f0] != materials[f1],
                    face_normal[f0].dot(face_normal[f1]) < cos_crease,
                )
            };
            // The first kind asked for, in priority order, that applies.
            e.fixed = [
                (EdgeKind::Boundary, boundary),
                (EdgeKind::Material, material),
                (EdgeKind::Crease, crease),
            ]
            .into_iter()
            .find(|(k, on)| *on && kinds.contains(k))
            .map(|(k, _)| k);
        }
        MeshEdges {
            points,
            edges,
            face_normal,
            face_point,
            silhouettes: kinds.contains(&EdgeKind::Silhouette),
        }
    }

    /// The scene's main-pass triangles (the ones the scene's meshes made).
    pub fn from_scene(scene: &SceneData, kinds: &[EdgeKind], crease_angle_deg: f32) -> MeshEdges {
        MeshEdges::new(
            &scene.positions,
            &scene.triangles,
            &scene.tri_material,
            kinds,
            crease_angle_deg,
        )
    }

    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// Every edge drawn from `eye`, with its kind: (welded a, welded b, kind).
    pub fn classify(&self, eye: Vec3) -> Vec<(u32, u32, EdgeKind)> {
        // Each face's facing once (an edge would test both of its faces,
        // and every face has three edges).
        let facing: Vec<bool> = if self.silhouettes {
            self.face_normal
                .par_iter()
                .zip(self.face_point.par_iter())
                .with_min_len(4096)
                .map(|(n, p)| n.dot(eye - *p) > 0.0)
                .collect()
        } else {
            Vec::new()
        };
        self.edges
            .par_iter()
            .with_min_len(4096)
            .filter_map(|e| self.kind(e, &facing).map(|k| (e.a, e.b, k)))
            .collect()
    }

    fn kind(&self, e: &Edge, facing: &[bool]) -> Option<EdgeKind> {
        if self.silhouettes
            && e.faces[1] != NO_FACE
            && facing[e.faces[0] as usize] != facing[e.faces[1] as usize]
        {
            return Some(EdgeKind::Silhouette);
        }
        e.fixed
    }
}

/// A polyline in output pixels (x right, y down, pixel centres at +½).
#[derive(Clone, Debug, PartialEq)]
pub struct Polyline {
    pub kind: EdgeKind,
    pub points: Vec<[f32; 2]>,
    /// The last point joins the first.
    pub closed: bool,
}

/// A visible stretch of one edge: its points in output pixels and, for
/// each end that is the edge's own end (visible up to its vertex), the
/// welded vertex there (for chaining).
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    pub kind: EdgeKind,
    pub a: [f32; 2],
    pub b: [f32; 2],
    pub ends: [Option<u32>; 2],
}

/// Depth-buffer view for [`visible_pieces`]: view depth per sample, +inf
/// where nothing is hit, at `width × height` samples; `ssaa` samples per
/// output pixel side.
pub(crate) struct DepthView<'a> {
    pub(crate) depth: &'a [f32],
    pub(crate) width: usize,
    pub(crate) height: usize,
    pub(crate) ssaa: usize,
}

impl DepthView<'_> {
    fn seen(&self, sx: f32, sy: f32, w: f32) -> bool {
        if !(sx >= 0.0 && sy >= 0.0 && sx < self.width as f32 && sy < self.height as f32) {
            return false;
        }
        // (In [0, width), far below 2³¹: through i32, the same value as a
        // saturating cast to usize, in fewer instructions.)
        let (x, y, r) = (sx as i32 as usize, sy as i32 as usize, self.ssaa.max(1));
        if r == 1 && x >= 1 && y >= 1 && x + 1 < self.width && y + 1 < self.height {
            return w <= self.max3x3(x, y) * (1.0 + DEPTH_BIAS);
        }
        let (x0, x1) = (x.saturating_sub(r), (x + r + 1).min(self.width));
        // Row by row as slices (the order of a max does not change it).
        let mut dmax = 0.0f32;
        for yy in y.saturating_sub(r)..(y + r + 1).min(self.height) {
            let row = &self.depth[yy * self.width..][x0..x1];
            dmax = row.iter().fold(dmax, |m, &d| m.max(d));
        }
        w <= dmax * (1.0 + DEPTH_BIAS)
    }

    /// The largest depth of the 3×3 samples around (x, y), which lie
    /// within the buffer, folded from 0 in the order of [`Self::seen`]'s
    /// general loop (rows top to bottom, each left to right): the same
    /// value, with three fixed-size rows instead of slices of any length.
    #[inline(always)]
    fn max3x3(&self, x: usize, y: usize) -> f32 {
        let row = |yy: usize| -> [f32; 3] {
            let at = yy * self.width + x - 1;
            self.depth[at..at + 3]
                .try_into()
                .unwrap_or([f32::INFINITY; 3])
        };
        [row(y - 1), row(y), row(y + 1)]
            .iter()
            .flatten()
            .fold(0.0f32, |m, &d| m.max(d))
    }
}

/// The visible pieces of `edges` (module docs), in edge order.
pub(crate) fn visible_pieces(
    mesh: &MeshEdges,
    edges: &[(u32, u32, EdgeKind)],
    view: &View,
    near: f32,
    depth: &DepthView,
) -> Vec<Piece> {
    // One output vector per parallel chunk of edges, not one per edge;
    // joined in edge order.
    let chunks: Vec<Vec<Piece>> = edges
        .par_chunks(256)
        .map(|chunk| {
            // The ends in clip space first, so that the depth around the
            // ends of an edge a few ahead can be asked for.
            let clip: Vec<[Vec4; 2]> = chunk
                .iter()
                .map(|&(a, b, _)| {
                    [a, b].map(|v| view.view_proj * Vec4::from((mesh.points[v as usize], 1.0)))
                })
                .collect();
            let mut out = Vec::new();
            for (i, &edge) in chunk.iter().enumerate() {
                if let Some(ahead) = clip.get(i + PREFETCH_EDGES) {
                    prefetch_ends(ahead, near, depth);
                }
                edge_pieces(edge, clip[i], near, depth, &mut out, true);
            }
            out
        })
        .collect();
    chunks.concat()
}

/// How many edges ahead [`visible_pieces`] asks for depth.
const PREFETCH_EDGES: usize = 4;

/// Asks the cache for the depth samples around the ends of an edge: the
/// depth buffer is cold when the stage runs, a neighbourhood spans rows a
/// page apart, and the tests of one edge wait on them one after another.
/// (Most drawn edges are silhouettes of a few pixels, whose tests all
/// fall near their ends.)
fn prefetch_ends(ends: &[Vec4; 2], near: f32, depth: &DepthView) {
    let (sw, sh) = (depth.width as f32, depth.height as f32);
    let r = depth.ssaa.max(1);
    for c in ends {
        let (sx, sy) = ((c.x / c.w * 0.5 + 0.5) * sw, (0.5 - c.y / c.w * 0.5) * sh);
        if !(c.w >= near && sx >= 0.0 && sy >= 0.0 && sx < sw && sy < sh) {
            continue;
        }
        let (x, y) = (sx as i32 as usize, sy as i32 as usize);
        if r == 1 && x >= 1 && y >= 1 && x + 1 < depth.width && y + 1 < depth.height {
            // The 3×3 of `DepthView::max3x3`: rows of a fixed size, one or
            // two lines each, asked for without a loop.
            for yy in y - 1..=y + 1 {
                let at = yy * depth.width + x - 1;
                if let Some(row) = depth.depth.get(at..at + 3) {
                    let row: Result<&[f32; 3], _> = row.try_into();
                    row.map(prefetch).unwrap_or_default();
                }
            }
            continue;
        }
        let (x0, x1) = (x.saturating_sub(r), (x + r + 1).min(depth.width));
        for yy in y.saturating_sub(r)..(y + r + 1).min(depth.height) {
            prefetch(&depth.depth[yy * depth.width..][x0..x1]);
        }
    }
}

/// Appends the visible pieces of one edge, whose ends are at `ca` and `cb`
/// in clip space, to `out`; with `clip`, testing only the samples that can
/// fall on the image.
fn edge_pieces(
    (a, b, kind): (u32, u32, EdgeKind),
    [ca, cb]: [Vec4; 2],
    near: f32,
    depth: &DepthView,
    out: &mut Vec<Piece>,
    clip: bool,
) {
    let (sw, sh) = (depth.width as f32, depth.height as f32);
    let inv_ss = 1.0 / depth.ssaa as f32;
    // Keep the part in front of the near plane (clip space is linear along
    // the edge).
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    if ca.w < near && cb.w < near {
        return;
    }
    if ca.w < near {
        t0 = (near - ca.w) / (cb.w - ca.w);
    } else if cb.w < near {
        t1 = (near - ca.w) / (cb.w - ca.w);
    }
    let at = |t: f32| {
        let c = ca + (cb - ca) * t;
        let (sx, sy) = ((c.x / c.w * 0.5 + 0.5) * sw, (0.5 - c.y / c.w * 0.5) * sh);
        (sx, sy, c.w)
    };
    let (p0, p1) = (at(t0), at(t1));
    let len = ((p1.0 - p0.0).powi(2) + (p1.1 - p0.1).powi(2)).sqrt();
    if !len.is_finite() {
        return;
    }
    // One test per sample along the edge; edges far off screen are capped
    // (their points outside the image are hidden anyway).
    let n = (len.ceil() as usize).clamp(1, 4 * (depth.width + depth.height)) + 1;
    let mut run: Option<(usize, (f32, f32))> = None;
    let mut close = |start: (usize, (f32, f32)), end: (usize, (f32, f32))| {
        out.push(Piece {
            kind,
            a: [start.1 .0 * inv_ss, start.1 .1 * inv_ss],
            b: [end.1 .0 * inv_ss, end.1 .1 * inv_ss],
            ends: [
                (t0 == 0.0 && start.0 == 0).then_some(a),
                (t1 == 1.0 && end.0 == n - 1).then_some(b),
            ],
        });
    };
    let mut last = (0usize, (0.0f32, 0.0f32));
    // Samples off the image are not seen: test only those that can be on
    // it (the run bookkeeping is the same, as every sample skipped is
    // unseen).
    let inside = |p: (f32, f32, f32)| p.0 >= 0.0 && p.1 >= 0.0 && p.0 < sw && p.1 < sh;
    let on = if clip && !(inside(p0) && inside(p1)) {
        let Some(on) = on_image(ca, cb, [t0, t1], n, [sw, sh]) else {
            return;
        };
        on
    } else {
        0..=n - 1
    };
    for i in on {
        // Perspective-correct: the clip-space point at parameter t.
        let t = t0 + (t1 - t0) * i as f32 / (n - 1) as f32;
        let (sx, sy, w) = at(t);
        let seen = depth.seen(sx, sy, w);
        match (seen, run) {
            (true, None) => run = Some((i, (sx, sy))),
            (false, Some(start)) => {
                if last.0 > start.0 {
                    close(start, last);
                }
                run = None;
            }
            _ => {}
        }
        last = (i, (sx, sy));
    }
    if let Some(start) = run {
        if last.0 > start.0 {
            close(start, last);
        }
    }
}

/// The sample indices `i` in 0..n (at t = t0 + (t1 − t0)·i/(n − 1)
/// between the clip-space points `ca` and `cb`, in front of the near
/// plane over [t0, t1]) whose point can fall on a `size` image; None when
/// none can. Solved in f64 on the exact line: |x| ≤ (1 + 2m/w)·w_clip and
/// |y| ≤ (1 + 2m/h)·w_clip are linear in t. The margin m (samples) covers
/// the rounding of the f32 points the samples are tested at, with room
/// (2 px plus 10⁻⁵ of the clip coordinates' size over the nearest w, in
/// pixels: f32 rounds each operation to 6·10⁻⁸), and the range is
/// widened by two samples more.
fn on_image(
    ca: Vec4,
    cb: Vec4,
    [t0, t1]: [f32; 2],
    n: usize,
    size: [f32; 2],
) -> Option<std::ops::RangeInclusive<usize>> {
    let all = Some(0..=n - 1);
    if t1 <= t0 {
        return all;
    }
    let (a, b) = (ca.as_dvec4(), cb.as_dvec4());
    let at = |t: f64| a + (b - a) * t;
    let (tf0, tf1) = (t0 as f64, t1 as f64);
    let w_min = at(tf0).w.min(at(tf1).w);
    let big = a.abs().max(b.abs()).max_element();
    if !(w_min > 0.0 && big.is_finite()) {
        return all;
    }
    let (mut lo, mut hi) = (tf0, tf1);
    for (k, extent) in [(0, size[0] as f64), (1, size[1] as f64)] {
        let m = 2.0 + 1e-5 * big / w_min * extent;
        let s = 1.0 + 2.0 * m / extent;
        // s·w − c ≥ 0 and s·w + c ≥ 0, each f(t) = f(0) + (f(1) − f(0))·t.
        for sign in [1.0, -1.0] {
            let f = |c: glam::DVec4| s * c.w - sign * c[k];
            let (f0, f1) = (f(a), f(b));
            if f1 > f0 {
                lo = lo.max(f0 / (f0 - f1));
            } else if f1 < f0 {
                hi = hi.min(f0 / (f0 - f1));
            } else if f0 < 0.0 {
                return None;
            }
        }
    }
    if lo > hi {
        return None;
    }
    let index = |t: f64| (t - tf0) / (tf1 - tf0) * (n - 1) as f64;
    let first = (index(lo).floor() - 2.0).max(0.0) as usize;
    let last = ((index(hi).ceil() + 2.0).max(0.0) as usize).min(n - 1);
    (first <= last).then_some(first..=last)
}

/// Chains pieces into polylines (module docs), kinds in [`EdgeKind`]
/// order; deterministic for a given piece order.
pub fn chain(pieces: &[Piece]) -> Vec<Polyline> {
    let mut out = Vec::new();
    for kind in EdgeKind::ALL {
        let ps: Vec<&Piece> = pieces.iter().filter(|p| p.kind == kind).collect();
        let point = |i: usize, end: usize| if end == 0 { ps[i].a } else { ps[i].b };
        // The piece ends at vertices, (vertex, piece, end) sorted (packed
        // in a u64, vertex high: a piece index is below 2³¹): the ends at a
        // vertex are a run, in piece order.
        let mut ends: Vec<u64> = ps
            .iter()
            .enumerate()
            .flat_map(|(i, p)| {
                (0..2).filter_map(move |end| {
                    p.ends[end].map(|v| (v as u64) << 32 | (i as u64) << 1 | end as u64)
                })
            })
            .collect();
        sort_by_vertex(&mut ends);
        let unpack = |k: u64| ((k >> 32) as u32, (k as u32 >> 1) as usize, (k & 1) as usize);
        // Each vertex once, ascending, with its run of ends; and the run of
        // each piece end at a vertex (piece i's end e at 2i + e).
        let mut runs: Vec<(u32, std::ops::Range<usize>)> = Vec::new();
        let mut run_of = vec![u32::MAX; 2 * ps.len()];
        for (k, &key) in ends.iter().enumerate() {
            let (v, i, e) = unpack(key);
            match runs.last_mut() {
                Some((u, r)) if *u == v => r.end = k + 1,
                _ => runs.push((v, k..k + 1)),
            }
            run_of[2 * i + e] = runs.len() as u32 - 1;
        }
        // The ends at the vertex of piece i's end e (which has one).
        let at = |i: usize, e: usize| {
            ends[runs[run_of[2 * i + e] as usize].1.clone()]
                .iter()
                .map(move |&k| (unpack(k).1, unpack(k).2))
        };
        let mut used = vec![false; ps.len()];
        // Walks from end `end` of piece `first` through the pieces after it.
        let walk = |first: usize, end: usize, used: &mut [bool]| {
            let start = ps[first].ends[end];
            let mut points = vec![point(first, end)];
            let (mut piece, mut from) = (first, end);
            let mut closed = false;
            loop {
                used[piece] = true;
                let to = 1 - from;
                points.push(point(piece, to));
                let Some(v) = ps[piece].ends[to] else { break };
                if Some(v) == start && points.len() > 2 {
                    closed = true;
                    break;
                }
                // Go on along the unused piece that turns least on screen.
                let (p, q) = (point(piece, from), point(piece, to));
                let dir = norm2([q[0] - p[0], q[1] - p[1]]);
                let next = at(piece, to)
                    .filter(|(i, _)| !used[*i])
                    .map(|(i, e)| {
                        let r = point(i, 1 - e);
                        let d = norm2([r[0] - q[0], r[1] - q[1]]);
                        (d[0] * dir[0] + d[1] * dir[1], i, e)
                    })
                    .max_by(|x, y| x.0.total_cmp(&y.0).then(y.1.cmp(&x.1)));
                match next {
                    Some((_, i, e)) => (piece, from) = (i, e),
                    None => break,
                }
            }
            if closed {
                points.pop();
            }
            Polyline {
                kind,
                points,
                closed,
            }
        };
        // Open chains first: from piece ends short of a vertex, then from
        // vertices with an odd number of piece ends; then loops.
        for i in 0..ps.len() {
            if used[i] {
                continue;
            }
            if let Some(end) = ps[i].ends.iter().position(|v| v.is_none()) {
                out.push(walk(i, end, &mut used));
            }
        }
        let odd = runs.iter().filter(|(_, r)| r.len() % 2 == 1);
        let starts: Vec<std::ops::Range<usize>> =
            odd.chain(runs.iter()).map(|(_, r)| r.clone()).collect();
        for r in starts {
            while let Some(&k) = ends[r.clone()].iter().find(|&&k| !used[unpack(k).1]) {
                let (_, i, e) = unpack(k);
                out.push(walk(i, e, &mut used));
            }
        }
    }
    out
}

/// Sorts piece-end keys (vertex in the high 32 bits, ascending in their
/// low bits as [`chain`] makes them) ascending: a stable least-significant
/// digit radix sort on the vertex, 11 bits a pass and only as many passes
/// as the largest vertex needs (two for 4 million vertices). The low bits
/// being ascending already, stable passes on the vertex alone give the
/// order of a sort on the whole key, in a few counting passes instead of
/// a comparison sort's n·log n.
fn sort_by_vertex(keys: &mut Vec<u64>) {
    const BITS: u32 = 11;
    let top = keys.iter().map(|k| k >> 32).max().unwrap_or(0);
    let passes = (u64::BITS - top.leading_zeros()).div_ceil(BITS);
    let mut out = vec![0u64; keys.len()];
    for pass in 0..passes {
        let digit = |k: u64| ((k >> (32 + pass * BITS)) & ((1 << BITS) - 1)) as usize;
        let mut at = [0usize; 1 << BITS];
        for &k in keys.iter() {
            at[digit(k)] += 1;
        }
        let mut sum = 0;
        for a in at.iter_mut() {
            (*a, sum) = (sum, sum + *a);
        }
        for &k in keys.iter() {
            out[at[digit(k)]] = k;
            at[digit(k)] += 1;
        }
        std::mem::swap(keys, &mut out);
    }
}

fn norm2(v: [f32; 2]) -> [f32; 2] {
    let l = (v[0] * v[0] + v[1] * v[1]).sqrt();
    if l > 0.0 {
        [v[0] / l, v[1] / l]
    } else {
        [0.0; 2]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use specula_raster::Camera;

    /// xorshift64* in [0, 1).
    fn rng(seed: u64) -> impl FnMut() -> f32 {
        let mut state = seed.max(1);
        move || {
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    #[test]
    fn piece_ends_sorted_by_vertex_are_sorted_whole() {
        // Keys as `chain` makes them (low bits ascending), vertices from a
        // few to millions apart (one to three radix passes), against the
        // comparison sort of the whole key.
        let mut next = rng(5);
        for (case, top) in [1u64, 7, 2047, 2048, 100_000, 5_000_000, u32::MAX as u64]
            .into_iter()
            .enumerate()
        {
            let mut keys = Vec::new();
            for i in 0..3000u64 {
                if next() < 0.8 {
                    let v = ((next() as f64 * top as f64) as u64).min(top);
                    keys.push(v << 32 | i);
                }
            }
            let mut want = keys.clone();
            want.sort_unstable();
            let mut got = keys;
            sort_by_vertex(&mut got);
            assert_eq!(got, want, "case {case}");
        }
        let mut empty = Vec::new();
        sort_by_vertex(&mut empty);
        assert!(empty.is_empty());
    }

    #[test]
    fn a_sample_is_seen_against_the_largest_depth_of_its_neighbourhood() {
        // `DepthView::seen` (its fixed 3×3 path inside the buffer and its
        // general path at the borders and with supersampling) against the
        // rule written plainly here: the largest depth of the samples within
        // `ssaa` of the sample's, clipped to the buffer, times 1 + bias.
        let mut next = rng(11);
        let (w, h) = (37usize, 23usize);
        let depth: Vec<f32> = (0..w * h)
            .map(|_| {
                if next() < 0.15 {
                    f32::INFINITY
                } else {
                    1.0 + 9.0 * next()
                }
            })
            .collect();
        let (mut seen, mut hidden) = (0, 0);
        for ssaa in [1usize, 2] {
            let view = DepthView {
                depth: &depth,
                width: w,
                height: h,
                ssaa,
            };
            for _ in 0..20_000 {
                // Points a little outside the buffer too.
                let (sx, sy) = (next() * (w + 2) as f32 - 1.0, next() * (h + 2) as f32 - 1.0);
                // A depth near one of the buffer's, to meet the threshold.
                let near = depth[(next() * (w * h) as f32) as usize % (w * h)];
                let wz = if near.is_finite() {
                    near * (0.97 + 0.06 * next())
                } else {
                    1.0 + 12.0 * next()
                };
                let want = if sx >= 0.0 && sy >= 0.0 && sx < w as f32 && sy < h as f32 {
                    let (x, y, r) = (sx.floor() as i64, sy.floor() as i64, ssaa as i64);
                    let mut m = 0.0f32;
                    for yy in (y - r).max(0)..=(y + r).min(h as i64 - 1) {
                        for xx in (x - r).max(0)..=(x + r).min(w as i64 - 1) {
                            let d = depth[yy as usize * w + xx as usize];
                            if d > m {
                                m = d;
                            }
                        }
                    }
                    wz <= m * (1.0 + DEPTH_BIAS)
                } else {
                    false
                };
                assert_eq!(
                    view.seen(sx, sy, wz),
                    want,
                    "({sx}, {sy}) at {wz}, ssaa {ssaa}"
                );
                if want {
                    seen += 1;
                } else {
                    hidden += 1;
                }
            }
        }
        assert!(
            seen > 8_000 && hidden > 4_000,
            "{seen} seen, {hidden} hidden"
        );
    }

    #[test]
    fn testing_only_the_samples_that_can_be_on_the_image_finds_the_same_pieces() {
        let mut next = rng(7);
        // Lone triangles (every edge a boundary) from behind the eye to far
        // off to the sides, a few huge ones, over a blocky depth buffer.
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        for t in 0..3000u32 {
            let scale = if t % 100 == 0 { 1e5 } else { 1.0 };
            let c = Vec3::new(
                next() * 60.0 - 30.0,
                next() * 40.0 - 20.0,
                next() * 40.0 - 32.0,
            );
            for _ in 0..3 {
                let d = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 8.0 * scale;
                positions.push(c + d);
            }
            triangles.push([3 * t, 3 * t + 1, 3 * t + 2]);
        }
        let mesh = MeshEdges::new(
            &positions,
            &triangles,
            &vec![0; triangles.len()],
            &[EdgeKind::Boundary],
            60.0,
        );
        let camera = Camera {
            eye: Vec3::new(0.0, 0.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 50.0,
            near: 0.5,
            far: 100.0,
        };
        let (w, h) = (160usize, 90usize);
        let depth: Vec<f32> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w / 13, i / w / 11);
                let v = ((x * 7 + y * 13) % 10) as f32;
                if v < 2.0 {
                    f32::INFINITY
                } else {
                    3.0 * v
                }
            })
            .collect();
        let view = camera.view(w as u32, h as u32);
        let drawn = mesh.classify(camera.eye);
        assert!(drawn.len() > 8900, "{}", drawn.len());
        let (mut clipped, mut pieces) = (0, 0);
        for ssaa in [1, 2] {
            let dv = DepthView {
                depth: &depth,
                width: w,
                height: h,
                ssaa,
            };
            for &edge in &drawn {
                let c = |v: u32| view.view_proj * Vec4::from((mesh.points[v as usize], 1.0));
                let (ca, cb) = (c(edge.0), c(edge.1));
                let (mut got, mut want) = (Vec::new(), Vec::new());
                edge_pieces(edge, [ca, cb], camera.near, &dv, &mut got, true);
                edge_pieces(edge, [ca, cb], camera.near, &dv, &mut want, false);
                assert_eq!(got, want, "edge {edge:?}");
                pieces += got.len();
                if ca.w >= camera.near && cb.w >= camera.near {
                    let len = 4 * (w + h);
                    match on_image(ca, cb, [0.0, 1.0], len + 1, [w as f32, h as f32]) {
                        Some(r) if *r.start() == 0 && *r.end() == len => {}
                        _ => clipped += 1,
                    }
                }
            }
        }
        // Many edges were cut short or skipped, and many pieces were found.
        assert!(
            clipped > 3000 && pieces > 1000,
            "{clipped} clipped, {pieces} pieces"
        );
    }
}
