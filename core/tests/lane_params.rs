//! Parameters per lane: a packet whose 8 lanes carry 8 different
//! materials must give, lane by lane, what each material gives on its own.
//! f is checked against the glTF 2.0 oracle written out in f64 (as in
//! metallic_roughness.rs); the environment albedo and the polygon
//! integral, whose broadcast forms the other tests check against
//! quadrature, against each lane's material evaluated alone in f64.

use rand::{Rng, SeedableRng};
use specula_core::light::{PolygonLocal, MAX_POLYGON_VERTICES};
use specula_core::models::{Fresnel, GtrLambda, Ndf, Smith};
use specula_core::models::{
    Lambert, LambertLaneParams, MetallicRoughness, MetallicRoughnessLaneParams, Microfacet,
    MicrofacetLaneParams, MicrofacetParams,
};
use specula_core::{f32x8, Brdf, Real, Rgb, V3};
use std::f64::consts::PI;

/// glTF 2.0 Appendix B's suggested implementation in f64, unit local
/// directions above the horizon.
fn oracle(base: [f64; 3], roughness: f64, metal: f64, wi: V3<f64>, wo: V3<f64>) -> [f64; 3] {
    let alpha = (roughness * roughness).max(1e-3);
    let h = (wi + wo).normalize();
    let (nh, vh) = (h.z, wo.dot(h));
    let a2 = alpha * alpha;
    let d = a2 / (PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
    let lambda = |c: f64| (-1.0 + (1.0 + a2 * (1.0 - c * c) / (c * c)).sqrt()) / 2.0;
    let g = 1.0 / (1.0 + lambda(wi.z) + lambda(wo.z));
    base.map(|b| {
        let f0 = 0.04 * (1.0 - metal) + b * metal;
        let f = f0 + (1.0 - f0) * (1.0 - vh).powi(5);
        f * d * g / (4.0 * wi.z * wo.z) + (1.0 - f) * (1.0 - metal) * b / PI
    })
}

fn lanes(f: impl Fn(usize) -> f32) -> f32x8 {
    let a: [f32; 8] = std::array::from_fn(f);
    f32x8::load(&a)
}

fn v3x8(v: &[V3<f64>; 8]) -> V3<f32x8> {
    V3::new(
        lanes(|l| v[l].x as f32),
        lanes(|l| v[l].y as f32),
        lanes(|l| v[l].z as f32),
    )
}

/// The f32 rounding of a direction, in f64.
fn rounded(v: V3<f64>) -> V3<f64> {
    V3::new(v.x as f32 as f64, v.y as f32 as f64, v.z as f32 as f64)
}

fn upper_dir(rng: &mut impl Rng) -> V3<f64> {
    loop {
        let v = V3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(0.05..1.0),
        );
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v * (1.0 / l);
        }
    }
}

fn rel(g: f64, w: f64) -> f64 {
    (g - w).abs() / w.abs().max(1e-4)
}

fn quad() -> PolygonLocal<f64> {
    let mut p = PolygonLocal {
        vertices: [V3::new(0.0, 0.0, 0.0); MAX_POLYGON_VERTICES],
        len: 4,
        two_sided: true,
    };
    let q = [
        V3::new(-0.6, -0.5, 1.2),
        V3::new(0.7, -0.4, 1.1),
        V3::new(0.5, 0.6, 1.4),
        V3::new(-0.5, 0.5, 1.3),
    ];
    p.vertices[..4].copy_from_slice(&q);
    p
}

fn quad_x8() -> PolygonLocal<f32x8> {
    let q = quad();
    let mut p = PolygonLocal {
        vertices: [V3::zero(); MAX_POLYGON_VERTICES],
        len: q.len,
        two_sided: q.two_sided,
    };
    for (d, s) in p.vertices.iter_mut().zip(q.vertices()) {
        *d = V3::from_f32([s.x as f32, s.y as f32, s.z as f32]);
    }
    p
}

#[test]
fn metallic_roughness_lanes_are_eight_materials() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let (mut worst_f, mut worst_albedo, mut worst_poly) = (0.0f64, 0.0f64, 0.0f64);
    // Any material: the lanes' parameters replace all of its constants.
    let shell = MetallicRoughness {
        base_color: [0.5; 3],
        roughness: 0.5,
        metallic: 0.5,
    };
    for _ in 0..500 {
        let mats: [MetallicRoughness; 8] = std::array::from_fn(|_| MetallicRoughness {
            base_color: [0, 1, 2].map(|_| rng.random_range(0.0..1.0)),
            roughness: rng.random_range(0.05..1.0),
            metallic: rng.random_range(0.0..1.0),
        });
        let params = MetallicRoughnessLaneParams::new(
            Rgb::new(
                lanes(|l| mats[l].base_color[0]),
                lanes(|l| mats[l].base_color[1]),
                lanes(|l| mats[l].base_color[2]),
            ),
            lanes(|l| mats[l].roughness),
            lanes(|l| mats[l].metallic),
        );
        let wi: [V3<f64>; 8] = std::array::from_fn(|_| upper_dir(&mut rng));
        let wo: [V3<f64>; 8] = std::array::from_fn(|_| upper_dir(&mut rng));
        let p = shell.prepare_with(&shell.pixel(&params), v3x8(&wo));
        let f = shell.f_local(&p, v3x8(&wi));
        let albedo = shell.albedo_local(&p);
        let poly = shell.polygon_local_with(&p, &shell.prepare_polygons(&p), &quad_x8());
        for l in 0..8 {
            let m = &mats[l];
            let (i, o) = (rounded(wi[l]), rounded(wo[l]).normalize());
            let want = oracle(
                m.base_color.map(|c| c as f64),
                m.roughness as f64,
                m.metallic as f64,
                i.normalize(),
                o,
            );
            let alone = m.prepare::<f64>(o);
            let want_albedo = m.albedo_local(&alone);
            let want_poly = m.polygon_local_with(&alone, &m.prepare_polygons(&alone), &quad());
            assert!(
                want_poly.x + want_poly.y + want_poly.z > 1e-4,
                "the quad lights lane {l}"
            );
            for c in 0..3 {
                let pick = |v: Rgb<f32x8>| [v.x, v.y, v.z][c].lane(l);
                let pick64 = |v: Rgb<f64>| [v.x, v.y, v.z][c];
                worst_f = worst_f.max(rel(pick(f), want[c]));
                worst_albedo = worst_albedo.max(rel(pick(albedo), pick64(want_albedo)));
                worst_poly = worst_poly.max(rel(pick(poly), pick64(want_poly)));
            }
        }
    }
    eprintln!("worst relative: f {worst_f:e}, albedo {worst_albedo:e}, polygon {worst_poly:e}");
    assert!(worst_f < 2e-4, "f vs the oracle: {worst_f:e}");
    assert!(worst_albedo < 1e-4, "albedo: {worst_albedo:e}");
    assert!(worst_poly < 1e-3, "polygon: {worst_poly:e}");
}

#[test]
fn lambert_and_microfacet_diffuse_lanes() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(12);
    let lambert = Lambert {
        base_color: [0.3, 0.6, 0.9],
    };
    let micro = Microfacet::new(
        MicrofacetParams {
            ndf: Ndf::Ggx,
            alpha: 0.3,
            smith: Smith::HeightCorrelated,
            fresnel: Fresnel::Dielectric { ior: 1.5 },
            diffuse: [0.2, 0.4, 0.1],
            gtr_lambda: GtrLambda::Ggx,
        },
        None,
    );
    for _ in 0..200 {
        let rho: [[f32; 3]; 8] =
            std::array::from_fn(|_| [0, 1, 2].map(|_| rng.random_range(0.0..1.0)));
        let rho_x8 = Rgb::new(
            lanes(|l| rho[l][0]),
            lanes(|l| rho[l][1]),
            lanes(|l| rho[l][2]),
        );
        let wi: [V3<f64>; 8] = std::array::from_fn(|_| upper_dir(&mut rng));
        let wo: [V3<f64>; 8] = std::array::from_fn(|_| upper_dir(&mut rng));

        let p = lambert.prepare_with(&LambertLaneParams { base_color: rho_x8 }, v3x8(&wo));
        let f = lambert.f_local(&p, v3x8(&wi));
        let albedo = lambert.albedo_local(&p);
        let pm = micro.prepare_with(&MicrofacetLaneParams { diffuse: rho_x8 }, v3x8(&wo));
        let fm = micro.f_local(&pm, v3x8(&wi));
        let em = micro.albedo_local(&pm);
        for l in 0..8 {
            let o = rounded(wo[l]).normalize();
            let i = rounded(wi[l]).normalize();
            let alone = Microfacet::new(
                MicrofacetParams {
                    diffuse: rho[l],
                    ..micro.params.clone()
                },
                None,
            );
            let want_f = alone.f_local(&alone.prepare::<f64>(o), i);
            let want_e = alone.albedo_local(&alone.prepare::<f64>(o));
            for c in 0..3 {
                let pick = |v: Rgb<f32x8>| [v.x, v.y, v.z][c].lane(l);
                let pick64 = |v: Rgb<f64>| [v.x, v.y, v.z][c];
                // Lambert: ρ/π and ρ, exactly as the lane's own ρ.
                let r = rho[l][c] as f64;
                assert!(rel(pick(f), r / PI) < 1e-6);
                assert!(rel(pick(albedo), r) < 1e-6);
                assert!(rel(pick(fm), pick64(want_f)) < 1e-4, "microfacet f");
                // The table rounds to f32 at the material's own ρd.
                assert!(rel(pick(em), pick64(want_e)) < 1e-5, "microfacet albedo");
            }
        }
    }
}
