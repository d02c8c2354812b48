//! `[[light]]`: each light's fields checked and turned into the
//! renderer's light (visible polygon lights also add their geometry and
//! material), with its shadow settings (`shadows.rs`).

use super::super::desc::{AreaLightsDesc, LightDesc};
use super::shadows::build_shadow;
use super::BuildError;
use super::SceneBuilder;
use crate::checks;
use crate::validate::check_point;
use specula_core::light::Light;

impl SceneBuilder<'_> {
    /// `[[light]]`s, in order. Visible polygon lights add their own
    /// geometry and material.
    pub(in crate::scene) fn add_lights(
        &mut self,
        descs: &[LightDesc],
        area: AreaLightsDesc,
    ) -> Result<(), BuildError> {
        for (i, l) in descs.iter().enumerate() {
            let light = self.build_light(i, l, area)?;
            let shadow = build_shadow(i, l)?;
            if let Some(s) = &shadow {
                crate::memory::reserve(&format!("light[{i}]'s shadow maps"), s.bytes(&light))
                    .map_err(BuildError::Memory)?;
            }
            self.data.lights.push(light);
            self.data.shadows.push(shadow);
        }
        if self.data.shadows.iter().all(Option::is_none) {
            self.data.shadows.clear();
        }
        Ok(())
    }

    fn build_light(
        &mut self,
        i: usize,
        l: &LightDesc,
        area: AreaLightsDesc,
    ) -> Result<Light, BuildError> {
        let field = format!("light[{i}]");
        let light = match l {
            LightDesc::Point {
                position,
                intensity,
                range,
                ..
            } => {
                check_point(&format!("{field}.position"), *position)?;
                checks::radiometric(&format!("{field}.intensity"), *intensity)?;
                checks::light_range(&format!("{field}.range"), *range)?;
                Light::Point {
                    position: *position,
                    intensity: *intensity,
                    range: *range,
                }
            }
            LightDesc::Spot {
                position,
                direction,
                intensity,
                inner_cone,
                outer_cone,
                range,
                ..
            } => {
                check_point(&format!("{field}.position"), *position)?;
                let d = crate::validate::direction(&format!("{field}.direction"), *direction)?;
                checks::radiometric(&format!("{field}.intensity"), *intensity)?;
                let (inner, outer) = (inner_cone.to_radians(), outer_cone.to_radians());
                checks::cone_angles(
                    (&format!("{field}.inner_cone"), inner),
                    (&format!("{field}.outer_cone"), outer),
                    &|r| format!("{}°", r.to_degrees()),
                )?;
                checks::light_range(&format!("{field}.range"), *range)?;
                Light::Spot {
                    position: *position,
                    direction: d.to_array(),
                    intensity: *intensity,
                    cos_inner: inner.cos(),
                    cos_outer: outer.cos(),
                    range: *range,
                }
            }
            LightDesc::Directional {
                direction,
                irradiance,
                ..
            } => {
                checks::radiometric(&format!("{field}.irradiance"), *irradiance)?;
                let d = crate::validate::direction(&format!("{field}.direction"), *direction)?;
                Light::Directional {
                    to_light: (-d).to_array(),
                    irradiance: *irradiance,
                }
            }
            LightDesc::Polygon {
                vertices,
                radiance,
                two_sided,
                visible,
                ..
            } => {
                use crate::polygon_light::{add_visible, check_polygon};
                use specula_core::light::AreaMethod;
                for (k, v) in vertices.iter().enumerate() {
                    check_point(&format!("{field}.vertices[{k}]"), *v)?;
                }
                check_polygon(&format!("{field}.vertices"), vertices)?;
                checks::radiometric(&format!("{field}.radiance"), *radiance)?;
                if *visible {
                    let name = format!("light[{i}]");
                    add_visible(
                        &mut self.data,
                        &mut self.materials.list,
                        &name,
                        vertices,
                        *radiance,
                        *two_sided,
                    );
                }
                Light::Polygon {
                    vertices: vertices.clone(),
                    radiance: *radiance,
                    two_sided: *two_sided,
                    method: match area {
                        AreaLightsDesc::Ltc => AreaMethod::Ltc,
                        AreaLightsDesc::Reference => AreaMethod::Reference,
                    },
                }
            }
        };
        // The reference quadrature integrates any model's lobe; only the
        // LTC tables are fitted to some.
        if matches!(
            light,
            Light::Polygon {
                method: specula_core::light::AreaMethod::Ltc,
                ..
            }
        ) {
            crate::polygon_light::check_materials(&self.materials.list)
                .map_err(|source| BuildError::Ltc { field, source })?;
        }
        Ok(light)
    }
}
