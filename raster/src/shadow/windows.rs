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
        self.near.resize(n * n, 0.0);
        self.far.resize(n * n, 0.0);
        // Down the columns first, an output row per task reading the w
        // rows from its own; then along each row in place (from a copy).
        self.near
            .par_chunks_mut(n)
            .zip(self.far.par_chunks_mut(n))
            .enumerate()
            .for_each_init(Vec::new, |row, (y, (near, far))| {
                let rows = &depth[y * n..(y + w).min(n) * n];
                sweep(near, rows, n, w, f32::min);
                sweep(far, rows, n, w, f32::max);
                for (out, pick) in [(near, f32::min as fn(f32, f32) -> f32), (far, f32::max)] {
                    row.clear();
                    row.extend_from_slice(out);
                    sweep(out, row, 1, w, pick);
                }
            });
    }
}

/// `out[x]` = `pick` over `v[x + i·stride]` for i in 0..`w`, of those
/// that exist (a window is cut to `v`, as a lookup's reads are clamped to
/// the map), for every x < `out.len()` ≤ `v.len()`. Whole slices at a
/// time, so the loops are vector loops.
fn sweep(out: &mut [f32], v: &[f32], stride: usize, w: usize, pick: fn(f32, f32) -> f32) {
    let len = out.len();
    out.copy_from_slice(&v[..len]);
    for i in 1..w {
        let from = &v[(i * stride).min(v.len())..];
        for (o, &z) in out.iter_mut().zip(from) {
            *o = pick(*o, z);
        }
    }
}
