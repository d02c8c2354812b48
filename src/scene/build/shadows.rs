//! The shadow fields of a `[[light]]`: the filter, the map size, the
//! biases and the filter's sizes, checked (with shadows off too) and
//! turned into the rasterizer's shadow settings.

use super::super::desc::{LightDesc, ShadowsDesc};
use super::BuildError;
use specula_raster::shadow::{ShadowFilter, ShadowSettings};

/// Light `i`'s shadow settings, checked (`None`: no shadows).
pub(super) fn build_shadow(i: usize, l: &LightDesc) -> Result<Option<ShadowSettings>, BuildError> {
    let cascades = match l {
        LightDesc::Directional { cascades, .. } => *cascades,
        _ => 1,
    };
    let (shadows, map_size, bias, normal_bias, filter_radius, light_size) = match l {
        LightDesc::Point {
            shadows,
            shadow_map_size,
            bias,
            normal_bias,
            filter_radius,
            light_size,
            ..
        }
        | LightDesc::Spot {
            shadows,
            shadow_map_size,
            bias,
            normal_bias,
            filter_radius,
            light_size,
            ..
        }
        | LightDesc::Directional {
            shadows,
            shadow_map_size,
            bias,
            normal_bias,
            filter_radius,
            light_size,
            ..
        } => (
            *shadows,
            *shadow_map_size,
            *bias,
            *normal_bias,
            *filter_radius,
            *light_size,
        ),
        LightDesc::Polygon {
            shadows,
            shadow_map_size,
            bias,
            normal_bias,
            filter_radius,
            ..
        } => (
            *shadows,
            *shadow_map_size,
            *bias,
            *normal_bias,
            *filter_radius,
            // Not a field of polygon lights: derived below, after the
            // check (a polygon up to the world bound has a size past
            // the field's range).
            0.0,
        ),
    };
    let filter = match shadows {
        ShadowsDesc::None | ShadowsDesc::Hard => ShadowFilter::Hard,
        ShadowsDesc::Pcf => ShadowFilter::Pcf,
        ShadowsDesc::Pcss => ShadowFilter::Pcss,
    };
    let mut s = ShadowSettings {
        filter,
        map_size,
        bias,
        normal_bias,
        filter_radius,
        light_size,
        cascades,
    };
    // Checked with shadows off too: a value out of range is a mistake
    // whether or not it is used.
    s.check().map_err(|source| BuildError::Shadows {
        table: format!("light[{i}]"),
        source,
    })?;
    if let LightDesc::Polygon { vertices, .. } = l {
        s.light_size = specula_raster::shadow::polygon_light_size(vertices);
    }
    Ok((shadows != ShadowsDesc::None).then_some(s))
}
