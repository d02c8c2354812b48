//! Checks of single scene and material fields, shared by the scene reader,
//! the material descriptions (scenes and `eval`), the line tables and the
//! labels. Each rule lives here once; its error names the field.

/// Largest accepted radiometric value (radiance, intensity, irradiance).
/// A pixel sums lights × BRDF (up to ~3e5 at α = 1e-3) over up to 256
/// supersamples: 1e20 · 3e5 · 256 ≈ 8e27 leaves f32 (3.4e38) room for many
/// lights; a uniform environment of 3e38 overflowed at ssaa 4.
pub(crate) const MAX_RADIOMETRIC: f32 = 1e20;

/// Largest accepted component of a linear colour a material multiplies
/// light by. Colours above 1 reflect more than they receive and are
/// allowed (some models warn), but bounded: with lights up to
/// [`MAX_RADIOMETRIC`], BRDF peaks of ~3e5 and 256 supersamples, 1e6 keeps a
/// pixel's sum (~8e33) inside f32.
pub(crate) const MAX_LINEAR_COLOR: f32 = 1e6;

/// A field's value refused: the field as the user wrote it (`light[2].range`,
/// `materials.red.roughness`) and why. Shows as `field: reason`.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{field}: {reason}")]
pub struct FieldError {
    pub field: String,
    pub(crate) reason: FieldReason,
}

impl FieldError {
    pub(crate) fn new(field: impl Into<String>, reason: FieldReason) -> FieldError {
        FieldError {
            field: field.into(),
            reason,
        }
    }
}

/// The seam for callers whose errors are still `String`s: `?` turns a
/// field error into the message the user sees.
impl From<FieldError> for String {
    fn from(e: FieldError) -> String {
        e.to_string()
    }
}

/// Why a field's value was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub(crate) enum FieldReason {
    /// Some component is NaN or infinite.
    #[error("every component must be finite, got {0:?}")]
    NotFinite(Vec<f32>),
    /// A radiometric RGB outside [0, `MAX_RADIOMETRIC`].
    #[error("every component must be in [0, {MAX_RADIOMETRIC:e}], got {0:?}")]
    Radiometric([f32; 3]),
    /// A material's linear colour outside [0, `MAX_LINEAR_COLOR`].
    #[error("colour components must be finite and in [0, {MAX_LINEAR_COLOR:e}], got {0:?}")]
    LinearColor([f32; 3]),
    /// A colour whose components must be in [0, 1] (display colours,
    /// glTF colour factors) that is not.
    #[error("every component must be in [0, 1], got {0:?}")]
    NotUnitRgb([f32; 3]),
    /// A weight outside [0, 1].
    #[error("must be in [0, 1], got {0}")]
    NotUnit(f32),
    /// A light's range that is not a positive distance.
    #[error("must be a distance > 0 (or inf for no cutoff), got {0}")]
    LightRange(f32),
    /// A spot light's inner angle outside [0, π/2), in the user's unit.
    #[error("must be ≥ {min} and < {max}, got {got}")]
    InnerCone {
        min: String,
        max: String,
        got: String,
    },
    /// A spot light's outer angle not in (inner, π/2], in the user's unit.
    #[error("must be > {inner_field} ({inner}) and ≤ {max}, got {got}")]
    OuterCone {
        inner_field: String,
        inner: String,
        max: String,
        got: String,
    },
    /// A world-space point beyond ±`max` (or not finite).
    #[error("every coordinate must be finite and within ±{max:e}, got {got:?}")]
    OutsideWorld { max: f32, got: [f32; 3] },
    /// A size outside [`min`, `max`].
    #[error("must be a number in [{min:e}, {max:e}], got {got}")]
    Extent { min: f32, max: f32, got: f32 },
    /// A direction that is zero or not finite.
    #[error("must be a finite non-zero vector, got {0:?}")]
    Direction([f32; 3]),
    /// A polygon light with too few or too many vertices.
    #[error("a polygon light needs 3 to {max} vertices, got {got}")]
    PolygonVertexCount { max: usize, got: usize },
    /// A polygon light whose vertices enclose no area.
    #[error("the polygon has no area")]
    NoArea,
    /// A polygon light vertex off the plane of the others.
    #[error("the polygon is not planar")]
    NotPlanar,
    /// Two polygon light vertices at one point.
    #[error("vertices {0} and {1} are the same point")]
    SamePoint(usize, usize),
    /// Two polygon light edges that cross.
    #[error("the polygon is not simple (edges {0} and {1} cross)")]
    NotSimple(usize, usize),
    /// A number that must be finite and > 0.
    #[error("must be finite and > 0, got {0}")]
    NotPositive(f32),
    /// A number that must be finite and ≥ 0.
    #[error("must be finite and ≥ 0, got {0}")]
    Negative(f32),
    /// A number that must be finite.
    #[error("must be a finite number, got {0}")]
    NotFiniteNumber(f32),
    /// A number above its largest accepted value.
    #[error("must be ≤ {max}, got {got}")]
    AboveMax { max: f32, got: f32 },
    /// A number outside [-1, 1] (a toon threshold on a cosine).
    #[error("must be in [-1, 1], got {0}")]
    NotSignedUnit(f32),
    /// An index of refraction (or extinction) outside `low`..=1e4, where
    /// `low` is `[0` or `(0`.
    #[error("must be in {low}, 1e4], got {got}")]
    Ior { low: &'static str, got: f32 },
    /// A glTF material's `ior` outside [1, 1e4] and not 0.
    #[error("must be in [1, 1e4], or 0 for an infinite IOR, got {0}")]
    GltfIor(f32),
    /// A glTF material's `fresnel` that names no variant (the value,
    /// shortened).
    #[error("must be \"normative\" or \"simplified\", got {0:?}")]
    GltfFresnel(String),
    /// A microfacet `alpha` negative or not finite.
    #[error("must be a finite number ≥ 0 (values outside [1e-3, 1] are clamped into it), got {0}")]
    Alpha(f32),
    /// A GTR `gamma` outside (0, `max`].
    #[error("must be in (0, {max:e}], got {got}")]
    Gamma { max: f32, got: f32 },
    /// `gtr_lambda = "exact"` on an NDF other than GTR.
    #[error("\"exact\" applies to ndf = \"gtr\" only (GGX and Beckmann always use their exact Λ)")]
    ExactLambdaNotGtr,
    /// A Schlick F0 with a component above 1.
    #[error("components must be ≤ 1, got {0:?}")]
    F0AboveOne([f32; 3]),
    /// A texture on a material asked for its BRDF value (`eval`).
    #[error(
        "a textured material has no single BRDF value (it depends on uv); leave the texture out"
    )]
    TexturedBrdf,
    /// Emission on a material asked for its BRDF value (`eval`).
    #[error("emission is radiance the surface adds, not part of its BRDF value; leave it out")]
    EmissiveBrdf,
    /// A stylized shader asked for its BRDF value (`eval`).
    #[error("\"toon\" and \"hatching\" are stylized shaders with no BRDF value")]
    StylizedBrdf,
    /// A stylized shader asked for its reflectance model.
    #[error("a stylized shader has no BRDF")]
    NoBrdf,
    /// An unlit material's intensity outside [0, `MAX_RADIOMETRIC`].
    #[error("must be finite and in [0, {MAX_RADIOMETRIC:e}], got {0}")]
    UnlitIntensity(f32),
    /// An unlit material whose colour times intensity overflows.
    #[error("color × intensity overflows f32 ({color:?} × {intensity})")]
    UnlitOverflow { color: [f32; 3], intensity: f32 },
    /// A toon material with both `bands` and `ramp`.
    #[error("give one of them, not both")]
    BandsAndRamp,
    /// A texture wrap mode that glTF does not name.
    #[error("expected \"repeat\", \"clamp_to_edge\" or \"mirrored_repeat\", got {0:?}")]
    Wrap(String),
}

/// Every component finite.
pub(crate) fn finite(field: &str, v: &[f32]) -> Result<(), FieldError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(FieldError::new(field, FieldReason::NotFinite(v.to_vec())))
    }
}

/// A light's or the background's radiometric RGB: finite, in
/// [0, `MAX_RADIOMETRIC`].
pub(crate) fn radiometric(field: &str, v: [f32; 3]) -> Result<(), FieldError> {
    finite(field, &v)?;
    if v.iter().all(|x| (0.0..=MAX_RADIOMETRIC).contains(x)) {
        Ok(())
    } else {
        Err(FieldError::new(field, FieldReason::Radiometric(v)))
    }
}

/// A linear colour a material multiplies light by (albedo, ink, ramp
/// steps, emission colours): finite, in [0, `MAX_LINEAR_COLOR`].
pub(crate) fn linear_color(field: &str, c: [f32; 3]) -> Result<(), FieldError> {
    if c.iter().all(|v| (0.0..=MAX_LINEAR_COLOR).contains(v)) {
        Ok(())
    } else {
        Err(FieldError::new(field, FieldReason::LinearColor(c)))
    }
}

/// A display colour drawn over the finished image (outlines, strokes,
/// labels): every component in [0, 1].
pub(crate) fn display_color(field: &str, c: [f32; 3]) -> Result<(), FieldError> {
    if c.iter().all(|v| (0.0..=1.0).contains(v)) {
        Ok(())
    } else {
        Err(FieldError::new(field, FieldReason::NotUnitRgb(c)))
    }
}

/// A weight in [0, 1] (NaN refused).
pub(crate) fn unit(field: &str, v: f32) -> Result<(), FieldError> {
    if (0.0..=1.0).contains(&v) {
        Ok(())
    } else {
        Err(FieldError::new(field, FieldReason::NotUnit(v)))
    }
}

/// A punctual light's `range`: a positive distance, or infinite (no
/// cutoff); NaN refused.
pub(crate) fn light_range(field: &str, range: f32) -> Result<(), FieldError> {
    if range > 0.0 {
        Ok(())
    } else {
        Err(FieldError::new(field, FieldReason::LightRange(range)))
    }
}

/// A spot light's half-angles in radians, as KHR_lights_punctual bounds
/// them: 0 ≤ inner < outer ≤ π/2. `inner_field` and `outer_field` name
/// the fields; `unit` turns a radian value back into the user's unit for
/// the message.
pub(crate) fn cone_angles(
    (inner_field, inner): (&str, f32),
    (outer_field, outer): (&str, f32),
    unit: &dyn Fn(f32) -> String,
) -> Result<(), FieldError> {
    let quarter = std::f32::consts::FRAC_PI_2;
    if !(0.0..quarter).contains(&inner) {
        return Err(FieldError::new(
            inner_field,
            FieldReason::InnerCone {
                min: unit(0.0),
                max: unit(quarter),
                got: unit(inner),
            },
        ));
    }
    // The slack admits 90° converted to radians in f32, a hair above π/2.
    if !(outer > inner && outer <= quarter * (1.0 + 1e-6)) {
        return Err(FieldError::new(
            outer_field,
            FieldReason::OuterCone {
                inner_field: inner_field.to_string(),
                inner: unit(inner),
                max: unit(quarter),
                got: unit(outer),
            },
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The messages, written out: the scene tests and users match them.
    #[test]
    fn field_errors_read_field_colon_reason() {
        let e = radiometric("light[0].intensity", [1.0, -1.0, 0.0]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "light[0].intensity: every component must be in [0, 1e20], got [1.0, -1.0, 0.0]"
        );
        let e = finite("camera.eye", &[0.0, f32::NAN, 1.0]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "camera.eye: every component must be finite, got [0.0, NaN, 1.0]"
        );
        let e = cone_angles(("a", 0.5), ("b", 0.25), &|r| format!("{r} rad")).unwrap_err();
        assert_eq!(e.field, "b");
        assert_eq!(
            e.to_string(),
            format!(
                "b: must be > a (0.5 rad) and ≤ {} rad, got 0.25 rad",
                std::f32::consts::FRAC_PI_2
            )
        );
        assert_eq!(String::from(e.clone()), e.to_string());
    }
}
