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
