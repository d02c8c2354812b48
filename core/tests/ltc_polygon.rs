//! The polygon integral against independent numbers: the analytic form
//! factor of a parallel rectangle, plainly written quadrature over tilted
//! and straddling rectangles, clipping identities (a vertex on the
//! horizon, all below, a concave polygon), nearly parallel and nearly
//! antipodal vertices in f32x8, f32x8 against f64; the reference
//! integration of a BRDF against an independent Monte Carlo, and its fan
//! from a peak direction inside, outside and beside the polygon.

use rand::{Rng, SeedableRng};
use specula_core::light::{PolygonLocal, MAX_POLYGON_VERTICES};
use specula_core::ltc::reference::{integrate_polygon, integrate_polygon_toward, Peak, Tolerance};
use specula_core::ltc::{form_factor, form_factor_signed};
use specula_core::models::microfacet::{Fresnel, Microfacet, MicrofacetParams, Ndf, Smith};
use specula_core::models::{Lambert, MetallicRoughness};
use specula_core::quadrature::GaussLegendre;
use specula_core::{f32x8, Brdf, Real, V3};
use std::f64::consts::PI;

fn v(x: f64, y: f64, z: f64) -> V3<f64> {
    V3::new(x, y, z)
}

/// Form factor from a point with normal +z to the rectangle [0, a] × [0, b]
/// in the plane z = c, the normal through one corner [Howell, config. B-3]:
/// F = (1/2π) [X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))].
fn corner(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
}

/// The same for the rectangle [x0, x1] × [y0, y1] at height c > 0, by
/// superposition of signed corner rectangles.
fn parallel_rect(x0: f64, x1: f64, y0: f64, y1: f64, c: f64) -> f64 {
    let f = |x: f64, y: f64| x.signum() * y.signum() * corner(x.abs(), y.abs(), c);
    f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0)
}

/// The rectangle's vertices, counter-clockwise seen from below (front
/// toward the origin).
fn rect_down(x0: f64, x1: f64, y0: f64, y1: f64, c: f64) -> Vec<V3<f64>> {
    vec![v(x0, y0, c), v(x0, y1, c), v(x1, y1, c), v(x1, y0, c)]
}

/// (1/π) ∫ over the parallelogram p + s e1 + t e2 (s, t ∈ [0, 1]) of
/// cos θ cos θ' / r² dA, only where the point is above the horizon:
/// Gauss–Legendre with `n` × `n` nodes on each of `k` × `k` panels.
fn quad_ff(p: V3<f64>, e1: V3<f64>, e2: V3<f64>, k: usize, n: usize) -> f64 {
    let g = GaussLegendre::new(n);
    let nrm = e1.cross(e2);
    let area = nrm.length();
    let nrm = nrm * (1.0 / area);
    let mut sum = 0.0;
    for i in 0..k {
        for j in 0..k {
            let (s0, t0) = (i as f64 / k as f64, j as f64 / k as f64);
            let h = 1.0 / k as f64;
            sum += g.integrate(s0, s0 + h, |s| {
                [g.integrate(t0, t0 + h, |t| {
                    let x = p + e1 * s + e2 * t;
                    let r2 = x.length_squared();
                    let r = r2.sqrt();
                    if x.z <= 0.0 {
                        return [0.0];
                    }
                    [(x.z / r) * (nrm.dot(x).abs() / r) / r2]
                })[0]]
            })[0];
        }
    }
    sum * area / PI
}

fn to_x8(p: &[V3<f64>]) -> Vec<V3<f32x8>> {
    p.iter()
        .map(|q| {
            V3::new(
                f32x8::splat(q.x as f32),
                f32x8::splat(q.y as f32),
                f32x8::splat(q.z as f32),
            )
        })
        .collect()
}

#[test]
fn parallel_rectangles_match_the_analytic_form_factor() {
    let cases = [
        (0.0, 1.0, 0.0, 2.0, 1.0),
        (-0.5, 0.5, -0.5, 0.5, 1.0),
        (-3.0, 4.0, 1.0, 2.5, 0.7),
        (2.0, 2.1, -0.05, 0.05, 3.0),
        (-50.0, 60.0, -40.0, 70.0, 1.0),
    ];
    for (x0, x1, y0, y1, c) in cases {
        let want = parallel_rect(x0, x1, y0, y1, c);
        let q = rect_down(x0, x1, y0, y1, c);
        let got = form_factor(&q, false);
        assert!(
            (got - want).abs() < 1e-12 * want.max(1e-3),
            "{:?}: {got} vs {want}",
            (x0, x1, y0, y1, c)
        );
        let got8 = form_factor(&to_x8(&q), false).lane(0);
        assert!(
            (got8 - want).abs() < 2e-6 * want.max(1e-2),
            "f32x8 {:?}: {got8} vs {want}",
            (x0, x1, y0, y1, c)
        );
        // Lambert through the identity: ρ F.
        let lam = Lambert {
            base_color: [0.2, 0.5, 0.9],
        };
        let poly = polygon_local(&q, false);
        let e = lam.polygon_local(&lam.prepare(v(0.3, 0.1, 0.9).normalize()), &poly);
        let (r, b) = (0.2f32 as f64, 0.9f32 as f64);
        assert!((e.z - b * want).abs() < 1e-12 && (e.x - r * want).abs() < 1e-12);
    }
}

fn polygon_local<R: Real>(q: &[V3<R>], two_sided: bool) -> PolygonLocal<R> {
    let mut p = PolygonLocal {
        vertices: [V3::new(R::ZERO, R::ZERO, R::ZERO); MAX_POLYGON_VERTICES],
        len: q.len(),
        two_sided,
    };
    p.vertices[..q.len()].copy_from_slice(q);
    p
}

#[test]
fn tilted_and_straddling_rectangles_match_quadrature() {
    // (corner, edge 1, edge 2): tilted overhead, a wall standing across the
    // horizon, a wall touching it, one leaning over the point, all below.
    let cases = [
        (v(-1.0, -0.5, 1.0), v(2.0, 0.0, 0.6), v(0.0, 1.5, 0.3)),
        (v(1.0, -1.0, -0.8), v(0.0, 2.0, 0.0), v(0.0, 0.0, 2.0)),
        (v(0.5, -1.0, 0.0), v(0.0, 2.5, 0.0), v(0.0, 0.0, 1.0)),
        (v(0.3, -2.0, -1.0), v(0.0, 4.0, 0.0), v(-1.0, 0.0, 3.0)),
        (v(-1.0, -1.0, -2.0), v(2.0, 0.0, 0.0), v(0.0, 2.0, 0.5)),
    ];
    for (p, e1, e2) in cases {
        // Both windings: one of them shows its front to the origin.
        let q = vec![p, p + e1, p + e1 + e2, p + e2];
        let s = form_factor_signed(&q);
        let rev: Vec<_> = q.iter().rev().copied().collect();
        // For a straddler, clip it by hand at z = 0 and integrate the part
        // above (the integrand's jump at the horizon is then on a panel edge).
        let want = if p.z < 0.0 && (p + e2).z > 0.0 {
            let t = -p.z / e2.z;
            let p0 = p + e2 * t;
            quad_ff(p0, e1, e2 * (1.0 - t), 48, 12)
        } else {
            quad_ff(p, e1, e2, 8, 12)
        };
        assert!((s.abs() - want).abs() < 1e-10, "{p:?}: |{s}| vs {want}");
        assert!((form_factor_signed(&rev) + s).abs() < 1e-14);
        let two = form_factor(&q, true);
        assert_eq!(two, s.abs());
        assert_eq!(form_factor(&q, false) + form_factor(&rev, false), s.abs());
    }
}

#[test]
fn clipping_cases() {
    // All below: exactly zero, in every precision.
    let below = rect_down(-1.0, 1.0, -1.0, 1.0, -0.5);
    assert_eq!(form_factor(&below, true), 0.0);
    assert_eq!(form_factor(&to_x8(&below), true).lane(0), 0.0);
    // A triangle with a vertex exactly on the horizon equals the limit of
    // raising it, and matches quadrature.
    let tri = |h: f64| vec![v(1.0, -1.0, 1.0), v(1.0, 1.0, 1.0), v(1.0, 0.0, h)];
    let on = form_factor_signed(&tri(0.0)).abs();
    let near = form_factor_signed(&tri(1e-9)).abs();
    assert!((on - near).abs() < 1e-8, "{on} vs {near}");
    // A vertex on the horizon with both neighbours below: only the edge's
    // point touches, nothing is seen.
    let touch = vec![v(1.0, 0.0, 0.0), v(1.0, 1.0, -1.0), v(1.0, -1.0, -1.0)];
    assert_eq!(form_factor(&touch, true), 0.0);
    // The triangle at h = 0: quadrature on the square [0,1]² mapped to it
    // (Duffy), plainly written.
    let g = GaussLegendre::new(24);
    let t = tri(0.0);
    let (e1, e2) = (t[1] - t[0], t[2] - t[1]);
    let area2 = e1.cross(e2).length();
    let want = g.integrate(0.0, 1.0, |s| {
        g.integrate(0.0, 1.0, |u| {
            let x = t[0] + e1 * s + e2 * (s * u);
            let r2 = x.length_squared();
            [x.z * x.x.abs() / (r2 * r2) * s * area2 / PI]
        })
    })[0];
    assert!((on - want).abs() < 1e-10, "{on} vs {want}");

    // A concave polygon (an L) straddling the horizon: the sum of its two
    // rectangles, and the analytic value where it is all above.
    let l = |c: f64| {
        vec![
            v(-1.0, -1.0, c),
            v(-1.0, 2.0, c),
            v(0.0, 2.0, c),
            v(0.0, 0.0, c),
            v(2.0, 0.0, c),
            v(2.0, -1.0, c),
        ]
    };
    let want = parallel_rect(-1.0, 0.0, -1.0, 2.0, 0.8) + parallel_rect(0.0, 2.0, -1.0, 0.0, 0.8);
    let got = form_factor(&l(0.8), false);
    assert!((got - want).abs() < 1e-12, "L: {got} vs {want}");
    // Tilt the L about the y axis so that it crosses the horizon twice
    // (clipping cuts it into two pieces for some tilts): compare with its two
    // rectangles, each clipped on its own.
    for tilt in [0.3f64, 0.9, 1.3, 2.0] {
        let rot = |p: V3<f64>| {
            let (s, c) = tilt.sin_cos();
            v(
                c * p.x + s * (p.z - 0.2),
                p.y,
                -s * p.x + c * (p.z - 0.2) + 0.1,
            )
        };
        let lp: Vec<_> = l(0.2).into_iter().map(rot).collect();
        let a: Vec<_> = rect_down(-1.0, 0.0, -1.0, 2.0, 0.2)
            .into_iter()
            .map(rot)
            .collect();
        let b: Vec<_> = rect_down(0.0, 2.0, -1.0, 0.0, 0.2)
            .into_iter()
            .map(rot)
            .collect();
        let whole = form_factor_signed(&lp);
        let parts = form_factor_signed(&a) + form_factor_signed(&b);
        assert!(
            (whole - parts).abs() < 1e-13,
            "tilt {tilt}: {whole} vs {parts}"
        );
        let w8 = form_factor_signed(&to_x8(&lp)).lane(0);
        assert!(
            (w8 - whole).abs() < 2e-6,
            "tilt {tilt}: f32x8 {w8} vs {whole}"
        );
    }
}

#[test]
fn nearly_parallel_and_antipodal_vertices_stay_accurate_in_f32x8() {
    // Tiny: a 1e-4 square at distance 10 (vertices 1e-5 rad apart).
    // The rectangle as f32 holds it (the analytic value of those corners).
    let r = |x: f64| x as f32 as f64;
    let (x0, x1, y0, y1) = (r(3.0), r(3.0001), r(-2.0), r(-1.9999));
    let tiny = rect_down(x0, x1, y0, y1, 10.0);
    let want = parallel_rect(x0, x1, y0, y1, 10.0);
    let got = form_factor(&to_x8(&tiny), false).lane(0);
    eprintln!("tiny square: f32x8 relative error {:e}", got / want - 1.0);
    assert!(
        (got / want - 1.0).abs() < 2e-3,
        "tiny: {got} vs {want} (relative {:e})",
        got / want - 1.0
    );
    // Huge and close: a strip passing over the point at height 1e-3, its
    // ends 1e4 away on either side (those vertices nearly antipodal).
    let strip = rect_down(-1e4, 1e4, -0.5, 0.5, 1e-3);
    let want = parallel_rect(-1e4, 1e4, -0.5, 0.5, 1e-3);
    let got = form_factor(&to_x8(&strip), false).lane(0);
    eprintln!("strip: f32x8 {got} vs {want}");
    assert!((got - want).abs() < 2e-6, "strip: {got} vs {want}");
    // A wall through the point's horizon almost edge-on.
    let wall = vec![
        v(-1e3, 1.0, 0.0),
        v(1e3, 1.0, 0.0),
        v(1e3, 1.0 + 1e-3, 5.0),
        v(-1e3, 1.0 + 1e-3, 5.0),
    ];
    let f64v = form_factor_signed(&wall);
    let f32v = form_factor_signed(&to_x8(&wall)).lane(0);
    assert!((f64v - f32v).abs() < 2e-6, "wall: {f32v} vs {f64v}");
}

#[test]
fn f32x8_lanes_match_f64_on_random_polygons() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(8);
    let mut worst = 0.0f64;
    for _ in 0..2000 {
        // A random planar convex-or-not polygon: a star of n points in a
        // random plane around a random centre.
        let n = rng.random_range(3..=MAX_POLYGON_VERTICES);
        let c = v(
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
            rng.random_range(-1.0..2.0),
        );
        let a = v(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize();
        let b0 = v(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let b = (b0 - a * a.dot(b0)).normalize();
        let q: Vec<V3<f64>> = (0..n)
            .map(|k| {
                let phi = 2.0 * PI * (k as f64 + rng.random_range(0.0..0.8)) / n as f64;
                let r = rng.random_range(0.3..1.5);
                c + a * (r * phi.cos()) + b * (r * phi.sin())
            })
            .collect();
        // Round to f32 first, so both see the same polygon.
        let q: Vec<V3<f64>> = q
            .iter()
            .map(|p| v(p.x as f32 as f64, p.y as f32 as f64, p.z as f32 as f64))
            .collect();
        let want = form_factor_signed(&q);
        let got = form_factor_signed(&to_x8(&q));
        let got1 = form_factor_signed(
            &q.iter()
                .map(|p| V3::new(p.x as f32, p.y as f32, p.z as f32))
                .collect::<Vec<_>>(),
        );
        for l in 0..8 {
            assert_eq!(got.lane(l), got.lane(0));
        }
        worst = worst
            .max((got.lane(0) - want).abs())
            .max((got1 as f64 - want).abs());
    }
    eprintln!("f32x8 / f32 vs f64 form factor, 2000 random polygons: worst |Δ| = {worst:e}");
    assert!(worst < 3e-6, "worst {worst:e}");
}

/// An independent Monte Carlo of ∫ f cos over the polygon: points uniform
/// on its area (rejection in its bounding box, so concave polygons work),
/// weighted by dω/dA = |n̂·X| / |X|³; no clipping (f_cos is zero below the
/// horizon), no fan. Mean and its standard error, per channel.
fn monte_carlo(
    q: &[V3<f64>],
    two_sided: bool,
    f_cos: &dyn Fn(V3<f64>) -> [f64; 3],
    samples: usize,
    seed: u64,
) -> ([f64; 3], [f64; 3]) {
    let mut nrm = V3::new(0.0, 0.0, 0.0);
    for k in 0..q.len() {
        nrm += q[k].cross(q[(k + 1) % q.len()]);
    }
    let nrm = nrm.normalize();
    if !two_sided && nrm.dot(q[0]) > 0.0 {
        return ([0.0; 3], [0.0; 3]);
    }
    let e1 = (q[1] - q[0]).normalize();
    let e2 = nrm.cross(e1);
    let uv: Vec<(f64, f64)> = q
        .iter()
        .map(|p| ((*p - q[0]).dot(e1), (*p - q[0]).dot(e2)))
        .collect();
    let (u0, u1) = uv
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (v0, v1) = uv
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let inside = |x: f64, y: f64| {
        let mut c = false;
        for k in 0..uv.len() {
            let (a, b) = (uv[k], uv[(k + 1) % uv.len()]);
            if (a.1 > y) != (b.1 > y) && x < a.0 + (y - a.1) / (b.1 - a.1) * (b.0 - a.0) {
                c = !c;
            }
        }
        c
    };
    let area = (u1 - u0) * (v1 - v0);
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let (mut s, mut s2) = ([0.0; 3], [0.0; 3]);
    for _ in 0..samples {
        let (x, y) = (rng.random_range(u0..u1), rng.random_range(v0..v1));
        if !inside(x, y) {
            continue;
        }
        let p = q[0] + e1 * x + e2 * y;
        let r2 = p.length_squared();
        let r = r2.sqrt();
        let w = p * (1.0 / r);
        if w.z <= 0.0 {
            continue;
        }
        let k = area * nrm.dot(p).abs() / (r2 * r);
        let f = f_cos(w);
        for c in 0..3 {
            let y = f[c] * k;
            s[c] += y;
            s2[c] += y * y;
        }
    }
    let n = samples as f64;
    let mean = s.map(|x| x / n);
    let se = core::array::from_fn(|c| ((s2[c] / n - mean[c] * mean[c]).max(0.0) / n).sqrt());
    (mean, se)
}

/// f(wi, wo) cos θi of a model at a fixed view.
type FCos = Box<dyn Fn(V3<f64>) -> [f64; 3]>;

fn ggx(alpha: f32, f0: f32, diffuse: f32) -> Microfacet {
    Microfacet::new_without_table(
        MicrofacetParams {
            ndf: Ndf::Ggx,
            alpha,
            smith: Smith::HeightCorrelated,
            fresnel: Fresnel::Schlick { f0: [f0, 0.5, 1.0] },
            diffuse: [diffuse; 3],
            gtr_lambda: Default::default(),
        },
        None,
    )
}

#[test]
fn the_reference_matches_an_independent_monte_carlo() {
    let polys: Vec<(&str, Vec<V3<f64>>, bool)> = vec![
        ("overhead quad", rect_down(-0.5, 1.0, -0.7, 0.4, 1.0), false),
        (
            "tilted triangle",
            vec![v(2.0, -1.0, 0.5), v(1.5, 1.0, 2.0), v(-0.5, -0.5, 1.5)]
                .into_iter()
                .rev()
                .collect(),
            true,
        ),
        (
            "straddling wall",
            vec![
                v(1.0, -1.5, -1.0),
                v(1.0, 1.5, -1.0),
                v(1.0, 1.5, 1.5),
                v(1.0, -1.5, 1.5),
            ],
            true,
        ),
        (
            "concave L",
            vec![
                v(-1.0, -1.0, 0.6),
                v(-1.0, 2.0, 0.6),
                v(0.0, 2.0, 0.6),
                v(0.0, 0.0, 0.6),
                v(2.0, 0.0, 0.6),
                v(2.0, -1.0, 0.6),
            ],
            false,
        ),
    ];
    let wo = v(-0.6, 0.2, 0.7).normalize();
    let models: Vec<(&str, FCos)> = vec![
        ("lambert", {
            let m = Lambert {
                base_color: [0.3, 0.6, 0.9],
            };
            let p = m.prepare(wo);
            Box::new(move |wi| {
                let c = m.f_cos_local(&p, wi);
                [c.x, c.y, c.z]
            })
        }),
        ("ggx 0.2", {
            let m = ggx(0.2, 0.04, 0.1);
            let p = m.prepare(wo);
            Box::new(move |wi| {
                let c = m.f_cos_local(&p, wi);
                [c.x, c.y, c.z]
            })
        }),
        ("ggx 0.6", {
            let m = ggx(0.6, 0.9, 0.0);
            let p = m.prepare(wo);
            Box::new(move |wi| {
                let c = m.f_cos_local(&p, wi);
                [c.x, c.y, c.z]
            })
        }),
        ("metallic_roughness", {
            let m = MetallicRoughness {
                base_color: [0.9, 0.5, 0.2],
                roughness: 0.5,
                metallic: 0.3,
            };
            let p = m.prepare(wo);
            Box::new(move |wi| {
                let c = m.f_cos_local(&p, wi);
                [c.x, c.y, c.z]
            })
        }),
    ];
    for (pname, q, two) in &polys {
        for (mname, f) in &models {
            let r = integrate_polygon(q, *two, f.as_ref(), Tolerance::FINE);
            let (mc, se) = monte_carlo(q, *two, f.as_ref(), 400_000, 3);
            eprintln!(
                "{pname:>16} {mname:>18}: reference {:.6} ± {:.1e}, Monte Carlo {:.6} ± {:.1e}",
                r.value[0], r.error, mc[0], se[0]
            );
            for c in 0..3 {
                let tol = 4.0 * se[c] + 2.0 * r.error + 1e-9;
                assert!(
                    (r.value[c] - mc[c]).abs() < tol,
                    "{pname} {mname} channel {c}: reference {} ± {}, MC {} ± {}",
                    r.value[c],
                    r.error,
                    mc[c],
                    se[c]
                );
            }
        }
    }
}

#[test]
fn the_reference_of_lambert_is_rho_times_the_analytic_form_factor() {
    let m = Lambert {
        base_color: [1.0, 0.5, 0.25],
    };
    let p = m.prepare(v(0.0, 0.0, 1.0));
    let f = |wi: V3<f64>| {
        let c = m.f_cos_local(&p, wi);
        [c.x, c.y, c.z]
    };
    for (x0, x1, y0, y1, c) in [(-0.5, 0.5, -0.5, 0.5, 1.0), (-3.0, 4.0, 1.0, 2.5, 0.7)] {
        let want = parallel_rect(x0, x1, y0, y1, c);
        let r = integrate_polygon(&rect_down(x0, x1, y0, y1, c), false, &f, Tolerance::FINE);
        assert!(
            (r.value[0] - want).abs() < 1e-5 * want
                && (r.value[0] - want).abs() <= r.error.max(1e-12),
            "{} ± {} vs {want}",
            r.value[0],
            r.error
        );
        let back: Vec<_> = rect_down(x0, x1, y0, y1, c).into_iter().rev().collect();
        assert_eq!(
            integrate_polygon(&back, false, &f, Tolerance::FINE).value,
            [0.0; 3]
        );
        let two = integrate_polygon(&back, true, &f, Tolerance::FINE);
        assert!((two.value[1] - 0.5 * want).abs() < 1e-5 * want);
    }
}

/// The fan taken from where a peak direction meets the plane, with its
/// triangles graded toward that point, integrates the same polygon: the
/// analytic form factor for the lambert integrand whether the point is
/// inside the rectangle, outside it, far away nearly along the plane, or
/// on its edge; and a concave polygon matches its ungraded integral.
#[test]
fn the_graded_fan_from_a_peak_integrates_the_same_polygon() {
    let m = Lambert {
        base_color: [1.0, 0.5, 0.25],
    };
    let p = m.prepare(v(0.0, 0.0, 1.0));
    let f = |wi: V3<f64>| {
        let c = m.f_cos_local(&p, wi);
        [c.x, c.y, c.z]
    };
    let (x0, x1, y0, y1, c) = (-3.0, 4.0, 1.0, 2.5, 0.7);
    let want = parallel_rect(x0, x1, y0, y1, c);
    let quad = rect_down(x0, x1, y0, y1, c);
    for d in [
        v(0.0, 1.5, 0.7),  // inside
        v(0.0, -1.0, 0.7), // outside
        v(1.0, 1e3, 1e-3), // far out, nearly along the plane
        v(4.0, 2.0, 0.7),  // on an edge
        v(-3.0, 1.0, 0.7), // on a corner
    ] {
        for angle in [1e-2, 1e-7] {
            let peak = Peak {
                direction: d.normalize(),
                angle,
            };
            let r = integrate_polygon_toward(&quad, false, &f, Tolerance::FINE, Some(peak));
            assert!(
                (r.value[0] - want).abs() < 2e-5 * want,
                "toward {d:?} to {angle}: {} ± {} vs {want}",
                r.value[0],
                r.error
            );
        }
    }
    let l_shape = vec![
        v(-1.0, -1.0, 0.6),
        v(-1.0, 2.0, 0.6),
        v(0.0, 2.0, 0.6),
        v(0.0, 0.0, 0.6),
        v(2.0, 0.0, 0.6),
        v(2.0, -1.0, 0.6),
    ];
    let plain = integrate_polygon(&l_shape, true, &f, Tolerance::FINE);
    for d in [v(1.0, 1.0, 0.6), v(-0.5, -0.5, 0.6), v(0.5, 1.0, 0.6)] {
        let peak = Peak {
            direction: d.normalize(),
            angle: 1e-6,
        };
        let r = integrate_polygon_toward(&l_shape, true, &f, Tolerance::FINE, Some(peak));
        assert!(
            (r.value[0] - plain.value[0]).abs() < 2e-5 * plain.value[0],
            "L toward {d:?}: {} vs {}",
            r.value[0],
            plain.value[0]
        );
    }
}
