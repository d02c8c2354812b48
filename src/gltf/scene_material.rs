//! A glTF material read by `material.rs` turned into a scene material:
//! [`scene_material`] is the one function that decides what specula
//! renders of it, and says in a warning what it does not render yet. A
//! renderer that gains a model or a map changes this function alone.

use super::images::Images;
use super::material::{AlphaMode, GltfMaterial, TextureRef, TextureTransform};
use super::GltfError;
use crate::material_desc::GltfDesc;
use specula_core::models::Gltf;
use specula_core::Model;
use specula_raster::maps::{ColorMap, LayerMaps, NormalMap, OcclusionMap, ParamMaps};
use specula_raster::texture::Encoding;
use specula_raster::{Lit, Material, MaterialAlpha, UnlitBase};

/// The scene material for a glTF material, and what of it is not
/// rendered (one warning, or none). With `vertex_color` (some primitive
/// using it has COLOR_0) the vertex colour multiplies its base colour.
///
/// Today: the `gltf` model (the specification's normative BRDF) with the
/// base colour factor's RGB, the metallic and
/// roughness factors, KHR_materials_ior, the factors of
/// KHR_materials_specular, _clearcoat and _sheen, each checked as the
/// scene field of the same snake_case name is, and their textures as
/// [`LayerMaps`] (the clearcoat normal map giving the coat its own
/// normal; without one the coat's normal is unmapped); the base colour texture
/// through [`ParamMaps::base_color`] (its sampler kept; uvs from the set it
/// names, chosen where the mesh is built), the metallic-roughness,
/// normal (with its scale), occlusion (with its strength) and emissive
/// maps, each moved by its KHR_texture_transform
/// ([`TextureTransform::uv_transform`]), the emissive factor times
/// KHR_materials_emissive_strength; `doubleSided` as the material's;
/// alphaMode MASK and BLEND as the material's [`MaterialAlpha`]
/// (baseColorFactor alpha × the base colour texture's alpha × COLOR_0's
/// alpha; that texture is then read with four channels).
/// Everything else is listed in the warning. A KHR_materials_unlit
/// material is [`UnlitBase`]: its base colour factor times its base
/// colour texture, shown as it is.
pub(crate) fn scene_material(
    m: &GltfMaterial,
    vertex_color: bool,
    images: &mut Images,
) -> Result<(Material, Option<String>), GltfError> {
    let mut missing: Vec<String> = Vec::new();
    let mut note = |what: &str, present: bool| {
        if present {
            missing.push(what.to_string());
        }
    };
    note("KHR_materials_transmission", m.transmission.is_some());
    note("KHR_materials_volume", m.volume.is_some());
    note(
        "KHR_materials_pbrSpecularGlossiness",
        m.specular_glossiness.is_some(),
    );
    // Clearcoat and sheen are rendered by the gltf model: their factors
    // read here, their textures (read with the material) as maps.
    let ext = |name: &str| m.other_extensions.get(name);
    let number = |v: Option<&serde_json::Value>, key: &str, default: f32| {
        v.and_then(|o| o.get(key))
            .and_then(|x| x.as_f64())
            .map_or(default, |x| x as f32)
    };
    let color = |v: Option<&serde_json::Value>, key: &str| -> [f32; 3] {
        let mut c = [0.0; 3];
        if let Some(a) = v.and_then(|o| o.get(key)).and_then(|x| x.as_array()) {
            for (k, x) in a.iter().take(3).enumerate() {
                c[k] = x.as_f64().map_or(f32::NAN, |x| x as f32);
            }
        }
        c
    };
    for (name, keys) in [
        (
            "KHR_materials_clearcoat",
            &[
                "clearcoatFactor",
                "clearcoatRoughnessFactor",
                "clearcoatTexture",
                "clearcoatRoughnessTexture",
                "clearcoatNormalTexture",
            ][..],
        ),
        (
            "KHR_materials_sheen",
            &[
                "sheenColorFactor",
                "sheenRoughnessFactor",
                "sheenColorTexture",
                "sheenRoughnessTexture",
            ][..],
        ),
    ] {
        if let Some(serde_json::Value::Object(o)) = ext(name) {
            for k in o.keys().filter(|k| !keys.contains(&k.as_str())) {
                missing.push(format!("{name}.{k}"));
            }
        }
    }
    for k in m.other_extensions.keys() {
        if k != "KHR_materials_clearcoat" && k != "KHR_materials_sheen" {
            missing.push(k.clone());
        }
    }
    let clearcoat = ext("KHR_materials_clearcoat");
    let sheen = ext("KHR_materials_sheen");
    let [r, g, b, _] = m.base_color_factor;
    let defaults = GltfDesc::default();
    let desc = GltfDesc {
        base_color_factor: [r, g, b],
        metallic_factor: m.metallic_factor,
        roughness_factor: m.roughness_factor,
        ior: m.ior.unwrap_or(defaults.ior),
        specular_factor: m
            .specular
            .as_ref()
            .map_or(defaults.specular_factor, |s| s.factor),
        specular_color_factor: m
            .specular
            .as_ref()
            .map_or(defaults.specular_color_factor, |s| s.color_factor),
        clearcoat_factor: number(clearcoat, "clearcoatFactor", 0.0),
        clearcoat_roughness_factor: number(clearcoat, "clearcoatRoughnessFactor", 0.0),
        sheen_color_factor: color(sheen, "sheenColorFactor"),
        sheen_roughness_factor: number(sheen, "sheenRoughnessFactor", 0.0),
        ..defaults
    };
    let at = m.index.map_or_else(
        || "the default material".to_string(),
        |i| format!("materials[{i}]"),
    );
    let params = desc.params().map_err(|source| GltfError::Material {
        at: at.clone(),
        source: Box::new(source),
    })?;
    let model = Model::Gltf(Gltf::new(params));
    let mut maps = ParamMaps {
        vertex_color,
        ..Default::default()
    };
    let mut sets = Vec::new();
    // A masked or blended material reads its base colour texture's alpha
    // too: that texture keeps four channels (the others three).
    let alpha_mode = match m.alpha_mode {
        AlphaMode::Opaque => None,
        AlphaMode::Mask { cutoff } => Some(specula_raster::AlphaMode::Mask { cutoff }),
        AlphaMode::Blend => Some(specula_raster::AlphaMode::Blend),
    };
    let base_channels = if alpha_mode.is_some() { 4 } else { 3 };
    let mut load =
        |t: &TextureRef, encoding: Encoding, channels: usize| -> Result<ColorMap, GltfError> {
            let mut map = images
                .map_channels(t.image, encoding, channels)
                .map_err(|source| GltfError::Image {
                    at: t.at.clone(),
                    source: Box::new(source),
                })?;
            map.sampler = t.sampler;
            map.transform = t.transform.as_ref().map(TextureTransform::uv_transform);
            sets.push(
                t.transform
                    .as_ref()
                    .and_then(|x| x.tex_coord)
                    .unwrap_or(t.tex_coord),
            );
            Ok(map)
        };
    if m.unlit {
        // KHR_materials_unlit: the base colour alone (factor × texture);
        // the other maps, the lights and the emission do not apply.
        let base_color = (m.base_color_texture.as_ref())
            .map(|t| load(t, Encoding::Srgb, base_channels))
            .transpose()?;
        let alpha = alpha_mode.map(|mode| MaterialAlpha {
            mode,
            factor: m.base_color_factor[3],
            map: base_color.clone(),
            vertex_alpha: vertex_color,
        });
        let shader = UnlitBase {
            color: [r, g, b],
            base_color,
            vertex_color,
        };
        let warning = rendered_without(&m.name, &missing);
        let material = Material::new(&m.name, shader, m.double_sided);
        return Ok((with_alpha(material, alpha), warning));
    }
    if let Some(t) = &m.base_color_texture {
        maps.base_color = Some(load(t, Encoding::Srgb, base_channels)?);
    }
    if let Some(t) = &m.metallic_roughness_texture {
        maps.metallic_roughness = Some(load(t, Encoding::Linear, 3)?);
    }
    if let Some(t) = &m.normal_texture {
        maps.normal = Some(NormalMap {
            map: load(t, Encoding::Linear, 3)?,
            scale: t.scale,
        });
    }
    if let Some(t) = &m.occlusion_texture {
        maps.occlusion = Some(OcclusionMap {
            map: load(t, Encoding::Linear, 3)?,
            strength: t.scale.clamp(0.0, 1.0),
        });
    }
    if let Some(t) = &m.emissive_texture {
        maps.emissive = Some(load(t, Encoding::Srgb, 3)?);
    }
    // The extensions' textures, each multiplying its factor (maps.rs):
    // specular and sheen roughness in their alpha, the colours sRGB.
    let mut layers = LayerMaps::default();
    if let Some(s) = &m.specular {
        if let Some(t) = &s.texture {
            layers.specular = Some(load(t, Encoding::Linear, 4)?);
        }
        if let Some(t) = &s.color_texture {
            layers.specular_color = Some(load(t, Encoding::Srgb, 3)?);
        }
    }
    let (c, sh) = (&m.clearcoat_textures, &m.sheen_textures);
    if let Some(t) = &c.texture {
        layers.clearcoat = Some(load(t, Encoding::Linear, 3)?);
    }
    if let Some(t) = &c.roughness_texture {
        layers.clearcoat_roughness = Some(load(t, Encoding::Linear, 3)?);
    }
    if let Some(t) = &c.normal_texture {
        layers.clearcoat_normal = Some(NormalMap {
            map: load(t, Encoding::Linear, 3)?,
            scale: t.scale,
        });
    }
    if let Some(t) = &sh.color_texture {
        layers.sheen_color = Some(load(t, Encoding::Srgb, 3)?);
    }
    if let Some(t) = &sh.roughness_texture {
        layers.sheen_roughness = Some(load(t, Encoding::Linear, 4)?);
    }
    if layers != LayerMaps::default() {
        maps.layers = Some(Box::new(layers));
    }
    sets.dedup();
    if sets.len() > 1 {
        missing.push(format!(
            "textures on TEXCOORD sets other than {} (one uv set per material is read)",
            sets[0]
        ));
    }
    let strength = m.emissive_strength.unwrap_or(1.0);
    let emissive = m.emissive_factor.map(|c| c * strength);
    if !emissive
        .iter()
        .all(|c| (0.0..=crate::checks::MAX_RADIOMETRIC).contains(c))
    {
        return Err(GltfError::at(
            &format!("{at}.emissiveFactor × KHR_materials_emissive_strength"),
            format!(
                "every component must be in [0, {:e}], got {emissive:?}",
                crate::checks::MAX_RADIOMETRIC
            ),
        ));
    }
    let alpha = alpha_mode.map(|mode| MaterialAlpha {
        mode,
        factor: m.base_color_factor[3],
        map: maps.base_color.clone(),
        vertex_alpha: vertex_color,
    });
    let shader = Lit::with_maps(model, maps)
        .map_err(|e| GltfError::at(&at, e.to_string()))?
        .with_emission(emissive);
    let warning = rendered_without(&m.name, &missing);
    let material = Material::new(&m.name, shader, m.double_sided);
    Ok((with_alpha(material, alpha), warning))
}

fn with_alpha(m: Material, alpha: Option<MaterialAlpha>) -> Material {
    match alpha {
        Some(a) => m.with_alpha(a),
        None => m,
    }
}

/// The warning for what a material is rendered without, if anything.
fn rendered_without(name: &str, missing: &[String]) -> Option<String> {
    (!missing.is_empty())
        .then(|| format!("material {name:?}: rendered without {}", missing.join(", ")))
}
