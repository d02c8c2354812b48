//! `unlit`: a surface that shows a constant radiance, whatever the lights.
//! Draws light polygons, and lets GPU-backend authors check geometry
//! (coverage, ids, depth) without any shading model in the way.
//! [`UnlitBase`] is glTF's KHR_materials_unlit: the base colour (factor
//! times texture) shown as it is.

use crate::maps::ColorMap;
use crate::shader::{PacketShader, ShadeEnv, ShadeInput};
use crate::texture::Filter;
use specula_core::{Real, Rgb};

/// Emits `color` × `intensity` (linear RGB radiance) toward the eye.
#[derive(Clone, Debug, PartialEq)]
pub struct Unlit {
    pub color: [f32; 3],
    pub intensity: f32,
}

impl Unlit {
    /// The emitted radiance.
    pub fn radiance(&self) -> [f32; 3] {
        self.color.map(|c| c * self.intensity)
    }
}

impl PacketShader for Unlit {
    #[inline(always)]
    fn shade<R: Real>(&self, _input: &ShadeInput<R>, _env: &ShadeEnv) -> Rgb<R> {
        Rgb::from_f32(self.radiance())
    }
}

/// KHR_materials_unlit: emits the base colour toward the eye, whatever
/// the lights: `color` (linear RGB) times the base colour map's texel
/// where there is one (times the vertex colour where `vertex_color`).
#[derive(Clone, Debug, PartialEq)]
pub struct UnlitBase {
    pub color: [f32; 3],
    pub base_color: Option<ColorMap>,
    /// The surface's vertex colour multiplies it (glTF's COLOR_0).
    pub vertex_color: bool,
}

impl PacketShader for UnlitBase {
    #[inline(always)]
    fn shade<R: Real>(&self, input: &ShadeInput<R>, _env: &ShadeEnv) -> Rgb<R> {
        let c = Rgb::from_f32(self.color);
        let c = match &self.base_color {
            Some(map) => c.mul_elem(map.sample(input)),
            None => c,
        };
        match (self.vertex_color, input.surface) {
            (true, Some(s)) => c.mul_elem(s.color),
            _ => c,
        }
    }

    fn needs_surface(&self) -> bool {
        self.base_color.is_some() || self.vertex_color
    }

    fn with_texture_filter(&self, filter: Filter) -> Option<UnlitBase> {
        let mut u = self.clone();
        u.base_color.as_mut()?.sampler.filter = filter;
        Some(u)
    }
}
