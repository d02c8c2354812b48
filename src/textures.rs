//! Image files as textures: PNG (or any format the `image` crate reads
//! here) through `image`, colour decoded from sRGB to linear, rows flipped
//! so that v = 0 is the bottom of the picture (the OBJ/MTL convention for
//! `vt`).

use crate::memory;
use specula_raster::maps::ColorMap;
use specula_raster::texture::{Encoding, Filter, Sampler, Texture, Wrap};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// An image file that cannot become a texture; each message starts with
/// the file (or the name the caller gave its bytes).
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    /// The file cannot be read.
    #[error("cannot read {}: {source}", .path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The bytes are not an image this build decodes, or are corrupt.
    #[error("{name}: {source}")]
    Decode {
        name: String,
        source: image::ImageError,
    },
    /// The image's format cannot be guessed from its bytes.
    #[error("{name}: {source}")]
    Sniff {
        name: String,
        source: std::io::Error,
    },
    /// A size the texture cannot hold, or texels it refused.
    #[error("{name}: {source}")]
    Texture {
        name: String,
        source: specula_raster::texture::TextureError,
    },
    /// The decoded image is not the size its header gave.
    #[error("{name}: the image is empty or not {width}×{height}")]
    Empty {
        name: String,
        width: usize,
        height: usize,
    },
    /// The memory budget refused the texture (the message names the file).
    #[error(transparent)]
    Memory(#[from] memory::OverBudget),
}

/// The seam for the callers whose errors are still `String`s: `?` turns
/// the error into its message.
impl From<TextureError> for String {
    fn from(e: TextureError) -> String {
        e.to_string()
    }
}

/// Supplies the files a material names (textures, tonal art maps),
/// relative to the scene's folder.
pub(crate) type ReadFile<'a> = &'a dyn Fn(&Path) -> std::io::Result<Vec<u8>>;

/// Reads an sRGB colour image (alpha dropped) with its mip chain, sampled
/// with repeat wrapping and trilinear filtering.
pub(crate) fn load_color_map(path: &Path, read: ReadFile) -> Result<ColorMap, TextureError> {
    load_map(
        path,
        read,
        Encoding::Srgb,
        Sampler::new(Wrap::Repeat, Filter::Trilinear),
    )
}

/// Reads an image's RGB (alpha dropped) with its mip chain: colour
/// (`Encoding::Srgb`: base colour, emission) or data (`Encoding::Linear`:
/// metallic-roughness, normal and occlusion maps, whose texels are not
/// colours).
pub(crate) fn load_map(
    path: &Path,
    read: ReadFile,
    encoding: Encoding,
    sampler: Sampler,
) -> Result<ColorMap, TextureError> {
    let bytes = read(path).map_err(|source| TextureError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    decode_map(&path.display().to_string(), &bytes, encoding, sampler)
}

/// Peak bytes per texel while an image becomes a texture: the decoded
/// image (up to 8 bytes for 16-bit RGBA), its 8-bit RGB copy and the
/// flipped rows (3 + 3), the f32 texels with their mip chain (16) and the
/// texture they are assembled into (16), rounded up.
pub(crate) const TEXEL_BYTES: u64 = 48;

/// [`TEXEL_BYTES`] for RGBA textures: 8 + 4 + 4 + 21⅓ + 21⅓, rounded up.
pub(crate) const TEXEL_BYTES_RGBA: u64 = 64;

/// An image's width and height from its header, without decoding it.
pub(crate) fn image_size(name: &str, bytes: &[u8]) -> Result<(u32, u32), TextureError> {
    image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|source| TextureError::Sniff {
            name: name.to_string(),
            source,
        })?
        .into_dimensions()
        .map_err(|source| TextureError::Decode {
            name: name.to_string(),
            source,
        })
}

/// [`load_map`] from an image file's bytes; `name` says where they came
/// from in messages. The size in the image's header is counted against
/// the memory budget before anything is decoded.
pub(crate) fn decode_map(
    name: &str,
    bytes: &[u8],
    encoding: Encoding,
    sampler: Sampler,
) -> Result<ColorMap, TextureError> {
    decode_map_channels(name, bytes, encoding, sampler, 3)
}

/// [`decode_map`] keeping `channels` of RGBA: 3 (alpha dropped) or 4
/// (alpha kept as channel 3, linear whatever `encoding` says: glTF's
/// base colour alpha is not sRGB-encoded; an image without alpha gets 1).
pub(crate) fn decode_map_channels(
    name: &str,
    bytes: &[u8],
    encoding: Encoding,
    sampler: Sampler,
    channels: usize,
) -> Result<ColorMap, TextureError> {
    let channels = channels.clamp(3, 4);
    let (w, h) = image_size(name, bytes)?;
    specula_raster::texture::check_mip_chain_size(w as usize, h as usize, channels).map_err(
        |source| TextureError::Texture {
            name: name.to_string(),
            source,
        },
    )?;
    let per_texel = if channels == 4 {
        TEXEL_BYTES_RGBA
    } else {
        TEXEL_BYTES
    };
    memory::reserve(
        &format!("{name} ({w}×{h})"),
        (w as u64 * h as u64).saturating_mul(per_texel),
    )?;
    let img = image::load_from_memory(bytes).map_err(|source| TextureError::Decode {
        name: name.to_string(),
        source,
    })?;
    let raw = if channels == 4 {
        img.to_rgba8().into_raw()
    } else {
        img.to_rgb8().into_raw()
    };
    let (w, h) = (w as usize, h as usize);
    if w == 0 || h == 0 || raw.len() != w * h * channels {
        return Err(TextureError::Empty {
            name: name.to_string(),
            width: w,
            height: h,
        });
    }
    let mut flipped = Vec::with_capacity(raw.len());
    for row in raw.chunks_exact(w * channels).rev() {
        flipped.extend_from_slice(row);
    }
    let texture = Texture::from_u8(w, h, channels, &flipped, encoding).map_err(|source| {
        TextureError::Texture {
            name: name.to_string(),
            source,
        }
    })?;
    Ok(ColorMap {
        texture: Arc::new(texture),
        sampler,
        transform: None,
    })
}
