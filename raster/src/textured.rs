//! Physically based models whose base colour is multiplied by an image
//! (`base_color_texture`), and the [`ColorMap`] every shader with such a
//! map uses.
//!
//! The core models take one base colour per material, so the texture is
//! applied around them, exactly:
//! - Lambert is linear in its base colour: f(b ⊙ t) = f(b) ⊙ t, so the lit
//!   result is multiplied by the texel ([`TexturedLit::Linear`]);
//! - metallic-roughness is, per channel, a quadratic polynomial in its
//!   base colour (F0 = mix(0.04, b, metallic) enters F linearly, and the
//!   diffuse lobe is (1 − F)(1 − metallic) b/π; its albedo is F0·A + B +
//!   (1 − F0)(1 − metallic) b (1 − C)). Three lit results at b = 0, ½, 1
//!   fix the polynomial; it is evaluated at base_color ⊙ texel
//!   ([`TexturedLit::Quadratic`], three times the shading cost). A test
//!   checks it against the model built with that base colour, so a change
//!   that breaks the quadratic shape fails there.

use crate::lit::Lit;
use crate::shader::{PacketShader, ShadeEnv, ShadeInput};
use crate::texture::{Sampler, Texture};
use specula_core::light::Light;
use specula_core::models::MetallicRoughness;
use specula_core::{Model, Real, Rgb, V3};
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

/// A lit model with a base-colour map; see the module docs.
#[derive(Clone, Debug, PartialEq)]
#[allow(clippy::large_enum_variant)] // one per material, built once
pub enum TexturedLit {
    /// The model is linear in its base colour (Lambert).
    Linear { lit: Lit, map: ColorMap },
    /// Metallic-roughness: the model at base colour 0, ½ and 1, and the
    /// material's base colour.
    Quadratic {
        base_color: [f32; 3],
        at: [Lit; 3],
        map: ColorMap,
    },
}

impl TexturedLit {
    /// The textured form of `model`, or `None` if the model has no base
    /// colour the map can multiply.
    pub fn new(model: Model, map: ColorMap) -> Option<TexturedLit> {
        match model {
            Model::Lambert(_) => Some(TexturedLit::Linear {
                lit: Lit { model },
                map,
            }),
            Model::MetallicRoughness(m) => {
                let at = |b: f32| Lit {
                    model: Model::MetallicRoughness(MetallicRoughness {
                        base_color: [b; 3],
                        ..m.clone()
                    }),
                };
                Some(TexturedLit::Quadratic {
                    base_color: m.base_color,
                    at: [at(0.0), at(0.5), at(1.0)],
                    map,
                })
            }
            _ => None,
        }
    }
}

impl PacketShader for TexturedLit {
    #[inline(always)]
    fn shade<R: Real>(&self, input: &ShadeInput<R>, env: &ShadeEnv) -> Rgb<R> {
        match self {
            TexturedLit::Linear { lit, map } => lit.shade(input, env).mul_elem(map.sample(input)),
            TexturedLit::Quadratic {
                base_color,
                at,
                map,
            } => {
                let t = Rgb::from_f32(*base_color).mul_elem(map.sample(input));
                let f0 = at[0].shade(input, env);
                let fh = at[1].shade(input, env);
                let f1 = at[2].shade(input, env);
                // q(t) = f0 + b t + c t² through (0, f0), (½, fh), (1, f1).
                let b = fh * R::splat(4.0) - f0 * R::splat(3.0) - f1;
                let c = (f0 + f1) * R::splat(2.0) - fh * R::splat(4.0);
                f0 + (b + c.mul_elem(t)).mul_elem(t)
            }
        }
    }

    fn needs_surface(&self) -> bool {
        true
    }

    fn check_lights(&self, lights: &[Light]) -> Result<(), String> {
        match self {
            TexturedLit::Linear { lit, .. } => lit.check_lights(lights),
            TexturedLit::Quadratic { at, .. } => at[0].check_lights(lights),
        }
    }
}
