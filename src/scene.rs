//! Scene files (TOML): camera, output, meshes, materials, lights,
//! environment. Parsed with serde into the `*Desc` types, validated once, and
//! turned into a `SceneData` the rasterizer trusts. Every error names the
//! file and the line (TOML syntax, unknown fields) or the field.

use crate::material_desc::MaterialDesc;
use crate::mesh::{self, MeshData};
use glam::{EulerRot, Mat3, Mat4, Quat, Vec3};
use serde::Deserialize;
use specula_core::light::Light;
use specula_core::models::MetallicRoughness;
use specula_core::Model;
use specula_raster::post::Tonemap;
use specula_raster::{Camera, SceneData};
use specula_raster::{GeometryPass, Lit, Material};
use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::path::{Path, PathBuf};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    camera: CameraDesc,
    #[serde(default)]
    output: OutputDesc,
    environment: Option<EnvironmentDesc>,
    #[serde(default, rename = "mesh")]
    meshes: Vec<MeshDesc>,
    #[serde(default)]
    materials: BTreeMap<String, MaterialDesc>,
    #[serde(default, rename = "light")]
    lights: Vec<LightDesc>,
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraDesc {
    eye: [f32; 3],
    target: [f32; 3],
    #[serde(default = "default_up")]
    up: [f32; 3],
    /// Vertical field of view, degrees.
    fov_y: f32,
    near: f32,
    far: f32,
}

/// How the image is produced; CLI flags override the size and supersampling.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct OutputDesc {
    pub width: u32,
    pub height: u32,
    pub ssaa: u32,
    pub tonemap: TonemapDesc,
    /// Exposure in stops: radiance is scaled by 2^exposure before tone mapping.
    pub exposure: f32,
    /// Radiance of uncovered pixels when there is no environment.
    pub background: [f32; 3],
    /// Text written on the image (`[[output.label]]`, label.rs).
    #[serde(rename = "label")]
    pub labels: Vec<crate::label::LabelDesc>,
}

impl Default for OutputDesc {
    fn default() -> Self {
        OutputDesc {
            width: 960,
            height: 540,
            ssaa: 1,
            tonemap: TonemapDesc::Clamp,
            exposure: 0.0,
            background: [0.0; 3],
            labels: Vec::new(),
        }
    }
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum TonemapDesc {
    #[default]
    Clamp,
    Reinhard,
    Aces,
}

impl From<TonemapDesc> for Tonemap {
    fn from(t: TonemapDesc) -> Tonemap {
        match t {
            TonemapDesc::Clamp => Tonemap::Clamp,
            TonemapDesc::Reinhard => Tonemap::Reinhard,
            TonemapDesc::Aces => Tonemap::Aces,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvironmentDesc {
    /// Radiance arriving equally from every direction.
    uniform: [f32; 3],
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SphereDesc {
    #[serde(default = "one")]
    radius: f32,
    #[serde(default = "sphere_segments")]
    segments: u32,
    #[serde(default = "sphere_rings")]
    rings: u32,
}

fn one() -> f32 {
    1.0
}
fn sphere_segments() -> u32 {
    64
}
fn sphere_rings() -> u32 {
    32
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlaneDesc {
    #[serde(default = "unit2")]
    size: [f32; 2],
    #[serde(default = "one2")]
    segments: [u32; 2],
}

fn unit2() -> [f32; 2] {
    [1.0, 1.0]
}
fn one2() -> [u32; 2] {
    [1, 1]
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CubeDesc {
    #[serde(default = "one")]
    size: f32,
    #[serde(default = "one_u")]
    segments: u32,
}

fn one_u() -> u32 {
    1
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum Scale {
    Uniform(f32),
    Axes([f32; 3]),
}

impl Default for Scale {
    fn default() -> Self {
        Scale::Uniform(1.0)
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshDesc {
    obj: Option<PathBuf>,
    sphere: Option<SphereDesc>,
    plane: Option<PlaneDesc>,
    cube: Option<CubeDesc>,
    /// Material for every triangle of the mesh (overrides the MTL's).
    material: Option<String>,
    #[serde(default)]
    translate: [f32; 3],
    /// Euler angles in degrees, applied about X, then Y, then Z.
    #[serde(default)]
    rotate: [f32; 3],
    #[serde(default)]
    scale: Scale,
}

#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
enum LightDesc {
    Point {
        position: [f32; 3],
        /// Radiant intensity (W/sr), RGB.
        intensity: [f32; 3],
    },
    Directional {
        /// Direction the light travels (from the light toward the scene).
        direction: [f32; 3],
        /// Irradiance on a surface facing the light, RGB.
        irradiance: [f32; 3],
    },
    Polygon {
        /// A planar convex polygon, 3 to 8 vertices, counter-clockwise seen
        /// from the side it lights.
        vertices: Vec<[f32; 3]>,
        /// Radiance (W/m²/sr), RGB.
        radiance: [f32; 3],
    },
}

/// Checks a polygon light's vertices: 3..=MAX_POLYGON_VERTICES finite
/// points, planar and convex with a non-zero area (so its orientation and
/// every edge's plane are defined).
fn check_polygon(field: &str, v: &[[f32; 3]]) -> Result<(), String> {
    use specula_core::light::MAX_POLYGON_VERTICES;
    if !(3..=MAX_POLYGON_VERTICES).contains(&v.len()) {
        return Err(format!(
            "{field}: a polygon light needs 3 to {MAX_POLYGON_VERTICES} vertices, got {}",
            v.len()
        ));
    }
    for (k, p) in v.iter().enumerate() {
        check_finite(&format!("{field}[{k}]"), p)?;
    }
    let p: Vec<glam::DVec3> = v
        .iter()
        .map(|p| glam::DVec3::from(p.map(|c| c as f64)))
        .collect();
    // Newell's normal: twice the area vector of a planar polygon.
    let mut n = glam::DVec3::ZERO;
    for k in 0..p.len() {
        n += p[k].cross(p[(k + 1) % p.len()]);
    }
    let size = p.iter().map(|q| (*q - p[0]).length()).fold(0.0, f64::max);
    // Finite vertices (checked above) give a finite normal.
    if size == 0.0 || n.length() <= 1e-9 * size * size {
        return Err(format!("{field}: the polygon has no area"));
    }
    let n = n.normalize();
    for (k, q) in p.iter().enumerate() {
        if (*q - p[0]).dot(n).abs() > 1e-4 * size {
            return Err(format!("{field}[{k}]: the polygon is not planar"));
        }
        let (a, b) = (p[(k + 1) % p.len()], p[(k + 2) % p.len()]);
        if (a - *q).cross(b - a).dot(n) <= 0.0 {
            return Err(format!(
                "{field}: the polygon is not convex (or repeats a vertex) at vertex {}",
                (k + 1) % p.len()
            ));
        }
    }
    Ok(())
}

/// A scene-loading error: where, and what.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    pub file: PathBuf,
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.file.display(), self.message)
    }
}

impl std::error::Error for SceneError {}

/// A loaded scene, ready to render.
pub struct LoadedScene {
    pub data: SceneData,
    pub output: OutputDesc,
    /// Files the scene was read from (the scene file, OBJs, MTLs): outputs
    /// must never overwrite them.
    pub inputs: Vec<PathBuf>,
    /// Things worth telling the user that did not stop the load.
    pub warnings: Vec<String>,
}

/// Reads a scene file from disk; relative paths resolve against its folder.
pub fn load_scene(path: &Path) -> Result<LoadedScene, SceneError> {
    let err = |message: String| SceneError {
        file: path.to_path_buf(),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|e| err(format!("cannot read: {e}")))?;
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let read = move |p: &Path| std::fs::read(dir.join(p));
    let mut scene = load_scene_str(path, &text, &read)?;
    let base = path.parent().unwrap_or(Path::new(""));
    for p in scene.inputs.iter_mut().skip(1) {
        *p = base.join(&p);
    }
    Ok(scene)
}

fn check_finite(field: &str, v: &[f32]) -> Result<(), String> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(format!(
            "{field}: every component must be finite, got {v:?}"
        ))
    }
}

fn check_radiometric(field: &str, v: [f32; 3]) -> Result<(), String> {
    check_finite(field, &v)?;
    if v.iter().all(|x| *x >= 0.0) {
        Ok(())
    } else {
        Err(format!("{field}: must be ≥ 0, got {v:?}"))
    }
}

/// Largest segment count a procedural mesh accepts (per axis).
const MAX_SEGMENTS: u32 = 4096;

fn check_segments(field: &str, v: u32, min: u32) -> Result<(), String> {
    if (min..=MAX_SEGMENTS).contains(&v) {
        Ok(())
    } else {
        Err(format!(
            "{field}: must be in {min}..={MAX_SEGMENTS}, got {v}"
        ))
    }
}

/// The material used where neither the scene nor an MTL gives one.
fn default_material() -> Material {
    let model = Model::MetallicRoughness(MetallicRoughness {
        base_color: [0.8, 0.8, 0.8],
        roughness: 0.5,
        metallic: 0.0,
    });
    Material::new("default", Lit { model }, false)
}

/// The metallic-roughness reading of an MTL material: `Kd` base colour, `Pr`
/// roughness and `Pm` metallic (the PBR extension); without `Pr`, roughness
/// from Phong `Ns` through α² = 2 / (Ns + 2) [Walter07, §5.2]; defaults 0.5
/// and 0.
fn mtl_material(m: &tobj::Material) -> Result<Material, String> {
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
    Ok(Material::new(&m.name, Lit { model }, false))
}

/// Parses and builds a scene from its text; `read` supplies the files it
/// names (relative to the scene's folder). `path` is only used in messages.
pub fn load_scene_str(
    path: &Path,
    text: &str,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<LoadedScene, SceneError> {
    let err = |message: String| SceneError {
        file: path.to_path_buf(),
        message,
    };
    let desc: SceneFile =
        toml::from_str(text).map_err(|e| err(format!("{}", e).trim_end().to_string()))?;
    let mut warnings = Vec::new();
    let mut inputs = vec![path.to_path_buf()];

    let c = &desc.camera;
    for (f, v) in [
        ("camera.eye", &c.eye),
        ("camera.target", &c.target),
        ("camera.up", &c.up),
    ] {
        check_finite(f, v).map_err(&err)?;
    }
    if !(c.fov_y > 0.0 && c.fov_y < 180.0) {
        return Err(err(format!(
            "camera.fov_y: must be in (0, 180) degrees, got {}",
            c.fov_y
        )));
    }
    if !(c.near > 0.0 && c.far > c.near && c.far.is_finite()) {
        return Err(err(format!(
            "camera.near / camera.far: need 0 < near < far < inf, got {} and {}",
            c.near, c.far
        )));
    }
    let forward = Vec3::from(c.target) - Vec3::from(c.eye);
    if forward.length_squared() == 0.0 || forward.cross(Vec3::from(c.up)).length_squared() == 0.0 {
        return Err(err("camera: eye, target and up must span a frame (target ≠ eye, up not parallel to the view)".into()));
    }
    let camera = Camera {
        eye: c.eye.into(),
        target: c.target.into(),
        up: c.up.into(),
        fov_y_deg: c.fov_y,
        near: c.near,
        far: c.far,
    };

    let o = &desc.output;
    check_radiometric("output.background", o.background).map_err(&err)?;
    if !o.exposure.is_finite() {
        return Err(err("output.exposure: must be finite".into()));
    }
    for (i, l) in o.labels.iter().enumerate() {
        l.validate()
            .map_err(|e| err(format!("output.label[{i}].{e}")))?;
    }

    // Materials: scene materials first, so they win over MTL ones of the same name.
    let mut materials = Vec::new();
    let mut by_name: HashMap<String, u32> = HashMap::new();
    for (name, m) in &desc.materials {
        let mut notes = Vec::new();
        let built = m
            .build(name, crate::material_desc::Tables::Build, &mut notes)
            .map_err(|e| err(format!("materials.{name}.{e}")))?;
        warnings.extend(
            notes
                .into_iter()
                .map(|n| format!("{}: materials.{name}.{n}", path.display())),
        );
        by_name.insert(name.clone(), materials.len() as u32);
        materials.push(built);
    }
    let mut default_id = None;

    let mut data = SceneData {
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        tangents: Vec::new(),
        triangles: Vec::new(),
        tri_material: Vec::new(),
        materials: Vec::new(),
        geometry: Vec::new(),
        lights: Vec::new(),
        environment: None,
        background: o.background,
        camera,
    };
    let mut any_uvs = false;

    for (i, md) in desc.meshes.iter().enumerate() {
        let field = format!("mesh[{i}]");
        let shapes = [
            md.obj.is_some(),
            md.sphere.is_some(),
            md.plane.is_some(),
            md.cube.is_some(),
        ];
        if shapes.iter().filter(|s| **s).count() != 1 {
            return Err(err(format!(
                "{field}: give exactly one of obj, sphere, plane, cube"
            )));
        }
        let mesh: MeshData = if let Some(p) = &md.obj {
            let bytes = read(p)
                .map_err(|e| err(format!("{field}.obj: cannot read {}: {e}", p.display())))?;
            inputs.push(p.clone());
            let m =
                mesh::load_obj(p, &bytes, read).map_err(|e| err(format!("{field}.obj: {e}")))?;
            let limit = specula_raster::setup::MAX_CLIP_COORD as f32;
            let bad = m
                .positions
                .iter()
                .filter(|v| v.is_nan() || v.abs().max_element() > limit)
                .count();
            if bad > 0 {
                warnings.push(format!(
                    "{}: {bad} vertices are not finite or beyond ±{limit:e}; triangles using them are skipped",
                    p.display()
                ));
            }
            m
        } else if let Some(s) = &md.sphere {
            check_segments(&format!("{field}.sphere.segments"), s.segments, 3).map_err(&err)?;
            check_segments(&format!("{field}.sphere.rings"), s.rings, 2).map_err(&err)?;
            mesh::sphere(s.radius, s.segments, s.rings)
        } else if let Some(p) = &md.plane {
            for (k, v) in p.segments.iter().enumerate() {
                check_segments(&format!("{field}.plane.segments[{k}]"), *v, 1).map_err(&err)?;
            }
            mesh::plane(p.size, p.segments)
        } else {
            let c = md.cube.as_ref().expect("one shape is set");
            check_segments(&format!("{field}.cube.segments"), c.segments, 1).map_err(&err)?;
            mesh::cube(c.size, c.segments)
        };

        // Material ids of this mesh → scene material ids.
        let mut local = Vec::with_capacity(mesh.material_names.len());
        for name in &mesh.material_names {
            let name = md.material.as_ref().or(name.as_ref());
            let id = match name {
                Some(n) => match by_name.get(n) {
                    Some(&id) => id,
                    None => {
                        let Some(mt) = mesh.mtl.iter().find(|m| &m.name == n) else {
                            return Err(err(format!("{field}.material: no material named {n:?} in [materials] or the mesh's MTL")));
                        };
                        let built =
                            mtl_material(mt).map_err(|e| err(format!("{field}.obj: {e}")))?;
                        let id = materials.len() as u32;
                        materials.push(built);
                        by_name.insert(n.clone(), id);
                        id
                    }
                },
                None => *default_id.get_or_insert_with(|| {
                    materials.push(default_material());
                    materials.len() as u32 - 1
                }),
            };
            local.push(id);
        }

        let scale = match md.scale {
            Scale::Uniform(s) => Vec3::splat(s),
            Scale::Axes(a) => Vec3::from(a),
        };
        check_finite(&format!("{field}.translate"), &md.translate).map_err(&err)?;
        check_finite(&format!("{field}.rotate"), &md.rotate).map_err(&err)?;
        if !scale.is_finite() || scale.cmpeq(Vec3::ZERO).any() {
            return Err(err(format!(
                "{field}.scale: must be finite and non-zero, got {scale}"
            )));
        }
        let r = md.rotate.map(f32::to_radians);
        let rot = Quat::from_euler(EulerRot::ZYX, r[2], r[1], r[0]);
        let model = Mat4::from_scale_rotation_translation(scale, rot, md.translate.into());
        let normal_m = Mat3::from_mat4(model).inverse().transpose();
        let flip = model.determinant() < 0.0;

        let base = data.positions.len() as u32;
        data.positions
            .extend(mesh.positions.iter().map(|p| model.transform_point3(*p)));
        data.normals.extend(
            mesh.normals
                .iter()
                .map(|n| (normal_m * *n).try_normalize().unwrap_or(Vec3::Z)),
        );
        any_uvs |= !mesh.uvs.is_empty();
        data.uvs.extend(mesh.uvs.iter().copied());
        if mesh.uvs.is_empty() {
            data.uvs
                .extend(std::iter::repeat_n(glam::Vec2::ZERO, mesh.positions.len()));
        }
        for (t, m) in mesh.triangles.iter().zip(&mesh.tri_material) {
            // A mirroring transform turns counter-clockwise into clockwise.
            let t = if flip { [t[0], t[2], t[1]] } else { *t };
            data.triangles.push(t.map(|k| k + base));
            data.tri_material.push(local[*m as usize]);
        }
    }
    if !any_uvs {
        data.uvs.clear();
    }
    data.tangents = specula_raster::scene::compute_tangents(
        &data.positions,
        &data.normals,
        &data.uvs,
        &data.triangles,
    );
    if data.triangles.is_empty() {
        warnings.push("the scene has no triangles".into());
    }

    for (i, l) in desc.lights.iter().enumerate() {
        let field = format!("light[{i}]");
        data.lights.push(match l {
            LightDesc::Point {
                position,
                intensity,
            } => {
                check_finite(&format!("{field}.position"), position).map_err(&err)?;
                check_radiometric(&format!("{field}.intensity"), *intensity).map_err(&err)?;
                Light::Point {
                    position: *position,
                    intensity: *intensity,
                }
            }
            LightDesc::Directional {
                direction,
                irradiance,
            } => {
                check_radiometric(&format!("{field}.irradiance"), *irradiance).map_err(&err)?;
                let d = Vec3::from(*direction);
                let Some(d) = d.try_normalize() else {
                    return Err(err(format!(
                        "{field}.direction: must be a finite non-zero vector, got {direction:?}"
                    )));
                };
                Light::Directional {
                    to_light: (-d).to_array(),
                    irradiance: *irradiance,
                }
            }
            LightDesc::Polygon { vertices, radiance } => {
                check_polygon(&format!("{field}.vertices"), vertices).map_err(&err)?;
                check_radiometric(&format!("{field}.radiance"), *radiance).map_err(&err)?;
                Light::Polygon {
                    vertices: vertices.clone(),
                    radiance: *radiance,
                }
            }
        });
    }
    if let Some(e) = &desc.environment {
        check_radiometric("environment.uniform", e.uniform).map_err(&err)?;
        data.environment = Some(e.uniform);
    }
    data.materials = materials;
    data.geometry = vec![GeometryPass::main(data.triangles.len())];
    data.validate().map_err(err)?;
    Ok(LoadedScene {
        data,
        output: desc.output,
        inputs,
        warnings,
    })
}
