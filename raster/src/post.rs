//! After shading: supersampling resolve (box filter, in linear HDR), then
//! exposure, tone mapping and the one sRGB encode at the very end.

use crate::shade::ColorBuffer;
use crate::target::Target;
use rayon::prelude::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Tonemap {
    /// Clamp each channel to [0, 1].
    #[default]
    Clamp,
    /// x / (1 + x) per channel.   [Reinhard02]
    Reinhard,
    /// Narkowicz's fit of the ACES filmic curve.   [Narkowicz15]
    Aces,
}

impl Tonemap {
    #[inline]
    pub fn apply(self, x: f32) -> f32 {
        // NaN and negatives become 0, so no NaN reaches the encoder; every
        // curve is within 1e-18 of 1 past 1e18, and capping there keeps x²
        // (ACES) and 1 + x (Reinhard) finite for +inf.
        let x = if x > 0.0 { x.min(1e18) } else { 0.0 };
        match self {
            Tonemap::Clamp => x.min(1.0),
            Tonemap::Reinhard => x / (1.0 + x),
            Tonemap::Aces => {
                ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
            }
        }
    }
}

/// Linear [0, 1] → sRGB-encoded 8-bit (IEC 61966-2-1 transfer function).
#[inline]
pub fn srgb_encode(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// Row-major linear HDR image of `width × height` (supersampled target size
/// divided by `ssaa`), each output pixel the mean of its ssaa² samples.
pub fn downsample(target: &Target, color: &ColorBuffer, ssaa: u32) -> (u32, u32, Vec<[f32; 3]>) {
    let (w, h) = (target.width / ssaa, target.height / ssaa);
    let scale = 1.0 / (ssaa * ssaa) as f32;
    let mut out = vec![[0.0f32; 3]; (w * h) as usize];
    out.par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                let mut s = [0.0f32; 3];
                for sy in 0..ssaa {
                    for sx in 0..ssaa {
                        let i = target.index(x as u32 * ssaa + sx, y as u32 * ssaa + sy);
                        s[0] += color.r[i];
                        s[1] += color.g[i];
                        s[2] += color.b[i];
                    }
                }
                *px = s.map(|c| c * scale);
            }
        });
    (w, h, out)
}

/// Exposure (in stops), tone mapping and sRGB encoding: 8-bit RGB, row-major.
pub fn encode_ldr(hdr: &[[f32; 3]], tonemap: Tonemap, exposure: f32) -> Vec<u8> {
    let k = exposure.exp2();
    let mut out = vec![0u8; hdr.len() * 3];
    out.par_chunks_mut(3 * 4096)
        .zip(hdr.par_chunks(4096))
        .for_each(|(o, h)| {
            for (o, px) in o.chunks_exact_mut(3).zip(h) {
                for c in 0..3 {
                    o[c] = srgb_encode(tonemap.apply(px[c] * k));
                }
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_matches_the_standard_at_known_points() {
        assert_eq!(srgb_encode(0.0), 0);
        assert_eq!(srgb_encode(1.0), 255);
        // 0.5 linear is 0.7354 encoded: 187.5 → 188.
        assert_eq!(srgb_encode(0.5), 188);
        assert_eq!(srgb_encode(0.0031308), 10);
    }

    #[test]
    fn tonemaps_send_nan_to_black_and_stay_in_range() {
        for op in [Tonemap::Clamp, Tonemap::Reinhard, Tonemap::Aces] {
            assert_eq!(op.apply(f32::NAN), 0.0);
            for x in [0.0, 0.1, 1.0, 10.0, 1e30, f32::INFINITY] {
                let y = op.apply(x);
                assert!((0.0..=1.0).contains(&y), "{op:?}({x}) = {y}");
            }
        }
    }
}
