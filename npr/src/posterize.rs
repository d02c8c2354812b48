//! Posterization: a post stage that quantizes the tone-mapped image to a
//! few levels, per channel or on luminance keeping hue (the course notes'
//! "colour blocks" in image space). It runs after the tone map and before
//! the sRGB encode, on values in [0, 1].
//!
//! Levels are spaced evenly in the *encoded* (sRGB) value, where steps look
//! even: level k of L is the linear value whose sRGB encoding is k/(L − 1),
//! and a value goes to the level nearest in encoded terms. The encode then
//! writes exactly one 8-bit code per level, so an image shows at most L
//! codes per channel. The cut points are computed once (in f64) when the
//! stage is made; a pixel costs one short search, no `powf`.

use crate::ParamError;
use specula_raster::post::{srgb_curve_inverse, HdrImage, PostStage};
use specula_raster::FrameBuffers;

/// What is quantized.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PosterizeMode {
    /// Each channel on its own.
    Rgb,
    /// The luminance Y (Rec. 709 weights on linear values); the colour is
    /// scaled by Yq / Y so its hue and saturation stay. Where that would
    /// push a channel past 1, the colour is scaled down until it does not
    /// (keeping hue; the luminance is then lower than Yq).
    Luminance,
}

/// The stage; see the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct Posterize {
    pub(crate) levels: u32,
    pub(crate) mode: PosterizeMode,
    /// Linear cut points between consecutive levels (L − 1 of them).
    cuts: Vec<f32>,
    /// Linear value of each level.
    values: Vec<f32>,
}

/// Rec. 709 / sRGB luminance weights.
const LUMA: [f32; 3] = [0.2126, 0.7152, 0.0722];

impl Posterize {
    /// `levels` in 2..=256.
    pub fn new(levels: u32, mode: PosterizeMode) -> Result<Posterize, ParamError> {
        if !(2..=256).contains(&levels) {
            return Err(ParamError::new(
                "levels",
                format!("must be in 2..=256, got {levels}"),
            ));
        }
        let n = (levels - 1) as f64;
        Ok(Posterize {
            levels,
            mode,
            cuts: (0..levels - 1)
                .map(|k| srgb_curve_inverse((k as f64 + 0.5) / n) as f32)
                .collect(),
            values: (0..levels)
                .map(|k| srgb_curve_inverse(k as f64 / n) as f32)
                .collect(),
        })
    }

    /// The level value of a tone-mapped value (NaN and negatives go to 0).
    #[inline]
    pub fn quantize(&self, v: f32) -> f32 {
        let v = if v > 0.0 { v.min(1.0) } else { 0.0 };
        self.values[self.cuts.partition_point(|&c| c <= v)]
    }

    /// The level values, darkest first (for tests and docs).
    pub fn level_values(&self) -> &[f32] {
        &self.values
    }

    fn pixel(&self, rgb: [f32; 3]) -> [f32; 3] {
        match self.mode {
            PosterizeMode::Rgb => rgb.map(|v| self.quantize(v)),
            PosterizeMode::Luminance => {
                let rgb = rgb.map(|v| if v > 0.0 { v.min(1.0) } else { 0.0 });
                let y = rgb[0] * LUMA[0] + rgb[1] * LUMA[1] + rgb[2] * LUMA[2];
                let yq = self.quantize(y);
                if y <= 0.0 {
                    return [yq; 3];
                }
                let max = rgb[0].max(rgb[1]).max(rgb[2]);
                // y > 0 implies max > 0; cap the scale so max · k ≤ 1.
                let k = (yq / y).min(1.0 / max);
                rgb.map(|v| v * k)
            }
        }
    }
}

impl PostStage for Posterize {
    fn name(&self) -> &str {
        "posterize"
    }

    fn instance(&self) -> Box<dyn PostStage> {
        Box::new(self.clone())
    }

    fn apply(&mut self, img: &mut HdrImage, _frame: &FrameBuffers) {
        let p = &mut img.rgb;
        for i in 0..p.r.len() {
            let [r, g, b] = self.pixel([p.r[i], p.g[i], p.b[i]]);
            (p.r[i], p.g[i], p.b[i]) = (r, g, b);
        }
    }
}
