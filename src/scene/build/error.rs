//! What can go wrong building a scene's tables: a variant per rule a table
//! breaks, naming its field, and the seams where a part the tables hand
//! their values to (mesh, texture and environment files, tangents, the
//! memory budget, the line tables, glTF meshes, material descriptions)
//! still reports a message. The messages are the ones users and the tests
//! in `tests/` read.

use crate::checks::FieldError;
use crate::validate::{MAX_FOV_Y_DEG, MAX_WORLD, MIN_FOV_Y_DEG};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// An error building a scene's tables (the loader adds the file's name).
#[derive(Debug, thiserror::Error)]
pub(in crate::scene) enum BuildError {
    /// A field out of range, by the checks shared with `eval`, glTF and
    /// the line tables.
    #[error(transparent)]
    Field(#[from] FieldError),
    /// A file a field names that cannot be read.
    #[error("{field}: cannot read {path}: {source}")]
    Read {
        field: String,
        path: String,
        source: std::io::Error,
    },
    /// `camera.fov_y` outside the accepted range.
    #[error("camera.fov_y: must be in [{MIN_FOV_Y_DEG}, {MAX_FOV_Y_DEG}] degrees, got {0}")]
    FovY(f32),
    /// `camera.near` and `camera.far` not a depth range.
    #[error(
        "camera.near / camera.far: need 0 < near < far (far may be inf), got {near} and {far}"
    )]
    NearFar { near: f32, far: f32 },
    /// A camera whose eye, target and up span no frame.
    #[error(
        "camera: eye, target and up must span a frame (target ≠ eye, up not parallel to the view)"
    )]
    NoFrame,
    /// `output.ssaa` outside 1..=16.
    #[error("output.ssaa: must be in 1..=16, got {0}")]
    Ssaa(u32),
    /// An image side that, supersampled, exceeds the render target.
    #[error("{field}: must be in 1..={limit} (at most {max} after ssaa {ssaa}), got {got}")]
    ImageSide {
        field: &'static str,
        limit: u32,
        max: u32,
        ssaa: u32,
        got: u32,
    },
    /// `output.exposure` not finite.
    #[error("output.exposure: must be finite")]
    Exposure,
    /// `[environment]` with both `uniform` and `map`.
    #[error("environment: give either uniform or map, not both")]
    EnvironmentBoth,
    /// `[environment]` with neither `uniform` nor `map`.
    #[error("environment: give uniform = [r, g, b] or map = \"file.hdr\"")]
    EnvironmentNeither,
    /// `environment.intensity` negative or not finite.
    #[error("environment.intensity must be finite and ≥ 0, got {0}")]
    EnvironmentIntensity(f32),
    /// `environment.rotate` not finite.
    #[error("environment.rotate must be finite, got {0}")]
    EnvironmentRotate(f32),
    /// `environment.ibl_samples` outside its range.
    #[error("environment.ibl_samples must be in 1..=1048576, got {0}")]
    IblSamples(u32),
    /// A mesh with no shape or more than one.
    #[error("{field}: give exactly one of obj, gltf, sphere, plane, cube")]
    Shapes { field: String },
    /// A procedural shape's segment count outside `min..=max`.
    #[error("{field}: must be in {min}..={max}, got {got}")]
    Segments {
        field: String,
        min: u32,
        max: u32,
        got: u32,
    },
    /// A mesh's scale with a component outside [`min`, `max`] in size.
    #[error(
        "{field}.scale: every component must be a number with {min:e} ≤ |s| ≤ {max:e}, got {got}"
    )]
    Scale {
        field: String,
        min: f32,
        max: f32,
        got: Vec3,
    },
    /// A mesh's transform that moves a vertex out of the world.
    #[error("{field}.translate / scale: move vertex {from} to {to}, outside ±{MAX_WORLD:e} (the world's extent)")]
    OutsideWorld { field: String, from: Vec3, to: Vec3 },
    /// A material name found neither in `[materials]` nor the mesh's MTL.
    #[error("{field}.material: no material named {name:?} in [materials] or the mesh's MTL")]
    NoMaterial { field: String, name: String },
    /// A mesh without uvs under a material that samples a texture.
    #[error("{}, and its material {material:?} samples a texture (give the mesh uvs or use an untextured material)", no_uvs(.field, .obj.as_deref()))]
    NoUvs {
        field: String,
        obj: Option<PathBuf>,
        material: String,
    },
    /// An MTL material's `Pr` or `Pm` that is not a number in [0, 1].
    #[error("material {material}: {key} must be a number in [0, 1], got {got:?}")]
    MtlParam {
        material: String,
        key: String,
        got: String,
    },
    /// An MTL material's `Kd` negative or not finite.
    #[error("material {material}: Kd must be finite and ≥ 0, got {got:?}")]
    MtlKd { material: String, got: [f32; 3] },
    /// An MTL material's `map_Kd` that the lit shader cannot use.
    #[error("material {material}: map_Kd: {source}")]
    MtlMap {
        material: String,
        source: specula_raster::UnsupportedMap,
    },
    /// An MTL material's `map_Kd` file that is not a texture.
    #[error("material {material}: map_Kd: {source}")]
    MtlTexture {
        material: String,
        source: crate::textures::TextureError,
    },
    /// An MTL material's error, under the mesh field that named the OBJ.
    #[error("{field}: {source}")]
    Mtl {
        field: String,
        source: Box<BuildError>,
    },
    /// `[posterize]` out of range.
    #[error("posterize.{0}")]
    Posterize(#[from] specula_npr::ParamError),
    /// A material polygon lights cannot light by LTC.
    #[error("{field}: {source}")]
    Ltc {
        field: String,
        source: crate::polygon_light::LtcRefusal,
    },
    /// A material description's error (its message starts with the field
    /// inside the material).
    #[error("materials.{name}.{source}")]
    Material {
        name: String,
        source: Box<crate::material_desc::MaterialError>,
    },
    /// An environment map file refused, under the field that named it.
    #[error("{field}: {source}")]
    EnvMap {
        field: &'static str,
        source: crate::envmap_file::EnvMapError,
    },
    /// MikkTSpace tangents refused for a mesh, under its field.
    #[error("{field}: {source}")]
    Tangents {
        field: String,
        source: crate::tangents::TangentError,
    },
    /// An OBJ file (or an MTL file it names) refused, under its field.
    #[error("{field}: {source}")]
    Obj {
        field: String,
        source: crate::objcheck::ObjError,
    },
    /// An `[[output.label]]` refused (`output.label[0].size: …`).
    #[error("output.label[{index}].{source}")]
    Label {
        index: usize,
        source: Box<crate::label::LabelError>,
    },
    /// Shadow settings refused, under the table that gave them
    /// (`light[1].bias: …`, `environment.sun.cascades: …`).
    #[error("{table}.{source}")]
    Shadows {
        table: String,
        source: specula_raster::shadow::ShadowSettingsError,
    },
    /// `[environment.sun]` under a uniform environment.
    #[error("environment.sun.shadows: a uniform environment has no sun; [environment.sun] needs map = \"file.hdr\"")]
    SunWithoutMap,
    /// `[environment.sun]` with shadows under a map with no sun found in it.
    #[error("environment.sun.shadows: {path} has no sun to shadow (no compact, bright source is taken out of it; docs/accuracy.md, \"Environment maps\")")]
    NoSun { path: String },
    /// The memory budget refused (its message names what asked).
    #[error(transparent)]
    Memory(#[from] crate::memory::OverBudget),
    /// The line tables' checks (`lines.rs`; the message names the table).
    #[error(transparent)]
    Lines(Box<crate::lines::LineTableError>),
    /// A glTF mesh (`gltf_file.rs`; the message names the field).
    #[error(transparent)]
    Gltf(Box<crate::scene::GltfSceneError>),
    /// The finished scene's own check (`SceneData::new`).
    #[error(transparent)]
    Scene(#[from] specula_raster::SceneDataError),
}

/// What a mesh without uvs is, for [`BuildError::NoUvs`].
fn no_uvs(field: &str, obj: Option<&Path>) -> String {
    match obj {
        Some(p) => format!(
            "{field}.obj: {} has no texture coordinates (vt)",
            p.display()
        ),
        None => format!("{field}: the mesh has no texture coordinates"),
    }
}
