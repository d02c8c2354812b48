//! `unlit`: a surface that shows a constant radiance, whatever the lights.
//! Draws light polygons, and lets GPU-backend authors check geometry
//! (coverage, ids, depth) without any shading model in the way.

use crate::shader::{PacketShader, ShadeEnv, ShadeInput};
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
