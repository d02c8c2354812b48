//! BRDF evaluations per second: the full microfacet BRDF (GGX,
//! height-correlated Smith, Schlick F), without and with Kulla–Conty
//! compensation, 8 lanes at a time in f32x8 vs one at a time in f32, over
//! the same 4096 random direction pairs. Run: `cargo bench -p specula-bench --bench brdf`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use specula_core::kulla_conty::KcColor;
use specula_core::models::{Fresnel, Microfacet, MicrofacetParams, Ndf, Smith};
use specula_core::{f32x8, Brdf, Real, V3};
use std::hint::black_box;

const N: usize = 4096;

/// Deterministic pseudo-random unit directions in the upper hemisphere (SoA).
fn directions(seed: u32) -> [Vec<f32>; 3] {
    let mut state = seed.wrapping_mul(2654435761).max(1);
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state as f32 / u32::MAX as f32
    };
    let (mut x, mut y, mut z) = (Vec::new(), Vec::new(), Vec::new());
    while x.len() < N {
        let v = [2.0 * next() - 1.0, 2.0 * next() - 1.0, next()];
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if l > 0.1 && l <= 1.0 && v[2] > 0.02 {
            x.push(v[0] / l);
            y.push(v[1] / l);
            z.push(v[2] / l);
        }
    }
    [x, y, z]
}

fn benches(c: &mut Criterion) {
    let (wi, wo) = (directions(1), directions(2));
    let params = MicrofacetParams {
        ndf: Ndf::Ggx,
        alpha: 0.4,
        smith: Smith::HeightCorrelated,
        fresnel: Fresnel::Schlick {
            f0: [0.9, 0.6, 0.3],
        },
        diffuse: [0.0; 3],
        gtr_lambda: Default::default(),
    };
    let mut g = c.benchmark_group("brdf");
    g.throughput(Throughput::Elements(N as u64));
    for (name, kc) in [
        ("microfacet", None),
        ("microfacet_kc", Some(KcColor::KullaConty)),
    ] {
        let m = Microfacet::new_without_table(params.clone(), kc);
        g.bench_function(BenchmarkId::new(name, "simd"), |b| {
            let n8 = V3::new(f32x8::ZERO, f32x8::ZERO, f32x8::ONE);
            b.iter(|| {
                let mut acc = f32x8::ZERO;
                for k in (0..N).step_by(8) {
                    let i = V3::new(
                        f32x8::load(&wi[0][k..]),
                        f32x8::load(&wi[1][k..]),
                        f32x8::load(&wi[2][k..]),
                    );
                    let o = V3::new(
                        f32x8::load(&wo[0][k..]),
                        f32x8::load(&wo[1][k..]),
                        f32x8::load(&wo[2][k..]),
                    );
                    acc += m.f(n8, i, o).x;
                }
                black_box(acc)
            })
        });
        g.bench_function(BenchmarkId::new(name, "scalar"), |b| {
            let n1 = V3::new(0.0f32, 0.0, 1.0);
            b.iter(|| {
                let mut acc = 0.0f32;
                for k in 0..N {
                    let i = V3::new(wi[0][k], wi[1][k], wi[2][k]);
                    let o = V3::new(wo[0][k], wo[1][k], wo[2][k]);
                    acc += m.f(n1, i, o).x;
                }
                black_box(acc)
            })
        });
    }
    g.finish();
}

criterion_group!(brdf, benches);
criterion_main!(brdf);
