//! The microfacet family against independent numbers: NDF normalization
//! and Smith G1 by numeric quadrature, Fresnel identities, reciprocity,
//! energy bounds, the tabulated albedo against brute-force integration, and
//! f32x8 lanes against f64.

use rand::{Rng, SeedableRng};
use specula_core::fresnel::{f_conductor, f_dielectric, f_schlick, r0_from_ior};
use specula_core::models::microfacet::{Fresnel, Microfacet, MicrofacetParams, Ndf, Smith};
use specula_core::{f32x8, Brdf, Real, Rgb, V3};
use std::f64::consts::PI;

const N: V3<f64> = V3 {
    x: 0.0,
    y: 0.0,
    z: 1.0,
};

fn ndfs() -> Vec<Ndf> {
    let mut v = vec![Ndf::Ggx, Ndf::Beckmann];
    v.extend([1.0, 1.5, 2.0, 3.0, 10.0].map(|gamma| Ndf::Gtr { gamma }));
    v
}

fn params(ndf: Ndf, alpha: f32) -> MicrofacetParams {
    MicrofacetParams {
        ndf,
        alpha,
        smith: Smith::HeightCorrelated,
        fresnel: Fresnel::Schlick { f0: [1.0; 3] },
        diffuse: [0.0; 3],
        gtr_lambda: Default::default(),
    }
}

/// ∫ over the hemisphere of g(θ) dω, midpoint rule in θ = (π/2)t² (dense
/// near the normal, where narrow lobes live).
fn hemisphere_theta(n: usize, g: impl Fn(f64) -> f64) -> f64 {
    (0..n)
        .map(|k| {
            let t = (k as f64 + 0.5) / n as f64;
            let theta = PI / 2.0 * t * t;
            g(theta) * theta.sin() * PI * t / n as f64 * 2.0 * PI
        })
        .sum()
}

#[test]
fn every_ndf_is_normalized_over_projected_solid_angle() {
    for ndf in ndfs() {
        for alpha in [0.05, 0.1, 0.2, 0.4, 0.7, 1.0] {
            let p = params(ndf, alpha as f32);
            let integral = hemisphere_theta(400_000, |th| {
                let c = th.cos();
                p.d(c * c, th.sin().powi(2)) * c
            });
            assert!(
                (integral - 1.0).abs() < 1e-3,
                "{ndf:?} alpha {alpha}: ∫ D cos = {integral}"
            );
        }
    }
}

/// G1(v) = cos θv / ∫ max(0, v·m) D(m) dm [Heitz14, eq. 2], by 2-D quadrature.
fn g1_definition(p: &MicrofacetParams, cos_v: f64) -> f64 {
    let v = [(1.0 - cos_v * cos_v).sqrt(), 0.0, cos_v];
    let (nt, np) = (4000, 512);
    let mut s = 0.0;
    for i in 0..nt {
        let t = (i as f64 + 0.5) / nt as f64;
        let th = PI / 2.0 * t * t;
        let dth = PI * t / nt as f64;
        let (st, ct) = th.sin_cos();
        let d = p.d(ct * ct, st * st);
        for j in 0..np {
            let ph = 2.0 * PI * (j as f64 + 0.5) / np as f64;
            let vm = v[0] * st * ph.cos() + v[2] * ct;
            if vm > 0.0 {
                s += vm * d * st * dth * 2.0 * PI / np as f64;
            }
        }
    }
    cos_v / s
}

#[test]
fn smith_g1_matches_its_definition() {
    for ndf in [Ndf::Ggx, Ndf::Beckmann] {
        for alpha in [0.1, 0.3, 0.6, 1.0] {
            let p = params(ndf, alpha);
            for cos_v in [0.1, 0.3, 0.6, 0.9] {
                let want = g1_definition(&p, cos_v);
                let got = 1.0 / (1.0 + p.lambda(cos_v));
                assert!(
                    (got - want).abs() < 1e-3,
                    "{ndf:?} α={alpha} cos={cos_v}: G1 {got} vs definition {want}"
                );
            }
        }
    }
}

fn random_dir(rng: &mut impl Rng) -> [f64; 3] {
    loop {
        let v: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if l > 0.1 && l <= 1.0 {
            return v.map(|x| x / l);
        }
    }
}

fn random_params(rng: &mut impl Rng) -> MicrofacetParams {
    let ndfs = ndfs();
    let fresnel = match rng.random_range(0..3) {
        0 => Fresnel::Schlick {
            f0: std::array::from_fn(|_| rng.random_range(0.0..1.0)),
        },
        1 => Fresnel::Dielectric {
            ior: rng.random_range(1.05..2.5),
        },
        _ => Fresnel::Conductor {
            eta: std::array::from_fn(|_| rng.random_range(0.1..2.0)),
            k: std::array::from_fn(|_| rng.random_range(0.5..5.0)),
        },
    };
    MicrofacetParams {
        ndf: ndfs[rng.random_range(0..ndfs.len())],
        alpha: rng.random_range(0.05..1.0),
        smith: if rng.random_bool(0.5) {
            Smith::Separable
        } else {
            Smith::HeightCorrelated
        },
        fresnel,
        diffuse: std::array::from_fn(|_| rng.random_range(0.0..0.5)),
        gtr_lambda: Default::default(),
    }
}

fn v64(d: [f64; 3]) -> V3<f64> {
    V3::new(d[0], d[1], d[2])
}

#[test]
fn reciprocal_nonnegative_and_height_correlated_at_least_separable() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    for _ in 0..50_000 {
        let p = random_params(&mut rng);
        let (wi, wo) = (v64(random_dir(&mut rng)), v64(random_dir(&mut rng)));
        let m = Microfacet::new_without_table(p.clone(), None);
        let a = m.f(N, wi, wo);
        let b = m.f(N, wo, wi);
        for (x, y) in [(a.x, b.x), (a.y, b.y), (a.z, b.z)] {
            assert!(x >= 0.0 && x.is_finite(), "{p:?}: f = {x}");
            assert!(
                (x - y).abs() <= 1e-9 * x.abs().max(1.0),
                "{p:?}: not reciprocal {x} vs {y}"
            );
        }
        if wi.z > 0.0 && wo.z > 0.0 {
            let sep = MicrofacetParams {
                smith: Smith::Separable,
                ..p.clone()
            };
            let hc = MicrofacetParams {
                smith: Smith::HeightCorrelated,
                ..p.clone()
            };
            assert!(hc.g2(wi.z, wo.z) >= sep.g2(wi.z, wo.z) - 1e-15);
        }
    }
}

#[test]
fn fresnel_identities() {
    for ior in [1.2, 1.33, 1.5, 2.0, 2.4] {
        let f = |c: f64| f_dielectric(c, ior);
        assert!(
            (f(1.0) - r0_from_ior(ior)).abs() < 1e-12,
            "normal incidence, ior {ior}"
        );
        assert!((f(0.0) - 1.0).abs() < 1e-12, "grazing, ior {ior}");
        // Total internal reflection from inside: η = 1/ior, past the critical angle.
        let crit = (1.0 - 1.0 / (ior * ior)).sqrt(); // cos of the critical angle
        assert_eq!(f_dielectric(crit * 0.99, 1.0 / ior), 1.0);
        assert!(f_dielectric(crit * 1.01 + 0.001, 1.0 / ior) < 1.0);
    }
    // Schlick against the exact curve for glass: known worst error ≈ 0.036 (at grazing).
    let r0 = r0_from_ior(1.5);
    let worst = (0..=1000)
        .map(|i| {
            let c = i as f64 / 1000.0;
            (f_schlick(Rgb::splat(r0), c).x - f_dielectric(c, 1.5)).abs()
        })
        .fold(0.0, f64::max);
    assert!(worst < 0.04, "Schlick vs exact: {worst}");
    // Conductors at normal incidence: F0 = ((η − 1)² + κ²) / ((η + 1)² + κ²), with
    // measured η, κ at ~650/550/450 nm [refractiveindex.info: Johnson & Christy 1972; Rakic 1995].
    for (name, eta, k) in [
        ("gold", [0.18, 0.42, 1.37], [3.42, 2.35, 1.77]),
        ("copper", [0.27, 0.68, 1.22], [3.61, 2.63, 2.29]),
        ("aluminium", [1.50, 0.96, 0.62], [7.63, 6.69, 5.47]),
    ] {
        for c in 0..3 {
            let (n, kk) = (eta[c], k[c]);
            let want = ((n - 1.0f64).powi(2) + kk * kk) / ((n + 1.0f64).powi(2) + kk * kk);
            let got = f_conductor(1.0, n, kk);
            assert!(
                (got - want).abs() < 0.02,
                "{name} channel {c}: F0 {got} vs {want}"
            );
            assert!(
                (f_conductor(0.0, n, kk) - 1.0).abs() < 1e-9,
                "{name}: grazing"
            );
        }
    }
}

/// E(μo) by brute-force quadrature of the BRDF the renderer evaluates.
fn albedo_quadrature(m: &Microfacet, mu_o: f64) -> [f64; 3] {
    let wo = V3::new((1.0 - mu_o * mu_o).sqrt(), 0.0, mu_o);
    let (nt, np) = (1500, 400);
    let mut s = [0.0; 3];
    for i in 0..nt {
        let u = (i as f64 + 0.5) / nt as f64;
        let th = PI / 2.0 * u * u;
        let dth = PI * u / nt as f64;
        for j in 0..np {
            let ph = 2.0 * PI * (j as f64 + 0.5) / np as f64;
            let wi = V3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
            let f = m.f(N, wi, wo);
            let w = th.cos() * th.sin() * dth * 2.0 * PI / np as f64;
            s[0] += f.x * w;
            s[1] += f.y * w;
            s[2] += f.z * w;
        }
    }
    s
}

#[test]
fn tabulated_albedo_matches_quadrature_and_energy_stays_below_one() {
    let cases = [
        params(Ndf::Ggx, 0.3),
        params(Ndf::Beckmann, 0.5),
        params(Ndf::Gtr { gamma: 1.5 }, 0.4),
        MicrofacetParams {
            fresnel: Fresnel::Dielectric { ior: 1.5 },
            diffuse: [0.3, 0.2, 0.1],
            ..params(Ndf::Ggx, 0.6)
        },
        MicrofacetParams {
            fresnel: Fresnel::Conductor {
                eta: [0.18, 0.42, 1.37],
                k: [3.42, 2.35, 1.77],
            },
            smith: Smith::Separable,
            ..params(Ndf::Ggx, 0.8)
        },
    ];
    for p in cases {
        let m = Microfacet::new(p.clone(), None);
        for mu in [0.2, 0.5, 0.8] {
            let want = albedo_quadrature(&m, mu);
            let got = m.albedo_at(mu as f32);
            for c in 0..3 {
                assert!(
                    (got[c] as f64 - want[c]).abs() < 5e-3,
                    "{p:?} μ={mu}: table {} vs quadrature {}",
                    got[c],
                    want[c]
                );
                let spec_only = want[c] - p.diffuse[c] as f64;
                assert!(
                    spec_only <= 1.0 + 1e-3,
                    "{p:?}: single-scattering albedo {spec_only} > 1"
                );
            }
        }
    }
}

#[test]
fn f32x8_lanes_agree_with_f64_over_a_million_evaluations() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(4);
    let mut worst = 0.0f64;
    let mut worst_case = String::new();
    let mut n = 0;
    while n < 1_000_000 {
        let p = random_params(&mut rng);
        // Compensation on a third of the GGX + height-correlated materials
        // (one table to build, shared by all of them).
        let kc = (p.ndf == Ndf::Ggx && p.smith == Smith::HeightCorrelated && rng.random_bool(0.33))
            .then_some(specula_core::kulla_conty::KcColor::KullaConty);
        let m = Microfacet::new_without_table(p.clone(), kc);
        for _ in 0..16 {
            let dirs: Vec<([f64; 3], [f64; 3])> = (0..8)
                .map(|_| {
                    let mut a = random_dir(&mut rng);
                    let mut b = random_dir(&mut rng);
                    a[2] = a[2].abs().max(0.02);
                    b[2] = b[2].abs().max(0.02);
                    (a, b)
                })
                .collect();
            // Unit in f64, then rounded to f32: both paths see the same inputs.
            let unit = |d: [f64; 3]| {
                let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                d.map(|x| (x / l) as f32)
            };
            let lane = |which: usize, k: usize| -> f32x8 {
                f32x8::load(&std::array::from_fn::<f32, 8, _>(|l| {
                    unit(if which == 0 { dirs[l].0 } else { dirs[l].1 })[k]
                }))
            };
            let wi = V3::new(lane(0, 0), lane(0, 1), lane(0, 2));
            let wo = V3::new(lane(1, 0), lane(1, 1), lane(1, 2));
            let n8 = V3::new(f32x8::ZERO, f32x8::ZERO, f32x8::ONE);
            let simd = m.f(n8, wi, wo);
            for (l, (i, o)) in dirs.iter().enumerate() {
                let r = |d: [f64; 3]| v64(unit(d).map(|x| x as f64));
                let want = m.f(N, r(*i), r(*o));
                for (g, w) in [(simd.x, want.x), (simd.y, want.y), (simd.z, want.z)] {
                    let rel = (g.lane(l) - w).abs() / w.abs().max(1e-3);
                    if rel > worst {
                        worst_case = format!("{p:?} wi={i:?} wo={o:?}: {} vs {w}", g.lane(l));
                    }
                    worst = worst.max(rel);
                }
                n += 1;
            }
        }
    }
    eprintln!("worst f32x8 vs f64 relative difference over {n}: {worst:e} at {worst_case}");
    assert!(worst < 1e-5, "worst relative difference {worst:e}");
}
