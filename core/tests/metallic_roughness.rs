//! The metallic-roughness model against independent numbers: a plainly
//! written f64 oracle from the glTF 2.0 spec (Appendix B, with branches and
//! the textbook G = 1/(1 + Λi + Λo) form), numeric integration for the NDF
//! and the directional albedo, reciprocity, and f32x8 vs f64 lane agreement.

// The oracle is written plainly, channel by channel, on purpose.
#![allow(clippy::needless_range_loop)]

use rand::{Rng, SeedableRng};
use specula_core::albedo_tables::AlbedoTables;
use specula_core::models::{Lambert, MetallicRoughness};
use specula_core::{f32x8, Brdf, Real, V3};
use std::f64::consts::PI;

/// glTF 2.0 Appendix B, written out independently in f64.
fn oracle(m: &MetallicRoughness, wi: [f64; 3], wo: [f64; 3]) -> [f64; 3] {
    if wi[2] <= 0.0 || wo[2] <= 0.0 {
        return [0.0; 3];
    }
    let r = m.roughness as f64;
    let alpha = (r * r).max(1e-3);
    let h = {
        let s = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
        let l = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
        [s[0] / l, s[1] / l, s[2] / l]
    };
    let nh = h[2];
    let vh = wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2];
    // D: Trowbridge-Reitz.
    let a2 = alpha * alpha;
    let d = a2 / (PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
    // G: height-correlated Smith, Λ(θ) = (−1 + √(1 + α² tan²θ)) / 2.
    let lambda = |c: f64| {
        let tan2 = (1.0 - c * c) / (c * c);
        (-1.0 + (1.0 + a2 * tan2).sqrt()) / 2.0
    };
    let g = 1.0 / (1.0 + lambda(wi[2]) + lambda(wo[2]));
    let mut out = [0.0; 3];
    for c in 0..3 {
        let base = m.base_color[c] as f64;
        let metal = m.metallic as f64;
        let f0 = 0.04 * (1.0 - metal) + base * metal;
        let f = f0 + (1.0 - f0) * (1.0 - vh).powi(5);
        let spec = f * d * g / (4.0 * wi[2] * wo[2]);
        let diffuse = (1.0 - f) * (1.0 - metal) * base / PI;
        out[c] = spec + diffuse;
    }
    out
}

fn random_dir(rng: &mut impl Rng, upper: bool) -> [f64; 3] {
    loop {
        let v: [f64; 3] = [
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ];
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if l > 0.05 && l <= 1.0 && (!upper || v[2] > 0.02 * l) {
            return v.map(|x| x / l);
        }
    }
}

fn random_material(rng: &mut impl Rng) -> MetallicRoughness {
    MetallicRoughness {
        base_color: [
            rng.random_range(0.0..1.0),
            rng.random_range(0.0..1.0),
            rng.random_range(0.0..1.0),
        ],
        roughness: rng.random_range(0.05..1.0),
        metallic: rng.random_range(0.0..1.0),
    }
}

fn v64(d: [f64; 3]) -> V3<f64> {
    V3::new(d[0], d[1], d[2])
}

const N: V3<f64> = V3 {
    x: 0.0,
    y: 0.0,
    z: 1.0,
};

#[test]
fn matches_the_gltf_oracle_reciprocal_and_nonnegative() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(1);
    for _ in 0..20_000 {
        let m = random_material(&mut rng);
        let (wi, wo) = (random_dir(&mut rng, false), random_dir(&mut rng, false));
        let got = m.f(N, v64(wi), v64(wo));
        let back = m.f(N, v64(wo), v64(wi));
        let want = oracle(&m, wi, wo);
        for (c, (g, w)) in [got.x, got.y, got.z].iter().zip(want).enumerate() {
            assert!(*g >= 0.0, "negative BRDF");
            assert!(
                (g - w).abs() <= 1e-6 * w.abs().max(1e-3),
                "channel {c}: {g} vs oracle {w} for {m:?} wi={wi:?} wo={wo:?}"
            );
        }
        for (a, b) in [(got.x, back.x), (got.y, back.y), (got.z, back.z)] {
            assert!(
                (a - b).abs() <= 1e-12 * a.abs().max(1.0),
                "not reciprocal: {a} vs {b}"
            );
        }
    }
}

#[test]
fn lanes_of_f32x8_agree_with_f64() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(2);
    let mut worst = 0.0f64;
    for _ in 0..20_000 {
        let m = random_material(&mut rng);
        let dirs: Vec<([f64; 3], [f64; 3])> = (0..8)
            .map(|_| (random_dir(&mut rng, true), random_dir(&mut rng, true)))
            .collect();
        let lanes = |k: usize, which: usize| -> f32x8 {
            let a: [f32; 8] = std::array::from_fn(|l| if which == 0 { dirs[l].0[k] } else { dirs[l].1[k] } as f32);
            f32x8::load(&a)
        };
        let wi = V3::new(lanes(0, 0), lanes(1, 0), lanes(2, 0));
        let wo = V3::new(lanes(0, 1), lanes(1, 1), lanes(2, 1));
        let n = V3::new(f32x8::ZERO, f32x8::ZERO, f32x8::ONE);
        let simd = m.f(n, wi, wo);
        for (l, (i, o)) in dirs.iter().enumerate() {
            // Compare with f64 evaluated at the same f32-rounded inputs.
            let r = |d: [f64; 3]| v64(d.map(|x| x as f32 as f64));
            let want = m.f(N, r(*i), r(*o));
            for (g, w) in [(simd.x, want.x), (simd.y, want.y), (simd.z, want.z)] {
                let g = g.lane(l);
                let rel = (g - w).abs() / w.abs().max(1e-6);
                worst = worst.max(rel);
            }
        }
    }
    assert!(worst < 1e-5, "worst relative lane difference {worst:e}");
    eprintln!("worst f32x8 vs f64 relative difference: {worst:e}");
}

/// `f_local_scaled` (the point-light path: an unnormalized light vector
/// and its 1/length, folded into the half vector) against f64 `f` at the
/// normalized direction of the same f32 vector, for lengths 1e-2 to 1e2.
#[test]
fn scaled_light_vectors_agree_with_f64() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    let mut worst = 0.0f64;
    for _ in 0..20_000 {
        let m = random_material(&mut rng);
        // Per lane: the light vector (a unit direction times a length) and wo.
        let lights: [[f64; 3]; 8] = std::array::from_fn(|_| {
            let len = 10f64.powf(rng.random_range(-2.0..2.0));
            random_dir(&mut rng, true).map(|x| x * len)
        });
        let wos: [[f64; 3]; 8] = std::array::from_fn(|_| random_dir(&mut rng, true));
        let lanes = |d: &[[f64; 3]; 8]| -> V3<f32x8> {
            let axis = |k: usize| f32x8::from(d.map(|v| v[k] as f32));
            V3::new(axis(0), axis(1), axis(2))
        };
        let (v, wo) = (lanes(&lights), lanes(&wos));
        let inv_len = v.length_squared().rsqrt();
        let p = m.prepare(wo);
        let simd = m.f_local_scaled(&p, v, inv_len);
        for (l, o) in wos.iter().enumerate() {
            let vl = V3::new(v.x.lane(l), v.y.lane(l), v.z.lane(l));
            let wi = vl * (1.0 / vl.length_squared().sqrt());
            let want = m.f(N, wi, v64(o.map(|x| x as f32 as f64)));
            for (g, w) in [(simd.x, want.x), (simd.y, want.y), (simd.z, want.z)] {
                let g = g.lane(l);
                worst = worst.max((g - w).abs() / w.abs().max(1e-6));
            }
        }
    }
    eprintln!("worst scaled f32x8 vs f64 relative difference: {worst:e}");
    // The lane test's f32 rounding (1e-5 there) plus the 1/length estimate
    // (rsqrt + one Newton step, ≤ 4e-7 relative): it scales wi's length,
    // which tilts s = wi + wo and moves D along its slope (~1/α).
    assert!(worst < 5e-5, "worst relative lane difference {worst:e}");
}

/// ∫ D(h) cos θh dωh over the hemisphere by midpoint quadrature in
/// u = cos²θh-friendly coordinates (μ = cos θh, substitution μ = 1 − s²
/// concentrates points at the peak).
#[test]
fn ggx_ndf_is_normalized() {
    for alpha in [0.05, 0.1, 0.3, 0.6, 1.0] {
        let n = 200_000;
        let mut sum = 0.0;
        for k in 0..n {
            // t ∈ (0, 1): θ = t π/2 with density concentrated near 0 via θ = (π/2) t².
            let t = (k as f64 + 0.5) / n as f64;
            let theta = PI / 2.0 * t * t;
            let dtheta = PI * t / n as f64;
            let mu = theta.cos();
            let d = specula_core::ndf::d_ggx(alpha, mu * mu, 1.0 - mu * mu);
            sum += d * mu * theta.sin() * dtheta * 2.0 * PI;
        }
        assert!((sum - 1.0).abs() < 1e-3, "alpha {alpha}: ∫ D cos = {sum}");
    }
}

/// Directional albedo of the model by brute-force quadrature of f·cos over
/// the hemisphere (independent of the split-sum tables).
fn albedo_quadrature(m: &MetallicRoughness, mu_o: f64) -> [f64; 3] {
    let wo = [(1.0 - mu_o * mu_o).sqrt(), 0.0, mu_o];
    let (nt, np) = (600, 600);
    let mut s = [0.0; 3];
    for i in 0..nt {
        // θ = (π/2) u², denser near the normal where rough and smooth lobes sit.
        let u = (i as f64 + 0.5) / nt as f64;
        let th = PI / 2.0 * u * u;
        let dth = PI * u / nt as f64;
        for j in 0..np {
            let ph = 2.0 * PI * (j as f64 + 0.5) / np as f64;
            let wi = [th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()];
            let f = oracle(m, wi, wo);
            let w = th.cos() * th.sin() * dth * 2.0 * PI / np as f64;
            for c in 0..3 {
                s[c] += f[c] * w;
            }
        }
    }
    s
}

/// The split-sum tables' directional albedo against brute-force
/// quadrature, within 0.01 and 1.5 %, at roughness 0.2–1 (glTF's default
/// roughness is 1, where the albedo falls fastest) and views from 81° to
/// the normal. (At grazing views of narrow lobes the quadrature's grid,
/// dense near the normal, is too coarse to judge.)
#[test]
fn uniform_environment_albedo_matches_quadrature() {
    AlbedoTables::get();
    let mut worst = 0.0f64;
    for (roughness, metallic, base) in [
        (0.5, 0.0, [0.8, 0.4, 0.2]),
        (0.7, 1.0, [1.0, 0.77, 0.34]),
        (0.9, 0.5, [0.5, 0.5, 0.5]),
        (0.35, 1.0, [0.95, 0.64, 0.54]),
        (0.2, 1.0, [0.8, 0.6, 0.4]),
        (1.0, 1.0, [0.8, 0.6, 0.4]),
        (1.0, 0.0, [0.8, 0.6, 0.4]),
    ] {
        let m = MetallicRoughness {
            base_color: base,
            roughness,
            metallic,
        };
        for mu in [0.15, 0.4, 0.7, 0.95, 0.999] {
            let want = albedo_quadrature(&m, mu);
            let wo = v64([(1.0 - mu * mu).sqrt(), 0.0, mu]);
            let got = m.albedo(N, wo);
            for (g, w) in [(got.x, want[0]), (got.y, want[1]), (got.z, want[2])] {
                let e = (g - w).abs() / w;
                worst = worst.max(e);
                assert!(
                    (g - w).abs() < 0.01 && e < 0.015,
                    "r={roughness} m={metallic} mu={mu}: table {g} vs quadrature {w}"
                );
            }
        }
    }
    eprintln!("worst albedo table error: {:.2} %", 100.0 * worst);
}

#[test]
fn lambert_is_constant_and_its_albedo_is_exact() {
    let l = Lambert {
        base_color: [0.2, 0.5, 0.9],
    };
    let f = l.f(N, v64([0.3, 0.1, 0.9]), v64([-0.5, 0.2, 0.6]));
    assert!((f.y - 0.5 / PI).abs() < 1e-15);
    assert_eq!(l.f(N, v64([0.3, 0.1, -0.9]), v64([-0.5, 0.2, 0.6])).y, 0.0);
    assert_eq!(l.albedo(N, v64([0.0, 0.6, 0.8])).z, 0.9f32 as f64);
}
