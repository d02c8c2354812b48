//! Which parts of an edge the eye sees: sampling the projected edge
//! against the depth buffer (see the parent module).

use super::*;

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

#[cfg(test)]
mod tests {
    use super::super::rng;
    use super::*;
    use specula_raster::Camera;

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
