//! A light's shadow settings: the filter, the map size, the biases and
//! the filter's sizes, with the checks that name the field at fault, and
//! what they cost (faces, bytes, how far a lookup reads).

use super::cascades::MAX_CASCADES;
use glam::Vec3;
use specula_core::light::Light;

/// How a light's shadow is filtered.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShadowFilter {
    /// One depth comparison at the nearest texel.
    #[default]
    Hard,
    /// Percentage-closer filtering: the mean of bilinear depth comparisons
    /// over a square of `filter_radius` texels.
    Pcf,
    /// Percentage-closer soft shadows: a blocker search, the penumbra
    /// width from the light's size, then PCF over that width.
    Pcss,
}

/// One light's shadow settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowSettings {
    pub filter: ShadowFilter,
    /// Map side in texels (each cube face's for point lights).
    pub map_size: u32,
    /// Depth offset toward the light, in texels at the shaded point.
    pub bias: f32,
    /// Offset of the shaded point along its normal, in texels at the
    /// point (times 1 + the filter radius).
    pub normal_bias: f32,
    /// PCF half-width in texels.
    pub filter_radius: f32,
    /// PCSS: the light's diameter in world units (directional lights: the
    /// tangent of its angular diameter).
    pub light_size: f32,
    /// Directional lights: maps along the view's depth (1..=4), each
    /// `map_size` a side (`cascade_splits`); 1 for other lights.
    pub cascades: u32,
}

/// Largest accepted map side.
pub const MAX_MAP_SIZE: u32 = 8192;

impl Default for ShadowSettings {
    fn default() -> Self {
        ShadowSettings {
            filter: ShadowFilter::Hard,
            map_size: 1024,
            bias: 1.0,
            normal_bias: 1.0,
            filter_radius: 1.5,
            light_size: 0.1,
            cascades: 1,
        }
    }
}

/// Why [`ShadowSettings::check`] refused a light's settings; the message
/// names the scene field at fault.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ShadowSettingsError {
    #[error("shadow_map_size: must be 1..={MAX_MAP_SIZE} texels, got {0}")]
    MapSize(u32),
    #[error("cascades: must be 1..={MAX_CASCADES}, got {0}")]
    Cascades(u32),
    #[error("{field}: must be a finite number in [0, {max}], got {got}")]
    OutOfRange {
        field: &'static str,
        max: f32,
        got: f32,
    },
}

impl ShadowSettings {
    /// Checks every field; the error names the field.
    pub fn check(&self) -> Result<(), ShadowSettingsError> {
        if !(1..=MAX_MAP_SIZE).contains(&self.map_size) {
            return Err(ShadowSettingsError::MapSize(self.map_size));
        }
        if !(1..=MAX_CASCADES).contains(&self.cascades) {
            return Err(ShadowSettingsError::Cascades(self.cascades));
        }
        let fields = [
            ("bias", self.bias, 1e3),
            ("normal_bias", self.normal_bias, 1e3),
            ("filter_radius", self.filter_radius, 64.0),
            ("light_size", self.light_size, 1e9),
        ];
        for (field, got, max) in fields {
            if !(0.0..=max).contains(&got) {
                return Err(ShadowSettingsError::OutOfRange { field, max, got });
            }
        }
        Ok(())
    }

    /// Faces of a light's map: 6 for a point light, 1 otherwise.
    pub(crate) fn faces(&self, light: &Light) -> u32 {
        match light {
            Light::Point { .. } | Light::Polygon { .. } => 6,
            Light::Directional { .. } => self.cascades,
            _ => 1,
        }
    }

    /// Bytes of a light's maps (a frame's depth and id per texel, the
    /// linear depth kept for lookups, and PCF's depth bounds per texel).
    pub fn bytes(&self, light: &Light) -> u64 {
        let side = (self.map_size as u64).div_ceil(64) * 64;
        let bounds = self
            .pcf_window()
            .map_or(0, |_| (self.map_size as u64).pow(2) * 8);
        (side * side * 12 + bounds) * self.faces(light) as u64
    }

    /// Texels a lookup may read away from its centre texel.
    pub(crate) fn reach(&self) -> f32 {
        match self.filter {
            ShadowFilter::Hard => 1.0,
            ShadowFilter::Pcf => self.filter_radius + 2.0,
            ShadowFilter::Pcss => self.filter_radius.max(PCSS_MAX_RADIUS) + 2.0,
        }
    }
}

/// Largest window side of a PCF face's depth bounds (filter radii up to
/// 7 texels); wider filters always read their taps.
const MAX_PCF_WINDOW: u32 = 17;

impl ShadowSettings {
    /// PCF: the side of the windows of a face's depth bounds, ⌈2r⌉ + 2
    /// for a filter radius r, since the taps at u − r, u and u + r read
    /// texels ⌊u − r⌋ to ⌊u + r⌋ + 1, at most ⌈2r⌉ + 2 of them. `None`
    /// for other filters and wider PCF.
    pub(crate) fn pcf_window(&self) -> Option<u32> {
        let window = (2.0 * self.filter_radius).ceil() as u32 + 2;
        (self.filter == ShadowFilter::Pcf && window <= MAX_PCF_WINDOW).then_some(window)
    }
}

/// Largest PCSS filter half-width in texels.
pub(super) const PCSS_MAX_RADIUS: f32 = 24.0;

/// A polygon's vertex mean, unit normal (Newell's, toward the side a
/// counter-clockwise polygon faces) and area, or `None` when it has no
/// area.
pub(crate) fn polygon_shape(vertices: &[[f32; 3]]) -> Option<(Vec3, Vec3, f32)> {
    let v: Vec<Vec3> = vertices.iter().map(|p| Vec3::from(*p)).collect();
    if v.len() < 3 {
        return None;
    }
    let centre = v.iter().copied().sum::<Vec3>() / v.len() as f32;
    let twice = (0..v.len())
        .map(|i| (v[i] - centre).cross(v[(i + 1) % v.len()] - centre))
        .sum::<Vec3>();
    let area = 0.5 * twice.length();
    (area > 0.0 && area.is_finite()).then(|| (centre, twice.normalize(), area))
}

/// The PCSS light size of a polygon light: the diameter of the disk of
/// the polygon's area (0 for a polygon without area).
pub fn polygon_light_size(vertices: &[[f32; 3]]) -> f32 {
    polygon_shape(vertices).map_or(0.0, |(_, _, a)| 2.0 * (a / std::f32::consts::PI).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polygon_light_size_is_the_equal_area_disk() {
        let square = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 0.0, 2.0],
            [0.0, 0.0, 2.0],
        ];
        let d = polygon_light_size(&square);
        assert!(
            (d - 2.0 * (4.0 / std::f32::consts::PI).sqrt()).abs() < 1e-5,
            "{d}"
        );
        assert_eq!(polygon_light_size(&[[0.0; 3]; 3]), 0.0);
    }
}
