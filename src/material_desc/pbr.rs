//! Physically based descriptions: lambert, metallic_roughness, microfacet,
//! disney, gltf, with the checks of their fields.

use super::*;

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(crate) enum NdfDesc {
    Ggx,
    Beckmann,
    Gtr,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub(crate) enum SmithDesc {
    Separable,
    #[default]
    HeightCorrelated,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub(crate) enum FresnelDesc {
    Schlick { f0: [f32; 3] },
    Dielectric { ior: f32 },
    Conductor { eta: [f32; 3], k: [f32; 3] },
}

/// Which Smith Λ `ndf = "gtr"` uses.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub(crate) enum GtrLambdaDesc {
    /// GGX's Λ at the same α.
    #[default]
    Ggx,
    /// The GTR distribution's own Λ, tabulated per material.
    Exact,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub(crate) enum KcColorDesc {
    /// F_avg² E_avg / (1 − F_avg (1 − E_avg)) \[Kulla17\].
    #[default]
    KullaConty,
    /// The course notes' F_avg E_avg / (1 − F_avg (1 − E_avg)).
    Notes,
}

pub(super) fn two() -> f32 {
    2.0
}

/// The microfacet family (core::models::microfacet); field names are the
/// `specula eval` contract.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MicrofacetDesc {
    pub(crate) ndf: NdfDesc,
    /// GTR exponent (ignored by the other NDFs).
    #[serde(default = "two")]
    pub(crate) gamma: f32,
    /// Smith Λ of GTR (`ndf = "gtr"` only).
    #[serde(default)]
    pub(crate) gtr_lambda: GtrLambdaDesc,
    pub alpha: f32,
    #[serde(default)]
    pub(crate) smith: SmithDesc,
    pub(crate) fresnel: FresnelDesc,
    #[serde(default)]
    pub(crate) diffuse: [f32; 3],
    #[serde(default)]
    pub energy_compensation: bool,
    #[serde(default)]
    pub(crate) kc_color: KcColorDesc,
    #[serde(default)]
    pub(crate) double_sided: bool,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LambertDesc {
    pub(crate) base_color: [f32; 3],
    /// An sRGB image multiplying base_color at the surface's uv.
    #[serde(default)]
    pub(crate) base_color_texture: Option<PathBuf>,
    /// Refused (lambert has no metallic or roughness); accepted here so
    /// the message says why rather than "unknown field".
    #[serde(default)]
    pub(crate) metallic_roughness_texture: Option<PathBuf>,
    // The maps every lit model takes (`SurfaceMaps`):
    /// A linear tangent-space normal map (glTF's normalTexture).
    #[serde(default)]
    pub(crate) normal_texture: Option<PathBuf>,
    /// Scales the normal map's x and y.
    #[serde(default = "one")]
    pub(crate) normal_scale: f32,
    /// A linear image whose red channel darkens the environment term.
    #[serde(default)]
    pub(crate) occlusion_texture: Option<PathBuf>,
    /// 1 + strength · (occlusion − 1); in [0, 1].
    #[serde(default = "one")]
    pub(crate) occlusion_strength: f32,
    /// Emitted radiance, linear RGB (the emissive texture multiplies it).
    #[serde(default)]
    pub(crate) emissive: [f32; 3],
    /// An sRGB image multiplying `emissive`.
    #[serde(default)]
    pub(crate) emissive_texture: Option<PathBuf>,
    /// "nearest", "bilinear", "trilinear" (default), "anisotropic" (16
    /// taps) or "anisotropic:N" (N in 1..=16), for every texture of the
    /// material.
    #[serde(default)]
    pub(crate) texture_filter: Option<String>,
    /// "repeat" (default), "clamp_to_edge" or "mirrored_repeat", or a pair
    /// [u, v] of them.
    #[serde(default)]
    pub(crate) texture_wrap: Option<WrapsDesc>,
    #[serde(default)]
    pub(crate) double_sided: bool,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MetallicRoughnessDesc {
    pub(crate) base_color: [f32; 3],
    pub(crate) roughness: f32,
    #[serde(default)]
    pub(crate) metallic: f32,
    /// An sRGB image multiplying base_color at the surface's uv.
    #[serde(default)]
    pub(crate) base_color_texture: Option<PathBuf>,
    /// A linear image whose blue channel multiplies metallic and green
    /// channel roughness (glTF's metallicRoughnessTexture).
    #[serde(default)]
    pub(crate) metallic_roughness_texture: Option<PathBuf>,
    // The maps every lit model takes (`SurfaceMaps`):
    /// A linear tangent-space normal map (glTF's normalTexture).
    #[serde(default)]
    pub(crate) normal_texture: Option<PathBuf>,
    /// Scales the normal map's x and y.
    #[serde(default = "one")]
    pub(crate) normal_scale: f32,
    /// A linear image whose red channel darkens the environment term.
    #[serde(default)]
    pub(crate) occlusion_texture: Option<PathBuf>,
    /// 1 + strength · (occlusion − 1); in [0, 1].
    #[serde(default = "one")]
    pub(crate) occlusion_strength: f32,
    /// Emitted radiance, linear RGB (the emissive texture multiplies it).
    #[serde(default)]
    pub(crate) emissive: [f32; 3],
    /// An sRGB image multiplying `emissive`.
    #[serde(default)]
    pub(crate) emissive_texture: Option<PathBuf>,
    /// "nearest", "bilinear", "trilinear" (default), "anisotropic" (16
    /// taps) or "anisotropic:N" (N in 1..=16), for every texture of the
    /// material.
    #[serde(default)]
    pub(crate) texture_filter: Option<String>,
    /// "repeat" (default), "clamp_to_edge" or "mirrored_repeat", or a pair
    /// [u, v] of them.
    #[serde(default)]
    pub(crate) texture_wrap: Option<WrapsDesc>,
    #[serde(default)]
    pub(crate) double_sided: bool,
}

/// Burley's principled BRDF (core::models::disney); field names and
/// defaults are the `specula eval` contract (README).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct DisneyDesc {
    pub(crate) base_color: [f32; 3],
    pub(crate) metallic: f32,
    pub(crate) subsurface: f32,
    pub(crate) specular: f32,
    pub(crate) specular_tint: f32,
    pub(crate) roughness: f32,
    pub(crate) anisotropic: f32,
    pub(crate) sheen: f32,
    pub(crate) sheen_tint: f32,
    pub(crate) clearcoat: f32,
    pub(crate) clearcoat_gloss: f32,
    pub(crate) energy_compensation: bool,
    pub(crate) double_sided: bool,
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
    pub(crate) base_color_factor: [f32; 3],
    pub(crate) metallic_factor: f32,
    pub(crate) roughness_factor: f32,
    pub(crate) ior: f32,
    pub(crate) specular_factor: f32,
    pub(crate) specular_color_factor: [f32; 3],
    pub(crate) clearcoat_factor: f32,
    pub(crate) clearcoat_roughness_factor: f32,
    pub(crate) sheen_color_factor: [f32; 3],
    pub(crate) sheen_roughness_factor: f32,
    /// `"normative"` (Appendix B's fresnel_mix) or `"simplified"` (the
    /// diffuse lobe weighted by 1 − F with F0 = mix(dielectric F0, base,
    /// metallic)); read as text so that an unknown value names the field.
    pub(crate) fresnel: String,
    /// An sRGB image multiplying base_color_factor at the surface's uv.
    pub(crate) base_color_texture: Option<PathBuf>,
    pub(crate) double_sided: bool,
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
    pub(crate) fn params(&self) -> Result<GltfParams, FieldError> {
        // The same rule as a display colour's: every component in [0, 1].
        checks::display_color("base_color_factor", self.base_color_factor)?;
        checks::display_color("sheen_color_factor", self.sheen_color_factor)?;
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
            return Err(FieldError::new("ior", FieldReason::GltfIor(self.ior)));
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
                    return Err(FieldError::new(
                        "fresnel",
                        FieldReason::GltfFresnel(crate::validate::truncate_echo(other, 100)),
                    ))
                }
            },
        })
    }
}

/// Largest `specular`: 0.08 specular is the dielectric's F0, which cannot
/// exceed 1.
pub(super) const DISNEY_SPECULAR_MAX: f32 = 12.5;

/// Largest Disney `roughness`: α = roughness² up to 100, and the diffuse
/// retro-reflection F_D90 = ½ + 2 cos²θd · roughness up to 20.5, so the
/// diffuse lobe multiplies light by at most ≈ 400 times `base_color`.
/// Beyond Burley's [0, 1] the lobe is an extrapolation; far beyond it the
/// terms overflow f32 (α = roughness² is infinite at 1.9e19).
pub(super) const DISNEY_ROUGHNESS_MAX: f32 = 10.0;

/// Largest GTR exponent γ. Past it the lobe at α < 1 is narrower than the
/// α floor of every other NDF (its width shrinks as α/√γ), and the f32
/// evaluation of r^(−γ) (module docs of `core::ndf::d_gtr`) loses its
/// digits: γ · 6e-8 nears 1.
pub(crate) const GTR_GAMMA_MAX: f32 = 1e6;

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
    pub(super) fn params(&self, warnings: &mut Vec<String>) -> Result<DisneyParams, FieldError> {
        checks::linear_color("base_color", self.base_color)?;
        if self.base_color.iter().any(|c| *c > 1.0) {
            warnings.push(format!(
                "base_color {:?} has components above 1: the material reflects more than it receives",
                self.base_color
            ));
        }
        let finite_nonneg = |field: &str, v: f32| -> Result<(), FieldError> {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(FieldError::new(field, FieldReason::Negative(v)))
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
                return Err(FieldError::new(
                    field,
                    FieldReason::AboveMax { max, got: v },
                ));
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

/// Largest accepted η, κ or ior. The conductor Fresnel squares η² − κ²,
/// so (1e4)⁴ = 1e16 keeps it inside f32 (3.4e38); real materials stay
/// below about 100.
pub(super) const MAX_IOR: f32 = 1e4;

pub(super) fn check_ior(field: &str, v: f32, zero_ok: bool) -> Result<(), FieldError> {
    let low_ok = if zero_ok { v >= 0.0 } else { v > 0.0 };
    if low_ok && v <= MAX_IOR {
        Ok(())
    } else {
        let low = if zero_ok { "[0" } else { "(0" };
        Err(FieldError::new(field, FieldReason::Ior { low, got: v }))
    }
}

impl MicrofacetDesc {
    pub(super) fn params(
        &self,
        warnings: &mut Vec<String>,
    ) -> Result<MicrofacetParams, FieldError> {
        if !(self.alpha.is_finite() && self.alpha >= 0.0) {
            return Err(FieldError::new("alpha", FieldReason::Alpha(self.alpha)));
        }
        let (alpha, clamped) = clamp_alpha(self.alpha);
        if clamped {
            warnings.push(format!(
                "alpha {} clamped to {alpha} (the valid range is [1e-3, 1])",
                self.alpha
            ));
        }
        if !(self.gamma > 0.0 && self.gamma <= GTR_GAMMA_MAX) {
            return Err(FieldError::new(
                "gamma",
                FieldReason::Gamma {
                    max: GTR_GAMMA_MAX,
                    got: self.gamma,
                },
            ));
        }
        let gtr_lambda = match (self.ndf, self.gtr_lambda) {
            (_, GtrLambdaDesc::Ggx) => GtrLambda::Ggx,
            (NdfDesc::Gtr, GtrLambdaDesc::Exact) => GtrLambda::exact(self.gamma, alpha),
            (_, GtrLambdaDesc::Exact) => {
                return Err(FieldError::new(
                    "gtr_lambda",
                    FieldReason::ExactLambdaNotGtr,
                ))
            }
        };
        checks::linear_color("diffuse", self.diffuse)?;
        let fresnel = match &self.fresnel {
            FresnelDesc::Schlick { f0 } => {
                checks::linear_color("fresnel.f0", *f0)?;
                if f0.iter().any(|c| *c > 1.0) {
                    return Err(FieldError::new("fresnel.f0", FieldReason::F0AboveOne(*f0)));
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
