//! Reading the two images `specula diff` compares, and the checks that
//! they can be compared: every format the `image` crate reads here (PNG 8
//! and 16-bit, JPEG, EXR, Radiance HDR, …), gray or colour, with or
//! without alpha (alpha is not compared).

use std::path::{Path, PathBuf};

/// How the stored values relate to light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Encoding {
    /// sRGB-encoded display values in [0, 1] (PNG, JPEG, …): LDR-FLIP.
    Display,
    /// Linear scene-referred values (OpenEXR, Radiance HDR): HDR-FLIP.
    Linear,
}

/// An image that cannot be read or compared; messages name the file.
#[derive(Debug, thiserror::Error)]
pub enum DiffImageError {
    /// The file cannot be opened or read.
    #[error("{}: cannot read: {source}", .path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// Bytes of no format this build reads.
    #[error("{}: not an image format specula reads", .path.display())]
    Format { path: PathBuf },
    /// A file its decoder refused.
    #[error("{}: cannot decode: {source}", .path.display())]
    Decode {
        path: PathBuf,
        source: image::ImageError,
    },
    /// An image without pixels.
    #[error("{}: the image is empty ({width}×{height})", .path.display())]
    Empty {
        path: PathBuf,
        width: usize,
        height: usize,
    },
    /// A NaN or infinite pixel.
    #[error("{}: pixel ({x}, {y}) is not finite ({}, {}, {}); a NaN or infinite texel cannot be compared", .path.display(), .rgb[0], .rgb[1], .rgb[2])]
    NotFinite {
        path: PathBuf,
        x: usize,
        y: usize,
        rgb: [f32; 3],
    },
    /// A negative pixel.
    #[error("{}: pixel ({x}, {y}) is negative ({}, {}, {}); light cannot be negative", .path.display(), .rgb[0], .rgb[1], .rgb[2])]
    Negative {
        path: PathBuf,
        x: usize,
        y: usize,
        rgb: [f32; 3],
    },
    /// Two images of different sizes.
    #[error("size mismatch: {} is {}×{}, {} is {}×{}", .reference.display(), .reference_size.0, .reference_size.1, .test.display(), .test_size.0, .test_size.1)]
    Size {
        reference: PathBuf,
        reference_size: (usize, usize),
        test: PathBuf,
        test_size: (usize, usize),
    },
    /// A gray image and an RGB one.
    #[error("channel mismatch: {} is {}, {} is {}", .reference.display(), channel_kind(*.reference_channels), .test.display(), channel_kind(*.test_channels))]
    Channels {
        reference: PathBuf,
        reference_channels: u8,
        test: PathBuf,
        test_channels: u8,
    },
    /// A display image and a linear one.
    #[error("{} is {} but {} is {}: compare like with like (render both to .exr, or both to .png)", .reference.display(), encoding_kind(*.reference_encoding), .test.display(), encoding_kind(*.test_encoding))]
    Encodings {
        reference: PathBuf,
        reference_encoding: Encoding,
        test: PathBuf,
        test_encoding: Encoding,
    },
    /// A mask of another size than the images.
    #[error("{}: the mask is {}×{}, the images {}×{}", .path.display(), .mask.0, .mask.1, .images.0, .images.1)]
    MaskSize {
        path: PathBuf,
        mask: (usize, usize),
        images: (usize, usize),
    },
    /// A mask with no pixel set.
    #[error("{}: the mask selects no pixel (all black)", .path.display())]
    EmptyMask { path: PathBuf },
}

/// The seam for the callers whose errors are still `String`s: `?` turns
/// the error into its message.
impl From<DiffImageError> for String {
    fn from(e: DiffImageError) -> String {
        e.to_string()
    }
}

fn channel_kind(c: u8) -> &'static str {
    if c == 1 {
        "gray"
    } else {
        "RGB"
    }
}

fn encoding_kind(e: Encoding) -> &'static str {
    match e {
        Encoding::Display => "a display (sRGB) image",
        Encoding::Linear => "a linear HDR image",
    }
}

/// An image as compared: RGB per pixel, row-major, top row first.
#[derive(Clone, Debug)]
pub struct DiffImage {
    pub path: PathBuf,
    pub width: usize,
    pub height: usize,
    /// Colour channels in the file (1 gray, 3 RGB), alpha not counted.
    pub channels: u8,
    pub alpha: bool,
    pub encoding: Encoding,
    /// Display images: the encoded values / (2^bits − 1); linear images:
    /// the stored values. Gray is repeated in all three channels.
    pub rgb: Vec<[f32; 3]>,
}

/// Reads an image; errors name the file.
pub fn load(path: &Path) -> Result<DiffImage, DiffImageError> {
    let read = |source| DiffImageError::Read {
        path: path.to_path_buf(),
        source,
    };
    let reader = image::ImageReader::open(path)
        .map_err(read)?
        .with_guessed_format()
        .map_err(read)?;
    let format = reader.format().ok_or_else(|| DiffImageError::Format {
        path: path.to_path_buf(),
    })?;
    let img = reader.decode().map_err(|source| DiffImageError::Decode {
        path: path.to_path_buf(),
        source,
    })?;
    let (width, height) = (img.width() as usize, img.height() as usize);
    if width == 0 || height == 0 {
        return Err(DiffImageError::Empty {
            path: path.to_path_buf(),
            width,
            height,
        });
    }
    let color = img.color();
    let alpha = color.has_alpha();
    let channels = color.channel_count() - alpha as u8;
    let encoding = if crate::image_file::is_hdr(format) {
        Encoding::Linear
    } else {
        Encoding::Display
    };
    let rgb: Vec<[f32; 3]> = img
        .to_rgb32f()
        .pixels()
        .map(|p| [p.0[0], p.0[1], p.0[2]])
        .collect();
    for (i, c) in rgb.iter().enumerate() {
        let (x, y) = (i % width, i / width);
        if c.iter().any(|v| !v.is_finite()) {
            return Err(DiffImageError::NotFinite {
                path: path.to_path_buf(),
                x,
                y,
                rgb: *c,
            });
        }
        if c.iter().any(|&v| v < 0.0) {
            return Err(DiffImageError::Negative {
                path: path.to_path_buf(),
                x,
                y,
                rgb: *c,
            });
        }
    }
    Ok(DiffImage {
        path: path.to_path_buf(),
        width,
        height,
        channels,
        alpha,
        encoding,
        rgb,
    })
}

/// Checks that two images can be compared pixel by pixel.
pub(crate) fn check_pair(r: &DiffImage, t: &DiffImage) -> Result<(), DiffImageError> {
    if (r.width, r.height) != (t.width, t.height) {
        return Err(DiffImageError::Size {
            reference: r.path.clone(),
            reference_size: (r.width, r.height),
            test: t.path.clone(),
            test_size: (t.width, t.height),
        });
    }
    if r.channels != t.channels {
        return Err(DiffImageError::Channels {
            reference: r.path.clone(),
            reference_channels: r.channels,
            test: t.path.clone(),
            test_channels: t.channels,
        });
    }
    if r.encoding != t.encoding {
        return Err(DiffImageError::Encodings {
            reference: r.path.clone(),
            reference_encoding: r.encoding,
            test: t.path.clone(),
            test_encoding: t.encoding,
        });
    }
    Ok(())
}

/// Reads a mask: an image of the same size whose non-zero pixels (in any
/// channel) are the ones compared.
pub(crate) fn load_mask(
    path: &Path,
    width: usize,
    height: usize,
) -> Result<Vec<bool>, DiffImageError> {
    let m = load(path)?;
    if (m.width, m.height) != (width, height) {
        return Err(DiffImageError::MaskSize {
            path: path.to_path_buf(),
            mask: (m.width, m.height),
            images: (width, height),
        });
    }
    let mask: Vec<bool> = m.rgb.iter().map(|c| c.iter().any(|&v| v > 0.0)).collect();
    if !mask.iter().any(|&b| b) {
        return Err(DiffImageError::EmptyMask {
            path: path.to_path_buf(),
        });
    }
    Ok(mask)
}
