//! Sampling an environment map by its luminance: the distribution of
//! luminance · sin θ over its texels (a marginal CDF over rows and a
//! conditional CDF per row), the directions it draws and their density per
//! solid angle. The Monte Carlo reference (`envmap_reference.rs`) mixes it
//! with the BRDF's own sampling.

use crate::equirect::{dir_to_uv, luminance, uv_to_dir, Equirect};
use std::f64::consts::PI;

/// The map's luminance distribution: a marginal CDF over rows and a
/// conditional CDF per row.
#[derive(Clone, Debug, Default)]
pub(crate) struct EnvSampler {
    width: usize,
    height: usize,
    /// Row CDF, `height + 1` entries from 0 to 1.
    marginal: Vec<f64>,
    /// Per row, `width + 1` entries from 0 to 1.
    conditional: Vec<f32>,
    /// Each texel's probability.
    prob: Vec<f32>,
}

impl EnvSampler {
    /// The distribution of `map`'s luminance · sin θ; empty (no map
    /// sampling) for a black map.
    pub(crate) fn new(map: &Equirect) -> EnvSampler {
        let (w, h) = (map.width, map.height);
        let mut weights = vec![0.0f64; w * h];
        let mut total = 0.0;
        for j in 0..h {
            let sin_t = ((j as f64 + 0.5) / h as f64 * PI).sin();
            for i in 0..w {
                let x = luminance(map.texels[j * w + i]) as f64 * sin_t;
                weights[j * w + i] = x;
                total += x;
            }
        }
        if !(total > 0.0 && total.is_finite()) {
            return EnvSampler::default();
        }
        let mut marginal = Vec::with_capacity(h + 1);
        let mut conditional = Vec::with_capacity(h * (w + 1));
        let mut acc = 0.0;
        marginal.push(0.0);
        for j in 0..h {
            let row = &weights[j * w..(j + 1) * w];
            let row_sum: f64 = row.iter().sum();
            let mut c = 0.0;
            conditional.push(0.0);
            for x in row {
                c += x;
                let cdf = if row_sum > 0.0 { c / row_sum } else { 0.0 };
                conditional.push(cdf as f32);
            }
            *conditional.last_mut().unwrap_or(&mut 0.0) = 1.0;
            acc += row_sum;
            marginal.push(acc / total);
        }
        if let Some(m) = marginal.last_mut() {
            *m = 1.0;
        }
        let prob = weights.iter().map(|x| (x / total) as f32).collect();
        EnvSampler {
            width: w,
            height: h,
            marginal,
            conditional,
            prob,
        }
    }

    /// Whether the map has light to sample.
    pub(crate) fn is_empty(&self) -> bool {
        self.prob.is_empty()
    }

    /// A map direction from uniform numbers, with its texel's probability.
    pub(crate) fn sample(&self, u: [f64; 4]) -> [f64; 3] {
        let j = upper(&self.marginal, u[0]).min(self.height - 1);
        let row = &self.conditional[j * (self.width + 1)..(j + 1) * (self.width + 1)];
        let i = upper_f32(row, u[1] as f32).min(self.width - 1);
        uv_to_dir(
            (i as f64 + u[2]) / self.width as f64,
            (j as f64 + u[3]) / self.height as f64,
        )
    }

    /// Density per solid angle of sampling unit map direction `d`:
    /// P(texel) · W·H / (2π² sin θ).
    pub(crate) fn pdf(&self, d: [f64; 3]) -> f64 {
        let (u, v) = dir_to_uv(d.map(|x| x as f32));
        let i = ((u as f64 * self.width as f64) as usize).min(self.width - 1);
        let j = ((v as f64 * self.height as f64) as usize).min(self.height - 1);
        let sin_t = (1.0 - d[1] * d[1]).max(0.0).sqrt().max(1e-9);
        self.prob[j * self.width + i] as f64 * (self.width * self.height) as f64
            / (2.0 * PI * PI * sin_t)
    }
}

/// The index i with cdf[i] ≤ x < cdf[i + 1] (cdf ascending from 0).
fn upper(cdf: &[f64], x: f64) -> usize {
    cdf.partition_point(|&c| c <= x).saturating_sub(1)
}

fn upper_f32(cdf: &[f32], x: f32) -> usize {
    cdf.partition_point(|&c| c <= x).saturating_sub(1)
}
