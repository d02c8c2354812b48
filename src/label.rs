//! Text labels written on the tone-mapped image (`[[output.label]]` in a
//! scene file): parameter sweeps name their rows and values on the picture.
//!
//! Glyphs are rasterized by `ab_glyph` from DejaVu Sans Mono, bundled into
//! the binary (fixtures/fonts/, with its licence), so labels look the same
//! on every machine. Coverage is blended over the 8-bit sRGB image (text is
//! an overlay, not scene radiance: it does not go through tone mapping and
//! is not in EXR output).

use ab_glyph::{Font, FontRef, PxScale, ScaleFont};
use serde::Deserialize;

/// The bundled font.
const FONT: &[u8] = include_bytes!("../fixtures/fonts/DejaVuSansMono.ttf");

fn default_size() -> f32 {
    24.0
}

fn white() -> [f32; 3] {
    [1.0; 3]
}

/// One line of text: `at` is its top-left corner in pixels of the scene's
/// own output size (scaled with `--width`/`--height`), `size` the line
/// height in pixels, `color` sRGB in [0, 1].
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LabelDesc {
    pub text: String,
    pub at: [f32; 2],
    #[serde(default = "default_size")]
    pub size: f32,
    #[serde(default = "white")]
    pub color: [f32; 3],
}

/// Longest label text, in characters.
const MAX_CHARS: usize = 1000;
/// Largest line height, in pixels.
const MAX_SIZE: f32 = 1000.0;

/// A label's field refused; the message names the field inside the label
/// (the caller adds which label of which file).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub(crate) enum LabelError {
    /// `text` longer than `MAX_CHARS` characters.
    #[error("text: longer than {MAX_CHARS} characters")]
    TooLong,
    /// `at` with a coordinate that is not finite.
    #[error("at: must be finite, got {0:?}")]
    At([f32; 2]),
    /// `size` outside (0, `MAX_SIZE`].
    #[error("size: must be in (0, {MAX_SIZE}] pixels, got {0}")]
    Size(f32),
    /// `color` outside [0, 1].
    #[error(transparent)]
    Color(#[from] crate::checks::FieldError),
}

impl LabelDesc {
    /// Checks the fields; the error names the field (the caller adds which
    /// label of which file).
    pub(crate) fn validate(&self) -> Result<(), LabelError> {
        if self.text.chars().count() > MAX_CHARS {
            return Err(LabelError::TooLong);
        }
        if !self.at.iter().all(|v| v.is_finite()) {
            return Err(LabelError::At(self.at));
        }
        if !(self.size.is_finite() && self.size > 0.0 && self.size <= MAX_SIZE) {
            return Err(LabelError::Size(self.size));
        }
        Ok(crate::checks::display_color("color", self.color)?)
    }
}

/// Width in pixels of `text` set at line height `size` (advances and
/// kerning, as [`draw_labels`] places the glyphs): for centring or
/// right-aligning a label.
pub fn text_width(text: &str, size: f32) -> f32 {
    let font = FontRef::try_from_slice(FONT).expect("the bundled font parses");
    let scaled = font.as_scaled(PxScale::from(size));
    let mut prev = None;
    let mut w = 0.0;
    for ch in text.chars() {
        let id = font.glyph_id(ch);
        if let Some(p) = prev {
            w += scaled.kern(p, id);
        }
        w += scaled.h_advance(id);
        prev = Some(id);
    }
    w
}

/// Draws `labels` onto the row-major RGB8 image `rgb8` (width × height),
/// with positions and sizes multiplied by `scale` (output size over the
/// scene's). Labels are validated. A line is never taller than the
/// image's shorter side (a glyph's coverage buffer then stays smaller than
/// the image), and glyphs wholly outside the image are not rasterized.
pub fn draw_labels(rgb8: &mut [u8], width: u32, height: u32, labels: &[LabelDesc], scale: f32) {
    if labels.is_empty() || rgb8.len() != width as usize * height as usize * 3 {
        return;
    }
    let font = FontRef::try_from_slice(FONT).expect("the bundled font parses");
    let tallest = width.min(height) as f32;
    for label in labels {
        let px = PxScale::from((label.size * scale).min(tallest));
        let scaled = font.as_scaled(px);
        let color = label.color.map(|c| c * 255.0);
        let mut x = label.at[0] * scale;
        let baseline = label.at[1] * scale + scaled.ascent();
        let mut prev = None;
        for ch in label.text.chars() {
            let id = font.glyph_id(ch);
            if let Some(p) = prev {
                x += scaled.kern(p, id);
            }
            let glyph = id.with_scale_and_position(px, ab_glyph::point(x, baseline));
            x += scaled.h_advance(id);
            prev = Some(id);
            let Some(outlined) = font.outline_glyph(glyph) else {
                continue; // spaces have no outline
            };
            let b = outlined.px_bounds();
            if b.max.x < 0.0 || b.max.y < 0.0 || b.min.x >= width as f32 || b.min.y >= height as f32
            {
                continue;
            }
            outlined.draw(|gx, gy, coverage| {
                let (ix, iy) = (b.min.x as i64 + gx as i64, b.min.y as i64 + gy as i64);
                if ix < 0 || iy < 0 || ix >= width as i64 || iy >= height as i64 {
                    return;
                }
                let k = (iy as usize * width as usize + ix as usize) * 3;
                let a = coverage.clamp(0.0, 1.0);
                for c in 0..3 {
                    let v = rgb8[k + c] as f32;
                    rgb8[k + c] = (v + (color[c] - v) * a).round() as u8;
                }
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_covers_pixels_inside_its_box_only() {
        let (w, h) = (200u32, 60u32);
        let mut img = vec![0u8; (w * h * 3) as usize];
        let label = LabelDesc {
            text: "metallic 0.25".into(),
            at: [10.0, 10.0],
            size: 20.0,
            color: [1.0, 0.5, 0.0],
        };
        label.validate().unwrap();
        draw_labels(&mut img, w, h, &[label], 1.0);
        let lit: Vec<(u32, u32)> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| img[((y * w + x) * 3) as usize] > 0)
            .collect();
        // 13 monospace glyphs of advance ≈ 0.6 em: about 156 px wide.
        assert!(lit.len() > 200, "only {} pixels drawn", lit.len());
        for &(x, y) in &lit {
            assert!(
                (10..=175).contains(&x) && (10..=32).contains(&y),
                "pixel ({x}, {y})"
            );
            let k = ((y * w + x) * 3) as usize;
            // Orange: green is half of red, blue stays 0.
            assert_eq!(img[k + 2], 0);
            assert!((img[k + 1] as i32 - img[k] as i32 / 2).abs() <= 1);
        }
    }

    #[test]
    fn bad_fields_are_named() {
        let ok = LabelDesc {
            text: "x".into(),
            at: [0.0, 0.0],
            size: 10.0,
            color: [1.0; 3],
        };
        let e = LabelDesc {
            size: f32::NAN,
            ..ok.clone()
        }
        .validate()
        .unwrap_err();
        assert!(matches!(e, LabelError::Size(_)), "{e}");
        assert!(e.to_string().starts_with("size"), "{e}");
        let e = LabelDesc {
            at: [f32::INFINITY, 0.0],
            ..ok.clone()
        }
        .validate()
        .unwrap_err();
        assert!(matches!(e, LabelError::At(_)), "{e}");
        assert!(e.to_string().starts_with("at"), "{e}");
        let e = LabelDesc {
            color: [2.0, 0.0, 0.0],
            ..ok
        }
        .validate()
        .unwrap_err();
        assert!(matches!(e, LabelError::Color(_)), "{e}");
        assert!(e.to_string().starts_with("color"), "{e}");
    }

    /// A label scaled far beyond the image (a 16 × 16 scene's size 1000 at
    /// 2048 × 2048, or 16384 × 16) is drawn at the image's shorter side at
    /// most, so it costs what the image does, not terabytes; one far off
    /// the image draws nothing.
    #[test]
    fn huge_and_distant_labels_stay_within_the_image() {
        let label = |at: [f32; 2]| LabelDesc {
            text: "WWWW".into(),
            at,
            size: 1000.0,
            color: [1.0; 3],
        };
        for (w, h, scale) in [(256u32, 256u32, 128.0f32), (1024, 16, 64.0)] {
            let mut img = vec![0u8; (w * h * 3) as usize];
            draw_labels(&mut img, w, h, &[label([0.0, 0.0])], scale);
            assert!(img.iter().any(|&v| v > 0), "{w}×{h}: nothing drawn");
            let mut far = vec![0u8; (w * h * 3) as usize];
            draw_labels(&mut far, w, h, &[label([1e6, 1e6])], scale);
            assert!(far.iter().all(|&v| v == 0), "{w}×{h}: a distant label drew");
        }
    }
}
