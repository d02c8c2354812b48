//! The clamped-cosine integral over a polygon, clipped to the upper
//! hemisphere exactly, in lane arithmetic (f64 / f32 / f32x8 from one
//! source).
//!
//! Lambert's formula [Lambert1760; Arvo95]: for a spherical polygon
//! P above the horizon with great-arc edges from vᵢ to vᵢ₊₁ (unit),
//!
//! (1/π) ∫_P cos θ dω = (1/2π) Σᵢ θᵢ ẑ·(vᵢ₊₁ × vᵢ)/|vᵢ₊₁ × vᵢ|,  θᵢ = ∠(vᵢ, vᵢ₊₁)
//!
//! (Stokes: a boundary sum, so it holds for any simple polygon, convex or
//! not). A planar polygon projects onto the sphere with great-arc edges (a
//! segment and the origin span a plane), so its vertices relative to the
//! shading point can be used directly. The sum is signed: positive when the
//! vertices run counter-clockwise seen from the origin, i.e. when the
//! polygon shows its front (the side from which its vertices run
//! counter-clockwise) to the shading point.
//!
//! **Edge integral.** θᵢ = atan2(|a × b|, a·b) is accurate for every angle,
//! where acos(a·b) loses half the digits near 0 and π (its slope is
//! infinite there: an f32 rounding of a·b near −1 moves θ by 3e-4). For
//! nearly parallel vertices θ ≈ |a × b| and the ratio θ/|a × b| → 1; for
//! nearly antipodal ones θ → π and ẑ·(a × b)/|a × b| is the z of the unit
//! normal of the edge's plane, bounded by 1 (its conditioning is that of the
//! plane itself, set by the input vertices).
//!
//! **Clipping.** Sutherland–Hodgman against z ≥ 0, streamed edge by edge so
//! that no clipped vertex list is formed (lanes clip differently): each
//! edge contributes its part above the horizon (from its first point, or
//! the horizon crossing, to its last point or the crossing), and consecutive
//! parts are joined along the horizon. Every crossing of a planar polygon
//! lies on one line (its plane ∩ z = 0) not through the origin, so the
//! horizon joins of a concave polygon clipped into several pieces sum to the
//! same angles as the pieces' own horizon edges: the sum stays exact for
//! non-convex polygons. Vertices with z = 0 count as above.

use crate::real::Real;
use crate::vec3::V3;

/// Below this |a × (b − a)| an edge's normal is not formed: its z-part is
/// as small, so the edge contributes nothing measurable. A normal f32
/// number, so that dividing by it stays finite.
const MIN_CROSS: f64 = 1e-30;

/// θ ẑ·n̂ of the great arc from `a` to `b` (points, any length;
/// n̂ = a × b / |a × b|, θ = ∠(a, b)): the edge's part of 2π × the signed
/// integral (module docs, with the sign of a × b; callers sum edges in
/// reverse order). The normal is formed as a × (b − a): for nearly
/// parallel a and b the difference is exact (the points are close) and
/// the cross product keeps f32's relative precision, where the cross of
/// the two unit directions would cancel to |a × b| ± 6e-8. Scale-free:
/// points up to 1e9 from the origin (|n|² within f32's range).
#[inline(always)]
pub fn edge_integral<R: Real>(a: V3<R>, b: V3<R>) -> R {
    let n = a.cross(b - a);
    let s = n.length();
    let theta = s.atan2(a.dot(b));
    // s = 0 only for points in line with the origin, where n.z = 0 too.
    theta * n.z / s.max(R::splat(MIN_CROSS))
}

/// [`edge_integral`] for two points on the horizon (z = 0): the signed
/// angle from `a` to `b` about +z, one atan2 and no square root.
#[inline(always)]
fn horizon_integral<R: Real>(a: V3<R>, b: V3<R>) -> R {
    let cz = a.x * b.y - a.y * b.x;
    cz.atan2(a.x.mul_add(b.x, a.y * b.y))
}

/// The point where the segment from `a` to `b` meets the horizon, for
/// lanes where a.z and b.z have opposite signs (other lanes get a finite
/// unused value): (a |b.z| + b |a.z|) / (|a.z| + |b.z|), a point of the
/// segment with z = 0.
#[inline(always)]
fn horizon_crossing<R: Real>(a: V3<R>, b: V3<R>) -> V3<R> {
    let (wa, wb) = (b.z.abs(), a.z.abs());
    let k = R::ONE / (wa + wb).max(R::splat(MIN_CROSS));
    V3::new(
        a.x.mul_add(wa, b.x * wb) * k,
        a.y.mul_add(wa, b.y * wb) * k,
        R::ZERO,
    )
}

/// (1/π) ∫ cos θ dω over the part of the polygon with z ≥ 0, signed
/// (module docs): the form factor from the origin, positive when the
/// polygon's front faces the origin. `vertices` are relative to the origin
/// (not normalized, not clipped, within 1e9 of it); any simple polygon of
/// ≥ 3 vertices; a vertex at the origin itself contributes nothing.
#[inline(always)]
pub fn form_factor_signed<R: Real>(vertices: &[V3<R>]) -> R {
    let n = vertices.len();
    let mut sum = R::ZERO;
    // End of the last part above the horizon, and the start of the first.
    let mut last = V3::zero();
    let mut first = V3::zero();
    let mut have: R::Mask = R::ZERO.lt(R::ZERO);
    let mut a = vertices[n - 1];
    for &v in vertices {
        let b = v;
        let (above_a, above_b) = (a.z.ge(R::ZERO), b.z.ge(R::ZERO));
        let p = horizon_crossing(a, b);
        let start = V3::select(above_a, a, p);
        let end = V3::select(above_b, b, p);
        let part = above_a | above_b;
        // Edges summed b → a: positive for counter-clockwise from the origin.
        let e = edge_integral(end, start);
        // Join along the horizon from the previous part's end to this start
        // (both on the horizon whenever they differ; equal points give 0).
        let j = horizon_integral(start, last);
        sum += R::select(part, e, R::ZERO) + R::select(part & have, j, R::ZERO);
        first = V3::select(part & !have, start, first);
        last = V3::select(part, end, last);
        have = have | part;
        a = b;
    }
    sum += R::select(have, horizon_integral(first, last), R::ZERO);
    sum * R::splat(0.5 * core::f64::consts::FRAC_1_PI)
}

/// The form factor of a polygon light: of its front only
/// (`two_sided` = false: zero when its back faces the origin), or of
/// either side.
#[inline(always)]
pub fn form_factor<R: Real>(vertices: &[V3<R>], two_sided: bool) -> R {
    let f = form_factor_signed(vertices);
    if two_sided {
        f.abs()
    } else {
        f.max(R::ZERO)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> V3<f64> {
        V3::new(x, y, z)
    }

    #[test]
    fn a_small_square_overhead_facing_down_has_its_projected_area() {
        // Counter-clockwise seen from below (the origin): x then −y.
        let e = 1e-3;
        let q = [v(-e, -e, 1.0), v(-e, e, 1.0), v(e, e, 1.0), v(e, -e, 1.0)];
        let f = form_factor_signed(&q);
        // Solid angle ≈ (2e)², cos ≈ 1: F ≈ 4e²/π.
        let want = 4.0 * e * e / core::f64::consts::PI;
        assert!((f / want - 1.0).abs() < 1e-5, "{f} vs {want}");
        let back: Vec<_> = q.iter().rev().copied().collect();
        assert!((form_factor_signed(&back) + f).abs() < 1e-18);
        assert_eq!(form_factor(&back, false), 0.0);
        assert_eq!(form_factor(&back, true), f);
    }

    #[test]
    fn equal_and_opposite_points_contribute_nothing() {
        let a = v(0.3, -0.4, 0.5).normalize();
        assert_eq!(edge_integral(a, a), 0.0);
        assert_eq!(edge_integral(a, -a), 0.0);
    }
}
