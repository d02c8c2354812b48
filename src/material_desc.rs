//! Materials as users write them: TOML tables in scene files and JSON objects
//! in `specula eval` share these serde types, so the field names are one
//! contract (documented in the README).

use serde::Deserialize;
use specula_core::models::{Lambert, MetallicRoughness};
use specula_core::{Material, Model};

/// One material description; `model` selects the variant.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(tag = "model", rename_all = "snake_case")]
pub enum MaterialDesc {
    Lambert(LambertDesc),
    MetallicRoughness(MetallicRoughnessDesc),
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LambertDesc {
    pub base_color: [f32; 3],
    #[serde(default)]
    pub double_sided: bool,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MetallicRoughnessDesc {
    pub base_color: [f32; 3],
    pub roughness: f32,
    #[serde(default)]
    pub metallic: f32,
    #[serde(default)]
    pub double_sided: bool,
}

fn check_color(field: &str, c: [f32; 3]) -> Result<(), String> {
    if c.iter().all(|v| v.is_finite() && *v >= 0.0) {
        Ok(())
    } else {
        Err(format!(
            "{field}: colour components must be finite and ≥ 0, got {c:?}"
        ))
    }
}

fn check_unit(field: &str, v: f32) -> Result<(), String> {
    if (0.0..=1.0).contains(&v) {
        Ok(())
    } else {
        Err(format!("{field}: must be in [0, 1], got {v}"))
    }
}

impl MaterialDesc {
    /// Validates every field and builds the runtime material. Errors name the
    /// field (the caller adds where the material came from).
    pub fn build(&self, name: &str) -> Result<Material, String> {
        let (model, double_sided) = match self {
            MaterialDesc::Lambert(d) => {
                check_color("base_color", d.base_color)?;
                (
                    Model::Lambert(Lambert {
                        base_color: d.base_color,
                    }),
                    d.double_sided,
                )
            }
            MaterialDesc::MetallicRoughness(d) => {
                check_color("base_color", d.base_color)?;
                check_unit("roughness", d.roughness)?;
                check_unit("metallic", d.metallic)?;
                (
                    Model::MetallicRoughness(MetallicRoughness {
                        base_color: d.base_color,
                        roughness: d.roughness,
                        metallic: d.metallic,
                    }),
                    d.double_sided,
                )
            }
        };
        Ok(Material {
            name: name.to_string(),
            model,
            double_sided,
        })
    }
}
