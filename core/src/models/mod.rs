//! Whole material models: compositions of the term functions in `fresnel`,
//! `ndf`, `masking` and `diffuse`. A model adds no formula of its own.
//! [`Model`] chooses one at run time.

pub mod disney;
pub mod gltf;
mod lambert;
mod metallic_roughness;
pub mod microfacet;

pub use disney::{Disney, DisneyLaneParams, DisneyParams};
pub use gltf::{Gltf, GltfFresnel, GltfLaneParams, GltfParams};
pub use lambert::{Lambert, LambertLaneParams};
pub use metallic_roughness::{MetallicRoughness, MetallicRoughnessLaneParams};
pub use microfacet::{
    Fresnel, GtrLambda, Microfacet, MicrofacetLaneParams, MicrofacetParams, Ndf, Smith,
};

use crate::brdf::{Brdf, BrdfVisitor, ShadingFrame};
use crate::real::Real;
use crate::vec3::{Rgb, V3};

/// A material model, chosen at run time. Adding a model means adding a variant
/// here and a `Brdf` impl; the rasterizer only sees [`BrdfVisitor`].
#[derive(Clone, Debug, PartialEq)]
// A scene holds a handful of materials, each built once: the size of the
// largest variant (microfacet's tables) costs nothing worth a box.
#[allow(clippy::large_enum_variant)]
pub enum Model {
    Lambert(Lambert),
    MetallicRoughness(MetallicRoughness),
    Microfacet(Microfacet),
    Disney(Disney),
    Gltf(Gltf),
}

impl Model {
    #[inline(always)]
    pub fn visit<V: BrdfVisitor>(&self, v: V) -> V::Output {
        match self {
            Model::Lambert(m) => v.visit(m),
            Model::MetallicRoughness(m) => v.visit(m),
            Model::Microfacet(m) => v.visit(m),
            Model::Disney(m) => v.visit(m),
            Model::Gltf(m) => v.visit(m),
        }
    }

    /// The BRDF value f(wi, wo) for one direction pair (any precision),
    /// directions in the frame's space.
    pub fn f_in<R: Real>(&self, frame: &ShadingFrame<R>, wi: V3<R>, wo: V3<R>) -> Rgb<R> {
        struct F<'a, R: Real>(&'a ShadingFrame<R>, V3<R>, V3<R>);
        impl<R: Real> BrdfVisitor for F<'_, R> {
            type Output = Rgb<R>;
            fn visit<B: Brdf>(self, b: &B) -> Rgb<R> {
                b.f_in(self.0, self.1, self.2)
            }
        }
        self.visit(F(frame, wi, wo))
    }

    /// Whether the model integrates polygon lights.
    pub fn polygon_lights(&self) -> bool {
        struct P;
        impl BrdfVisitor for P {
            type Output = bool;
            fn visit<B: Brdf>(self, _: &B) -> bool {
                B::POLYGON_LIGHTS
            }
        }
        self.visit(P)
    }

    /// The model's name as scene files write it.
    pub fn name(&self) -> &'static str {
        match self {
            Model::Lambert(_) => "lambert",
            Model::MetallicRoughness(_) => "metallic_roughness",
            Model::Microfacet(_) => "microfacet",
            Model::Disney(_) => "disney",
            Model::Gltf(_) => "gltf",
        }
    }
}
