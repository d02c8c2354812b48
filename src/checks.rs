//! Checks of single scene and material fields, shared by the scene reader,
//! the material descriptions (scenes and `eval`), the line tables and the
//! labels. Each rule lives here once; its message names the field.

/// Largest accepted radiometric value (radiance, intensity, irradiance).
/// A pixel sums lights × BRDF (up to ~3e5 at α = 1e-3) over up to 256
/// supersamples: 1e20 · 3e5 · 256 ≈ 8e27 leaves f32 (3.4e38) room for many
/// lights; a uniform environment of 3e38 overflowed at ssaa 4.
pub(crate) const MAX_RADIOMETRIC: f32 = 1e20;

/// Every component finite.
pub(crate) fn finite(field: &str, v: &[f32]) -> Result<(), String> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(format!(
            "{field}: every component must be finite, got {v:?}"
        ))
    }
}

/// A light's or the background's radiometric RGB: finite, in
/// [0, `MAX_RADIOMETRIC`].
pub(crate) fn radiometric(field: &str, v: [f32; 3]) -> Result<(), String> {
    finite(field, &v)?;
    if v.iter().all(|x| (0.0..=MAX_RADIOMETRIC).contains(x)) {
        Ok(())
    } else {
        Err(format!(
            "{field}: every component must be in [0, {MAX_RADIOMETRIC:e}], got {v:?}"
        ))
    }
}

/// Largest accepted component of a linear colour a material multiplies
/// light by. Colours above 1 reflect more than they receive and are
/// allowed (some models warn), but bounded: with lights up to
/// [`MAX_RADIOMETRIC`], BRDF peaks of ~3e5 and 256 supersamples, 1e6 keeps a
/// pixel's sum (~8e33) inside f32.
pub(crate) const MAX_LINEAR_COLOR: f32 = 1e6;

/// A linear colour a material multiplies light by (albedo, ink, ramp
/// steps, emission colours): finite, in [0, `MAX_LINEAR_COLOR`].
pub(crate) fn linear_color(field: &str, c: [f32; 3]) -> Result<(), String> {
    if c.iter().all(|v| (0.0..=MAX_LINEAR_COLOR).contains(v)) {
        Ok(())
    } else {
        Err(format!(
            "{field}: colour components must be finite and in [0, {MAX_LINEAR_COLOR:e}], got {c:?}"
        ))
    }
}

/// A display colour drawn over the finished image (outlines, strokes,
/// labels): every component in [0, 1].
pub(crate) fn display_color(field: &str, c: [f32; 3]) -> Result<(), String> {
    if c.iter().all(|v| (0.0..=1.0).contains(v)) {
        Ok(())
    } else {
        Err(format!(
            "{field}: every component must be in [0, 1], got {c:?}"
        ))
    }
}

/// A weight in [0, 1] (NaN refused).
pub(crate) fn unit(field: &str, v: f32) -> Result<(), String> {
    if (0.0..=1.0).contains(&v) {
        Ok(())
    } else {
        Err(format!("{field}: must be in [0, 1], got {v}"))
    }
}
