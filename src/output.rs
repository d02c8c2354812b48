//! Writing images: PNG (tone-mapped sRGB), OpenEXR (linear HDR) and AOVs.
//! Every file is written to a temporary name in the same folder and renamed
//! into place, so a failed run never leaves a half-written image.

use image::{ImageFormat, Rgb32FImage, RgbImage};
use std::path::{Path, PathBuf};

/// Magic of the raw triangle-id AOV; see `write_ids`.
pub const ID_MAGIC: &[u8; 8] = b"SPCLID01";

fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Writes through `write` to a temporary file, then renames it to `path`.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), String> {
    if path.file_name().is_none() {
        return Err(format!("{}: not a file path", path.display()));
    }
    let tmp = temp_path(path);
    let result = write(&tmp).and_then(|()| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

pub fn write_png(path: &Path, width: u32, height: u32, rgb8: Vec<u8>) -> Result<(), String> {
    let img = RgbImage::from_raw(width, height, rgb8).ok_or("image buffer has the wrong size")?;
    write_atomic(path, |tmp| {
        img.save_with_format(tmp, ImageFormat::Png)
            .map_err(|e| e.to_string())
    })
}

pub fn write_exr(path: &Path, width: u32, height: u32, rgb: &[[f32; 3]]) -> Result<(), String> {
    let flat: Vec<f32> = rgb.iter().flatten().copied().collect();
    let img =
        Rgb32FImage::from_raw(width, height, flat).ok_or("image buffer has the wrong size")?;
    write_atomic(path, |tmp| {
        img.save_with_format(tmp, ImageFormat::OpenExr)
            .map_err(|e| e.to_string())
    })
}

/// Raw triangle-id AOV, lossless: the 8 bytes `SPCLID01`, width and height as
/// little-endian u32, then width × height little-endian u32 ids, row-major,
/// top row first. 0xFFFFFFFF marks pixels no triangle covers.
pub fn write_ids(path: &Path, width: u32, height: u32, ids: &[u32]) -> Result<(), String> {
    let mut bytes = Vec::with_capacity(16 + ids.len() * 4);
    bytes.extend_from_slice(ID_MAGIC);
    bytes.extend_from_slice(&width.to_le_bytes());
    bytes.extend_from_slice(&height.to_le_bytes());
    for id in ids {
        bytes.extend_from_slice(&id.to_le_bytes());
    }
    write_atomic(path, |tmp| {
        std::fs::write(tmp, &bytes).map_err(|e| e.to_string())
    })
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
