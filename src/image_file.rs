//! Writing images: PNG (tone-mapped sRGB), OpenEXR (linear HDR) and AOVs.
//! Encoders produce bytes in memory; [`crate::output_plan`] decides where they
//! go (temporary file + rename, a device written through, or stdout).

use image::{ImageFormat, Rgb32FImage, RgbImage};
use std::path::Path;

/// Magic of the raw triangle-id AOV; see `write_ids`.
pub const ID_MAGIC: &[u8; 8] = b"SPCLID01";

/// Encodes 8-bit sRGB in `format` (PNG, or whatever the name asked for).
pub fn encode_ldr(
    width: u32,
    height: u32,
    rgb8: Vec<u8>,
    format: ImageFormat,
) -> Result<Vec<u8>, String> {
    let img = RgbImage::from_raw(width, height, rgb8).ok_or("image buffer has the wrong size")?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, format)
        .map_err(|e| format!("cannot encode {format:?}: {e}"))?;
    Ok(bytes.into_inner())
}

/// Encodes linear RGB in an HDR `format` (OpenEXR, Radiance HDR).
pub fn encode_hdr(
    width: u32,
    height: u32,
    rgb: &[[f32; 3]],
    format: ImageFormat,
) -> Result<Vec<u8>, String> {
    let flat: Vec<f32> = rgb.iter().flatten().copied().collect();
    let img =
        Rgb32FImage::from_raw(width, height, flat).ok_or("image buffer has the wrong size")?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, format)
        .map_err(|e| format!("cannot encode {format:?}: {e}"))?;
    Ok(bytes.into_inner())
}

/// Whether `format` stores linear floating-point colour.
pub fn is_hdr(format: ImageFormat) -> bool {
    matches!(format, ImageFormat::OpenExr | ImageFormat::Hdr)
}

/// Writes `bytes` to `path` as [`crate::output_plan`] resolves it.
fn write_path(path: &Path, bytes: &[u8]) -> Result<(), String> {
    let sink = crate::output_plan::resolve(path, false)?;
    crate::output_plan::Output {
        flag: String::new(),
        path: path.to_path_buf(),
        sink,
    }
    .write(bytes)
}

pub fn write_png(path: &Path, width: u32, height: u32, rgb8: Vec<u8>) -> Result<(), String> {
    write_path(path, &encode_ldr(width, height, rgb8, ImageFormat::Png)?)
}

pub fn write_exr(path: &Path, width: u32, height: u32, rgb: &[[f32; 3]]) -> Result<(), String> {
    write_path(path, &encode_hdr(width, height, rgb, ImageFormat::OpenExr)?)
}

/// Raw triangle-id AOV, lossless: the 8 bytes `SPCLID01`, width and height as
/// little-endian u32, then width × height little-endian u32 ids, row-major,
/// top row first. 0xFFFFFFFF marks pixels no triangle covers.
pub fn encode_ids(width: u32, height: u32, ids: &[u32]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(16 + ids.len() * 4);
    bytes.extend_from_slice(ID_MAGIC);
    bytes.extend_from_slice(&width.to_le_bytes());
    bytes.extend_from_slice(&height.to_le_bytes());
    for id in ids {
        bytes.extend_from_slice(&id.to_le_bytes());
    }
    bytes
}

pub fn write_ids(path: &Path, width: u32, height: u32, ids: &[u32]) -> Result<(), String> {
    write_path(path, &encode_ids(width, height, ids))
}

/// Reads an id AOV written by [`write_ids`]: (width, height, ids).
pub fn read_ids(path: &Path) -> Result<(u32, u32, Vec<u32>), String> {
    let b = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    if b.len() < 16 || &b[..8] != ID_MAGIC {
        return Err(format!("{}: not a specula id file", path.display()));
    }
    let w = u32::from_le_bytes(b[8..12].try_into().expect("4 bytes"));
    let h = u32::from_le_bytes(b[12..16].try_into().expect("4 bytes"));
    if b.len() as u64 != 16 + 4 * w as u64 * h as u64 {
        return Err(format!("{}: size does not match {w}×{h}", path.display()));
    }
    let ids = b[16..]
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect();
    Ok((w, h, ids))
}
