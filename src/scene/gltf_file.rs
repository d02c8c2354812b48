//! glTF files in scenes: `[[mesh]] gltf = "…"` (the file's default scene
//! placed by the entry's transform, with its materials, under the TOML's
//! camera and lights), and a glTF file rendered on its own
//! (`specula render model.glb`: its camera and lights, or defaults that
//! are printed).

use super::build::*;
use super::desc::*;
use super::{GltfSceneError, LoadedScene, SceneError};
use crate::gltf::material::GltfMaterial;
use crate::gltf::scene_material::scene_material;
use crate::gltf::{GltfScene, Projection};
use crate::memory;
use crate::mesh::MeshData;
use glam::{Vec2, Vec3, Vec4};
use specula_core::light::Light;
use specula_raster::{Camera, GeometryPass, SceneData};
use std::path::{Path, PathBuf};

/// The default camera's vertical field of view (degrees) when the file
/// has none.
const DEFAULT_FOV_Y: f32 = 40.0;
/// The default lights when the file has none: a directional key light
/// from above, in front and to the right, and a dim uniform environment.
pub(crate) const DEFAULT_KEY_TO_LIGHT: [f32; 3] = [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
pub(crate) const DEFAULT_KEY_IRRADIANCE: f32 = 3.0;
pub(crate) const DEFAULT_ENVIRONMENT: f32 = 0.3;
/// How far an orthographic camera is stood back, in units of its ymag: its
/// rays then diverge by at most 1/1000 rad.
const ORTHO_DISTANCE: f32 = 1000.0;

/// Options of a glTF file rendered on its own.
#[derive(Clone, Debug, Default)]
pub struct GltfOptions {
    /// Which camera (`--camera N`; 0 when the file has any).
    pub camera: Option<usize>,
    /// An environment map lighting the file (`--env PATH`, split sum,
    /// visible): it replaces the default uniform environment.
    pub env: Option<PathBuf>,
}

impl SceneBuilder<'_> {
    /// Reads a glTF file (its buffers and images through `read`, relative
    /// to its folder), counted against the memory budget.
    fn read_gltf(&mut self, what: &str, p: &Path) -> Result<GltfScene, GltfSceneError> {
        let bytes = (self.read)(p).map_err(|source| GltfSceneError::Read {
            what: what.to_string(),
            path: p.to_path_buf(),
            source,
        })?;
        memory::reserve(
            &format!("{what} ({} bytes)", bytes.len()),
            bytes.len() as u64,
        )?;
        self.inputs.push(p.to_path_buf());
        let g = crate::gltf::load(p, &bytes, self.read).map_err(|source| GltfSceneError::Gltf {
            what: what.to_string(),
            path: p.to_path_buf(),
            source,
        })?;
        self.inputs.extend(g.inputs.iter().cloned());
        self.warnings
            .extend(g.warnings.iter().map(|w| format!("{}: {w}", p.display())));
        Ok(g)
    }

    /// `[[mesh]] gltf`: every primitive of the file's default scene, its
    /// node transforms then the entry's translate / rotate / scale, with
    /// its own materials (or the entry's `material` for all of them).
    pub(super) fn add_gltf_mesh(
        &mut self,
        field: &str,
        md: &MeshDesc,
        p: &Path,
    ) -> Result<(), GltfSceneError> {
        let what = format!("{field}.gltf");
        let g = self.read_gltf(&what, p)?;
        let (mut mesh, local) = self.gltf_mesh(&what, p, &g, md.material.as_deref())?;
        self.add_tangents_if_normal_mapped(&what, &mut mesh, &local)
            .map_err(scene_check)?;
        let placement = place_mesh(field, md, &mesh.positions).map_err(scene_check)?;
        self.append_mesh(&mesh, &placement, &local);
        Ok(())
    }

    /// The file's primitives as one mesh, and the scene material of each of
    /// its materials (`override_name`: a `[materials]` entry for all).
    fn gltf_mesh(
        &mut self,
        what: &str,
        p: &Path,
        g: &GltfScene,
        override_name: Option<&str>,
    ) -> Result<(MeshData, Vec<u32>), GltfSceneError> {
        let file = p.display().to_string();
        let nmat = g.materials.len();
        // local[k]: material k of the file; local[nmat]: its default material.
        let mut local = vec![u32::MAX; nmat + 1];
        let mut textured = vec![None; nmat + 1];
        if let Some(name) = override_name {
            let id =
                *self
                    .materials
                    .by_name
                    .get(name)
                    .ok_or_else(|| GltfSceneError::NoMaterial {
                        what: what.to_string(),
                        name: name.to_string(),
                    })?;
            local.fill(id);
            if self.materials.textured.contains(&id) {
                textured.fill(Some(0));
            }
        }
        let mut images = g.images(self.read);
        let mut mesh = MeshData {
            material_names: vec![None; nmat + 1],
            ..Default::default()
        };
        let mut any_uv = false;
        // Materials some primitive with COLOR_0 uses: their base colour
        // is multiplied by it (the others see white).
        let mut colored = vec![false; nmat + 1];
        for prim in g.primitives.iter().filter(|p| p.color0.is_some()) {
            colored[prim.material.unwrap_or(nmat)] = true;
        }
        let any_color = colored.contains(&true);
        let any_tangents = g.primitives.iter().any(|p| p.tangents.is_some());
        if any_color {
            let n: usize = g.primitives.iter().map(|p| p.positions.len()).sum();
            memory::reserve(
                &format!("{what}: vertex colours ({n} vertices)"),
                memory::COLOR_VERTEX_BYTES.saturating_mul(n as u64),
            )?;
        }
        let mut clamped = 0usize;
        for prim in &g.primitives {
            let k = prim.material.unwrap_or(nmat);
            if local[k] == u32::MAX {
                let desc = match prim.material {
                    Some(i) => g.materials[i].clone(),
                    None => GltfMaterial::default_material(),
                };
                let (mut built, warning) =
                    scene_material(&desc, colored[k], &mut images).map_err(|source| {
                        GltfSceneError::Gltf {
                            what: what.to_string(),
                            path: p.to_path_buf(),
                            source,
                        }
                    })?;
                built.name = format!("{file}#{}", desc.name);
                self.warnings
                    .extend(warning.map(|w| format!("{file}: {w}")));
                let id = self.materials.list.len() as u32;
                if let Some(set) = desc.uv_set() {
                    self.materials.textured.insert(id);
                    textured[k] = Some(set);
                }
                if desc.normal_texture.is_some() || desc.clearcoat_textures.normal_texture.is_some()
                {
                    self.materials.normal_mapped.insert(id);
                }
                self.materials.list.push(built);
                local[k] = id;
            }
            // The uv set the material's texture reads (TEXCOORD_0 otherwise),
            // flipped to our convention (v = 0 at the bottom of the image).
            let set = textured[k].unwrap_or(0);
            let uvs = match set {
                0 => prim.uv0.as_ref(),
                1 => prim.uv1.as_ref(),
                _ => None,
            };
            if uvs.is_none() && textured[k].is_some() {
                return Err(GltfSceneError::NoUvSet {
                    what: what.to_string(),
                    path: p.to_path_buf(),
                    at: prim.at.clone(),
                    set,
                });
            }
            let mut piece = MeshData {
                positions: prim.positions.clone(),
                normals: prim.normals.clone(),
                triangles: prim.triangles.clone(),
                ..Default::default()
            };
            piece.uvs = match uvs {
                Some(uv) => {
                    any_uv = true;
                    uv.iter().map(|t| Vec2::new(t.x, 1.0 - t.y)).collect()
                }
                None => vec![Vec2::ZERO; prim.positions.len()],
            };
            piece.colors = match (&prim.color0, any_color) {
                (Some(c), _) => c
                    .iter()
                    .map(|c| {
                        let k = c.clamp(Vec4::ZERO, Vec4::ONE);
                        clamped += usize::from(k != *c);
                        k
                    })
                    .collect(),
                (None, true) => vec![Vec4::ONE; prim.positions.len()],
                (None, false) => Vec::new(),
            };
            if any_tangents {
                // Some primitive brings TANGENT: every one gets tangents
                // here, its own, else MikkTSpace's (normal-mapped), else
                // the per-vertex uv tangents every mesh gets.
                let normal_mapped = self.materials.normal_mapped.contains(&local[k]);
                match &prim.tangents {
                    Some(t) => piece.tangents = t.clone(),
                    None if normal_mapped => crate::tangents::add_mikktspace_tangents(&mut piece)
                        .map_err(|source| GltfSceneError::Tangents {
                        what: what.to_string(),
                        path: p.to_path_buf(),
                        at: prim.at.clone(),
                        source,
                    })?,
                    None => {
                        piece.tangents = specula_raster::scene::compute_tangents(
                            &piece.positions,
                            &piece.normals,
                            &piece.uvs,
                            &piece.triangles,
                        )
                    }
                }
            }
            let base = mesh.positions.len() as u32;
            mesh.positions.extend_from_slice(&piece.positions);
            mesh.normals.extend_from_slice(&piece.normals);
            mesh.uvs.extend_from_slice(&piece.uvs);
            mesh.colors.extend_from_slice(&piece.colors);
            mesh.tangents.extend_from_slice(&piece.tangents);
            mesh.triangles
                .extend(piece.triangles.iter().map(|t| t.map(|i| i + base)));
            mesh.tri_material
                .extend(std::iter::repeat_n(k as u32, piece.triangles.len()));
        }
        if clamped > 0 {
            self.warnings.push(format!(
                "{file}: COLOR_0 of {clamped} vertices had components outside [0, 1], clamped to it"
            ));
        }
        self.inputs.append(&mut images.inputs);
        if !any_uv {
            mesh.uvs.clear();
        }
        self.any_uvs |= any_uv;
        // Unused slots (materials no primitive uses) point at material 0;
        // no triangle refers to them.
        for l in &mut local {
            if *l == u32::MAX {
                *l = 0;
            }
        }
        Ok((mesh, local))
    }
}

/// A checked scene camera from a glTF camera.
fn scene_camera(c: &crate::gltf::GltfCamera) -> Result<(Camera, Option<String>), GltfSceneError> {
    let (desc, note) = match c.projection {
        Projection::Perspective {
            yfov, znear, zfar, ..
        } => (
            CameraDesc {
                eye: c.eye.to_array(),
                target: (c.eye + c.forward).to_array(),
                up: c.up.to_array(),
                fov_y: yfov.to_degrees(),
                near: znear,
                far: zfar.unwrap_or(f32::INFINITY),
            },
            None,
        ),
        Projection::Orthographic {
            ymag, znear, zfar, ..
        } => {
            if !(ymag.is_finite() && ymag > 0.0) {
                return Err(GltfSceneError::OrthographicYmag {
                    at: c.at.clone(),
                    ymag,
                });
            }
            let d = ORTHO_DISTANCE * ymag;
            let eye = c.eye - c.forward * d;
            (
                CameraDesc {
                    eye: eye.to_array(),
                    target: c.eye.to_array(),
                    up: c.up.to_array(),
                    fov_y: 2.0 * (1.0 / ORTHO_DISTANCE).atan().to_degrees(),
                    near: d + znear,
                    far: d + zfar,
                },
                Some(format!(
                    "{}: orthographic, drawn as a perspective camera {d} away with the same view height (rays within 1/{ORTHO_DISTANCE} rad of parallel)",
                    c.at
                )),
            )
        }
    };
    let cam = build_camera(&desc).map_err(|e| GltfSceneError::Camera {
        at: c.at.clone(),
        message: e.to_string(),
    })?;
    Ok((cam, note))
}

/// The camera framing a bounding sphere from +Z with +Y up; an error when
/// the sphere is too large for its eye to stay inside the world.
fn framing_camera(positions: &[Vec3]) -> Result<(Camera, String), GltfSceneError> {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in positions {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let centre = if positions.is_empty() {
        Vec3::ZERO
    } else {
        (lo + hi) / 2.0
    };
    let radius = positions
        .iter()
        .map(|p| p.distance(centre))
        .fold(0.0f32, f32::max)
        .max(1e-3);
    let d = radius / (DEFAULT_FOV_Y.to_radians() / 2.0).sin();
    let eye = centre + Vec3::Z * d;
    crate::validate::check_point("the default camera's eye", eye.to_array())
        .map_err(|source| GltfSceneError::TooLargeToFrame { radius, source })?;
    let cam = Camera {
        eye,
        target: centre,
        up: Vec3::Y,
        fov_y_deg: DEFAULT_FOV_Y,
        near: ((d - radius) * 0.5).max(d * 1e-4),
        far: f32::INFINITY,
    };
    let note = format!(
        "no camera in the file: framing its bounding sphere (centre {centre}, radius {radius}) from +Z, +Y up: eye {eye}, fov_y {DEFAULT_FOV_Y}°"
    );
    Ok((cam, note))
}

/// A glTF file rendered on its own (`specula render model.glb`): its
/// default scene, its camera `opts.camera` (else the first; else one
/// framing the scene), its lights (else a key light and an environment).
pub fn load_gltf_scene(path: &Path, opts: &GltfOptions) -> Result<LoadedScene, SceneError> {
    let err = |message: String| SceneError {
        file: path.to_path_buf(),
        message,
    };
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let read = move |p: &Path| std::fs::read(dir.join(p));
    let name = PathBuf::from(path.file_name().unwrap_or_default());
    let mut scene = load_gltf_str(&name, &read, opts).map_err(|e| err(e.to_string()))?;
    let base = path.parent().unwrap_or(Path::new(""));
    for p in scene.inputs.iter_mut() {
        *p = base.join(&p);
    }
    if let Some(env) = &opts.env {
        let bytes = std::fs::read(env)
            .map_err(|e| err(format!("--env: cannot read {}: {e}", env.display())))?;
        let settings = crate::envmap_file::EnvSettings {
            intensity: 1.0,
            rotate_deg: 0.0,
            visible: true,
            method: specula_raster::envmap::IblMethod::SplitSum,
        };
        let map = crate::envmap_file::load_env_map(&env.display().to_string(), &bytes, &settings)
            .map_err(|e| err(format!("--env: {e}")))?;
        let mut parts = scene.data.into_parts();
        // A sun taken out of the map casts PCF shadows, as the file's
        // punctual lights do.
        if let Some(sun) = map.sun_world() {
            let pcf = specula_raster::shadow::ShadowSettings {
                filter: specula_raster::shadow::ShadowFilter::Pcf,
                light_size: super::build::sun_light_size(sun.sin2_radius),
                ..Default::default()
            };
            crate::memory::reserve("the sun's shadow maps", pcf.bytes(&sun.directional()))
                .map_err(|e| err(e.to_string()))?;
            parts.sun_shadows = Some(pcf);
        }
        parts.environment = None;
        parts.env_map = Some(std::sync::Arc::new(map));
        scene.data = SceneData::new(parts).map_err(|e| err(e.to_string()))?;
        scene.inputs.push(env.clone());
        specula_core::albedo_tables::AlbedoTables::get();
    }
    Ok(scene)
}

/// [`load_gltf_scene`] with the files supplied by `read` (the glTF is
/// `name`, relative to what `read` resolves against); messages do not
/// repeat the file's name.
pub fn load_gltf_str(
    name: &Path,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    opts: &GltfOptions,
) -> Result<LoadedScene, GltfSceneError> {
    let output = OutputDesc::default();
    let placeholder = framing_camera(&[])?.0;
    let mut scene = SceneBuilder::new(name, read, placeholder, output.background);
    // The glTF is the scene's first input (read_gltf records it).
    scene.inputs.clear();
    let bytes = read(name).map_err(GltfSceneError::ReadScene)?;
    memory::reserve(
        &format!("the file ({} bytes)", bytes.len()),
        bytes.len() as u64,
    )?;
    scene.inputs.push(name.to_path_buf());
    let g = crate::gltf::load(name, &bytes, read)?;
    scene.inputs.extend(g.inputs.iter().cloned());
    scene.warnings.extend(g.warnings.iter().cloned());
    let (mut mesh, local) = scene.gltf_mesh("mesh", name, &g, None)?;
    scene
        .add_tangents_if_normal_mapped("mesh", &mut mesh, &local)
        .map_err(scene_check)?;
    let md = MeshDesc {
        obj: None,
        gltf: Some(name.to_path_buf()),
        sphere: None,
        plane: None,
        cube: None,
        material: None,
        translate: [0.0; 3],
        rotate: [0.0; 3],
        scale: Scale::Uniform(1.0),
    };
    let placement = place_mesh("mesh", &md, &mesh.positions).map_err(scene_check)?;
    scene.append_mesh(&mesh, &placement, &local);
    scene.finish_meshes();
    let camera = match (opts.camera, g.cameras.is_empty()) {
        (Some(n), _) if n >= g.cameras.len() => {
            return Err(GltfSceneError::NoSuchCamera {
                index: n,
                count: g.cameras.len(),
            })
        }
        (None, true) => {
            let (c, note) = framing_camera(&scene.data.positions)?;
            scene.warnings.push(note);
            c
        }
        (n, _) => {
            let (c, note) = scene_camera(&g.cameras[n.unwrap_or(0)])?;
            scene.warnings.extend(note);
            c
        }
    };
    scene.data.camera = camera;
    if g.lights.is_empty() {
        scene.data.lights.push(Light::Directional {
            to_light: DEFAULT_KEY_TO_LIGHT,
            irradiance: [DEFAULT_KEY_IRRADIANCE; 3],
        });
        scene.data.environment = Some([DEFAULT_ENVIRONMENT; 3]);
        scene.warnings.push(format!(
            "no lights in the file: a directional key light (irradiance {DEFAULT_KEY_IRRADIANCE} W/m², toward {DEFAULT_KEY_TO_LIGHT:?}) and a uniform environment (radiance {DEFAULT_ENVIRONMENT} W/m²/sr) light it"
        ));
    } else {
        scene.data.lights.extend(g.lights.iter().cloned());
        // The file's punctual lights cast PCF shadows.
        let pcf = specula_raster::shadow::ShadowSettings {
            filter: specula_raster::shadow::ShadowFilter::Pcf,
            ..Default::default()
        };
        scene.data.shadows = (scene.data.lights.iter())
            .map(|l| (!matches!(l, Light::Polygon { .. })).then_some(pcf))
            .collect();
        for (l, s) in scene.data.lights.iter().zip(&scene.data.shadows) {
            if let Some(s) = s {
                crate::memory::reserve("a glTF light's shadow maps", s.bytes(l))?;
            }
        }
    }
    scene.warm_tables();
    let SceneBuilder {
        mut data,
        materials,
        inputs,
        warnings,
        ..
    } = scene;
    data.materials = materials.list;
    data.geometry = vec![GeometryPass::main(data.triangles.len())];
    let lines = crate::lines::build(&mut data, &[], None, output.tonemap.into(), output.exposure);
    let data = SceneData::new(data)?;
    Ok(LoadedScene {
        data,
        output,
        inputs,
        warnings,
        post_stages: Vec::new(),
        outlines: Vec::new(),
        strokes: None,
        lines,
    })
}

/// A scene check shared with TOML scenes, as its message.
fn scene_check(e: BuildError) -> GltfSceneError {
    GltfSceneError::Scene(e.to_string())
}
