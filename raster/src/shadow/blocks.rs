//! A shadow map's depth bounds over blocks of texels ([`DepthBlocks`]),
//! filled after its depth pass: what lets a PCF lookup decide wholly lit
//! and wholly shadowed points without reading its taps (`lanes.rs`).

use super::DepthBlocks;
use rayon::prelude::*;

impl DepthBlocks {
    /// The bounds of the `n` × `n` row-major `depth` over blocks of
    /// `side` texels (the buffers of an earlier frame refilled).
    pub(crate) fn fill(&mut self, depth: &[f32], n: usize, side: u32) {
        let b = side as usize;
        let m = n.div_ceil(b);
        self.side = side;
        self.count = m as u32;
        self.near.clear();
        self.near.resize(m * m, f32::INFINITY);
        self.far.clear();
        self.far.resize(m * m, f32::NEG_INFINITY);
        // Each block's own bounds, a row of blocks per task.
        self.near
            .par_chunks_mut(m)
            .zip(self.far.par_chunks_mut(m))
            .enumerate()
            .for_each(|(j, (near, far))| {
                for row in depth[j * b * n..((j + 1) * b).min(n) * n].chunks_exact(n) {
                    for ((lo, hi), texels) in near.iter_mut().zip(far.iter_mut()).zip(row.chunks(b))
                    {
                        for &z in texels {
                            *lo = lo.min(z);
                            *hi = hi.max(z);
                        }
                    }
                }
            });
        // Then over each block and its neighbours right and down (in
        // place: each entry reads ones not yet overwritten).
        sweep(&mut self.near, m, f32::min);
        sweep(&mut self.far, m, f32::max);
    }
}

/// `v` (m × m, row-major) replaced by `pick` over each entry and its
/// neighbours right, down and diagonal (where they exist), in place.
fn sweep(v: &mut [f32], m: usize, pick: fn(f32, f32) -> f32) {
    for row in v.chunks_exact_mut(m) {
        for i in 0..m - 1 {
            row[i] = pick(row[i], row[i + 1]);
        }
    }
    for j in 0..m - 1 {
        let (top, rest) = v[j * m..].split_at_mut(m);
        for (a, b) in top.iter_mut().zip(&rest[..m]) {
            *a = pick(*a, *b);
        }
    }
}
