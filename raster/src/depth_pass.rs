//! Depth-only passes (a shadow map's): the scene's main triangles through
//! a light's view-projection into a depth buffer, by the camera pass's
//! vertex stage, setup, binning and scan, keeping only what depth needs.
//! Both faces are drawn, except those of closed solids the light is
//! outside of, whose back faces are culled (`closed.rs`: the nearest depth
//! is a front face's).
//!
//! Two cuts against the camera's pass (`frame::geometry_pass`), neither
//! changing a depth bit (`tests/shadows.rs` compares every texel of each
//! light kind's maps against the full pass):
//! - setup keeps each triangle's depth plane alone ([`DepthPlanes`]: 20
//!   bytes a triangle written and read back by the scan, not 60), and the
//!   scan writes no ids;
//! - triangles whose three vertices lie beyond one plane of the light's
//!   frustum (setup's own outside test, on outcodes taken once a vertex)
//!   skip setup four at a time, before their vertices are gathered;
//! - the scan draws each tile into a scratch tile and writes it at once,
//!   as linear depth, into the row-major map: no tile-major depth buffer
//!   of the map's size is cleared, written and read back.
//!
//! A scene with masked or blended materials takes the full pass: its
//! alpha test reads the barycentric planes.

use crate::bin::{BinnedChunk, CHUNK};
use crate::camera::View;
use crate::clip::GuardBand;
use crate::closed::depth_cull;
use crate::geometry::{Cull, GeometryPass};
use crate::scan::{rasterize_tile_depth, AlphaScan};
use crate::scene::SceneData;
use crate::setup::{outcode_f32, DepthPlanes, SetupContext, SetupCounts};
use crate::setup_x4::{Vertices4, LANES};
use crate::stats::{count_setup_sweep, ms_since, FrameStats};
use crate::target::{Target, VisBuffer, TILE, TILE_PIXELS};
use crate::visibility::{geometry_pass, Visibility};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// Which setup a depth pass runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DepthSetup {
    /// Depth planes only, outside triangles skipped before setup (the
    /// default; scenes with alpha materials still take `Full`).
    #[default]
    DepthOnly,
    /// The camera pass's setup and scan, every plane and id: the
    /// reference the depth-only pass is tested against.
    Full,
}

/// How a depth pass's NDC depth becomes a map's linear depth (along the
/// light's axis; infinity where nothing was drawn, NDC depth ≤ 0).
#[derive(Clone, Copy, Debug)]
pub(crate) enum LinearDepth {
    /// NDC depth = near / depth.
    Perspective { near: f32 },
    /// NDC depth = 1 − (depth − near) / span.
    Orthographic { near: f32, span: f32 },
}

impl LinearDepth {
    /// `out[i]` = the linear depth of NDC depth `z[i]`, for every i <
    /// `out.len()` ≤ `z.len()`.
    fn convert(self, out: &mut [f32], z: &[f32]) {
        match self {
            LinearDepth::Perspective { near } => {
                for (d, &z) in out.iter_mut().zip(z) {
                    *d = if z <= 0.0 { f32::INFINITY } else { near / z };
                }
            }
            LinearDepth::Orthographic { near, span } => {
                for (d, &z) in out.iter_mut().zip(z) {
                    *d = if z <= 0.0 {
                        f32::INFINITY
                    } else {
                        near + (1.0 - z) * span
                    };
                }
            }
        }
    }
}

/// A depth-only pass of the scene's main triangles seen through
/// `view_proj` from `eye` (a point or spot light's position and the
/// distance from it to the near plane's corners; `None` for a directional
/// light) into `map` (row-major, `target`'s width × height) as `linear`
/// depth, with its buffers in `out` (made on first use, reused after);
/// counted in `stats` as a shadow pass (`render_maps` times them all).
#[allow(clippy::too_many_arguments)]
pub(crate) fn depth_pass(
    scene: &SceneData,
    target: &Target,
    view_proj: glam::Mat4,
    eye: Option<(glam::Vec3, f32)>,
    setup: DepthSetup,
    out: &mut Option<Visibility>,
    map: &mut [f32],
    linear: LinearDepth,
    stats: &mut FrameStats,
) {
    let view = View {
        view_proj,
        eye: glam::Vec3::ZERO,
        right: glam::Vec3::X,
        up: glam::Vec3::Y,
        forward: glam::Vec3::NEG_Z,
        tan_x: 1.0,
        tan_y: 1.0,
        width: target.width as f32,
        height: target.height as f32,
    };
    let v = out.get_or_insert_with(|| Visibility::empty(target, view.clone()));
    v.view = view;
    match scene.solids() {
        Some(solids) if solids.any() => solids.cull_back_mask(eye, &mut v.cull_back),
        _ => v.cull_back.clear(),
    }
    let triangles = scene.geometry.first().map_or(0..0, |p| p.triangles.clone());
    let stage = match v.stages.first() {
        Some((s, _)) => s.clone(),
        None => Arc::new(crate::geometry::Project),
    };
    let pass = GeometryPass {
        name: "shadow".into(),
        vertex: stage,
        cull: Cull::None,
        triangles,
        id_base: 0,
        material: None,
    };
    // The pass's setup counts (its stage times are not read: `render_maps`
    // times the shadow maps whole).
    let mut own = FrameStats::default();
    if setup == DepthSetup::Full || AlphaScan::new(scene, false).is_some() {
        if v.vis.id.len() != target.buffer_len() {
            v.vis = VisBuffer::new(target);
        }
        crate::buffers::resize_zeroed(&mut v.planes, pass.ids().end as usize);
        // The first pass of its buffer: it clears it and tests against nothing.
        geometry_pass(scene, target, &pass, 0, false, &mut true, v, &mut own, true);
        let depth = &v.vis.depth;
        write_map(target, map, linear, |tile, out| {
            out.copy_from_slice(&depth[tile * TILE_PIXELS..(tile + 1) * TILE_PIXELS]);
        });
    } else {
        // This path never reads the tile-major buffer: free one a full
        // pass left.
        v.vis = VisBuffer::default();
        depth_only_pass(scene, target, &pass, v, map, linear, &mut own);
    }
    stats.shadow_passes += 1;
    stats.shadow_counts.add(&own.counts);
}

/// Fills `map` (row-major, `target`'s size) with the `linear` depth of
/// each tile, a band of tile rows per task: `tile(t, depth)` puts tile
/// `t`'s NDC depth (row-major in the tile) into `depth`.
fn write_map(
    target: &Target,
    map: &mut [f32],
    linear: LinearDepth,
    tile: impl Fn(usize, &mut [f32; TILE_PIXELS]) + Sync,
) {
    let width = target.width as usize;
    let tiles_x = target.tiles_x as usize;
    map.par_chunks_mut(width * TILE)
        .enumerate()
        .for_each(|(ty, band)| {
            let mut depth = [0.0; TILE_PIXELS];
            for tx in 0..tiles_x {
                tile(ty * tiles_x + tx, &mut depth);
                let x0 = tx * TILE;
                let run = TILE.min(width - x0);
                for (r, row) in band.chunks_exact_mut(width).enumerate() {
                    linear.convert(&mut row[x0..x0 + run], &depth[r * TILE..]);
                }
            }
        });
}

/// `geometry_pass` of a first pass with `Cull::None` (but the back faces
/// of the triangles in `out.cull_back`) and no alpha materials, keeping
/// depth alone, written to `map` as `linear` depth (see the module doc).
fn depth_only_pass(
    scene: &SceneData,
    target: &Target,
    pass: &GeometryPass,
    out: &mut Visibility,
    map: &mut [f32],
    linear: LinearDepth,
    stats: &mut FrameStats,
) {
    out.vertex_stage(scene, target, pass, false);
    let clip = &out.clip;
    out.outcodes.resize(clip.len(), 0);
    out.outcodes
        .par_chunks_mut(CHUNK)
        .zip(clip.par_chunks(CHUNK))
        .for_each(|(codes, clip)| {
            for (c, p) in codes.iter_mut().zip(clip) {
                *c = outcode_f32(p);
            }
        });
    let outcodes = &out.outcodes;
    let cull_back = &out.cull_back[..];

    let t = Instant::now();
    let ctx = SetupContext {
        width: target.width,
        height: target.height,
        guard: GuardBand::for_image(target.width, target.height),
    };
    let range = pass.triangles.start as usize..pass.triangles.end as usize;
    let ids = pass.ids();
    crate::buffers::resize_zeroed(&mut out.depth_planes, ids.end as usize);
    let n_chunks = range.len().div_ceil(CHUNK);
    if out.chunks.len() < n_chunks {
        out.chunks.resize_with(n_chunks, BinnedChunk::default);
    }
    let chunks = &mut out.chunks[..n_chunks];
    let set_up: Vec<(SetupCounts, f64)> = scene.triangles[range.clone()]
        .par_chunks(CHUNK)
        .zip(out.depth_planes[ids.start as usize..ids.end as usize].par_chunks_mut(CHUNK))
        .zip(chunks.par_iter_mut())
        .enumerate()
        .map(|(c, ((tris, planes), chunk))| {
            let raster = &mut chunk.tris;
            raster.clear();
            let mut counts = SetupCounts::default();
            let base = c * CHUNK;
            let id = |i: usize| ids.start as u32 + (base + i) as u32;
            let cull = |i: usize| depth_cull(cull_back, range.start + base + i);
            // Setup's trivial reject: all three vertices beyond one plane.
            let outside = |&[a, b, c]: &[u32; 3]| {
                outcodes[a as usize] & outcodes[b as usize] & outcodes[c as usize] != 0
            };
            let quads = tris.len() / LANES * LANES;
            for (q, (tris4, planes4)) in tris[..quads]
                .chunks_exact(LANES)
                .zip(planes[..quads].chunks_exact_mut(LANES))
                .enumerate()
            {
                if tris4.iter().all(outside) {
                    counts.triangles += LANES as u64;
                    counts.culled_outside += LANES as u64;
                    continue;
                }
                let v = Vertices4::gather(clip, tris4.try_into().expect("chunks of LANES"));
                let planes4 = planes4.try_into().expect("chunks of LANES");
                let i = q * LANES;
                ctx.setup_x4_vertices(
                    id(i),
                    &v,
                    [cull(i), cull(i + 1), cull(i + 2), cull(i + 3)],
                    None,
                    planes4,
                    raster,
                    &mut counts,
                );
            }
            for (i, (tri, plane)) in tris.iter().zip(planes.iter_mut()).enumerate().skip(quads) {
                let v = tri.map(|k| clip[k as usize]);
                if let Some(p) = ctx.setup(id(i), v, cull(i), raster, &mut counts) {
                    *plane = DepthPlanes {
                        origin: p.origin,
                        z: p.z,
                    };
                }
            }
            let tb = Instant::now();
            chunk.bin(target);
            (counts, ms_since(tb))
        })
        .collect();
    count_setup_sweep(stats, t, &set_up, chunks);
    let chunks = &*chunks;

    let planes = &out.depth_planes;
    write_map(target, map, linear, |tile, depth| {
        depth.fill(0.0);
        rasterize_tile_depth(target, tile, chunks, planes, depth);
    });
}
