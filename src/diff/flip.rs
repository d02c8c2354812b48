//! ꟻLIP, the perceptual difference of two images, as its authors define it:
//! LDR-FLIP for display images \[Andersson20\] and HDR-FLIP for linear ones
//! \[Andersson21\]. Written from the papers and checked against the authors'
//! reference implementation (the `flip-evaluator` package) on the pairs in
//! `fixtures/flip/` (`tests/flip.rs`, `fixtures/flip/flip_reference.py`).
//!
//! LDR-FLIP, per pixel, for a viewer at `ppd` pixels per degree:
//! 1. colour pipeline: both images to YCxCz (linear RGB → XYZ, D65 white),
//!    filtered by the contrast sensitivity functions of the achromatic,
//!    red-green and blue-yellow channels (sums of Gaussians, separable),
//!    back to linear RGB clamped to [0, 1], to L\*a\*b\* with the Hunt
//!    adjustment (a, b scaled by 0.01 L), HyAB distance, raised to
//!    qc = 0.7 and remapped to [0, 1] (the lower 40 % of the largest
//!    distance, green to blue, onto [0, 0.95]);
//! 2. feature pipeline: edges and points of the normalized luminance
//!    (first and second derivatives of a Gaussian of σ = 0.082/2 degrees),
//!    their largest difference ΔF, divided by √2, raised to qf = 0.5;
//! 3. the error is ΔE^(1 − ΔF).
//!
//! HDR-FLIP tone maps both images at exposures 2^c for c from c_start to
//! c_stop (from the reference's largest and median luminance), runs
//! LDR-FLIP at each, and keeps the largest error per pixel.
//!
//! Everything is in f32 as the reference implementation computes it; the
//! rows are processed in parallel and each pixel's value depends only on
//! its inputs, so the result does not depend on the thread count.

use rayon::prelude::*;

/// The contrast sensitivity functions' Gaussians, per channel (Y, Cx, Cz):
/// a₁, b₁ and a₂, b₂ of S(f) = a₁ √(π/b₁) e^(−π² x²/b₁) + a₂ √(π/b₂) e^(−π² x²/b₂)
/// in the spatial domain (x in degrees) [Andersson20, Table 1].
const CSF_A1: [f32; 3] = [1.0, 1.0, 34.1];
const CSF_B1: [f32; 3] = [0.0047, 0.0053, 0.04];
const CSF_A2: [f32; 3] = [0.0, 0.0, 13.5];
const CSF_B2: [f32; 3] = [1.0e-5, 1.0e-5, 0.025];
/// Colour-difference exponent qc, the share pc of the largest distance
/// mapped onto [0, pt] \[Andersson20\].
const QC: f32 = 0.7;
const PC: f32 = 0.4;
const PT: f32 = 0.95;
/// Feature filter width w (degrees) and exponent qf \[Andersson20\].
const FEATURE_W: f32 = 0.082;
const QF: f32 = 0.5;
/// The exposure a tone curve maps to 0.85 sets c_start and c_stop \[Andersson21\].
const HDR_TARGET: f32 = 0.85;

/// Pixels per degree of the authors' default viewer: 0.7 m from a 0.7 m
/// wide 3840-pixel monitor (about 67).
pub fn default_ppd() -> f32 {
    ppd(0.7, 3840.0, 0.7)
}

/// Pixels per degree for a viewer `distance` metres from a monitor
/// `width_m` metres and `width_px` pixels wide.
pub(crate) fn ppd(distance: f32, width_px: f32, width_m: f32) -> f32 {
    distance * (width_px / width_m) * (std::f32::consts::PI / 180.0)
}

/// The tone curves HDR-FLIP may assume.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ToneCurve {
    /// Narkowicz's fit of ACES with the 0.6 pre-exposure cancelled (the
    /// authors' default).
    Aces,
    /// Hable's filmic curve.
    Hable,
    /// Reinhard on luminance: c / (1 + Y).
    Reinhard,
}

impl ToneCurve {
    /// (p₀, p₁, p₂, q₀, q₁, q₂) of the rational curve
    /// t(x) = (p₀x² + p₁x + p₂)/(q₀x² + q₁x + q₂) per channel.
    fn coefficients(self) -> [f32; 6] {
        match self {
            // ACES: (2.51x² + 0.03x)/(2.43x² + 0.59x + 0.14) at x = 0.6 input.
            ToneCurve::Aces => [
                0.6 * 0.6 * 2.51,
                0.6 * 0.03,
                0.0,
                0.6 * 0.6 * 2.43,
                0.6 * 0.59,
                0.14,
            ],
            ToneCurve::Hable => [0.231683, 0.013791, 0.0, 0.18, 0.3, 0.018],
            // Only used to find the exposure range: x / (x + 1).
            ToneCurve::Reinhard => [0.0, 1.0, 0.0, 0.0, 1.0, 1.0],
        }
    }

    /// Tone maps one linear colour.
    pub(crate) fn apply(self, c: [f32; 3]) -> [f32; 3] {
        if self == ToneCurve::Reinhard {
            let f = 1.0 / (1.0 + luminance(c));
            return c.map(|v| v * f);
        }
        let t = self.coefficients();
        c.map(|x| (x * x * t[0] + x * t[1] + t[2]) / (x * x * t[3] + x * t[4] + t[5]))
    }

    /// The exposure x at which the curve reaches [`HDR_TARGET`]: the larger
    /// root of (p₀ − t q₀)x² + (p₁ − t q₁)x + (p₂ − t q₂) = 0.
    fn x_at_target(self) -> f32 {
        let c = self.coefficients();
        let (a, b, k) = (
            c[0] - HDR_TARGET * c[3],
            c[1] - HDR_TARGET * c[4],
            c[2] - HDR_TARGET * c[5],
        );
        if a == 0.0 {
            return -k / b;
        }
        let d1 = -0.5 * (b / a);
        let d2 = (d1 * d1 - k / a).sqrt();
        d1 + d2
    }
}

/// Rec. 709 luminance of linear RGB.
pub(crate) fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// sRGB transfer function, encoded → linear (IEC 61966-2-1).
pub(crate) fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// sRGB transfer function, linear → encoded.
pub(crate) fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.0031308 {
        v * 12.92
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear sRGB → CIE XYZ, D65 white (the sRGB primaries' exact fractions).
fn rgb_to_xyz(c: [f32; 3]) -> [f32; 3] {
    let m = [
        [
            10135552.0 / 24577794.0,
            8788810.0 / 24577794.0,
            4435075.0 / 24577794.0,
        ],
        [
            2613072.0 / 12288897.0,
            8788810.0 / 12288897.0,
            887015.0 / 12288897.0,
        ],
        [
            1425312.0 / 73733382.0,
            8788810.0 / 73733382.0,
            70074185.0 / 73733382.0,
        ],
    ];
    m.map(|r| r[0] * c[0] + r[1] * c[1] + r[2] * c[2])
}

/// CIE XYZ → linear sRGB, D65 white.
// The matrix and white point as the FLIP authors give them (more digits
// than f32 holds; the literals round to the nearest f32).
#[allow(clippy::excessive_precision)]
fn xyz_to_rgb(c: [f32; 3]) -> [f32; 3] {
    let m = [
        [3.241003275, -1.537398934, -0.498615861],
        [-0.969224334, 1.875930071, 0.041554224],
        [0.055639423, -0.204011202, 1.057148933],
    ];
    m.map(|r| r[0] * c[0] + r[1] * c[1] + r[2] * c[2])
}

/// The D65 white point in XYZ and its reciprocal.
#[allow(clippy::excessive_precision)]
const WHITE: [f32; 3] = [0.950428545, 1.0, 1.088900371];
#[allow(clippy::excessive_precision)]
const INV_WHITE: [f32; 3] = [1.052156925, 1.0, 0.918357670];

/// XYZ → YCxCz: CIELAB's opponent axes without its cube root (linear in
/// XYZ, so filtering there is filtering the stimulus).
fn xyz_to_ycxcz(c: [f32; 3]) -> [f32; 3] {
    let (x, y, z) = (c[0] * INV_WHITE[0], c[1], c[2] * INV_WHITE[2]);
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn ycxcz_to_xyz(c: [f32; 3]) -> [f32; 3] {
    let y = (c[0] + 16.0) / 116.0;
    let x = y + c[1] / 500.0;
    let z = y - c[2] / 200.0;
    [x * WHITE[0], y * WHITE[1], z * WHITE[2]]
}

/// XYZ → CIE L\*a\*b\*, D65 white.
fn xyz_to_lab(c: [f32; 3]) -> [f32; 3] {
    let delta = 6.0f32 / 29.0;
    let delta3 = delta * delta * delta;
    let f = |t: f32| {
        if t > delta3 {
            t.powf(1.0 / 3.0)
        } else {
            t / (3.0 * delta * delta) + 4.0 / 29.0
        }
    };
    let (x, y, z) = (f(c[0] * INV_WHITE[0]), f(c[1]), f(c[2] * INV_WHITE[2]));
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// L\*a\*b\* with the Hunt effect: chroma scaled by 0.01 L\*.
fn hunt(lab: [f32; 3]) -> [f32; 3] {
    [lab[0], 0.01 * lab[0] * lab[1], 0.01 * lab[0] * lab[2]]
}

/// HyAB distance: |ΔL| + √(Δa² + Δb²).
fn hyab(p: [f32; 3], q: [f32; 3]) -> f32 {
    (p[0] - q[0]).abs() + ((p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

/// The largest colour distance, between pure green and pure blue, raised to qc.
fn max_distance() -> f32 {
    let lab = |c| hunt(xyz_to_lab(rgb_to_xyz(c)));
    hyab(lab([0.0, 1.0, 0.0]), lab([0.0, 0.0, 1.0])).powf(QC)
}

/// One channel's CSF Gaussian a √(π/b) e^(−π² x²/b) at x² (degrees²).
fn csf_gaussian(x2: f32, a: f32, b: f32) -> f32 {
    let pi = std::f32::consts::PI;
    a * (pi / b).sqrt() * (-pi * pi * x2 / b).exp()
}

/// The 1-D factor of a 2-D CSF Gaussian: its product in x and y is the 2-D
/// Gaussian, so a sum of two is filtered as two separable passes.
fn csf_gaussian_factor(x2: f32, a: f32, b: f32) -> f32 {
    let pi = std::f32::consts::PI;
    (a * (pi / b).sqrt()).sqrt() * (-pi * pi * x2 / b).exp()
}

/// The separable CSF filters: per tap (Y, Cx) weights, each summing to 1,
/// and the Cz channel's two factors, normalized so that the 2-D kernel
/// (g₁ ⊗ g₁ + g₂ ⊗ g₂) sums to 1.
struct CsfFilters {
    ycx: Vec<[f32; 2]>,
    cz: Vec<[f32; 2]>,
}

fn csf_filters(ppd: f32) -> CsfFilters {
    let pi2 = std::f32::consts::PI * std::f32::consts::PI;
    // Three standard deviations of the widest Gaussian (σ² = b / 2π²).
    let b_max = CSF_B1.iter().chain(&CSF_B2).fold(0.0f32, |m, &b| m.max(b));
    let radius = (3.0 * (b_max / (2.0 * pi2)).sqrt() * ppd).ceil() as i32;
    let dx = 1.0 / ppd;
    let mut ycx = Vec::new();
    let mut cz = Vec::new();
    let (mut s_ycx, mut s_cz) = ([0.0f32; 2], [0.0f32; 2]);
    for i in -radius..=radius {
        let x = i as f32 * dx;
        let x2 = x * x;
        let w = [
            csf_gaussian(x2, CSF_A1[0], CSF_B1[0]),
            csf_gaussian(x2, CSF_A1[1], CSF_B1[1]),
        ];
        let z = [
            csf_gaussian_factor(x2, CSF_A1[2], CSF_B1[2]),
            csf_gaussian_factor(x2, CSF_A2[2], CSF_B2[2]),
        ];
        for k in 0..2 {
            s_ycx[k] += w[k];
            s_cz[k] += z[k];
        }
        ycx.push(w);
        cz.push(z);
    }
    let n_cz = 1.0 / (s_cz[0] * s_cz[0] + s_cz[1] * s_cz[1]).sqrt();
    for w in &mut ycx {
        *w = [w[0] / s_ycx[0], w[1] / s_ycx[1]];
    }
    for z in &mut cz {
        *z = [z[0] * n_cz, z[1] * n_cz];
    }
    CsfFilters { ycx, cz }
}

/// Per tap: Gaussian, its first and its second derivative, for σ =
/// w/2 degrees. The Gaussian sums to 1; each derivative's positive taps
/// sum to 1 and its negative taps to −1.
fn feature_filter(ppd: f32) -> Vec<[f32; 3]> {
    let sd = 0.5 * FEATURE_W * ppd;
    let radius = (3.0 * sd).ceil() as i32;
    let mut taps = Vec::new();
    let (mut g_sum, mut d_pos, mut d_neg, mut dd_pos, mut dd_neg) = (0.0f32, 0.0, 0.0, 0.0, 0.0);
    for i in -radius..=radius {
        let x = i as f32;
        let g = (-(x * x) / (2.0 * sd * sd)).exp();
        let dg = -x * g;
        let ddg = (x * x / (sd * sd) - 1.0) * g;
        g_sum += g;
        if dg > 0.0 {
            d_pos += dg;
        } else {
            d_neg -= dg;
        }
        if ddg > 0.0 {
            dd_pos += ddg;
        } else {
            dd_neg -= ddg;
        }
        taps.push([g, dg, ddg]);
    }
    for t in &mut taps {
        *t = [
            t[0] / g_sum,
            t[1] / if t[1] > 0.0 { d_pos } else { d_neg },
            t[2] / if t[2] > 0.0 { dd_pos } else { dd_neg },
        ];
    }
    taps
}

/// LDR-FLIP of two linear-RGB images in [0, 1] (values outside are
/// clamped), row-major, `width` × `height`: the per-pixel error in [0, 1].
pub(crate) fn ldr_flip(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    width: usize,
    height: usize,
    ppd: f32,
) -> Vec<f32> {
    assert_eq!(reference.len(), width * height);
    assert_eq!(test.len(), width * height);
    let to_ycxcz = |img: &[[f32; 3]]| -> Vec<[f32; 3]> {
        img.iter()
            .map(|c| xyz_to_ycxcz(rgb_to_xyz(c.map(|v| v.clamp(0.0, 1.0)))))
            .collect()
    };
    let r = to_ycxcz(reference);
    let t = to_ycxcz(test);
    let color = color_difference(&r, &t, width, height, ppd);
    let feature = feature_difference(&r, &t, width, height, ppd);
    color
        .iter()
        .zip(&feature)
        .map(|(&c, &f)| c.powf(1.0 - f))
        .collect()
}

/// Clamps a tap's position to the image (edge texels repeat).
fn clamp_index(i: isize, n: usize) -> usize {
    i.clamp(0, n as isize - 1) as usize
}

/// The colour pipeline's ΔE per pixel, remapped to [0, 1].
fn color_difference(
    r: &[[f32; 3]],
    t: &[[f32; 3]],
    width: usize,
    height: usize,
    ppd: f32,
) -> Vec<f32> {
    let f = csf_filters(ppd);
    let half = (f.ycx.len() / 2) as isize;
    // Horizontal pass: (Y, Cx) and the two Cz factors, for both images.
    let horizontal = |img: &[[f32; 3]]| -> Vec<[f32; 4]> {
        let mut out = vec![[0.0f32; 4]; width * height];
        out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let mut acc = [0.0f32; 4];
                for k in -half..=half {
                    let xx = clamp_index(x as isize + k, width);
                    let c = img[y * width + xx];
                    let (w, z) = (f.ycx[(k + half) as usize], f.cz[(k + half) as usize]);
                    acc[0] += w[0] * c[0];
                    acc[1] += w[1] * c[1];
                    acc[2] += z[0] * c[2];
                    acc[3] += z[1] * c[2];
                }
                *o = acc;
            }
        });
        out
    };
    let hr = horizontal(r);
    let ht = horizontal(t);
    let c_max = max_distance();
    let pc_max = PC * c_max;
    let mut out = vec![0.0f32; width * height];
    out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let vertical = |h: &[[f32; 4]]| {
                let mut acc = [0.0f32; 4];
                for k in -half..=half {
                    let yy = clamp_index(y as isize + k, height);
                    let c = h[yy * width + x];
                    let (w, z) = (f.ycx[(k + half) as usize], f.cz[(k + half) as usize]);
                    acc[0] += w[0] * c[0];
                    acc[1] += w[1] * c[1];
                    acc[2] += z[0] * c[2];
                    acc[3] += z[1] * c[3];
                }
                let ycxcz = [acc[0], acc[1], acc[2] + acc[3]];
                let rgb = xyz_to_rgb(ycxcz_to_xyz(ycxcz)).map(|v| v.clamp(0.0, 1.0));
                hunt(xyz_to_lab(rgb_to_xyz(rgb)))
            };
            let d = hyab(vertical(&hr), vertical(&ht)).powf(QC);
            *o = if d < pc_max {
                d * PT / pc_max
            } else {
                PT + (d - pc_max) / (c_max - pc_max) * (1.0 - PT)
            };
        }
    });
    out
}

/// The feature pipeline's ΔF per pixel, in [0, 1].
fn feature_difference(
    r: &[[f32; 3]],
    t: &[[f32; 3]],
    width: usize,
    height: usize,
    ppd: f32,
) -> Vec<f32> {
    let taps = feature_filter(ppd);
    let half = (taps.len() / 2) as isize;
    // Luminance normalized to [0, 1]: (Y + 16)/116.
    let norm = |c: [f32; 3]| c[0] * (1.0 / 116.0) + 16.0 / 116.0;
    // Horizontal pass: x-derivative, x-second derivative, Gaussian.
    let horizontal = |img: &[[f32; 3]]| -> Vec<[f32; 3]> {
        let mut out = vec![[0.0f32; 3]; width * height];
        out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let mut acc = [0.0f32; 3];
                for k in -half..=half {
                    let xx = clamp_index(x as isize + k, width);
                    let v = norm(img[y * width + xx]);
                    let w = taps[(k + half) as usize];
                    acc[0] += w[1] * v;
                    acc[1] += w[2] * v;
                    acc[2] += w[0] * v;
                }
                *o = acc;
            }
        });
        out
    };
    let hr = horizontal(r);
    let ht = horizontal(t);
    let mut out = vec![0.0f32; width * height];
    out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            // (edge, point) magnitudes of one image at (x, y).
            let features = |h: &[[f32; 3]]| {
                let (mut dx, mut ddx, mut dy, mut ddy) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
                for k in -half..=half {
                    let yy = clamp_index(y as isize + k, height);
                    let c = h[yy * width + x];
                    let w = taps[(k + half) as usize];
                    dx += w[0] * c[0];
                    ddx += w[0] * c[1];
                    dy += w[1] * c[2];
                    ddy += w[2] * c[2];
                }
                ((dx * dx + dy * dy).sqrt(), (ddx * ddx + ddy * ddy).sqrt())
            };
            let (er, pr) = features(&hr);
            let (et, pt) = features(&ht);
            let d = (er - et).abs().max((pr - pt).abs());
            *o = (std::f32::consts::FRAC_1_SQRT_2 * d).powf(QF);
        }
    });
    out
}

/// The exposure range and count HDR-FLIP uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exposures {
    pub start: f32,
    pub stop: f32,
    pub count: usize,
}

/// Why a reference has no automatic HDR-FLIP exposure range.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ExposureError {
    /// Every pixel is black.
    #[error("the reference is black: HDR-FLIP has no exposure range to use")]
    Black,
    /// The median luminance is 0; `start` and `stop` are the range that
    /// the median of the lit pixels would give, suggested to the user.
    #[error("more than half of the reference's pixels are black, so HDR-FLIP's automatic exposure range is unbounded; give one, e.g. --exposures={start:.3}:{stop:.3} (the median of the lit pixels)")]
    MostlyBlack { start: f32, stop: f32 },
}

/// The authors' automatic range \[Andersson21\]: c_start puts the reference's
/// largest luminance, c_stop its median, where the tone curve reaches
/// 0.85; one exposure per stop, at least two. `Err` when the largest or
/// the median luminance is 0 (the range is then unbounded), with the
/// median of the non-zero luminances as a suggestion.
pub fn auto_exposures(
    reference: &[[f32; 3]],
    curve: ToneCurve,
) -> Result<Exposures, ExposureError> {
    let x = curve.x_at_target();
    let mut lum: Vec<f32> = reference.iter().map(|&c| luminance(c)).collect();
    let y_max = lum.iter().fold(f32::NEG_INFINITY, |m, &v| m.max(v));
    let mid = lum.len() / 2;
    let (_, &mut y_median, _) = lum.select_nth_unstable_by(mid, f32::total_cmp);
    if y_max <= 0.0 {
        return Err(ExposureError::Black);
    }
    let start = (x / y_max).log2();
    if y_median <= 0.0 {
        let mut nonzero: Vec<f32> = lum.into_iter().filter(|&v| v > 0.0).collect();
        let m = nonzero.len() / 2;
        let (_, &mut y, _) = nonzero.select_nth_unstable_by(m, f32::total_cmp);
        return Err(ExposureError::MostlyBlack {
            start,
            stop: (x / y).log2(),
        });
    }
    let stop = (x / y_median).log2();
    Ok(Exposures {
        start,
        stop,
        count: ((stop - start).ceil().max(2.0)) as usize,
    })
}

/// HDR-FLIP of two linear images (non-negative), with the given exposures
/// and tone curve: the per-pixel error in [0, 1].
pub(crate) fn hdr_flip(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    width: usize,
    height: usize,
    ppd: f32,
    exposures: Exposures,
    curve: ToneCurve,
) -> Vec<f32> {
    let mut error = vec![0.0f32; width * height];
    let n = exposures.count.max(2);
    let step = (exposures.stop - exposures.start) / (n - 1) as f32;
    for i in 0..n {
        let m = (exposures.start + i as f32 * step).exp2();
        let expose = |img: &[[f32; 3]]| -> Vec<[f32; 3]> {
            img.iter()
                .map(|c| curve.apply(c.map(|v| v * m)).map(|v| v.clamp(0.0, 1.0)))
                .collect()
        };
        let e = ldr_flip(&expose(reference), &expose(test), width, height, ppd);
        for (o, v) in error.iter_mut().zip(e) {
            if v > *o {
                *o = v;
            }
        }
    }
    error
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_zero_error() {
        let img: Vec<[f32; 3]> = (0..32 * 24)
            .map(|i| [(i % 7) as f32 / 7.0, (i % 5) as f32 / 5.0, 0.5])
            .collect();
        let e = ldr_flip(&img, &img, 32, 24, default_ppd());
        assert!(e.iter().all(|&v| v == 0.0), "{:?}", &e[..8]);
    }

    #[test]
    fn black_against_white_is_near_the_top_of_the_scale() {
        // Flat fields: no features, so the error is the remapped colour
        // distance of black and white, ΔL = 100 → 100^0.7 against c_max.
        let (w, h) = (24, 24);
        let e = ldr_flip(
            &vec![[0.0; 3]; w * h],
            &vec![[1.0; 3]; w * h],
            w,
            h,
            default_ppd(),
        );
        let c_max = max_distance();
        let d = 100.0f32.powf(QC);
        let expect = if d < PC * c_max {
            d * PT / (PC * c_max)
        } else {
            PT + (d - PC * c_max) / (c_max - PC * c_max) * (1.0 - PT)
        };
        for v in e {
            assert!((v - expect).abs() < 1e-3, "{v} vs {expect}");
        }
    }

    #[test]
    fn filters_are_normalized() {
        let f = csf_filters(default_ppd());
        let s: f32 = f.ycx.iter().map(|w| w[0]).sum();
        assert!((s - 1.0).abs() < 1e-5);
        let s1: f32 = f.cz.iter().map(|w| w[0]).sum();
        let s2: f32 = f.cz.iter().map(|w| w[1]).sum();
        assert!((s1 * s1 + s2 * s2 - 1.0).abs() < 1e-5);
        let taps = feature_filter(default_ppd());
        let pos: f32 = taps.iter().map(|t| t[1].max(0.0)).sum();
        assert!((pos - 1.0).abs() < 1e-5);
    }

    #[test]
    fn aces_reaches_the_target_at_the_solved_exposure() {
        for curve in [ToneCurve::Aces, ToneCurve::Hable] {
            let x = curve.x_at_target();
            let t = curve.apply([x; 3])[0];
            assert!((t - HDR_TARGET).abs() < 1e-4, "{curve:?}: {t}");
        }
    }
}
