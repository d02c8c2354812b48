//! The procedural shapes of `[[mesh]]` (`sphere`, `plane`, `cube`): their
//! segment counts and sizes checked, and the memory they take reserved.

use super::super::desc::{CubeDesc, MeshDesc, PlaneDesc, SphereDesc};
use super::BuildError;
use crate::memory;
use crate::mesh::{self, MeshData};
use crate::validate::check_extent;

/// Largest segment count a procedural mesh accepts (per axis).
const MAX_SEGMENTS: u32 = 4096;

fn check_segments(field: &str, v: u32, min: u32) -> Result<(), BuildError> {
    if (min..=MAX_SEGMENTS).contains(&v) {
        Ok(())
    } else {
        Err(BuildError::Segments {
            field: field.to_string(),
            min,
            max: MAX_SEGMENTS,
            got: v,
        })
    }
}

/// A mesh gives exactly one of obj, gltf, sphere, plane, cube.
pub(super) fn check_one_shape(field: &str, md: &MeshDesc) -> Result<(), BuildError> {
    let shapes = [
        md.obj.is_some(),
        md.gltf.is_some(),
        md.sphere.is_some(),
        md.plane.is_some(),
        md.cube.is_some(),
    ];
    if shapes.iter().filter(|s| **s).count() != 1 {
        return Err(BuildError::Shapes {
            field: field.to_string(),
        });
    }
    Ok(())
}

/// `sphere`: segment and ring counts, radius, and the memory it takes.
pub(super) fn build_sphere(field: &str, s: &SphereDesc) -> Result<MeshData, BuildError> {
    check_segments(&format!("{field}.sphere.segments"), s.segments, 3)?;
    check_segments(&format!("{field}.sphere.rings"), s.rings, 2)?;
    check_extent(&format!("{field}.sphere.radius"), s.radius)?;
    let (u, v) = (s.segments as u64, s.rings as u64);
    memory::reserve(
        &format!("{field}.sphere ({u} segments × {v} rings)"),
        memory::mesh_bytes((u + 1) * (v + 1), 2 * u * v),
    )
    .map_err(BuildError::Memory)?;
    Ok(mesh::sphere(s.radius, s.segments, s.rings))
}

/// `plane`: segments and size per axis, and the memory it takes.
pub(super) fn build_plane(field: &str, p: &PlaneDesc) -> Result<MeshData, BuildError> {
    for (k, v) in p.segments.iter().enumerate() {
        check_segments(&format!("{field}.plane.segments[{k}]"), *v, 1)?;
        check_extent(&format!("{field}.plane.size[{k}]"), p.size[k])?;
    }
    let (u, v) = (p.segments[0] as u64, p.segments[1] as u64);
    memory::reserve(
        &format!("{field}.plane ({u} × {v} segments)"),
        memory::mesh_bytes((u + 1) * (v + 1), 2 * u * v),
    )
    .map_err(BuildError::Memory)?;
    Ok(mesh::plane(p.size, p.segments))
}

/// `cube`: segments and size, and the memory it takes.
pub(super) fn build_cube(field: &str, c: &CubeDesc) -> Result<MeshData, BuildError> {
    check_segments(&format!("{field}.cube.segments"), c.segments, 1)?;
    check_extent(&format!("{field}.cube.size"), c.size)?;
    let n = c.segments as u64;
    memory::reserve(
        &format!("{field}.cube ({n} segments)"),
        memory::mesh_bytes(6 * (n + 1) * (n + 1), 12 * n * n),
    )
    .map_err(BuildError::Memory)?;
    Ok(mesh::cube(c.size, c.segments))
}
