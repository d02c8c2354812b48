//! The NPR shaders' view of lights: the arccos approximation's error, and
//! a polygon light's vector irradiance against a numeric integral over its
//! area.

use specula_core::light::Light;
use specula_core::V3;
use specula_npr::lights::{acos_approx, for_each_light};
use specula_raster::ShadeEnv;

#[test]
fn acos_approximation_is_within_its_stated_error() {
    let mut worst = 0.0f64;
    for i in 0..=20000 {
        let x = -1.0 + i as f64 / 10000.0;
        worst = worst.max((acos_approx(x) - x.acos()).abs());
    }
    assert!(worst < 7e-5, "worst error {worst}");
    assert_eq!(acos_approx(1.0f64 + 1e-6), 0.0);
    assert!((acos_approx(-1.0f64 - 1e-6) - std::f64::consts::PI).abs() < 1e-9);
}

/// E·n at `p` for a unit-radiance planar polygon: ∫ cos θp cos θq / r² dA
/// over the polygon, by a fine midpoint rule on its triangle fan (front
/// side only).
fn irradiance_numeric(p: [f64; 3], n: [f64; 3], poly: &[[f64; 3]]) -> f64 {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let mut e = 0.0;
    let k = 400;
    for t in 1..poly.len() - 1 {
        let (a, b, c) = (poly[0], poly[t], poly[t + 1]);
        let (ab, ac) = (sub(b, a), sub(c, a));
        let area_n = cross(ab, ac); // front normal × 2·area (counter-clockwise)
        let area = dot(area_n, area_n).sqrt() / 2.0;
        let nq = area_n.map(|v| v / (2.0 * area));
        let da = area / (k * k) as f64;
        for i in 0..k {
            for j in 0..k - i {
                // Two sub-triangles per cell; midpoint of the upright one
                // and (where it exists) the inverted one.
                for (s, u) in [
                    (
                        (i as f64 + 1.0 / 3.0) / k as f64,
                        (j as f64 + 1.0 / 3.0) / k as f64,
                    ),
                    (
                        (i as f64 + 2.0 / 3.0) / k as f64,
                        (j as f64 + 2.0 / 3.0) / k as f64,
                    ),
                ] {
                    if s + u > 1.0 {
                        continue;
                    }
                    let q = [0, 1, 2].map(|d| a[d] + s * ab[d] + u * ac[d]);
                    let w = sub(q, p);
                    let r2 = dot(w, w);
                    let cos_p = dot(w, n) / r2.sqrt();
                    let cos_q = -dot(w, nq) / r2.sqrt();
                    if cos_p > 0.0 && cos_q > 0.0 {
                        e += cos_p * cos_q / r2 * da;
                    }
                }
            }
        }
    }
    e
}

#[test]
fn polygon_vector_irradiance_matches_the_area_integral() {
    // A square above the point, facing down (counter-clockwise seen from
    // below), and a tilted triangle; points and normals with the polygon
    // wholly above their horizon.
    let square = vec![
        [-0.5, 1.0, -0.5],
        [-0.5, 1.0, 0.5],
        [0.5, 1.0, 0.5],
        [0.5, 1.0, -0.5],
    ];
    let tri = vec![[0.2, 1.5, 0.0], [-0.6, 0.9, 0.4], [0.5, 0.8, 0.9]];
    let mut checked = 0;
    for mut poly in [square, tri] {
        // Orient each polygon to face the points below it, and pick a
        // point behind it.
        let (a, b, c) = (poly[0], poly[1], poly[2]);
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let mut nq = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        if nq[1] > 0.0 {
            poly.reverse();
            nq = nq.map(|v| -v);
        }
        let k = poly.len() as f64;
        let centre = [0, 1, 2].map(|d| poly.iter().map(|v| v[d]).sum::<f64>() / k);
        let behind_p = [0, 1, 2].map(|d| centre[d] - 2.0 * nq[d]);
        for (p, n) in [
            ([0.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            ([0.3, -0.2, 0.1], [0.2, 0.9, 0.1]),
            ([-0.4, 0.1, -0.3], [0.0, 0.8, -0.6]),
        ] {
            let len = f64::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            let n = n.map(|v: f64| v / len);
            let polygon = |two_sided| Light::Polygon {
                vertices: poly.iter().map(|v| v.map(|c| c as f32)).collect(),
                radiance: [1.0; 3],
                two_sided,
                method: Default::default(),
            };
            let light = polygon(false);
            let env = ShadeEnv {
                lights: std::slice::from_ref(&light),
                environment: None,
                env_map: None,
                shadows: None,
                pair_packets: false,
            };
            let mut got = 0.0;
            let pv = V3::new(p[0], p[1], p[2]);
            for_each_light(pv, &env, |wi: V3<f64>, e| {
                got += e.x * wi.dot(V3::new(n[0], n[1], n[2])).max(0.0);
            });
            // The vector irradiance is exact only for a polygon wholly
            // above the horizon (lights.rs); skip the other cases.
            let above = poly
                .iter()
                .all(|v| (0..3).map(|d| (v[d] - p[d]) * n[d]).sum::<f64>() > 0.0);
            if !above {
                continue;
            }
            checked += 1;
            let want = irradiance_numeric(p, n, &poly);
            assert!(want > 0.05, "the case must see the light: {want}");
            // Polygon vertices are f32 and the arccos is approximate.
            assert!(
                (got - want).abs() < 2e-4 * want.max(1.0),
                "p {p:?} n {n:?}: {got} vs {want}"
            );
            // Behind the polygon: nothing.
            let mut behind = 0.0;
            let bp = V3::new(behind_p[0], behind_p[1], behind_p[2]);
            for_each_light(bp, &env, |_, e: V3<f64>| behind += e.x);
            assert_eq!(behind, 0.0);
            // A two-sided light lights the point behind it like one seen
            // from the front (facing normal: toward the polygon).
            let two = polygon(true);
            let env2 = ShadeEnv {
                lights: std::slice::from_ref(&two),
                environment: None,
                env_map: None,
                shadows: None,
                pair_packets: false,
            };
            let ln = f64::sqrt(nq.iter().map(|v| v * v).sum::<f64>());
            let nb = nq.map(|v| v / ln);
            let mut got2 = 0.0;
            for_each_light(bp, &env2, |wi: V3<f64>, e| {
                got2 += e.x * wi.dot(V3::new(nb[0], nb[1], nb[2])).max(0.0);
            });
            // Its back seen from behind_p is the reversed polygon's front.
            let reversed: Vec<[f64; 3]> = poly.iter().rev().copied().collect();
            let want2 = irradiance_numeric(behind_p, nb, &reversed);
            assert!(
                (got2 - want2).abs() < 2e-4 * want2.max(1.0),
                "two-sided, behind: {got2} vs {want2}"
            );
        }
    }
    assert!(checked >= 5, "{checked} cases");
}

/// A spot light as the stylized shaders see it: the unit direction toward
/// it and I · a / d² · window, against KHR_lights_punctual's formulas
/// written here in f64.
#[test]
fn spot_lights_give_the_extensions_falloff() {
    let (inner, outer, range) = (0.2f64, 0.7f64, 6.0f64);
    let axis: [f64; 3] = [0.0, -0.6, -0.8];
    let light = Light::Spot {
        position: [0.0, 3.0, 4.0],
        direction: axis.map(|v| v as f32),
        intensity: [5.0, 2.5, 1.0],
        cos_inner: inner.cos() as f32,
        cos_outer: outer.cos() as f32,
        range: range as f32,
    };
    let lights = [light];
    let env = ShadeEnv {
        lights: &lights,
        environment: None,
        env_map: None,
        shadows: None,
        pair_packets: false,
    };
    let scale = 1.0 / (inner.cos() - outer.cos()).max(0.001);
    for p in [
        [0.0, 0.0, 0.0],
        [0.8, 0.0, 0.3],
        [-1.5, 0.2, -0.5],
        [2.5, 0.0, 0.0],
        [0.3, 1.0, 1.0],
    ] {
        let to: [f64; 3] = [-p[0], 3.0 - p[1], 4.0 - p[2]];
        let d = (to[0] * to[0] + to[1] * to[1] + to[2] * to[2]).sqrt();
        let cd = -(axis[0] * to[0] + axis[1] * to[1] + axis[2] * to[2]) / d;
        let a = ((cd - outer.cos()) * scale).clamp(0.0, 1.0).powi(2);
        let w = (1.0 - (d / range).powi(4)).clamp(0.0, 1.0);
        let mut seen = 0;
        for_each_light(V3::new(p[0], p[1], p[2]), &env, |wi, e| {
            seen += 1;
            let dir = [wi.x - to[0] / d, wi.y - to[1] / d, wi.z - to[2] / d];
            assert!(dir.iter().all(|v| v.abs() < 1e-6), "at {p:?}: {dir:?}");
            let want = [5.0, 2.5, 1.0].map(|i| i * a * w / (d * d));
            for (got, want) in [e.x, e.y, e.z].into_iter().zip(want) {
                assert!(
                    (got - want).abs() <= 1e-6 * want.max(1e-3),
                    "at {p:?}: {got} vs {want}"
                );
            }
        });
        assert_eq!(seen, 1);
    }
}
