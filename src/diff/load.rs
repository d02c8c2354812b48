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
pub fn load(path: &Path) -> Result<DiffImage, String> {
    let name = path.display();
    let reader = image::ImageReader::open(path)
        .map_err(|e| format!("{name}: cannot read: {e}"))?
        .with_guessed_format()
        .map_err(|e| format!("{name}: cannot read: {e}"))?;
    let format = reader
        .format()
        .ok_or_else(|| format!("{name}: not an image format specula reads"))?;
    let img = reader
        .decode()
        .map_err(|e| format!("{name}: cannot decode: {e}"))?;
    let (width, height) = (img.width() as usize, img.height() as usize);
    if width == 0 || height == 0 {
        return Err(format!("{name}: the image is empty ({width}×{height})"));
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
            return Err(format!(
                "{name}: pixel ({x}, {y}) is not finite ({}, {}, {}); a NaN or infinite texel cannot be compared",
                c[0], c[1], c[2]
            ));
        }
        if c.iter().any(|&v| v < 0.0) {
            return Err(format!(
                "{name}: pixel ({x}, {y}) is negative ({}, {}, {}); light cannot be negative",
                c[0], c[1], c[2]
            ));
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
pub fn check_pair(r: &DiffImage, t: &DiffImage) -> Result<(), String> {
    if (r.width, r.height) != (t.width, t.height) {
        return Err(format!(
            "size mismatch: {} is {}×{}, {} is {}×{}",
            r.path.display(),
            r.width,
            r.height,
            t.path.display(),
            t.width,
            t.height
        ));
    }
    if r.channels != t.channels {
        let kind = |c: u8| if c == 1 { "gray" } else { "RGB" };
        return Err(format!(
            "channel mismatch: {} is {}, {} is {}",
            r.path.display(),
            kind(r.channels),
            t.path.display(),
            kind(t.channels)
        ));
    }
    if r.encoding != t.encoding {
        let kind = |e: Encoding| match e {
            Encoding::Display => "a display (sRGB) image",
            Encoding::Linear => "a linear HDR image",
        };
        return Err(format!(
            "{} is {} but {} is {}: compare like with like (render both to .exr, or both to .png)",
            r.path.display(),
            kind(r.encoding),
            t.path.display(),
            kind(t.encoding)
        ));
    }
    Ok(())
}

/// Reads a mask: an image of the same size whose non-zero pixels (in any
/// channel) are the ones compared.
pub fn load_mask(path: &Path, width: usize, height: usize) -> Result<Vec<bool>, String> {
    let m = load(path)?;
    if (m.width, m.height) != (width, height) {
        return Err(format!(
            "{}: the mask is {}×{}, the images {width}×{height}",
            path.display(),
            m.width,
            m.height
        ));
    }
    let mask: Vec<bool> = m.rgb.iter().map(|c| c.iter().any(|&v| v > 0.0)).collect();
    if !mask.iter().any(|&b| b) {
        return Err(format!(
            "{}: the mask selects no pixel (all black)",
            path.display()
        ));
    }
    Ok(mask)
}
