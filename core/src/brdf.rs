//! The interface every material model implements, and the dispatch from the
//! runtime `Material` value to monomorphized kernels.

use crate::models::{Lambert, MetallicRoughness, Microfacet};
use crate::real::Real;
use crate::vec3::{Rgb, V3};

/// Smallest α any model passes to an NDF: below it D(m) is a spike narrower
/// than f32 can resolve at the peak. (Microfacet inputs are clamped to it
/// with a warning where the scene is read.)
pub const ALPHA_MIN: f32 = 1e-3;

/// The angles every microfacet model starts from, per lane.
#[derive(Clone, Copy, Debug)]
pub struct HalfAngles<R: Real> {
    /// n·wi and n·wo, floored at 1e-7 (see `above`).
    pub cos_i: R,
    pub cos_o: R,
    /// Both directions strictly above the horizon; other lanes must be
    /// zeroed by the caller (the floors above only keep them finite).
    pub above: R::Mask,
    /// cos²θh and sin²θh of the half vector, from the unnormalized sum
    /// (ndf.rs explains why); both carry the same `rcp` rounding (≤ 4e-7),
    /// so their ratio, which shapes D, is exact.
    pub cos2_h: R,
    pub sin2_h: R,
    /// cos θd = wi·h, the Fresnel angle.
    pub cos_d: R,
}

impl<R: Real> HalfAngles<R> {
    #[inline(always)]
    pub fn new(n: V3<R>, wi: V3<R>, wo: V3<R>) -> HalfAngles<R> {
        let cos_i = n.dot(wi);
        let cos_o = n.dot(wo);
        let above = cos_i.gt(R::ZERO) & cos_o.gt(R::ZERO);
        let tiny = R::splat(1e-7);
        // s = wi + wo is zero only for opposite directions, which `above`
        // excludes. For unit wi, wo: |s|² = 2 (1 + wi·wo), so
        // cos θd = wi·s / |s| = |s| / 2 — no normalized h needed.
        let s = wi + wo;
        let len2 = s.length_squared();
        let inv_len2 = len2.rcp();
        let c = n.dot(s);
        HalfAngles {
            cos_i: cos_i.max(tiny),
            cos_o: cos_o.max(tiny),
            above,
            cos2_h: c * c * inv_len2,
            sin2_h: n.cross(s).length_squared() * inv_len2,
            cos_d: len2 * len2.rsqrt() * R::HALF,
        }
    }
}

/// A BRDF in any frame: `n` the unit shading normal, `wi` toward the light,
/// `wo` toward the viewer, both unit length and pointing away from the surface.
pub trait Brdf: Send + Sync {
    /// The BRDF value f(wi, wo), no cosine folded in; zero when either
    /// direction is at or below the horizon.
    fn f<R: Real>(&self, n: V3<R>, wi: V3<R>, wo: V3<R>) -> Rgb<R>;

    /// f(wi, wo) · max(0, n·wi): the reflected radiance per unit radiance
    /// arriving from `wi`.
    #[inline(always)]
    fn f_cos<R: Real>(&self, n: V3<R>, wi: V3<R>, wo: V3<R>) -> Rgb<R> {
        self.f(n, wi, wo) * n.dot(wi).max(R::ZERO)
    }

    /// Directional albedo ρ(wo) = ∫ f(wi, wo) cos θi dωi over the hemisphere:
    /// the reflected radiance under a uniform white environment of radiance 1.
    fn albedo<R: Real>(&self, n: V3<R>, wo: V3<R>) -> Rgb<R>;
}

/// A material model, chosen at run time. Adding a model means adding a variant
/// here and a `Brdf` impl; the rasterizer only sees [`BrdfVisitor`].
#[derive(Clone, Debug, PartialEq)]
pub enum Model {
    Lambert(Lambert),
    MetallicRoughness(MetallicRoughness),
    Microfacet(Microfacet),
}

/// A material: a model plus the properties the rasterizer needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub model: Model,
    /// Back faces are drawn (and shaded with the normal flipped toward the
    /// viewer) instead of culled.
    pub double_sided: bool,
}

/// Code generic over the model: `Model::visit` calls `visit` with the concrete
/// BRDF type, so the per-light loop inside is monomorphized per model and has
/// no dispatch of its own.
pub trait BrdfVisitor {
    type Output;
    fn visit<B: Brdf>(self, brdf: &B) -> Self::Output;
}

impl Model {
    #[inline(always)]
    pub fn visit<V: BrdfVisitor>(&self, v: V) -> V::Output {
        match self {
            Model::Lambert(m) => v.visit(m),
            Model::MetallicRoughness(m) => v.visit(m),
            Model::Microfacet(m) => v.visit(m),
        }
    }

    /// The BRDF value f(wi, wo) for one direction pair (any precision).
    pub fn f<R: Real>(&self, n: V3<R>, wi: V3<R>, wo: V3<R>) -> Rgb<R> {
        struct F<R: Real>(V3<R>, V3<R>, V3<R>);
        impl<R: Real> BrdfVisitor for F<R> {
            type Output = Rgb<R>;
            fn visit<B: Brdf>(self, b: &B) -> Rgb<R> {
                b.f(self.0, self.1, self.2)
            }
        }
        self.visit(F(n, wi, wo))
    }
}
