//! The Lambertian material.

use crate::brdf::{Brdf, Outgoing};
use crate::diffuse::f_lambert;
use crate::light::PolygonLocal;
use crate::ltc::form_factor;
use crate::real::Real;
use crate::vec3::{Rgb, V3};

/// A perfectly diffuse reflector with albedo `base_color`.
#[derive(Clone, Debug, PartialEq)]
pub struct Lambert {
    pub base_color: [f32; 3],
}

impl Brdf for Lambert {
    type Prepared<R: Real> = Outgoing<R>;
    type PolygonPrepared<R: Real> = Rgb<R>;
    const POLYGON_LIGHTS: bool = true;

    #[inline(always)]
    fn prepare<R: Real>(&self, wo: V3<R>) -> Outgoing<R> {
        Outgoing::new(wo)
    }

    #[inline(always)]
    fn f_local<R: Real>(&self, p: &Outgoing<R>, wi: V3<R>) -> Rgb<R> {
        let above = wi.z.gt(R::ZERO) & p.above;
        Rgb::select(
            above,
            f_lambert(Rgb::from_f32(self.base_color)),
            Rgb::zero(),
        )
    }

    #[inline(always)]
    fn albedo_local<R: Real>(&self, p: &Outgoing<R>) -> Rgb<R> {
        // ∫ (ρ/π) cos θi dωi = ρ exactly.
        Rgb::select(p.above, Rgb::from_f32(self.base_color), Rgb::zero())
    }

    /// ρ where the view is above the horizon, else 0.
    #[inline(always)]
    fn prepare_polygons<R: Real>(&self, p: &Outgoing<R>) -> Rgb<R> {
        Rgb::select(p.above, Rgb::from_f32(self.base_color), Rgb::zero())
    }

    /// ∫ (ρ/π) cos θi dωi over the polygon = ρ F, F the exact form factor
    /// (ltc/polygon.rs): the LTC of a Lambertian lobe is the identity.
    #[inline(always)]
    fn polygon_local_with<R: Real>(
        &self,
        _p: &Outgoing<R>,
        rho: &Rgb<R>,
        poly: &PolygonLocal<R>,
    ) -> Rgb<R> {
        *rho * form_factor(poly.vertices(), poly.two_sided)
    }
}
