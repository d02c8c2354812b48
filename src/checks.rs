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

/// A punctual light's `range`: a positive distance, or infinite (no
/// cutoff); NaN refused.
pub(crate) fn light_range(field: &str, range: f32) -> Result<(), String> {
    if range > 0.0 {
        Ok(())
    } else {
        Err(format!(
            "{field}: must be a distance > 0 (or inf for no cutoff), got {range}"
        ))
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
) -> Result<(), String> {
    let quarter = std::f32::consts::FRAC_PI_2;
    if !(0.0..quarter).contains(&inner) {
        return Err(format!(
            "{inner_field}: must be ≥ {} and < {}, got {}",
            unit(0.0),
            unit(quarter),
            unit(inner)
        ));
    }
    // The slack admits 90° converted to radians in f32, a hair above π/2.
    if !(outer > inner && outer <= quarter * (1.0 + 1e-6)) {
        return Err(format!(
            "{outer_field}: must be > {inner_field} ({}) and ≤ {}, got {}",
            unit(inner),
            unit(quarter),
            unit(outer)
        ));
    }
    Ok(())
}
