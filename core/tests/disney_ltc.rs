//! The Disney model under polygon lights: its LTC integral (specular
//! through the GGX fit at √(αx αy), clearcoat through the GGX fit at its
//! stand-in α, diffuse lobes as their albedo times the form factor)
//! against the reference integration of its full BRDF (ltc/reference.rs,
//! checked against Monte Carlo in ltc_polygon.rs), over a parameter grid,
//! views 0–85° at three azimuths, and the shared test polygons. The error is a
//! fraction of the directional albedo at that view, per channel (the
//! worst channel). Also: each lobe alone, f32x8 against f64, and the
//! diffuse-albedo polynomial against the model's own quadrature.

mod common;

use common::{poly, polygons, quantile, v};
use specula_core::light::PolygonLocal;
use specula_core::ltc::reference::{integrate_polygon, Tolerance};
use specula_core::models::disney::{
    diffuse_albedo_coefficients, Disney, DisneyParams, DisneyPolygons, Lobe,
};
use specula_core::{Brdf, Real, V3};

const VIEWS: [f64; 8] = [0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 80.0, 85.0];
/// View azimuths from the tangent, cycled over the views: along the
/// tangent, between, along the bitangent.
const AZIMUTHS: [f64; 3] = [0.0, 45.0, 90.0];

const TOL: Tolerance = Tolerance {
    relative: 1e-4,
    absolute: 1e-7,
    max_nodes: 100_000,
};

/// One measured case.
#[derive(Clone, Debug)]
struct Case {
    params: DisneyParams,
    view: usize,
    what: String,
    err: f64,
}

fn rotate(p: V3<f64>, phi: f64) -> V3<f64> {
    let (s, c) = phi.sin_cos();
    v(c * p.x - s * p.y, s * p.x + c * p.y, p.z)
}

/// The views the tests measure, the azimuths cycled over them: (index,
/// θo in degrees, θo, φo, wo).
fn views() -> impl Iterator<Item = (usize, f64, f64, f64, V3<f64>)> {
    VIEWS.iter().enumerate().map(|(vi, &deg)| {
        let theta = deg.to_radians();
        let phi = AZIMUTHS[vi % AZIMUTHS.len()].to_radians();
        (
            vi,
            deg,
            theta,
            phi,
            rotate(v(theta.sin(), 0.0, theta.cos()), phi),
        )
    })
}

/// A polygon as seen from one side: its vertices as given, or reversed
/// for the back of a two-sided light.
fn wound(q: &[V3<f64>], back: bool) -> Vec<V3<f64>> {
    if back {
        q.iter().rev().copied().collect()
    } else {
        q.to_vec()
    }
}

/// The directional albedo per channel, by the model's lobe quadratures.
fn albedo(m: &Disney, wo: V3<f64>) -> [f64; 3] {
    let p = m.prepare(wo);
    let mut a = [0.0; 3];
    for lobe in [Lobe::Diffuse, Lobe::Specular, Lobe::Clearcoat] {
        let l = m.albedo_quadrature(&p, lobe);
        for c in 0..3 {
            a[c] += l[c];
        }
    }
    a
}

/// Errors of one material over every view and polygon (one- and
/// two-sided).
fn cases_of(params: &DisneyParams, two_sided: bool, kc: bool) -> Vec<Case> {
    let m = Disney::new_without_table(params.clone(), kc);
    let mut out = Vec::new();
    for (vi, deg, theta, phi, wo) in views() {
        let p = m.prepare(wo);
        let pp = m.prepare_polygons(&p);
        let alb = albedo(&m, wo);
        let f = |wi: V3<f64>| {
            let c = m.f_cos_local(&p, wi);
            [c.x, c.y, c.z]
        };
        for (name, q) in polygons(theta) {
            let q: Vec<_> = q.iter().map(|x| rotate(*x, phi)).collect();
            for sided in [false, true] {
                if sided && !two_sided {
                    continue;
                }
                let q = wound(&q, sided);
                let r = integrate_polygon(&q, sided, &f, TOL);
                let l = m.polygon_local_with(&p, &pp, &poly(&q, sided));
                let err = [l.x, l.y, l.z]
                    .iter()
                    .enumerate()
                    .map(|(c, x)| (x - r.value[c]).abs() / alb[c].max(1e-9))
                    .fold(0.0, f64::max);
                out.push(Case {
                    params: params.clone(),
                    view: vi,
                    what: format!(
                        "{name}{}, θo {deg}°, φo {}°: LTC {:.5?}, reference {:.5?}, albedo {:.4?}",
                        if sided { " (two-sided, back)" } else { "" },
                        AZIMUTHS[vi % AZIMUTHS.len()],
                        [l.x, l.y, l.z],
                        r.value,
                        alb
                    ),
                    err,
                });
            }
        }
    }
    out
}

/// [`cases_of`] over many materials on two threads (deterministic: the
/// results are concatenated in material order).
fn cases(materials: &[DisneyParams], two_sided: bool, kc: bool) -> Vec<Case> {
    let half = materials.len().div_ceil(2);
    std::thread::scope(|s| {
        let parts: Vec<_> = materials
            .chunks(half.max(1))
            .map(|chunk| {
                s.spawn(move || {
                    chunk
                        .iter()
                        .flat_map(|p| cases_of(p, two_sided, kc))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        parts.into_iter().flat_map(|h| h.join().unwrap()).collect()
    })
}

fn stats(errs: &mut [f64]) -> (f64, f64, f64) {
    errs.sort_by(f64::total_cmp);
    (
        quantile(errs, 0.5),
        quantile(errs, 0.9),
        quantile(errs, 1.0),
    )
}

/// p90 and max of the errors of the cases that `keep`.
fn p90_max_where(cases: &[Case], keep: impl Fn(&Case) -> bool) -> (f64, f64) {
    let mut e: Vec<f64> = cases.iter().filter(|c| keep(c)).map(|c| c.err).collect();
    let (_, p90, max) = stats(&mut e);
    (p90, max)
}

/// A label and the parameter a table groups cases by.
type Group<'a> = (&'a str, &'a dyn Fn(&DisneyParams) -> f32);

/// Prints median / p90 / max by view, overall, and grouped by `groups`
/// (label, key of a case); returns (p90, max) overall.
fn print_table(title: &str, cases: &[Case], groups: &[Group]) -> (f64, f64) {
    eprintln!("{title}: LTC error / directional albedo (worst channel)");
    eprintln!("  {:<22} median     p90       max", "");
    let row = |label: String, mut e: Vec<f64>| {
        let (a, b, c) = stats(&mut e);
        eprintln!(
            "  {label:<22} {:7.3}%  {:7.3}%  {:7.3}%   ({} cases)",
            100.0 * a,
            100.0 * b,
            100.0 * c,
            e.len()
        );
    };
    for (vi, deg) in VIEWS.iter().enumerate() {
        row(
            format!("θo {deg}°"),
            cases
                .iter()
                .filter(|c| c.view == vi)
                .map(|c| c.err)
                .collect(),
        );
    }
    for (label, key) in groups {
        let mut values: Vec<f32> = cases.iter().map(|c| key(&c.params)).collect();
        values.sort_by(f32::total_cmp);
        values.dedup();
        for x in values {
            row(
                format!("{label} {x}"),
                cases
                    .iter()
                    .filter(|c| key(&c.params) == x)
                    .map(|c| c.err)
                    .collect(),
            );
        }
    }
    let mut all: Vec<f64> = cases.iter().map(|c| c.err).collect();
    row("all".into(), all.clone());
    let worst = cases.iter().max_by(|a, b| a.err.total_cmp(&b.err)).unwrap();
    eprintln!(
        "  worst {:.2}%: roughness {}, metallic {}, anisotropic {}, clearcoat {}, sheen {}; {}",
        100.0 * worst.err,
        worst.params.roughness,
        worst.params.metallic,
        worst.params.anisotropic,
        worst.params.clearcoat,
        worst.params.sheen,
        worst.what
    );
    let (_, p90, max) = stats(&mut all);
    (p90, max)
}

fn base() -> DisneyParams {
    DisneyParams {
        base_color: [0.9, 0.6, 0.3],
        ..DisneyParams::default()
    }
}

const ROUGHNESS: [f32; 6] = [0.05, 0.15, 0.3, 0.5, 0.75, 1.0];

#[test]
fn disney_ltc_error_table_over_the_parameter_grid() {
    let mut materials = Vec::new();
    for roughness in [0.05, 0.3, 0.6, 1.0] {
        for metallic in [0.0, 1.0] {
            for anisotropic in [0.0, 0.5, 1.0] {
                for clearcoat in [0.0, 1.0] {
                    for sheen in [0.0, 1.0] {
                        if metallic == 1.0 && sheen == 1.0 {
                            continue; // sheen is × (1 − metallic)
                        }
                        materials.push(DisneyParams {
                            roughness,
                            metallic,
                            anisotropic,
                            clearcoat,
                            sheen,
                            ..base()
                        });
                    }
                }
            }
        }
    }
    let cases = cases(&materials, false, false);
    let (p90, max) = print_table(
        "Disney (base [0.9, 0.6, 0.3])",
        &cases,
        &[
            ("roughness", &|p| p.roughness),
            ("metallic", &|p| p.metallic),
            ("anisotropic", &|p| p.anisotropic),
            ("clearcoat", &|p| p.clearcoat),
            ("sheen", &|p| p.sheen),
        ],
    );
    // The figures are in docs/accuracy.md, "Disney under polygon
    // lights": the tail is anisotropic = 1 at grazing views.
    assert!(p90 < 0.045 && max < 0.55, "p90 {p90}, max {max}");
    let (p90, max) = p90_max_where(&cases, |c| c.params.anisotropic == 0.0);
    eprintln!(
        "  isotropic materials: p90 {:.2}%, max {:.2}%",
        100.0 * p90,
        100.0 * max
    );
    assert!(p90 < 0.03 && max < 0.13, "isotropic: p90 {p90}, max {max}");
}

/// Each lobe alone: specular (a white metal: no diffuse, C_spec0 = 1),
/// a coated black dielectric (black base, specular 0: the coat, plus the
/// specular lobe's Schlick (1 − cos θd)⁵, which F0 = 0 leaves and which
/// dominates at grazing views; the coat truly alone is
/// [`coat_ltc_error_by_gloss_and_view`]), diffuse
/// (specular 0, no coat: diffuse, subsurface blend and sheen).
#[test]
fn disney_ltc_error_of_each_lobe_alone() {
    let mut spec = Vec::new();
    let mut coat = Vec::new();
    let mut diffuse = Vec::new();
    for &roughness in &ROUGHNESS {
        for anisotropic in [0.0, 0.5, 1.0] {
            spec.push(DisneyParams {
                base_color: [1.0; 3],
                metallic: 1.0,
                roughness,
                anisotropic,
                ..DisneyParams::default()
            });
        }
        for (subsurface, sheen) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)] {
            diffuse.push(DisneyParams {
                base_color: [0.9, 0.6, 0.3],
                specular: 0.0,
                roughness,
                subsurface,
                sheen,
                ..DisneyParams::default()
            });
        }
    }
    for clearcoat_gloss in [0.0, 0.5, 1.0] {
        coat.push(DisneyParams {
            base_color: [0.0; 3],
            specular: 0.0,
            clearcoat: 1.0,
            clearcoat_gloss,
            ..DisneyParams::default()
        });
    }
    let spec_cases = cases(&spec, true, false);
    let coat_cases = cases(&coat, true, false);
    let diffuse_cases = cases(&diffuse, true, false);
    let (p90, max) = print_table(
        "specular alone (white metal)",
        &spec_cases,
        &[
            ("roughness", &|p| p.roughness),
            ("anisotropic", &|p| p.anisotropic),
        ],
    );
    // The tail is anisotropic (its lobe is not corrected: ltc/ggx.rs);
    // figures in docs/accuracy.md.
    assert!(p90 < 0.06 && max < 0.42, "specular: p90 {p90}, max {max}");
    // The isotropic lobe alone: the GGX fit with separable Smith.
    let (p90, max) = p90_max_where(&spec_cases, |c| c.params.anisotropic == 0.0);
    eprintln!(
        "  isotropic specular: p90 {:.2}%, max {:.2}%",
        100.0 * p90,
        100.0 * max
    );
    assert!(
        p90 < 0.015 && max < 0.10,
        "isotropic specular: p90 {p90}, max {max}"
    );
    let (p90, max) = print_table(
        "coated black dielectric (coat + F0 = 0 specular)",
        &coat_cases,
        &[("clearcoat_gloss", &|p| p.clearcoat_gloss)],
    );
    // Measured: p90 18.1 %, max 30.1 %, nearly all of it the F0 = 0
    // specular lobe's (its own error is up to 58 % of its albedo: the
    // Schlick split's n_w part keeps the F = 1 lobe's shape); at views
    // ≤ 30°: max 4.5 %. (Before the coat's own fit, with the two-GGX
    // stand-in: p90 21 %, max 33.8 %.)
    assert!(
        p90 < 0.21 && max < 0.35,
        "coated black dielectric: p90 {p90}, max {max}"
    );
    let (p90, max) = p90_max_where(&coat_cases, |c| VIEWS[c.view] <= 30.0);
    assert!(
        p90 < 0.06 && max < 0.10,
        "coated black dielectric, θo ≤ 30°: p90 {p90}, max {max}"
    );
    let (p90, max) = print_table(
        "diffuse alone",
        &diffuse_cases,
        &[
            ("roughness", &|p| p.roughness),
            ("subsurface", &|p| p.subsurface),
            ("sheen", &|p| p.sheen),
        ],
    );
    // Figures in docs/accuracy.md (retro-reflection and sheen at
    // grazing views, where the lobe is far from its Lambert equivalent).
    assert!(p90 < 0.03 && max < 0.16, "diffuse: p90 {p90}, max {max}");
}

/// Kulla–Conty compensation under polygon lights: its lobe as its albedo
/// factor (1 − E(μo)) times the form factor, like `microfacet`'s.
#[test]
fn compensated_metals_through_the_ltc() {
    let metals: Vec<_> = [0.3, 0.6, 1.0]
        .iter()
        .map(|&roughness| DisneyParams {
            base_color: [0.95, 0.7, 0.4],
            metallic: 1.0,
            roughness,
            ..DisneyParams::default()
        })
        .collect();
    let c = cases(&metals, false, true);
    let (p90, max) = print_table("compensated metal", &c, &[("roughness", &|p| p.roughness)]);
    // The tail is large polygons at grazing views, where the correction
    // is off; figures in docs/accuracy.md.
    assert!(p90 < 0.035 && max < 0.09, "p90 {p90}, max {max}");
}

/// The diffuse-albedo polynomial table against the model's own diffuse
/// quadrature of the full lobes (roughness up to 2, subsurface, sheen).
#[test]
fn the_diffuse_albedo_table_matches_the_lobe_quadrature() {
    let mut worst = 0.0f64;
    for roughness in [0.0, 0.3, 0.8, 1.0, 2.0] {
        for (subsurface, sheen) in [(0.0, 0.0), (0.5, 0.0), (1.0, 1.0), (0.0, 2.0)] {
            let m = Disney::new_without_table(
                DisneyParams {
                    base_color: [0.9, 0.6, 0.3],
                    roughness,
                    subsurface,
                    sheen,
                    ..DisneyParams::default()
                },
                false,
            );
            for mu in [0.02, 0.1, 0.37, 0.7, 1.0] {
                let wo = v((1.0 - mu * mu).sqrt(), 0.0, mu);
                let want = m.albedo_quadrature(&m.prepare(wo), Lobe::Diffuse);
                let got = m.diffuse_albedo(mu);
                for (c, g) in [got.x, got.y, got.z].iter().enumerate() {
                    worst = worst.max((g - want[c]).abs() / want[c]);
                }
            }
        }
    }
    // And the coefficients directly against the lobe at r = 0 (F_d only).
    let c = diffuse_albedo_coefficients(1.0);
    eprintln!("diffuse albedo table vs quadrature: worst relative {worst:e}; at μo = 1: {c:?}");
    assert!(worst < 2e-3, "{worst:e}");
}

#[test]
fn f32x8_matches_f64_through_the_disney_ltc() {
    let mut worst = 0.0f64;
    for p in [
        DisneyParams::default(),
        DisneyParams {
            metallic: 1.0,
            roughness: 0.3,
            anisotropic: 0.7,
            clearcoat: 1.0,
            clearcoat_gloss: 0.6,
            ..DisneyParams::default()
        },
        DisneyParams {
            roughness: 0.8,
            subsurface: 1.0,
            sheen: 1.0,
            clearcoat: 0.5,
            ..DisneyParams::default()
        },
    ] {
        for kc in [false, true] {
            let m = Disney::new_without_table(p.clone(), kc);
            worst = worst.max(common::worst_lanes_against_f64(&m));
        }
    }
    eprintln!("f32x8 and f32 vs f64 through the Disney LTC: worst |Δ| = {worst:e}");
    assert!(worst < 3e-5, "{worst:e}");
}

/// The errors of one lobe of `m` alone (`lobe` of [`Disney::lobes`]
/// against `ltc`, its share of the polygon integral), as a fraction of
/// that lobe's own directional albedo, over [`VIEWS`] and every polygon, one- and two-sided: (view index, error).
fn lobe_errors(
    m: &Disney,
    lobe: Lobe,
    ltc: &dyn Fn(&DisneyPolygons<f64>, &PolygonLocal<f64>) -> f64,
) -> Vec<(usize, f64)> {
    let mut out = Vec::new();
    // The views and azimuths of `cases_of` (the coat is isotropic: every
    // azimuth gives the same errors).
    for (vi, _, theta, phi, wo) in views() {
        let p = m.prepare(wo);
        let pp = m.prepare_polygons(&p);
        let alb = m.albedo_quadrature(&p, lobe)[0];
        let f = |wi: V3<f64>| {
            let (l, above) = m.lobes(&p, wi);
            let x = match lobe {
                Lobe::Clearcoat => l.clearcoat,
                Lobe::Specular => l.specular.x,
                Lobe::Diffuse => l.diffuse.x,
            };
            [if above { x * wi.z } else { 0.0 }; 3]
        };
        for (_, q) in polygons(theta) {
            let q: Vec<_> = q.iter().map(|x| rotate(*x, phi)).collect();
            for sided in [false, true] {
                let q = wound(&q, sided);
                let r = integrate_polygon(&q, sided, &f, TOL).value[0];
                let l = ltc(&pp, &poly(&q, sided));
                out.push((vi, (l - r).abs() / alb));
            }
        }
    }
    out
}

/// The clearcoat lobe truly alone: the coat's part of the LTC integral
/// against the reference integral of the coat lobe only, per
/// clearcoat_gloss and view, as a fraction of the coat's own albedo.
/// (`disney_ltc_error_of_each_lobe_alone`'s coat material still has a
/// specular lobe: specular = 0 makes its F0 zero, but Schlick's
/// (1 − cos θd)⁵ remains and dominates at grazing views; printed here too.)
#[test]
fn coat_ltc_error_by_gloss_and_view() {
    let glosses = [0.0f32, 0.1, 0.25, 0.4, 0.5, 0.6, 0.75, 0.9, 0.97, 1.0];
    // Per gloss: (the coat's errors, the specular lobe's), by view.
    type Errors = Vec<(usize, f64)>;
    let per: Vec<(Errors, Errors)> = std::thread::scope(|s| {
        let hs: Vec<_> = glosses
            .iter()
            .map(|&clearcoat_gloss| {
                s.spawn(move || {
                    let m = Disney::new_without_table(
                        DisneyParams {
                            base_color: [0.0; 3],
                            specular: 0.0,
                            clearcoat: 1.0,
                            clearcoat_gloss,
                            ..DisneyParams::default()
                        },
                        false,
                    );
                    let coat = lobe_errors(&m, Lobe::Clearcoat, &|pp, q| {
                        let c = pp.coat.as_ref().expect("a coat");
                        c.ltc
                            .iter()
                            .zip(c.scale)
                            .map(|(l, s)| s * l.integral(q))
                            .sum()
                    });
                    let spec = lobe_errors(&m, Lobe::Specular, &|pp, q| {
                        pp.specular.x * pp.spec.integral(q)
                    });
                    (coat, spec)
                })
            })
            .collect();
        hs.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let summary = |e: &[(usize, f64)], view: Option<usize>| {
        let mut x: Vec<f64> = e
            .iter()
            .filter(|(v, _)| view.is_none_or(|w| *v == w))
            .map(|(_, e)| *e)
            .collect();
        let (_, p90, max) = stats(&mut x);
        (p90, max)
    };
    for (title, pick) in [
        ("clearcoat lobe alone", 0usize),
        ("its F0 = 0 specular lobe, roughness 0.5", 1),
    ] {
        eprintln!("{title}: LTC error / the lobe's albedo, p90 / max (%)");
        eprint!("  {:<10}", "gloss");
        for deg in VIEWS {
            eprint!(" {:>13}", format!("θo {deg}°"));
        }
        eprintln!(" {:>13}", "all");
        for (g, e) in glosses.iter().zip(&per) {
            let e = if pick == 0 { &e.0 } else { &e.1 };
            eprint!("  {:<10}", g);
            for vi in 0..VIEWS.len() {
                let (p, m) = summary(e, Some(vi));
                eprint!(" {:>13}", format!("{:.1} / {:.1}", 100.0 * p, 100.0 * m));
            }
            let (p, m) = summary(e, None);
            eprintln!(" {:>13}", format!("{:.1} / {:.1}", 100.0 * p, 100.0 * m));
        }
    }
    let coat: Vec<(usize, f64)> = per.iter().flat_map(|e| e.0.clone()).collect();
    let (p90, max) = summary(&coat, None);
    let near: Vec<(usize, f64)> = coat
        .iter()
        .filter(|(v, _)| VIEWS[*v] <= 30.0)
        .copied()
        .collect();
    let (p90_near, max_near) = summary(&near, None);
    let below_1: Vec<(usize, f64)> = glosses
        .iter()
        .zip(&per)
        .filter(|(g, _)| **g <= 0.75)
        .flat_map(|(_, e)| e.0.clone())
        .collect();
    let (p90_rough, max_rough) = summary(&below_1, None);
    eprintln!(
        "clearcoat lobe alone: all p90 {:.2} %, max {:.2} %; θo ≤ 30°: p90 {:.2} %, max {:.2} %; \
         gloss ≤ 0.75: p90 {:.2} %, max {:.2} %",
        100.0 * p90,
        100.0 * max,
        100.0 * p90_near,
        100.0 * max_near,
        100.0 * p90_rough,
        100.0 * max_rough
    );
    // Measured with three cosines: p90 1.1 %, max 7.3 % (gloss 1,
    // α = 0.001, at 85°); gloss ≤ 0.75 p90 0.95 %, max 3.6 %; θo ≤ 30°
    // p90 0.38 %, max 1.5 %. On the glosses 0, ¼, ½, ¾, 1 alone: p90
    // 1.2 %, max 7.3 %; with two cosines p90 2.0 %, max 13.6 %; with the
    // two-GGX stand-in before them p90 6.2 %, max 17.4 % (θo ≤ 30° p90
    // 2.8 %, max 7.7 %).
    assert!(p90 < 0.015 && max < 0.085, "coat: p90 {p90}, max {max}");
    assert!(
        p90_rough < 0.012 && max_rough < 0.045,
        "coat, gloss ≤ 0.75: p90 {p90_rough}, max {max_rough}"
    );
    assert!(
        p90_near < 0.006 && max_near < 0.02,
        "coat, θo ≤ 30°: p90 {p90_near}, max {max_near}"
    );
}
