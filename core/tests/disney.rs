//! The Disney principled BRDF against independent numbers: each lobe
//! against a plainly written f64 oracle of the BRDF Explorer's 2015
//! `disney.brdf` (Burley's formulas with branches, textbook Smith forms),
//! reciprocity on a parameter grid, directional albedo by a quadrature
//! written here (not the model's), the Lambert limit, metallic furnace
//! bounds, and f32x8 vs f64.

// The oracle is written plainly, channel by channel, on purpose.
#![allow(clippy::needless_range_loop)]

use rand::{Rng, SeedableRng};
use specula_core::models::disney::{Disney, DisneyParams, DisneyPrepared};
use specula_core::quadrature::GaussLegendre;
use specula_core::{f32x8, Brdf, Real, ShadingFrame, V3};
use std::f64::consts::PI;

/// The three lobes of the Explorer's BRDF: (diffuse + sheen, specular,
/// clearcoat), in f64, from its formulas written out independently.
fn oracle(p: &DisneyParams, l: [f64; 3], v: [f64; 3]) -> ([f64; 3], [f64; 3], f64) {
    if l[2] <= 0.0 || v[2] <= 0.0 {
        return ([0.0; 3], [0.0; 3], 0.0);
    }
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let hs = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
    let hl = dot(hs, hs).sqrt();
    let h = [hs[0] / hl, hs[1] / hl, hs[2] / hl];
    let (nl, nv, nh, lh) = (l[2], v[2], h[2], dot(l, h));
    let schlick = |u: f64| (1.0 - u).clamp(0.0, 1.0).powi(5);
    let lerp = |a: f64, b: f64, t: f64| (1.0 - t) * a + t * b;

    let cd: [f64; 3] = p.base_color.map(|c| c as f64);
    let lum = 0.3 * cd[0] + 0.6 * cd[1] + 0.1 * cd[2];
    let ctint: [f64; 3] = if lum > 0.0 {
        [cd[0] / lum, cd[1] / lum, cd[2] / lum]
    } else {
        [1.0; 3]
    };
    let (metallic, rough) = (p.metallic as f64, p.roughness as f64);
    let mut cspec0 = [0.0; 3];
    let mut csheen = [0.0; 3];
    for c in 0..3 {
        let dielectric = p.specular as f64 * 0.08 * lerp(1.0, ctint[c], p.specular_tint as f64);
        cspec0[c] = lerp(dielectric, cd[c], metallic);
        csheen[c] = lerp(1.0, ctint[c], p.sheen_tint as f64);
    }

    // Diffuse: Fresnel-weighted with retro-reflection, and the
    // Hanrahan–Krueger-like subsurface.
    let (fl, fv) = (schlick(nl), schlick(nv));
    let fd90 = 0.5 + 2.0 * lh * lh * rough;
    let fd = lerp(1.0, fd90, fl) * lerp(1.0, fd90, fv);
    let fss90 = lh * lh * rough;
    let fss = lerp(1.0, fss90, fl) * lerp(1.0, fss90, fv);
    let ss = 1.25 * (fss * (1.0 / (nl + nv) - 0.5) + 0.5);
    let fh = schlick(lh);
    let mut diffuse = [0.0; 3];
    for c in 0..3 {
        let d = lerp(fd, ss, p.subsurface as f64) * cd[c] / PI;
        let sheen = fh * p.sheen as f64 * csheen[c];
        diffuse[c] = (d + sheen) * (1.0 - metallic);
    }

    // Specular: anisotropic GGX, separable anisotropic Smith.
    let aspect = (1.0 - 0.9 * p.anisotropic as f64).sqrt();
    let ax = (rough * rough / aspect).max(0.001);
    let ay = (rough * rough * aspect).max(0.001);
    let ds = 1.0 / (PI * ax * ay * ((h[0] / ax).powi(2) + (h[1] / ay).powi(2) + nh * nh).powi(2));
    // G1 = 1 / (1 + Λ), Λ = (−1 + √(1 + α(φ)² tan²θ)) / 2 with
    // α(φ)² tan²θ = (αx² x² + αy² y²) / z².
    let g1 = |w: [f64; 3]| {
        let a2t2 = ((ax * w[0]).powi(2) + (ay * w[1]).powi(2)) / (w[2] * w[2]);
        1.0 / (1.0 + (-1.0 + (1.0 + a2t2).sqrt()) / 2.0)
    };
    let gs = g1(l) * g1(v);
    let mut specular = [0.0; 3];
    for c in 0..3 {
        let fs = lerp(cspec0[c], 1.0, fh);
        specular[c] = fs * ds * gs / (4.0 * nl * nv);
    }

    // Clearcoat: GTR1 (normalized: (α² − 1) / (π ln α² (1 + (α² − 1) cos²θh))),
    // Smith GGX at α = 0.25, Schlick with F0 = 0.04.
    let ac = lerp(0.1, 0.001, p.clearcoat_gloss as f64);
    let a2 = ac * ac;
    let dr = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * nh * nh));
    let g1c = |c: f64| {
        let tan2 = (1.0 - c * c) / (c * c);
        1.0 / (1.0 + (-1.0 + (1.0 + 0.0625 * tan2).sqrt()) / 2.0)
    };
    let fr = lerp(0.04, 1.0, fh);
    let coat = 0.25 * p.clearcoat as f64 * fr * dr * g1c(nl) * g1c(nv) / (4.0 * nl * nv);
    (diffuse, specular, coat)
}

fn random_dir(rng: &mut impl Rng) -> [f64; 3] {
    let z: f64 = rng.random_range(0.02..1.0);
    let phi: f64 = rng.random_range(0.0..2.0 * PI);
    let s = (1.0 - z * z).sqrt();
    [s * phi.cos(), s * phi.sin(), z]
}

fn random_params(rng: &mut impl Rng) -> DisneyParams {
    let mut u = || rng.random_range(0.0f32..=1.0);
    DisneyParams {
        base_color: [u(), u(), u()],
        metallic: u(),
        subsurface: u(),
        specular: u(),
        specular_tint: u(),
        // Not below 0.1: with α = r² < 0.01 most random pairs sit far out in
        // the lobe's tail, where the value is ~0 and says little.
        roughness: 0.1 + 0.9 * u(),
        anisotropic: u(),
        sheen: u(),
        sheen_tint: u(),
        clearcoat: u(),
        clearcoat_gloss: u(),
    }
}

fn v64(d: [f64; 3]) -> V3<f64> {
    V3::new(d[0], d[1], d[2])
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-12)
}

#[test]
fn each_lobe_matches_the_explorer_oracle() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(9);
    let mut worst = [0.0f64; 3];
    for _ in 0..20000 {
        let p = random_params(&mut rng);
        let m = Disney::new_without_table(p.clone(), false);
        let (wi, wo) = (random_dir(&mut rng), random_dir(&mut rng));
        let prepared: DisneyPrepared<f64> = m.prepare(v64(wo));
        let (lobes, above) = m.lobes(&prepared, v64(wi));
        assert!(above);
        let (d, s, c) = oracle(&p, wi, wo);
        let got_d = [lobes.diffuse.x, lobes.diffuse.y, lobes.diffuse.z];
        let got_s = [lobes.specular.x, lobes.specular.y, lobes.specular.z];
        for k in 0..3 {
            worst[0] = worst[0].max(rel(got_d[k], d[k]));
            worst[1] = worst[1].max(rel(got_s[k], s[k]));
        }
        worst[2] = worst[2].max(rel(lobes.clearcoat, c));
        // The whole f is the lobes' sum.
        let f = m.f_in(&identity(), v64(wi), v64(wo));
        assert!(rel(f.x, d[0] + s[0] + c) < 1e-9);
    }
    eprintln!(
        "worst relative error vs oracle: diffuse {:e}, specular {:e}, clearcoat {:e}",
        worst[0], worst[1], worst[2]
    );
    // The parameters are f32 and derived constants are formed in f64 from
    // them exactly as the oracle does: only rounding-order differences.
    assert!(worst.iter().all(|w| *w < 1e-9), "{worst:?}");
}

fn identity() -> ShadingFrame<f64> {
    ShadingFrame {
        t: V3::new(1.0, 0.0, 0.0),
        b: V3::new(0.0, 1.0, 0.0),
        n: V3::new(0.0, 0.0, 1.0),
    }
}

#[test]
fn zero_below_the_horizon_and_nonnegative() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    for _ in 0..2000 {
        let p = random_params(&mut rng);
        let m = Disney::new_without_table(p, true);
        let (a, mut b) = (random_dir(&mut rng), random_dir(&mut rng));
        let f = m.f_in(&identity(), v64(a), v64(b));
        assert!(f.x >= 0.0 && f.y >= 0.0 && f.z >= 0.0);
        b[2] = -b[2];
        let f = m.f_in(&identity(), v64(a), v64(b));
        assert_eq!([f.x, f.y, f.z], [0.0; 3]);
        let f = m.f_in(&identity(), v64(b), v64(a));
        assert_eq!([f.x, f.y, f.z], [0.0; 3]);
    }
}

/// Every parameter on {0, ½, 1} (3¹⁰ combinations), with and without
/// compensation on a coarser grid, at a few direction pairs.
#[test]
fn reciprocal_on_a_parameter_grid() {
    let vals = [0.0f32, 0.5, 1.0];
    let pairs = [
        ([0.3, 0.2, 0.93], [-0.5, 0.6, 0.62]),
        ([0.9, -0.1, 0.42], [0.05, 0.1, 0.99]),
        ([-0.7, -0.69, 0.18], [0.6, -0.3, 0.74]),
    ];
    let mut worst = 0.0f64;
    let mut count = 0;
    for i in 0..3usize.pow(10) {
        let mut k = i;
        let mut next = || {
            let v = vals[k % 3];
            k /= 3;
            v
        };
        let p = DisneyParams {
            base_color: [0.9, 0.5, 0.1],
            metallic: next(),
            subsurface: next(),
            specular: next(),
            specular_tint: next(),
            roughness: next(),
            anisotropic: next(),
            sheen: next(),
            sheen_tint: next(),
            clearcoat: next(),
            clearcoat_gloss: next(),
        };
        // Compensation needs the (shared) table; check it on every 7th.
        let m = Disney::new_without_table(p, i % 7 == 0);
        for (a, b) in pairs {
            let (a, b) = (v64(a).normalize(), v64(b).normalize());
            let f1 = m.f_in(&identity(), a, b);
            let f2 = m.f_in(&identity(), b, a);
            for (x, y) in [(f1.x, f2.x), (f1.y, f2.y), (f1.z, f2.z)] {
                worst = worst.max((x - y).abs() / x.abs().max(y.abs()).max(1e-300));
            }
            count += 1;
        }
    }
    eprintln!("reciprocity: {count} evaluations, worst relative asymmetry {worst:e}");
    assert!(worst < 1e-12, "{worst:e}");
}

#[test]
fn lanes_of_f32x8_agree_with_f64() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    let mut worst = 0.0f64;
    for _ in 0..500 {
        let p = random_params(&mut rng);
        let m = Disney::new_without_table(p, rng.random_bool(0.3));
        let dirs: Vec<([f64; 3], [f64; 3])> = (0..8)
            .map(|_| (random_dir(&mut rng), random_dir(&mut rng)))
            .collect();
        let lanes = |k: usize, which: usize| -> f32x8 {
            let a: Vec<f32> = dirs
                .iter()
                .map(|d| if which == 0 { d.0[k] } else { d.1[k] } as f32)
                .collect();
            f32x8::load(&a)
        };
        let wi = V3::new(lanes(0, 0), lanes(1, 0), lanes(2, 0));
        let wo = V3::new(lanes(0, 1), lanes(1, 1), lanes(2, 1));
        let f8 = m.f_local(&m.prepare(wo), wi);
        for l in 0..8 {
            // The f64 reference at the f32-rounded directions.
            let r = |v: [f64; 3]| v64(v.map(|x| x as f32 as f64));
            let f = m.f_local(&m.prepare(r(dirs[l].1)), r(dirs[l].0));
            for (a, b) in [
                (f8.x.lane(l), f.x),
                (f8.y.lane(l), f.y),
                (f8.z.lane(l), f.z),
            ] {
                // Relative, with an absolute floor far below any visible value.
                worst = worst.max((a - b).abs() / b.abs().max(1e-3));
            }
        }
    }
    eprintln!("worst f32x8 vs f64 relative difference: {worst:e}");
    assert!(worst < 2e-5, "{worst:e}");
}

/// ∫ f μi dωi for one lobe of `m` at `wo`, by quadrature written here:
/// `Lobe::Diffuse` over wi (Gauss–Legendre in μi on 8 panels × midpoint in
/// φi); the microfacet lobes over the half vector in polar coordinates,
/// dωi = 4 (wo·h) dωh, with θh warped by tan θh = αw tan ψ (αw the lobe's
/// width, so nodes crowd where D does), Gauss–Legendre in ψ on 16 panels
/// up to the θh past which wi = 2(wo·h)h − wo drops below the horizon
/// (tan 2θ = … : wi·n = R cos(2θh − β), β = atan2(wo_xy·(cos φ, sin φ), μo)),
/// and the midpoint rule in φh.
#[derive(Clone, Copy, PartialEq)]
enum Which {
    Diffuse,
    Specular,
    Clearcoat,
}

fn lobe_albedo(m: &Disney, wo: [f64; 3], which: Which, width: f64) -> [f64; 3] {
    let gl = GaussLegendre::new(12);
    let pr: DisneyPrepared<f64> = m.prepare(v64(wo));
    let mut acc = [0.0; 3];
    let mut add = |wi: [f64; 3], w: f64| {
        if wi[2] <= 0.0 {
            return;
        }
        let (l, _) = m.lobes(&pr, v64(wi));
        let v = match which {
            Which::Diffuse => [l.diffuse.x, l.diffuse.y, l.diffuse.z],
            Which::Specular => [l.specular.x, l.specular.y, l.specular.z],
            Which::Clearcoat => [l.clearcoat; 3],
        };
        for c in 0..3 {
            acc[c] += v[c] * w;
        }
    };
    let n_phi = 128;
    for k in 0..n_phi {
        let phi = 2.0 * PI * (k as f64 + 0.5) / n_phi as f64;
        let dphi = 2.0 * PI / n_phi as f64;
        let (cp, sp) = (phi.cos(), phi.sin());
        if which == Which::Diffuse {
            let panels = 8;
            for j in 0..panels {
                let (a, b) = (j as f64 / panels as f64, (j + 1) as f64 / panels as f64);
                for (x, w) in gl.nodes_weights() {
                    let mu = 0.5 * (a + b) + 0.5 * (b - a) * x;
                    let s = (1.0 - mu * mu).sqrt();
                    add([s * cp, s * sp, mu], mu * 0.5 * (b - a) * w * dphi);
                }
            }
            continue;
        }
        let beta = (wo[0] * cp + wo[1] * sp).atan2(wo[2]);
        let theta_max = 0.5 * (beta + 0.5 * PI);
        let psi_max = (theta_max.tan() / width).atan();
        let panels = 16;
        for j in 0..panels {
            let (a, b) = (
                psi_max * j as f64 / panels as f64,
                psi_max * (j + 1) as f64 / panels as f64,
            );
            for (x, w) in gl.nodes_weights() {
                let psi = 0.5 * (a + b) + 0.5 * (b - a) * x;
                let t = width * psi.tan();
                let theta = t.atan();
                // dθ/dψ = αw sec²ψ / (1 + tan²θ).
                let dtheta = width / (psi.cos().powi(2) * (1.0 + t * t));
                let (st, ct) = (theta.sin(), theta.cos());
                let h = [st * cp, st * sp, ct];
                let oh = wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2];
                if oh <= 0.0 {
                    continue;
                }
                let wi = [
                    2.0 * oh * h[0] - wo[0],
                    2.0 * oh * h[1] - wo[1],
                    2.0 * oh * h[2] - wo[2],
                ];
                add(
                    wi,
                    wi[2] * 4.0 * oh * st * dtheta * 0.5 * (b - a) * w * dphi,
                );
            }
        }
    }
    acc
}

/// ∫ (f_comp − f_plain) μi dωi of the specular lobes of two models that
/// differ only in compensation: the Kulla–Conty lobe, smooth in wi, so
/// Gauss–Legendre in μi (8 panels × 12) × midpoint in φi (128).
fn ms_albedo(comp: &Disney, plain: &Disney, wo: [f64; 3]) -> f64 {
    let gl = GaussLegendre::new(12);
    let (pc, pp): (DisneyPrepared<f64>, DisneyPrepared<f64>) =
        (comp.prepare(v64(wo)), plain.prepare(v64(wo)));
    let mut acc = 0.0;
    let n_phi = 128;
    for k in 0..n_phi {
        let phi = 2.0 * PI * (k as f64 + 0.5) / n_phi as f64;
        for j in 0..8 {
            let (a, b) = (j as f64 / 8.0, (j + 1) as f64 / 8.0);
            for (x, w) in gl.nodes_weights() {
                let mu = 0.5 * (a + b) + 0.5 * (b - a) * x;
                let s = (1.0 - mu * mu).sqrt();
                let wi = v64([s * phi.cos(), s * phi.sin(), mu]);
                let d = comp.lobes(&pc, wi).0.specular.x - plain.lobes(&pp, wi).0.specular.x;
                acc += d * mu * 0.5 * (b - a) * w * 2.0 * PI / n_phi as f64;
            }
        }
    }
    acc
}

/// ρ(wo) of the whole model by [`lobe_albedo`].
fn albedo(m: &Disney, p: &DisneyParams, wo: [f64; 3]) -> [f64; 3] {
    let (ax, ay) = p.alphas();
    let d = lobe_albedo(m, wo, Which::Diffuse, 1.0);
    let s = lobe_albedo(m, wo, Which::Specular, (ax * ay).sqrt());
    let c = if p.clearcoat > 0.0 {
        lobe_albedo(m, wo, Which::Clearcoat, p.clearcoat_alpha())
    } else {
        [0.0; 3]
    };
    core::array::from_fn(|k| d[k] + s[k] + c[k])
}

fn view(mu: f64, phi: f64) -> [f64; 3] {
    let s = (1.0 - mu * mu).sqrt();
    [s * phi.cos(), s * phi.sin(), mu]
}

/// At normal view (μo = 1, so (1 − μo)⁵ = 0 and cos²θd = (1 + μi)/2) the
/// diffuse lobe's albedo has a closed form: with B(2, 6) = 1/42 and
/// B(3, 6) = 1/168, 2 ∫₀¹ (1 + (r(1 + μ) − ½)(1 − μ)⁵) μ dμ
/// = 1 + (r − ½)/21 + r/84 (times C_d): the Lambert value 1 plus the
/// Fresnel darkening and retro-reflection.
#[test]
fn diffuse_albedo_at_normal_view_has_its_closed_form() {
    for r in [0.0f32, 0.25, 0.5, 0.75, 1.0] {
        let p = DisneyParams {
            base_color: [1.0, 0.5, 0.25],
            specular: 0.0,
            roughness: r,
            ..DisneyParams::default()
        };
        let m = Disney::new(p.clone(), false);
        let r = r as f64;
        let expect = 1.0 + (r - 0.5) / 21.0 + r / 84.0;
        let got = lobe_albedo(&m, [0.0, 0.0, 1.0], Which::Diffuse, 1.0);
        let table = m.albedo_local(&m.prepare(V3::new(0.0, 0.0, 1.0)));
        eprintln!(
            "r = {r}: closed form {expect:.6}, quadrature {:.6}, table {:.6}",
            got[0], table.x
        );
        for c in 0..3 {
            let want = expect * p.base_color[c] as f64;
            assert!((got[c] - want).abs() < 1e-6, "r = {r}: {got:?} vs {want}");
        }
        // Specular = 0 makes F0 zero but leaves Schlick's (1 − cos θd)⁵
        // part of the specular lobe, small at a normal view: the table's
        // albedo stays within 2e-3 of the diffuse closed form (its μ = 1
        // end is also clamped at the last texel centre, μ = 0.9995).
        assert!((table.x - expect).abs() < 2e-3, "{} vs {expect}", table.x);
    }
}

/// The per-material albedo table (its own quadrature, interpolated) against
/// this file's quadrature, within 3e-3, from grazing views to the normal
/// (a rough metal's albedo still changes there).
#[test]
fn albedo_table_matches_quadrature() {
    let cases = [
        DisneyParams::default(),
        DisneyParams {
            roughness: 0.2,
            anisotropic: 0.8,
            metallic: 0.5,
            clearcoat: 1.0,
            clearcoat_gloss: 0.3,
            sheen: 1.0,
            subsurface: 0.5,
            ..DisneyParams::default()
        },
        DisneyParams {
            roughness: 0.05,
            metallic: 1.0,
            base_color: [0.9, 0.6, 0.3],
            ..DisneyParams::default()
        },
        DisneyParams {
            roughness: 0.8,
            anisotropic: 1.0,
            specular: 1.0,
            specular_tint: 1.0,
            ..DisneyParams::default()
        },
        DisneyParams {
            roughness: 1.0,
            metallic: 1.0,
            base_color: [0.8, 0.6, 0.4],
            ..DisneyParams::default()
        },
    ];
    let mut worst = 0.0f64;
    for p in cases {
        let m = Disney::new(p.clone(), false);
        for mu in [0.08, 0.2, 0.45, 0.7, 0.95, 0.999] {
            for phi in [0.0, 0.5, 1.2, 2.0, 3.5] {
                let wo = view(mu, phi);
                let q = albedo(&m, &p, wo);
                let t = m.albedo_local(&m.prepare(v64(wo)));
                for (a, b) in [(t.x, q[0]), (t.y, q[1]), (t.z, q[2])] {
                    worst = worst.max((a - b).abs());
                    assert!(
                        (a - b).abs() < 3e-3,
                        "{p:?} μ {mu} φ {phi}: table {a} vs {b}"
                    );
                }
            }
        }
    }
    eprintln!("albedo table vs quadrature: worst absolute difference {worst:e}");
}

/// metallic = 1 with a white base: F = 1 everywhere, so the specular lobe
/// is the single-scattering white furnace: never above 1, and with
/// compensation 1 (isotropic: the Kulla–Conty table is exact up to its
/// interpolation; anisotropic: indexed at √(αx αy), its error measured and
/// printed, per case with DISNEY_VERBOSE=1).
/// Indexing at the RMS α √((αx² + αy²)/2) instead was closer on average
/// but overshot to 1.08 (roughness 0.3, anisotropic 1, μo 0.3, φo = π/2).
#[test]
fn metallic_white_furnace_bounds() {
    let mut worst_iso = 0.0f64;
    let mut worst_aniso = 0.0f64;
    let mut worst_over = 0.0f64;
    for r in [0.1f32, 0.3, 0.5, 0.7, 1.0] {
        for an in [0.0f32, 0.5, 1.0] {
            let p = DisneyParams {
                base_color: [1.0; 3],
                metallic: 1.0,
                roughness: r,
                anisotropic: an,
                ..DisneyParams::default()
            };
            let plain = Disney::new_without_table(p.clone(), false);
            let comp = Disney::new_without_table(p.clone(), true);
            let (ax, ay) = p.alphas();
            for mu in [0.1, 0.3, 0.6, 0.9] {
                for phi in [0.0, 0.7, std::f64::consts::FRAC_PI_2] {
                    let wo = view(mu, phi);
                    let e = lobe_albedo(&plain, wo, Which::Specular, (ax * ay).sqrt())[0];
                    // The compensation lobe is broad and smooth: integrated
                    // over wi (the half-vector warp of a narrow lobe
                    // under-resolves it by up to 1.4e-3).
                    let ec = e + ms_albedo(&comp, &plain, wo);
                    if std::env::var("DISNEY_VERBOSE").is_ok() {
                        eprintln!("  r {r} anisotropic {an} μo {mu} φo {phi:.2}: E {e:.4}, compensated {ec:.4}");
                    }
                    assert!(e <= 1.0 + 1e-4, "r {r} an {an} μ {mu}: E = {e}");
                    // Indexed at √(αx αy), the compensation under-corrects
                    // most anisotropic lobes (by up to 0.41) and
                    // over-corrects some views by up to 2.2e-2 (roughness
                    // 0.3, anisotropic 1, μo 0.1, φo = π/2): the isotropic
                    // table cannot follow the view's azimuth. Bounded here
                    // at what was measured, so a change that makes it worse
                    // fails.
                    assert!(
                        ec <= 1.0 + 2.5e-2,
                        "r {r} an {an} μ {mu}: compensated E = {ec}"
                    );
                    worst_over = worst_over.max(ec - 1.0);
                    if an == 0.0 {
                        worst_iso = worst_iso.max((ec - 1.0).abs());
                    } else {
                        worst_aniso = worst_aniso.max((ec - 1.0).abs());
                    }
                }
            }
        }
    }
    eprintln!("compensated white furnace |E − 1|: isotropic {worst_iso:.2e}, anisotropic {worst_aniso:.2e}; largest excess over 1 {worst_over:.2e}");
    assert!(worst_iso < 5e-3, "{worst_iso}");
}

/// Directional albedo over a parameter grid with a white base (the worst
/// case): each lobe's albedo from this file's quadrature.
///
/// Bounded, and asserted ≤ 1 + 1e-3: the specular lobe (single-scattering
/// microfacet, F ≤ 1), the clearcoat (≤ ¼) and the diffuse lobe without
/// the retro-reflection term (roughness ≤ ¼ keeps F_D90 ≤ 1, so F_d ≤ 1),
/// without subsurface and without sheen. Not bounded by Burley's model,
/// measured and printed: retro-reflection (F_D90 up to 2.5), subsurface
/// (its 1/(μi + μo) grows at grazing angles), sheen (added on top), and the
/// sum of the lobes, which the model adds without energy coupling
/// (diffuse is not weighted by 1 − F of the specular or the coat).
#[test]
fn albedo_over_a_parameter_grid() {
    let vals = [0.0f32, 1.0];
    let mut max = std::collections::BTreeMap::<&str, (f64, String)>::new();
    let mut note = |key: &'static str, e: f64, what: String| {
        let w = max.entry(key).or_insert((0.0, String::new()));
        if e > w.0 {
            *w = (e, what);
        }
    };
    let mut checked = 0;
    for i in 0..2usize.pow(7) {
        for r in [0.0f32, 0.25, 0.5, 1.0] {
            let mut k = i;
            let mut next = || {
                let v = vals[k % 2];
                k /= 2;
                v
            };
            let p = DisneyParams {
                base_color: [1.0; 3],
                metallic: next(),
                subsurface: next(),
                specular: next(),
                specular_tint: next(),
                roughness: r,
                anisotropic: next(),
                sheen: next(),
                sheen_tint: 0.0,
                clearcoat: next(),
                clearcoat_gloss: next(),
            };
            let m = Disney::new_without_table(p.clone(), false);
            let (ax, ay) = p.alphas();
            for mu in [0.05, 0.2, 0.5, 1.0] {
                let wo = view(mu, 0.6);
                let what = format!("{p:?} at μo {mu}");
                let d = lobe_albedo(&m, wo, Which::Diffuse, 1.0)[0];
                let s = lobe_albedo(&m, wo, Which::Specular, (ax * ay).sqrt())[0];
                let c = lobe_albedo(&m, wo, Which::Clearcoat, p.clearcoat_alpha())[0];
                assert!(s <= 1.0 + 1e-3, "specular albedo {s} for {what}");
                assert!(c <= 0.25 + 1e-3, "clearcoat albedo {c} for {what}");
                note("specular", s, what.clone());
                note("clearcoat", c, what.clone());
                let key = match (p.sheen > 0.0, p.subsurface > 0.0, r > 0.25) {
                    (false, false, false) => {
                        assert!(d <= 1.0 + 1e-3, "diffuse albedo {d} for {what}");
                        "diffuse (no retro-reflection, subsurface or sheen)"
                    }
                    (false, false, true) => "diffuse with retro-reflection (roughness > 1/4)",
                    (false, true, _) => "diffuse with subsurface",
                    (true, _, _) => "diffuse with sheen",
                };
                note(key, d, what.clone());
                note("sum of the lobes", d + s + c, what);
                checked += 1;
            }
        }
    }
    eprintln!("{checked} (material, view) pairs; largest directional albedo, white base:");
    for (k, (e, what)) in &max {
        eprintln!("  {k}: {e:.4} ({what})");
    }
}
