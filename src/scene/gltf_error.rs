//! What can go wrong placing a glTF file in a scene, or rendering one on
//! its own: reading it, the glTF loader's errors under the field and file
//! that named it, a material or uv set a primitive lacks, its cameras,
//! and the scene checks it shares with TOML scenes (their message).

use crate::gltf::GltfError;
use crate::memory::OverBudget;
use std::path::PathBuf;

/// An error loading a glTF file as a scene or as a `[[mesh]]`.
#[derive(Debug, thiserror::Error)]
pub enum GltfSceneError {
    /// A glTF file a field names that cannot be read.
    #[error("{what}: cannot read {}: {source}", .path.display())]
    Read {
        what: String,
        path: PathBuf,
        source: std::io::Error,
    },
    /// The glTF rendered on its own cannot be read.
    #[error("cannot read: {0}")]
    ReadScene(std::io::Error),
    /// The memory budget refused (the message names what asked).
    #[error(transparent)]
    Memory(#[from] OverBudget),
    /// The glTF loader's error in a file a field names.
    #[error("{what}: {}: {source}", .path.display())]
    Gltf {
        what: String,
        path: PathBuf,
        source: GltfError,
    },
    /// The glTF loader's error in the file rendered on its own.
    #[error(transparent)]
    File(#[from] GltfError),
    /// `material = "name"` with no such `[materials]` entry.
    #[error("{what}: material {name:?}: no such entry in [materials]")]
    NoMaterial { what: String, name: String },
    /// A primitive without the uv set its material's texture reads.
    #[error("{what}: {}: {at}: the material samples a texture through TEXCOORD_{set}, which the primitive does not have", .path.display())]
    NoUvSet {
        what: String,
        path: PathBuf,
        at: String,
        set: u32,
    },
    /// MikkTSpace tangents refused for a primitive.
    #[error("{what}: {}: {at}: {source}", .path.display())]
    Tangents {
        what: String,
        path: PathBuf,
        at: String,
        source: crate::tangents::TangentError,
    },
    /// An orthographic camera without a positive view height.
    #[error("{at}: orthographic.ymag must be > 0, got {ymag}")]
    OrthographicYmag { at: String, ymag: f32 },
    /// A camera the scene's camera checks refused (their message).
    #[error("{at}: {message}")]
    Camera { at: String, message: String },
    /// No camera, and the scene too large for a framing camera to stay in
    /// the world.
    #[error("no camera in the file, and its bounding sphere (radius {radius:e}) is too large to frame: {source}")]
    TooLargeToFrame {
        radius: f32,
        source: crate::checks::FieldError,
    },
    /// `--camera N` past the file's cameras.
    #[error("--camera {index}: the file has {count} cameras{}", camera_range(*.count))]
    NoSuchCamera { index: usize, count: usize },
    /// A check shared with TOML scenes (placement, tangents), as its
    /// message.
    #[error("{0}")]
    Scene(String),
    /// The finished scene's own check (`SceneData::new`).
    #[error(transparent)]
    Invalid(#[from] specula_raster::SceneDataError),
}

/// ` (0 to n-1)` after a count of cameras, nothing for none.
fn camera_range(count: usize) -> String {
    if count == 0 {
        String::new()
    } else {
        format!(" (0 to {})", count - 1)
    }
}

/// The seam for the callers whose errors are still `String`s: `?` turns
/// the error into its message.
impl From<GltfSceneError> for String {
    fn from(e: GltfSceneError) -> String {
        e.to_string()
    }
}
