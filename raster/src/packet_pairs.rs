//! Batches shaded two packets at a time, where the processor has AVX-512:
//! packets i and i + 1 of a batch go into the low and high halves of
//! sixteen-lane registers ([`F32x16`](crate::lanes16::F32x16)), and the
//! model's per-pixel work, each light's term and the environment's run
//! once for the sixteen pixels, in the f32x8 light loop's order with its
//! fused multiply-adds. Every lane does what the f32x8 path does, so the
//! pixels are the same bits (tests/golden.rs renders every fixture scene
//! that takes the pairs with f32x8 alone too); a light's chain of square
//! roots and quotients runs for two packets per instruction, which pays
//! where 512-bit units are full width (docs/PERFORMANCE.md, "Packet
//! pairs").
//!
//! Used for the batches (packets of one material without maps) of every
//! model but Disney's ([`pairs_model`]), lit by point, spot and
//! directional lights under a uniform environment, none, or a map lit by
//! the split sum; frames with polygon lights or the Monte Carlo reference
//! take the f32x8 path. A light's shadow factor is each half's as the
//! f32x8 loop looks it up: on one hard or PCF map, or on the one face of a
//! cube map or cascade that all sixteen lanes pick, the lookup's common
//! end runs in sixteen lanes (`LightShadow::visibility_where_pair`), the
//! rest per half in f32x8; an environment map's sun's factor is looked up in
//! f32x8, with the map's term then made per packet.

use crate::envmap::{EnvMap, IblMethod};
use crate::fragment::Fragment;
use crate::shader::ShadeEnv;
use specula_core::light::Light;
use specula_core::{f32x8, Model, Rgb};

/// Whether [`shade_batch`] shades this frame's batches.
pub(crate) fn handles(env: &ShadeEnv) -> bool {
    applies(env.lights, env.env_map)
}

/// Whether packet pairs shade a frame with these lights and environment
/// map: on a processor with AVX-512 ([`available`]), point, spot and
/// directional lights (any number, with or without shadow maps), no
/// polygon light, and no map or one lit by the split sum.
pub(crate) fn applies(lights: &[Light], env_map: Option<&EnvMap>) -> bool {
    available()
        && env_map.is_none_or(|m| m.method == IblMethod::SplitSum)
        && !lights.iter().any(|l| matches!(l, Light::Polygon { .. }))
}

/// Whether `model`'s batches take the pairs: every model but Disney's,
/// which shaded a few percent slower in pairs than in f32x8
/// (docs/PERFORMANCE.md, "Packet pairs").
pub(crate) fn pairs_model(model: &Model) -> bool {
    !matches!(model, Model::Disney(_))
}

/// Whether this processor runs the packet pairs (AVX-512F, DQ, VL, BW).
pub(crate) fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    return crate::lanes16::available();
    #[cfg(not(target_arch = "x86_64"))]
    return false;
}

/// `Lit::shade_batch`'s packets (`out[i]` for `frags[i]` under
/// `lanes[i]`), two at a time. Only where [`handles`] is true.
pub(crate) fn shade_batch(
    model: &Model,
    emissive: Option<[f32; 3]>,
    maps: &crate::maps::ParamMaps,
    frags: &[Fragment<f32x8>],
    lanes: &[u32],
    env: &ShadeEnv,
    out: &mut [Rgb<f32x8>],
) {
    #[cfg(target_arch = "x86_64")]
    {
        model.visit(x86::Packets {
            emissive,
            maps,
            frags,
            lanes,
            env,
            out,
        })
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (model, emissive, maps, frags, lanes, env, out);
        unreachable!("packet pairs are not built for this target (`handles` is false)");
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::*;
    use crate::delta_light::add_delta_light;
    use crate::lanes16::{v3_halves as halves, v3_hi as hi, v3_lo as lo, F32x16};
    use crate::shader::ShadeInput;
    use crate::split_sum::{env_split_sum, env_split_sum_inline};
    use specula_core::{Brdf, BrdfVisitor, Real, ShadingFrame, V3};

    /// A batch's packets and what lights them.
    pub(super) struct Packets<'a> {
        pub(super) emissive: Option<[f32; 3]>,
        pub(super) maps: &'a crate::maps::ParamMaps,
        pub(super) frags: &'a [Fragment<f32x8>],
        pub(super) lanes: &'a [u32],
        pub(super) env: &'a ShadeEnv<'a>,
        pub(super) out: &'a mut [Rgb<f32x8>],
    }

    impl BrdfVisitor for Packets<'_> {
        type Output = ();
        #[inline(always)]
        fn visit<B: Brdf>(mut self, brdf: &B) {
            assert!(crate::lanes16::available(), "packet pairs need AVX-512");
            // SAFETY: the processor has AVX-512F/DQ/VL/BW (asserted).
            unsafe {
                match self.env.shadows {
                    Some(_) => shade_packets::<B, true>(brdf, &mut self),
                    None => shade_packets::<B, false>(brdf, &mut self),
                }
            }
        }
    }

    /// The packets of `p`, as `LightLoop::shade` shades them, two at a
    /// time: packet i in the low half of sixteen lanes, i + 1 in the high
    /// one (an odd last packet in both). `SHADOWS` if the frame has shadow
    /// maps (`p.env.shadows`): a constant, so that frames without them
    /// compile without lookups.
    ///
    /// # Safety
    /// The processor has AVX-512F, DQ, VL and BW.
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
    unsafe fn shade_packets<B: Brdf, const SHADOWS: bool>(brdf: &B, p: &mut Packets) {
        let shadows = p.env.shadows;
        let pixel = brdf.pixel(&brdf.params::<F32x16>());
        // With shadow maps an environment map's sun has a factor looked up
        // in f32x8: the map's term is then made per packet in f32x8, as
        // the f32x8 loop makes it.
        let pixel8 =
            (SHADOWS && p.env.env_map.is_some()).then(|| brdf.pixel(&brdf.params::<f32x8>()));
        let n = p.frags.len();
        for i in (0..n).step_by(2) {
            let j = (i + 1).min(n - 1);
            let (a, b) = (&p.frags[i], &p.frags[j]);
            let (lanes_a, lanes_b) = (p.lanes[i], p.lanes[j]);
            let frag = Fragment {
                p: halves(a.p, b.p),
                n: halves(a.n, b.n),
                wo: halves(a.wo, b.wo),
                w: F32x16::from_halves(a.w, b.w),
                b1: F32x16::from_halves(a.b1, b.b1),
                b2: F32x16::from_halves(a.b2, b.b2),
            };
            let input = ShadeInput {
                frag: &frag,
                surface: None,
                lanes: lanes_a | lanes_b << 8,
                shadow_factors: None,
            };
            let frame = p.maps.frame(&input);
            let prepared = brdf.prepare_with(&pixel, frame.to_local(frag.wo));
            let mut acc = Rgb::<F32x16>::zero();
            for (k, light) in p.env.lights.iter().enumerate() {
                let shadow = match SHADOWS {
                    true => shadows.and_then(|s| s.light(k)),
                    false => None,
                };
                acc = match shadow {
                    None => add_delta_light(brdf, &prepared, &frag, &frame, light, acc),
                    // `lit.rs`'s `shadowed_lights`' operations, each
                    // half's factor as f32x8 looks it up.
                    Some(shadow) => {
                        let zero = Rgb::zero();
                        let part = add_delta_light(brdf, &prepared, &frag, &frame, light, zero);
                        let visible =
                            shadow.visibility_where_pair(&part, &frag.p, &frag.n, input.lanes);
                        part.mul_elem_add(V3::splat(visible), acc)
                    }
                };
            }
            if let Some(e) = p.env.environment {
                acc += brdf.albedo_local(&prepared).mul_elem(V3::from_f32(e));
            }
            if let Some(map) = p.env.env_map {
                acc += match &pixel8 {
                    Some(pixel8) => {
                        let half = |frag8: &Fragment<f32x8>, lanes: u32| {
                            let input8 = ShadeInput {
                                frag: frag8,
                                surface: None,
                                lanes,
                                shadow_factors: None,
                            };
                            let frame8 = p.maps.frame(&input8);
                            let prepared8 = brdf.prepare_with(pixel8, frame8.to_local(frag8.wo));
                            let sun = |part: &Rgb<f32x8>| p.env.sun_visibility(&input8, part);
                            env_split_sum(brdf, &prepared8, &frame8, frag8.wo, map, sun)
                        };
                        halves(half(a, lanes_a), half(b, lanes_b))
                    }
                    None => map_term(brdf, &prepared, &frame, frag.wo, map),
                };
            }
            if let Some(e) = p.emissive {
                acc += Rgb::from_f32(e);
            }
            p.out[i] = lo(&acc);
            if j != i {
                p.out[j] = hi(&acc);
            }
        }
    }

    /// An environment map's split sum in sixteen lanes, its sun unshadowed.
    /// Out of line: inlined, it made the light loop's body spill.
    ///
    /// # Safety
    /// The processor has AVX-512F, DQ, VL and BW.
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
    #[inline(never)]
    unsafe fn map_term<B: Brdf>(
        brdf: &B,
        prepared: &B::Prepared<F32x16>,
        frame: &ShadingFrame<F32x16>,
        wo: V3<F32x16>,
        map: &EnvMap,
    ) -> Rgb<F32x16> {
        env_split_sum_inline(brdf, prepared, frame, wo, map, |_| <F32x16 as Real>::ONE)
    }
}
