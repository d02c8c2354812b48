//! A shadow map's depth bounds over every window of texels a PCF lookup
//! may read ([`DepthWindows`]), filled after its depth pass: what lets a
//! PCF lookup decide wholly lit and wholly shadowed points without
//! reading its taps (`lanes.rs`).

use super::DepthWindows;
use rayon::prelude::*;
use wide::f32x8;

impl DepthWindows {
    /// The bounds of the `n` × `n` row-major `depth` over its windows of
    /// `window` × `window` texels (the buffers of an earlier frame
    /// refilled).
    pub(crate) fn fill(&mut self, depth: &[f32], n: usize, window: u32) {
        let w = window as usize;
        self.window = window;
        crate::buffers::resize_zeroed(&mut self.near, n * n);
        crate::buffers::resize_zeroed(&mut self.far, n * n);
        // Down the columns first, an output row per task reading the w
        // rows from its own into two scratch rows; then along those rows.
        self.near
            .par_chunks_mut(n)
            .zip(self.far.par_chunks_mut(n))
            .enumerate()
            .for_each_init(
                || (Vec::new(), Vec::new()),
                |(lo, hi), (y, (near, far))| {
                    let rows = &depth[y * n..(y + w).min(n) * n];
                    lo.resize(n, 0.0);
                    hi.resize(n, 0.0);
                    column_bounds(lo, hi, rows);
                    row_bounds(near, far, lo, hi, w);
                },
            );
    }
}

/// Lanes a bound is taken over at once.
const LANES: usize = 8;

/// `s[at..at + LANES]` as one vector.
#[inline(always)]
fn load(s: &[f32], at: usize) -> f32x8 {
    f32x8::from(<[f32; LANES]>::try_from(&s[at..at + LANES]).expect("LANES floats"))
}

/// Writes `v` to `s[at..at + LANES]`.
#[inline(always)]
fn store(s: &mut [f32], at: usize, v: f32x8) {
    s[at..at + LANES].copy_from_slice(&v.to_array());
}

/// `lo[x]` = the least and `hi[x]` the greatest of column x of `rows`
/// (one or more rows of `lo.len()` texels, back to back), for every x.
/// Depths are never NaN (finite, or infinity where nothing was drawn), so
/// the vector min and max and a plain comparison pick the same texel; a
/// run of lanes keeps its bounds in registers over all the rows.
fn column_bounds(lo: &mut [f32], hi: &mut [f32], rows: &[f32]) {
    let n = lo.len();
    let k = rows.len() / n;
    let runs = n / LANES * LANES;
    for x in (0..runs).step_by(LANES) {
        let first = load(rows, x);
        let (mut a, mut b) = (first, first);
        for j in 1..k {
            let v = load(rows, j * n + x);
            a = a.fast_min(v);
            b = b.fast_max(v);
        }
        store(lo, x, a);
        store(hi, x, b);
    }
    for x in runs..n {
        let column = rows[x..].iter().step_by(n).take(k);
        (lo[x], hi[x]) = (least(column.clone()), greatest(column));
    }
}

/// `near[x]` = the least of `lo[x..x + w]` and `far[x]` the greatest of
/// `hi[x..x + w]`, each cut to the row (a window is cut to the map, as a
/// lookup's reads are clamped to it), for every x < `near.len()` (the
/// length of all four).
fn row_bounds(near: &mut [f32], far: &mut [f32], lo: &[f32], hi: &[f32], w: usize) {
    let n = near.len();
    // Windows wholly inside the row start at 0..whole; runs of LANES of
    // them read w vectors from each input.
    let whole = (n + 1).saturating_sub(w);
    let runs = whole / LANES * LANES;
    for x in (0..runs).step_by(LANES) {
        let (mut a, mut b) = (load(lo, x), load(hi, x));
        for i in 1..w {
            a = a.fast_min(load(lo, x + i));
            b = b.fast_max(load(hi, x + i));
        }
        store(near, x, a);
        store(far, x, b);
    }
    for x in runs..n {
        let end = (x + w).min(n);
        (near[x], far[x]) = (least(lo[x..end].iter()), greatest(hi[x..end].iter()));
    }
}

/// The least of `v` (infinity if empty).
fn least<'a>(v: impl Iterator<Item = &'a f32>) -> f32 {
    v.fold(f32::INFINITY, |a, &v| if v < a { v } else { a })
}

/// The greatest of `v` (minus infinity if empty).
fn greatest<'a>(v: impl Iterator<Item = &'a f32>) -> f32 {
    v.fold(f32::NEG_INFINITY, |b, &v| if v > b { v } else { b })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Every window's bounds against the least and greatest depth found
    /// by visiting its texels one by one (cut to the map), on maps whose
    /// sides are and are not multiples of eight, windows wider than the
    /// map included, with empty texels (infinity) among the depths; one
    /// set of bounds refilled for every map, as frames reuse theirs.
    #[test]
    fn window_bounds_are_the_least_and_greatest_texel() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let mut bounds = DepthWindows::default();
        let sizes = [
            (1, 1),
            (5, 3),
            (8, 5),
            (13, 5),
            (24, 1),
            (37, 9),
            (9, 16),
            (70, 5),
        ];
        for (n, window) in sizes {
            let depth: Vec<f32> = (0..n * n)
                .map(|_| match rng.random_range(0..5) {
                    0 => f32::INFINITY,
                    _ => rng.random_range(0.1..50.0),
                })
                .collect();
            bounds.fill(&depth, n, window);
            let (w, depth) = (window as usize, &depth);
            for y in 0..n {
                for x in 0..n {
                    let texels = (y..(y + w).min(n))
                        .flat_map(|j| (x..(x + w).min(n)).map(move |i| depth[j * n + i]));
                    let lo = texels.clone().fold(f32::INFINITY, f32::min);
                    let hi = texels.fold(f32::NEG_INFINITY, f32::max);
                    let at = y * n + x;
                    assert_eq!(
                        (bounds.near[at], bounds.far[at]),
                        (lo, hi),
                        "n {n}, window {w}, texel ({x}, {y})"
                    );
                }
            }
        }
    }
}
