//! The scalar reference of each source's measure (see the module docs of
//! [`crate::sobel`]): `measure` at one sample, clamped at the image's
//! edges, which the detection's 8-lane kernels match bit for bit; and,
//! for the tests, its lane form.

use super::inputs::EdgeInput;
use super::Source;
use specula_core::Real;

/// The Sobel weights (1, 2, 1)/4 across a derivative's direction.
pub(super) const W: [f32; 3] = [0.25, 0.5, 0.25];

/// The lane form of [`measure`] (the tests check the two agree): the
/// measure of source `s` at the `R::LANES` samples (x.., y) whose
/// neighbourhood rows start at `rows` (above, at, below; clamped by the
/// caller), for 1 ≤ x and x + LANES < width (no clamping along x). The
/// same operations in the same order as [`measure_at`].
#[cfg(test)]
#[inline(always)]
pub(super) fn measure_lanes<R: Real>(
    input: &EdgeInput,
    s: Source,
    rows: [usize; 3],
    x: usize,
) -> R {
    // The 3×3 neighbourhood of f, [row][column offset + 1] (row 0 above,
    // 2 below): one slice of LANES + 2 per row, each of the nine loads
    // once, so the bounds checks are three per field.
    let around = |f: &[f32]| {
        let mut n = [[R::ZERO; 3]; 3];
        for (r, nr) in n.iter_mut().enumerate() {
            let s = &f[rows[r] + x - 1..rows[r] + x + 1 + R::LANES];
            for (c, v) in nr.iter_mut().enumerate() {
                *v = R::load(&s[c..]);
            }
        }
        n
    };
    let wk = W.map(|v| R::splat(v as f64));
    let gradient = |f: &[f32]| {
        let n = around(f);
        let at = |r: usize, c: usize| n[r][c];
        let (mut gx, mut gy) = (R::ZERO, R::ZERO);
        for (k, &w) in wk.iter().enumerate() {
            gx += w * (at(k, 2) - at(k, 0));
            gy += w * (at(2, k) - at(0, k));
        }
        (gx, gy)
    };
    match s {
        Source::Depth => {
            let n = around(input.inv_depth);
            let at = |r: usize, c: usize| n[r][c];
            let two = R::splat(2.0);
            let (mut dxx, mut dyy, mut qmax) = (R::ZERO, R::ZERO, R::ZERO);
            for (k, &w) in wk.iter().enumerate() {
                dxx += w * (at(k, 2) + at(k, 0) - two * at(k, 1));
                dyy += w * (at(2, k) + at(0, k) - two * at(1, k));
                qmax = qmax.max(at(k, 0)).max(at(k, 1)).max(at(k, 2));
            }
            // Lanes with q_max = 0 divide 0 by 0; the select drops them.
            R::select(qmax.gt(R::ZERO), dxx.abs().max(dyy.abs()) / qmax, R::ZERO)
        }
        Source::Normal => {
            let mut g2 = R::ZERO;
            for c in input.normal {
                let (gx, gy) = gradient(c);
                g2 += gx * gx + gy * gy;
            }
            g2.sqrt()
        }
        Source::Id => {
            let n = around(input.material);
            let m = n[1][1];
            let mut f = R::ZERO;
            for (r, nr) in n.iter().enumerate() {
                for (c, &o) in nr.iter().enumerate() {
                    let weight = R::splat(if r == 1 || c == 1 { 2.0 } else { 1.0 });
                    f += R::select(o.lt(m) | o.gt(m), weight, R::ZERO);
                }
            }
            f / R::splat(12.0)
        }
        Source::Color => {
            let (gx, gy) = gradient(input.luma);
            (gx * gx + gy * gy).sqrt()
        }
    }
}

/// Sample indices of the 3×3 neighbourhood of (x, y), `[dy + 1][dx + 1]`,
/// clamped to the image.
#[cfg(test)]
#[inline]
fn neighbours(input: &EdgeInput, x: usize, y: usize) -> [[usize; 3]; 3] {
    let w = input.width;
    let xs = [x.saturating_sub(1), x, (x + 1).min(w - 1)];
    let ys = [y.saturating_sub(1), y, (y + 1).min(input.height - 1)];
    ys.map(|yy| xs.map(|xx| yy * w + xx))
}

/// Sobel gradient (Gx, Gy) of `f` over the neighbourhood `nb`, weights
/// (1, 2, 1)/4 across: a step of Δ gives Δ.
#[inline]
fn gradient(f: &[f32], nb: &[[usize; 3]; 3]) -> (f32, f32) {
    let (mut gx, mut gy) = (0.0, 0.0);
    for (k, wk) in W.iter().enumerate() {
        gx += wk * (f[nb[k][2]] - f[nb[k][0]]);
        gy += wk * (f[nb[2][k]] - f[nb[0][k]]);
    }
    (gx, gy)
}

/// The measure of one source at (x, y); see [`crate::sobel`]. The scalar
/// reference of the detection's row kernels (and of the lane form the
/// tests keep).
#[cfg(test)]
pub(crate) fn measure(input: &EdgeInput, s: Source, x: usize, y: usize) -> f32 {
    measure_at(input, s, &neighbours(input, x, y))
}

#[inline]
pub(super) fn measure_at(input: &EdgeInput, s: Source, nb: &[[usize; 3]; 3]) -> f32 {
    match s {
        Source::Depth => {
            let q = input.inv_depth;
            let (mut dxx, mut dyy, mut qmax) = (0.0f32, 0.0f32, 0.0f32);
            for (k, wk) in W.iter().enumerate() {
                dxx += wk * (q[nb[k][2]] + q[nb[k][0]] - 2.0 * q[nb[k][1]]);
                dyy += wk * (q[nb[2][k]] + q[nb[0][k]] - 2.0 * q[nb[1][k]]);
                // Real::max (a NaN self gives the other), as the lanes.
                qmax = Real::max(
                    Real::max(Real::max(qmax, q[nb[k][0]]), q[nb[k][1]]),
                    q[nb[k][2]],
                );
            }
            if qmax > 0.0 {
                Real::max(dxx.abs(), dyy.abs()) / qmax
            } else {
                0.0
            }
        }
        Source::Normal => {
            let mut g2 = 0.0;
            for c in input.normal {
                let (gx, gy) = gradient(c, nb);
                g2 += gx * gx + gy * gy;
            }
            g2.sqrt()
        }
        Source::Id => {
            let mat = input.material;
            let m = mat[nb[1][1]];
            let mut f = 0.0;
            for (r, row) in nb.iter().enumerate() {
                for (c, &i) in row.iter().enumerate() {
                    // Sides weigh 2, corners 1 (the centre never differs).
                    let weight = if r == 1 || c == 1 { 2.0 } else { 1.0 };
                    if mat[i] != m {
                        f += weight;
                    }
                }
            }
            f / 12.0
        }
        Source::Color => {
            let (gx, gy) = gradient(input.luma, nb);
            (gx * gx + gy * gy).sqrt()
        }
    }
}
