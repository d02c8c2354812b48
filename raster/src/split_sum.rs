//! The environment map's light by the split sum, for the f32x8 light loop
//! of `lit.rs` and the packet pairs of `packet_pairs.rs` alike.

use crate::envmap::{disk_cos_factor, EnvMap};
use specula_core::{Brdf, Mask, Real, Rgb, ShadingFrame, V3};

/// The environment map's light by the split sum: the model's diffuse
/// albedo times E(n)/π, its glossy albedo times the prefiltered radiance
/// around the mirror direction at its roughness, a clearcoat's albedo
/// times the prefiltered radiance around the mirror direction about the
/// coat's normal at the coat's roughness (all without the sun; each
/// read where and as wide as [`prefilter_reading`] says),
/// plus the sun taken out of the map as a distant light through the
/// model's BRDF: f(wi, wo) · E_sun toward the sun's centroid times the
/// disk's clamped cosine (`disk_cos_factor`), at most L_sun · ρ(wo),
/// times `sun_visibility` of that part (its shadow factor).
/// `frame` is the shading frame (world space, unit normal) and `wo` the
/// unit view direction in world space. Out of line: inlined, its code
/// changed how the shading function that every frame runs was compiled
/// and slowed frames without a map (docs/PERFORMANCE.md).
#[inline(never)]
pub fn env_split_sum<B: Brdf, R: Real>(
    brdf: &B,
    prepared: &B::Prepared<R>,
    frame: &ShadingFrame<R>,
    wo: V3<R>,
    map: &EnvMap,
    sun_visibility: impl FnOnce(&Rgb<R>) -> R,
) -> Rgb<R> {
    env_split_sum_inline(brdf, prepared, frame, wo, map, sun_visibility)
}

/// [`env_split_sum`] inline in its caller: for the packet pairs'
/// sixteen-lane code, whose operations are calls in a function compiled
/// without AVX-512.
#[inline(always)]
pub(crate) fn env_split_sum_inline<B: Brdf, R: Real>(
    brdf: &B,
    prepared: &B::Prepared<R>,
    frame: &ShadingFrame<R>,
    wo: V3<R>,
    map: &EnvMap,
    sun_visibility: impl FnOnce(&Rgb<R>) -> R,
) -> Rgb<R> {
    let n = frame.n;
    let lobes = brdf.env_lobes(prepared);
    let e = map.sky_irradiance_over_pi(n);
    let mut out = lobes.diffuse.mul_elem(e);
    let s = lobes.specular;
    if (s.x.gt(R::ZERO) | s.y.gt(R::ZERO) | s.z.gt(R::ZERO)).any() {
        let (r, roughness) = prefilter_reading(n, wo, lobes.roughness);
        out = lobes
            .specular
            .mul_elem_add(map.prefiltered(r, roughness), out);
    }
    if lobes.coat.gt(R::ZERO).any() {
        // The coat's own lobe, about its normal (in world space).
        let c = lobes.coat_normal;
        let nc = frame.t * c.x + frame.b * c.y + frame.n * c.z;
        let (r, roughness) = prefilter_reading(nc, wo, lobes.coat_roughness);
        out += map.prefiltered(r, roughness) * lobes.coat;
    }
    if let Some(sun) = map.sun_world() {
        let wi = frame.to_local(V3::from_f32(sun.to_light));
        // The disk's clamped cosine (it may straddle the horizon), and f
        // toward its centre lifted just above the horizon.
        let k = disk_cos_factor(wi.z, sun.sin2_radius);
        let wi_above = V3::new(wi.x, wi.y, wi.z.max(R::splat(1e-4))).normalize();
        let part = brdf
            .f_local(prepared, wi_above)
            .mul_elem(V3::from_f32(sun.irradiance) * k);
        // ∫ over the disk of f cos θi L ≤ L ρ(wo): a lobe narrower than
        // the disk, whose value at the centre times Ω overshoots it, is
        // cut to the disk's radiance times the albedo (a mirror's exact
        // value when it reflects the disk).
        let cap = lobes.total().mul_elem(V3::from_f32(sun.radiance));
        let part = Rgb::new(part.x.min(cap.x), part.y.min(cap.y), part.z.min(cap.z));
        // part × 1 is part: unshadowed, the same bits as without a factor.
        out += part * sun_visibility(&part);
    }
    out
}

/// Where and how wide the prefiltered chain is read for a GGX lobe at
/// perceptual `roughness` about unit normal `n` seen from unit `wo`
/// (world space): a direction (not unit length: the octahedral lookup
/// divides by its own norm) and the roughness to read there.
///
/// The chain is made with n = v = r, so its kernel is the lobe seen
/// along the normal, centred on the mirror direction r. Seen from an
/// angle the true lobe leans toward the normal (the masking and the
/// horizon cut the side away from it) and is narrower across the plane
/// of n and v (a half vector's tilt across it turns l by cos θv as much),
/// more so the smoother it is. So the reading is
/// - along r pulled toward n by t = (0.1 + (1 − μo) + α) · t_dom, where
///   t_dom = 1 − s (√s + α), s = 1 − α, is the pull of the lobe's dominant
///   direction \[Lagarde14, listing 22\] (lerp(n, r, 1 − t_dom)), at most
///   all the way to n;
/// - at α × (1 − 0.8 (1 − μo) s): the roughness times the square root of
///   that factor.
///
/// The three constants were fitted, per view angle, to the split sum's
/// error against the Monte Carlo reference under the two fixture maps,
/// with the chain's kernel integrated exactly; docs/accuracy.md, "Split
/// sum against reference", has how they were fitted and the errors.
#[inline(always)]
pub fn prefilter_reading<R: Real>(n: V3<R>, wo: V3<R>, roughness: R) -> (V3<R>, R) {
    let mu = n.dot(wo);
    let r = n * (R::splat(2.0) * mu) - wo;
    let off_normal = R::ONE - mu.clamp(R::ZERO, R::ONE);
    let alpha = roughness * roughness;
    let s = (R::ONE - alpha).clamp(R::ZERO, R::ONE);
    let t_dom = R::ONE - s * (s.sqrt() + alpha);
    let t = ((R::splat(0.1) + off_normal + alpha) * t_dom).min(R::ONE);
    let width = (R::splat(-0.8) * off_normal).mul_add(s, R::ONE);
    // Not below level 1 by narrowing: under it a read is a blend of the
    // mirror image and level 1, not a narrower lobe.
    let floor = roughness.min(R::splat(0.2));
    ((n - r).mul_add(t, r), (roughness * width.sqrt()).max(floor))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reading's ends, from its definition in f64: seen along the
    /// normal the lobe is the chain's own (read along n, at its own
    /// roughness); at α = 1 it is read along n; elsewhere it lies in the
    /// plane of n and wo between the mirror direction and n, no wider
    /// than the lobe and not narrowed below level 1.
    #[test]
    fn the_reading_leans_toward_n_and_narrows_with_the_view() {
        let n = V3::new(0.0f64, 0.0, 1.0);
        for i in 0..=20 {
            let roughness = i as f64 / 20.0;
            let (d, w) = prefilter_reading(n, n, roughness);
            assert!(d.x.abs() < 1e-12 && d.y.abs() < 1e-12 && d.z > 0.0);
            assert!((w - roughness).abs() < 1e-12, "roughness {roughness}: {w}");
            for j in 1..=17 {
                let theta = (j as f64 * 5.0).to_radians();
                let wo = V3::new(theta.sin(), 0.0, theta.cos());
                let (d, w) = prefilter_reading(n, wo, roughness);
                let r = V3::new(-theta.sin(), 0.0, theta.cos());
                let d = d * (1.0 / d.length());
                // In the plane of n and wo, between r and n.
                assert!(d.y.abs() < 1e-12);
                assert!(
                    d.x <= 1e-12 && d.x >= r.x - 1e-12,
                    "{roughness} {theta}: {d:?}"
                );
                if roughness == 1.0 {
                    assert!(d.x.abs() < 1e-12, "α = 1 reads along n: {d:?}");
                }
                assert!(w <= roughness + 1e-12 && w >= roughness.min(0.2) - 1e-12);
                // Narrower the further from the normal (down to level 1),
                // for lobes above level 1 that are not the broadest.
                if (0.3..1.0).contains(&roughness) {
                    let (_, w_prev) = prefilter_reading(
                        n,
                        V3::new((theta - 0.05).sin(), 0.0, (theta - 0.05).cos()),
                        roughness,
                    );
                    let at_floor = (w - 0.2).abs() < 1e-12;
                    assert!(
                        w < w_prev || at_floor,
                        "{roughness} {theta}: {w} vs {w_prev}"
                    );
                }
            }
        }
    }
}
