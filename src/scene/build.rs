//! Each table of a parsed scene checked and turned into the renderer's
//! values: the camera, output, environment, materials (MTL and the
//! scene's), meshes (OBJ and procedural, placed), lights and lines.

use super::desc::*;
use crate::checks;
use crate::material_desc::MaterialDesc;
use crate::memory;
use crate::mesh::{self, MeshData};
use crate::validate::{check_extent, check_point, MAX_FOV_Y_DEG, MAX_WORLD, MIN_FOV_Y_DEG};
use glam::{EulerRot, Mat3, Mat4, Quat, Vec3};
use specula_core::light::Light;
use specula_core::models::MetallicRoughness;
use specula_core::Model;
use specula_raster::shadow::{ShadowFilter, ShadowSettings};
use specula_raster::{Camera, SceneData};
use specula_raster::{Lit, Material};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};

/// The accepted |scale| per axis: their ratio (≤ 1e24) keeps the normal
/// matrix finite in f32.
pub(super) const MIN_SCALE: f32 = 1e-12;
pub(super) const MAX_SCALE: f32 = 1e12;

/// Checks that a mesh's transform keeps its (finite, in-range) vertices
/// inside ±MAX_WORLD.
pub(super) fn check_transform(field: &str, positions: &[Vec3], model: &Mat4) -> Result<(), String> {
    let inside = |p: Vec3| p.is_finite() && p.abs().max_element() <= MAX_WORLD;
    if let Some(p) = positions
        .iter()
        .find(|p| inside(**p) && !inside(model.transform_point3(**p)))
    {
        return Err(format!(
            "{field}.translate / scale: move vertex {p} to {}, outside ±{MAX_WORLD:e} (the world's extent)",
            model.transform_point3(*p)
        ));
    }
    Ok(())
}

/// The image size and supersampling: each side, supersampled, within the
/// render target's limit.
pub(super) fn check_output_size(o: &OutputDesc) -> Result<(), String> {
    let max = specula_raster::target::MAX_DIM;
    if !(1..=16).contains(&o.ssaa) {
        return Err(format!("output.ssaa: must be in 1..=16, got {}", o.ssaa));
    }
    for (field, v) in [("output.width", o.width), ("output.height", o.height)] {
        let limit = max / o.ssaa;
        if !(1..=limit).contains(&v) {
            return Err(format!(
                "{field}: must be in 1..={limit} (at most {max} after ssaa {}), got {v}",
                o.ssaa
            ));
        }
    }
    Ok(())
}

/// Largest segment count a procedural mesh accepts (per axis).
pub(super) const MAX_SEGMENTS: u32 = 4096;

pub(super) fn check_segments(field: &str, v: u32, min: u32) -> Result<(), String> {
    if (min..=MAX_SEGMENTS).contains(&v) {
        Ok(())
    } else {
        Err(format!(
            "{field}: must be in {min}..={MAX_SEGMENTS}, got {v}"
        ))
    }
}

/// The material used where neither the scene nor an MTL gives one.
pub(super) fn default_material() -> Material {
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
pub(super) fn mtl_material(
    m: &tobj::Material,
    obj_dir: &Path,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<Material, String> {
    let param = |key: &str| -> Result<Option<f32>, String> {
        match m.unknown_param.get(key) {
            None => Ok(None),
            Some(s) => s
                .trim()
                .parse::<f32>()
                .ok()
                .filter(|v| (0.0..=1.0).contains(v))
                .map(Some)
                .ok_or_else(|| {
                    format!(
                        "material {}: {key} must be a number in [0, 1], got {s:?}",
                        m.name
                    )
                }),
        }
    };
    let base_color = m.diffuse.unwrap_or([0.8, 0.8, 0.8]);
    if !base_color.iter().all(|c| c.is_finite() && *c >= 0.0) {
        return Err(format!(
            "material {}: Kd must be finite and ≥ 0, got {base_color:?}",
            m.name
        ));
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
            let map = crate::textures::load_color_map(&path, read)
                .map_err(|e| format!("material {}: map_Kd: {e}", m.name))?;
            let maps = specula_raster::maps::ParamMaps {
                base_color: Some(map),
                ..Default::default()
            };
            let shader = Lit::with_maps(model, maps)
                .map_err(|e| format!("material {}: map_Kd: {e}", m.name))?;
            Ok(Material::new(&m.name, shader, false))
        }
        None => Ok(Material::new(&m.name, Lit::new(model), false)),
    }
}

/// `[camera]`: finite, inside the world, a usable field of view and depth
/// range, and a frame that eye, target and up can span.
pub(super) fn build_camera(c: &CameraDesc) -> Result<Camera, String> {
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
        return Err(format!(
            "camera.fov_y: must be in [{MIN_FOV_Y_DEG}, {MAX_FOV_Y_DEG}] degrees, got {}",
            c.fov_y
        ));
    }
    // Depth is reversed (camera.rs), so any near/far ratio keeps its
    // precision; only the near plane must be a positive finite distance.
    // `far = inf` (TOML's infinity) is an infinite far plane.
    if !(c.near > 0.0 && c.near.is_finite() && c.far > c.near) {
        return Err(format!(
            "camera.near / camera.far: need 0 < near < far (far may be inf), got {} and {}",
            c.near, c.far
        ));
    }
    let forward = Vec3::from(c.target) - Vec3::from(c.eye);
    if forward.length_squared() == 0.0 || forward.cross(Vec3::from(c.up)).length_squared() == 0.0 {
        return Err("camera: eye, target and up must span a frame (target ≠ eye, up not parallel to the view)".into());
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

/// `[output]` and its `[[output.label]]`s.
pub(super) fn check_output(o: &OutputDesc) -> Result<(), String> {
    check_output_size(o)?;
    checks::radiometric("output.background", o.background)?;
    if !o.exposure.is_finite() {
        return Err("output.exposure: must be finite".into());
    }
    for (i, l) in o.labels.iter().enumerate() {
        l.validate().map_err(|e| format!("output.label[{i}].{e}"))?;
    }
    Ok(())
}

/// What `[environment]` gives: a uniform radiance or a map.
pub(super) enum Environment {
    Uniform([f32; 3]),
    Map(std::sync::Arc<specula_raster::envmap::EnvMap>),
}

/// `[environment]`: exactly one of `uniform` and `map`, the map's fields
/// checked and its file read through `read`.
pub(super) fn build_environment(
    e: &EnvironmentDesc,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<Environment, String> {
    match (&e.uniform, &e.map) {
        (Some(u), None) => {
            checks::radiometric("environment.uniform", *u)?;
            Ok(Environment::Uniform(*u))
        }
        (None, Some(path)) => {
            let settings = env_settings(e)?;
            let bytes = read(Path::new(path))
                .map_err(|err| format!("environment.map: cannot read {path}: {err}"))?;
            let map = crate::envmap_file::load_env_map(path, &bytes, &settings)
                .map_err(|err| format!("environment.map: {err}"))?;
            Ok(Environment::Map(std::sync::Arc::new(map)))
        }
        (Some(_), Some(_)) => Err("environment: give either uniform or map, not both".into()),
        (None, None) => Err("environment: give uniform = [r, g, b] or map = \"file.hdr\"".into()),
    }
}

/// The map settings of `[environment]`, checked.
pub(super) fn env_settings(e: &EnvironmentDesc) -> Result<crate::envmap_file::EnvSettings, String> {
    use specula_raster::envmap::IblMethod;
    if !(e.intensity.is_finite() && e.intensity >= 0.0) {
        return Err(format!(
            "environment.intensity must be finite and ≥ 0, got {}",
            e.intensity
        ));
    }
    if !e.rotate.is_finite() {
        return Err(format!(
            "environment.rotate must be finite, got {}",
            e.rotate
        ));
    }
    if !(1..=1 << 20).contains(&e.ibl_samples) {
        return Err(format!(
            "environment.ibl_samples must be in 1..=1048576, got {}",
            e.ibl_samples
        ));
    }
    Ok(crate::envmap_file::EnvSettings {
        intensity: e.intensity,
        rotate_deg: e.rotate,
        visible: e.visible,
        method: match e.ibl {
            IblDesc::SplitSum => IblMethod::SplitSum,
            IblDesc::Reference => IblMethod::Reference {
                samples: e.ibl_samples,
            },
        },
    })
}

/// `[[outline]]`s; the materials they name must exist.
pub(super) fn check_outlines(
    descs: &[crate::lines::OutlineDesc],
    by_name: &HashMap<String, u32>,
) -> Result<Vec<crate::lines::OutlineSpec>, String> {
    descs
        .iter()
        .enumerate()
        .map(|(i, o)| o.check(&format!("outline[{i}]"), &|n| by_name.contains_key(n)))
        .collect()
}

/// `[posterize]`: the image-space stage it asks for, if any.
pub(super) fn build_posterize(
    p: Option<&PosterizeDesc>,
) -> Result<Vec<std::sync::Arc<dyn specula_raster::post::PostStage>>, String> {
    let mut post_stages: Vec<std::sync::Arc<dyn specula_raster::post::PostStage>> = Vec::new();
    if let Some(p) = p {
        use specula_npr::posterize::{Posterize, PosterizeMode};
        let mode = match p.mode {
            PosterizeModeDesc::Rgb => PosterizeMode::Rgb,
            PosterizeModeDesc::Luminance => PosterizeMode::Luminance,
        };
        let stage = Posterize::new(p.levels, mode).map_err(|e| format!("posterize.{e}"))?;
        post_stages.push(std::sync::Arc::new(stage));
    }
    Ok(post_stages)
}

/// The scene's materials as they are gathered: `[materials]` first, then
/// MTL materials and the default as meshes ask for them, then visible
/// lights' own.
pub(super) struct Materials {
    pub(super) list: Vec<Material>,
    /// Ids of `[materials]` and MTL materials by name (not lights' own).
    pub(super) by_name: HashMap<String, u32>,
    /// Materials that read uvs (textures, tonal art maps).
    pub(super) textured: HashSet<u32>,
    /// Materials with a normal map: their meshes get MikkTSpace tangents.
    pub(super) normal_mapped: HashSet<u32>,
    /// The default material's id, once a mesh needed it.
    pub(super) default_id: Option<u32>,
}

/// Where a mesh goes in the world: its model matrix, the matrix for its
/// normals, and whether it mirrors (which flips the winding).
pub(super) struct Placement {
    pub(super) model: Mat4,
    pub(super) normal_m: Mat3,
    pub(super) flip: bool,
}

/// What the tables add up to while they are read in order.
pub(super) struct SceneBuilder<'a> {
    pub(super) path: &'a Path,
    pub(super) read: &'a dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    pub(super) data: SceneData,
    pub(super) materials: Materials,
    /// Whether some mesh brought texture coordinates.
    pub(super) any_uvs: bool,
    pub(super) inputs: Vec<PathBuf>,
    pub(super) warnings: Vec<String>,
    /// Tangents meshes brought or were given (tangents.rs), by their
    /// first vertex in `data`.
    pub(super) given_tangents: Vec<(usize, Vec<glam::Vec4>)>,
}

impl<'a> SceneBuilder<'a> {
    pub(super) fn new(
        path: &'a Path,
        read: &'a dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
        camera: Camera,
        background: [f32; 3],
    ) -> Self {
        SceneBuilder {
            path,
            read,
            data: SceneData {
                positions: Vec::new(),
                normals: Vec::new(),
                uvs: Vec::new(),
                tangents: Vec::new(),
                colors: Vec::new(),
                triangles: Vec::new(),
                tri_material: Vec::new(),
                materials: Vec::new(),
                geometry: Vec::new(),
                lights: Vec::new(),
                shadows: Vec::new(),
                environment: None,
                env_map: None,
                background,
                camera,
            },
            materials: Materials {
                list: Vec::new(),
                by_name: HashMap::new(),
                textured: HashSet::new(),
                normal_mapped: HashSet::new(),
                default_id: None,
            },
            any_uvs: false,
            inputs: vec![path.to_path_buf()],
            warnings: Vec::new(),
            given_tangents: Vec::new(),
        }
    }

    /// `[materials]`: built before the meshes, so they win over MTL
    /// materials of the same name.
    pub(super) fn add_materials(
        &mut self,
        descs: &BTreeMap<String, MaterialDesc>,
    ) -> Result<(), String> {
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
                .map_err(|e| format!("materials.{name}.{e}"))?;
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

    /// `[[mesh]]`s, appended in order; then the scene-wide uvs and
    /// tangents.
    pub(super) fn add_meshes(&mut self, descs: &[MeshDesc]) -> Result<(), String> {
        for (i, md) in descs.iter().enumerate() {
            self.add_mesh(&format!("mesh[{i}]"), md)?;
        }
        self.finish_meshes();
        Ok(())
    }

    /// After the last mesh: the scene-wide uvs and tangents.
    pub(super) fn finish_meshes(&mut self) {
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
    pub(super) fn add_mesh(&mut self, field: &str, md: &MeshDesc) -> Result<(), String> {
        if let Some(p) = &md.gltf {
            check_one_shape(field, md)?;
            return self.add_gltf_mesh(field, md, p);
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
    pub(super) fn add_tangents_if_normal_mapped(
        &self,
        field: &str,
        mesh: &mut MeshData,
        local: &[u32],
    ) -> Result<(), String> {
        let normal_mapped = mesh
            .tri_material
            .iter()
            .any(|m| self.materials.normal_mapped.contains(&local[*m as usize]));
        if normal_mapped && mesh.tangents.is_empty() {
            crate::tangents::add_mikktspace_tangents(mesh).map_err(|e| format!("{field}: {e}"))?;
        }
        Ok(())
    }

    /// The mesh's geometry: exactly one of obj, sphere, plane, cube.
    pub(super) fn build_shape(&mut self, field: &str, md: &MeshDesc) -> Result<MeshData, String> {
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
    pub(super) fn load_obj(&mut self, field: &str, p: &Path) -> Result<MeshData, String> {
        let bytes =
            (self.read)(p).map_err(|e| format!("{field}.obj: cannot read {}: {e}", p.display()))?;
        memory::reserve(
            &format!("{field}.obj ({} bytes)", bytes.len()),
            memory::obj_bytes(bytes.len() as u64),
        )?;
        self.inputs.push(p.to_path_buf());
        let m = mesh::load_obj(p, &bytes, self.read).map_err(|e| format!("{field}.obj: {e}"))?;
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

    /// The mesh's material ids → scene material ids: the mesh's `material`
    /// (or else the OBJ's) looked up in `[materials]`, then in the mesh's
    /// MTL (built on first use); unnamed ones get the default material.
    pub(super) fn mesh_materials(
        &mut self,
        field: &str,
        md: &MeshDesc,
        mesh: &MeshData,
    ) -> Result<Vec<u32>, String> {
        let mats = &mut self.materials;
        let mut local = Vec::with_capacity(mesh.material_names.len());
        for name in &mesh.material_names {
            let name = md.material.as_ref().or(name.as_ref());
            let id = match name {
                Some(n) => match mats.by_name.get(n) {
                    Some(&id) => id,
                    None => {
                        let Some(mt) = mesh.mtl.iter().find(|m| &m.name == n) else {
                            return Err(format!("{field}.material: no material named {n:?} in [materials] or the mesh's MTL"));
                        };
                        let obj_dir = md.obj.as_deref().and_then(Path::parent);
                        let built = mtl_material(mt, obj_dir.unwrap_or(Path::new("")), self.read)
                            .map_err(|e| format!("{field}.obj: {e}"))?;
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

    /// A mesh without uvs may not use a material that samples a texture.
    pub(super) fn check_uvs(
        &self,
        field: &str,
        md: &MeshDesc,
        mesh: &MeshData,
        local: &[u32],
    ) -> Result<(), String> {
        if !mesh.uvs.is_empty() {
            return Ok(());
        }
        let used: std::collections::BTreeSet<u32> = mesh
            .tri_material
            .iter()
            .map(|m| local[*m as usize])
            .collect();
        if let Some(m) = used.iter().find(|m| self.materials.textured.contains(m)) {
            let what = match &md.obj {
                Some(p) => format!(
                    "{field}.obj: {} has no texture coordinates (vt)",
                    p.display()
                ),
                None => format!("{field}: the mesh has no texture coordinates"),
            };
            return Err(format!(
                "{what}, and its material {:?} samples a texture (give the mesh uvs or use an untextured material)",
                self.materials.list[*m as usize].name
            ));
        }
        Ok(())
    }

    /// Appends a checked, placed mesh to the scene's buffers.
    pub(super) fn append_mesh(&mut self, mesh: &MeshData, placement: &Placement, local: &[u32]) {
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

    /// `[[light]]`s, in order. Visible polygon lights add their own
    /// geometry and material.
    pub(super) fn add_lights(
        &mut self,
        descs: &[LightDesc],
        area: AreaLightsDesc,
    ) -> Result<(), String> {
        for (i, l) in descs.iter().enumerate() {
            let light = self.build_light(i, l, area)?;
            let shadow = build_shadow(i, l)?;
            if let Some(s) = &shadow {
                crate::memory::reserve(&format!("light[{i}]'s shadow maps"), s.bytes(&light))?;
            }
            self.data.lights.push(light);
            self.data.shadows.push(shadow);
        }
        if self.data.shadows.iter().all(Option::is_none) {
            self.data.shadows.clear();
        }
        Ok(())
    }

    pub(super) fn build_light(
        &mut self,
        i: usize,
        l: &LightDesc,
        area: AreaLightsDesc,
    ) -> Result<Light, String> {
        let field = format!("light[{i}]");
        let light = match l {
            LightDesc::Point {
                position,
                intensity,
                range,
                ..
            } => {
                check_point(&format!("{field}.position"), *position)?;
                checks::radiometric(&format!("{field}.intensity"), *intensity)?;
                checks::light_range(&format!("{field}.range"), *range)?;
                Light::Point {
                    position: *position,
                    intensity: *intensity,
                    range: *range,
                }
            }
            LightDesc::Spot {
                position,
                direction,
                intensity,
                inner_cone,
                outer_cone,
                range,
                ..
            } => {
                check_point(&format!("{field}.position"), *position)?;
                let d = crate::validate::direction(&format!("{field}.direction"), *direction)?;
                checks::radiometric(&format!("{field}.intensity"), *intensity)?;
                let (inner, outer) = (inner_cone.to_radians(), outer_cone.to_radians());
                checks::cone_angles(
                    (&format!("{field}.inner_cone"), inner),
                    (&format!("{field}.outer_cone"), outer),
                    &|r| format!("{}°", r.to_degrees()),
                )?;
                checks::light_range(&format!("{field}.range"), *range)?;
                Light::Spot {
                    position: *position,
                    direction: d.to_array(),
                    intensity: *intensity,
                    cos_inner: inner.cos(),
                    cos_outer: outer.cos(),
                    range: *range,
                }
            }
            LightDesc::Directional {
                direction,
                irradiance,
                ..
            } => {
                checks::radiometric(&format!("{field}.irradiance"), *irradiance)?;
                let d = crate::validate::direction(&format!("{field}.direction"), *direction)?;
                Light::Directional {
                    to_light: (-d).to_array(),
                    irradiance: *irradiance,
                }
            }
            LightDesc::Polygon {
                vertices,
                radiance,
                two_sided,
                visible,
                ..
            } => {
                use crate::polygon_light::{add_visible, check_polygon};
                use specula_core::light::AreaMethod;
                for (k, v) in vertices.iter().enumerate() {
                    check_point(&format!("{field}.vertices[{k}]"), *v)?;
                }
                check_polygon(&format!("{field}.vertices"), vertices)?;
                checks::radiometric(&format!("{field}.radiance"), *radiance)?;
                if *visible {
                    let name = format!("light[{i}]");
                    add_visible(
                        &mut self.data,
                        &mut self.materials.list,
                        &name,
                        vertices,
                        *radiance,
                        *two_sided,
                    );
                }
                Light::Polygon {
                    vertices: vertices.clone(),
                    radiance: *radiance,
                    two_sided: *two_sided,
                    method: match area {
                        AreaLightsDesc::Ltc => AreaMethod::Ltc,
                        AreaLightsDesc::Reference => AreaMethod::Reference,
                    },
                }
            }
        };
        // The reference quadrature integrates any model's lobe; only the
        // LTC tables are fitted to some.
        if matches!(
            light,
            Light::Polygon {
                method: specula_core::light::AreaMethod::Ltc,
                ..
            }
        ) {
            crate::polygon_light::check_materials(&self.materials.list)
                .map_err(|e| format!("{field}: {e}"))?;
        }
        Ok(light)
    }

    /// Tables built once per process on first use: made here, so that
    /// their cost (the split-sum tables above all) counts as
    /// loading and not as the first frame's shading pass.
    pub(super) fn warm_tables(&self) {
        let polygon_lights = self
            .data
            .lights
            .iter()
            .any(|l| matches!(l, Light::Polygon { .. }));
        if polygon_lights {
            specula_core::ltc::ggx::table();
        }
        if (polygon_lights || self.data.environment.is_some() || self.data.env_map.is_some())
            && self.materials.list.iter().any(is_split_sum_model)
        {
            specula_core::albedo_tables::AlbedoTables::get();
        }
        if self.materials.list.iter().any(has_sheen) {
            specula_core::sheen::SheenTable::get();
        }
    }
}

/// A mesh gives exactly one of obj, gltf, sphere, plane, cube.
pub(super) fn check_one_shape(field: &str, md: &MeshDesc) -> Result<(), String> {
    let shapes = [
        md.obj.is_some(),
        md.gltf.is_some(),
        md.sphere.is_some(),
        md.plane.is_some(),
        md.cube.is_some(),
    ];
    if shapes.iter().filter(|s| **s).count() != 1 {
        return Err(format!(
            "{field}: give exactly one of obj, gltf, sphere, plane, cube"
        ));
    }
    Ok(())
}

/// `sphere`: segment and ring counts, radius, and the memory it takes.
pub(super) fn build_sphere(field: &str, s: &SphereDesc) -> Result<MeshData, String> {
    check_segments(&format!("{field}.sphere.segments"), s.segments, 3)?;
    check_segments(&format!("{field}.sphere.rings"), s.rings, 2)?;
    check_extent(&format!("{field}.sphere.radius"), s.radius)?;
    let (u, v) = (s.segments as u64, s.rings as u64);
    memory::reserve(
        &format!("{field}.sphere ({u} segments × {v} rings)"),
        memory::mesh_bytes((u + 1) * (v + 1), 2 * u * v),
    )?;
    Ok(mesh::sphere(s.radius, s.segments, s.rings))
}

/// `plane`: segments and size per axis, and the memory it takes.
pub(super) fn build_plane(field: &str, p: &PlaneDesc) -> Result<MeshData, String> {
    for (k, v) in p.segments.iter().enumerate() {
        check_segments(&format!("{field}.plane.segments[{k}]"), *v, 1)?;
        check_extent(&format!("{field}.plane.size[{k}]"), p.size[k])?;
    }
    let (u, v) = (p.segments[0] as u64, p.segments[1] as u64);
    memory::reserve(
        &format!("{field}.plane ({u} × {v} segments)"),
        memory::mesh_bytes((u + 1) * (v + 1), 2 * u * v),
    )?;
    Ok(mesh::plane(p.size, p.segments))
}

/// `cube`: segments and size, and the memory it takes.
pub(super) fn build_cube(field: &str, c: &CubeDesc) -> Result<MeshData, String> {
    check_segments(&format!("{field}.cube.segments"), c.segments, 1)?;
    check_extent(&format!("{field}.cube.size"), c.size)?;
    let n = c.segments as u64;
    memory::reserve(
        &format!("{field}.cube ({n} segments)"),
        memory::mesh_bytes(6 * (n + 1) * (n + 1), 12 * n * n),
    )?;
    Ok(mesh::cube(c.size, c.segments))
}

/// The mesh's `translate`, `rotate` and `scale`, checked, and checked to
/// keep its vertices inside the world.
pub(super) fn place_mesh(
    field: &str,
    md: &MeshDesc,
    positions: &[Vec3],
) -> Result<Placement, String> {
    let scale = match md.scale {
        Scale::Uniform(s) => Vec3::splat(s),
        Scale::Axes(a) => Vec3::from(a),
    };
    checks::finite(&format!("{field}.translate"), &md.translate)?;
    checks::finite(&format!("{field}.rotate"), &md.rotate)?;
    if !(scale.abs().cmpge(Vec3::splat(MIN_SCALE)) & scale.abs().cmple(Vec3::splat(MAX_SCALE)))
        .all()
    {
        return Err(format!(
            "{field}.scale: every component must be a number with {MIN_SCALE:e} ≤ |s| ≤ {MAX_SCALE:e}, got {scale}"
        ));
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

/// Whether a material is `metallic_roughness` or `gltf`, whose
/// polygon-light and environment terms read the process-wide split-sum
/// tables.
pub(super) fn is_split_sum_model(m: &Material) -> bool {
    m.shader
        .as_any()
        .downcast_ref::<Lit>()
        .is_some_and(|l| matches!(l.model(), Model::MetallicRoughness(_) | Model::Gltf(_)))
}

/// Whether a material is `gltf` with sheen, whose every light reads the
/// sheen albedo table.
fn has_sheen(m: &Material) -> bool {
    m.shader
        .as_any()
        .downcast_ref::<Lit>()
        .is_some_and(|l| matches!(l.model(), Model::Gltf(g) if g.has_sheen()))
}

/// Light `i`'s shadow settings, checked (`None`: no shadows).
fn build_shadow(i: usize, l: &LightDesc) -> Result<Option<ShadowSettings>, String> {
    let cascades = match l {
        LightDesc::Directional { cascades, .. } => *cascades,
        _ => 1,
    };
    let (shadows, map_size, bias, normal_bias, filter_radius, light_size) = match l {
        LightDesc::Point {
            shadows,
            shadow_map_size,
            bias,
            normal_bias,
            filter_radius,
            light_size,
            ..
        }
        | LightDesc::Spot {
            shadows,
            shadow_map_size,
            bias,
            normal_bias,
            filter_radius,
            light_size,
            ..
        }
        | LightDesc::Directional {
            shadows,
            shadow_map_size,
            bias,
            normal_bias,
            filter_radius,
            light_size,
            ..
        } => (
            *shadows,
            *shadow_map_size,
            *bias,
            *normal_bias,
            *filter_radius,
            *light_size,
        ),
        LightDesc::Polygon {
            shadows,
            shadow_map_size,
            bias,
            normal_bias,
            filter_radius,
            ..
        } => (
            *shadows,
            *shadow_map_size,
            *bias,
            *normal_bias,
            *filter_radius,
            // Not a field of polygon lights: derived below, after the
            // check (a polygon up to the world bound has a size past
            // the field's range).
            0.0,
        ),
    };
    let filter = match shadows {
        ShadowsDesc::None | ShadowsDesc::Hard => ShadowFilter::Hard,
        ShadowsDesc::Pcf => ShadowFilter::Pcf,
        ShadowsDesc::Pcss => ShadowFilter::Pcss,
    };
    let mut s = ShadowSettings {
        filter,
        map_size,
        bias,
        normal_bias,
        filter_radius,
        light_size,
        cascades,
    };
    // Checked with shadows off too: a value out of range is a mistake
    // whether or not it is used.
    s.check().map_err(|e| format!("light[{i}].{e}"))?;
    if let LightDesc::Polygon { vertices, .. } = l {
        s.light_size = specula_raster::shadow::polygon_light_size(vertices);
    }
    Ok((shadows != ShadowsDesc::None).then_some(s))
}
