//! Whole material models: compositions of the term functions in `fresnel`,
//! `ndf`, `masking` and `diffuse`. A model adds no formula of its own.

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
