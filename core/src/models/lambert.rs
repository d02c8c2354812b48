//! The Lambertian material.

use crate::brdf::Brdf;
use crate::diffuse::f_lambert;
use crate::real::Real;
use crate::vec3::{Rgb, V3};

/// A perfectly diffuse reflector with albedo `base_color`.
#[derive(Clone, Debug, PartialEq)]
pub struct Lambert {
    pub base_color: [f32; 3],
}

impl Brdf for Lambert {
    #[inline(always)]
    fn f<R: Real>(&self, n: V3<R>, wi: V3<R>, wo: V3<R>) -> Rgb<R> {
        let above = n.dot(wi).gt(R::ZERO) & n.dot(wo).gt(R::ZERO);
        Rgb::select(
            above,
            f_lambert(Rgb::from_f32(self.base_color)),
            Rgb::zero(),
        )
    }

    #[inline(always)]
    fn albedo<R: Real>(&self, n: V3<R>, wo: V3<R>) -> Rgb<R> {
        // ∫ (ρ/π) cos θi dωi = ρ exactly.
        Rgb::select(
            n.dot(wo).gt(R::ZERO),
            Rgb::from_f32(self.base_color),
            Rgb::zero(),
        )
    }
}
