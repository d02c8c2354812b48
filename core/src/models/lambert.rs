//! The Lambertian material. Its base colour is a lane parameter.

use crate::brdf::{Brdf, LaneParams, Outgoing};
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

/// Lambert's parameters per lane.
#[derive(Clone, Copy, Debug)]
pub struct LambertLaneParams<R: Real> {
    /// Albedo ρ, linear RGB.
    pub base_color: Rgb<R>,
}

impl<R: Real> LaneParams<R> for LambertLaneParams<R> {
    #[inline(always)]
    fn base_color_mut(&mut self) -> Option<&mut Rgb<R>> {
        Some(&mut self.base_color)
    }
}

/// A Lambertian pixel: ρ, zero where the view is below the horizon (so
/// every lobe below needs no mask of its own for it).
#[derive(Clone, Copy)]
pub struct LambertPrepared<R: Real> {
    pub(crate) rho: Rgb<R>,
}

impl Brdf for Lambert {
    type Params<R: Real> = LambertLaneParams<R>;
    type Pixel<R: Real> = LambertLaneParams<R>;
    type Prepared<R: Real> = LambertPrepared<R>;
    type PolygonPrepared<R: Real> = ();
    const POLYGON_LIGHTS: bool = true;

    #[inline(always)]
    fn params<R: Real>(&self) -> LambertLaneParams<R> {
        LambertLaneParams {
            base_color: Rgb::from_f32(self.base_color),
        }
    }

    /// The parameters themselves: nothing to derive before the view.
    #[inline(always)]
    fn pixel<R: Real>(&self, params: &LambertLaneParams<R>) -> LambertLaneParams<R> {
        *params
    }

    #[inline(always)]
    fn params_lane<R: Real>(p: &LambertLaneParams<R>, i: usize) -> LambertLaneParams<f64> {
        LambertLaneParams {
            base_color: p.base_color.lane(i),
        }
    }

    #[inline(always)]
    fn prepare_with<R: Real>(
        &self,
        params: &LambertLaneParams<R>,
        wo: V3<R>,
    ) -> LambertPrepared<R> {
        let o = Outgoing::new(wo);
        LambertPrepared {
            rho: Rgb::select(o.above, params.base_color, Rgb::zero()),
        }
    }

    #[inline(always)]
    fn f_local<R: Real>(&self, p: &LambertPrepared<R>, wi: V3<R>) -> Rgb<R> {
        Rgb::select(wi.z.gt(R::ZERO), f_lambert(p.rho), Rgb::zero())
    }

    #[inline(always)]
    fn albedo_local<R: Real>(&self, p: &LambertPrepared<R>) -> Rgb<R> {
        // ∫ (ρ/π) cos θi dωi = ρ exactly.
        p.rho
    }

    #[inline(always)]
    fn prepare_polygons<R: Real>(&self, _p: &LambertPrepared<R>) {}

    /// ∫ (ρ/π) cos θi dωi over the polygon = ρ F, F the exact form factor
    /// (ltc/polygon.rs): the LTC of a Lambertian lobe is the identity.
    #[inline(always)]
    fn polygon_local_with<R: Real>(
        &self,
        p: &LambertPrepared<R>,
        _pp: &(),
        poly: &PolygonLocal<R>,
    ) -> Rgb<R> {
        p.rho * form_factor(poly.vertices(), poly.two_sided)
    }
}
