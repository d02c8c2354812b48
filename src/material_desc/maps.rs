//! The texture maps every physically based description shares (normal,
//! occlusion, emissive) and their sampler settings.

use super::*;

/// The fields of a lit material (`lambert`, `metallic_roughness`) for
/// the maps that belong to the material whatever its model (normal,
/// occlusion, emission; raster's maps.rs) and the sampler all of its
/// textures use, borrowed from its table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct SurfaceMaps<'a> {
    pub(super) normal_texture: Option<&'a Path>,
    pub(super) normal_scale: f32,
    pub(super) occlusion_texture: Option<&'a Path>,
    pub(super) occlusion_strength: f32,
    pub(super) emissive: [f32; 3],
    pub(super) emissive_texture: Option<&'a Path>,
    pub(super) texture_filter: Option<&'a str>,
    pub(super) texture_wrap: Option<&'a WrapsDesc>,
}

/// Borrows the `SurfaceMaps` fields of a description that has them.
macro_rules! surface_maps {
    ($d:expr) => {
        SurfaceMaps {
            normal_texture: $d.normal_texture.as_deref(),
            normal_scale: $d.normal_scale,
            occlusion_texture: $d.occlusion_texture.as_deref(),
            occlusion_strength: $d.occlusion_strength,
            emissive: $d.emissive,
            emissive_texture: $d.emissive_texture.as_deref(),
            texture_filter: $d.texture_filter.as_deref(),
            texture_wrap: $d.texture_wrap.as_ref(),
        }
    };
}

/// `texture_wrap`: one wrap mode for both axes, or [u, v]; names are
/// checked when the material is built (`wrap_mode`), so a wrong one is an
/// error naming the field.
#[derive(Clone, Debug, Deserialize, PartialEq, Eq)]
#[serde(untagged)]
pub(crate) enum WrapsDesc {
    Both(String),
    Axes([String; 2]),
}

/// glTF's wrap modes by their glTF names in snake case.
pub(super) fn wrap_mode(name: &str) -> Result<Wrap, FieldError> {
    match name {
        "repeat" => Ok(Wrap::Repeat),
        "clamp_to_edge" => Ok(Wrap::Clamp),
        "mirrored_repeat" => Ok(Wrap::Mirror),
        _ => Err(FieldError::new(
            "texture_wrap",
            FieldReason::Wrap(name.to_string()),
        )),
    }
}

impl<'a> SurfaceMaps<'a> {
    /// The sampler of the material's textures, checked.
    pub(super) fn sampler(&self) -> Result<Sampler, MaterialError> {
        let filter = match self.texture_filter {
            Some(f) => f.parse::<Filter>()?,
            None => Filter::Trilinear,
        };
        let [u, v] = match self.texture_wrap {
            None => [Wrap::Repeat; 2],
            Some(WrapsDesc::Both(w)) => [wrap_mode(w)?; 2],
            Some(WrapsDesc::Axes([u, v])) => [wrap_mode(u)?, wrap_mode(v)?],
        };
        Ok(Sampler {
            wrap_u: u,
            wrap_v: v,
            filter,
        })
    }

    /// The files these fields name, with their field names.
    pub(super) fn files(&self) -> [(&'static str, Option<&'a Path>); 3] {
        [
            ("normal_texture", self.normal_texture),
            ("occlusion_texture", self.occlusion_texture),
            ("emissive_texture", self.emissive_texture),
        ]
    }
}
