//! Scene files (TOML): camera, output, meshes, materials, lights,
//! environment. Parsed with serde into the `*Desc` types, validated once, and
//! turned into a `SceneData` the rasterizer trusts. Every error names the
//! file and the line (TOML syntax, unknown fields) or the field.

mod build;
mod desc;
mod field_error;
mod gltf_error;
mod gltf_file;

use build::*;
pub(crate) use desc::OutputDesc;
use desc::*;
pub use gltf_error::GltfSceneError;
pub use gltf_file::{load_gltf_scene, load_gltf_str, GltfOptions};
use specula_raster::GeometryPass;
use specula_raster::SceneData;
use std::path::{Path, PathBuf};

/// A scene-loading error: where, and what.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}: {message}", file.display())]
pub struct SceneError {
    pub(crate) file: PathBuf,
    pub(crate) message: String,
}

/// A loaded scene, ready to render.
pub struct LoadedScene {
    pub data: SceneData,
    pub output: OutputDesc,
    /// Files the scene was read from (the scene file, OBJs, MTLs,
    /// textures, tonal art maps; relative ones against the scene's
    /// folder; by [`load_scene`], every file it read): outputs must never
    /// overwrite them.
    pub inputs: Vec<PathBuf>,
    /// Things worth telling the user that did not stop the load.
    pub warnings: Vec<String>,
    /// Image-space stages the scene asks for, run after the tone map and
    /// before the encode (`[posterize]`).
    pub(crate) post_stages: Vec<std::sync::Arc<dyn specula_raster::post::PostStage>>,
    /// The checked `[[outline]]` tables, in order, and `[strokes]` (lines.rs).
    pub outlines: Vec<crate::lines::OutlineSpec>,
    pub strokes: Option<crate::lines::StrokesSpec>,
    /// The extrusion outlines' vertex stages and the stroke overlay
    /// (lines.rs), for the renderer and `--svg-lines`.
    pub lines: crate::lines::LineStages,
}

/// Whether `path` names a glTF file (`.gltf`, `.glb`), which
/// [`load_gltf_scene`] reads, rather than a TOML scene.
pub fn is_gltf_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// Reads a scene file from disk; relative paths resolve against its folder.
pub fn load_scene(path: &Path) -> Result<LoadedScene, SceneError> {
    let err = |message: String| SceneError {
        file: path.to_path_buf(),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|e| err(format!("cannot read: {e}")))?;
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    // Every file the load reads is an input (textures named by an MTL,
    // tonal art map tones, …), recorded where it is read.
    let read_paths = std::cell::RefCell::new(Vec::new());
    let read = |p: &Path| {
        let full = dir.join(p);
        read_paths.borrow_mut().push(full.clone());
        std::fs::read(full)
    };
    let mut scene = load_scene_in(path, &text, &read, Some(&dir))?;
    for p in scene.inputs.iter_mut().skip(1) {
        *p = dir.join(&p);
    }
    for p in read_paths.into_inner() {
        if !scene.inputs.contains(&p) {
            scene.inputs.push(p);
        }
    }
    Ok(scene)
}

/// Parses and builds a scene from its text; `read` supplies the files it
/// names (relative to the scene's folder). `path` is only used in messages.
pub fn load_scene_str(
    path: &Path,
    text: &str,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<LoadedScene, SceneError> {
    load_scene_in(path, text, read, None)
}

/// [`load_scene_str`], where `read` reads the files under `dir` when
/// `dir` is given (a large OBJ is then looked up in the mesh cache
/// without being read whole: `mesh_cache::file_key`).
fn load_scene_in(
    path: &Path,
    text: &str,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    dir: Option<&Path>,
) -> Result<LoadedScene, SceneError> {
    let err = |message: String| SceneError {
        file: path.to_path_buf(),
        message,
    };
    let desc = parse(text).map_err(err)?;
    build_scene(path, desc, read, dir).map_err(|e| err(e.to_string()))
}

/// The scene's tables from its text. A TOML error says the line; a value
/// of the wrong kind or a missing field also names the table and field it
/// belongs to (`in `mesh[1].sphere``), which the line alone does not show
/// (a missing field is reported at its table's first line).
fn parse(text: &str) -> Result<SceneFile, String> {
    let toml_message = |e: toml::de::Error| e.to_string().trim_end().to_string();
    let de = toml::Deserializer::parse(text).map_err(toml_message)?;
    serde_path_to_error::deserialize(de).map_err(|e| {
        if let Some(located) = field_error::locate(text, e.path()) {
            return located;
        }
        let at = e.path().to_string();
        let message = toml_message(e.into_inner());
        if at.is_empty() || at == "." {
            message
        } else {
            format!("{message} (in `{at}`)")
        }
    })
}

/// Builds a parsed scene, one table after another. The order is part of
/// the behaviour: the first table with a problem is the one reported, and
/// later tables see what earlier ones added (meshes name materials,
/// visible lights add geometry, outlines name materials).
fn build_scene(
    path: &Path,
    desc: SceneFile,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    dir: Option<&Path>,
) -> Result<LoadedScene, BuildError> {
    let camera = build_camera(&desc.camera)?;
    check_output(&desc.output)?;
    let mut scene = SceneBuilder::new(path, read, camera, desc.output.background);
    scene.dir = dir;
    scene.add_materials(&desc.materials)?;
    scene.add_meshes(&desc.meshes)?;
    scene.add_lights(&desc.lights, desc.render.area_lights)?;
    if let Some(e) = &desc.environment {
        match build_environment(e, read)? {
            Environment::Uniform(u) => scene.data.environment = Some(u),
            Environment::Map { map, sun_shadows } => {
                scene.data.env_map = Some(map);
                scene.data.sun_shadows = sun_shadows;
            }
        }
    }
    if scene.data.lights.is_empty()
        && scene.data.environment.is_none()
        && scene.data.env_map.is_none()
    {
        scene.warnings.push(
            "the scene has no [[light]] and no [environment]: lit materials render black (unlit ones and the background still show)".into(),
        );
    }
    scene.warm_tables();
    let outlines = check_outlines(&desc.outlines, &scene.materials.by_name)?;
    let strokes = desc
        .strokes
        .as_ref()
        .map(|s| s.check())
        .transpose()
        .map_err(|e| BuildError::Lines(Box::new(e)))?;

    let SceneBuilder {
        mut data,
        materials,
        inputs,
        warnings,
        ..
    } = scene;
    data.materials = materials.list;
    data.geometry = vec![GeometryPass::main(data.triangles.len())];
    let mut lines = crate::lines::build(
        &mut data,
        &outlines,
        strokes.as_ref(),
        desc.output.tonemap.into(),
        desc.output.exposure,
    );
    let data = SceneData::new(data)?;
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
