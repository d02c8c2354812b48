//! Texture maps that fill a material's parameters per pixel.
//!
//! A shader builds its parameters per lane in two steps: the material's
//! constants, broadcast ([`specula_core::Brdf::params`]), then each map
//! the material has overwrites its slot lane by lane ([`ParamMaps::fill`]).
//! A material without maps skips the second step, and the shading pass
//! then hands it whole runs of packets at once (shading_pass.rs).

use crate::shader::ShadeInput;
use crate::texture::{Sampler, Texture};
use specula_core::{LaneParams, Real, Rgb, V3};
use std::sync::Arc;

/// An image multiplying a colour, sampled at the surface's uv.
#[derive(Clone, Debug, PartialEq)]
pub struct ColorMap {
    /// At least three channels (RGB, linear).
    pub texture: Arc<Texture>,
    pub sampler: Sampler,
}

impl ColorMap {
    /// The map's RGB at the packet's uv (its filter's level from the
    /// resolve's analytic derivatives); white where the shader got no
    /// surface.
    #[inline(always)]
    pub fn sample<R: Real>(&self, input: &ShadeInput<R>) -> Rgb<R> {
        match input.surface {
            Some(s) => {
                let [r, g, b] = self.texture.sample(&self.sampler, s.uv, s.duv_dx, s.duv_dy);
                V3::new(r, g, b)
            }
            None => Rgb::splat(R::ONE),
        }
    }
}

/// The maps of one material, one optional map per parameter slot of
/// [`LaneParams`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParamMaps {
    /// Multiplies the base colour.
    pub base_color: Option<ColorMap>,
}

impl ParamMaps {
    /// No maps: the material's parameters are its constants.
    pub fn is_empty(&self) -> bool {
        self.base_color.is_none()
    }

    /// The name of the first map whose slot `params` does not have, as
    /// scene files write it; `None` when every map has its slot. Checked
    /// once when a material is built, so [`ParamMaps::fill`] never drops
    /// a map.
    pub(crate) fn unsupported<P: LaneParams<f32>>(&self, mut params: P) -> Option<&'static str> {
        if self.base_color.is_some() && params.base_color_mut().is_none() {
            return Some("base_color_texture");
        }
        None
    }

    /// Overwrites the slots of `params` that have maps, per lane, at the
    /// packet's uv.
    #[inline(always)]
    pub fn fill<R: Real, P: LaneParams<R>>(&self, input: &ShadeInput<R>, params: &mut P) {
        if let Some(map) = &self.base_color {
            if let Some(c) = params.base_color_mut() {
                *c = c.mul_elem(map.sample(input));
            }
        }
    }
}
