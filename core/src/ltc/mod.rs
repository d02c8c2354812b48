//! Polygonal area lights with linearly transformed cosines \[Heitz16\].
//!
//! - `polygon`: the clamped-cosine integral over a polygon clipped to the
//!   upper hemisphere, in lane arithmetic (the runtime's geometry);
//! - `reference`: the project's own converged integration of any BRDF over
//!   a polygon's solid angle (f64), what the LTC approximation is measured
//!   against and what `area_lights = "reference"` renders.

pub mod coat;
mod file;
pub mod ggx;
mod polygon;
pub mod reference;

pub use polygon::{form_factor, form_factor_signed, sided};
