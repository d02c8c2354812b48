//! The reference: ∫ over a polygon of f(wi, wo) cos θi dωi for any BRDF,
//! by adaptive quadrature in f64, with an error estimate. What the LTC
//! approximation is measured against (core/tests/ltc.rs, `specula
//! fit-ltc`), what `area_lights = "reference"` renders and what `eval`
//! answers for `"method": "reference"`.
//!
//! 1. One-sided lights whose back faces the origin give 0 (the side is that
//!    of Newell's normal, as for the runtime).
//! 2. The polygon (planar, relative to the shading point) is clipped to
//!    z ≥ 0 in 3-D (Sutherland–Hodgman; a concave polygon may come out as
//!    pieces joined by zero-width bridges on the horizon, which the signed
//!    fan below integrates to nothing).
//! 3. Signed fan from the first vertex: ∫ over any closed polygon = Σ
//!    ±∫ over the triangles (v₀, vᵢ, vᵢ₊₁), + where a triangle turns like
//!    the polygon, − where it does not.
//! 4. Each triangle is integrated over its area with
//!    dω = |n̂·X| / |X|³ dA, by a 6 × 6 Gauss–Legendre rule on the square
//!    mapped onto it (Duffy), and refined globally: every node knows the
//!    rule's value on itself and on its four midpoint children; the node
//!    whose difference is largest is split, until the sum of differences
//!    (the error estimate: each is a bound on the error of the coarse value,
//!    far above that of the children's sum that is used) is below the
//!    tolerance or the node budget is spent.
//!
//! The estimate is checked against an independent Monte Carlo of the BRDF
//! over the polygon's area in core/tests/ltc.rs.

use crate::brdf::Brdf;
use crate::light::PolygonLocal;
use crate::quadrature::GaussLegendre;
use crate::real::Real;
use crate::vec3::{Rgb, V3};
use std::collections::BinaryHeap;
use std::sync::OnceLock;

/// A converged value and its estimated absolute error (the largest over
/// the channels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    pub value: [f64; 3],
    pub error: f64,
}

/// How far [`integrate_polygon`] refines.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// Stop when the error estimate is below `relative` × the value's
    /// largest channel, or below `absolute`.
    pub relative: f64,
    pub absolute: f64,
    /// Most triangles refined (each costs 4 × 36 evaluations).
    pub max_nodes: usize,
}

impl Tolerance {
    /// What tests and `eval` use: 1e-5 relative.
    pub const FINE: Tolerance = Tolerance {
        relative: 1e-5,
        absolute: 1e-9,
        max_nodes: 200_000,
    };
    /// What reference renders use per pixel: 1e-3 relative.
    pub(crate) const RENDER: Tolerance = Tolerance {
        relative: 1e-3,
        absolute: 1e-6,
        max_nodes: 4_000,
    };
}

/// Newell's normal: twice the polygon's vector area, pointing to the side
/// from which the vertices run counter-clockwise (its front).
pub(crate) fn newell_normal(v: &[V3<f64>]) -> V3<f64> {
    let mut n = V3::zero();
    for (k, a) in v.iter().enumerate() {
        n += a.cross(v[(k + 1) % v.len()]);
    }
    n
}

/// The part of the polygon with z ≥ 0 (Sutherland–Hodgman).
pub(crate) fn clip_to_horizon(v: &[V3<f64>]) -> Vec<V3<f64>> {
    let mut out = Vec::with_capacity(v.len() + 2);
    for (k, &a) in v.iter().enumerate() {
        let b = v[(k + 1) % v.len()];
        if a.z >= 0.0 {
            out.push(a);
        }
        if (a.z >= 0.0) != (b.z >= 0.0) {
            // a.z and b.z differ in sign, so the denominator is not zero.
            let t = a.z / (a.z - b.z);
            let mut p = V3::lerp(a, b, t);
            p.z = 0.0;
            out.push(p);
        }
    }
    out
}

fn rule() -> &'static GaussLegendre {
    static R: OnceLock<GaussLegendre> = OnceLock::new();
    R.get_or_init(|| GaussLegendre::new(6))
}

/// ∫ over triangle (p0, p1, p2) of f_cos(X̂) |n̂·X| / |X|³ dA: the square
/// (s, t) ∈ [0, 1]² maps to X = p0 + s (p1 − p0) + s t (p2 − p1), with
/// Jacobian s |(p1 − p0) × (p2 − p1)|.
fn triangle_rule(
    p: &[V3<f64>; 3],
    unit_n: V3<f64>,
    f_cos: &dyn Fn(V3<f64>) -> [f64; 3],
) -> [f64; 3] {
    let (e1, e2) = (p[1] - p[0], p[2] - p[1]);
    let area2 = e1.cross(e2).length();
    if area2 == 0.0 {
        return [0.0; 3];
    }
    let g = rule();
    g.integrate(0.0, 1.0, |s| {
        g.integrate(0.0, 1.0, |t| {
            let x = p[0] + e1 * s + e2 * (s * t);
            let r2 = x.length_squared();
            if r2 == 0.0 {
                return [0.0; 3];
            }
            let r = r2.sqrt();
            let w = x * (1.0 / r);
            if w.z <= 0.0 {
                return [0.0; 3];
            }
            let k = unit_n.dot(x).abs() / (r2 * r) * s * area2;
            f_cos(w).map(|c| c * k)
        })
    })
}

struct Node {
    tri: [V3<f64>; 3],
    sign: f64,
    children: [[f64; 3]; 4],
    error: f64,
}

impl Node {
    fn new(
        tri: [V3<f64>; 3],
        sign: f64,
        coarse: [f64; 3],
        n: V3<f64>,
        f: &dyn Fn(V3<f64>) -> [f64; 3],
    ) -> Node {
        let children = Node::split(&tri).map(|c| triangle_rule(&c, n, f));
        let error = (0..3)
            .map(|c| (coarse[c] - children.iter().map(|k| k[c]).sum::<f64>()).abs())
            .fold(0.0, f64::max);
        Node {
            tri,
            sign,
            children,
            error,
        }
    }

    fn split(t: &[V3<f64>; 3]) -> [[V3<f64>; 3]; 4] {
        let m = |a: V3<f64>, b: V3<f64>| (a + b) * 0.5;
        let (m01, m12, m20) = (m(t[0], t[1]), m(t[1], t[2]), m(t[2], t[0]));
        [
            [t[0], m01, m20],
            [m01, t[1], m12],
            [m20, m12, t[2]],
            [m01, m12, m20],
        ]
    }

    fn value(&self) -> [f64; 3] {
        core::array::from_fn(|c| self.sign * self.children.iter().map(|k| k[c]).sum::<f64>())
    }
}

impl PartialEq for Node {
    fn eq(&self, o: &Self) -> bool {
        self.error == o.error
    }
}
impl Eq for Node {}
impl PartialOrd for Node {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Node {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.error.total_cmp(&o.error)
    }
}

/// ∫ over the polygon of `f_cos(wi)` dωi, where `f_cos` is f(wi, wo) cos θi
/// for a unit `wi` with z > 0; vertices relative to the shading point, in
/// its local frame (normal +Z), planar, any simple polygon. See the module
/// docs.
pub fn integrate_polygon(
    vertices: &[V3<f64>],
    two_sided: bool,
    f_cos: &dyn Fn(V3<f64>) -> [f64; 3],
    tol: Tolerance,
) -> Estimate {
    integrate_polygon_toward(vertices, two_sided, f_cos, tol, None)
}

/// Where a lobe narrower than the quadrature's first nodes peaks, for
/// [`integrate_polygon_toward`]: its unit direction and the angle (radians)
/// the triangles around it are graded down to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Peak {
    pub direction: V3<f64>,
    pub angle: f64,
}

/// [`integrate_polygon`] for an integrand that may peak sharply around
/// `peak` (a glossy lobe around the mirror direction). Adaptive refinement
/// alone can miss such a lobe: when it is narrower than the spacing of the
/// first rule's nodes, every node and every child reads its tail, the
/// coarse and refined values agree, and the estimate claims a converged
/// value near zero. So when the peak direction meets the polygon's plane,
/// the signed fan is taken from that point, or from the nearest point of
/// the polygon's edge when it falls outside (a fan from any point of the
/// plane integrates a closed polygon), and each triangle of the fan is
/// split toward it, the three other children refined as usual, until the
/// triangle at the peak spans less than `peak.angle` as seen from the
/// origin. The Duffy map clusters nodes at that corner.
pub fn integrate_polygon_toward(
    vertices: &[V3<f64>],
    two_sided: bool,
    f_cos: &dyn Fn(V3<f64>) -> [f64; 3],
    tol: Tolerance,
    peak: Option<Peak>,
) -> Estimate {
    let zero = Estimate {
        value: [0.0; 3],
        error: 0.0,
    };
    if vertices.len() < 3 {
        return zero;
    }
    let n = newell_normal(vertices);
    let len = n.length();
    if !(len > 0.0 && len.is_finite()) {
        return zero;
    }
    let unit_n = n * (1.0 / len);
    // The origin on the front side: n·(0 − v₀) > 0.
    let facing = -unit_n.dot(vertices[0]);
    if facing == 0.0 || (!two_sided && facing < 0.0) {
        return zero;
    }
    let c = clip_to_horizon(vertices);
    if c.len() < 3 {
        return zero;
    }
    let mut heap = BinaryHeap::new();
    let mut nodes = 0;
    let apex = peak.and_then(|p| {
        on_plane(p.direction, unit_n, c[0]).map(|x| (nearest_in_polygon(x, &c, unit_n), p.angle))
    });
    match apex {
        Some((apex, angle)) => {
            for k in 0..c.len() {
                let tri = [apex, c[k], c[(k + 1) % c.len()]];
                let turn = (tri[1] - tri[0]).cross(tri[2] - tri[0]).dot(unit_n);
                if turn == 0.0 {
                    continue;
                }
                nodes += graded(tri, turn.signum(), angle, unit_n, f_cos, &mut heap);
            }
        }
        None => {
            for k in 1..c.len() - 1 {
                let tri = [c[0], c[k], c[k + 1]];
                let turn = (tri[1] - tri[0]).cross(tri[2] - tri[0]).dot(unit_n);
                if turn == 0.0 {
                    continue;
                }
                let coarse = triangle_rule(&tri, unit_n, f_cos);
                heap.push(Node::new(tri, turn.signum(), coarse, unit_n, f_cos));
                nodes += 1;
            }
        }
    }
    let total = |h: &BinaryHeap<Node>| {
        let mut v = [0.0; 3];
        let mut e = 0.0;
        for node in h {
            let nv = node.value();
            for c in 0..3 {
                v[c] += nv[c];
            }
            e += node.error;
        }
        (v, e)
    };
    let (mut value, mut error) = total(&heap);
    let target = |v: &[f64; 3]| {
        (tol.relative * v.iter().fold(0.0f64, |m, x| m.max(x.abs()))).max(tol.absolute)
    };
    while error > target(&value) && nodes < tol.max_nodes {
        let Some(worst) = heap.pop() else { break };
        let old = worst.value();
        error -= worst.error;
        for (t, coarse) in Node::split(&worst.tri).iter().zip(worst.children) {
            let node = Node::new(*t, worst.sign, coarse, unit_n, f_cos);
            let nv = node.value();
            for c in 0..3 {
                value[c] += nv[c];
            }
            error += node.error;
            heap.push(node);
        }
        for c in 0..3 {
            value[c] -= old[c];
        }
        nodes += 4;
    }
    // The running sums were updated by differences; the final ones are
    // summed afresh so that no rounding drift is reported.
    let (value, error) = total(&heap);
    Estimate { value, error }
}

/// Where the ray from the origin along unit `d` meets the plane through
/// `p` with unit normal `n`, if it does in front of the origin and above
/// the horizon.
fn on_plane(d: V3<f64>, n: V3<f64>, p: V3<f64>) -> Option<V3<f64>> {
    let t = n.dot(p) / n.dot(d);
    let x = d * t;
    (t > 0.0 && t.is_finite() && x.z > 0.0).then_some(x)
}

/// `x` (a point of the polygon's plane) when it is inside polygon `c`
/// (even–odd rule, in the plane's two coordinates that `n` tilts least),
/// else the nearest point of `c`'s boundary: a fan from a point far
/// outside would integrate the polygon as the difference of large, thin
/// triangles.
fn nearest_in_polygon(x: V3<f64>, c: &[V3<f64>], n: V3<f64>) -> V3<f64> {
    let (i, j) = if n.z.abs() >= n.x.abs() && n.z.abs() >= n.y.abs() {
        (0, 1)
    } else if n.y.abs() >= n.x.abs() {
        (2, 0)
    } else {
        (1, 2)
    };
    let at = |v: V3<f64>, k: usize| [v.x, v.y, v.z][k];
    let (px, py) = (at(x, i), at(x, j));
    let mut inside = false;
    let mut best = (f64::INFINITY, x);
    for k in 0..c.len() {
        let (a, b) = (c[k], c[(k + 1) % c.len()]);
        let (ax, ay, bx, by) = (at(a, i), at(a, j), at(b, i), at(b, j));
        if (ay > py) != (by > py) && px < ax + (py - ay) / (by - ay) * (bx - ax) {
            inside = !inside;
        }
        let ab = b - a;
        let len2 = ab.length_squared();
        let t = if len2 > 0.0 {
            ((x - a).dot(ab) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let q = a + ab * t;
        let d = (x - q).length_squared();
        if d < best.0 {
            best = (d, q);
        }
    }
    if inside {
        x
    } else {
        best.1
    }
}

/// The angle between the directions of `a` and `b` from the origin
/// (atan2 of |a × b| and a · b: accurate for tiny angles).
fn angle_between(a: V3<f64>, b: V3<f64>) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// Pushes triangle `tri` (its corner 0 at the peak) onto `heap` split
/// toward corner 0 until the triangle there spans less than `angle` from
/// the origin (at most 64 times); the other children go on the heap as
/// they are. Returns the nodes pushed.
fn graded(
    mut tri: [V3<f64>; 3],
    sign: f64,
    angle: f64,
    n: V3<f64>,
    f: &dyn Fn(V3<f64>) -> [f64; 3],
    heap: &mut BinaryHeap<Node>,
) -> usize {
    let mut pushed = 0;
    for _ in 0..64 {
        let span = angle_between(tri[0], tri[1]).max(angle_between(tri[0], tri[2]));
        if span.is_nan() || span <= angle {
            break;
        }
        let [corner, rest @ ..] = Node::split(&tri);
        for t in rest {
            let coarse = triangle_rule(&t, n, f);
            heap.push(Node::new(t, sign, coarse, n, f));
            pushed += 1;
        }
        tri = corner;
    }
    let coarse = triangle_rule(&tri, n, f);
    heap.push(Node::new(tri, sign, coarse, n, f));
    pushed + 1
}

/// The reference for every lane of a packet: each lane's parameters, view
/// and polygon taken to f64 and integrated at `Tolerance::RENDER` with the
/// model's own f cos θi. Slow (thousands of BRDF evaluations per lane); for
/// `area_lights = "reference"`.
pub fn polygon_reference_lanes<B: Brdf, R: Real>(
    brdf: &B,
    params: &B::Params<R>,
    wo: V3<R>,
    poly: &PolygonLocal<R>,
) -> Rgb<R> {
    let mut out = [[0.0f32; 8]; 3];
    #[allow(clippy::needless_range_loop)] // `lane` indexes lanes of R, not an array
    for lane in 0..R::LANES {
        let get = |v: V3<R>| V3::new(v.x.lane(lane), v.y.lane(lane), v.z.lane(lane));
        let wo = get(wo).normalize_or(V3::new(0.0, 0.0, 1.0));
        let p = brdf.prepare_with(&brdf.pixel(&B::params_lane(params, lane)), wo);
        let verts: Vec<V3<f64>> = poly.vertices().iter().map(|v| get(*v)).collect();
        let f = |wi: V3<f64>| {
            let c = brdf.f_cos_local(&p, wi);
            [c.x, c.y, c.z]
        };
        let e = integrate_polygon(&verts, poly.two_sided, &f, Tolerance::RENDER);
        for (o, v) in out.iter_mut().zip(e.value) {
            o[lane] = v as f32;
        }
    }
    Rgb::new(R::load(&out[0]), R::load(&out[1]), R::load(&out[2]))
}
