//! One frame, pass by pass: vertex → clip + setup → bin → raster (visibility
//! buffer) → resolve + shade. Each pass is timed; parallel work is split in
//! fixed pieces (vertex and setup chunks, tiles) so that the result does not
//! depend on the thread count.

use crate::bin::{bin_chunk, BinnedChunk, CHUNK};
use crate::camera::View;
use crate::clip::GuardBand;
use crate::resolve::ResolveContext;
use crate::scan::rasterize_tile;
use crate::scene::SceneData;
use crate::setup::{SetupContext, SetupCounts, TriPlanes};
use crate::shade::{shade_tile, ColorBuffer};
use crate::target::{Target, VisBuffer, MISS, TILE_PIXELS};
use glam::Vec4;
use rayon::prelude::*;
use specula_core::f32x8;
use std::time::Instant;

/// Wall time of each pass in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassTimes {
    pub vertex: f64,
    pub setup: f64,
    pub bin: f64,
    pub raster: f64,
    pub shade: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    pub times: PassTimes,
    pub counts: SetupCounts,
    /// Screen triangles after clipping and fan splitting.
    pub raster_triangles: u64,
    /// Pixels (samples) covered by a triangle and shaded.
    pub pixels_shaded: u64,
}

/// The visibility pass's output, reusable from frame to frame: passing the
/// previous frame's `Visibility` to [`visibility_into`] overwrites it without
/// allocating (no page faults in steady state).
pub struct Visibility {
    pub vis: VisBuffer,
    /// Per source triangle; meaningful for triangles drawn this frame (the
    /// only ones the visibility buffer can name).
    pub planes: Vec<TriPlanes>,
    pub view: View,
    clip: Vec<[f32; 4]>,
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Vertex through visibility buffer, in the calling rayon pool.
pub fn visibility(scene: &SceneData, target: &Target, stats: &mut FrameStats) -> Visibility {
    let mut v = Visibility {
        vis: VisBuffer::new(target),
        planes: Vec::new(),
        view: scene.camera.view(target.width, target.height),
        clip: Vec::new(),
    };
    visibility_into(scene, target, &mut v, stats);
    v
}

/// [`visibility`] into the buffers of an earlier frame of the same target.
pub fn visibility_into(
    scene: &SceneData,
    target: &Target,
    out: &mut Visibility,
    stats: &mut FrameStats,
) {
    assert_eq!(
        out.vis.id.len(),
        target.buffer_len(),
        "visibility buffers are for another target"
    );
    out.view = scene.camera.view(target.width, target.height);

    let t = Instant::now();
    let m = out.view.view_proj;
    out.clip.clear();
    scene
        .positions
        .par_iter()
        .with_min_len(4096)
        .map(|p| (m * Vec4::from((*p, 1.0))).to_array())
        .collect_into_vec(&mut out.clip);
    let clip = &out.clip;
    stats.times.vertex = ms_since(t);

    let t = Instant::now();
    let ctx = SetupContext {
        width: target.width,
        height: target.height,
        guard: GuardBand::for_image(target.width, target.height),
    };
    out.planes
        .resize(scene.triangles.len(), TriPlanes::default());
    let set_up: Vec<(Vec<crate::setup::RasterTri>, SetupCounts)> = scene
        .triangles
        .par_chunks(CHUNK)
        .zip(out.planes.par_chunks_mut(CHUNK))
        .enumerate()
        .map(|(c, (tris, planes))| {
            let mut raster = Vec::with_capacity(tris.len());
            let mut counts = SetupCounts::default();
            for (i, (tri, plane)) in tris.iter().zip(planes.iter_mut()).enumerate() {
                let id = (c * CHUNK + i) as u32;
                let v = tri.map(|k| clip[k as usize]);
                let double_sided =
                    scene.materials[scene.tri_material[id as usize] as usize].double_sided;
                if let Some(p) = ctx.setup(id, v, double_sided, &mut raster, &mut counts) {
                    *plane = p;
                }
            }
            (raster, counts)
        })
        .collect();
    stats.times.setup = ms_since(t);

    let t = Instant::now();
    for (tris, c) in &set_up {
        stats.counts.add(c);
        stats.raster_triangles += tris.len() as u64;
    }
    let chunks: Vec<BinnedChunk> = set_up
        .into_par_iter()
        .map(|(tris, _)| bin_chunk(target, tris))
        .collect();
    stats.times.bin = ms_since(t);

    let t = Instant::now();
    let planes = &out.planes;
    out.vis
        .depth
        .par_chunks_mut(TILE_PIXELS)
        .zip(out.vis.id.par_chunks_mut(TILE_PIXELS))
        .enumerate()
        .for_each(|(tile, (depth, ids))| {
            // Cleared here, while the tile is about to be in cache anyway.
            depth.fill(1.0);
            ids.fill(MISS);
            rasterize_tile(target, tile, &chunks, planes, depth, ids)
        });
    stats.times.raster = ms_since(t);
}

/// Lane width of the shading pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ShadePath {
    /// 8 pixels per packet in f32x8.
    #[default]
    Simd,
    /// One pixel at a time in f32: the same kernels, for comparison.
    Scalar,
}

impl ColorBuffer {
    pub fn new(target: &Target) -> ColorBuffer {
        let n = target.buffer_len();
        ColorBuffer {
            r: vec![0.0; n],
            g: vec![0.0; n],
            b: vec![0.0; n],
        }
    }
}

/// Resolve + shade every tile, in the calling rayon pool.
pub fn shade(
    scene: &SceneData,
    target: &Target,
    v: &Visibility,
    path: ShadePath,
    stats: &mut FrameStats,
) -> ColorBuffer {
    let mut color = ColorBuffer::new(target);
    shade_into(scene, target, v, path, &mut color, stats);
    color
}

/// [`shade`] into the colour buffer of an earlier frame of the same target.
pub fn shade_into(
    scene: &SceneData,
    target: &Target,
    v: &Visibility,
    path: ShadePath,
    color: &mut ColorBuffer,
    stats: &mut FrameStats,
) {
    let t = Instant::now();
    let ctx = ResolveContext {
        scene,
        planes: &v.planes,
        view: &v.view,
    };
    let covered: u64 = color
        .r
        .par_chunks_mut(TILE_PIXELS)
        .zip(color.g.par_chunks_mut(TILE_PIXELS))
        .zip(color.b.par_chunks_mut(TILE_PIXELS))
        .zip(v.vis.id.par_chunks(TILE_PIXELS))
        .enumerate()
        .map(|(tile, (((r, g), b), ids))| match path {
            ShadePath::Simd => shade_tile::<f32x8>(&ctx, target, tile, ids, [r, g, b]),
            ShadePath::Scalar => shade_tile::<f32>(&ctx, target, tile, ids, [r, g, b]),
        })
        .sum();
    stats.pixels_shaded = covered;
    stats.times.shade = ms_since(t);
}

/// A rendered frame: the visibility buffer and HDR colour at target size.
pub struct Frame {
    pub target: Target,
    pub visibility: Visibility,
    pub color: ColorBuffer,
    pub stats: FrameStats,
}

/// Renders one frame in the calling rayon pool.
pub fn render(scene: &SceneData, target: Target, path: ShadePath) -> Frame {
    let mut stats = FrameStats::default();
    let visibility = visibility(scene, &target, &mut stats);
    let color = shade(scene, &target, &visibility, path, &mut stats);
    Frame {
        target,
        visibility,
        color,
        stats,
    }
}

/// Renders the scene again into `frame`'s buffers (same target).
pub fn render_into(scene: &SceneData, frame: &mut Frame, path: ShadePath) {
    let mut stats = FrameStats::default();
    visibility_into(scene, &frame.target, &mut frame.visibility, &mut stats);
    shade_into(
        scene,
        &frame.target,
        &frame.visibility,
        path,
        &mut frame.color,
        &mut stats,
    );
    frame.stats = stats;
}
