//! An equirectangular radiance image and its direction conventions.
//!
//! Directions: the map's centre column looks down −Z, +Y (the scene's up)
//! is the top row. A direction d = (sin θ sin φ, cos θ, −sin θ cos φ) is at
//! u = 1/2 + φ/2π, v = θ/π.

use specula_core::{Real, V3};

/// Largest radiance a texel keeps: larger values (and +inf) are clamped
/// to it, so sums over the map stay finite in f32.
pub const MAX_TEXEL: f32 = 1e9;

/// An equirectangular image, RGB per texel, row 0 at the top.
#[derive(Clone, Debug, Default)]
pub struct Equirect {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<[f32; 3]>,
}

impl Equirect {
    /// The texel at column `i` (wrapped) and row `j` (clamped).
    #[inline]
    fn at(&self, i: isize, j: isize) -> [f32; 3] {
        let i = i.rem_euclid(self.width as isize) as usize;
        let j = j.clamp(0, self.height as isize - 1) as usize;
        self.texels[j * self.width + i]
    }

    /// Bilinear radiance at (u, v) ∈ [0, 1]², wrapping in u.
    pub(crate) fn bilinear(&self, u: f32, v: f32) -> [f32; 3] {
        let x = u * self.width as f32 - 0.5;
        let y = v * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (i, j) = (x0 as isize, y0 as isize);
        let t = [
            self.at(i, j),
            self.at(i + 1, j),
            self.at(i, j + 1),
            self.at(i + 1, j + 1),
        ];
        std::array::from_fn(|c| {
            let a = t[0][c] + (t[1][c] - t[0][c]) * fx;
            let b = t[2][c] + (t[3][c] - t[2][c]) * fx;
            a + (b - a) * fy
        })
    }

    /// The texel containing (u, v) (the map as a piecewise-constant
    /// function: what the reference integrates).
    pub(crate) fn nearest(&self, u: f32, v: f32) -> [f32; 3] {
        let i = ((u * self.width as f32) as isize).min(self.width as isize - 1);
        let j = (v * self.height as f32) as isize;
        self.at(i.max(0), j)
    }

    /// The radiance toward unit map direction `d`: the texel containing
    /// it, as the reference reads the map (for checks and tests).
    pub fn radiance_toward(&self, d: [f32; 3]) -> [f32; 3] {
        let (u, v) = dir_to_uv(d);
        self.nearest(u, v)
    }

    /// The next mip: 2×2 box (a single column or row is kept as is).
    pub(crate) fn half(&self) -> Equirect {
        let (w, h) = ((self.width / 2).max(1), (self.height / 2).max(1));
        let (sx, sy) = (self.width / w, self.height / h);
        let mut texels = Vec::with_capacity(w * h);
        for j in 0..h {
            for i in 0..w {
                let mut s = [0.0f32; 3];
                for dy in 0..sy {
                    for dx in 0..sx {
                        let t = self.texels[(j * sy + dy) * self.width + i * sx + dx];
                        for c in 0..3 {
                            s[c] += t[c];
                        }
                    }
                }
                let k = 1.0 / (sx * sy) as f32;
                texels.push(s.map(|x| x * k));
            }
        }
        Equirect {
            width: w,
            height: h,
            texels,
        }
    }
}

/// Map direction of any nonzero length → (u, v), per lane: u as
/// [`dir_to_uv`]'s, v = acos(y / |d|) / π as atan2(√(x² + z²), y) / π
/// (accurate near the poles too, and no normalisation); checked against
/// the definition in f64 by `lane_uv_matches_the_definition`.
#[inline(always)]
pub(crate) fn dir_to_uv_lanes<R: Real>(d: V3<R>) -> (R, R) {
    let u =
        d.x.atan2(-d.z)
            .mul_add(R::splat(0.5 * std::f64::consts::FRAC_1_PI), R::HALF);
    let sin = d.x.mul_add(d.x, d.z * d.z).sqrt();
    let v = sin.atan2(d.y) * R::FRAC_1_PI;
    (u.clamp(R::ZERO, R::ONE), v.clamp(R::ZERO, R::ONE))
}

/// Unit map direction → (u, v).
#[inline]
pub(crate) fn dir_to_uv(d: [f32; 3]) -> (f32, f32) {
    let u = 0.5 + d[0].atan2(-d[2]) * (0.5 * std::f32::consts::FRAC_1_PI);
    let v = d[1].clamp(-1.0, 1.0).acos() * std::f32::consts::FRAC_1_PI;
    (u.clamp(0.0, 1.0), v.clamp(0.0, 1.0))
}

/// (u, v) → unit map direction.
#[inline]
pub fn uv_to_dir(u: f64, v: f64) -> [f64; 3] {
    let (theta, phi) = (v * std::f64::consts::PI, (u - 0.5) * std::f64::consts::TAU);
    let s = theta.sin();
    [s * phi.sin(), theta.cos(), -s * phi.cos()]
}

/// Rec. 709 luminance.
#[inline]
pub(crate) fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// A texel's documented clamping: NaN and negative → 0, above
/// [`MAX_TEXEL`] (and +inf) → [`MAX_TEXEL`].
#[inline]
pub(crate) fn clamp_texel(c: f32) -> f32 {
    if c.is_nan() {
        0.0
    } else {
        c.clamp(0.0, MAX_TEXEL)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use specula_core::f32x8;

    /// The lanes' (u, v) against the convention in f64 (u = 1/2 +
    /// atan2(x, −z)/2π, v = acos(y/|d|)/π) over a grid of directions
    /// with the poles, the seam behind the map's centre and lengths from
    /// 1e-3 to 1e3.
    #[test]
    fn lane_uv_matches_the_definition() {
        let mut worst = 0.0f64;
        for i in 0..=64 {
            let theta = i as f64 * std::f64::consts::PI / 64.0;
            for j in 0..96 {
                let phi = (j as f64 - 48.0) * std::f64::consts::TAU / 96.0 + 1e-3 * i as f64;
                let scale = [1e-3, 1.0, 1e3][(i + j) % 3];
                let d = [
                    (theta.sin() * phi.sin() * scale) as f32,
                    (theta.cos() * scale) as f32,
                    (-theta.sin() * phi.cos() * scale) as f32,
                ];
                let (u, v) = dir_to_uv_lanes(V3::new(
                    f32x8::splat(d[0]),
                    f32x8::splat(d[1]),
                    f32x8::splat(d[2]),
                ));
                let (x, y, z) = (d[0] as f64, d[1] as f64, d[2] as f64);
                let len = (x * x + y * y + z * z).sqrt();
                let want_u = 0.5 + x.atan2(-z) / std::f64::consts::TAU;
                let want_v = (y / len).clamp(-1.0, 1.0).acos() / std::f64::consts::PI;
                // atan2's branch cut: ±1/2 of a turn are the same column.
                let du = (u.lane(5) - want_u).abs();
                worst = worst
                    .max(du.min((du - 1.0).abs()))
                    .max((v.lane(2) - want_v).abs());
            }
        }
        assert!(worst < 3e-7, "worst |uv − f64| = {worst:e}");
    }
}
