//! `hatching`: the surface drawn with a tonal art map \[Praun01\].
//!
//! 1. The shaded luminance: Y of Σ E max(n·l, 0)/π over the lights plus
//!    the uniform environment or an environment map's E(n)/π (a white
//!    Lambertian surface), clamped to
//!    [0, 1]; the tone to draw is darkness D = 1 − Y.
//! 2. Tone blend: channel 0 of the map is paper (darkness 0) and channel
//!    t + 1 tone t (darkness d_t, increasing). D falls between two
//!    neighbouring channels i and i + 1; they are blended with weights
//!    (1 − w, w), w = (D − d_i)/(d_{i+1} − d_i) (clamped, so darker than
//!    the darkest tone draws the darkest tone). This is Praun et al.'s
//!    6-way blend per pixel: of the six (here tones + 1) weights only the
//!    two neighbours of D are non-zero, so only they are read.
//! 3. Each is read at uv × `scale` with trilinear mip filtering, its level
//!    from the resolve's analytic uv derivatives × `scale` (texture.rs);
//!    since every level of a TAM has the same darkness, the tone holds at
//!    any distance.
//! 4. Colour: ink + (paper − ink) × brightness (brightness 1 is paper).

use crate::lights::for_each_light_shadowed;
use crate::tam::{TamError, TamTexture};
use specula_core::{Real, Rgb};
use specula_raster::texture::{Filter, Sampler, Wrap};
use specula_raster::{PacketShader, ShadeEnv, ShadeInput};
use std::sync::Arc;

/// Rec. 709 luminance weights.
const LUMA: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// The `hatching` shader; see the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct Hatching {
    pub tam: Arc<TamTexture>,
    /// Radiance of ink and of paper (linear RGB).
    pub ink: [f32; 3],
    pub paper: [f32; 3],
    /// Map repeats per unit of uv.
    pub scale: f32,
}

/// The map `hatching` uses when the material names none: 6 tones, 256²
/// down to 16², seed 1, generated once per process (about 0.1 s).
/// A failure is kept as its message (the error itself is not `Clone`).
pub fn builtin_tam() -> Result<Arc<TamTexture>, TamError> {
    static TAM: std::sync::OnceLock<Result<Arc<TamTexture>, String>> = std::sync::OnceLock::new();
    TAM.get_or_init(|| {
        crate::tam::generate(crate::tam::TamParams::new(6, 256, 1))
            .and_then(|tam| TamTexture::from_tam(&tam))
            .map(Arc::new)
            .map_err(|e| e.to_string())
    })
    .clone()
    .map_err(TamError::Layout)
}

/// Maps tile and filter trilinearly.
pub(crate) const TAM_SAMPLER: Sampler = Sampler {
    wrap_u: Wrap::Repeat,
    wrap_v: Wrap::Repeat,
    filter: Filter::Trilinear,
};

impl Hatching {
    /// Luminance of a white Lambertian surface at the packet's lanes.
    #[inline(always)]
    pub(crate) fn luminance<R: Real>(input: &ShadeInput<R>, env: &ShadeEnv) -> R {
        let frag = input.frag;
        let mut e_sum = Rgb::zero();
        for_each_light_shadowed(input, env, |wi, e| {
            e_sum += e * frag.n.dot(wi).max(R::ZERO);
        });
        let mut l = e_sum * R::FRAC_1_PI;
        if let Some(env) = env.environment {
            l += Rgb::from_f32(env);
        }
        if let Some(map) = env.env_map {
            l += env.map_irradiance_over_pi(map, input, frag.n);
        }
        l.x * R::splat(LUMA[0]) + l.y * R::splat(LUMA[1]) + l.z * R::splat(LUMA[2])
    }

    /// Lower channel i (integral) and the weight w of channel i + 1 for
    /// darkness `d` (module docs, step 2).
    #[inline(always)]
    pub(crate) fn tone_pair<R: Real>(&self, d: R) -> (R, R) {
        let dk = &self.tam.darkness;
        let top = dk.len() - 1; // the darkest tone's channel
        let mut i = R::ZERO;
        for &edge in &dk[1..top] {
            i += R::select(d.ge(R::splat(edge as f64)), R::ONE, R::ZERO);
        }
        let d0 = R::gather(dk, i);
        let d1 = R::gather(dk, i + R::ONE);
        let w = ((d - d0) / (d1 - d0)).clamp(R::ZERO, R::ONE);
        (i, w)
    }

    /// Paper brightness of the blended tones at darkness `d` (1 paper, 0
    /// ink) at uv, for tests and the shader.
    #[inline(always)]
    pub(crate) fn brightness<R: Real>(
        &self,
        d: R,
        uv: [R; 2],
        duv_dx: [R; 2],
        duv_dy: [R; 2],
    ) -> R {
        let k = R::splat(self.scale as f64);
        let t = &self.tam.texture;
        let uv = [uv[0] * k, uv[1] * k];
        let lod = t.lod(
            [duv_dx[0] * k, duv_dx[1] * k],
            [duv_dy[0] * k, duv_dy[1] * k],
        );
        let (i, w) = self.tone_pair(d);
        t.sample_channel_blend(&TAM_SAMPLER, uv, lod, i, w)
    }
}

impl PacketShader for Hatching {
    #[inline(always)]
    fn shade<R: Real>(&self, input: &ShadeInput<R>, env: &ShadeEnv) -> Rgb<R> {
        let y = Self::luminance(input, env).clamp(R::ZERO, R::ONE);
        let d = R::ONE - y;
        let b = match input.surface {
            Some(s) => self.brightness(d, s.uv, s.duv_dx, s.duv_dy),
            None => self.brightness(d, [R::ZERO; 2], [R::ZERO; 2], [R::ZERO; 2]),
        };
        let ink = Rgb::from_f32(self.ink);
        ink + (Rgb::from_f32(self.paper) - ink) * b
    }

    fn needs_surface(&self) -> bool {
        true
    }
}
