//! The numbers `specula diff` reports, over the compared pixels (all, or
//! those a mask or `--ignore-background` leaves) and every colour channel.

use super::load::Encoding;
use serde::Serialize;

/// Added to the reference in relative errors, so that black pixels do not
/// divide by zero; small against display values and typical radiances.
pub(crate) const REL_EPSILON: f64 = 0.01;

/// Pixel-share thresholds: on the absolute error of display values (1, 4
/// and 16 codes of 255), on the relative error of linear ones.
pub(crate) fn thresholds(encoding: Encoding) -> [f64; 3] {
    match encoding {
        Encoding::Display => [1.0 / 255.0, 4.0 / 255.0, 16.0 / 255.0],
        Encoding::Linear => [0.01, 0.05, 0.25],
    }
}

/// Names of the three pixel shares, smallest threshold first.
pub(crate) const OVER_NAMES: [&str; 3] = ["over_small", "over_medium", "over_large"];

#[derive(Clone, Debug, Serialize)]
pub(crate) struct Share {
    pub(crate) name: &'static str,
    /// The threshold, on the absolute error (display) or relative error (linear).
    pub(crate) threshold: f64,
    /// Share of compared pixels whose largest channel error exceeds it.
    pub(crate) share: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Metrics {
    /// Pixels compared.
    pub(crate) pixels: usize,
    /// The PSNR's peak: 1 for display images, the reference's largest
    /// compared value for linear ones.
    pub(crate) peak: f64,
    /// 10 log₁₀(peak² / MSE) in dB; `null` when the images are equal.
    pub(crate) psnr: Option<f64>,
    pub(crate) rmse: f64,
    pub(crate) mean_abs: f64,
    pub max_abs: f64,
    /// |test − ref| / (ref + 0.01), averaged and largest.
    pub(crate) mean_rel: f64,
    pub(crate) max_rel: f64,
    pub(crate) over: Vec<Share>,
    pub flip_mean: f64,
    pub(crate) flip_median: f64,
    pub(crate) flip_p99: f64,
    pub(crate) flip_max: f64,
    /// Where the FLIP error is largest (x, y).
    pub(crate) flip_worst: [usize; 2],
}

/// Computes the metrics over the pixels `keep` selects (all when `None`).
pub(crate) fn compute(
    r: &[[f32; 3]],
    t: &[[f32; 3]],
    width: usize,
    flip: &[f32],
    keep: Option<&[bool]>,
    encoding: Encoding,
) -> Metrics {
    let th = thresholds(encoding);
    let mut n = 0usize;
    let (mut se, mut sa, mut sr) = (0.0f64, 0.0f64, 0.0f64);
    let (mut max_abs, mut max_rel, mut peak) = (0.0f64, 0.0f64, 0.0f64);
    let mut over = [0usize; 3];
    let mut flips = Vec::with_capacity(r.len());
    let mut worst = (0.0f32, 0usize);
    for i in 0..r.len() {
        if keep.is_some_and(|k| !k[i]) {
            continue;
        }
        n += 1;
        let mut px = 0.0f64;
        for c in 0..3 {
            let (a, b) = (r[i][c] as f64, t[i][c] as f64);
            let d = (b - a).abs();
            let rel = d / (a + REL_EPSILON);
            se += d * d;
            sa += d;
            sr += rel;
            max_abs = max_abs.max(d);
            max_rel = max_rel.max(rel);
            peak = peak.max(a);
            px = px.max(match encoding {
                Encoding::Display => d,
                Encoding::Linear => rel,
            });
        }
        for k in 0..3 {
            over[k] += (px > th[k]) as usize;
        }
        flips.push(flip[i]);
        if flip[i] > worst.0 || flips.len() == 1 {
            worst = (flip[i], i);
        }
    }
    let samples = (3 * n.max(1)) as f64;
    let mse = se / samples;
    if encoding == Encoding::Display {
        peak = 1.0;
    }
    let flip_mean = flips.iter().map(|&v| v as f64).sum::<f64>() / n.max(1) as f64;
    flips.sort_by(f32::total_cmp);
    let pct = |p: f64| -> f64 {
        if flips.is_empty() {
            return 0.0;
        }
        let idx = ((flips.len() - 1) as f64 * p).round() as usize;
        flips[idx] as f64
    };
    Metrics {
        pixels: n,
        peak,
        psnr: (mse > 0.0).then(|| 10.0 * (peak * peak / mse).log10()),
        rmse: mse.sqrt(),
        mean_abs: sa / samples,
        max_abs,
        mean_rel: sr / samples,
        max_rel,
        over: (0..3)
            .map(|k| Share {
                name: OVER_NAMES[k],
                threshold: th[k],
                share: over[k] as f64 / n.max(1) as f64,
            })
            .collect(),
        flip_mean,
        flip_median: pct(0.5),
        flip_p99: pct(0.99),
        flip_max: flips.last().map_or(0.0, |&v| v as f64),
        flip_worst: [worst.1 % width.max(1), worst.1 / width.max(1)],
    }
}

/// Every metric a bound (`--fail-above`, `--fail-below`) may name.
pub(crate) const NAMES: [&str; 14] = [
    "psnr",
    "rmse",
    "mean_abs",
    "max_abs",
    "mean_rel",
    "max_rel",
    "over_small",
    "over_medium",
    "over_large",
    "flip_mean",
    "flip_median",
    "flip_p99",
    "flip_max",
    "pixels",
];

impl Metrics {
    /// A metric by name; PSNR of equal images is +∞.
    pub(crate) fn get(&self, name: &str) -> Option<f64> {
        Some(match name {
            "psnr" => self.psnr.unwrap_or(f64::INFINITY),
            "rmse" => self.rmse,
            "mean_abs" => self.mean_abs,
            "max_abs" => self.max_abs,
            "mean_rel" => self.mean_rel,
            "max_rel" => self.max_rel,
            "flip_mean" => self.flip_mean,
            "flip_median" => self.flip_median,
            "flip_p99" => self.flip_p99,
            "flip_max" => self.flip_max,
            "pixels" => self.pixels as f64,
            _ => return self.over.iter().find(|s| s.name == name).map(|s| s.share),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn psnr_of_a_uniform_offset_is_the_textbook_value() {
        // Every sample off by 0.1: MSE = 0.01, PSNR = 10 log10(1/0.01) = 20 dB.
        let r = vec![[0.5f32; 3]; 16];
        let t = vec![[0.6f32; 3]; 16];
        let m = compute(&r, &t, 4, &[0.0; 16], None, Encoding::Display);
        assert!((m.psnr.unwrap() - 20.0).abs() < 1e-4, "{:?}", m.psnr);
        assert!((m.rmse - 0.1).abs() < 1e-6);
        assert!((m.mean_rel - 0.1 / 0.51).abs() < 1e-5);
        assert_eq!(m.over[2].share, 1.0); // 0.1 > 16/255
    }

    #[test]
    fn the_mask_leaves_pixels_out() {
        let r = vec![[0.0f32; 3]; 4];
        let t = vec![[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [0.0; 3], [0.0; 3]];
        let keep = [true, false, true, true];
        let m = compute(
            &r,
            &t,
            2,
            &[0.0, 0.9, 0.0, 0.0],
            Some(&keep),
            Encoding::Display,
        );
        assert_eq!(m.pixels, 3);
        assert_eq!(m.psnr, None);
        assert_eq!(m.flip_max, 0.0);
    }
}
