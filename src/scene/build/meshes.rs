//! `[[mesh]]`: each mesh's shape (an OBJ file or a procedural shape),
//! its materials, its uvs and tangents, and its placement, appended to
//! the scene's buffers in order.

use super::super::desc::MeshDesc;
use super::placement::{place_mesh, Placement};
use super::shapes::{build_cube, build_plane, build_sphere, check_one_shape};
use super::{BuildError, SceneBuilder};
use crate::memory;
use crate::mesh::MeshData;
use glam::Vec3;
use std::path::Path;

impl SceneBuilder<'_> {
    /// `[[mesh]]`s, appended in order; then the scene-wide uvs and
    /// tangents.
    pub(in crate::scene) fn add_meshes(&mut self, descs: &[MeshDesc]) -> Result<(), BuildError> {
        for (i, md) in descs.iter().enumerate() {
            self.add_mesh(&format!("mesh[{i}]"), md)?;
        }
        self.finish_meshes();
        Ok(())
    }

    /// After the last mesh: the scene-wide uvs and tangents.
    pub(in crate::scene) fn finish_meshes(&mut self) {
        let data = &mut self.data;
        if !self.any_uvs {
            data.uvs.clear();
        }
        data.tangents = specula_raster::scene::compute_tangents(
            &data.positions,
            &data.normals,
            &data.uvs,
            &data.triangles,
        );
        // Meshes that brought (or were given MikkTSpace) tangents keep
        // them: the tangents above depend only on each vertex's own
        // triangles, so the other meshes' are what they were alone.
        // (A scene where no mesh has uvs has no tangents at all.)
        for (start, tangents) in std::mem::take(&mut self.given_tangents) {
            if let Some(dst) = data.tangents.get_mut(start..start + tangents.len()) {
                dst.copy_from_slice(&tangents);
            }
        }
        if data.triangles.is_empty() {
            self.warnings.push("the scene has no triangles".into());
        }
    }

    /// One `[[mesh]]`: its shape, its materials, its placement.
    fn add_mesh(&mut self, field: &str, md: &MeshDesc) -> Result<(), BuildError> {
        if let Some(p) = &md.gltf {
            check_one_shape(field, md)?;
            return self
                .add_gltf_mesh(field, md, p)
                .map_err(|e| BuildError::Gltf(Box::new(e)));
        }
        let mut mesh = self.build_shape(field, md)?;
        let local = self.mesh_materials(field, md, &mesh)?;
        self.check_uvs(field, md, &mesh, &local)?;
        self.add_tangents_if_normal_mapped(field, &mut mesh, &local)?;
        let placement = place_mesh(field, md, &mesh.positions)?;
        self.append_mesh(&mesh, &placement, &local);
        Ok(())
    }

    /// MikkTSpace tangents for a mesh without its own where any of its
    /// triangles has a normal-mapped material (`local`: the mesh's
    /// material slots as scene materials).
    pub(in crate::scene) fn add_tangents_if_normal_mapped(
        &self,
        field: &str,
        mesh: &mut MeshData,
        local: &[u32],
    ) -> Result<(), BuildError> {
        let normal_mapped = mesh
            .tri_material
            .iter()
            .any(|m| self.materials.normal_mapped.contains(&local[*m as usize]));
        if normal_mapped && mesh.tangents.is_empty() {
            crate::tangents::add_mikktspace_tangents(mesh).map_err(|source| {
                BuildError::Tangents {
                    field: field.to_string(),
                    source,
                }
            })?;
        }
        Ok(())
    }

    /// The mesh's geometry: exactly one of obj, sphere, plane, cube.
    fn build_shape(&mut self, field: &str, md: &MeshDesc) -> Result<MeshData, BuildError> {
        check_one_shape(field, md)?;
        if let Some(p) = &md.obj {
            self.load_obj(field, p)
        } else if let Some(s) = &md.sphere {
            build_sphere(field, s)
        } else if let Some(p) = &md.plane {
            build_plane(field, p)
        } else {
            build_cube(field, md.cube.as_ref().expect("one shape is set"))
        }
    }

    /// An OBJ file (and its MTLs), recorded as inputs; vertices the
    /// rasterizer will skip are worth a warning.
    fn load_obj(&mut self, field: &str, p: &Path) -> Result<MeshData, BuildError> {
        let reserve = |len: u64| {
            memory::reserve(
                &format!("{field}.obj ({len} bytes)"),
                memory::obj_bytes(len),
            )
            .map_err(BuildError::Memory)
        };
        // A file on disk: found in the mesh cache without reading it whole.
        let keyed = self
            .dir
            .and_then(|dir| crate::mesh_cache::file_key(p, &dir.join(p)));
        let cached = match &keyed {
            Some((key, len)) => {
                reserve(*len)?;
                crate::mesh_cache::load_cached(key, p, self.read)
            }
            None => None,
        };
        let m = match cached {
            Some(m) => m,
            None => {
                let bytes = (self.read)(p).map_err(|source| BuildError::Read {
                    field: format!("{field}.obj"),
                    path: p.display().to_string(),
                    source,
                })?;
                if keyed.is_none() {
                    reserve(bytes.len() as u64)?;
                }
                crate::mesh_cache::load_obj(p, &bytes, self.read).map_err(|source| {
                    BuildError::Obj {
                        field: format!("{field}.obj"),
                        source,
                    }
                })?
            }
        };
        self.inputs.push(p.to_path_buf());
        self.inputs.extend(m.mtl_files.iter().cloned());
        self.warnings.extend(m.warnings.iter().cloned());
        let limit = specula_raster::setup::MAX_CLIP_COORD as f32;
        let bad = m
            .positions
            .iter()
            .filter(|v| v.is_nan() || v.abs().max_element() > limit)
            .count();
        if bad > 0 {
            self.warnings.push(format!(
                "{}: {bad} vertices are not finite or beyond ±{limit:e}; triangles using them are skipped",
                p.display()
            ));
        }
        Ok(m)
    }

    /// A mesh without uvs may not use a material that samples a texture.
    fn check_uvs(
        &self,
        field: &str,
        md: &MeshDesc,
        mesh: &MeshData,
        local: &[u32],
    ) -> Result<(), BuildError> {
        if !mesh.uvs.is_empty() {
            return Ok(());
        }
        let used: std::collections::BTreeSet<u32> = mesh
            .tri_material
            .iter()
            .map(|m| local[*m as usize])
            .collect();
        if let Some(m) = used.iter().find(|m| self.materials.textured.contains(m)) {
            return Err(BuildError::NoUvs {
                field: field.to_string(),
                obj: md.obj.clone(),
                material: self.materials.list[*m as usize].name.clone(),
            });
        }
        Ok(())
    }

    /// Appends a checked, placed mesh to the scene's buffers.
    pub(in crate::scene) fn append_mesh(
        &mut self,
        mesh: &MeshData,
        placement: &Placement,
        local: &[u32],
    ) {
        let Placement {
            model,
            normal_m,
            flip,
        } = placement;
        let data = &mut self.data;
        let base = data.positions.len() as u32;
        data.positions
            .extend(mesh.positions.iter().map(|p| model.transform_point3(*p)));
        data.normals.extend(
            mesh.normals
                .iter()
                .map(|n| (*normal_m * *n).try_normalize().unwrap_or(Vec3::Z)),
        );
        self.any_uvs |= !mesh.uvs.is_empty();
        if !mesh.tangents.is_empty() {
            // Tangents are directions on the surface: they go with the
            // model matrix; a mirroring one flips the bitangent's sign.
            let m3 = glam::Mat3::from_mat4(*model);
            let sign = if *flip { -1.0 } else { 1.0 };
            let placed = mesh
                .tangents
                .iter()
                .zip(&mesh.normals)
                .map(|(t, n)| {
                    let v = (m3 * t.truncate())
                        .try_normalize()
                        .unwrap_or_else(|| (*normal_m * *n).any_orthonormal_vector());
                    v.extend(t.w * sign)
                })
                .collect();
            self.given_tangents.push((base as usize, placed));
        }
        // Vertex colours: white for meshes without any, and the scene has
        // none until a mesh brings some.
        match (mesh.colors.is_empty(), data.colors.is_empty()) {
            (true, true) => {}
            (true, false) => data
                .colors
                .extend(std::iter::repeat_n(glam::Vec4::ONE, mesh.positions.len())),
            (false, empty) => {
                if empty {
                    data.colors.resize(base as usize, glam::Vec4::ONE);
                }
                data.colors.extend_from_slice(&mesh.colors);
            }
        }
        data.uvs.extend(mesh.uvs.iter().copied());
        if mesh.uvs.is_empty() {
            data.uvs
                .extend(std::iter::repeat_n(glam::Vec2::ZERO, mesh.positions.len()));
        }
        for (t, m) in mesh.triangles.iter().zip(&mesh.tri_material) {
            // A mirroring transform turns counter-clockwise into clockwise.
            let t = if *flip { [t[0], t[2], t[1]] } else { *t };
            data.triangles.push(t.map(|k| k + base));
            data.tri_material.push(local[*m as usize]);
        }
    }
}
