//! What can go wrong reading a glTF file: the container (GLB), the JSON
//! (with its path), an extension the file requires, the `gltf` crate's
//! validation, files and data URIs its buffers and images name, and every
//! rule of the data broken at a JSON path
//! (`meshes[0].primitives[1].attributes.POSITION`). Messages name the JSON
//! path, not the file (the caller adds it); they are the ones users and
//! the tests in `tests/` read.

use crate::checks::FieldError;
use crate::memory::OverBudget;
use crate::textures::TextureError;
use std::path::PathBuf;

/// An error reading a glTF file or making its materials.
#[derive(Debug, thiserror::Error)]
pub enum GltfError {
    /// A GLB container that is not one (what is wrong with it).
    #[error("GLB: {0}")]
    Glb(String),
    /// JSON that does not parse, where no path is known.
    #[error("JSON: {0}")]
    Syntax(serde_json::Error),
    /// JSON that does not parse as glTF at a path (syntax or type).
    #[error("{at}: {source}")]
    Json {
        at: String,
        source: serde_json::Error,
    },
    /// `extensionsRequired[index]` names an extension this loader does
    /// not read.
    #[error(
        "extensionsRequired[{index}]: {name:?} is required by the file and not supported here"
    )]
    Extension { index: usize, name: String },
    /// The `gltf` crate's validation refused a value at a path.
    #[error("{at}: {what}")]
    Invalid { at: String, what: &'static str },
    /// A file a URI names that cannot be read.
    #[error("{at}: cannot read {}: {source}", .path.display())]
    Read {
        at: String,
        path: PathBuf,
        source: std::io::Error,
    },
    /// A data URI that carries no binary data.
    #[error("{at}: {source}")]
    DataUri { at: String, source: DataUriError },
    /// A value out of range, by the checks shared with scene files.
    #[error(transparent)]
    Field(Box<FieldError>),
    /// The memory budget refused (the message names what asked).
    #[error(transparent)]
    Memory(#[from] OverBudget),
    /// An image that cannot become a texture (named by `images[i]`).
    #[error(transparent)]
    Texture(Box<TextureError>),
    /// A material's texture whose image failed, under the texture's path.
    #[error("{at}: {source}")]
    Image { at: String, source: Box<GltfError> },
    /// A material whose parameters the renderer's material description
    /// refused (the field inside the material).
    #[error("{at}: {source}")]
    Material { at: String, source: Box<FieldError> },
    /// A rule of the data broken at a JSON path (what the rule says).
    #[error("{at}: {message}")]
    At { at: String, message: String },
}

impl GltfError {
    /// A rule broken at the JSON path `at`.
    pub(crate) fn at(at: &str, message: impl Into<String>) -> GltfError {
        GltfError::At {
            at: at.to_string(),
            message: message.into(),
        }
    }
}

impl From<FieldError> for GltfError {
    fn from(e: FieldError) -> GltfError {
        GltfError::Field(Box::new(e))
    }
}

impl From<TextureError> for GltfError {
    fn from(e: TextureError) -> GltfError {
        GltfError::Texture(Box::new(e))
    }
}

/// The seam for the callers whose errors are still `String`s: `?` turns
/// the error into its message.
impl From<GltfError> for String {
    fn from(e: GltfError) -> String {
        e.to_string()
    }
}

/// A `data:` URI that carries no binary data.
#[derive(Debug, thiserror::Error)]
pub enum DataUriError {
    /// No `,` between the media type and the payload.
    #[error("a data URI without a ',' before its payload")]
    NoComma,
    /// A payload that is not base64 (the head, shortened).
    #[error("data URI {0:?} is not base64 (\";base64,\" expected)")]
    NotBase64(String),
    /// A base64 payload that does not decode.
    #[error("data URI: invalid base64: {0}")]
    Base64(base64::DecodeError),
}
