//! Writing images: PNG (tone-mapped sRGB), OpenEXR (linear HDR) and AOVs.
//! Encoders produce bytes in memory; [`crate::output_plan`] decides where they
//! go (temporary file + rename, a device written through, or stdout).

use image::{ImageFormat, Rgb32FImage, RgbImage};
use std::path::Path;

/// An image that cannot be encoded, or an id file that cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum ImageFileError {
    /// Pixels that are not `width × height` of the format's channels.
    #[error("image buffer has the wrong size")]
    WrongSize,
    /// The encoder refused (its message).
    #[error("cannot encode {format:?}: {source}")]
    Encode {
        format: ImageFormat,
        source: image::ImageError,
    },
    /// Where the bytes were to go refused them (its message names the
    /// file).
    #[error(transparent)]
    Output(#[from] crate::output_plan::OutputError),
    /// An id file that cannot be read.
    #[error("{}: {source}", .path.display())]
    Read {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    /// A file that does not start with `ID_MAGIC`.
    #[error("{}: not a specula id file", .path.display())]
    NotIds { path: std::path::PathBuf },
    /// An id file whose length is not its header's size.
    #[error("{}: size does not match {width}×{height}", .path.display())]
    IdsSize {
        path: std::path::PathBuf,
        width: u32,
        height: u32,
    },
}

/// The seam for the callers whose errors are still `String`s: `?` turns
/// the error into its message.
impl From<ImageFileError> for String {
    fn from(e: ImageFileError) -> String {
        e.to_string()
    }
}

/// Magic of the raw triangle-id AOV; see `encode_ids`.
pub(crate) const ID_MAGIC: &[u8; 8] = b"SPCLID01";

/// Encodes 8-bit sRGB in `format` (PNG, or whatever the name asked for).
///
/// Two formats leave the `image` crate's defaults for what common readers
/// open: PNM is written as a binary PPM (`P6`), not PAM (`P7`), and TGA
/// without run-length packets (its encoder lets a packet run across
/// scanlines, which the TGA specification advises against and decoders
/// such as Pillow refuse). PNG keeps the crate's fast deflate but filters
/// every row with Paeth rather than picking a filter per row: on rendered
/// frames that is both quicker (one filter tried, not five) and as small
/// or smaller (docs/PERFORMANCE.md, time to image).
pub fn encode_ldr(
    width: u32,
    height: u32,
    rgb8: Vec<u8>,
    format: ImageFormat,
) -> Result<Vec<u8>, ImageFileError> {
    use image::codecs::{png, pnm, tga};
    use image::{ExtendedColorType, ImageEncoder};
    let expected = width as u64 * height as u64 * 3;
    if rgb8.len() as u64 != expected {
        return Err(ImageFileError::WrongSize);
    }
    let fail = |source| ImageFileError::Encode { format, source };
    let mut bytes = Vec::new();
    match format {
        ImageFormat::Png => png::PngEncoder::new_with_quality(
            &mut bytes,
            png::CompressionType::Fast,
            png::FilterType::Paeth,
        )
        .write_image(&rgb8, width, height, ExtendedColorType::Rgb8)
        .map_err(fail)?,
        ImageFormat::Pnm => pnm::PnmEncoder::new(&mut bytes)
            .with_subtype(pnm::PnmSubtype::Pixmap(pnm::SampleEncoding::Binary))
            .write_image(&rgb8, width, height, ExtendedColorType::Rgb8)
            .map_err(fail)?,
        ImageFormat::Tga => tga::TgaEncoder::new(&mut bytes)
            .disable_rle()
            .write_image(&rgb8, width, height, ExtendedColorType::Rgb8)
            .map_err(fail)?,
        _ => {
            let img = RgbImage::from_raw(width, height, rgb8).ok_or(ImageFileError::WrongSize)?;
            img.write_to(&mut std::io::Cursor::new(&mut bytes), format)
                .map_err(fail)?;
        }
    }
    Ok(bytes)
}

/// Encodes linear RGB in an HDR `format` (OpenEXR, Radiance HDR).
pub fn encode_hdr(
    width: u32,
    height: u32,
    rgb: &[[f32; 3]],
    format: ImageFormat,
) -> Result<Vec<u8>, ImageFileError> {
    let flat: Vec<f32> = rgb.iter().flatten().copied().collect();
    let img = Rgb32FImage::from_raw(width, height, flat).ok_or(ImageFileError::WrongSize)?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, format)
        .map_err(|source| ImageFileError::Encode { format, source })?;
    Ok(bytes.into_inner())
}

/// Whether `format` stores linear floating-point colour.
pub fn is_hdr(format: ImageFormat) -> bool {
    matches!(format, ImageFormat::OpenExr | ImageFormat::Hdr)
}

/// Writes `bytes` to `path` as [`crate::output_plan`] resolves it.
fn write_path(path: &Path, bytes: &[u8]) -> Result<(), ImageFileError> {
    let sink =
        crate::output_plan::resolve(path, false).map_err(crate::output_plan::OutputError::from)?;
    crate::output_plan::Output {
        flag: String::new(),
        path: path.to_path_buf(),
        sink,
    }
    .write(bytes)?;
    Ok(())
}

pub fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    rgb8: Vec<u8>,
) -> Result<(), ImageFileError> {
    write_path(path, &encode_ldr(width, height, rgb8, ImageFormat::Png)?)
}

pub fn write_exr(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[[f32; 3]],
) -> Result<(), ImageFileError> {
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

/// Reads an id AOV written as [`encode_ids`] encodes it: (width, height, ids).
pub fn read_ids(path: &Path) -> Result<(u32, u32, Vec<u32>), ImageFileError> {
    let b = std::fs::read(path).map_err(|source| ImageFileError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    if b.len() < 16 || &b[..8] != ID_MAGIC {
        return Err(ImageFileError::NotIds {
            path: path.to_path_buf(),
        });
    }
    let w = u32::from_le_bytes(b[8..12].try_into().expect("4 bytes"));
    let h = u32::from_le_bytes(b[12..16].try_into().expect("4 bytes"));
    if b.len() as u64 != 16 + 4 * w as u64 * h as u64 {
        return Err(ImageFileError::IdsSize {
            path: path.to_path_buf(),
            width: w,
            height: h,
        });
    }
    let ids = b[16..]
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect();
    Ok((w, h, ids))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 5 × 3 image whose every pixel differs, with runs of equal pixels
    /// that cross the end of a row (what a run-length encoder would merge).
    fn picture() -> (u32, u32, Vec<u8>) {
        let (w, h) = (5u32, 3u32);
        let mut px = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let run = x >= 3 || (y > 0 && x < 2);
                let v = if run {
                    [9, 99, 199]
                } else {
                    [x as u8 * 40, y as u8 * 70, 7]
                };
                px.extend_from_slice(&v);
            }
        }
        (w, h, px)
    }

    /// Binary PPM as Netpbm defines it: `P6`, width, height, maxval 255,
    /// one whitespace byte, then RGB rows top first.
    #[test]
    fn ppm_is_a_binary_p6_pixmap() {
        let (w, h, px) = picture();
        let bytes = encode_ldr(w, h, px.clone(), ImageFormat::Pnm).unwrap();
        let header = format!("P6\n{w} {h}\n255\n");
        let text = String::from_utf8_lossy(&bytes[..header.len()]);
        let fields: Vec<&str> = text.split_ascii_whitespace().collect();
        assert_eq!(fields, ["P6", "5", "3", "255"], "header {text:?}");
        assert_eq!(&bytes[bytes.len() - px.len()..], &px[..]);
        assert_eq!(bytes.len(), header.len() + px.len());
    }

    /// TGA as its specification defines it: an 18-byte header, image type 2
    /// (uncompressed true colour, so no packet can cross a scanline), 24
    /// bits per pixel stored B, G, R, rows bottom first unless bit 5 of the
    /// descriptor says top first.
    #[test]
    fn tga_is_uncompressed_true_colour() {
        let (w, h, px) = picture();
        let b = encode_ldr(w, h, px.clone(), ImageFormat::Tga).unwrap();
        let id_len = b[0] as usize;
        assert_eq!(b[1], 0, "no colour map");
        assert_eq!(b[2], 2, "uncompressed true colour");
        assert_eq!(u16::from_le_bytes([b[12], b[13]]) as u32, w);
        assert_eq!(u16::from_le_bytes([b[14], b[15]]) as u32, h);
        assert_eq!(b[16], 24);
        let top_first = b[17] & 0x20 != 0;
        let data = &b[18 + id_len..18 + id_len + px.len()];
        for y in 0..h as usize {
            let row = if top_first { y } else { h as usize - 1 - y };
            for x in 0..w as usize {
                let s = (row * w as usize + x) * 3;
                let d = (y * w as usize + x) * 3;
                assert_eq!(
                    [data[s + 2], data[s + 1], data[s]],
                    px[d..d + 3],
                    "pixel {x},{y}"
                );
            }
        }
    }
}
