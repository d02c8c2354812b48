//! The Monte Carlo reference of environment lighting: per pixel, the
//! integral of f(wi, wo) cos θi L(wi) over the sphere with multiple
//! importance sampling \[Veach95\] as one mixture density: half the samples
//! from the map's luminance (texel probability ∝ luminance · sin θ, uniform
//! within the texel), half from the BRDF (GGX visible normals \[Heitz18\]
//! at the model's glossy α for the share of its glossy albedo, at the
//! coat's α about the coat's normal for the share of a clearcoat's,
//! cosine otherwise). Each sample is weighted by f cos θi L / p_mix(wi), which is
//! the balance heuristic over the strategies. The map is read as a
//! piecewise-constant function (each texel's radiance over its solid
//! angle). Random numbers come from a counter-based hash of the pixel's
//! position and the sample index, so an image does not depend on the
//! thread count.

use crate::envmap::EnvMap;
use specula_core::{Brdf, EnvLobes, ShadingFrame, V3};
use std::f64::consts::{PI, TAU};

/// splitmix64's finalizer: a well-mixed 64-bit hash.
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A pixel's seed from its world position.
pub(crate) fn seed_of(p: V3<f64>) -> u64 {
    let bits = |x: f64| (x as f32).to_bits() as u64;
    mix64(bits(p.x) ^ mix64(bits(p.y) ^ mix64(bits(p.z))))
}

/// Uniform numbers in [0, 1) from a counter.
struct Counter {
    seed: u64,
    n: u64,
}

impl Counter {
    fn next(&mut self) -> f64 {
        self.n += 1;
        (mix64(
            self.seed
                .wrapping_add(self.n.wrapping_mul(0x9e37_79b9_7f4a_7c15)),
        ) >> 11) as f64
            * (1.0 / (1u64 << 53) as f64)
    }
}

/// Λ of GGX at local direction `w` \[Heitz14\]: (−1 + √(1 + α² tan²θ)) / 2.
fn lambda_ggx(alpha: f64, w: V3<f64>) -> f64 {
    let c2 = w.z * w.z;
    let t2 = (1.0 - c2).max(0.0) / c2.max(1e-300);
    0.5 * (-1.0 + (1.0 + alpha * alpha * t2).sqrt())
}

/// D of GGX at local half vector `h`.
fn d_ggx(alpha: f64, h: V3<f64>) -> f64 {
    let a2 = alpha * alpha;
    let t = h.z * h.z * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

/// A GGX visible normal for view `wo` (local, above) \[Heitz18\], from
/// two uniform numbers in [0, 1).
pub fn sample_vndf(wo: V3<f64>, alpha: f64, u1: f64, u2: f64) -> V3<f64> {
    let vh = V3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 1e-14 {
        V3::new(-vh.y, vh.x, 0.0) * (1.0 / lensq.sqrt())
    } else {
        V3::new(1.0, 0.0, 0.0)
    };
    let t2 = vh.cross(t1);
    let r = u1.sqrt();
    let phi = TAU * u2;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    V3::new(alpha * nh.x, alpha * nh.y, nh.z.max(1e-6)).normalize()
}

/// Density per solid angle of wi from [`sample_vndf`] reflected about h:
/// G1(wo) D(h) / (4 μo).
fn pdf_vndf(wo: V3<f64>, wi: V3<f64>, alpha: f64) -> f64 {
    let h = wo + wi;
    let l2 = h.length_squared();
    if wo.z <= 0.0 || l2 < 1e-20 {
        return 0.0;
    }
    let h = h * (1.0 / l2.sqrt());
    if h.z <= 0.0 {
        return 0.0;
    }
    let g1 = 1.0 / (1.0 + lambda_ggx(alpha, wo));
    g1 * d_ggx(alpha, h) / (4.0 * wo.z)
}

/// One pixel's environment radiance toward `wo` (local, unit), by
/// `samples` mixture samples (module docs). `frame` is the pixel's local
/// frame in world space; `lobes` the model's albedo split, which sets the
/// BRDF strategies' shares and the glossy α.
#[allow(clippy::too_many_arguments)]
pub fn reference_radiance<B: Brdf>(
    brdf: &B,
    prepared: &B::Prepared<f64>,
    lobes: &EnvLobes<f64>,
    wo: V3<f64>,
    frame: &ShadingFrame<f64>,
    map: &EnvMap,
    samples: u32,
    seed: u64,
) -> [f64; 3] {
    let lum = |c: specula_core::Rgb<f64>| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    let above = wo.z > 0.0;
    // The BRDF strategies' shares by the lobes' albedos: cosine for the
    // diffuse part, GGX visible normals at the glossy α about the normal,
    // and at the coat's α about the coat's normal (in its own frame). A
    // strategy that cannot sample (the view below its horizon) gives its
    // share to the cosine.
    let coat_frame = ShadingFrame::from_normal(lobes.coat_normal);
    let wo_coat = coat_frame.to_local(wo);
    let (ld, ls) = (lum(lobes.diffuse).max(0.0), lum(lobes.specular).max(0.0));
    let lc = lobes.coat.max(0.0);
    let ls = if above { ls } else { 0.0 };
    let lc = if above && wo_coat.z > 0.0 { lc } else { 0.0 };
    let sum_l = ld + ls + lc;
    let (glossy, coat) = if sum_l > 0.0 {
        (ls / sum_l, lc / sum_l)
    } else {
        (0.0, 0.0)
    };
    let alpha = (lobes.roughness * lobes.roughness).max(1e-3);
    let alpha_c = (lobes.coat_roughness * lobes.coat_roughness).max(1e-3);
    let env_share = if map.sampler.is_empty() { 0.0 } else { 0.5 };
    let to_world = |w: V3<f64>| frame.t * w.x + frame.b * w.y + frame.n * w.z;
    let to_local = |w: V3<f64>| V3::new(w.dot(frame.t), w.dot(frame.b), w.dot(frame.n));
    let from_coat = |w: V3<f64>| coat_frame.t * w.x + coat_frame.b * w.y + coat_frame.n * w.z;
    let mut rng = Counter { seed, n: 0 };
    let mut sum = [0.0f64; 3];
    for _ in 0..samples {
        let pick = rng.next();
        let u = [rng.next(), rng.next(), rng.next(), rng.next()];
        let (wi, wi_map) = if pick < env_share {
            let m = map.sampler.sample(u);
            let w = map.to_world(m);
            (to_local(V3::new(w[0], w[1], w[2])), m)
        } else {
            let b = (pick - env_share) / (1.0 - env_share);
            let local = if b < glossy {
                let h = sample_vndf(wo, alpha, u[0], u[1]);
                h * (2.0 * wo.dot(h)) - wo
            } else if b < glossy + coat {
                let h = sample_vndf(wo_coat, alpha_c, u[0], u[1]);
                from_coat(h * (2.0 * wo_coat.dot(h)) - wo_coat)
            } else {
                cosine_hemisphere(u[0], u[1])
            };
            let w = to_world(local);
            let m = map.to_map(w);
            (local, [m.x, m.y, m.z])
        };
        let wi = wi.normalize_or(V3::new(0.0, 0.0, 1.0));
        if wi.z <= 0.0 {
            continue;
        }
        let mut p = (1.0 - env_share) * (1.0 - glossy - coat) * wi.z / PI;
        if glossy > 0.0 {
            p += (1.0 - env_share) * glossy * pdf_vndf(wo, wi, alpha);
        }
        if coat > 0.0 {
            let wi_coat = coat_frame.to_local(wi);
            p += (1.0 - env_share) * coat * pdf_vndf(wo_coat, wi_coat, alpha_c);
        }
        if env_share > 0.0 {
            p += env_share * map.sampler.pdf(wi_map);
        }
        if !(p > 0.0 && p.is_finite()) {
            continue;
        }
        let (u, v) = crate::equirect::dir_to_uv(wi_map.map(|x| x as f32));
        let l = map.source.nearest(u, v);
        let f = brdf.f_cos_local(prepared, wi);
        let fc = [f.x, f.y, f.z];
        for c in 0..3 {
            sum[c] += fc[c] * l[c] as f64 / p;
        }
    }
    sum.map(|s| {
        let x = s / samples.max(1) as f64;
        if x.is_finite() {
            x.max(0.0)
        } else {
            0.0
        }
    })
}

/// A cosine-distributed local direction (Malley's method).
fn cosine_hemisphere(u1: f64, u2: f64) -> V3<f64> {
    let r = u1.sqrt();
    let phi = TAU * u2;
    V3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The VNDF sampler's directions have the density `pdf_vndf` claims:
    /// ∫ over the hemisphere of the histogram equals the integral of the
    /// pdf over the same bins (a coarse χ²-like check on θ).
    #[test]
    fn vndf_pdf_integrates_to_visible_fraction() {
        let wo = V3::new(0.6, 0.0, 0.8);
        for alpha in [0.1, 0.5, 1.0] {
            // ∫ pdf dω over the upper hemisphere by quadrature: ≤ 1, the
            // share of reflected directions that stay above the horizon.
            let n = 400;
            let mut total = 0.0;
            for a in 0..n {
                let ct = (a as f64 + 0.5) / n as f64;
                for b in 0..(2 * n) {
                    let phi = (b as f64 + 0.5) / (2 * n) as f64 * TAU;
                    let st = (1.0 - ct * ct).sqrt();
                    let wi = V3::new(st * phi.cos(), st * phi.sin(), ct);
                    total += pdf_vndf(wo, wi, alpha) * (1.0 / n as f64) * (TAU / (2 * n) as f64);
                }
            }
            // The same share by sampling.
            let mut rng = Counter { seed: 7, n: 0 };
            let m = 20000;
            let above = (0..m)
                .filter(|_| {
                    let h = sample_vndf(wo, alpha, rng.next(), rng.next());
                    (h * (2.0 * wo.dot(h)) - wo).z > 0.0
                })
                .count() as f64
                / m as f64;
            assert!(
                (total - above).abs() < 0.02,
                "α {alpha}: ∫pdf {total}, sampled {above}"
            );
        }
    }
}
