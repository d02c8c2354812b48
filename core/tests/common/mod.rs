//! Test polygons shared by the LTC tests: the cases of the LTC error
//! table (overhead, mirror direction, tilted, straddling, near and below
//! the horizon).

#![allow(dead_code)]

use specula_core::light::{PolygonLocal, MAX_POLYGON_VERTICES};
use specula_core::{f32x8, Brdf, Real, V3};

pub fn v(x: f64, y: f64, z: f64) -> V3<f64> {
    V3::new(x, y, z)
}

pub fn poly<R: Real>(q: &[V3<R>], two_sided: bool) -> PolygonLocal<R> {
    let mut p = PolygonLocal {
        vertices: [V3::new(R::ZERO, R::ZERO, R::ZERO); MAX_POLYGON_VERTICES],
        len: q.len(),
        two_sided,
    };
    p.vertices[..q.len()].copy_from_slice(q);
    p
}

/// A square of side `s` centred at `c`, facing the origin (front toward
/// it), turned by `twist` about its normal.
pub fn facing_square(c: V3<f64>, s: f64, twist: f64) -> Vec<V3<f64>> {
    let n = (c * -1.0).normalize();
    let up = if n.z.abs() < 0.9 {
        v(0.0, 0.0, 1.0)
    } else {
        v(1.0, 0.0, 0.0)
    };
    let e1 = up.cross(n).normalize();
    let e2 = n.cross(e1);
    let (sn, cs) = twist.sin_cos();
    let (a, b) = (e1 * cs + e2 * sn, e2 * cs - e1 * sn);
    let h = s / 2.0;
    // Counter-clockwise seen from the origin: a, then b, around −n.
    vec![
        c - a * h - b * h,
        c - a * h + b * h,
        c + a * h + b * h,
        c + a * h - b * h,
    ]
}

/// The test polygons for a view at θo (in the xz-plane, x > 0): name,
/// vertices (front toward the origin unless reversed below).
pub fn polygons(theta: f64) -> Vec<(&'static str, Vec<V3<f64>>)> {
    let mirror = v(-theta.sin(), 0.0, theta.cos());
    let mut out = vec![
        ("overhead quad", facing_square(v(0.0, 0.0, 1.5), 1.0, 0.3)),
        ("mirror quad", facing_square(mirror * 2.0, 0.8, 0.0)),
        ("mirror small quad", facing_square(mirror * 4.0, 0.3, 0.5)),
        ("tilted quad", facing_square(v(0.8, 1.2, 1.0), 1.2, 0.7)),
        (
            "tilted triangle",
            vec![v(-1.5, -0.6, 0.9), v(-0.4, 0.9, 1.6), v(-1.0, 1.0, 0.3)],
        ),
        (
            "straddling wall",
            vec![
                v(-1.5, -1.0, -0.5),
                v(-1.5, -1.0, 1.0),
                v(-1.5, 1.0, 1.0),
                v(-1.5, 1.0, -0.5),
            ],
        ),
        (
            "straddling triangle",
            vec![v(0.4, -1.5, -0.6), v(0.4, -1.5, 1.2), v(-1.2, -1.5, 0.2)],
        ),
        (
            "low wall (horizon)",
            vec![
                v(-3.0, -2.0, 0.02),
                v(-3.0, -2.0, 0.6),
                v(-3.0, 2.0, 0.6),
                v(-3.0, 2.0, 0.02),
            ],
        ),
        (
            "below",
            vec![
                v(-1.0, -1.0, -0.3),
                v(-1.0, 1.0, -0.3),
                v(1.0, 1.0, -0.3),
                v(1.0, -1.0, -0.3),
            ],
        ),
    ];
    // Make every polygon face the origin (Newell normal against v₀).
    for (_, q) in out.iter_mut() {
        let mut n = v(0.0, 0.0, 0.0);
        for k in 0..q.len() {
            n += q[k].cross(q[(k + 1) % q.len()]);
        }
        if n.dot(q[0]) > 0.0 {
            q.reverse();
        }
    }
    out
}

pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

/// The largest |f32x8 lane − f64| and |f32 − f64| of `m`'s polygon
/// integral over views at 0–88° (three azimuths) and [`polygons`] of each:
/// the lane types against the exact one, on the same inputs.
pub fn worst_lanes_against_f64<B: Brdf>(m: &B) -> f64 {
    let mut worst = 0.0f64;
    for deg in [0.0f64, 20.0, 50.0, 75.0, 88.0] {
        let t = deg.to_radians();
        for phi in [0.0f64, 1.0, 2.5] {
            let wo = v(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos());
            for (_, q) in polygons(t) {
                let want = m.polygon_local(&m.prepare(wo), &poly(&q, false));
                let s8 = |x: f64| f32x8::splat(x as f32);
                let w8 = V3::new(s8(wo.x), s8(wo.y), s8(wo.z));
                let q8: Vec<_> = q
                    .iter()
                    .map(|p| V3::new(s8(p.x), s8(p.y), s8(p.z)))
                    .collect();
                let got = m.polygon_local(&m.prepare(w8), &poly(&q8, false));
                let s1 = |p: V3<f64>| V3::new(p.x as f32, p.y as f32, p.z as f32);
                let q1: Vec<_> = q.iter().map(|&p| s1(p)).collect();
                let one = m.polygon_local(&m.prepare(s1(wo)), &poly(&q1, false));
                for (a, b, c) in [
                    (got.x, want.x, one.x),
                    (got.y, want.y, one.y),
                    (got.z, want.z, one.z),
                ] {
                    for k in 0..8 {
                        worst = worst.max((a.lane(k) - b).abs());
                    }
                    worst = worst.max((c as f64 - b).abs());
                }
            }
        }
    }
    worst
}
