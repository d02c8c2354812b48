//! Scene files (TOML): camera, output, meshes, materials, lights,
//! environment. Parsed with serde into the `*Desc` types, validated once, and
//! turned into a `SceneData` the rasterizer trusts. Every error names the
//! file and the line (TOML syntax, unknown fields) or the field.

use crate::material_desc::MaterialDesc;
use crate::memory;
use crate::mesh::{self, MeshData};
use crate::validate::{check_extent, check_point, MAX_FOV_Y_DEG, MAX_WORLD, MIN_FOV_Y_DEG};
use glam::{EulerRot, Mat3, Mat4, Quat, Vec3};
use serde::Deserialize;
use specula_core::light::Light;
use specula_core::models::MetallicRoughness;
use specula_core::Model;
use specula_raster::post::Tonemap;
use specula_raster::{Camera, SceneData};
use specula_raster::{GeometryPass, Lit, Material};
use std::collections::{BTreeMap, HashMap, HashSet};
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
    posterize: Option<PosterizeDesc>,
    #[serde(default)]
    render: RenderDesc,
    /// `[[outline]]` and `[strokes]` (lines.rs).
    #[serde(default, rename = "outline")]
    outlines: Vec<crate::lines::OutlineDesc>,
    strokes: Option<crate::lines::StrokesDesc>,
}

/// `[posterize]`: quantize the tone-mapped image (npr/src/posterize.rs).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PosterizeDesc {
    levels: u32,
    #[serde(default)]
    mode: PosterizeModeDesc,
}

#[derive(Debug, Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum PosterizeModeDesc {
    #[default]
    Rgb,
    Luminance,
}

/// How the frame is lit (the `[render]` table).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderDesc {
    /// How polygon lights are integrated: "ltc" (closed form) or
    /// "reference" (converged quadrature per pixel, slow).
    #[serde(default)]
    area_lights: AreaLightsDesc,
}

#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
enum AreaLightsDesc {
    #[default]
    Ltc,
    Reference,
}

fn yes() -> bool {
    true
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
        /// A planar simple polygon (convex or not), 3 to 16 vertices,
        /// counter-clockwise seen from the side it lights.
        vertices: Vec<[f32; 3]>,
        /// Radiance (W/m²/sr), RGB.
        radiance: [f32; 3],
        /// Emits from both sides.
        #[serde(default)]
        two_sided: bool,
        /// Drawn as unlit geometry of its radiance.
        #[serde(default = "yes")]
        visible: bool,
    },
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
    /// Files the scene was read from (the scene file, OBJs, MTLs; relative
    /// ones against the scene's folder): outputs
    /// must never overwrite them.
    pub inputs: Vec<PathBuf>,
    /// Things worth telling the user that did not stop the load.
    pub warnings: Vec<String>,
    /// Image-space stages the scene asks for, run after the tone map and
    /// before the encode (`[posterize]`).
    pub post_stages: Vec<std::sync::Arc<dyn specula_raster::post::PostStage>>,
    /// The checked `[[outline]]` tables, in order, and `[strokes]` (lines.rs).
    pub outlines: Vec<crate::lines::OutlineSpec>,
    pub strokes: Option<crate::lines::StrokesSpec>,
    /// The extrusion outlines' vertex stages and the stroke overlay
    /// (lines.rs), for the renderer and `--svg-lines`.
    pub lines: crate::lines::LineStages,
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

/// Largest accepted radiometric value (radiance, intensity, irradiance).
/// A pixel sums lights × BRDF (up to ~3e5 at α = 1e-3) over up to 256
/// supersamples: 1e20 · 3e5 · 256 ≈ 8e27 leaves f32 (3.4e38) room for many
/// lights; a uniform environment of 3e38 overflowed at ssaa 4.
const MAX_RADIOMETRIC: f32 = 1e20;

fn check_radiometric(field: &str, v: [f32; 3]) -> Result<(), String> {
    check_finite(field, &v)?;
    if v.iter().all(|x| (0.0..=MAX_RADIOMETRIC).contains(x)) {
        Ok(())
    } else {
        Err(format!(
            "{field}: every component must be in [0, {MAX_RADIOMETRIC:e}], got {v:?}"
        ))
    }
}

/// The accepted |scale| per axis: their ratio (≤ 1e24) keeps the normal
/// matrix finite in f32.
const MIN_SCALE: f32 = 1e-12;
const MAX_SCALE: f32 = 1e12;

/// Checks that a mesh's transform keeps its (finite, in-range) vertices
/// inside ±MAX_WORLD.
fn check_transform(field: &str, positions: &[Vec3], model: &Mat4) -> Result<(), String> {
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
fn check_output_size(o: &OutputDesc) -> Result<(), String> {
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
            };
            let shader = Lit::with_maps(model, maps)
                .map_err(|e| format!("material {}: map_Kd: {e}", m.name))?;
            Ok(Material::new(&m.name, shader, false))
        }
        None => Ok(Material::new(&m.name, Lit::new(model), false)),
    }
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
    build_scene(path, desc, read).map_err(err)
}

/// Builds a parsed scene, one table after another. The order is part of
/// the behaviour: the first table with a problem is the one reported, and
/// later tables see what earlier ones added (meshes name materials,
/// visible lights add geometry, outlines name materials).
fn build_scene(
    path: &Path,
    desc: SceneFile,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<LoadedScene, String> {
    let camera = build_camera(&desc.camera)?;
    check_output(&desc.output)?;
    let mut scene = SceneBuilder::new(path, read, camera, desc.output.background);
    scene.add_materials(&desc.materials)?;
    scene.add_meshes(&desc.meshes)?;
    scene.add_lights(&desc.lights, desc.render.area_lights)?;
    if let Some(e) = &desc.environment {
        scene.data.environment = Some(build_environment(e)?);
    }
    scene.warm_tables();
    let outlines = check_outlines(&desc.outlines, &scene.materials.by_name)?;
    let strokes = desc.strokes.as_ref().map(|s| s.check()).transpose()?;

    let SceneBuilder {
        mut data,
        materials,
        inputs,
        warnings,
        ..
    } = scene;
    data.materials = materials.list;
    data.geometry = vec![GeometryPass::main(data.triangles.len())];
    let mut lines = crate::lines::build(&mut data, &outlines, strokes.as_ref(), &desc.output);
    data.validate()?;
    let mut post_stages = build_posterize(desc.posterize.as_ref())?;
    post_stages.extend(std::mem::take(&mut lines.post));
    Ok(LoadedScene {
        data,
        output: desc.output,
        inputs,
        warnings,
        post_stages,
        outlines,
        strokes,
        lines,
    })
}

/// `[camera]`: finite, inside the world, a usable field of view and depth
/// range, and a frame that eye, target and up can span.
fn build_camera(c: &CameraDesc) -> Result<Camera, String> {
    for (f, v) in [
        ("camera.eye", &c.eye),
        ("camera.target", &c.target),
        ("camera.up", &c.up),
    ] {
        check_finite(f, v)?;
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
fn check_output(o: &OutputDesc) -> Result<(), String> {
    check_output_size(o)?;
    check_radiometric("output.background", o.background)?;
    if !o.exposure.is_finite() {
        return Err("output.exposure: must be finite".into());
    }
    for (i, l) in o.labels.iter().enumerate() {
        l.validate().map_err(|e| format!("output.label[{i}].{e}"))?;
    }
    Ok(())
}

/// `[environment]`: the uniform radiance.
fn build_environment(e: &EnvironmentDesc) -> Result<[f32; 3], String> {
    check_radiometric("environment.uniform", e.uniform)?;
    Ok(e.uniform)
}

/// `[[outline]]`s; the materials they name must exist.
fn check_outlines(
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
fn build_posterize(
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
struct Materials {
    list: Vec<Material>,
    /// Ids of `[materials]` and MTL materials by name (not lights' own).
    by_name: HashMap<String, u32>,
    /// Materials that read uvs (textures, tonal art maps).
    textured: HashSet<u32>,
    /// The default material's id, once a mesh needed it.
    default_id: Option<u32>,
}

/// Where a mesh goes in the world: its model matrix, the matrix for its
/// normals, and whether it mirrors (which flips the winding).
struct Placement {
    model: Mat4,
    normal_m: Mat3,
    flip: bool,
}

/// What the tables add up to while they are read in order.
struct SceneBuilder<'a> {
    path: &'a Path,
    read: &'a dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    data: SceneData,
    materials: Materials,
    /// Whether some mesh brought texture coordinates.
    any_uvs: bool,
    inputs: Vec<PathBuf>,
    warnings: Vec<String>,
}

impl<'a> SceneBuilder<'a> {
    fn new(
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
                triangles: Vec::new(),
                tri_material: Vec::new(),
                materials: Vec::new(),
                geometry: Vec::new(),
                lights: Vec::new(),
                environment: None,
                background,
                camera,
            },
            materials: Materials {
                list: Vec::new(),
                by_name: HashMap::new(),
                textured: HashSet::new(),
                default_id: None,
            },
            any_uvs: false,
            inputs: vec![path.to_path_buf()],
            warnings: Vec::new(),
        }
    }

    /// `[materials]`: built before the meshes, so they win over MTL
    /// materials of the same name.
    fn add_materials(&mut self, descs: &BTreeMap<String, MaterialDesc>) -> Result<(), String> {
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
            self.inputs
                .extend(m.base_color_texture().map(Path::to_path_buf));
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
    fn add_meshes(&mut self, descs: &[MeshDesc]) -> Result<(), String> {
        for (i, md) in descs.iter().enumerate() {
            self.add_mesh(&format!("mesh[{i}]"), md)?;
        }
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
        if data.triangles.is_empty() {
            self.warnings.push("the scene has no triangles".into());
        }
        Ok(())
    }

    /// One `[[mesh]]`: its shape, its materials, its placement.
    fn add_mesh(&mut self, field: &str, md: &MeshDesc) -> Result<(), String> {
        let mesh = self.build_shape(field, md)?;
        let local = self.mesh_materials(field, md, &mesh)?;
        self.check_uvs(field, md, &mesh, &local)?;
        let placement = place_mesh(field, md, &mesh.positions)?;
        self.append_mesh(&mesh, &placement, &local);
        Ok(())
    }

    /// The mesh's geometry: exactly one of obj, sphere, plane, cube.
    fn build_shape(&mut self, field: &str, md: &MeshDesc) -> Result<MeshData, String> {
        let shapes = [
            md.obj.is_some(),
            md.sphere.is_some(),
            md.plane.is_some(),
            md.cube.is_some(),
        ];
        if shapes.iter().filter(|s| **s).count() != 1 {
            return Err(format!(
                "{field}: give exactly one of obj, sphere, plane, cube"
            ));
        }
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
    fn load_obj(&mut self, field: &str, p: &Path) -> Result<MeshData, String> {
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
    fn mesh_materials(
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
    fn check_uvs(
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
    fn append_mesh(&mut self, mesh: &MeshData, placement: &Placement, local: &[u32]) {
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
    fn add_lights(&mut self, descs: &[LightDesc], area: AreaLightsDesc) -> Result<(), String> {
        for (i, l) in descs.iter().enumerate() {
            let light = self.build_light(i, l, area)?;
            self.data.lights.push(light);
        }
        Ok(())
    }

    fn build_light(
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
            } => {
                check_point(&format!("{field}.position"), *position)?;
                check_radiometric(&format!("{field}.intensity"), *intensity)?;
                Light::Point {
                    position: *position,
                    intensity: *intensity,
                }
            }
            LightDesc::Directional {
                direction,
                irradiance,
            } => {
                check_radiometric(&format!("{field}.irradiance"), *irradiance)?;
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
            } => {
                use crate::polygon_light::{add_visible, check_polygon};
                use specula_core::light::AreaMethod;
                check_polygon(&format!("{field}.vertices"), vertices)?;
                check_radiometric(&format!("{field}.radiance"), *radiance)?;
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
        if matches!(light, Light::Polygon { .. }) {
            crate::polygon_light::check_materials(&self.materials.list)
                .map_err(|e| format!("{field}: {e}"))?;
        }
        Ok(light)
    }

    /// Tables built once per process on first use: made here, so that
    /// their cost (the split-sum tables: ~400 M instructions) counts as
    /// loading and not as the first frame's shading pass.
    fn warm_tables(&self) {
        let polygon_lights = self
            .data
            .lights
            .iter()
            .any(|l| matches!(l, Light::Polygon { .. }));
        if polygon_lights {
            specula_core::ltc::ggx::table();
        }
        if (polygon_lights || self.data.environment.is_some())
            && self.materials.list.iter().any(is_metallic_roughness)
        {
            specula_core::albedo_tables::AlbedoTables::get();
        }
    }
}

/// `sphere`: segment and ring counts, radius, and the memory it takes.
fn build_sphere(field: &str, s: &SphereDesc) -> Result<MeshData, String> {
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
fn build_plane(field: &str, p: &PlaneDesc) -> Result<MeshData, String> {
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
fn build_cube(field: &str, c: &CubeDesc) -> Result<MeshData, String> {
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
fn place_mesh(field: &str, md: &MeshDesc, positions: &[Vec3]) -> Result<Placement, String> {
    let scale = match md.scale {
        Scale::Uniform(s) => Vec3::splat(s),
        Scale::Axes(a) => Vec3::from(a),
    };
    check_finite(&format!("{field}.translate"), &md.translate)?;
    check_finite(&format!("{field}.rotate"), &md.rotate)?;
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

/// Whether a material is `metallic_roughness`, whose polygon-light and
/// environment terms read the process-wide split-sum tables.
fn is_metallic_roughness(m: &Material) -> bool {
    m.shader
        .as_any()
        .downcast_ref::<Lit>()
        .is_some_and(|l| matches!(l.model(), Model::MetallicRoughness(_)))
}
