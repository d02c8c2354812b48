//! The anisotropic filter against a supersampled box-filtered reference on
//! a tilted checker plane, and the material maps (maps.rs) in f32x8
//! against the scalar twin and a plain f64 formula written here.

use rand::{Rng, SeedableRng};
use specula_core::light::Light;
use specula_core::models::Lambert;
use specula_core::ShadingFrame;
use specula_core::{f32x8, Model, Real, Rgb, V3};
use specula_raster::maps::{ColorMap, NormalMap, OcclusionMap, ParamMaps};
use specula_raster::texture::{Filter, Sampler, Texture, Wrap};
use specula_raster::Lit;
use specula_raster::{Fragment, Surface};
use specula_raster::{PacketShader, ShadeEnv, ShadeInput};
use std::sync::Arc;

/// A ground plane seen toward its horizon: pixel (x, y) of a 64 × 64
/// image (y down from just below the horizon) shows
/// uv = (S (x − 32) / (y + Y0), K / (y + Y0)), a homography, with its
/// analytic derivatives.
const Y0: f64 = 4.0;
const S: f64 = 0.125;
const K: f64 = 20.0;

fn plane_uv(x: f64, y: f64) -> [f64; 2] {
    [S * (x - 32.0) / (y + Y0), K / (y + Y0)]
}

fn plane_duv(x: f64, y: f64) -> ([f64; 2], [f64; 2]) {
    let d = y + Y0;
    ([S / d, 0.0], [-S * (x - 32.0) / (d * d), -K / (d * d)])
}

#[test]
fn anisotropic_filtering_is_closer_than_trilinear_to_the_supersampled_plane() {
    // A 128 × 128 checker of 8-texel squares, 0 and 1.
    let n = 128usize;
    let img: Vec<f32> = (0..n * n)
        .map(|k| (((k % n) / 8 + (k / n) / 8) % 2) as f32)
        .collect();
    let tex = Texture::from_f32(n, n, 1, img).unwrap();
    let sampler = |filter| Sampler::new(Wrap::Repeat, filter);
    let bilinear = sampler(Filter::Bilinear);
    // Reference: the box average over the pixel of the level-0 image (its
    // bilinear reconstruction), 32 × 32 samples a pixel.
    let sub = 32;
    let (mut err_tri, mut err_aniso, mut count) = (0.0f64, 0.0f64, 0usize);
    for y in 0..64 {
        for x in 0..64 {
            let mut sum = 0.0;
            for j in 0..sub {
                for i in 0..sub {
                    let px = x as f64 + (i as f64 + 0.5) / sub as f64;
                    let py = y as f64 + (j as f64 + 0.5) / sub as f64;
                    let [v]: [f64; 1] = tex.sample_lod(&bilinear, plane_uv(px, py), 0.0);
                    sum += v;
                }
            }
            let want = sum / (sub * sub) as f64;
            let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
            let (dx, dy) = plane_duv(cx, cy);
            let uv = plane_uv(cx, cy);
            let [tri]: [f64; 1] = tex.sample(&sampler(Filter::Trilinear), uv, dx, dy);
            let [an]: [f64; 1] = tex.sample(&sampler(Filter::Anisotropic(16)), uv, dx, dy);
            err_tri += (tri - want).powi(2);
            err_aniso += (an - want).powi(2);
            count += 1;
        }
    }
    let (rms_tri, rms_aniso) = (
        (err_tri / count as f64).sqrt(),
        (err_aniso / count as f64).sqrt(),
    );
    // Stated errors (RMS over the 64 × 64 pixels, checker values 0 and 1):
    // trilinear blurs the footprint's short axis to its long one's width
    // and is off by more than 0.06; 16 anisotropic taps stay under 0.02,
    // at most a quarter of trilinear's.
    assert!(rms_tri > 0.06, "trilinear RMS {rms_tri}");
    assert!(rms_aniso < 0.02, "anisotropic RMS {rms_aniso}");
    assert!(
        rms_aniso < 0.25 * rms_tri,
        "anisotropic {rms_aniso} vs trilinear {rms_tri}"
    );
}

#[test]
fn one_anisotropic_tap_is_trilinear_and_isotropic_footprints_take_one_tap() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let (w, h) = (32usize, 16usize);
    let img: Vec<f32> = (0..w * h * 3).map(|_| rng.random::<f32>()).collect();
    let tex = Texture::from_f32(w, h, 3, img).unwrap();
    let tri = Sampler::new(Wrap::Repeat, Filter::Trilinear);
    for _ in 0..300 {
        let uv = [rng.random_range(-2.0..2.0f64), rng.random_range(-2.0..2.0)];
        let dx = [rng.random_range(-0.2..0.2f64), rng.random_range(-0.2..0.2)];
        let dy = [rng.random_range(-0.2..0.2f64), rng.random_range(-0.2..0.2)];
        let want: [f64; 3] = tex.sample(&tri, uv, dx, dy);
        let one = Sampler::new(Wrap::Repeat, Filter::Anisotropic(1));
        let got: [f64; 3] = tex.sample(&one, uv, dx, dy);
        for c in 0..3 {
            assert!((got[c] - want[c]).abs() < 1e-12, "{got:?} vs {want:?}");
        }
        // A round footprint (equal axes in texels): one tap at the same λ.
        let r = rng.random_range(0.001..0.1f64);
        let (dx, dy) = ([r / w as f64, 0.0], [0.0, r / h as f64]);
        let (n, _, _) = tex.anisotropic_footprint(dx, dy, 16);
        assert_eq!(n, 1.0);
    }
}

/// A texture of 3 channels, w × h random values in [0, 1] (the third in
/// [½, 1]: as a normal map, normals above the surface).
fn random_map(rng: &mut impl Rng, w: usize, h: usize, filter: Filter) -> ColorMap {
    let img: Vec<f32> = (0..w * h * 3)
        .map(|k| {
            let r = rng.random::<f32>();
            if k % 3 == 2 {
                0.5 + 0.5 * r
            } else {
                r
            }
        })
        .collect();
    ColorMap {
        texture: Arc::new(Texture::from_f32(w, h, 3, img).unwrap()),
        sampler: Sampler::new(Wrap::Repeat, filter),
        transform: None,
    }
}

/// A unit vector of random direction.
fn unit(rng: &mut impl Rng) -> [f64; 3] {
    loop {
        let v: [f64; 3] = core::array::from_fn(|_| rng.random_range(-1.0..1.0));
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if l > 0.2 && l < 1.0 {
            return v.map(|c| c / l);
        }
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalize(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    a.map(|c| c / l)
}

/// One lane's inputs: uv, its derivatives, the normal, tangent, sign and
/// the view direction.
#[derive(Clone, Copy, Debug)]
struct LaneIn {
    uv: [f64; 2],
    duv: [f64; 4],
    n: [f64; 3],
    t: [f64; 3],
    sign: f64,
    wo: [f64; 3],
}

fn random_lane(rng: &mut impl Rng) -> LaneIn {
    let n = unit(rng);
    let t = normalize({
        let a = unit(rng);
        let k = dot(a, n);
        [a[0] - n[0] * k, a[1] - n[1] * k, a[2] - n[2] * k]
    });
    // Views above the surface, so the bend toward the eye rarely applies.
    let wo = normalize({
        let a = unit(rng);
        let k = dot(a, n).abs() + 0.3;
        [a[0] + n[0] * k, a[1] + n[1] * k, a[2] + n[2] * k]
    });
    LaneIn {
        uv: [rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0)],
        duv: core::array::from_fn(|_| rng.random_range(-0.05..0.05)),
        n,
        t,
        sign: if rng.random::<bool>() { 1.0 } else { -1.0 },
        wo,
    }
}

/// The fragment and surface of `lanes` in lane type R.
fn inputs<R: Real>(lanes: &[LaneIn]) -> (Fragment<R>, Surface<R>) {
    let col = |f: &dyn Fn(&LaneIn) -> f64| -> R {
        let v: Vec<f32> = (0..R::LANES).map(|l| f(&lanes[l]) as f32).collect();
        R::load(&v)
    };
    let v3 = |f: &dyn Fn(&LaneIn) -> [f64; 3]| {
        V3::new(col(&|l| f(l)[0]), col(&|l| f(l)[1]), col(&|l| f(l)[2]))
    };
    let n = v3(&|l| l.n);
    let t = v3(&|l| l.t);
    let sign = col(&|l| l.sign);
    let frag = Fragment {
        p: V3::zero(),
        n,
        wo: v3(&|l| l.wo),
        w: R::ONE,
        b1: R::ZERO,
        b2: R::ZERO,
    };
    let surface = Surface {
        uv: [col(&|l| l.uv[0]), col(&|l| l.uv[1])],
        duv_dx: [col(&|l| l.duv[0]), col(&|l| l.duv[1])],
        duv_dy: [col(&|l| l.duv[2]), col(&|l| l.duv[3])],
        tangent: t,
        bitangent_sign: sign,
        frame: ShadingFrame::from_normal_tangent(n, t, sign),
        color: V3::splat(R::ONE),
        alpha: R::ONE,
    };
    (frag, surface)
}

#[test]
fn normal_map_frame_matches_the_formula_and_lanes_match_the_scalar_twin() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    for filter in [Filter::Nearest, Filter::Trilinear, Filter::Anisotropic(8)] {
        let scale = rng.random_range(0.3..1.5f32);
        let map = random_map(&mut rng, 8, 8, filter);
        let maps = ParamMaps {
            normal: Some(NormalMap {
                map: map.clone(),
                scale,
            }),
            ..Default::default()
        };
        for _ in 0..100 {
            let lanes: Vec<LaneIn> = (0..8).map(|_| random_lane(&mut rng)).collect();
            let (frag, surface) = inputs::<f32x8>(&lanes);
            let input = ShadeInput {
                frag: &frag,
                surface: Some(&surface),
                lanes: 0xFF,
                shadow_factors: None,
            };
            let got = maps.frame(&input);
            for (l, x) in lanes.iter().enumerate() {
                let (f1, s1) = inputs::<f32>(&lanes[l..l + 1]);
                let one = maps.frame(&ShadeInput {
                    frag: &f1,
                    surface: Some(&s1),
                    lanes: 1,
                    shadow_factors: None,
                });
                // The formula: texel t → m = (2t − 1)(s, s, 1), n' ∝
                // T m.x + B m.y + N m.z with B = sign · N × T.
                let tx: [f64; 3] = map.texture.sample(
                    &map.sampler,
                    [x.uv[0] as f32 as f64, x.uv[1] as f32 as f64],
                    [x.duv[0] as f32 as f64, x.duv[1] as f32 as f64],
                    [x.duv[2] as f32 as f64, x.duv[3] as f32 as f64],
                );
                let s = scale as f64;
                let m = [
                    (2.0 * tx[0] - 1.0) * s,
                    (2.0 * tx[1] - 1.0) * s,
                    2.0 * tx[2] - 1.0,
                ];
                let b = cross(x.n, x.t).map(|c| c * x.sign);
                let want = normalize(core::array::from_fn(|k| {
                    x.t[k] * m[0] + b[k] * m[1] + x.n[k] * m[2]
                }));
                if dot(want, x.wo) < 0.05 {
                    continue; // the bend toward the eye applies: not this formula
                }
                let g = [got.n.x.lane(l), got.n.y.lane(l), got.n.z.lane(l)];
                let sc = [one.n.x as f64, one.n.y as f64, one.n.z as f64];
                for k in 0..3 {
                    assert!(
                        (g[k] - want[k]).abs() < 2e-4,
                        "{filter:?} lane {l}: {g:?} vs {want:?}"
                    );
                    assert!(
                        (g[k] - sc[k]).abs() < 2e-5,
                        "{filter:?} lane {l}: {g:?} vs scalar {sc:?}"
                    );
                }
                // An orthonormal frame of the same handedness as (T, B, N).
                let (t2, b2) = (
                    [got.t.x.lane(l), got.t.y.lane(l), got.t.z.lane(l)],
                    [got.b.x.lane(l), got.b.y.lane(l), got.b.z.lane(l)],
                );
                let worst = [dot(t2, g), dot(b2, g), dot(t2, b2)].map(f64::abs);
                assert!(worst.iter().all(|d| *d < 1e-4), "not orthogonal: {worst:?}");
                let hand = dot(cross(t2, b2), g);
                assert!(
                    (hand - x.sign).abs() < 1e-4,
                    "handedness {hand} vs {}",
                    x.sign
                );
            }
        }
    }
}

#[test]
fn occlusion_and_metallic_roughness_lanes_match_the_scalar_twin() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(9);
    let mr = random_map(&mut rng, 5, 7, Filter::Anisotropic(16));
    let occ = random_map(&mut rng, 6, 3, Filter::Bilinear);
    let strength = 0.6f32;
    let maps = ParamMaps {
        metallic_roughness: Some(mr.clone()),
        occlusion: Some(OcclusionMap {
            map: occ.clone(),
            strength,
        }),
        ..Default::default()
    };
    use specula_core::models::{MetallicRoughness, MetallicRoughnessLaneParams};
    use specula_core::Brdf;
    let model = MetallicRoughness {
        base_color: [0.5, 0.5, 0.5],
        roughness: 0.7,
        metallic: 0.9,
    };
    for _ in 0..100 {
        let lanes: Vec<LaneIn> = (0..8).map(|_| random_lane(&mut rng)).collect();
        let (frag, surface) = inputs::<f32x8>(&lanes);
        let input = ShadeInput {
            frag: &frag,
            surface: Some(&surface),
            lanes: 0xFF,
            shadow_factors: None,
        };
        let mut p: MetallicRoughnessLaneParams<f32x8> = model.params();
        maps.fill(&input, &mut p);
        let k = maps.occlusion(&input).unwrap();
        for (l, x) in lanes.iter().enumerate() {
            let (f1, s1) = inputs::<f32>(&lanes[l..l + 1]);
            let one = ShadeInput {
                frag: &f1,
                surface: Some(&s1),
                lanes: 1,
                shadow_factors: None,
            };
            let mut q: MetallicRoughnessLaneParams<f32> = model.params();
            maps.fill(&one, &mut q);
            let k1 = maps.occlusion(&one).unwrap();
            let close = |a: f64, b: f64| (a - b).abs() < 2e-5 * b.abs().max(1e-3);
            assert!(close(p.alpha.lane(l), q.alpha as f64));
            assert!(close(p.metallic.lane(l), q.metallic as f64));
            assert!(close(k.lane(l), k1 as f64));
            // The formulas: metallic × B, α = (roughness × G)², and
            // 1 + s (R − 1), from f64 lookups.
            let uv = [x.uv[0] as f32 as f64, x.uv[1] as f32 as f64];
            let (dx, dy) = (
                [x.duv[0] as f32 as f64, x.duv[1] as f32 as f64],
                [x.duv[2] as f32 as f64, x.duv[3] as f32 as f64],
            );
            let t: [f64; 3] = mr.texture.sample(&mr.sampler, uv, dx, dy);
            let o: [f64; 3] = occ.texture.sample(&occ.sampler, uv, dx, dy);
            let alpha = (0.7 * t[1]).powi(2).max(1e-3);
            let near = |a: f64, b: f64| (a - b).abs() < 1e-4 * b.abs().max(1e-2);
            assert!(
                near(p.alpha.lane(l), alpha),
                "{} vs {alpha}",
                p.alpha.lane(l)
            );
            assert!(near(p.metallic.lane(l), 0.9 * t[2]));
            assert!(near(k.lane(l), 1.0 + strength as f64 * (o[0] - 1.0)));
        }
    }
}

#[test]
fn a_lambert_material_refuses_a_metallic_roughness_map() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(1);
    let maps = ParamMaps {
        metallic_roughness: Some(random_map(&mut rng, 2, 2, Filter::Nearest)),
        ..Default::default()
    };
    let err = Lit::with_maps(
        Model::Lambert(Lambert {
            base_color: [1.0; 3],
        }),
        maps,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("metallic_roughness_texture"), "{err}");
    // Occlusion, normal and emissive maps fit every model.
    let maps = ParamMaps {
        occlusion: Some(OcclusionMap {
            map: random_map(&mut rng, 2, 2, Filter::Nearest),
            strength: 1.0,
        }),
        emissive: Some(random_map(&mut rng, 2, 2, Filter::Nearest)),
        ..Default::default()
    };
    let lit = Lit::with_maps(
        Model::Lambert(Lambert {
            base_color: [1.0; 3],
        }),
        maps,
    )
    .unwrap()
    .with_emission([0.5, 1.0, 2.0]);
    // No lights, no environment: the emission alone, factor × texel.
    let lanes: Vec<LaneIn> = (0..8).map(|_| random_lane(&mut rng)).collect();
    let (frag, surface) = inputs::<f32x8>(&lanes);
    let input = ShadeInput {
        frag: &frag,
        surface: Some(&surface),
        lanes: 0xFF,
        shadow_factors: None,
    };
    let env = ShadeEnv {
        lights: &[] as &[Light],
        environment: None,
        env_map: None,
        shadows: None,
        pair_packets: false,
    };
    let got: Rgb<f32x8> = lit.shade(&input, &env);
    let em = lit.maps().emissive.as_ref().unwrap();
    for (l, x) in lanes.iter().enumerate() {
        let uv = [x.uv[0] as f32 as f64, x.uv[1] as f32 as f64];
        let t: [f64; 3] = em.texture.sample(&em.sampler, uv, [0.0; 2], [0.0; 2]);
        let want = [0.5 * t[0], 1.0 * t[1], 2.0 * t[2]];
        let g = [got.x.lane(l), got.y.lane(l), got.z.lane(l)];
        for k in 0..3 {
            assert!((g[k] - want[k]).abs() < 1e-5, "lane {l}: {g:?} vs {want:?}");
        }
    }
}
