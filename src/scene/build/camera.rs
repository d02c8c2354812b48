//! `[camera]`: checked and turned into the rasterizer's camera.

use super::super::desc::CameraDesc;
use super::BuildError;
use crate::checks;
use crate::validate::{check_point, MAX_FOV_Y_DEG, MIN_FOV_Y_DEG};
use glam::Vec3;
use specula_raster::Camera;

/// `[camera]`: finite, inside the world, a usable field of view and depth
/// range, and a frame that eye, target and up can span.
pub(in crate::scene) fn build_camera(c: &CameraDesc) -> Result<Camera, BuildError> {
    for (f, v) in [
        ("camera.eye", &c.eye),
        ("camera.target", &c.target),
        ("camera.up", &c.up),
    ] {
        checks::finite(f, v)?;
    }
    check_point("camera.eye", c.eye)?;
    check_point("camera.target", c.target)?;
    if !(MIN_FOV_Y_DEG..=MAX_FOV_Y_DEG).contains(&c.fov_y) {
        return Err(BuildError::FovY(c.fov_y));
    }
    // Depth is reversed (camera.rs), so any near/far ratio keeps its
    // precision; only the near plane must be a positive finite distance.
    // `far = inf` (TOML's infinity) is an infinite far plane.
    if !(c.near > 0.0 && c.near.is_finite() && c.far > c.near) {
        return Err(BuildError::NearFar {
            near: c.near,
            far: c.far,
        });
    }
    let forward = Vec3::from(c.target) - Vec3::from(c.eye);
    if forward.length_squared() == 0.0 || forward.cross(Vec3::from(c.up)).length_squared() == 0.0 {
        return Err(BuildError::NoFrame);
    }
    Ok(Camera {
        eye: c.eye.into(),
        target: c.target.into(),
        up: c.up.into(),
        fov_y_deg: c.fov_y,
        near: c.near,
        far: c.far,
    })
}
