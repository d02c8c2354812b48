//! The seam between the shading pass and what a material does to a pixel
//! packet: [`SurfaceShader`].
//!
//! A shader is written once, generic over the lane type, by implementing
//! [`PacketShader`]; the blanket impl turns it into a [`SurfaceShader`],
//! the object-safe form the scene stores (`Arc<dyn SurfaceShader>`), with
//! one monomorphized entry per lane width (f32x8 for the hot path, f32 for
//! `--scalar`). The dynamic call happens once per packet and material, or
//! once per run of packets of one material in a tile row
//! ([`SurfaceShader::shade_x8_batch`]); everything inside it (the light
//! loop, the BRDF) is static. Crates above
//! raster (npr's toon and hatching shaders) add shaders this way without
//! touching core or raster.
//!
//! Shaders in this crate: [`crate::lit::Lit`] (a physically based
//! [`specula_core::Model`] under the scene's lights) and
//! [`crate::unlit::Unlit`] (a constant radiance).

use crate::fragment::{Fragment, Surface};
use crate::texture::Filter;
use specula_core::light::Light;
use specula_core::{f32x8, Real, Rgb, ShadingFrame};
use std::any::Any;
use std::fmt::Debug;
use std::sync::Arc;

/// What the shading pass knows of a packet, for the lanes of one material.
pub struct ShadeInput<'a, R: Real> {
    /// Position, normal, view direction, depth, barycentrics.
    pub frag: &'a Fragment<R>,
    /// uv, uv derivatives and the uv tangent frame, when the shader asked
    /// for them ([`SurfaceShader::needs_surface`]).
    pub surface: Option<&'a Surface<R>>,
    /// Bit i set: lane i shows this material (other lanes are computed and
    /// discarded, so they only need to stay finite).
    pub lanes: u32,
    /// The packet's shadow factors, one per scene light (1 for a light
    /// without a shadow map), looked up once for every lane a triangle
    /// covers, when the shading pass shades the packet's materials one
    /// after the other; `None`: each shader looks its lanes up
    /// ([`ShadeInput::light_visibility`]).
    pub shadow_factors: Option<&'a [R]>,
}

impl<'a, R: Real> ShadeInput<'a, R> {
    /// The local shading frame (normal +Z). Its tangent follows the mesh's
    /// uv tangents when the shader asked for the surface and the mesh has
    /// uvs; otherwise it is some tangent orthogonal to the normal (fine for
    /// isotropic models). Built here, inside the shader, rather than by the
    /// shading pass: passed through memory across the dynamic call it cost
    /// more than the dozen instructions that compute it.
    #[inline(always)]
    pub(crate) fn frame(&self) -> ShadingFrame<R> {
        match self.surface {
            Some(s) => s.frame,
            None => ShadingFrame::from_normal(self.frag.n),
        }
    }

    /// Light `k`'s shadow factor `shadow` at the lanes of this input, for
    /// `part`, the light's part there: from
    /// [`ShadeInput::shadow_factors`] when the packet has them, else
    /// looked up where `part` is not zero
    /// ([`LightShadow::visibility_where`](crate::shadow::LightShadow::visibility_where)).
    /// Either way `part` × factor is the same bits: a lane's factor does
    /// not depend on the other lanes looked up with it, and where `part`
    /// is zero the factor (finite, in [0, 1]) keeps it zero.
    #[inline(always)]
    pub fn light_visibility(
        &self,
        k: usize,
        shadow: &crate::shadow::LightShadow,
        part: &specula_core::V3<R>,
    ) -> R {
        match self.shadow_factors {
            Some(f) => f[k],
            None => shadow.visibility_where(part, &self.frag.p, &self.frag.n, self.lanes),
        }
    }

    /// The inputs of a batch (no surface): `frags[i]` under `lanes[i]`
    /// ([`PacketShader::shade_batch`]).
    #[inline(always)]
    pub(crate) fn batch(
        frags: &'a [Fragment<R>],
        lanes: &'a [u32],
    ) -> impl Iterator<Item = Self> + 'a {
        frags.iter().zip(lanes).map(|(frag, &lanes)| ShadeInput {
            frag,
            surface: None,
            lanes,
            shadow_factors: None,
        })
    }
}

/// The scene's light, shared by every packet.
#[derive(Clone, Copy, Debug)]
pub struct ShadeEnv<'a> {
    pub lights: &'a [Light],
    /// Uniform environment radiance, if the scene has one.
    pub environment: Option<[f32; 3]>,
    /// The environment map, if the scene has one (then `environment` is
    /// `None`).
    pub env_map: Option<&'a crate::envmap::EnvMap>,
    /// The frame's shadow maps, when some light has shadows: a light's
    /// contribution is multiplied by its factor
    /// ([`crate::shadow::LightShadow::visibility_lanes`]).
    pub shadows: Option<&'a crate::shadow::ShadowMaps>,
    /// Batches of packets may be shaded two packets per AVX-512 register
    /// where the processor has it (`packet_pairs`; the same bits as
    /// f32x8): set by the frame for [`ShadePath::Simd`](crate::frame::ShadePath::Simd).
    pub pair_packets: bool,
}

impl ShadeEnv<'_> {
    /// The environment map's sun's shadow factor at the lanes of `input`,
    /// for `part`, its part of the light there (1 where that is zero, or
    /// when the sun has no shadow map).
    #[inline(always)]
    pub(crate) fn sun_visibility<R: Real>(&self, input: &ShadeInput<R>, part: &Rgb<R>) -> R {
        match self.shadows.and_then(crate::shadow::ShadowMaps::sun) {
            Some(s) => s.visibility_where(part, &input.frag.p, &input.frag.n, input.lanes),
            None => R::ONE,
        }
    }

    /// `map`'s [`EnvMap::irradiance_over_pi`](crate::envmap::EnvMap::irradiance_over_pi)
    /// at unit world normal `n` of the lanes of `input`, its sun's part
    /// shadowed (`ShadeEnv::sun_visibility`).
    #[inline(always)]
    pub fn map_irradiance_over_pi<R: Real>(
        &self,
        map: &crate::envmap::EnvMap,
        input: &ShadeInput<R>,
        n: specula_core::V3<R>,
    ) -> Rgb<R> {
        map.irradiance_over_pi_shadowed(n, |part| self.sun_visibility(input, part))
    }
}

/// A light a shader cannot light with ([`PacketShader::check_lights`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("light {} is {why}", .light + 1)]
pub struct LightRefusal {
    /// The light's index in the scene's list (the message counts from 1).
    pub light: usize,
    /// Why, as the message goes on after "light N is".
    pub why: String,
}

/// A shader written once over the lane type; see the module docs.
pub trait PacketShader: Debug + Send + Sync + 'static {
    /// Outgoing radiance toward the eye in the lanes of `input.lanes`.
    fn shade<R: Real>(&self, input: &ShadeInput<R>, env: &ShadeEnv) -> Rgb<R>;

    /// [`PacketShader::shade`] of several packets of this material
    /// (`out[i]` for `frags[i]` under `lanes[i]`), none of them with a
    /// surface. A shader whose work per call does not depend on the packet
    /// (a model's dispatch, its constants) may do that once here.
    #[inline(always)]
    fn shade_batch<R: Real>(
        &self,
        frags: &[Fragment<R>],
        lanes: &[u32],
        env: &ShadeEnv,
        out: &mut [Rgb<R>],
    ) {
        for (input, out) in ShadeInput::batch(frags, lanes).zip(out) {
            *out = self.shade(&input, env);
        }
    }

    /// [`PacketShader::shade_batch`] in f32x8, the entry the shading pass
    /// calls: a shader may take a wider path there (`Lit`'s packet pairs).
    #[inline(always)]
    fn shade_batch_x8(
        &self,
        frags: &[Fragment<f32x8>],
        lanes: &[u32],
        env: &ShadeEnv,
        out: &mut [Rgb<f32x8>],
    ) {
        self.shade_batch(frags, lanes, env, out)
    }

    /// The shader reads [`ShadeInput::surface`] (uvs, tangents).
    fn needs_surface(&self) -> bool {
        false
    }

    /// Whether the shader can light itself with these lights; called once
    /// when a scene is loaded, so a shader never meets a light it cannot
    /// handle. The error says which light and why.
    fn check_lights(&self, _lights: &[Light]) -> Result<(), LightRefusal> {
        Ok(())
    }

    /// This shader with every texture map it has sampled with `filter`
    /// (`--texture-filter`); `None` when it has no maps to change.
    fn with_texture_filter(&self, _filter: Filter) -> Option<Self>
    where
        Self: Sized,
    {
        None
    }
}

/// The object-safe form of [`PacketShader`] that materials hold.
pub trait SurfaceShader: Debug + Send + Sync + 'static {
    fn shade_x8(&self, input: &ShadeInput<f32x8>, env: &ShadeEnv) -> Rgb<f32x8>;
    fn shade_x1(&self, input: &ShadeInput<f32>, env: &ShadeEnv) -> Rgb<f32>;
    /// [`SurfaceShader::shade_x8`] of several packets in one call (no
    /// surface; `out[i]` for `frags[i]` under `lanes[i]`): see
    /// `ShadeLanes::shade_batch_with`.
    fn shade_x8_batch(
        &self,
        frags: &[Fragment<f32x8>],
        lanes: &[u32],
        env: &ShadeEnv,
        out: &mut [Rgb<f32x8>],
    );
    fn needs_surface(&self) -> bool;
    fn check_lights(&self, lights: &[Light]) -> Result<(), LightRefusal>;
    /// See [`PacketShader::with_texture_filter`].
    fn with_texture_filter(&self, filter: Filter) -> Option<Arc<dyn SurfaceShader>>;
    /// For callers that need the concrete shader back (benchmarks swapping
    /// a model, tests).
    fn as_any(&self) -> &dyn Any;
}

impl<T: PacketShader> SurfaceShader for T {
    fn shade_x8(&self, input: &ShadeInput<f32x8>, env: &ShadeEnv) -> Rgb<f32x8> {
        self.shade(input, env)
    }
    fn shade_x1(&self, input: &ShadeInput<f32>, env: &ShadeEnv) -> Rgb<f32> {
        self.shade(input, env)
    }
    fn shade_x8_batch(
        &self,
        frags: &[Fragment<f32x8>],
        lanes: &[u32],
        env: &ShadeEnv,
        out: &mut [Rgb<f32x8>],
    ) {
        self.shade_batch_x8(frags, lanes, env, out)
    }
    fn needs_surface(&self) -> bool {
        PacketShader::needs_surface(self)
    }
    fn check_lights(&self, lights: &[Light]) -> Result<(), LightRefusal> {
        PacketShader::check_lights(self, lights)
    }
    fn with_texture_filter(&self, filter: Filter) -> Option<Arc<dyn SurfaceShader>> {
        PacketShader::with_texture_filter(self, filter)
            .map(|s| Arc::new(s) as Arc<dyn SurfaceShader>)
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
}

/// The lane types the shading pass runs: picks the matching entry of a
/// `dyn SurfaceShader`.
pub(crate) trait ShadeLanes: Real {
    fn shade_with(
        shader: &dyn SurfaceShader,
        input: &ShadeInput<Self>,
        env: &ShadeEnv,
    ) -> Rgb<Self>;

    /// Several packets of one material, none needing the surface, in one
    /// dynamic call. Per call, a material's shader pays its prologue, the
    /// model's dispatch and its constants (F0, the diffuse colour, α),
    /// so the shading pass hands
    /// it the runs of packets of one material a tile row shows.
    fn shade_batch_with(
        shader: &dyn SurfaceShader,
        frags: &[Fragment<Self>],
        lanes: &[u32],
        env: &ShadeEnv,
        out: &mut [Rgb<Self>],
    );
}

impl ShadeLanes for f32x8 {
    #[inline(always)]
    fn shade_with(s: &dyn SurfaceShader, input: &ShadeInput<Self>, env: &ShadeEnv) -> Rgb<Self> {
        s.shade_x8(input, env)
    }
    #[inline(always)]
    fn shade_batch_with(
        s: &dyn SurfaceShader,
        frags: &[Fragment<Self>],
        lanes: &[u32],
        env: &ShadeEnv,
        out: &mut [Rgb<Self>],
    ) {
        s.shade_x8_batch(frags, lanes, env, out)
    }
}

impl ShadeLanes for f32 {
    #[inline(always)]
    fn shade_with(s: &dyn SurfaceShader, input: &ShadeInput<Self>, env: &ShadeEnv) -> Rgb<Self> {
        s.shade_x1(input, env)
    }
    /// One call a packet: the shading pass does not batch the scalar twin
    /// (a 1-pixel packet pays more for its place in a batch than it saves
    /// of the call), so this only has to be right.
    #[inline(always)]
    fn shade_batch_with(
        s: &dyn SurfaceShader,
        frags: &[Fragment<Self>],
        lanes: &[u32],
        env: &ShadeEnv,
        out: &mut [Rgb<Self>],
    ) {
        for (input, out) in ShadeInput::batch(frags, lanes).zip(out) {
            *out = s.shade_x1(&input, env);
        }
    }
}
