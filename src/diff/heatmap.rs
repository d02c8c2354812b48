//! The heat map `specula diff --heatmap` writes: a caption row, then the
//! reference, the test and the FLIP error in magma side by side, then the
//! colour bar (0 to 1) with its ticks. Images narrower than
//! [`MIN_PANEL`] pixels are enlarged by a whole factor (nearest pixel) so
//! that the captions fit.

use super::flip::{linear_to_srgb, ToneCurve};
use super::load::Encoding;
use super::magma::MAGMA;
use crate::label::{draw_labels, LabelDesc};

const GAP: usize = 4;
const CAPTION: usize = 20;
const BAR: usize = 12;
const TICKS: usize = 22;
const TEXT: f32 = 14.0;
/// Narrowest panel drawn, in pixels.
pub(crate) const MIN_PANEL: usize = 192;

/// The magma colour of an error in [0, 1] (the nearest of 256 entries).
pub(crate) fn magma(e: f32) -> [u8; 3] {
    MAGMA[((e.clamp(0.0, 1.0) * 255.0 + 0.5) as usize).min(255)]
}

/// One image as shown: display values as stored, linear ones tone mapped
/// (ACES, exposure 0) and sRGB encoded.
fn shown(rgb: &[[f32; 3]], encoding: Encoding) -> Vec<[u8; 3]> {
    let to8 = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    rgb.iter()
        .map(|&c| match encoding {
            Encoding::Display => c.map(to8),
            Encoding::Linear => ToneCurve::Aces.apply(c).map(|v| to8(linear_to_srgb(v))),
        })
        .collect()
}

/// The heat map as RGB8 (width, height, bytes).
pub(crate) fn render(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    flip: &[f32],
    width: usize,
    height: usize,
    encoding: Encoding,
    flip_label: &str,
) -> (u32, u32, Vec<u8>) {
    let k = MIN_PANEL.div_ceil(width.max(1)).max(1);
    let (pw, ph) = (width * k, height * k);
    let out_w = 3 * pw + 2 * GAP;
    let out_h = CAPTION + ph + GAP + BAR + TICKS;
    let mut img = vec![32u8; out_w * out_h * 3];
    let mut put = |x: usize, y: usize, c: [u8; 3]| {
        let i = (y * out_w + x) * 3;
        img[i..i + 3].copy_from_slice(&c);
    };
    let panels = [
        shown(reference, encoding),
        shown(test, encoding),
        flip.iter().map(|&e| magma(e)).collect(),
    ];
    for (p, px) in panels.iter().enumerate() {
        let x0 = p * (pw + GAP);
        for y in 0..ph {
            for x in 0..pw {
                put(x0 + x, CAPTION + y, px[(y / k) * width + x / k]);
            }
        }
    }
    let bar_y = CAPTION + ph + GAP;
    for x in 0..out_w {
        let c = magma(x as f32 / (out_w - 1).max(1) as f32);
        for y in 0..BAR {
            put(x, bar_y + y, c);
        }
    }
    let label = |text: String, x: f32, y: f32| LabelDesc {
        text,
        at: [x, y],
        size: TEXT,
        color: [0.9, 0.9, 0.9],
    };
    let mut labels = vec![
        label("reference".into(), 2.0, 2.0),
        label("test".into(), (pw + GAP) as f32 + 2.0, 2.0),
        label(flip_label.into(), (2 * (pw + GAP)) as f32 + 2.0, 2.0),
    ];
    for k in 0..=4 {
        let v = k as f32 / 4.0;
        let text = format!("{v:.2}");
        let tw = crate::label::text_width(&text, TEXT);
        let x = (v * (out_w - 1) as f32 - tw * v).max(0.0);
        labels.push(label(text, x, (bar_y + BAR + 3) as f32));
    }
    draw_labels(&mut img, out_w as u32, out_h as u32, &labels, 1.0);
    (out_w as u32, out_h as u32, img)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn magma_runs_dark_to_bright() {
        let lum = |c: [u8; 3]| c.iter().map(|&v| v as u32).sum::<u32>();
        assert!(lum(magma(0.0)) < 20);
        assert!(lum(magma(1.0)) > 600);
        assert!(lum(magma(0.5)) > lum(magma(0.25)));
    }
}
