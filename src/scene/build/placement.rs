//! A mesh's `translate`, `rotate` and `scale`: checked, turned into its
//! model and normal matrices, and checked to keep its vertices inside the
//! world.

use super::super::desc::{MeshDesc, Scale};
use super::BuildError;
use crate::checks;
use crate::validate::MAX_WORLD;
use glam::{EulerRot, Mat3, Mat4, Quat, Vec3};

/// Where a mesh goes in the world: its model matrix, the matrix for its
/// normals, and whether it mirrors (which flips the winding).
pub(in crate::scene) struct Placement {
    pub(super) model: Mat4,
    pub(super) normal_m: Mat3,
    pub(super) flip: bool,
}

/// The accepted |scale| per axis: their ratio (≤ 1e24) keeps the normal
/// matrix finite in f32.
const MIN_SCALE: f32 = 1e-12;
const MAX_SCALE: f32 = 1e12;

/// Checks that a mesh's transform keeps its (finite, in-range) vertices
/// inside ±MAX_WORLD.
fn check_transform(field: &str, positions: &[Vec3], model: &Mat4) -> Result<(), BuildError> {
    let inside = |p: Vec3| p.is_finite() && p.abs().max_element() <= MAX_WORLD;
    if let Some(p) = positions
        .iter()
        .find(|p| inside(**p) && !inside(model.transform_point3(**p)))
    {
        return Err(BuildError::OutsideWorld {
            field: field.to_string(),
            from: *p,
            to: model.transform_point3(*p),
        });
    }
    Ok(())
}

/// The mesh's `translate`, `rotate` and `scale`, checked, and checked to
/// keep its vertices inside the world.
pub(in crate::scene) fn place_mesh(
    field: &str,
    md: &MeshDesc,
    positions: &[Vec3],
) -> Result<Placement, BuildError> {
    let scale = match md.scale {
        Scale::Uniform(s) => Vec3::splat(s),
        Scale::Axes(a) => Vec3::from(a),
    };
    checks::finite(&format!("{field}.translate"), &md.translate)?;
    checks::finite(&format!("{field}.rotate"), &md.rotate)?;
    if !(scale.abs().cmpge(Vec3::splat(MIN_SCALE)) & scale.abs().cmple(Vec3::splat(MAX_SCALE)))
        .all()
    {
        return Err(BuildError::Scale {
            field: field.to_string(),
            min: MIN_SCALE,
            max: MAX_SCALE,
            got: scale,
        });
    }
    let r = md.rotate.map(f32::to_radians);
    let rot = Quat::from_euler(EulerRot::ZYX, r[2], r[1], r[0]);
    let model = Mat4::from_scale_rotation_translation(scale, rot, md.translate.into());
    // (R·S)⁻ᵀ = R·S⁻¹, scaled by the smallest |s| so no entry overflows
    // (normals are renormalized anyway).
    let normal_m =
        Mat3::from_quat(rot) * Mat3::from_diagonal(Vec3::splat(scale.abs().min_element()) / scale);
    let flip = model.determinant() < 0.0;
    check_transform(field, positions, &model)?;
    Ok(Placement {
        model,
        normal_m,
        flip,
    })
}
