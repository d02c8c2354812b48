//! The environment map's light by the split sum, for the f32x8 light loop
//! of `lit.rs` and the packet pairs of `packet_pairs.rs` alike.

use crate::envmap::{disk_cos_factor, EnvMap};
use specula_core::{Brdf, Mask, Real, Rgb, ShadingFrame, V3};

/// The environment map's light by the split sum: the model's diffuse
/// albedo times E(n)/π, its glossy albedo times the prefiltered radiance
/// around the mirror direction at its roughness, a clearcoat's albedo
/// times the prefiltered radiance around the mirror direction about the
/// coat's normal at the coat's roughness (all without the sun; each
/// read along its lobe's dominant direction: [`prefilter_direction`]),
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
        let r = prefilter_direction(n, wo, lobes.roughness);
        out = lobes
            .specular
            .mul_elem_add(map.prefiltered(r, lobes.roughness), out);
    }
    if lobes.coat.gt(R::ZERO).any() {
        // The coat's own lobe, about its normal (in world space).
        let c = lobes.coat_normal;
        let nc = frame.t * c.x + frame.b * c.y + frame.n * c.z;
        let r = prefilter_direction(nc, wo, lobes.coat_roughness);
        out += map.prefiltered(r, lobes.coat_roughness) * lobes.coat;
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

/// Where the prefiltered chain is read for a GGX lobe at perceptual
/// `roughness` about unit normal `n` seen from unit `wo` (world space):
/// the lobe's dominant direction \[Lagarde14, listing 22\], the mirror
/// direction r of wo about n pulled toward n as α grows,
/// lerp(n, r, s (√s + α)) with s = 1 − α. The prefiltered chain is made
/// with n = v = r, so its lobe is centred on r; the true lobe leans
/// toward the normal (its Fresnel and masking, and the horizon, cut the
/// side away from it), more the rougher it is: at α = 1 it is read along
/// n. Chosen over the other fits tried by the split sum's error against
/// the Monte Carlo reference (docs/accuracy.md, "Split sum against
/// reference"). Not unit length: the octahedral lookup divides by its
/// own norm.
#[inline(always)]
pub fn prefilter_direction<R: Real>(n: V3<R>, wo: V3<R>, roughness: R) -> V3<R> {
    let r = n * (R::splat(2.0) * n.dot(wo)) - wo;
    let alpha = roughness * roughness;
    let s = (R::ONE - alpha).clamp(R::ZERO, R::ONE);
    let t = s * (s.sqrt() + alpha);
    (r - n).mul_add(t, n)
}
