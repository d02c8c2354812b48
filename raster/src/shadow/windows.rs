//! A shadow map's depth bounds over every window of texels a PCF lookup
//! may read ([`DepthWindows`]), filled after its depth pass: what lets a
//! PCF lookup decide wholly lit and wholly shadowed points without
//! reading its taps (`lanes.rs`).

use super::DepthWindows;
use rayon::prelude::*;

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
                    sweep(lo, hi, rows, rows, n, w);
                    sweep(near, far, lo, hi, 1, w);
                },
            );
    }
}

/// `near[x]` = the least of `lo[x + i·stride]` and `far[x]` the greatest
/// of `hi[x + i·stride]` for i in 0..`w`, of those that exist (a window is
/// cut to the input, as a lookup's reads are clamped to the map), for
/// every x < `near.len()` = `far.len()` ≤ the inputs' length (the same
/// for both). Both bounds in one pass over whole slices, so the loops
/// are vector loops. Depths are never NaN (finite, or infinity where
/// nothing was drawn), so a plain comparison picks.
fn sweep(near: &mut [f32], far: &mut [f32], lo: &[f32], hi: &[f32], stride: usize, w: usize) {
    let len = near.len();
    near.copy_from_slice(&lo[..len]);
    far.copy_from_slice(&hi[..len]);
    for i in 1..w {
        let start = (i * stride).min(lo.len());
        let pairs = near.iter_mut().zip(far.iter_mut());
        for ((a, b), (&l, &h)) in pairs.zip(lo[start..].iter().zip(&hi[start..])) {
            *a = if l < *a { l } else { *a };
            *b = if h > *b { h } else { *b };
        }
    }
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
        for (n, window) in [(1, 1), (5, 3), (8, 5), (13, 5), (24, 1), (37, 9), (9, 16)] {
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
