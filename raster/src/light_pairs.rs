//! Packets shaded two lights at a time, where the processor has AVX-512:
//! a packet's eight lanes are copied into both halves of sixteen-lane
//! registers ([`F32x16`](crate::lanes16::F32x16)), each half takes one
//! light of a pair, and the halves' terms are added to the packet's sum
//! in the lights' order, with the fused multiply-adds of the f32x8 light
//! loop. Every lane does what the f32x8 path does, so the pixels are the
//! same bits (tests/golden.rs renders every fixture scene that takes the
//! pairs with f32x8 alone too); a light's chain of square roots and
//! quotients runs for two lights per instruction, which pays where
//! 512-bit units are full width (docs/PERFORMANCE.md, "Light pairs").
//!
//! Used for batches of metallic-roughness and Lambert materials without
//! maps ([`pairs_model`]) lit by point, spot and directional lights, two
//! of one kind in a row, under a uniform environment, none, or a map lit
//! by the split sum (those terms made for two packets at a time, one a
//! half, without shadow maps; in f32x8 with them); everything else takes
//! the f32x8 path. Lights with shadow maps are not paired (their
//! lookups, not their BRDFs, are most of their cost): each is lit alone
//! in sixteen lanes and its shadow factor looked up in f32x8, as the f32x8
//! loop looks it up.

use crate::envmap::{EnvMap, IblMethod};
use crate::fragment::Fragment;
use crate::shader::ShadeEnv;
use specula_core::light::Light;
use specula_core::{f32x8, Model, Rgb};

/// Whether [`shade_batch`] shades this frame's batches.
pub(crate) fn handles(env: &ShadeEnv) -> bool {
    let shadowed = |k| env.shadows.is_some_and(|s| s.light(k).is_some());
    applies(env.lights, shadowed, env.env_map)
}

/// Whether light pairs shade a frame with these lights (`shadowed(k)`:
/// whether light `k` has shadow maps) and environment map: on a processor
/// with AVX-512 ([`available`]), point, spot and directional lights, two
/// in a row of one [`kind`] without shadow maps (else no pair forms), no
/// polygon light, and no map or one lit by the split sum.
pub(crate) fn applies(
    lights: &[Light],
    shadowed: impl Fn(usize) -> bool,
    env_map: Option<&EnvMap>,
) -> bool {
    available()
        && env_map.is_none_or(|m| m.method == IblMethod::SplitSum)
        && !lights.iter().any(|l| matches!(l, Light::Polygon { .. }))
        && (1..lights.len()).any(|k| pair(lights, k - 1, &shadowed))
}

/// Whether lights `k` and `k + 1` make a pair: both of one [`kind`], and
/// neither with shadow maps.
fn pair(lights: &[Light], k: usize, shadowed: impl Fn(usize) -> bool) -> bool {
    kind(&lights[k]) == kind(&lights[k + 1]) && !shadowed(k) && !shadowed(k + 1)
}

/// A light's kind for pairing: two consecutive lights of one kind make a
/// pair (point, spot with or without a finite range alike, directional).
fn kind(l: &Light) -> (u8, bool) {
    match l {
        Light::Point { range, .. } => (0, range.is_finite()),
        Light::Spot { range, .. } => (1, range.is_finite()),
        Light::Directional { .. } => (2, false),
        Light::Polygon { .. } => (3, false),
    }
}

/// Whether `model`'s batches take the pairs: the metallic-roughness and
/// Lambert models. The glTF, Disney and microfacet models' light loops
/// compile to sixteen-lane code too, but lit in pairs they were no faster
/// than f32x8 (docs/PERFORMANCE.md, "Tried and dropped").
pub(crate) fn pairs_model(model: &Model) -> bool {
    matches!(model, Model::MetallicRoughness(_) | Model::Lambert(_))
}

/// Whether this processor runs the light pairs (AVX-512F, DQ, VL, BW).
pub(crate) fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    return crate::lanes16::available();
    #[cfg(not(target_arch = "x86_64"))]
    return false;
}

/// `Lit::shade_batch`'s packets (`out[i]` for `frags[i]` under
/// `lanes[i]`) lit two lights at a time. Only where [`handles`] is true.
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
        unreachable!("light pairs are not built for this target (`handles` is false)");
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::*;
    use crate::delta_light::{add_delta_light, punctual_part, Punctual};
    use crate::lanes16::F32x16;
    use crate::shader::ShadeInput;
    use crate::split_sum::{env_split_sum, env_split_sum_inline};
    use specula_core::{Brdf, BrdfVisitor, Real, V3};

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
            assert!(crate::lanes16::available(), "light pairs need AVX-512");
            // SAFETY: the processor has AVX-512F/DQ/VL/BW (asserted).
            unsafe {
                match self.env.shadows {
                    Some(_) => shade_packets::<B, true>(brdf, &mut self),
                    None => shade_packets::<B, false>(brdf, &mut self),
                }
            }
        }
    }

    /// One light (with its index in the frame's list), or two in the
    /// halves.
    enum Step<'a> {
        Pair(&'a Light, &'a Light),
        One(usize, &'a Light),
    }

    /// The lights in order, consecutive ones that make a [`pair`] paired.
    fn steps<'a>(
        lights: &'a [Light],
        shadowed: impl Fn(usize) -> bool + 'a,
    ) -> impl Iterator<Item = Step<'a>> {
        let mut i = 0;
        std::iter::from_fn(move || {
            let step = match lights.get(i..)? {
                [] => return None,
                [a, b, ..] if pair(lights, i, &shadowed) => Step::Pair(a, b),
                [a, ..] => Step::One(i, a),
            };
            i += match step {
                Step::Pair(..) => 2,
                Step::One(..) => 1,
            };
            Some(step)
        })
    }

    /// `v` in both halves.
    #[inline(always)]
    fn both(v: &V3<f32x8>) -> V3<F32x16> {
        V3::new(F32x16::both(v.x), F32x16::both(v.y), F32x16::both(v.z))
    }

    /// Lanes 0–7 of `v`.
    #[inline(always)]
    fn lo(v: &V3<F32x16>) -> V3<f32x8> {
        V3::new(v.x.lo(), v.y.lo(), v.z.lo())
    }

    /// Lanes 8–15 of `v`.
    #[inline(always)]
    fn hi(v: &V3<F32x16>) -> V3<f32x8> {
        V3::new(v.x.hi(), v.y.hi(), v.z.hi())
    }

    /// `a`'s lanes in the low half, `b`'s in the high one.
    #[inline(always)]
    fn halves(a: V3<f32x8>, b: V3<f32x8>) -> V3<F32x16> {
        V3::new(
            F32x16::from_halves(a.x, b.x),
            F32x16::from_halves(a.y, b.y),
            F32x16::from_halves(a.z, b.z),
        )
    }

    /// Two point or spot lights of one kind as one [`Punctual`]: each
    /// parameter as f32x8 broadcasts it, one light a half.
    #[inline(always)]
    fn punctual_pair(a: &Light, b: &Light) -> Punctual<F32x16> {
        let (a, b) = (
            Punctual::<f32x8>::of(a).expect("a point or spot light"),
            Punctual::<f32x8>::of(b).expect("a point or spot light"),
        );
        let pair = |x: f32x8, y: f32x8| F32x16::from_halves(x, y);
        Punctual {
            position: halves(a.position, b.position),
            intensity: halves(a.intensity, b.intensity),
            cone: match (a.cone, b.cone) {
                (Some((ax, sa, oa)), Some((bx, sb, ob))) => {
                    Some((halves(ax, bx), pair(sa, sb), pair(oa, ob)))
                }
                _ => None,
            },
            range2: match (a.range2, b.range2) {
                (Some(ra), Some(rb)) => Some(pair(ra, rb)),
                _ => None,
            },
        }
    }

    /// The packets of `p`, as `LightLoop::shade` shades them;
    /// `SHADOWS` if the frame has shadow maps (`p.env.shadows`): a
    /// constant, so that frames without them compile without lookups.
    ///
    /// # Safety
    /// The processor has AVX-512F, DQ, VL and BW.
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
    unsafe fn shade_packets<B: Brdf, const SHADOWS: bool>(brdf: &B, p: &mut Packets) {
        let shadows = p.env.shadows;
        let shadow = |k: usize| match SHADOWS {
            true => shadows.and_then(|s| s.light(k)),
            false => None,
        };
        let steps = || steps(p.env.lights, move |k| shadow(k).is_some());
        let pixel = brdf.pixel(&brdf.params::<F32x16>());
        // The environment's terms: without shadow maps, two packets' at a
        // time, one a half (`add_environments`); with them (a sun's factor
        // is looked up in f32x8), in f32x8 as the f32x8 loop makes them.
        let env = p.env.environment.is_some() || p.env.env_map.is_some();
        let env8 = env && SHADOWS;
        let pixel8 = env8.then(|| brdf.pixel(&brdf.params::<f32x8>()));
        for ((frag8, &lanes), out) in p.frags.iter().zip(p.lanes).zip(p.out.iter_mut()) {
            let frag = Fragment {
                p: both(&frag8.p),
                n: both(&frag8.n),
                wo: both(&frag8.wo),
                w: F32x16::both(frag8.w),
                b1: F32x16::both(frag8.b1),
                b2: F32x16::both(frag8.b2),
            };
            let input = ShadeInput {
                frag: &frag,
                surface: None,
                lanes: lanes | lanes << 8,
            };
            let frame = p.maps.frame(&input);
            let prepared = brdf.prepare_with(&pixel, frame.to_local(frag.wo));
            let mut acc = Rgb::<f32x8>::zero();
            for step in steps() {
                acc = match step {
                    Step::Pair(a @ Light::Directional { .. }, b) => {
                        let (
                            Light::Directional {
                                to_light: ta,
                                irradiance: ea,
                            },
                            Light::Directional {
                                to_light: tb,
                                irradiance: eb,
                            },
                        ) = (a, b)
                        else {
                            unreachable!("paired lights are of one kind")
                        };
                        let to_light = halves(V3::from_f32(*ta), V3::from_f32(*tb));
                        let f_cos = brdf.f_cos_local(&prepared, frame.to_local(to_light));
                        let acc = lo(&f_cos).mul_elem_add(V3::from_f32(*ea), acc);
                        hi(&f_cos).mul_elem_add(V3::from_f32(*eb), acc)
                    }
                    Step::Pair(a, b) => {
                        let light = punctual_pair(a, b);
                        let (f, radiance) = punctual_part(brdf, &prepared, &frag, &frame, &light);
                        let acc = lo(&f).mul_elem_add(lo(&radiance), acc);
                        hi(&f).mul_elem_add(hi(&radiance), acc)
                    }
                    // In sixteen lanes on a sum copied into both halves:
                    // the low half is the f32x8 light loop's sum.
                    Step::One(k, light) => match shadow(k) {
                        None => {
                            let acc = both(&acc);
                            lo(&add_delta_light(brdf, &prepared, &frag, &frame, light, acc))
                        }
                        // `lit.rs`'s `shadowed_lights`' operations.
                        Some(shadow) => {
                            let zero = Rgb::zero();
                            let part = add_delta_light(brdf, &prepared, &frag, &frame, light, zero);
                            let part = lo(&part);
                            let visible = shadow.visibility_where(&part, &frag8.p, &frag8.n, lanes);
                            part.mul_elem_add(V3::splat(visible), acc)
                        }
                    },
                };
            }
            if let Some(pixel8) = &pixel8 {
                let input8 = ShadeInput {
                    frag: frag8,
                    surface: None,
                    lanes,
                };
                let frame8 = p.maps.frame(&input8);
                let prepared8 = brdf.prepare_with(pixel8, frame8.to_local(frag8.wo));
                if let Some(e) = p.env.environment {
                    acc += brdf.albedo_local(&prepared8).mul_elem(V3::from_f32(e));
                }
                if let Some(map) = p.env.env_map {
                    let sun = |part: &Rgb<f32x8>| p.env.sun_visibility(&input8, part);
                    acc += env_split_sum(brdf, &prepared8, &frame8, frag8.wo, map, sun);
                }
            }
            if env && !SHADOWS {
                // Its environment and emission follow in `add_environments`.
                *out = acc;
                continue;
            }
            if let Some(e) = p.emissive {
                acc += Rgb::from_f32(e);
            }
            *out = acc;
        }
        if env && !SHADOWS {
            add_environments(brdf, p, &pixel);
        }
    }

    /// Adds to each packet's sum in `p.out` its environment's term and
    /// its emission, the terms of two packets made at a time in sixteen
    /// lanes (packet i in the low half, i + 1 in the high one; an odd last
    /// packet in both), each added in f32x8 as the f32x8 loop adds it.
    /// Without shadow maps: the environment map's sun is unshadowed.
    #[inline(always)]
    fn add_environments<B: Brdf>(brdf: &B, p: &mut Packets, pixel: &B::Pixel<F32x16>) {
        let n = p.frags.len();
        for i in (0..n).step_by(2) {
            let j = (i + 1).min(n - 1);
            let (a, b) = (&p.frags[i], &p.frags[j]);
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
                lanes: p.lanes[i] | p.lanes[j] << 8,
            };
            let frame = p.maps.frame(&input);
            let prepared = brdf.prepare_with(pixel, frame.to_local(frag.wo));
            let uniform = p
                .env
                .environment
                .map(|e| brdf.albedo_local(&prepared).mul_elem(V3::from_f32(e)));
            let map = p.env.env_map.map(|map| {
                env_split_sum_inline(brdf, &prepared, &frame, frag.wo, map, |_| {
                    <F32x16 as Real>::ONE
                })
            });
            let mut add = |k: usize, high: bool| {
                let half = |t: &Rgb<F32x16>| if high { hi(t) } else { lo(t) };
                let mut acc = p.out[k];
                if let Some(t) = &uniform {
                    acc += half(t);
                }
                if let Some(t) = &map {
                    acc += half(t);
                }
                if let Some(e) = p.emissive {
                    acc += Rgb::from_f32(e);
                }
                p.out[k] = acc;
            };
            add(i, false);
            if j != i {
                add(j, true);
            }
        }
    }
}
