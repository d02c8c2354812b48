//! Materials as users write them: TOML tables in scene files and JSON objects
//! in `specula eval` share these serde types, so the field names are one
//! contract (documented in the README).

use crate::checks;
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

pub use crate::textures::ReadFile;

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

/// `toon`: hard shading (npr/src/toon.rs). `bands` or an explicit `ramp`
/// of `[edge, [r, g, b]]` pairs on n·l (default 3 bands); a hard highlight
/// where n·h ≥ `specular_threshold`; a rim where 1 − n·v ≥ `rim_threshold`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ToonDesc {
    pub base_color: [f32; 3],
    #[serde(default)]
    pub base_color_texture: Option<PathBuf>,
    #[serde(default)]
    pub bands: Option<u32>,
    #[serde(default)]
    pub ramp: Option<Vec<(f32, [f32; 3])>>,
    #[serde(default)]
    pub specular_threshold: Option<f32>,
    #[serde(default = "white")]
    pub specular_color: [f32; 3],
    #[serde(default)]
    pub rim_threshold: Option<f32>,
    #[serde(default = "white")]
    pub rim_color: [f32; 3],
    #[serde(default)]
    pub double_sided: bool,
}

fn default_ink() -> [f32; 3] {
    [0.02, 0.02, 0.03]
}
fn default_scale() -> f32 {
    4.0
}

/// `hatching`: a tonal art map selected by the shaded luminance
/// (npr/src/hatching.rs). `tam` names a directory written by `specula tam`
/// (relative to the scene file); without it a built-in map is generated.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HatchingDesc {
    #[serde(default)]
    pub tam: Option<PathBuf>,
    #[serde(default = "default_ink")]
    pub ink: [f32; 3],
    #[serde(default = "white")]
    pub paper: [f32; 3],
    /// Map repeats per unit of uv.
    #[serde(default = "default_scale")]
    pub scale: f32,
    #[serde(default)]
    pub double_sided: bool,
}

fn one() -> f32 {
    1.0
}

/// `unlit`: emits color × intensity, ignores lights.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct UnlitDesc {
    pub color: [f32; 3],
    #[serde(default = "one")]
    pub intensity: f32,
    #[serde(default)]
    pub double_sided: bool,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum NdfDesc {
    Ggx,
    Beckmann,
    Gtr,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum SmithDesc {
    Separable,
    #[default]
    HeightCorrelated,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum FresnelDesc {
    Schlick { f0: [f32; 3] },
    Dielectric { ior: f32 },
    Conductor { eta: [f32; 3], k: [f32; 3] },
}

/// Which Smith Λ `ndf = "gtr"` uses.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum GtrLambdaDesc {
    /// GGX's Λ at the same α.
    #[default]
    Ggx,
    /// The GTR distribution's own Λ, tabulated per material.
    Exact,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum KcColorDesc {
    /// F_avg² E_avg / (1 − F_avg (1 − E_avg)) \[Kulla17\].
    #[default]
    KullaConty,
    /// The course notes' F_avg E_avg / (1 − F_avg (1 − E_avg)).
    Notes,
}

fn two() -> f32 {
    2.0
}

/// The microfacet family (core::models::microfacet); field names are the
/// `specula eval` contract.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MicrofacetDesc {
    pub ndf: NdfDesc,
    /// GTR exponent (ignored by the other NDFs).
    #[serde(default = "two")]
    pub gamma: f32,
    /// Smith Λ of GTR (`ndf = "gtr"` only).
    #[serde(default)]
    pub gtr_lambda: GtrLambdaDesc,
    pub alpha: f32,
    #[serde(default)]
    pub smith: SmithDesc,
    pub fresnel: FresnelDesc,
    #[serde(default)]
    pub diffuse: [f32; 3],
    #[serde(default)]
    pub energy_compensation: bool,
    #[serde(default)]
    pub kc_color: KcColorDesc,
    #[serde(default)]
    pub double_sided: bool,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LambertDesc {
    pub base_color: [f32; 3],
    /// An sRGB image multiplying base_color at the surface's uv.
    #[serde(default)]
    pub base_color_texture: Option<PathBuf>,
    /// Refused (lambert has no metallic or roughness); accepted here so
    /// the message says why rather than "unknown field".
    #[serde(default)]
    pub metallic_roughness_texture: Option<PathBuf>,
    // The maps every lit model takes (`SurfaceMaps`):
    /// A linear tangent-space normal map (glTF's normalTexture).
    #[serde(default)]
    pub normal_texture: Option<PathBuf>,
    /// Scales the normal map's x and y.
    #[serde(default = "one")]
    pub normal_scale: f32,
    /// A linear image whose red channel darkens the environment term.
    #[serde(default)]
    pub occlusion_texture: Option<PathBuf>,
    /// 1 + strength · (occlusion − 1); in [0, 1].
    #[serde(default = "one")]
    pub occlusion_strength: f32,
    /// Emitted radiance, linear RGB (the emissive texture multiplies it).
    #[serde(default)]
    pub emissive: [f32; 3],
    /// An sRGB image multiplying `emissive`.
    #[serde(default)]
    pub emissive_texture: Option<PathBuf>,
    /// "nearest", "bilinear", "trilinear" (default), "anisotropic" (16
    /// taps) or "anisotropic:N" (N in 1..=16), for every texture of the
    /// material.
    #[serde(default)]
    pub texture_filter: Option<String>,
    /// "repeat" (default), "clamp_to_edge" or "mirrored_repeat", or a pair
    /// [u, v] of them.
    #[serde(default)]
    pub texture_wrap: Option<WrapsDesc>,
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
    /// An sRGB image multiplying base_color at the surface's uv.
    #[serde(default)]
    pub base_color_texture: Option<PathBuf>,
    /// A linear image whose blue channel multiplies metallic and green
    /// channel roughness (glTF's metallicRoughnessTexture).
    #[serde(default)]
    pub metallic_roughness_texture: Option<PathBuf>,
    // The maps every lit model takes (`SurfaceMaps`):
    /// A linear tangent-space normal map (glTF's normalTexture).
    #[serde(default)]
    pub normal_texture: Option<PathBuf>,
    /// Scales the normal map's x and y.
    #[serde(default = "one")]
    pub normal_scale: f32,
    /// A linear image whose red channel darkens the environment term.
    #[serde(default)]
    pub occlusion_texture: Option<PathBuf>,
    /// 1 + strength · (occlusion − 1); in [0, 1].
    #[serde(default = "one")]
    pub occlusion_strength: f32,
    /// Emitted radiance, linear RGB (the emissive texture multiplies it).
    #[serde(default)]
    pub emissive: [f32; 3],
    /// An sRGB image multiplying `emissive`.
    #[serde(default)]
    pub emissive_texture: Option<PathBuf>,
    /// "nearest", "bilinear", "trilinear" (default), "anisotropic" (16
    /// taps) or "anisotropic:N" (N in 1..=16), for every texture of the
    /// material.
    #[serde(default)]
    pub texture_filter: Option<String>,
    /// "repeat" (default), "clamp_to_edge" or "mirrored_repeat", or a pair
    /// [u, v] of them.
    #[serde(default)]
    pub texture_wrap: Option<WrapsDesc>,
    #[serde(default)]
    pub double_sided: bool,
}

/// The fields of a lit material (`lambert`, `metallic_roughness`) for
/// the maps that belong to the material whatever its model (normal,
/// occlusion, emission; raster's maps.rs) and the sampler all of its
/// textures use, borrowed from its table.
#[derive(Clone, Copy, Debug, PartialEq)]
struct SurfaceMaps<'a> {
    normal_texture: Option<&'a Path>,
    normal_scale: f32,
    occlusion_texture: Option<&'a Path>,
    occlusion_strength: f32,
    emissive: [f32; 3],
    emissive_texture: Option<&'a Path>,
    texture_filter: Option<&'a str>,
    texture_wrap: Option<&'a WrapsDesc>,
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
pub enum WrapsDesc {
    Both(String),
    Axes([String; 2]),
}

/// glTF's wrap modes by their glTF names in snake case.
fn wrap_mode(name: &str) -> Result<Wrap, String> {
    match name {
        "repeat" => Ok(Wrap::Repeat),
        "clamp_to_edge" => Ok(Wrap::Clamp),
        "mirrored_repeat" => Ok(Wrap::Mirror),
        _ => Err(format!(
            "texture_wrap: expected \"repeat\", \"clamp_to_edge\" or \"mirrored_repeat\", got {name:?}"
        )),
    }
}

impl<'a> SurfaceMaps<'a> {
    /// The sampler of the material's textures, checked.
    fn sampler(&self) -> Result<Sampler, String> {
        let filter = match self.texture_filter {
            Some(f) => f.parse().map_err(|e| format!("texture_filter: {e}"))?,
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
    fn files(&self) -> [(&'static str, Option<&'a Path>); 3] {
        [
            ("normal_texture", self.normal_texture),
            ("occlusion_texture", self.occlusion_texture),
            ("emissive_texture", self.emissive_texture),
        ]
    }
}

/// Burley's principled BRDF (core::models::disney); field names and
/// defaults are the `specula eval` contract (README).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct DisneyDesc {
    pub base_color: [f32; 3],
    pub metallic: f32,
    pub subsurface: f32,
    pub specular: f32,
    pub specular_tint: f32,
    pub roughness: f32,
    pub anisotropic: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub clearcoat: f32,
    pub clearcoat_gloss: f32,
    pub energy_compensation: bool,
    pub double_sided: bool,
}

impl Default for DisneyDesc {
    fn default() -> DisneyDesc {
        let p = DisneyParams::default();
        DisneyDesc {
            base_color: p.base_color,
            metallic: p.metallic,
            subsurface: p.subsurface,
            specular: p.specular,
            specular_tint: p.specular_tint,
            roughness: p.roughness,
            anisotropic: p.anisotropic,
            sheen: p.sheen,
            sheen_tint: p.sheen_tint,
            clearcoat: p.clearcoat,
            clearcoat_gloss: p.clearcoat_gloss,
            energy_compensation: false,
            double_sided: false,
        }
    }
}

/// The glTF 2.0 material with KHR_materials_ior, _specular, _clearcoat and
/// _sheen (core::models::gltf): the glTF names in snake_case, the glTF
/// defaults.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct GltfDesc {
    pub base_color_factor: [f32; 3],
    pub metallic_factor: f32,
    pub roughness_factor: f32,
    pub ior: f32,
    pub specular_factor: f32,
    pub specular_color_factor: [f32; 3],
    pub clearcoat_factor: f32,
    pub clearcoat_roughness_factor: f32,
    pub sheen_color_factor: [f32; 3],
    pub sheen_roughness_factor: f32,
    /// `"normative"` (Appendix B's fresnel_mix) or `"simplified"` (the
    /// diffuse lobe weighted by 1 − F with F0 = mix(dielectric F0, base,
    /// metallic)); read as text so that an unknown value names the field.
    pub fresnel: String,
    /// An sRGB image multiplying base_color_factor at the surface's uv.
    pub base_color_texture: Option<PathBuf>,
    pub double_sided: bool,
}

impl Default for GltfDesc {
    fn default() -> GltfDesc {
        let p = GltfParams::default();
        GltfDesc {
            base_color_factor: p.base_color,
            metallic_factor: p.metallic,
            roughness_factor: p.roughness,
            ior: p.ior,
            specular_factor: p.specular,
            specular_color_factor: p.specular_color,
            clearcoat_factor: p.clearcoat,
            clearcoat_roughness_factor: p.clearcoat_roughness,
            sheen_color_factor: p.sheen_color,
            sheen_roughness_factor: p.sheen_roughness,
            fresnel: "normative".into(),
            base_color_texture: None,
            double_sided: false,
        }
    }
}

impl GltfDesc {
    /// Every field checked, each against the range its glTF schema gives:
    /// factors in [0, 1] (NaN refused), `specular_color_factor` components
    /// finite and ≥ 0 (KHR_materials_specular allows values above 1; F0 is
    /// clamped to 1 after the IOR's r0 multiplies it), `ior` ≥ 1 and at
    /// most 1e4, or exactly 0 (KHR_materials_ior's infinite IOR).
    pub(crate) fn params(&self) -> Result<GltfParams, String> {
        let unit3 = |field: &str, c: [f32; 3]| -> Result<(), String> {
            if c.iter().all(|v| (0.0..=1.0).contains(v)) {
                Ok(())
            } else {
                Err(format!(
                    "{field}: every component must be in [0, 1], got {c:?}"
                ))
            }
        };
        unit3("base_color_factor", self.base_color_factor)?;
        unit3("sheen_color_factor", self.sheen_color_factor)?;
        checks::linear_color("specular_color_factor", self.specular_color_factor)?;
        for (field, v) in [
            ("metallic_factor", self.metallic_factor),
            ("roughness_factor", self.roughness_factor),
            ("specular_factor", self.specular_factor),
            ("clearcoat_factor", self.clearcoat_factor),
            (
                "clearcoat_roughness_factor",
                self.clearcoat_roughness_factor,
            ),
            ("sheen_roughness_factor", self.sheen_roughness_factor),
        ] {
            checks::unit(field, v)?;
        }
        if !(self.ior == 0.0 || (1.0..=MAX_IOR).contains(&self.ior)) {
            return Err(format!(
                "ior: must be in [1, 1e4], or 0 for an infinite IOR, got {}",
                self.ior
            ));
        }
        Ok(GltfParams {
            base_color: self.base_color_factor,
            metallic: self.metallic_factor,
            roughness: self.roughness_factor,
            ior: self.ior,
            specular: self.specular_factor,
            specular_color: self.specular_color_factor,
            clearcoat: self.clearcoat_factor,
            clearcoat_roughness: self.clearcoat_roughness_factor,
            sheen_color: self.sheen_color_factor,
            sheen_roughness: self.sheen_roughness_factor,
            fresnel: match self.fresnel.as_str() {
                "normative" => GltfFresnel::Normative,
                "simplified" => GltfFresnel::Simplified,
                other => {
                    return Err(format!(
                        "fresnel: must be \"normative\" or \"simplified\", got {:?}",
                        crate::validate::truncate_echo(other, 100)
                    ))
                }
            },
        })
    }
}

/// Largest `specular`: 0.08 specular is the dielectric's F0, which cannot
/// exceed 1.
const DISNEY_SPECULAR_MAX: f32 = 12.5;

/// Largest Disney `roughness`: α = roughness² up to 100, and the diffuse
/// retro-reflection F_D90 = ½ + 2 cos²θd · roughness up to 20.5, so the
/// diffuse lobe multiplies light by at most ≈ 400 times `base_color`.
/// Beyond Burley's [0, 1] the lobe is an extrapolation; far beyond it the
/// terms overflow f32 (α = roughness² is infinite at 1.9e19).
const DISNEY_ROUGHNESS_MAX: f32 = 10.0;

/// Largest GTR exponent γ. Past it the lobe at α < 1 is narrower than the
/// α floor of every other NDF (its width shrinks as α/√γ), and the f32
/// evaluation of r^(−γ) (module docs of `core::ndf::d_gtr`) loses its
/// digits: γ · 6e-8 nears 1.
pub const GTR_GAMMA_MAX: f32 = 1e6;

impl DisneyDesc {
    /// Every field checked. Burley's parameters live in [0, 1]; beyond it:
    /// - accepted with a warning where the formula still means something:
    ///   `base_color` components above 1 (albedo > 1), `specular` in
    ///   (1, 12.5] (F0 = 0.08 specular up to 1: IORs above 1.8),
    ///   `roughness` above 1 (α = roughness² > 1, a valid but flatter
    ///   lobe), `sheen` and `clearcoat` above 1 (stronger lobes);
    /// - errors elsewhere: NaN or infinite values, negatives, and values
    ///   above 1 of `metallic`, `subsurface`, `specular_tint`, `sheen_tint`
    ///   and `anisotropic` (mixing weights: past 1 the blends extrapolate
    ///   to negative reflectance; aspect = √(1 − 0.9 anisotropic) turns
    ///   imaginary past 1.11) and of `clearcoat_gloss` (α of the coat < 0).
    fn params(&self, warnings: &mut Vec<String>) -> Result<DisneyParams, String> {
        checks::linear_color("base_color", self.base_color)?;
        if self.base_color.iter().any(|c| *c > 1.0) {
            warnings.push(format!(
                "base_color {:?} has components above 1: the material reflects more than it receives",
                self.base_color
            ));
        }
        let finite_nonneg = |field: &str, v: f32| -> Result<(), String> {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(format!("{field}: must be finite and ≥ 0, got {v}"))
            }
        };
        for (field, v) in [
            ("metallic", self.metallic),
            ("subsurface", self.subsurface),
            ("specular_tint", self.specular_tint),
            ("anisotropic", self.anisotropic),
            ("sheen_tint", self.sheen_tint),
            ("clearcoat_gloss", self.clearcoat_gloss),
        ] {
            finite_nonneg(field, v)?;
            checks::unit(field, v)?;
        }
        for (field, v, max, why) in [
            (
                "specular",
                self.specular,
                DISNEY_SPECULAR_MAX,
                "F0 = 0.08 · specular above 0.08, i.e. an IOR above ≈ 1.8",
            ),
            (
                "roughness",
                self.roughness,
                DISNEY_ROUGHNESS_MAX,
                "α = roughness² above 1",
            ),
            (
                "sheen",
                self.sheen,
                checks::MAX_LINEAR_COLOR,
                "a sheen stronger than Burley's range",
            ),
            (
                "clearcoat",
                self.clearcoat,
                checks::MAX_LINEAR_COLOR,
                "a clearcoat stronger than Burley's range",
            ),
        ] {
            finite_nonneg(field, v)?;
            if v > max {
                return Err(format!("{field}: must be ≤ {max}, got {v}"));
            }
            if v > 1.0 {
                warnings.push(format!(
                    "{field} {v} is beyond Burley's range [0, 1] ({why})"
                ));
            }
        }
        Ok(DisneyParams {
            base_color: self.base_color,
            metallic: self.metallic,
            subsurface: self.subsurface,
            specular: self.specular,
            specular_tint: self.specular_tint,
            roughness: self.roughness,
            anisotropic: self.anisotropic,
            sheen: self.sheen,
            sheen_tint: self.sheen_tint,
            clearcoat: self.clearcoat,
            clearcoat_gloss: self.clearcoat_gloss,
        })
    }
}

/// Whether to tabulate what uniform environment light needs (scenes) or
/// not (`specula eval` evaluates f only, and builds many materials).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tables {
    Build,
    Skip,
}

fn check_positive(field: &str, v: f32) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!("{field}: must be finite and > 0, got {v}"))
    }
}

/// Largest accepted η, κ or ior. The conductor Fresnel squares η² − κ²,
/// so (1e4)⁴ = 1e16 keeps it inside f32 (3.4e38); real materials stay
/// below about 100.
const MAX_IOR: f32 = 1e4;

fn check_ior(field: &str, v: f32, zero_ok: bool) -> Result<(), String> {
    let low_ok = if zero_ok { v >= 0.0 } else { v > 0.0 };
    if low_ok && v <= MAX_IOR {
        Ok(())
    } else {
        let low = if zero_ok { "[0" } else { "(0" };
        Err(format!("{field}: must be in {low}, 1e4], got {v}"))
    }
}

impl MicrofacetDesc {
    fn params(&self, warnings: &mut Vec<String>) -> Result<MicrofacetParams, String> {
        if !(self.alpha.is_finite() && self.alpha >= 0.0) {
            return Err(format!(
                "alpha: must be a finite number ≥ 0 (values outside [1e-3, 1] are clamped into it), got {}",
                self.alpha
            ));
        }
        let (alpha, clamped) = clamp_alpha(self.alpha);
        if clamped {
            warnings.push(format!(
                "alpha {} clamped to {alpha} (the valid range is [1e-3, 1])",
                self.alpha
            ));
        }
        if !(self.gamma > 0.0 && self.gamma <= GTR_GAMMA_MAX) {
            return Err(format!(
                "gamma: must be in (0, {GTR_GAMMA_MAX:e}], got {}",
                self.gamma
            ));
        }
        let gtr_lambda = match (self.ndf, self.gtr_lambda) {
            (_, GtrLambdaDesc::Ggx) => GtrLambda::Ggx,
            (NdfDesc::Gtr, GtrLambdaDesc::Exact) => GtrLambda::exact(self.gamma, alpha),
            (_, GtrLambdaDesc::Exact) => {
                return Err(
                    "gtr_lambda: \"exact\" applies to ndf = \"gtr\" only (GGX and Beckmann always use their exact Λ)"
                        .into(),
                )
            }
        };
        checks::linear_color("diffuse", self.diffuse)?;
        let fresnel = match &self.fresnel {
            FresnelDesc::Schlick { f0 } => {
                checks::linear_color("fresnel.f0", *f0)?;
                if f0.iter().any(|c| *c > 1.0) {
                    return Err(format!("fresnel.f0: components must be ≤ 1, got {f0:?}"));
                }
                Fresnel::Schlick { f0: *f0 }
            }
            FresnelDesc::Dielectric { ior } => {
                check_ior("fresnel.ior", *ior, false)?;
                Fresnel::Dielectric { ior: *ior }
            }
            FresnelDesc::Conductor { eta, k } => {
                for (c, v) in eta.iter().enumerate() {
                    check_ior(&format!("fresnel.eta[{c}]"), *v, false)?;
                }
                for (c, v) in k.iter().enumerate() {
                    check_ior(&format!("fresnel.k[{c}]"), *v, true)?;
                }
                Fresnel::Conductor { eta: *eta, k: *k }
            }
        };
        Ok(MicrofacetParams {
            ndf: match self.ndf {
                NdfDesc::Ggx => Ndf::Ggx,
                NdfDesc::Beckmann => Ndf::Beckmann,
                NdfDesc::Gtr => Ndf::Gtr { gamma: self.gamma },
            },
            alpha,
            smith: match self.smith {
                SmithDesc::Separable => Smith::Separable,
                SmithDesc::HeightCorrelated => Smith::HeightCorrelated,
            },
            fresnel,
            diffuse: self.diffuse,
            gtr_lambda,
        })
    }
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
    /// such as a clamped alpha are pushed to `warnings`.
    pub fn build(
        &self,
        name: &str,
        tables: Tables,
        warnings: &mut Vec<String>,
    ) -> Result<Material, String> {
        let no_files = |p: &Path| -> std::io::Result<Vec<u8>> {
            Err(std::io::Error::new(
                std::io::ErrorKind::NotFound,
                format!("{}: no files are available here", p.display()),
            ))
        };
        self.build_with(name, tables, warnings, &no_files)
    }

    /// [`MaterialDesc::build`] with the files the material names (textures,
    /// tonal art maps) read through `read`.
    pub fn build_with(
        &self,
        name: &str,
        tables: Tables,
        warnings: &mut Vec<String>,
        read: ReadFile,
    ) -> Result<Material, String> {
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
    pub fn texture_files(&self) -> Vec<&Path> {
        self.texture_fields().into_iter().map(|(_, p)| p).collect()
    }

    /// The material has a normal map: its meshes need tangents
    /// (tangents.rs).
    pub fn has_normal_map(&self) -> bool {
        self.surface_maps()
            .is_some_and(|m| m.normal_texture.is_some())
    }

    /// A lit material's maps, every field checked and every image read
    /// through `read`, and its emissive colour.
    fn param_maps(
        &self,
        warnings: &mut Vec<String>,
        read: ReadFile,
    ) -> Result<(ParamMaps, [f32; 3]), String> {
        let Some(m) = self.surface_maps() else {
            return Ok((ParamMaps::default(), [0.0; 3]));
        };
        let sampler = m.sampler()?;
        if !m.normal_scale.is_finite() {
            return Err(format!(
                "normal_scale: must be a finite number, got {}",
                m.normal_scale
            ));
        }
        checks::unit("occlusion_strength", m.occlusion_strength)?;
        checks::linear_color("emissive", m.emissive)?;
        if m.emissive_texture.is_some() && m.emissive == [0.0; 3] {
            warnings.push(
                "emissive_texture: multiplies `emissive`, which is [0, 0, 0] (glTF's default): the material emits nothing"
                    .into(),
            );
        }
        let load = |field: &str, path: Option<&Path>, encoding: Encoding| {
            path.map(|p| {
                crate::textures::load_map(p, read, encoding, sampler)
                    .map_err(|e| format!("{field}: {e}"))
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
        };
        Ok((maps, m.emissive))
    }

    /// The base-colour image the material names, if any.
    pub fn base_color_texture(&self) -> Option<&Path> {
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
    pub fn needs_uvs(&self) -> bool {
        !self.texture_fields().is_empty() || matches!(self, MaterialDesc::Hatching(_))
    }

    /// [`MaterialDesc::build`] before it becomes a shader (what `specula
    /// eval` evaluates), and whether it is double-sided. Only materials
    /// with a BRDF value at a direction pair have one: stylized shaders
    /// and textured materials (whose value depends on uv) are refused.
    pub fn build_shading(
        &self,
        tables: Tables,
        warnings: &mut Vec<String>,
    ) -> Result<(Shading, bool), String> {
        if let Some((field, _)) = self.texture_fields().first() {
            return Err(format!("{field}: a textured material has no single BRDF value (it depends on uv); leave the texture out"));
        }
        if self.surface_maps().is_some_and(|m| m.emissive != [0.0; 3]) {
            return Err("emissive: emission is radiance the surface adds, not part of its BRDF value; leave it out".into());
        }
        if let MaterialDesc::Toon(_) | MaterialDesc::Hatching(_) = self {
            return Err(
                "model: \"toon\" and \"hatching\" are stylized shaders with no BRDF value".into(),
            );
        }
        self.build_model(tables, warnings)
    }

    fn build_model(
        &self,
        tables: Tables,
        warnings: &mut Vec<String>,
    ) -> Result<(Shading, bool), String> {
        let (model, double_sided) = match self {
            MaterialDesc::Toon(_) | MaterialDesc::Hatching(_) => {
                return Err("model: a stylized shader has no BRDF".into())
            }
            MaterialDesc::Unlit(d) => {
                checks::linear_color("color", d.color)?;
                if !(0.0..=checks::MAX_RADIOMETRIC).contains(&d.intensity) {
                    return Err(format!(
                        "intensity: must be finite and in [0, {:e}], got {}",
                        checks::MAX_RADIOMETRIC,
                        d.intensity
                    ));
                }
                if d.color.iter().any(|c| !(c * d.intensity).is_finite()) {
                    return Err(format!(
                        "intensity: color × intensity overflows f32 ({:?} × {})",
                        d.color, d.intensity
                    ));
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

impl ToonDesc {
    fn shader(&self, read: ReadFile) -> Result<Toon, String> {
        checks::linear_color("base_color", self.base_color)?;
        // Checked whether or not their threshold is set: a colour in the
        // file is a colour, used or not.
        checks::linear_color("specular_color", self.specular_color)?;
        checks::linear_color("rim_color", self.rim_color)?;
        let ramp = match (&self.bands, &self.ramp) {
            (Some(_), Some(_)) => return Err("bands / ramp: give one of them, not both".into()),
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
                    return Err(format!("{field}: must be in [-1, 1], got {t}"));
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
            Some(p) => Some(
                crate::textures::load_color_map(p, read)
                    .map_err(|e| format!("base_color_texture: {e}"))?,
            ),
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
    fn shader(&self, read: ReadFile) -> Result<Hatching, String> {
        checks::linear_color("ink", self.ink)?;
        checks::linear_color("paper", self.paper)?;
        check_positive("scale", self.scale)?;
        let tam = match &self.tam {
            Some(dir) => Arc::new(
                TamTexture::read_with_budget(dir, read, &crate::memory::reserve)
                    .map_err(|e| format!("tam: {e}"))?,
            ),
            None => builtin_tam().map_err(|e| format!("tam: the built-in map: {e}"))?,
        };
        Ok(Hatching {
            tam,
            ink: self.ink,
            paper: self.paper,
            scale: self.scale,
        })
    }
}
