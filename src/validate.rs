//! Small checks shared by the scene loader, `eval` and the CLI: how to quote
//! user input back in a message, and range checks for numeric fields.

/// `s` cut to at most `max` characters (on a character boundary), with the
/// number of characters left out, so a 5 MB bad value does not come back as
/// 5 MB of error message.
pub(crate) fn truncate_echo(s: &str, max: usize) -> String {
    match s.char_indices().nth(max) {
        None => s.to_string(),
        Some((cut, _)) => {
            let left = s[cut..].chars().count();
            format!("{}… ({left} more characters)", &s[..cut])
        }
    }
}

/// Every line of `s` cut to at most `max` characters (`truncate_echo`):
/// for messages that may quote user input (a TOML error shows the line).
pub fn truncate_lines(s: &str, max: usize) -> String {
    s.lines()
        .map(|l| truncate_echo(l, max))
        .collect::<Vec<_>>()
        .join("\n")
}

use crate::checks::{FieldError, FieldReason};
use glam::Vec3;

/// Largest |coordinate| of a world-space point: vertices after their mesh's
/// transform, the camera, point lights. With fov_y ≥ [`MIN_FOV_Y_DEG`] the
/// projection scales view coordinates by at most 1/tan(0.0005°) ≈ 1.15e5,
/// so for images at most as tall as they are wide the clip coordinates stay
/// below 2·1e9·1.15e5 ≈ 2.3e14, inside the rasterizer's MAX_CLIP_COORD
/// (2^50 ≈ 1.1e15); and f32 still resolves 1/16 m at 1e6 m.
pub(crate) const MAX_WORLD: f32 = 1e9;

/// Smallest size of a procedural shape (radius, edge): below this the
/// triangles are sub-micrometre and f32 positions degenerate.
pub(crate) const MIN_EXTENT: f32 = 1e-6;

/// The accepted vertical field of view, degrees: tan(fov/2) stays well
/// inside f32 at both ends.
pub(crate) const MIN_FOV_Y_DEG: f32 = 1e-3;
pub(crate) const MAX_FOV_Y_DEG: f32 = 179.0;

/// A point every coordinate of which is finite and within ±[`MAX_WORLD`].
pub(crate) fn check_point(field: &str, v: [f32; 3]) -> Result<(), FieldError> {
    if v.iter().all(|x| x.abs() <= MAX_WORLD) {
        Ok(())
    } else {
        Err(FieldError::new(
            field,
            FieldReason::OutsideWorld {
                max: MAX_WORLD,
                got: v,
            },
        ))
    }
}

/// A size (radius, edge length) in [[`MIN_EXTENT`], [`MAX_WORLD`]].
pub(crate) fn check_extent(field: &str, v: f32) -> Result<(), FieldError> {
    if (MIN_EXTENT..=MAX_WORLD).contains(&v) {
        Ok(())
    } else {
        Err(FieldError::new(
            field,
            FieldReason::Extent {
                min: MIN_EXTENT,
                max: MAX_WORLD,
                got: v,
            },
        ))
    }
}

/// The unit vector along `v`; any finite non-zero `v` works, however large
/// or small its components (it is scaled by its largest one first, so
/// [3e38, −3e38, 0] does not overflow to an infinite length).
pub(crate) fn direction(field: &str, v: [f32; 3]) -> Result<Vec3, FieldError> {
    let v = Vec3::from(v);
    let m = v.abs().max_element();
    if !(v.is_finite() && m > 0.0) {
        return Err(FieldError::new(field, FieldReason::Direction(v.to_array())));
    }
    Ok((v / m).normalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truncate_keeps_short_text_and_cuts_long_text_on_a_char_boundary() {
        assert_eq!(truncate_echo("abc", 3), "abc");
        assert_eq!(truncate_echo("ééééé", 2), "éé… (3 more characters)");
        assert_eq!(truncate_lines("abcd\nef", 2), "ab… (2 more characters)\nef");
    }

    #[test]
    fn directions_of_any_finite_size_normalize() {
        let s = std::f32::consts::FRAC_1_SQRT_2;
        for (v, want) in [
            ([3e38, -3e38, 0.0], [s, -s, 0.0]),
            ([1e-40, 0.0, 0.0], [1.0, 0.0, 0.0]),
            ([0.0, 0.0, -2.0], [0.0, 0.0, -1.0]),
        ] {
            let d = direction("d", v).unwrap();
            assert!((d - Vec3::from(want)).length() < 1e-6, "{v:?} -> {d}");
        }
        for bad in [[0.0; 3], [f32::NAN, 0.0, 1.0], [f32::INFINITY, 0.0, 0.0]] {
            assert!(direction("d", bad).is_err());
        }
    }
}
