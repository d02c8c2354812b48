//! `[materials]`, the MTL materials meshes name, and the default
//! material: gathered as the tables are read, with the ids meshes use.

use super::super::desc::MeshDesc;
use super::{BuildError, SceneBuilder};
use crate::material_desc::MaterialDesc;
use crate::mesh::MeshData;
use specula_core::models::MetallicRoughness;
use specula_core::Model;
use specula_raster::{Lit, Material};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::Path;

/// The scene's materials as they are gathered: `[materials]` first, then
/// MTL materials and the default as meshes ask for them, then visible
/// lights' own.
pub(in crate::scene) struct Materials {
    pub(in crate::scene) list: Vec<Material>,
    /// Ids of `[materials]` and MTL materials by name (not lights' own).
    pub(in crate::scene) by_name: HashMap<String, u32>,
    /// Materials that read uvs (textures, tonal art maps).
    pub(in crate::scene) textured: HashSet<u32>,
    /// Materials with a normal map: their meshes get MikkTSpace tangents.
    pub(in crate::scene) normal_mapped: HashSet<u32>,
    /// The default material's id, once a mesh needed it.
    pub(in crate::scene) default_id: Option<u32>,
}

/// The material used where neither the scene nor an MTL gives one.
fn default_material() -> Material {
    let model = Model::MetallicRoughness(MetallicRoughness {
        base_color: [0.8, 0.8, 0.8],
        roughness: 0.5,
        metallic: 0.0,
    });
    Material::new("default", Lit::new(model), false)
}

/// The metallic-roughness reading of an MTL material: `Kd` base colour, `Pr`
/// roughness and `Pm` metallic (the PBR extension); without `Pr`, roughness
/// from Phong `Ns` through α² = 2 / (Ns + 2) [Walter07, §5.2]; defaults 0.5
/// and 0.
/// `map_Kd` (relative to the OBJ's folder) becomes the base-colour texture.
fn mtl_material(
    m: &tobj::Material,
    obj_dir: &Path,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<Material, BuildError> {
    let param = |key: &str| -> Result<Option<f32>, BuildError> {
        match m.unknown_param.get(key) {
            None => Ok(None),
            Some(s) => s
                .trim()
                .parse::<f32>()
                .ok()
                .filter(|v| (0.0..=1.0).contains(v))
                .map(Some)
                .ok_or_else(|| BuildError::MtlParam {
                    material: m.name.clone(),
                    key: key.to_string(),
                    got: s.clone(),
                }),
        }
    };
    let base_color = m.diffuse.unwrap_or([0.8, 0.8, 0.8]);
    if !base_color.iter().all(|c| c.is_finite() && *c >= 0.0) {
        return Err(BuildError::MtlKd {
            material: m.name.clone(),
            got: base_color,
        });
    }
    let roughness = match (param("Pr")?, m.shininess) {
        (Some(r), _) => r,
        (None, Some(ns)) if ns.is_finite() && ns >= 0.0 => (2.0 / (ns + 2.0)).sqrt().sqrt(),
        _ => 0.5,
    };
    let model = Model::MetallicRoughness(MetallicRoughness {
        base_color,
        roughness,
        metallic: param("Pm")?.unwrap_or(0.0),
    });
    match &m.diffuse_texture {
        Some(tex) => {
            let path = obj_dir.join(tex.trim());
            let map_kd = |source| BuildError::MtlMap {
                material: m.name.clone(),
                source,
            };
            let map = crate::textures::load_color_map(&path, read).map_err(|source| {
                BuildError::MtlTexture {
                    material: m.name.clone(),
                    source,
                }
            })?;
            let maps = specula_raster::maps::ParamMaps {
                base_color: Some(map),
                ..Default::default()
            };
            let shader = Lit::with_maps(model, maps).map_err(map_kd)?;
            Ok(Material::new(&m.name, shader, false))
        }
        None => Ok(Material::new(&m.name, Lit::new(model), false)),
    }
}

impl SceneBuilder<'_> {
    /// `[materials]`: built before the meshes, so they win over MTL
    /// materials of the same name.
    pub(in crate::scene) fn add_materials(
        &mut self,
        descs: &BTreeMap<String, MaterialDesc>,
    ) -> Result<(), BuildError> {
        let mats = &mut self.materials;
        for (name, m) in descs {
            let mut notes = Vec::new();
            let built = m
                .build_with(
                    name,
                    crate::material_desc::Tables::Build,
                    &mut notes,
                    self.read,
                )
                .map_err(|source| BuildError::Material {
                    name: name.clone(),
                    source: Box::new(source),
                })?;
            if m.needs_uvs() {
                mats.textured.insert(mats.list.len() as u32);
            }
            if m.has_normal_map() {
                mats.normal_mapped.insert(mats.list.len() as u32);
            }
            self.inputs
                .extend(m.texture_files().into_iter().map(Path::to_path_buf));
            self.warnings.extend(
                notes
                    .into_iter()
                    .map(|n| format!("{}: materials.{name}.{n}", self.path.display())),
            );
            mats.by_name.insert(name.clone(), mats.list.len() as u32);
            mats.list.push(built);
        }
        Ok(())
    }

    /// The mesh's material ids → scene material ids: the mesh's `material`
    /// (or else the OBJ's) looked up in `[materials]`, then in the mesh's
    /// MTL (built on first use); unnamed ones get the default material.
    pub(super) fn mesh_materials(
        &mut self,
        field: &str,
        md: &MeshDesc,
        mesh: &MeshData,
    ) -> Result<Vec<u32>, BuildError> {
        let mats = &mut self.materials;
        let mut local = Vec::with_capacity(mesh.material_names.len());
        for name in &mesh.material_names {
            let name = md.material.as_ref().or(name.as_ref());
            let id = match name {
                Some(n) => match mats.by_name.get(n) {
                    Some(&id) => id,
                    None => {
                        let Some(mt) = mesh.mtl.iter().find(|m| &m.name == n) else {
                            return Err(BuildError::NoMaterial {
                                field: field.to_string(),
                                name: n.clone(),
                            });
                        };
                        let obj_dir = md.obj.as_deref().and_then(Path::parent);
                        let built = mtl_material(mt, obj_dir.unwrap_or(Path::new("")), self.read)
                            .map_err(|e| BuildError::Mtl {
                            field: format!("{field}.obj"),
                            source: Box::new(e),
                        })?;
                        if mt.diffuse_texture.is_some() {
                            mats.textured.insert(mats.list.len() as u32);
                        }
                        let id = mats.list.len() as u32;
                        mats.list.push(built);
                        mats.by_name.insert(n.clone(), id);
                        id
                    }
                },
                None => *mats.default_id.get_or_insert_with(|| {
                    mats.list.push(default_material());
                    mats.list.len() as u32 - 1
                }),
            };
            local.push(id);
        }
        Ok(local)
    }
}
