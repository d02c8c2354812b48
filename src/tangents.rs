//! Tangents for normal maps: MikkTSpace \[Mikkelsen08\] through the
//! `mikktspace` crate, the convention glTF's normal maps are baked in
//! (glTF 2.0, "meshes": "When tangents are not specified, client
//! implementations SHOULD calculate tangents using default MikkTSpace
//! algorithms").
//!
//! MikkTSpace works on the welded mesh: the indexed triangles as loaded
//! (OBJ corners with the same position, normal and uv share a vertex),
//! which it reads corner by corner. Its result is one tangent per corner;
//! where the corners of one vertex get different tangents (a mirrored uv
//! layout's seam, where the handedness changes), the vertex is split, so
//! each corner keeps its own tangent through the raster's per-vertex
//! attributes.

use crate::mesh::MeshData;
use glam::Vec4;
use std::collections::HashMap;

/// Why a mesh got no MikkTSpace tangents.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TangentError {
    /// The mesh has no uv per vertex.
    #[error("tangents need texture coordinates")]
    NoUvs,
    /// MikkTSpace gave up on the mesh.
    #[error("MikkTSpace could not make tangents for this mesh")]
    Failed,
}

/// The mesh as MikkTSpace reads it, and the tangents it writes per corner.
struct Corners<'a> {
    mesh: &'a MeshData,
    tangents: Vec<[f32; 4]>,
}

impl mikktspace::Geometry for Corners<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.triangles.len()
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.mesh.triangles[face][vert] as usize].to_array()
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.normals[self.mesh.triangles[face][vert] as usize].to_array()
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        self.mesh.uvs[self.mesh.triangles[face][vert] as usize].to_array()
    }
    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        self.tangents[face * 3 + vert] = tangent;
    }
}

/// MikkTSpace's tangent (xyz, w = ±1 the bitangent's sign) of every
/// triangle corner of `mesh` (which has uvs), `3 · t + k` for corner k of
/// triangle t.
pub(crate) fn corner_tangents(mesh: &MeshData) -> Result<Vec<[f32; 4]>, TangentError> {
    if mesh.uvs.len() != mesh.positions.len() {
        return Err(TangentError::NoUvs);
    }
    let mut c = Corners {
        mesh,
        tangents: vec![[0.0; 4]; mesh.triangles.len() * 3],
    };
    if !mikktspace::generate_tangents(&mut c) {
        return Err(TangentError::Failed);
    }
    Ok(c.tangents)
}

/// Gives `mesh` (with uvs, without tangents) MikkTSpace tangents, one per
/// vertex: a vertex whose corners got different tangents is split into
/// one copy per distinct tangent (same position, normal, uv and colour).
pub(crate) fn add_mikktspace_tangents(mesh: &mut MeshData) -> Result<(), TangentError> {
    let corners = corner_tangents(mesh)?;
    let n = mesh.positions.len();
    let mut tangents: Vec<Option<[f32; 4]>> = vec![None; n];
    // (vertex, tangent bits) → the vertex (original or copy) holding it.
    let mut copies: HashMap<(u32, [u32; 4]), u32> = HashMap::new();
    for (t, tri) in mesh.triangles.iter_mut().enumerate() {
        for (k, v) in tri.iter_mut().enumerate() {
            let tan = corners[3 * t + k];
            let key = (*v, tan.map(f32::to_bits));
            let i = *v as usize;
            match tangents[i] {
                None => {
                    tangents[i] = Some(tan);
                    copies.insert(key, *v);
                }
                Some(have) if have.map(f32::to_bits) == key.1 => {}
                Some(_) => {
                    *v = *copies.entry(key).or_insert_with(|| {
                        mesh.positions.push(mesh.positions[i]);
                        mesh.normals.push(mesh.normals[i]);
                        mesh.uvs.push(mesh.uvs[i]);
                        if !mesh.colors.is_empty() {
                            mesh.colors.push(mesh.colors[i]);
                        }
                        tangents.push(Some(tan));
                        (mesh.positions.len() - 1) as u32
                    });
                }
            }
        }
    }
    // Vertices no triangle uses keep some tangent orthogonal to their
    // normal (they are never drawn).
    mesh.tangents = tangents
        .into_iter()
        .zip(&mesh.normals)
        .map(|(t, n)| match t {
            Some(t) => Vec4::from_array(t),
            None => n.any_orthonormal_vector().extend(1.0),
        })
        .collect();
    Ok(())
}
