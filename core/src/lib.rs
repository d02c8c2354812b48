//! specula-core: lane math and material models, with no I/O.
//!
//! Every term is written once, generic over [`Real`] (f32, f64, f32x8); see
//! `real.rs`. Conventions: shading frame normal +Z, tangent +X, bitangent +Y;
//! directions point away from the surface, `wi` toward the light, `wo` toward
//! the viewer. Citation keys such as `\[Walter07\]` resolve in docs/REFERENCES.md.

#![warn(unreachable_pub)]

pub mod albedo_tables;
mod brdf;
mod diffuse;
pub mod fresnel;
mod ggx_equivalent;
pub mod gtr_lambda;
pub mod kulla_conty;
pub mod light;
pub mod ltc;
pub mod masking;
pub mod models;
pub mod ndf;
pub mod quadrature;
pub mod real;
pub mod sheen;
pub mod small_light;
mod specular_lobe;
pub mod table;
mod vec3;

pub use brdf::{Brdf, BrdfVisitor, EnvLobes, LaneParams, Outgoing, ShadingFrame};
pub use models::Model;
pub use real::{Constant, Mask, Real};
pub use vec3::{Rgb, V3};
pub use wide::f32x8;
