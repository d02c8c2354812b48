//! Punctual lights.

/// A light as the shading pass uses it (world space, linear RGB).
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Radiant intensity I (W/sr) at `position`; irradiance I / d² (inverse square).
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
    },
    /// Irradiance E (W/m²) on a surface facing the light; `to_light` is the
    /// unit direction from the scene toward the light.
    Directional {
        to_light: [f32; 3],
        irradiance: [f32; 3],
    },
}
