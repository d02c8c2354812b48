//! The surface a band of rows is drawn on: a tiny-skia mask, whose alpha
//! is the strokes' coverage.

use super::Draw;
use std::ops::Range;
use tiny_skia::{FillRule, IntSize, Mask, Transform};

/// Fills the outlines of `draws`, in order, on rows `rows` of a
/// `w`-pixel-wide image held in `bytes` (those rows only, a byte a pixel,
/// all zero on entry: transparent), anti-aliased with the winding rule:
/// each outline moved up by the band's first row, so the surface is the
/// image's rows `rows` and tiny-skia clips what lies outside them.
/// Returns the bytes.
pub(in crate::overlay) fn draw_band<'d>(
    bytes: Vec<u8>,
    w: usize,
    rows: Range<usize>,
    draws: impl IntoIterator<Item = &'d Draw>,
) -> Vec<u8> {
    debug_assert_eq!(bytes.len(), w * rows.len());
    let Some(size) = IntSize::from_wh(w as u32, rows.len() as u32) else {
        return bytes;
    };
    let Some(mut mask) = Mask::from_vec(bytes, size) else {
        return Vec::new();
    };
    let up = Transform::from_translate(0.0, -(rows.start as f32));
    for d in draws {
        mask.fill_path(&d.outline, FillRule::Winding, true, up);
    }
    mask.take()
}
