//! glTF materials: read completely into [`GltfMaterial`] (every factor,
//! every texture reference with its sampler, texCoord set and
//! KHR_texture_transform, the alpha mode, doubleSided, the values of every
//! KHR material extension), checked. `scene_material.rs` turns one into
//! a scene material.

use super::GltfError;
use gltf::json;
use json::validation::Checked;
use specula_raster::maps::UvTransform;
use specula_raster::texture::{Filter, Sampler, Wrap};
use std::collections::BTreeMap;

/// KHR_texture_transform: uv' = T(offset) · R(rotation) · S(scale) · uv
/// in glTF's uvs, with R = [[cos r, sin r], [−sin r, cos r]] (rows).
///
/// That R is the one the extension's example JSON needs (offset (0, 1),
/// rotation π/2, scale ½ shows "the lower left quadrant of the image,
/// rotated clockwise 90°"); the README's GLSL listing, read with GLSL's
/// column-major `mat3`, is its transpose.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TextureTransform {
    pub(crate) offset: [f32; 2],
    /// Radians, counter-clockwise in uv.
    pub(crate) rotation: f32,
    pub(crate) scale: [f32; 2],
    /// Overrides the reference's texCoord set.
    pub(crate) tex_coord: Option<u32>,
}

impl TextureTransform {
    /// The transform as it acts on glTF's uvs (v = 0 at the top of the
    /// image): uv' = rows · (u, v, 1).
    pub(crate) fn gltf_rows(&self) -> [[f64; 3]; 2] {
        let (s, c) = (self.rotation as f64).sin_cos();
        let [sx, sy] = self.scale.map(|x| x as f64);
        let [ox, oy] = self.offset.map(|x| x as f64);
        [[c * sx, s * sy, ox], [-s * sx, c * sy, oy]]
    }

    /// The same transform on specula's uvs, which loading flipped
    /// (v_ours = 1 − v_glTF, F(u, v) = (u, 1 − v)): F ∘ A ∘ F, so a texel
    /// lands where glTF puts it.
    pub(crate) fn uv_transform(&self) -> UvTransform {
        let [[a, b, c], [d, e, f]] = self.gltf_rows();
        // F(A(F(x))) with F = diag(1, −1)·x + (0, 1):
        // linear part diag(1,−1)·L·diag(1,−1), offset diag(1,−1)·(L·(0,1) + o) + (0, 1).
        UvTransform {
            rows: [
                [a as f32, -b as f32, (b + c) as f32],
                [-d as f32, e as f32, (1.0 - e - f) as f32],
            ],
        }
    }
}

/// A texture as a material refers to it: the image, how it is sampled,
/// which uv set reads it and how that set is transformed.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TextureRef {
    /// Where the reference is (`materials[0].pbrMetallicRoughness.baseColorTexture`).
    pub(crate) at: String,
    pub(crate) texture: usize,
    /// `images[i]`.
    pub(crate) image: usize,
    pub(crate) sampler: Sampler,
    pub(crate) tex_coord: u32,
    pub(crate) transform: Option<TextureTransform>,
    /// normalTexture.scale, occlusionTexture.strength (1 for the others).
    pub(crate) scale: f32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum AlphaMode {
    Opaque,
    Mask { cutoff: f32 },
    Blend,
}

/// KHR_materials_pbrSpecularGlossiness.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SpecularGlossiness {
    pub(crate) diffuse_factor: [f32; 4],
    pub(crate) diffuse_texture: Option<TextureRef>,
    pub(crate) specular_factor: [f32; 3],
    pub(crate) glossiness_factor: f32,
    pub(crate) specular_glossiness_texture: Option<TextureRef>,
}

/// KHR_materials_specular.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Specular {
    pub(crate) factor: f32,
    pub(crate) texture: Option<TextureRef>,
    pub(crate) color_factor: [f32; 3],
    pub(crate) color_texture: Option<TextureRef>,
}

/// The textures of KHR_materials_clearcoat (its factors are read where
/// the scene material is made, from `other_extensions`).
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct ClearcoatTextures {
    pub(crate) texture: Option<TextureRef>,
    pub(crate) roughness_texture: Option<TextureRef>,
    /// With its `scale`.
    pub(crate) normal_texture: Option<TextureRef>,
}

/// The textures of KHR_materials_sheen (its factors are read where the
/// scene material is made, from `other_extensions`).
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct SheenTextures {
    pub(crate) color_texture: Option<TextureRef>,
    pub(crate) roughness_texture: Option<TextureRef>,
}

/// KHR_materials_transmission.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Transmission {
    pub(crate) factor: f32,
    pub(crate) texture: Option<TextureRef>,
}

/// KHR_materials_volume.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Volume {
    pub(crate) thickness_factor: f32,
    pub(crate) thickness_texture: Option<TextureRef>,
    pub(crate) attenuation_distance: f32,
    pub(crate) attenuation_color: [f32; 3],
}

/// One glTF material, as the file gives it (defaults filled in).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct GltfMaterial {
    /// Its name, or `materials[i]`, or "default" for the spec's default
    /// material (primitives without one).
    pub(crate) name: String,
    /// `materials[i]`, or `None` for the default material.
    pub(crate) index: Option<usize>,
    pub(crate) base_color_factor: [f32; 4],
    pub(crate) base_color_texture: Option<TextureRef>,
    pub(crate) metallic_factor: f32,
    pub(crate) roughness_factor: f32,
    pub(crate) metallic_roughness_texture: Option<TextureRef>,
    pub(crate) normal_texture: Option<TextureRef>,
    pub(crate) occlusion_texture: Option<TextureRef>,
    pub(crate) emissive_factor: [f32; 3],
    pub(crate) emissive_texture: Option<TextureRef>,
    pub(crate) alpha_mode: AlphaMode,
    pub(crate) double_sided: bool,
    /// KHR_materials_unlit.
    pub(crate) unlit: bool,
    /// KHR_materials_emissive_strength.
    pub(crate) emissive_strength: Option<f32>,
    /// KHR_materials_ior.
    pub(crate) ior: Option<f32>,
    pub(crate) specular: Option<Specular>,
    pub(crate) transmission: Option<Transmission>,
    pub(crate) volume: Option<Volume>,
    pub(crate) specular_glossiness: Option<SpecularGlossiness>,
    /// KHR_materials_clearcoat's textures (none without the extension).
    pub(crate) clearcoat_textures: ClearcoatTextures,
    /// KHR_materials_sheen's textures (none without the extension).
    pub(crate) sheen_textures: SheenTextures,
    /// Every other material extension (KHR_materials_clearcoat, _sheen,
    /// _iridescence, _anisotropy, …), by name, as its JSON object.
    pub(crate) other_extensions: BTreeMap<String, serde_json::Value>,
}

impl GltfMaterial {
    /// The spec's default material: white, metallic 1, roughness 1.
    pub(crate) fn default_material() -> GltfMaterial {
        GltfMaterial {
            name: "default".into(),
            index: None,
            base_color_factor: [1.0; 4],
            base_color_texture: None,
            metallic_factor: 1.0,
            roughness_factor: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            occlusion_texture: None,
            emissive_factor: [0.0; 3],
            emissive_texture: None,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
            unlit: false,
            emissive_strength: None,
            ior: None,
            specular: None,
            transmission: None,
            volume: None,
            specular_glossiness: None,
            clearcoat_textures: ClearcoatTextures::default(),
            sheen_textures: SheenTextures::default(),
            other_extensions: BTreeMap::new(),
        }
    }

    /// The uv set the rendered maps read: that of the first of base
    /// colour, metallic-roughness, normal, occlusion and emissive textures
    /// the material has, else of the first rendered extension texture
    /// (specular, specular colour, clearcoat, clearcoat roughness,
    /// clearcoat normal, sheen colour, sheen roughness), with
    /// KHR_texture_transform's override.
    pub(crate) fn uv_set(&self) -> Option<u32> {
        [
            &self.base_color_texture,
            &self.metallic_roughness_texture,
            &self.normal_texture,
            &self.occlusion_texture,
            &self.emissive_texture,
        ]
        .into_iter()
        .flatten()
        .chain(self.layer_textures())
        .next()
        .map(|t| {
            t.transform
                .as_ref()
                .and_then(|x| x.tex_coord)
                .unwrap_or(t.tex_coord)
        })
    }

    /// The rendered extension textures, in [`GltfMaterial::uv_set`]'s
    /// order.
    fn layer_textures(&self) -> impl Iterator<Item = &TextureRef> {
        let (c, sh) = (&self.clearcoat_textures, &self.sheen_textures);
        let spec = self.specular.as_ref();
        [
            spec.and_then(|s| s.texture.as_ref()),
            spec.and_then(|s| s.color_texture.as_ref()),
            c.texture.as_ref(),
            c.roughness_texture.as_ref(),
            c.normal_texture.as_ref(),
            sh.color_texture.as_ref(),
            sh.roughness_texture.as_ref(),
        ]
        .into_iter()
        .flatten()
    }
}

fn wrap(w: Checked<json::texture::WrappingMode>) -> Wrap {
    use json::texture::WrappingMode as W;
    match w {
        Checked::Valid(W::ClampToEdge) => Wrap::Clamp,
        Checked::Valid(W::MirroredRepeat) => Wrap::Mirror,
        _ => Wrap::Repeat,
    }
}

/// A glTF sampler as ours: wrap modes per axis; a min filter without
/// mipmaps reads level 0 (nearest or bilinear), one with mipmaps, or none
/// given, is trilinear.
fn sampler(root: &json::Root, s: Option<json::Index<json::texture::Sampler>>) -> Sampler {
    use json::texture::MinFilter as M;
    let Some(s) = s.and_then(|s| root.samplers.get(s.value())) else {
        return Sampler::new(Wrap::Repeat, Filter::Trilinear);
    };
    let filter = match s.min_filter {
        Some(Checked::Valid(M::Nearest)) => Filter::Nearest,
        Some(Checked::Valid(M::Linear)) => Filter::Bilinear,
        _ => Filter::Trilinear,
    };
    Sampler {
        wrap_u: wrap(s.wrap_s),
        wrap_v: wrap(s.wrap_t),
        filter,
    }
}

/// Resolves a texture reference (`at` is its JSON path).
fn texture_ref(
    root: &json::Root,
    at: String,
    index: json::Index<json::Texture>,
    tex_coord: u32,
    ext: Option<&json::extensions::texture::Info>,
    others: Option<&serde_json::Map<String, serde_json::Value>>,
    scale: f32,
) -> Result<TextureRef, GltfError> {
    let t = root
        .textures
        .get(index.value())
        .ok_or_else(|| GltfError::at(&format!("{at}.index"), format!("no texture {index}")))?;
    let image = t.source.value();
    if image >= root.images.len() {
        return Err(GltfError::at(
            &format!("textures[{index}].source"),
            format!("no image {image}"),
        ));
    }
    let transform = ext
        .and_then(|e| e.texture_transform.as_ref())
        .map(|t| TextureTransform {
            offset: t.offset.0,
            rotation: t.rotation.0,
            scale: t.scale.0,
            tex_coord: t.tex_coord,
        });
    let transform = match transform {
        Some(t) => Some(t),
        None => other_transform(&at, others)?,
    };
    if let Some(t) = &transform {
        if !t.uv_transform().is_finite() {
            return Err(GltfError::at(
                &format!("{at}.extensions.KHR_texture_transform"),
                format!("offset, rotation and scale must be finite, got {t:?}"),
            ));
        }
    }
    Ok(TextureRef {
        at,
        texture: index.value(),
        image,
        sampler: sampler(root, t.sampler),
        tex_coord,
        transform,
        scale,
    })
}

/// KHR_texture_transform where the `gltf` crate keeps it as plain JSON
/// (normalTexture and occlusionTexture extensions).
fn other_transform(
    at: &str,
    others: Option<&serde_json::Map<String, serde_json::Value>>,
) -> Result<Option<TextureTransform>, GltfError> {
    let Some(v) = others.and_then(|o| o.get("KHR_texture_transform")) else {
        return Ok(None);
    };
    let t: json::extensions::texture::TextureTransform = serde_json::from_value(v.clone())
        .map_err(|source| GltfError::Json {
            at: format!("{at}.extensions.KHR_texture_transform"),
            source,
        })?;
    Ok(Some(TextureTransform {
        offset: t.offset.0,
        rotation: t.rotation.0,
        scale: t.scale.0,
        tex_coord: t.tex_coord,
    }))
}

fn info(
    root: &json::Root,
    at: String,
    i: &Option<json::texture::Info>,
) -> Result<Option<TextureRef>, GltfError> {
    i.as_ref()
        .map(|i| {
            texture_ref(
                root,
                at,
                i.index,
                i.tex_coord,
                i.extensions.as_ref(),
                None,
                1.0,
            )
        })
        .transpose()
}

/// The field `key` of an extension's JSON object `ext` (at JSON path
/// `p`) read as `T`, with its JSON path; `None` when it is absent.
fn extension_field<T: serde::de::DeserializeOwned>(
    p: &str,
    ext: &serde_json::Value,
    key: &str,
) -> Result<Option<(String, T)>, GltfError> {
    let Some(v) = ext.get(key) else {
        return Ok(None);
    };
    let at = format!("{p}.{key}");
    let t = serde_json::from_value(v.clone()).map_err(|source| GltfError::Json {
        at: at.clone(),
        source,
    })?;
    Ok(Some((at, t)))
}

/// The textureInfo `key` of an extension's JSON object `ext` (at JSON
/// path `p`), if it has one.
fn extension_info(
    root: &json::Root,
    p: &str,
    ext: &serde_json::Value,
    key: &str,
) -> Result<Option<TextureRef>, GltfError> {
    match extension_field::<json::texture::Info>(p, ext, key)? {
        Some((at, i)) => info(root, at, &Some(i)),
        None => Ok(None),
    }
}

/// The normalTextureInfo `key` (with its scale) of an extension's JSON
/// object `ext` (at JSON path `p`), if it has one.
fn extension_normal(
    root: &json::Root,
    p: &str,
    ext: &serde_json::Value,
    key: &str,
) -> Result<Option<TextureRef>, GltfError> {
    let Some((at, n)) = extension_field::<json::material::NormalTexture>(p, ext, key)? else {
        return Ok(None);
    };
    if !n.scale.is_finite() {
        return Err(GltfError::at(
            &format!("{at}.scale"),
            format!("must be finite, got {}", n.scale),
        ));
    }
    texture_ref(
        root,
        at,
        n.index,
        n.tex_coord,
        None,
        n.extensions.as_ref().map(|e| &e.others),
        n.scale,
    )
    .map(Some)
}

/// Reads `materials[i]` completely.
pub(super) fn read_material(root: &json::Root, i: usize) -> Result<GltfMaterial, GltfError> {
    let m = &root.materials[i];
    let at = format!("materials[{i}]");
    let pbr = &m.pbr_metallic_roughness;
    let mut out = GltfMaterial::default_material();
    out.name = m.name.clone().unwrap_or_else(|| at.clone());
    out.index = Some(i);
    out.base_color_factor = pbr.base_color_factor.0;
    out.base_color_texture = info(
        root,
        format!("{at}.pbrMetallicRoughness.baseColorTexture"),
        &pbr.base_color_texture,
    )?;
    out.metallic_factor = pbr.metallic_factor.0;
    out.roughness_factor = pbr.roughness_factor.0;
    out.metallic_roughness_texture = info(
        root,
        format!("{at}.pbrMetallicRoughness.metallicRoughnessTexture"),
        &pbr.metallic_roughness_texture,
    )?;
    out.normal_texture = m
        .normal_texture
        .as_ref()
        .map(|n| {
            texture_ref(
                root,
                format!("{at}.normalTexture"),
                n.index,
                n.tex_coord,
                None,
                n.extensions.as_ref().map(|e| &e.others),
                n.scale,
            )
        })
        .transpose()?;
    out.occlusion_texture = m
        .occlusion_texture
        .as_ref()
        .map(|n| {
            texture_ref(
                root,
                format!("{at}.occlusionTexture"),
                n.index,
                n.tex_coord,
                None,
                n.extensions.as_ref().map(|e| &e.others),
                n.strength.0,
            )
        })
        .transpose()?;
    out.emissive_factor = m.emissive_factor.0;
    out.emissive_texture = info(root, format!("{at}.emissiveTexture"), &m.emissive_texture)?;
    out.alpha_mode = match m.alpha_mode {
        Checked::Valid(json::material::AlphaMode::Mask) => AlphaMode::Mask {
            cutoff: m.alpha_cutoff.map_or(0.5, |c| c.0),
        },
        Checked::Valid(json::material::AlphaMode::Blend) => AlphaMode::Blend,
        _ => AlphaMode::Opaque,
    };
    out.double_sided = m.double_sided;
    if let Some(e) = &m.extensions {
        let ext = format!("{at}.extensions");
        out.unlit = e.unlit.is_some();
        out.emissive_strength = e.emissive_strength.as_ref().map(|s| s.emissive_strength.0);
        out.ior = e.ior.as_ref().map(|s| s.ior.0);
        out.specular = e
            .specular
            .as_ref()
            .map(|s| -> Result<Specular, GltfError> {
                let p = format!("{ext}.KHR_materials_specular");
                Ok(Specular {
                    factor: s.specular_factor.0,
                    texture: info(root, format!("{p}.specularTexture"), &s.specular_texture)?,
                    color_factor: s.specular_color_factor.0,
                    color_texture: info(
                        root,
                        format!("{p}.specularColorTexture"),
                        &s.specular_color_texture,
                    )?,
                })
            })
            .transpose()?;
        out.transmission = e
            .transmission
            .as_ref()
            .map(|s| -> Result<Transmission, GltfError> {
                Ok(Transmission {
                    factor: s.transmission_factor.0,
                    texture: info(
                        root,
                        format!("{ext}.KHR_materials_transmission.transmissionTexture"),
                        &s.transmission_texture,
                    )?,
                })
            })
            .transpose()?;
        out.volume = e
            .volume
            .as_ref()
            .map(|s| -> Result<Volume, GltfError> {
                Ok(Volume {
                    thickness_factor: s.thickness_factor.0,
                    thickness_texture: info(
                        root,
                        format!("{ext}.KHR_materials_volume.thicknessTexture"),
                        &s.thickness_texture,
                    )?,
                    attenuation_distance: s.attenuation_distance.0,
                    attenuation_color: s.attenuation_color.0,
                })
            })
            .transpose()?;
        out.specular_glossiness = e
            .pbr_specular_glossiness
            .as_ref()
            .map(|s| -> Result<SpecularGlossiness, GltfError> {
                let p = format!("{ext}.KHR_materials_pbrSpecularGlossiness");
                Ok(SpecularGlossiness {
                    diffuse_factor: s.diffuse_factor.0,
                    diffuse_texture: info(root, format!("{p}.diffuseTexture"), &s.diffuse_texture)?,
                    specular_factor: s.specular_factor.0,
                    glossiness_factor: s.glossiness_factor.0,
                    specular_glossiness_texture: info(
                        root,
                        format!("{p}.specularGlossinessTexture"),
                        &s.specular_glossiness_texture,
                    )?,
                })
            })
            .transpose()?;
        out.other_extensions = e
            .others
            .iter()
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        if let Some(c) = e.others.get("KHR_materials_clearcoat") {
            let p = format!("{ext}.KHR_materials_clearcoat");
            out.clearcoat_textures = ClearcoatTextures {
                texture: extension_info(root, &p, c, "clearcoatTexture")?,
                roughness_texture: extension_info(root, &p, c, "clearcoatRoughnessTexture")?,
                normal_texture: extension_normal(root, &p, c, "clearcoatNormalTexture")?,
            };
        }
        if let Some(c) = e.others.get("KHR_materials_sheen") {
            let p = format!("{ext}.KHR_materials_sheen");
            out.sheen_textures = SheenTextures {
                color_texture: extension_info(root, &p, c, "sheenColorTexture")?,
                roughness_texture: extension_info(root, &p, c, "sheenRoughnessTexture")?,
            };
        }
    }
    check_factors(&at, &out)?;
    Ok(out)
}

/// Factors the spec bounds, checked so the scene material gets finite,
/// in-range values.
fn check_factors(at: &str, m: &GltfMaterial) -> Result<(), GltfError> {
    let unit = |f: &str, v: f32| {
        if (0.0..=1.0).contains(&v) {
            Ok(())
        } else {
            Err(GltfError::at(
                &format!("{at}.{f}"),
                format!("must be in [0, 1], got {v}"),
            ))
        }
    };
    for (k, v) in m.base_color_factor.iter().enumerate() {
        unit(&format!("pbrMetallicRoughness.baseColorFactor[{k}]"), *v)?;
    }
    unit("pbrMetallicRoughness.metallicFactor", m.metallic_factor)?;
    unit("pbrMetallicRoughness.roughnessFactor", m.roughness_factor)?;
    for (k, v) in m.emissive_factor.iter().enumerate() {
        unit(&format!("emissiveFactor[{k}]"), *v)?;
    }
    if let AlphaMode::Mask { cutoff } = m.alpha_mode {
        if !(cutoff >= 0.0 && cutoff.is_finite()) {
            return Err(GltfError::at(
                &format!("{at}.alphaCutoff"),
                format!("must be ≥ 0, got {cutoff}"),
            ));
        }
    }
    Ok(())
}
