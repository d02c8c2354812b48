//! The GGX LTC against the reference integration (ltc/reference.rs, itself
//! checked against Monte Carlo in ltc_polygon.rs): the error table over
//! α ∈ [0.05, 1], views 0–85°, quads and triangles overhead, in the mirror
//! direction, tilted, straddling, near and below the horizon, one- and
//! two-sided; the error is a fraction of the directional albedo n(α, μo)
//! (F = 1), the measure of [Heitz16]'s evaluation. Also: the committed
//! table decodes, f32x8 matches f64, and the materials built on it.

mod common;

use common::{facing_square, poly, polygons, quantile, v};
use specula_core::ltc::ggx::{decode, encode, lookup, table, Cell, N, X_AXIS};
use specula_core::ltc::reference::{integrate_polygon, Tolerance};
use specula_core::models::microfacet::{Fresnel, Microfacet, MicrofacetParams, Ndf, Smith};
use specula_core::models::MetallicRoughness;
use specula_core::small_light::{self, PixelError, Scene};
use specula_core::{Brdf, V3};

fn ggx(alpha: f32, f0: [f32; 3]) -> Microfacet {
    Microfacet::new_without_table(
        MicrofacetParams {
            ndf: Ndf::Ggx,
            alpha,
            smith: Smith::HeightCorrelated,
            fresnel: Fresnel::Schlick { f0 },
            diffuse: [0.0; 3],
            gtr_lambda: Default::default(),
        },
        None,
    )
}

#[test]
fn the_committed_table_round_trips_through_its_format() {
    let t = table();
    // Re-encode the decoded values and decode again: same nodes.
    let cells: Vec<Vec<Cell>> = (0..N)
        .map(|j| {
            (0..N)
                .map(|i| {
                    let m = t.node_value(i, j);
                    // Channels are c M⁻¹ with m11 = 1: M ∝ its inverse.
                    let (m00, m02, m20, m22) = (m[0] as f64, m[1] as f64, m[2] as f64, m[3] as f64);
                    let det = m00 * m22 - m02 * m20;
                    let (a, b, d, e) = (m22 / det, -m02 / det, -m20 / det, m00 / det);
                    Cell {
                        a: a / e,
                        b: b / e,
                        c: 1.0 / e,
                        d: d / e,
                        n: m[4] as f64,
                        n_w: m[5] as f64,
                    }
                })
                .collect()
        })
        .collect();
    let again = decode(&encode(&cells, &["test".into()])).unwrap();
    for j in 0..N {
        for i in 0..N {
            let (x, y) = (t.node_value(i, j), again.node_value(i, j));
            for c in 0..6 {
                assert!(
                    (x[c] - y[c]).abs() <= 1e-5 * x[c].abs().max(1.0),
                    "node ({i}, {j}) channel {c}: {} vs {}",
                    x[c],
                    y[c]
                );
            }
        }
    }
    assert!(decode(b"specula-ltc 1 64 64 6\nend\n").is_err());
    assert!(decode(b"nonsense").is_err());
}

/// Errors of `model`'s LTC integral against the reference, as fractions
/// of its albedo n (F = 1), over the test set: all, by view, the worst.
fn error_table(model: impl Fn(f32) -> Microfacet) -> (Vec<f64>, Vec<Vec<f64>>, String) {
    let alphas = [0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0];
    let tol = Tolerance {
        relative: 1e-4,
        absolute: 1e-7,
        max_nodes: 100_000,
    };
    let mut all = Vec::new();
    let mut by_view: Vec<Vec<f64>> = vec![Vec::new(); VIEWS.len()];
    let mut worst = (0.0, String::new());
    for &alpha in &alphas {
        let m = model(alpha as f32);
        for (vi, &deg) in VIEWS.iter().enumerate() {
            let theta = deg.to_radians();
            let wo = v(theta.sin(), 0.0, theta.cos());
            let p = m.prepare(wo);
            let n = m.params.specular_albedo(theta.cos())[0];
            let f = |wi: V3<f64>| {
                let c = m.f_cos_local(&p, wi);
                [c.x, c.y, c.z]
            };
            for (name, q) in polygons(theta) {
                for two_sided in [false, true] {
                    // Two-sided: show the light's back.
                    let q: Vec<_> = if two_sided {
                        q.iter().rev().copied().collect()
                    } else {
                        q.clone()
                    };
                    let r = integrate_polygon(&q, two_sided, &f, tol);
                    let ltc = m.polygon_local(&p, &poly(&q, two_sided)).x;
                    let e = (ltc - r.value[0]).abs() / n;
                    all.push(e);
                    by_view[vi].push(e);
                    if e > worst.0 {
                        worst = (
                            e,
                            format!("α {alpha}, θo {deg}°, {name}, two-sided {two_sided}: LTC {ltc:.5}, reference {:.5} ± {:.1e}, n {n:.4}", r.value[0], r.error),
                        );
                    }
                }
            }
        }
    }
    all.sort_by(f64::total_cmp);
    (all, by_view, worst.1)
}

const VIEWS: [f64; 8] = [0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 80.0, 85.0];

fn print_table(title: &str, all: &[f64], by_view: &[Vec<f64>], worst: &str) {
    eprintln!("{title}: LTC error / albedo, by view (all α, polygons, sidedness):");
    eprintln!("  θo     median     p90       max");
    for (vi, &deg) in VIEWS.iter().enumerate() {
        let mut e = by_view[vi].clone();
        e.sort_by(f64::total_cmp);
        eprintln!(
            "  {deg:>3}°   {:7.3}%  {:7.3}%  {:7.3}%",
            100.0 * quantile(&e, 0.5),
            100.0 * quantile(&e, 0.9),
            100.0 * quantile(&e, 1.0)
        );
    }
    eprintln!(
        "  all    {:7.3}%  {:7.3}%  {:7.3}%   ({} cases)",
        100.0 * quantile(all, 0.5),
        100.0 * quantile(all, 0.9),
        100.0 * quantile(all, 1.0),
        all.len()
    );
    eprintln!("  worst: {worst}");
}

#[test]
fn ltc_error_table_against_the_reference() {
    let (all, by_view, worst) = error_table(|a| ggx(a, [1.0; 3]));
    print_table("GGX, height-correlated Smith", &all, &by_view, &worst);
    let (p90, max) = (quantile(&all, 0.9), quantile(&all, 1.0));
    assert!(
        p90 < P90_BOUND && max < MAX_BOUND,
        "p90 {p90}, max {max}: {worst}"
    );
}

/// What sharing the fit costs: separable Smith and Beckmann through the
/// GGX (height-correlated) table at the same α.
#[test]
fn ltc_error_of_the_lobes_that_share_the_ggx_fit() {
    let with = |ndf: Ndf, smith: Smith| {
        move |alpha: f32| {
            Microfacet::new_without_table(
                MicrofacetParams {
                    ndf,
                    alpha,
                    smith,
                    fresnel: Fresnel::Schlick { f0: [1.0; 3] },
                    diffuse: [0.0; 3],
                    gtr_lambda: Default::default(),
                },
                None,
            )
        }
    };
    let (all, by_view, worst) = error_table(with(Ndf::Ggx, Smith::Separable));
    print_table(
        "GGX, separable Smith (height-correlated fit)",
        &all,
        &by_view,
        &worst,
    );
    assert!(quantile(&all, 0.9) < SEPARABLE_P90 && quantile(&all, 1.0) < SEPARABLE_MAX);
    let (all, by_view, worst) = error_table(with(Ndf::Beckmann, Smith::HeightCorrelated));
    print_table("Beckmann (GGX fit at the same α)", &all, &by_view, &worst);
    assert!(quantile(&all, 0.9) < BECKMANN_P90 && quantile(&all, 1.0) < BECKMANN_MAX);
}

/// Bounds above the measured figures (docs/accuracy.md): separable Smith
/// shares the height-correlated fit (its n is the height-correlated
/// albedo, above the separable one at grazing views, where large polygons
/// get no correction); Beckmann through the GGX fit is far off, which is
/// why scenes and eval refuse polygon lights on non-GGX microfacet
/// materials.
const SEPARABLE_P90: f64 = 0.02;
const SEPARABLE_MAX: f64 = 0.11;
const BECKMANN_P90: f64 = 0.14;
const BECKMANN_MAX: f64 = 0.36;

/// The measured p90 and max with a margin, over the 1008 cases, of the
/// committed table with the lobe's correction (figures by view in
/// docs/accuracy.md).
const P90_BOUND: f64 = 0.015;
const MAX_BOUND: f64 = 0.09;

#[test]
fn f32x8_and_f32_match_f64_through_the_ltc() {
    let worst = common::worst_lanes_against_f64(&ggx(0.3, [0.9, 0.5, 0.1]));
    eprintln!("f32x8 and f32 vs f64 through the GGX LTC: worst |Δ| = {worst:e}");
    assert!(worst < 2e-5, "{worst:e}");
}

#[test]
fn the_view_azimuth_only_rotates_the_problem() {
    // Rotating view and polygon together about the normal changes nothing.
    let m = ggx(0.25, [1.0; 3]);
    let t = 0.9f64;
    let q = facing_square(v(-1.0, 0.3, 1.2), 0.7, 0.2);
    let base = m
        .polygon_local(&m.prepare(v(t.sin(), 0.0, t.cos())), &poly(&q, false))
        .x;
    for phi in [0.4f64, 2.0, -2.8] {
        let (s, c) = phi.sin_cos();
        let rot = |p: V3<f64>| v(c * p.x - s * p.y, s * p.x + c * p.y, p.z);
        let qr: Vec<_> = q.iter().map(|p| rot(*p)).collect();
        let got = m
            .polygon_local(&m.prepare(rot(v(t.sin(), 0.0, t.cos()))), &poly(&qr, false))
            .x;
        assert!((got - base).abs() < 1e-12, "φ {phi}: {got} vs {base}");
    }
}

#[test]
fn metallic_roughness_through_the_ltc_against_the_reference() {
    let mut errs = Vec::new();
    for (roughness, metallic) in [(0.3f32, 0.0f32), (0.5, 1.0), (0.8, 0.4)] {
        let m = MetallicRoughness {
            base_color: [0.9, 0.6, 0.3],
            roughness,
            metallic,
        };
        for deg in [0.0f64, 30.0, 60.0, 80.0] {
            let t = deg.to_radians();
            let wo = v(t.sin(), 0.0, t.cos());
            let p = m.prepare(wo);
            let f = |wi: V3<f64>| {
                let c = m.f_cos_local(&p, wi);
                [c.x, c.y, c.z]
            };
            let alb = m.albedo_local(&p);
            for (_, q) in polygons(t) {
                let r = integrate_polygon(&q, false, &f, Tolerance::FINE);
                let l = m.polygon_local(&p, &poly(&q, false));
                for (c, (a, b)) in [(l.x, alb.x), (l.y, alb.y), (l.z, alb.z)]
                    .iter()
                    .enumerate()
                {
                    errs.push((a - r.value[c]).abs() / b);
                }
            }
        }
    }
    errs.sort_by(f64::total_cmp);
    eprintln!(
        "metallic_roughness LTC error / albedo: median {:.3}%, p90 {:.3}%, max {:.3}%",
        100.0 * quantile(&errs, 0.5),
        100.0 * quantile(&errs, 0.9),
        100.0 * quantile(&errs, 1.0)
    );
    // Figures in docs/accuracy.md; the tail is the diffuse part's (1 − F)
    // taken at its hemispherical mean (see the model's docs).
    assert!(quantile(&errs, 0.9) < 0.025 && quantile(&errs, 1.0) < 0.16);
}

/// The per-pixel error under a small light (core/src/small_light.rs: a 0.3 ×
/// 0.3 quad at distance 1 over a sphere and a floor) for α 0.2–0.5,
/// against the reference quadrature.
#[test]
fn small_light_per_pixel_error_on_a_sphere_and_a_floor() {
    let cases: Vec<(f64, Scene)> = [0.2, 0.3, 0.4, 0.5]
        .iter()
        .flat_map(|&a| [(a, Scene::Sphere), (a, Scene::Floor)])
        .collect();
    let errs: Vec<PixelError> = std::thread::scope(|s| {
        let handles: Vec<_> = cases
            .chunks(cases.len() / 2)
            .map(|chunk| {
                s.spawn(move || {
                    chunk
                        .iter()
                        .map(|&(a, scene)| {
                            small_light::pixel_error(table(), a, scene, 32, small_light::LIT)
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("no panic"))
            .collect()
    });
    eprintln!("small light, per pixel |LTC / reference − 1| (pixels ≥ 1 % of the brightest):");
    for ((alpha, scene), e) in cases.iter().zip(&errs) {
        eprintln!(
            "  α {alpha} {scene:?}: mean {:.2}%, worst {:.1}%, brightness-weighted {:.2}% ({} pixels)",
            100.0 * e.mean,
            100.0 * e.worst,
            100.0 * e.weighted,
            e.pixels
        );
    }
    for ((alpha, scene), e) in cases.iter().zip(&errs) {
        assert!(
            e.mean <= SMALL_LIGHT_MEAN && e.worst <= SMALL_LIGHT_WORST,
            "α {alpha} {scene:?}: {e:?}"
        );
    }
}

/// The LTC / reference ratio along a view sweep (light in the mirror
/// direction): its second difference centred on the table's row nodes
/// against centred inside the rows (root mean square), over views 0–85°
/// and 0–65°. The aim is a ratio of at most 1 (no kinks at row
/// boundaries; docs/accuracy.md, "Seams"). Over 0–65°, where the ratio
/// is smooth and slowly curved, the two measures are equal up to their
/// statistical spread (`KINK_RATIO_LOW`).
#[test]
fn the_view_sweep_has_no_kinks_at_row_boundaries() {
    let y = |deg: f64| (1.0 - deg.to_radians().cos()).sqrt();
    for alpha in [0.2, 0.3, 0.4, 0.5] {
        let k = small_light::kinks(table(), alpha, 0.0, y(85.0));
        let low = small_light::kinks(table(), alpha, 0.0, y(65.0));
        eprintln!(
            "α {alpha}: second difference rms across rows {:.2e}, within rows {:.2e} (0–85°); \
             {:.2e} and {:.2e} (0–65°)",
            k.across_rms(),
            k.within_rms(),
            low.across_rms(),
            low.within_rms()
        );
        assert!(
            low.across_rms() <= KINK_RATIO_LOW * low.within_rms(),
            "α {alpha}: {:.2e} across vs {:.2e} within rows at views up to 65°",
            low.across_rms(),
            low.within_rms()
        );
        assert!(
            low.across_rms() <= KINK_LOW,
            "α {alpha}: {:.2e} across rows at views up to 65°",
            low.across_rms()
        );
        assert!(
            k.across_rms() <= KINK_RATIO * k.within_rms(),
            "α {alpha}: {:.2e} across vs {:.2e} within",
            k.across_rms(),
            k.within_rms()
        );
    }
}

/// The runtime's lookup of the committed table (the transform splined
/// along the view, which unlike a bilinear lookup can leave its nodes'
/// range) keeps every transform valid: m00, m22 and the determinant of c
/// M⁻¹ positive (no reflection, which would flip a polygon's winding),
/// and n_w ≤ n; over the whole table and densely in the corner of
/// mirror-like roughness and grazing views, where the transform
/// degenerates.
#[test]
fn the_runtime_lookup_keeps_every_transform_valid() {
    let l = lookup();
    let (lo, hi) = (X_AXIS.lo(), X_AXIS.hi());
    let grids = [
        ((lo, hi), (0.0, 1.0), 400),
        ((lo, lo + 0.05), (0.99, 1.0), 300),
    ];
    let mut worst = f64::MAX;
    for ((x0, x1), (y0, y1), n) in grids {
        for a in 0..=n {
            let x = x0 + (x1 - x0) * a as f64 / n as f64;
            for b in 0..=n {
                let y = y0 + (y1 - y0) * b as f64 / n as f64;
                let [m00, m02, m20, m22, albedo, albedo_w] = l.get(x, y);
                let det = m00 * m22 - m02 * m20;
                worst = worst.min(det / (m00 * m22 + (m02 * m20).abs()));
                assert!(
                    m00 > 0.0 && m22 > 0.0 && det > 0.0,
                    "(x {x}, y {y}): m00 {m00:e}, m22 {m22:e}, det {det:e}"
                );
                assert!(
                    albedo_w <= albedo,
                    "(x {x}, y {y}): n {albedo}, n_w {albedo_w}"
                );
            }
        }
    }
    eprintln!("runtime lookup: smallest det / (|m00 m22| + |m02 m20|) {worst:.3e}");
}

/// Bounds that hold the committed table and its correction where they
/// are (their figures and the aims, a mean of 2 % and a ratio of 1, are
/// in docs/accuracy.md, "Per pixel under a small light, and seams"): a
/// change must not do worse. The per-pixel bounds are the aim itself.
const SMALL_LIGHT_MEAN: f64 = 0.02;
const SMALL_LIGHT_WORST: f64 = 0.02;
/// The aim of 1 with room for the spread of two equal root mean squares
/// over some 50 rows.
const KINK_RATIO_LOW: f64 = 1.05;
/// The aim itself, over 0–85°.
const KINK_RATIO: f64 = 1.0;
/// Root mean square of the second differences across rows, views 0–65°.
const KINK_LOW: f64 = 1.5e-4;
