//! The physically based shader: a core [`Model`] lit by the scene's lights.
//!
//! Per packet the model's parameters are made (its constants, then its
//! texture maps where it has any: maps.rs); the model then prepares what
//! depends on the pixel alone ([`Brdf::prepare_with`] with wo in the local
//! frame); then each light adds its
//! part in the local frame: delta lights (point, spot, directional) through one
//! direction, polygon lights through the model's integral over the polygon,
//! the uniform environment through the directional albedo (times the
//! occlusion map's factor where the material has one). The material's
//! emission (its emissive colour times its emissive map) is added last.
//! A normal map bends the local frame all of this is computed in
//! ([`ParamMaps::frame`]).

use crate::delta_light::add_delta_light;
use crate::envmap::{EnvMap, IblMethod};
use crate::envmap_reference::{reference_radiance, seed_of};
use crate::fragment::Fragment;
use crate::maps::ParamMaps;
use crate::shader::{LightRefusal, PacketShader, ShadeEnv, ShadeInput};
use crate::shadow::ShadowMaps;
use crate::split_sum::env_split_sum;
use crate::texture::Filter;
use specula_core::light::{AreaMethod, Light, PolygonLocal, MAX_POLYGON_VERTICES};
use specula_core::ltc::reference::polygon_reference_lanes;
use specula_core::{f32x8, Brdf, BrdfVisitor, LaneParams, Model, Real, Rgb, ShadingFrame, V3};

/// A model under the scene's lights, its parameters filled per pixel by
/// its maps.
#[derive(Clone, Debug, PartialEq)]
pub struct Lit {
    model: Model,
    maps: ParamMaps,
    /// Emitted radiance (linear RGB; the emissive map multiplies it), or
    /// `None` for none.
    emissive: Option<[f32; 3]>,
}

/// A parameter map given to a model that has no parameter it fills
/// ([`Lit::with_maps`]).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{map}: the \"{model}\" model has no parameter this map fills")]
pub struct UnsupportedMap {
    pub(crate) map: &'static str,
    pub(crate) model: &'static str,
}

impl Lit {
    /// The model with its constant parameters.
    pub fn new(model: Model) -> Lit {
        Lit {
            model,
            maps: ParamMaps::default(),
            emissive: None,
        }
    }

    /// The model with parameters from `maps`; an error names the first map
    /// whose parameter the model does not have. A `gltf` model whose maps
    /// make its clearcoat's normal differ from the base's (a clearcoat
    /// normal map, or a base normal map, which the coat does not take:
    /// maps.rs) reads the coat's normal per lane.
    pub fn with_maps(model: Model, maps: ParamMaps) -> Result<Lit, UnsupportedMap> {
        let model = match model {
            Model::Gltf(g) if maps.normal.is_some() || maps.has_coat_normal_map() => {
                Model::Gltf(g.with_coat_normal())
            }
            m => m,
        };
        struct Check<'a>(&'a ParamMaps);
        impl BrdfVisitor for Check<'_> {
            type Output = Option<&'static str>;
            fn visit<B: Brdf>(self, b: &B) -> Option<&'static str> {
                self.0.unsupported(b.params::<f32>())
            }
        }
        match model.visit(Check(&maps)) {
            Some(map) => Err(UnsupportedMap {
                map,
                model: model.name(),
            }),
            None => Ok(Lit {
                model,
                maps,
                emissive: None,
            }),
        }
    }

    /// The material also emits `emissive` (linear RGB radiance, times the
    /// emissive map where it has one); zero emits nothing.
    pub fn with_emission(mut self, emissive: [f32; 3]) -> Lit {
        self.emissive = (emissive != [0.0; 3]).then_some(emissive);
        self
    }

    pub fn maps(&self) -> &ParamMaps {
        &self.maps
    }

    pub fn model(&self) -> &Model {
        &self.model
    }
}

/// The parameters of `brdf` at a packet (its constants, then its maps;
/// the clearcoat's normal in the packet's local `frame` where the maps
/// set it: [`ParamMaps::coat_normal`]), and what they determine before
/// the view is known.
#[inline(always)]
fn pixel_at<B: Brdf, R: Real>(
    brdf: &B,
    maps: &ParamMaps,
    input: &ShadeInput<R>,
    frame: &ShadingFrame<R>,
) -> (B::Params<R>, B::Pixel<R>) {
    let mut params = brdf.params();
    maps.fill(input, &mut params);
    if let Some(c) = params.coat_normal_mut() {
        if let Some(n) = maps.coat_normal(input, frame) {
            *c = n;
        }
    }
    (params, brdf.pixel(&params))
}

struct LightLoop<'a, 'b, R: Real> {
    input: &'a ShadeInput<'b, R>,
    env: &'a ShadeEnv<'a>,
    maps: &'a ParamMaps,
    emissive: Option<[f32; 3]>,
}

impl<R: Real> LightLoop<'_, '_, R> {
    /// Every light on one packet whose parameters determined `pixel`, in
    /// its local `frame` ([`ParamMaps::frame`]).
    #[inline(always)]
    fn shade<B: Brdf>(self, brdf: &B, pixel: &B::Pixel<R>, frame: &ShadingFrame<R>) -> Rgb<R> {
        let frag = self.input.frag;
        let prepared = brdf.prepare_with(pixel, frame.to_local(frag.wo));
        let mut acc = Rgb::zero();
        let mut rest = self.env.lights;
        if let Some(shadows) = self.env.shadows {
            acc = shadowed_lights(brdf, &prepared, frame, self.maps, self.input, rest, shadows);
            rest = &[];
        }
        while let [light, tail @ ..] = rest {
            // Only models with B::POLYGON_LIGHTS meet polygon lights
            // (`check_lights`); the constant folds this test away for the
            // others. The first one hands the rest of the list to an
            // out-of-line loop that makes the polygons' per-pixel state
            // once for all of them.
            if B::POLYGON_LIGHTS && matches!(light, Light::Polygon { .. }) {
                acc += lights_from_polygon(brdf, self.maps, self.input, rest, true);
                break;
            }
            acc = add_delta_light(brdf, &prepared, frag, frame, light, acc);
            rest = tail;
        }
        if let Some(env) = self.env.environment {
            let env = brdf.albedo_local(&prepared).mul_elem(V3::from_f32(env));
            acc += match self.maps.occlusion(self.input) {
                Some(k) => env * k,
                None => env,
            };
        }
        if let Some(map) = self.env.env_map {
            let env = match map.method {
                IblMethod::SplitSum => {
                    let sun = |part: &Rgb<R>| self.env.sun_visibility(self.input, part);
                    env_split_sum(brdf, &prepared, frame, frag.wo, map, sun)
                }
                IblMethod::Reference { samples } => {
                    env_reference(brdf, self.maps, self.input, map, samples)
                }
            };
            acc += match self.maps.occlusion(self.input) {
                Some(k) => env * k,
                None => env,
            };
        }
        if let Some(e) = self.emissive {
            let e = Rgb::from_f32(e);
            acc += match &self.maps.emissive {
                Some(map) => e.mul_elem(map.sample(self.input)),
                None => e,
            };
        }
        acc
    }
}

impl<R: Real> BrdfVisitor for LightLoop<'_, '_, R> {
    type Output = Rgb<R>;

    #[inline(always)]
    fn visit<B: Brdf>(self, brdf: &B) -> Rgb<R> {
        let frame = self.maps.frame(self.input);
        let (_, pixel) = pixel_at(brdf, self.maps, self.input, &frame);
        self.shade(brdf, &pixel, &frame)
    }
}

/// The environment map's light by the Monte Carlo reference
/// (envmap_reference.rs), lane by lane in f64. Out of line: it is the slow
/// path by design.
#[inline(never)]
#[cold]
fn env_reference<B: Brdf, R: Real>(
    brdf: &B,
    maps: &ParamMaps,
    input: &ShadeInput<R>,
    map: &EnvMap,
    samples: u32,
) -> Rgb<R> {
    let (frag, frame) = (input.frag, &maps.frame(input));
    let (params, _) = pixel_at(brdf, maps, input, frame);
    let wo = frame.to_local(frag.wo);
    let mut out = [[0.0f32; 8]; 3];
    for i in 0..R::LANES {
        if input.lanes & (1 << i) == 0 {
            continue;
        }
        let pixel = brdf.pixel(&B::params_lane(&params, i));
        let wo_i = wo.lane(i).normalize_or(V3::new(0.0, 0.0, 1.0));
        let prepared = brdf.prepare_with(&pixel, wo_i);
        let lobes = brdf.env_lobes(&prepared);
        let frame_i = ShadingFrame {
            t: frame.t.lane(i),
            b: frame.b.lane(i),
            n: frame.n.lane(i),
        };
        let seed = seed_of(frag.p.lane(i));
        let c = reference_radiance(brdf, &prepared, &lobes, wo_i, &frame_i, map, samples, seed);
        for (plane, v) in out.iter_mut().zip(c) {
            plane[i] = v as f32;
        }
    }
    Rgb::new(
        R::load(&out[0][..R::LANES]),
        R::load(&out[1][..R::LANES]),
        R::load(&out[2][..R::LANES]),
    )
}

/// The reflected radiance of `lights`, from the scene's first polygon
/// light on (delta lights among them through `add_delta_light`). Out of
/// line: inlined into the light loop, its clipping and reference
/// integration made the register allocator spill the point-light path
/// (+10 % instructions in the shading pass of a scene without polygon
/// lights). The model's per-pixel state for polygon lights
/// ([`Brdf::prepare_polygons`]: the LTC lookup) is made here, once for all
/// of them, so pixels lit only by point lights never pay for it.
///
/// The parameters, the frame and the prepared view are made again here
/// (the same values, bit for bit) rather than passed by reference: a
/// reference made the light loop store them to memory in every call,
/// polygon lights or not.
///
/// With `delta` false the delta lights among `lights` are left out (the
/// shadowed path shades them itself).
#[inline(never)]
#[cold]
fn lights_from_polygon<B: Brdf, R: Real>(
    brdf: &B,
    maps: &ParamMaps,
    input: &ShadeInput<R>,
    lights: &[Light],
    delta: bool,
) -> Rgb<R> {
    let (frag, frame) = (input.frag, &maps.frame(input));
    let (params, pixel) = pixel_at(brdf, maps, input, frame);
    let prepared = &brdf.prepare_with(&pixel, frame.to_local(frag.wo));
    let mut poly = PolygonLocal {
        vertices: [V3::zero(); MAX_POLYGON_VERTICES],
        len: 0,
        two_sided: false,
    };
    let mut per_pixel = None;
    let mut acc = Rgb::zero();
    for light in lights {
        let Light::Polygon {
            vertices,
            radiance,
            two_sided,
            method,
        } = light
        else {
            if delta {
                acc = add_delta_light(brdf, prepared, frag, frame, light, acc);
            }
            continue;
        };
        poly.len = vertices.len();
        poly.two_sided = *two_sided;
        for (v, p) in poly.vertices.iter_mut().zip(vertices) {
            *v = frame.to_local(V3::from_f32(*p) - frag.p);
        }
        let e = match method {
            AreaMethod::Ltc => {
                let pp = per_pixel.get_or_insert_with(|| brdf.prepare_polygons(prepared));
                brdf.polygon_local_with(prepared, pp, &poly)
            }
            AreaMethod::Reference => {
                polygon_reference_lanes(brdf, &params, frame.to_local(frag.wo), &poly)
            }
        };
        acc += e.mul_elem(V3::from_f32(*radiance));
    }
    acc
}

/// The reflected radiance of `lights` when some have shadow maps: each
/// light's part times its shadow factor at the packet's points (a polygon
/// light's part is its unshadowed integral), with the packet's `prepared`
/// view in its local `frame`. Inline, so each shadowed light's lookup
/// (its common end, [`LightShadow::visibility_at`](crate::shadow::LightShadow::visibility_at))
/// runs beside the other lights' BRDFs rather than behind a call; scenes
/// without shadows never enter it (their frames measured no slower).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn shadowed_lights<B: Brdf, R: Real>(
    brdf: &B,
    prepared: &B::Prepared<R>,
    frame: &ShadingFrame<R>,
    maps: &ParamMaps,
    input: &ShadeInput<R>,
    lights: &[Light],
    shadows: &ShadowMaps,
) -> Rgb<R> {
    let frag = input.frag;
    let mut acc = Rgb::zero();
    let mut polygons = false;
    for (k, light) in lights.iter().enumerate() {
        if matches!(light, Light::Polygon { .. }) {
            polygons = true;
            continue;
        }
        acc = match shadows.light(k) {
            Some(shadow) => {
                let part = add_delta_light(brdf, prepared, frag, frame, light, Rgb::zero());
                part.mul_elem_add(V3::splat(input.light_visibility(k, shadow, &part)), acc)
            }
            None => add_delta_light(brdf, prepared, frag, frame, light, acc),
        };
    }
    if !(B::POLYGON_LIGHTS && polygons) {
        return acc;
    }
    let shadowed_polygon =
        |(k, l): (usize, &Light)| matches!(l, Light::Polygon { .. }) && shadows.light(k).is_some();
    if !lights.iter().enumerate().any(shadowed_polygon) {
        return acc + lights_from_polygon(brdf, maps, input, lights, false);
    }
    // Each polygon light's unshadowed integral times its shadow factor
    // (the visibility ratio its cube map estimates).
    for (k, light) in lights.iter().enumerate() {
        if !matches!(light, Light::Polygon { .. }) {
            continue;
        }
        let part = lights_from_polygon(brdf, maps, input, std::slice::from_ref(light), false);
        acc = match shadows.light(k) {
            Some(shadow) => {
                part.mul_elem_add(V3::splat(input.light_visibility(k, shadow, &part)), acc)
            }
            None => acc + part,
        };
    }
    acc
}

impl PacketShader for Lit {
    #[inline(always)]
    fn shade<R: Real>(&self, input: &ShadeInput<R>, env: &ShadeEnv) -> Rgb<R> {
        self.model.visit(LightLoop {
            input,
            env,
            maps: &self.maps,
            emissive: self.emissive,
        })
    }

    /// The model is dispatched once for the batch, so its parameters and
    /// what they determine before the view are made once too: batches hold
    /// only packets of materials without maps (which need no surface),
    /// whose parameters are their constants.
    #[inline(always)]
    fn shade_batch<R: Real>(
        &self,
        frags: &[Fragment<R>],
        lanes: &[u32],
        env: &ShadeEnv,
        out: &mut [Rgb<R>],
    ) {
        if !self.maps.is_empty() {
            for (input, out) in ShadeInput::batch(frags, lanes).zip(out) {
                *out = self.shade(&input, env);
            }
            return;
        }
        struct Packets<'a, R: Real> {
            frags: &'a [Fragment<R>],
            lanes: &'a [u32],
            env: &'a ShadeEnv<'a>,
            /// The material's maps: none (checked above).
            maps: &'a ParamMaps,
            emissive: Option<[f32; 3]>,
            out: &'a mut [Rgb<R>],
        }
        impl<R: Real> BrdfVisitor for Packets<'_, R> {
            type Output = ();
            #[inline(always)]
            fn visit<B: Brdf>(self, brdf: &B) {
                let pixel = brdf.pixel(&brdf.params());
                for (input, out) in ShadeInput::batch(self.frags, self.lanes).zip(self.out) {
                    let frame = self.maps.frame(&input);
                    *out = LightLoop {
                        input: &input,
                        env: self.env,
                        maps: self.maps,
                        emissive: self.emissive,
                    }
                    .shade(brdf, &pixel, &frame);
                }
            }
        }
        self.model.visit(Packets {
            frags,
            lanes,
            env,
            maps: &self.maps,
            emissive: self.emissive,
            out,
        })
    }

    /// [`PacketShader::shade_batch`], or where the frame allows it (the
    /// material has no maps and a model the pairs take, the lights are
    /// point, spot and directional lights and a map, if any, is lit by the
    /// split sum): two packets per AVX-512 register (packet_pairs.rs: the
    /// same bits).
    fn shade_batch_x8(
        &self,
        frags: &[Fragment<f32x8>],
        lanes: &[u32],
        env: &ShadeEnv,
        out: &mut [Rgb<f32x8>],
    ) {
        if env.pair_packets
            && self.maps.is_empty()
            && crate::packet_pairs::pairs_model(&self.model)
            && crate::packet_pairs::handles(env)
        {
            return crate::packet_pairs::shade_batch(
                &self.model,
                self.emissive,
                &self.maps,
                frags,
                lanes,
                env,
                out,
            );
        }
        self.shade_batch(frags, lanes, env, out)
    }

    fn needs_surface(&self) -> bool {
        struct Aniso;
        impl BrdfVisitor for Aniso {
            type Output = bool;
            fn visit<B: Brdf>(self, _: &B) -> bool {
                B::ANISOTROPIC
            }
        }
        self.model.visit(Aniso) || !self.maps.is_empty()
    }

    fn with_texture_filter(&self, filter: Filter) -> Option<Lit> {
        if self.maps.is_empty() {
            return None;
        }
        let mut lit = self.clone();
        lit.maps.force_filter(filter);
        Some(lit)
    }

    fn check_lights(&self, lights: &[Light]) -> Result<(), LightRefusal> {
        if !self.model.polygon_lights() {
            if let Some(i) = lights
                .iter()
                .position(|l| matches!(l, Light::Polygon { .. }))
            {
                return Err(LightRefusal {
                    light: i,
                    why: format!(
                        "a polygon light, and the \"{}\" model has no integral over polygons yet (polygon lights shade only materials that have one; \"unlit\" ignores lights)",
                        self.model.name()
                    ),
                });
            }
        }
        Ok(())
    }
}
