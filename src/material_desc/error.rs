//! What can go wrong turning a material description into a material: a
//! field out of range ([`FieldError`], named as inside the material, e.g.
//! `roughness`; the caller adds where the material came from), or a part
//! the description hands a value to that refused it (textures, the toon
//! ramp, tonal art maps, the lit shader's maps).

use crate::checks::FieldError;
use specula_npr::tam::TamError;
use specula_npr::ParamError;

/// An error building a material from its description.
#[derive(Debug, thiserror::Error)]
pub enum MaterialError {
    /// A field out of range.
    #[error(transparent)]
    Field(#[from] FieldError),
    /// A toon ramp out of range.
    #[error(transparent)]
    Ramp(#[from] ParamError),
    /// A texture a field names that cannot be used (the texture loader's
    /// message).
    #[error("{field}: {source}")]
    Texture {
        field: &'static str,
        source: crate::textures::TextureError,
    },
    /// A `texture_filter` the sampler does not know.
    #[error("texture_filter: {0}")]
    Filter(#[from] specula_raster::texture::FilterParseError),
    /// A tonal art map folder that cannot be read.
    #[error("tam: {0}")]
    Tam(TamError),
    /// The built-in tonal art map could not be made.
    #[error("tam: the built-in map: {0}")]
    BuiltinTam(TamError),
    /// The lit shader refused the material's maps.
    #[error(transparent)]
    Maps(#[from] specula_raster::UnsupportedMap),
}

/// The seam for the callers whose errors are still `String`s
/// (`eval`, glTF materials): `?` turns the error into its message.
impl From<MaterialError> for String {
    fn from(e: MaterialError) -> String {
        e.to_string()
    }
}
