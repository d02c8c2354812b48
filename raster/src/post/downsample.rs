//! Downsampling the supersamples: a box filter over each output pixel's
//! ssaa² samples, on its own into an HDR image ([`downsample`]) or fused
//! with exposure and tone mapping ([`downsample_hdr_into`]) and with the sRGB
//! encode as well ([`downsample_ldr_into`]), in one pass over the samples.

use super::encode::{encode_pixels, encode_planes, load8, size_output};
use super::tonemap::{curve_of, Tonemap};
use super::HdrImage;
use crate::buffers::{FrameBuffers, Planes3};
use rayon::prelude::*;
use specula_core::f32x8;

/// Sum of the ssaa² samples of output pixel (x, y), in sample order.
#[inline]
fn box_sum(color: &Planes3, width: usize, ssaa: usize, x: usize, y: usize) -> [f32; 3] {
    let mut s = [0.0f32; 3];
    for sy in 0..ssaa {
        let row = (y * ssaa + sy) * width + x * ssaa;
        for i in row..row + ssaa {
            s[0] += color.r[i];
            s[1] += color.g[i];
            s[2] += color.b[i];
        }
    }
    s
}

/// The downsample: each output pixel the mean of its ssaa²
/// samples of `color` (`width × height` samples).
pub fn downsample(color: &Planes3, width: u32, height: u32, ssaa: u32) -> HdrImage {
    let (w, h) = (width / ssaa, height / ssaa);
    if ssaa == 1 {
        return HdrImage {
            width: w,
            height: h,
            rgb: color.clone(),
        };
    }
    let scale = 1.0 / (ssaa * ssaa) as f32;
    let mut rgb = Planes3::new((w * h) as usize);
    rgb.r
        .par_chunks_mut(w as usize)
        .zip(rgb.g.par_chunks_mut(w as usize))
        .zip(rgb.b.par_chunks_mut(w as usize))
        .enumerate()
        .for_each(|(y, ((r, g), b))| {
            for x in 0..w as usize {
                let s = box_sum(color, width as usize, ssaa as usize, x, y);
                r[x] = s[0] * scale;
                g[x] = s[1] * scale;
                b[x] = s[2] * scale;
            }
        });
    HdrImage {
        width: w,
        height: h,
        rgb,
    }
}

/// Downsample, exposure (in stops) and tone mapping in one pass
/// over the samples, into `out` (planes of (width / ssaa) × (height /
/// ssaa), their allocations reused): the values the three stages give one
/// after the other (the same products in the same order), without the
/// copies and passes in between. The head of a post list with custom
/// stages.
pub(crate) fn downsample_hdr_into(
    frame: &FrameBuffers,
    ssaa: u32,
    tonemap: Tonemap,
    exposure: f32,
    out: &mut Planes3,
) {
    match tonemap {
        Tonemap::Clamp => downsample_hdr_with::<0>(frame, ssaa, exposure, out),
        Tonemap::Reinhard => downsample_hdr_with::<1>(frame, ssaa, exposure, out),
        Tonemap::Aces => downsample_hdr_with::<2>(frame, ssaa, exposure, out),
    }
}

fn downsample_hdr_with<const CURVE: u8>(
    frame: &FrameBuffers,
    ssaa: u32,
    exposure: f32,
    out: &mut Planes3,
) {
    let curve = curve_of::<CURVE>();
    let (sw, ssaa) = (frame.width as usize, ssaa as usize);
    let (w, h) = (sw / ssaa, frame.height as usize / ssaa);
    let color = &frame.color;
    let (inv_n, k) = (1.0 / (ssaa * ssaa) as f32, exposure.exp2());
    for p in [&mut out.r, &mut out.g, &mut out.b] {
        // Every value is written below: zeros only where the plane grows.
        p.truncate(w * h);
        p.resize(w * h, 0.0);
    }
    let full = w / 8 * 8;
    out.r
        .par_chunks_mut(w.max(1))
        .zip(out.g.par_chunks_mut(w.max(1)))
        .zip(out.b.par_chunks_mut(w.max(1)))
        .enumerate()
        .for_each(|(y, ((r, g), b))| {
            for x0 in (0..full).step_by(8) {
                let s = sums8(color, sw, ssaa, x0, y);
                let mapped = |ch: f32x8| {
                    let v = ch * f32x8::splat(inv_n) * f32x8::splat(k);
                    curve.apply_x8(v).to_array()
                };
                r[x0..x0 + 8].copy_from_slice(&mapped(s[0]));
                g[x0..x0 + 8].copy_from_slice(&mapped(s[1]));
                b[x0..x0 + 8].copy_from_slice(&mapped(s[2]));
            }
            for x in full..w {
                let s = sum1(color, sw, ssaa, x, y);
                r[x] = curve.apply(s[0] * inv_n * k);
                g[x] = curve.apply(s[1] * inv_n * k);
                b[x] = curve.apply(s[2] * inv_n * k);
            }
        });
}

/// Downsample, exposure (in stops), tone mapping and sRGB
/// encoding in one pass over the samples: 8-bit RGB, row-major, of
/// (width / ssaa) × (height / ssaa), into `out`, resized to the output (its
/// earlier bytes are all overwritten, so an allocation from an earlier frame
/// is reused as it is). Equal to the unfused stage list (a test checks it)
/// without the HDR images in between.
pub(crate) fn downsample_ldr_into(
    frame: &FrameBuffers,
    ssaa: u32,
    tonemap: Tonemap,
    exposure: f32,
    out: &mut Vec<u8>,
) {
    // One monomorphized loop per curve: no match per pixel.
    match tonemap {
        Tonemap::Clamp => downsample_ldr_with::<0>(frame, ssaa, exposure, out),
        Tonemap::Reinhard => downsample_ldr_with::<1>(frame, ssaa, exposure, out),
        Tonemap::Aces => downsample_ldr_with::<2>(frame, ssaa, exposure, out),
    }
}

fn downsample_ldr_with<const CURVE: u8>(
    frame: &FrameBuffers,
    ssaa: u32,
    exposure: f32,
    out: &mut Vec<u8>,
) {
    let (sw, ssaa) = (frame.width as usize, ssaa as usize);
    let (w, h) = (sw / ssaa, frame.height as usize / ssaa);
    let color = &frame.color;
    // The same products, in the same order, as the unfused stages.
    let (inv_n, k) = (1.0 / (ssaa * ssaa) as f32, exposure.exp2());
    size_output(out, w * h * 3);
    out.par_chunks_mut(3 * w).enumerate().for_each(|(y, row)| {
        if ssaa == 1 {
            // The shading pass's encode (LdrEncoding), on the row's slices.
            let i = y * sw;
            let [r, g, b] = [&color.r, &color.g, &color.b].map(|p| &p[i..i + w]);
            encode_planes::<CURVE>(r, g, b, k, row);
        } else {
            encode_pixels::<CURVE>(
                row,
                inv_n,
                k,
                |x0| sums8(color, sw, ssaa, x0, y),
                |x| sum1(color, sw, ssaa, x, y),
            );
        }
    });
}

/// The sample sums of output pixels (x0.., y), 8 of them, per channel:
/// the samples themselves at ssaa 1.
#[inline(always)]
fn sums8(color: &Planes3, sw: usize, ssaa: usize, x0: usize, y: usize) -> [f32x8; 3] {
    if ssaa == 1 {
        let i = y * sw + x0;
        [load8(&color.r, i), load8(&color.g, i), load8(&color.b, i)]
    } else {
        let sums: [[f32; 3]; 8] =
            std::array::from_fn(|lane| box_sum(color, sw, ssaa, x0 + lane, y));
        [0, 1, 2].map(|c| f32x8::from(sums.map(|v| v[c])))
    }
}

/// [`sums8`] for one pixel.
#[inline(always)]
fn sum1(color: &Planes3, sw: usize, ssaa: usize, x: usize, y: usize) -> [f32; 3] {
    if ssaa == 1 {
        color.get(y * sw + x)
    } else {
        box_sum(color, sw, ssaa, x, y)
    }
}
