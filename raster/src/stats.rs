//! What a frame counts and times ([`FrameStats`]): each pass's wall
//! time, summed over a frame's geometry passes per stage, setup's counts,
//! and the shadow maps (their time whole, their depth passes' counts).

use crate::bin::BinnedChunk;
use crate::setup::SetupCounts;
use std::time::Instant;

/// Wall time of each pass in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassTimes {
    pub vertex: f64,
    pub setup: f64,
    pub bin: f64,
    pub raster: f64,
    pub shade: f64,
    /// The shadow maps: fitting each light's faces, their depth passes
    /// (all stages), linear depth and PCF window bounds.
    pub shadow: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    pub times: PassTimes,
    pub counts: SetupCounts,
    /// Screen triangles after clipping and fan splitting.
    pub raster_triangles: u64,
    /// Pixels (samples) covered by a triangle and shaded.
    pub pixels_shaded: u64,
    /// Samples of blended (alphaMode BLEND) surfaces shaded and composited
    /// over the opaque frame: a sample under k of them counts k times.
    pub blended_samples: u64,
    /// Shadow-map depth passes drawn (a cube map is 6, less its faces
    /// that see nothing).
    pub shadow_passes: u32,
    /// Shadow-map faces that see nothing of the scene, given an empty map
    /// without a depth pass.
    pub shadow_faces_blank: u32,
    /// Setup's counts over those depth passes (not in `counts`).
    pub shadow_counts: SetupCounts,
}

pub(crate) fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Adds to `stats` a setup-and-bin sweep that started at `t`: each
/// chunk's setup counts and binning time (`set_up`) and its screen
/// triangles (`chunks`). The sweep's wall time is split: binning's share
/// is the chunks' binning time (thread time) over the worker count.
pub(crate) fn count_setup_sweep(
    stats: &mut FrameStats,
    t: Instant,
    set_up: &[(SetupCounts, f64)],
    chunks: &[BinnedChunk],
) {
    let total = ms_since(t);
    let busy: f64 = set_up.iter().map(|(_, b)| b).sum();
    let bin = (busy / rayon::current_num_threads() as f64).min(total);
    stats.times.setup += total - bin;
    stats.times.bin += bin;
    for ((c, _), chunk) in set_up.iter().zip(chunks) {
        stats.counts.add(c);
        stats.raster_triangles += chunk.tris.len() as u64;
    }
}
