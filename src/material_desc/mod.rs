//! Materials as users write them: TOML tables in scene files and JSON objects
//! in `specula eval` share these serde types, so the field names are one
//! contract (documented in the README).

use crate::checks::{self, FieldError, FieldReason};
use serde::Deserialize;
use specula_core::kulla_conty::KcColor;
use specula_core::models::microfacet::clamp_alpha;
use specula_core::models::{
    Disney, DisneyParams, Fresnel, Gltf, GltfFresnel, GltfParams, GtrLambda, Lambert,
    MetallicRoughness, Microfacet, MicrofacetParams, Ndf, Smith,
};
use specula_core::Model;
use specula_npr::hatching::{builtin_tam, Hatching};
use specula_npr::tam::TamTexture;
use specula_npr::toon::{Hard, Ramp, Toon};
use specula_raster::maps::{NormalMap, OcclusionMap, ParamMaps};
use specula_raster::texture::{Encoding, Filter, Sampler, Wrap};
use specula_raster::{Lit, Material, Unlit};
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub(crate) use crate::textures::ReadFile;

mod error;
#[macro_use]
mod maps;
mod npr;
mod pbr;

pub use error::MaterialError;

use maps::SurfaceMaps;
pub(crate) use maps::WrapsDesc;
pub(crate) use npr::{HatchingDesc, ToonDesc, UnlitDesc};
pub(crate) use pbr::{
    DisneyDesc, GltfDesc, KcColorDesc, LambertDesc, MetallicRoughnessDesc, MicrofacetDesc,
};

/// One material description; `model` selects the variant.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(tag = "model", rename_all = "snake_case")]
pub enum MaterialDesc {
    Lambert(LambertDesc),
    MetallicRoughness(MetallicRoughnessDesc),
    Microfacet(MicrofacetDesc),
    Disney(DisneyDesc),
    Gltf(GltfDesc),
    Unlit(UnlitDesc),
    Toon(ToonDesc),
    Hatching(HatchingDesc),
}

fn white() -> [f32; 3] {
    [1.0; 3]
}

fn one() -> f32 {
    1.0
}

fn check_positive(field: &str, v: f32) -> Result<(), FieldError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(FieldError::new(field, FieldReason::NotPositive(v)))
    }
}

/// Whether to tabulate what uniform environment light needs (scenes) or
/// not (`specula eval` evaluates f only, and builds many materials).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tables {
    Build,
    Skip,
}

/// What a material description builds: a physically based model (shaded
/// by [`Lit`]) or an [`Unlit`] surface.
#[derive(Clone, Debug, PartialEq)]
#[allow(clippy::large_enum_variant)] // built once per material, as `Model`
pub enum Shading {
    Lit(Model),
    Unlit(Unlit),
}

impl MaterialDesc {
    /// Validates every field and builds the runtime material. Errors name the
    /// field (the caller adds where the material came from); adjustments
    /// such as a clamped alpha are pushed to `warnings`. The files the
    /// material names (textures, tonal art maps) are read through `read`.
    pub(crate) fn build_with(
        &self,
        name: &str,
        tables: Tables,
        warnings: &mut Vec<String>,
        read: ReadFile,
    ) -> Result<Material, MaterialError> {
        match self {
            MaterialDesc::Toon(d) => {
                return Ok(Material::new(name, d.shader(read)?, d.double_sided))
            }
            MaterialDesc::Hatching(d) => {
                return Ok(Material::new(name, d.shader(read)?, d.double_sided))
            }
            _ => {}
        }
        let (shading, double_sided) = self.build_model(tables, warnings)?;
        Ok(match shading {
            Shading::Lit(model) => {
                let (maps, emissive) = self.param_maps(warnings, read)?;
                let lit = if maps.is_empty() {
                    Lit::new(model)
                } else {
                    Lit::with_maps(model, maps)?
                };
                Material::new(name, lit.with_emission(emissive), double_sided)
            }
            Shading::Unlit(u) => Material::new(name, u, double_sided),
        })
    }

    /// The `SurfaceMaps` fields of a lit material, if it has them.
    fn surface_maps(&self) -> Option<SurfaceMaps<'_>> {
        match self {
            MaterialDesc::Lambert(d) => Some(surface_maps!(d)),
            MaterialDesc::MetallicRoughness(d) => Some(surface_maps!(d)),
            _ => None,
        }
    }

    /// The metallic-roughness image the material names, if any.
    fn metallic_roughness_texture(&self) -> Option<&Path> {
        match self {
            MaterialDesc::Lambert(d) => d.metallic_roughness_texture.as_deref(),
            MaterialDesc::MetallicRoughness(d) => d.metallic_roughness_texture.as_deref(),
            _ => None,
        }
    }

    /// Every texture file the material names, with its field.
    fn texture_fields(&self) -> Vec<(&'static str, &Path)> {
        let mut out = vec![
            ("base_color_texture", self.base_color_texture()),
            (
                "metallic_roughness_texture",
                self.metallic_roughness_texture(),
            ),
        ];
        if let Some(m) = self.surface_maps() {
            out.extend(m.files());
        }
        out.into_iter()
            .filter_map(|(f, p)| p.map(|p| (f, p)))
            .collect()
    }

    /// The texture files the material names (inputs outputs must not
    /// overwrite).
    pub(crate) fn texture_files(&self) -> Vec<&Path> {
        self.texture_fields().into_iter().map(|(_, p)| p).collect()
    }

    /// The material has a normal map: its meshes need tangents
    /// (tangents.rs).
    pub(crate) fn has_normal_map(&self) -> bool {
        self.surface_maps()
            .is_some_and(|m| m.normal_texture.is_some())
    }

    /// A lit material's maps, every field checked and every image read
    /// through `read`, and its emissive colour.
    fn param_maps(
        &self,
        warnings: &mut Vec<String>,
        read: ReadFile,
    ) -> Result<(ParamMaps, [f32; 3]), MaterialError> {
        let Some(m) = self.surface_maps() else {
            return Ok((ParamMaps::default(), [0.0; 3]));
        };
        let sampler = m.sampler()?;
        if !m.normal_scale.is_finite() {
            return Err(FieldError::new(
                "normal_scale",
                FieldReason::NotFiniteNumber(m.normal_scale),
            )
            .into());
        }
        checks::unit("occlusion_strength", m.occlusion_strength)?;
        checks::linear_color("emissive", m.emissive)?;
        if m.emissive_texture.is_some() && m.emissive == [0.0; 3] {
            warnings.push(
                "emissive_texture: multiplies `emissive`, which is [0, 0, 0] (glTF's default): the material emits nothing"
                    .into(),
            );
        }
        let load = |field: &'static str, path: Option<&Path>, encoding: Encoding| {
            path.map(|p| {
                crate::textures::load_map(p, read, encoding, sampler)
                    .map_err(|source| MaterialError::Texture { field, source })
            })
            .transpose()
        };
        let maps = ParamMaps {
            base_color: load(
                "base_color_texture",
                self.base_color_texture(),
                Encoding::Srgb,
            )?,
            metallic_roughness: load(
                "metallic_roughness_texture",
                self.metallic_roughness_texture(),
                Encoding::Linear,
            )?,
            normal: load("normal_texture", m.normal_texture, Encoding::Linear)?.map(|map| {
                NormalMap {
                    map,
                    scale: m.normal_scale,
                }
            }),
            occlusion: load("occlusion_texture", m.occlusion_texture, Encoding::Linear)?.map(
                |map| OcclusionMap {
                    map,
                    strength: m.occlusion_strength,
                },
            ),
            emissive: load("emissive_texture", m.emissive_texture, Encoding::Srgb)?,
            // Scene materials do not read vertex colours (OBJ has none).
            vertex_color: false,
            layers: None,
        };
        Ok((maps, m.emissive))
    }

    /// The base-colour image the material names, if any.
    pub(crate) fn base_color_texture(&self) -> Option<&Path> {
        match self {
            MaterialDesc::Lambert(d) => d.base_color_texture.as_deref(),
            MaterialDesc::MetallicRoughness(d) => d.base_color_texture.as_deref(),
            MaterialDesc::Gltf(d) => d.base_color_texture.as_deref(),
            MaterialDesc::Toon(d) => d.base_color_texture.as_deref(),
            _ => None,
        }
    }

    /// The material reads uvs (a texture or a tonal art map): meshes
    /// without them cannot use it.
    pub(crate) fn needs_uvs(&self) -> bool {
        !self.texture_fields().is_empty() || matches!(self, MaterialDesc::Hatching(_))
    }

    /// `MaterialDesc::build_with` before it becomes a shader (what `specula
    /// eval` evaluates), and whether it is double-sided. Only materials
    /// with a BRDF value at a direction pair have one: stylized shaders
    /// and textured materials (whose value depends on uv) are refused.
    pub fn build_shading(
        &self,
        tables: Tables,
        warnings: &mut Vec<String>,
    ) -> Result<(Shading, bool), MaterialError> {
        if let Some((field, _)) = self.texture_fields().first() {
            return Err(FieldError::new(*field, FieldReason::TexturedBrdf).into());
        }
        if self.surface_maps().is_some_and(|m| m.emissive != [0.0; 3]) {
            return Err(FieldError::new("emissive", FieldReason::EmissiveBrdf).into());
        }
        if let MaterialDesc::Toon(_) | MaterialDesc::Hatching(_) = self {
            return Err(FieldError::new("model", FieldReason::StylizedBrdf).into());
        }
        self.build_model(tables, warnings)
    }

    fn build_model(
        &self,
        tables: Tables,
        warnings: &mut Vec<String>,
    ) -> Result<(Shading, bool), MaterialError> {
        let (model, double_sided) = match self {
            MaterialDesc::Toon(_) | MaterialDesc::Hatching(_) => {
                return Err(FieldError::new("model", FieldReason::NoBrdf).into())
            }
            MaterialDesc::Unlit(d) => {
                checks::linear_color("color", d.color)?;
                if !(0.0..=checks::MAX_RADIOMETRIC).contains(&d.intensity) {
                    return Err(FieldError::new(
                        "intensity",
                        FieldReason::UnlitIntensity(d.intensity),
                    )
                    .into());
                }
                if d.color.iter().any(|c| !(c * d.intensity).is_finite()) {
                    return Err(FieldError::new(
                        "intensity",
                        FieldReason::UnlitOverflow {
                            color: d.color,
                            intensity: d.intensity,
                        },
                    )
                    .into());
                }
                let u = Unlit {
                    color: d.color,
                    intensity: d.intensity,
                };
                return Ok((Shading::Unlit(u), d.double_sided));
            }
            MaterialDesc::Lambert(d) => {
                checks::linear_color("base_color", d.base_color)?;
                (
                    Model::Lambert(Lambert {
                        base_color: d.base_color,
                    }),
                    d.double_sided,
                )
            }
            MaterialDesc::MetallicRoughness(d) => {
                checks::linear_color("base_color", d.base_color)?;
                checks::unit("roughness", d.roughness)?;
                checks::unit("metallic", d.metallic)?;
                (
                    Model::MetallicRoughness(MetallicRoughness {
                        base_color: d.base_color,
                        roughness: d.roughness,
                        metallic: d.metallic,
                    }),
                    d.double_sided,
                )
            }
            MaterialDesc::Microfacet(d) => {
                let params = d.params(warnings)?;
                let kc = d.energy_compensation.then_some(match d.kc_color {
                    KcColorDesc::KullaConty => KcColor::KullaConty,
                    KcColorDesc::Notes => KcColor::Notes,
                });
                let m = match tables {
                    Tables::Build => Microfacet::new(params, kc),
                    Tables::Skip => Microfacet::new_without_table(params, kc),
                };
                (Model::Microfacet(m), d.double_sided)
            }
            MaterialDesc::Disney(d) => {
                let params = d.params(warnings)?;
                let m = match tables {
                    Tables::Build => Disney::new(params, d.energy_compensation),
                    Tables::Skip => Disney::new_without_table(params, d.energy_compensation),
                };
                (Model::Disney(m), d.double_sided)
            }
            MaterialDesc::Gltf(d) => (Model::Gltf(Gltf::new(d.params()?)), d.double_sided),
        };
        Ok((Shading::Lit(model), double_sided))
    }
}
