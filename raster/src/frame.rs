//! One frame as a list of passes: the scene's geometry passes (each:
//! vertex → clip + setup → bin → raster) into one visibility buffer, then
//! resolve + shade into the frame buffers; post stages (post/) follow.
//! Each pass is timed (geometry passes summed per stage); parallel work is
//! split in fixed pieces (vertex and setup chunks, tiles) so that the result
//! does not depend on the thread count.

use crate::bin::{BinnedChunk, CHUNK};
use crate::blend;
use crate::buffers::{BufferSet, FrameBuffers, Planes3, TileWriter};
use crate::camera::View;
use crate::clip::GuardBand;
use crate::geometry::{mask_bits4, Cull, FrameContext, GeometryPass, VertexStage};
use crate::occlusion::{tile_minima, DepthBounds, TileMinima};
use crate::post::LdrEncoding;
use crate::resolve::ResolveContext;
use crate::scan::{rasterize_tile, rasterize_tile_alpha, AlphaScan};
use crate::scene::SceneData;
use crate::setup::{DepthPlanes, RasterTri, SetupContext, SetupCounts, TriPlanes};
use crate::setup_x4::{Vertices4, LANES};
use crate::shading_pass::{shade_tile, ShadeTargets};
use crate::shadow::ShadowMaps;
use crate::target::{Target, VisBuffer, MISS, TILE_PIXELS};
use rayon::prelude::*;
use specula_core::f32x8;
use std::sync::Arc;
use std::time::Instant;

/// Wall time of each pass in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassTimes {
    pub vertex: f64,
    pub setup: f64,
    pub bin: f64,
    pub raster: f64,
    pub shade: f64,
    /// The shadow maps' depth passes (all stages).
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
    /// Shadow-map depth passes drawn (a cube map is 6).
    pub shadow_passes: u32,
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
    pub(crate) clip: Vec<[f32; 4]>,
    /// Setup's and binning's output per chunk, kept for the next frame's
    /// geometry passes to refill (see [`BinnedChunk::bin`]).
    pub(crate) chunks: Vec<BinnedChunk>,
    /// A depth-only pass's planes per source triangle and its vertices'
    /// outcodes (`depth_pass.rs`); empty elsewhere.
    pub(crate) depth_planes: Vec<DepthPlanes>,
    pub(crate) outcodes: Vec<u8>,
    /// Block depth bounds after the first pass, for the later ones, and
    /// each tile's part of them, taken in the first pass's raster sweep.
    occluder: DepthBounds,
    tile_bounds: Vec<TileMinima>,
    /// The frames' instances of the scene's vertex stages, each beside the
    /// stage it was made from (held, so its address names it).
    pub(crate) stages: Vec<(Arc<dyn VertexStage>, Box<dyn VertexStage>)>,
    /// The shadowed lights' maps of this frame (shadow.rs).
    pub shadows: ShadowMaps,
    /// Per tile, the blended triangles of the first pass that touch it,
    /// in scene order (blend.rs); empty when the scene has none.
    pub(crate) blended: Vec<Vec<RasterTri>>,
}

impl Visibility {
    /// The instance of the scene's vertex stage `stage` that drew this
    /// frame, if a pass of the frame used it (what it kept of the frame:
    /// [`VertexStage::front_faces`], [`VertexStage::hidden`]).
    pub fn stage(&self, stage: &Arc<dyn VertexStage>) -> Option<&dyn VertexStage> {
        (self.stages.iter())
            .find(|(s, _)| Arc::ptr_eq(s, stage))
            .map(|(_, i)| &**i)
    }

    /// The index in `stages` of the instance of `stage` this run of
    /// frames uses (made on first use).
    pub(crate) fn stage_index(&mut self, stage: &Arc<dyn VertexStage>) -> usize {
        match self.stages.iter().position(|(s, _)| Arc::ptr_eq(s, stage)) {
            Some(i) => i,
            None => {
                self.stages.push((stage.clone(), stage.instance()));
                self.stages.len() - 1
            }
        }
    }
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

/// Every geometry pass of the scene into one visibility buffer, in the
/// calling rayon pool.
pub fn visibility(scene: &SceneData, target: &Target, stats: &mut FrameStats) -> Visibility {
    let mut v = Visibility::empty(target, scene.camera.view(target.width, target.height));
    visibility_into(scene, target, &mut v, stats);
    v
}

impl Visibility {
    /// Buffers for `target` seen through `view`, nothing drawn yet.
    pub(crate) fn empty(target: &Target, view: View) -> Visibility {
        Visibility {
            vis: VisBuffer::new(target),
            planes: Vec::new(),
            view,
            clip: Vec::new(),
            chunks: Vec::new(),
            depth_planes: Vec::new(),
            outcodes: Vec::new(),
            occluder: DepthBounds::default(),
            tile_bounds: Vec::new(),
            stages: Vec::new(),
            shadows: ShadowMaps::default(),
            blended: Vec::new(),
        }
    }
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
    let ids = scene
        .geometry
        .iter()
        .map(|p| p.ids().end)
        .max()
        .unwrap_or(0);
    out.planes.resize(ids as usize, TriPlanes::default());
    // Instances of stages this scene no longer has (a frame reused for
    // another scene) go.
    out.stages
        .retain(|(s, _)| scene.geometry.iter().any(|p| Arc::ptr_eq(&p.vertex, s)));
    let mut bounds_built = false;
    for (i, pass) in scene.geometry.iter().enumerate() {
        // A pass whose vertex stage is the previous pass's (one outline's
        // passes share one) finds its positions in `out.clip` already.
        let same_stage = i > 0 && Arc::ptr_eq(&scene.geometry[i - 1].vertex, &pass.vertex);
        geometry_pass(
            scene,
            target,
            pass,
            i,
            same_stage,
            &mut bounds_built,
            out,
            stats,
            false,
        );
    }
    if scene.geometry.is_empty() {
        out.vis.depth.fill(0.0);
        out.vis.id.fill(MISS);
    }
    if scene.shadows.iter().any(Option::is_some) || scene.sun_shadows.is_some() {
        out.shadows.render(scene, &out.view, stats);
    } else if out.shadows.active().is_some() {
        out.shadows = ShadowMaps::default();
    }
}

/// One geometry pass: vertex stage, clip + setup, bin, raster. The first
/// pass of a frame clears the visibility buffer; later ones depth-test
/// against what the earlier ones drew, and skip in setup the triangles
/// that test shows cannot pass anywhere (`occlusion`; bounds built once,
/// before the first later pass that is set up, and counted in the setup
/// time). A later pass whose vertex stage shows its triangles hidden
/// ([`crate::geometry::VertexStage::hidden`]) stops after the vertex
/// stage; its triangles count as hidden by earlier passes. With
/// `same_stage` the previous pass ran this pass's vertex stage for this
/// view: its positions in `out.clip` are reused. Masked materials are
/// alpha-tested per sample; blended ones draw nothing, and the camera's
/// first pass (not a `shadow` map's) keeps them per tile for blend.rs.
#[allow(clippy::too_many_arguments)]
pub(crate) fn geometry_pass(
    scene: &SceneData,
    target: &Target,
    pass: &GeometryPass,
    index: usize,
    same_stage: bool,
    bounds_built: &mut bool,
    out: &mut Visibility,
    stats: &mut FrameStats,
    shadow: bool,
) {
    let first = index == 0;
    let t = Instant::now();
    let stage = out.stage_index(&pass.vertex);
    if !same_stage {
        out.clip.clear();
        let frame = FrameContext {
            view: &out.view,
            ssaa: target.ssaa,
        };
        out.stages[stage]
            .1
            .clip_positions(&frame, scene, &mut out.clip);
    }
    assert_eq!(
        out.clip.len(),
        scene.positions.len(),
        "vertex stage of pass {:?}: one position per vertex",
        pass.name
    );
    let clip = &out.clip;
    let hidden = !first && out.stages[stage].1.hidden(pass.triangles.clone());
    stats.times.vertex += ms_since(t);
    if hidden {
        let n = pass.triangles.len() as u64;
        stats.counts.triangles += n;
        stats.counts.culled_occluded += n;
        return;
    }

    let t = Instant::now();
    let ctx = SetupContext {
        width: target.width,
        height: target.height,
        guard: GuardBand::for_image(target.width, target.height),
    };
    if !first && !*bounds_built {
        out.occluder.build_from_tiles(target, &out.tile_bounds);
        *bounds_built = true;
    }
    let occluder = (!first).then_some(&out.occluder);
    let range = pass.triangles.start as usize..pass.triangles.end as usize;
    let ids = pass.ids();
    let n_chunks = range.len().div_ceil(CHUNK);
    if out.chunks.len() < n_chunks {
        out.chunks.resize_with(n_chunks, BinnedChunk::default);
    }
    let chunks = &mut out.chunks[..n_chunks];
    // Triangles the vertex stage showed front-facing: a `Cull::Front`
    // pass skips their groups of 4 whole (setup would cull each).
    let front = match pass.cull {
        Cull::Front => out.stages[stage].1.front_faces(),
        _ => None,
    };
    let mask: &[u64] = front.as_deref().map_or(&[], Vec::as_slice);
    let masked = !mask.is_empty();
    let set_up: Vec<(SetupCounts, f64)> = scene.triangles[range.clone()]
        .par_chunks(CHUNK)
        .zip(out.planes[ids.start as usize..ids.end as usize].par_chunks_mut(CHUNK))
        .zip(chunks.par_iter_mut())
        .enumerate()
        .map(|(c, ((tris, planes), chunk))| {
            let raster = &mut chunk.tris;
            raster.clear();
            let mut counts = SetupCounts::default();
            let base = c * CHUNK;
            let cull = |i: usize| match pass.cull {
                Cull::Back
                    if scene.materials[scene.tri_material[range.start + base + i] as usize]
                        .double_sided =>
                {
                    Cull::None
                }
                c => c,
            };
            let id = |i: usize| ids.start as u32 + (base + i) as u32;
            let vertices =
                |&[a, b, c]: &[u32; 3]| [clip[a as usize], clip[b as usize], clip[c as usize]];
            // 4 triangles at a time (bit-identical to `setup` per triangle,
            // passes after the first with the occlusion test), the chunk's
            // last 0–3 one at a time.
            let quads = tris.len() / LANES * LANES;
            for (q, (tris4, planes4)) in tris[..quads]
                .chunks_exact(LANES)
                .zip(planes[..quads].chunks_exact_mut(LANES))
                .enumerate()
            {
                let i = q * LANES;
                if masked && mask_bits4(mask, range.start + base + i) == 0xF {
                    counts.triangles += LANES as u64;
                    counts.culled_backface += LANES as u64;
                    continue;
                }
                let v = Vertices4::gather(clip, tris4.try_into().expect("chunks of LANES"));
                // Spelled out: `array::from_fn` compiled to copies through
                // the stack here, which stalled on store forwarding.
                let cull4 = [cull(i), cull(i + 1), cull(i + 2), cull(i + 3)];
                let planes4 = planes4.try_into().expect("chunks of LANES");
                ctx.setup_x4_vertices(id(i), &v, cull4, occluder, planes4, raster, &mut counts);
            }
            for (i, (tri, plane)) in tris.iter().zip(planes.iter_mut()).enumerate().skip(quads) {
                if let Some(p) =
                    ctx.setup_occluded(id(i), vertices(tri), cull(i), occluder, raster, &mut counts)
                {
                    *plane = p;
                }
            }
            // Binned in the same sweep, while its triangles are in cache:
            // a parallel pass of its own cost a wake-up of the other
            // workers.
            let tb = Instant::now();
            chunk.bin(target);
            (counts, ms_since(tb))
        })
        .collect();
    count_setup_sweep(stats, t, &set_up, chunks);
    let chunks = &*chunks;

    let t = Instant::now();
    let planes = &out.planes;
    // The first pass of several takes the occlusion bounds of each tile
    // while it is in cache (the later passes' test needs them).
    let bounds = first && scene.geometry.len() > 1;
    let tiles = out.vis.depth.len() / TILE_PIXELS;
    if bounds {
        // One entry a tile (1 KB), kept from frame to frame.
        out.tile_bounds.resize(tiles, [0.0; _]);
    }
    let alpha = AlphaScan::new(scene, first && !shadow);
    if first && !shadow {
        out.blended.iter_mut().for_each(Vec::clear);
        if alpha.is_some() {
            out.blended.resize_with(tiles, Vec::new);
        }
    }
    let alpha = alpha.as_ref();
    let mut no_blended = Vec::new();
    let blended = match alpha {
        Some(a) if a.record_blend => &mut out.blended[..],
        _ => &mut no_blended[..],
    };
    out.vis
        .depth
        .par_chunks_mut(TILE_PIXELS)
        .zip(out.vis.id.par_chunks_mut(TILE_PIXELS))
        // Entries past the kept ones (none, or all when not taking
        // bounds): `None`; the zip stops at the last tile.
        .zip(
            (out.tile_bounds.par_iter_mut().map(Some))
                .chain((0..tiles).into_par_iter().map(|_| None)),
        )
        .zip((blended.par_iter_mut().map(Some)).chain((0..tiles).into_par_iter().map(|_| None)))
        .enumerate()
        .for_each(|(tile, (((depth, ids), minima), blended))| {
            if first {
                // Cleared here, while the tile is about to be in cache anyway.
                depth.fill(0.0);
                ids.fill(MISS);
            }
            match alpha {
                None => rasterize_tile(target, tile, chunks, planes, depth, ids),
                Some(a) => {
                    let mut skipped = Vec::new();
                    let blended = blended.unwrap_or(&mut skipped);
                    rasterize_tile_alpha(target, tile, chunks, planes, depth, ids, a, blended);
                }
            }
            if let Some(m) = minima.filter(|_| bounds) {
                *m = tile_minima(depth);
            }
        });
    stats.times.raster += ms_since(t);
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

/// Resolve + shade every tile into new frame buffers holding `set`, in
/// the calling rayon pool.
pub fn shade(
    scene: &SceneData,
    target: &Target,
    v: &Visibility,
    path: ShadePath,
    set: BufferSet,
    stats: &mut FrameStats,
) -> FrameBuffers {
    let mut buffers = FrameBuffers::new(target, set);
    shade_into(scene, target, v, path, &mut buffers, stats);
    buffers
}

/// [`shade`] into the frame buffers of an earlier frame of the same target
/// (the buffers it holds are the ones filled).
pub fn shade_into(
    scene: &SceneData,
    target: &Target,
    v: &Visibility,
    path: ShadePath,
    buffers: &mut FrameBuffers,
    stats: &mut FrameStats,
) {
    // Buffers of a frame drawn by `render_ldr` have no colour planes:
    // this pass's output is the colour, so they come back.
    if buffers.color.is_empty() {
        buffers.color = Planes3::new(target.pixel_count());
    }
    shade_impl(scene, target, v, path, buffers, None, stats);
}

/// [`shade_into`] that also encodes the 8-bit sRGB image into `ldr`
/// (resized to width × height × 3) tile row by tile row; the linear colour
/// planes are filled only if `buffers` has them (not empty).
fn shade_impl(
    scene: &SceneData,
    target: &Target,
    v: &Visibility,
    path: ShadePath,
    buffers: &mut FrameBuffers,
    ldr: Option<(LdrEncoding, &mut Vec<u8>)>,
    stats: &mut FrameStats,
) {
    assert!(
        buffers.width == target.width && buffers.height == target.height,
        "frame buffers are for another target"
    );
    let ldr = match ldr {
        Some((enc, bytes)) if blend::any(v) => {
            // Blended surfaces go over the shaded opaque frame before the
            // encode: shaded into colour planes, composited, then encoded.
            let kept = !buffers.color.is_empty();
            if !kept {
                buffers.color = Planes3::new(target.pixel_count());
            }
            shade_impl(scene, target, v, path, buffers, None, stats);
            let w = target.width as usize;
            bytes.resize(target.pixel_count() * 3, 0);
            let c = &buffers.color;
            bytes
                .par_chunks_mut(w * 3)
                .zip(
                    c.r.par_chunks(w)
                        .zip(c.g.par_chunks(w))
                        .zip(c.b.par_chunks(w)),
                )
                .for_each(|(out, ((r, g), b))| enc.encode_row(r, g, b, out));
            if !kept {
                buffers.color = Planes3::default();
            }
            return;
        }
        ldr => ldr,
    };
    let t = Instant::now();
    let mut ctx = ResolveContext::new(scene, &v.planes, &v.view);
    ctx.shadows = v.shadows.active();
    let FrameBuffers {
        color,
        depth,
        normal,
        id,
        ..
    } = buffers;
    let out = ShadeTargets {
        color: [
            TileWriter::new(&mut color.r, target),
            TileWriter::new(&mut color.g, target),
            TileWriter::new(&mut color.b, target),
        ],
        depth: TileWriter::new(depth, target),
        normal: [
            TileWriter::new(&mut normal.r, target),
            TileWriter::new(&mut normal.g, target),
            TileWriter::new(&mut normal.b, target),
        ],
        id: TileWriter::new(id, target),
        ldr: ldr.map(|(enc, bytes)| {
            bytes.resize(target.pixel_count() * 3, 0);
            let px: &mut [[u8; 3]] = bytes.as_mut_slice().as_chunks_mut().0;
            (enc, TileWriter::new(px, target))
        }),
    };
    let covered: u64 = v
        .vis
        .id
        .par_chunks(TILE_PIXELS)
        .enumerate()
        .map(|(tile, ids)| {
            // SAFETY: the parallel iterator gives each tile index to one
            // call, and tiles are disjoint rectangles.
            unsafe {
                match path {
                    ShadePath::Simd => shade_tile::<f32x8>(&ctx, target, tile, ids, &out),
                    ShadePath::Scalar => shade_tile::<f32>(&ctx, target, tile, ids, &out),
                }
            }
        })
        .sum();
    stats.blended_samples = 0;
    if blend::any(v) {
        let color = [
            TileWriter::new(&mut buffers.color.r, target),
            TileWriter::new(&mut buffers.color.g, target),
            TileWriter::new(&mut buffers.color.b, target),
        ];
        stats.blended_samples = (0..target.tile_count())
            .into_par_iter()
            .map(|tile| {
                // SAFETY: each tile index goes to one call; tiles are disjoint.
                unsafe {
                    match path {
                        ShadePath::Simd => {
                            blend::composite_tile::<f32x8>(&ctx, target, v, tile, &color)
                        }
                        ShadePath::Scalar => {
                            blend::composite_tile::<f32>(&ctx, target, v, tile, &color)
                        }
                    }
                }
            })
            .sum();
    }
    stats.pixels_shaded = covered;
    stats.times.shade = ms_since(t);
}

/// A rendered frame: the visibility buffer and the frame buffers at target
/// size.
pub struct Frame {
    pub target: Target,
    pub visibility: Visibility,
    pub buffers: FrameBuffers,
    pub stats: FrameStats,
}

/// Renders one frame (colour only) in the calling rayon pool.
pub fn render(scene: &SceneData, target: Target, path: ShadePath) -> Frame {
    render_with(scene, target, path, BufferSet::default())
}

/// Renders one frame filling the optional buffers of `set` too.
pub fn render_with(scene: &SceneData, target: Target, path: ShadePath, set: BufferSet) -> Frame {
    let mut stats = FrameStats::default();
    let visibility = visibility(scene, &target, &mut stats);
    let buffers = shade(scene, &target, &visibility, path, set, &mut stats);
    Frame {
        target,
        visibility,
        buffers,
        stats,
    }
}

/// Renders one frame straight to 8-bit sRGB in `ldr` (the bytes the post
/// list of `enc` gives; [`crate::post::Post::ldr_in_shading`]) without linear
/// colour planes: the shading pass encodes each tile row while it is in
/// cache. The frame keeps the optional buffers of `set`; its colour planes
/// are empty.
pub fn render_ldr(
    scene: &SceneData,
    target: Target,
    path: ShadePath,
    set: BufferSet,
    enc: LdrEncoding,
    ldr: &mut Vec<u8>,
) -> Frame {
    let mut stats = FrameStats::default();
    let visibility = visibility(scene, &target, &mut stats);
    let mut buffers = FrameBuffers::new(&target, set);
    // Never touched, so never faulted in: freed at once.
    buffers.color = Planes3::default();
    shade_impl(
        scene,
        &target,
        &visibility,
        path,
        &mut buffers,
        Some((enc, ldr)),
        &mut stats,
    );
    Frame {
        target,
        visibility,
        buffers,
        stats,
    }
}

/// [`render_ldr`] again into `frame` (same target); its colour planes, if
/// it has any, are dropped.
pub fn render_ldr_into(
    scene: &SceneData,
    frame: &mut Frame,
    path: ShadePath,
    enc: LdrEncoding,
    ldr: &mut Vec<u8>,
) {
    let mut stats = FrameStats::default();
    visibility_into(scene, &frame.target, &mut frame.visibility, &mut stats);
    frame.buffers.color = Planes3::default();
    shade_impl(
        scene,
        &frame.target,
        &frame.visibility,
        path,
        &mut frame.buffers,
        Some((enc, ldr)),
        &mut stats,
    );
    frame.stats = stats;
}

/// Renders the scene again into `frame`'s buffers (same target, same set).
pub fn render_into(scene: &SceneData, frame: &mut Frame, path: ShadePath) {
    let mut stats = FrameStats::default();
    visibility_into(scene, &frame.target, &mut frame.visibility, &mut stats);
    shade_into(
        scene,
        &frame.target,
        &frame.visibility,
        path,
        &mut frame.buffers,
        &mut stats,
    );
    frame.stats = stats;
}
