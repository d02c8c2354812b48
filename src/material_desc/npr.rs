//! Stylized and unlit materials: toon, hatching, unlit.

use super::*;

/// `toon`: hard shading (npr/src/toon.rs). `bands` or an explicit `ramp`
/// of `[edge, [r, g, b]]` pairs on n·l (default 3 bands); a hard highlight
/// where n·h ≥ `specular_threshold`; a rim where 1 − n·v ≥ `rim_threshold`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ToonDesc {
    pub(crate) base_color: [f32; 3],
    #[serde(default)]
    pub(crate) base_color_texture: Option<PathBuf>,
    #[serde(default)]
    pub(crate) bands: Option<u32>,
    #[serde(default)]
    pub(crate) ramp: Option<Vec<(f32, [f32; 3])>>,
    #[serde(default)]
    pub(crate) specular_threshold: Option<f32>,
    #[serde(default = "white")]
    pub(crate) specular_color: [f32; 3],
    #[serde(default)]
    pub(crate) rim_threshold: Option<f32>,
    #[serde(default = "white")]
    pub(crate) rim_color: [f32; 3],
    #[serde(default)]
    pub(crate) double_sided: bool,
}

pub(super) fn default_ink() -> [f32; 3] {
    [0.02, 0.02, 0.03]
}
pub(super) fn default_scale() -> f32 {
    4.0
}

/// `hatching`: a tonal art map selected by the shaded luminance
/// (npr/src/hatching.rs). `tam` names a directory written by `specula tam`
/// (relative to the scene file); without it a built-in map is generated.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HatchingDesc {
    #[serde(default)]
    pub(crate) tam: Option<PathBuf>,
    #[serde(default = "default_ink")]
    pub(crate) ink: [f32; 3],
    #[serde(default = "white")]
    pub(crate) paper: [f32; 3],
    /// Map repeats per unit of uv.
    #[serde(default = "default_scale")]
    pub(crate) scale: f32,
    #[serde(default)]
    pub(crate) double_sided: bool,
}

/// `unlit`: emits color × intensity, ignores lights.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct UnlitDesc {
    pub(crate) color: [f32; 3],
    #[serde(default = "one")]
    pub(crate) intensity: f32,
    #[serde(default)]
    pub(crate) double_sided: bool,
}

impl ToonDesc {
    pub(super) fn shader(&self, read: ReadFile) -> Result<Toon, MaterialError> {
        checks::linear_color("base_color", self.base_color)?;
        // Checked whether or not their threshold is set: a colour in the
        // file is a colour, used or not.
        checks::linear_color("specular_color", self.specular_color)?;
        checks::linear_color("rim_color", self.rim_color)?;
        let ramp = match (&self.bands, &self.ramp) {
            (Some(_), Some(_)) => {
                return Err(FieldError::new("bands / ramp", FieldReason::BandsAndRamp).into())
            }
            (_, Some(r)) => {
                for (i, (_, color)) in r.iter().enumerate() {
                    checks::linear_color(&format!("ramp[{i}]"), *color)?;
                }
                Ramp::explicit(r.clone())?
            }
            (b, None) => Ramp::bands(b.unwrap_or(3))?,
        };
        let hard = |field: &str, t: Option<f32>, color: [f32; 3], cfield: &str| {
            t.map(|t| {
                if !(-1.0..=1.0).contains(&t) {
                    return Err(FieldError::new(field, FieldReason::NotSignedUnit(t)));
                }
                checks::linear_color(cfield, color)?;
                Ok(Hard {
                    threshold: t,
                    color,
                })
            })
            .transpose()
        };
        let base_color_map = match &self.base_color_texture {
            Some(p) => Some(crate::textures::load_color_map(p, read).map_err(|source| {
                MaterialError::Texture {
                    field: "base_color_texture",
                    source,
                }
            })?),
            None => None,
        };
        Ok(Toon {
            base_color: self.base_color,
            maps: ParamMaps {
                base_color: base_color_map,
                ..Default::default()
            },
            ramp,
            specular: hard(
                "specular_threshold",
                self.specular_threshold,
                self.specular_color,
                "specular_color",
            )?,
            rim: hard(
                "rim_threshold",
                self.rim_threshold,
                self.rim_color,
                "rim_color",
            )?,
        })
    }
}

impl HatchingDesc {
    pub(super) fn shader(&self, read: ReadFile) -> Result<Hatching, MaterialError> {
        checks::linear_color("ink", self.ink)?;
        checks::linear_color("paper", self.paper)?;
        check_positive("scale", self.scale)?;
        let tam = match &self.tam {
            Some(dir) => Arc::new(
                TamTexture::read_with_budget(dir, read, &|what, bytes| {
                    crate::memory::reserve(what, bytes).map_err(|e| e.to_string())
                })
                .map_err(MaterialError::Tam)?,
            ),
            None => builtin_tam().map_err(MaterialError::BuiltinTam)?,
        };
        Ok(Hatching {
            tam,
            ink: self.ink,
            paper: self.paper,
            scale: self.scale,
        })
    }
}
