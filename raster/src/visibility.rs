//! The visibility buffer ([`Visibility`]: each sample's depth and triangle
//! id, with what the passes that drew it keep from frame to frame) and
//! the pass that draws one geometry pass into it ([`geometry_pass`]:
//! vertex stage → clip + setup → bin → raster). `frame.rs` runs a frame's
//! passes in order; the shadow maps' depth passes (`depth_pass.rs`) draw
//! into visibility buffers of their own.

use crate::bin::{BinnedChunk, CHUNK};
use crate::camera::View;
use crate::clip::GuardBand;
use crate::closed::depth_cull;
use crate::geometry::{mask_bits4, Cull, FrameContext, GeometryPass, VertexStage};
use crate::occlusion::{tile_minima, DepthBounds, TileMinima};
use crate::scan::{rasterize_tile, rasterize_tile_alpha, AlphaScan};
use crate::scene::SceneData;
use crate::setup::{DepthPlanes, RasterTri, SetupContext, SetupCounts, TriPlanes};
use crate::setup_x4::{Vertices4, LANES};
use crate::shadow::ShadowMaps;
use crate::stats::{count_setup_sweep, ms_since, FrameStats};
use crate::target::{Target, VisBuffer, MISS, TILE_PIXELS};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// The visibility pass's output, reusable from frame to frame: passing the
/// previous frame's `Visibility` to [`visibility_into`](crate::visibility_into) overwrites it without
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
    /// A depth pass's triangles that it draws front faces only (a bit a
    /// triangle, in scene order: those of the closed solids its light is
    /// outside of, [`ClosedSolids::cull_back_mask`](crate::closed::ClosedSolids::cull_back_mask)); the rest it draws
    /// both ways. Empty elsewhere.
    pub(crate) cull_back: Vec<u64>,
    /// Block depth bounds after the first pass, for the later ones, and
    /// each tile's part of them, taken in the first pass's raster sweep.
    occluder: DepthBounds,
    tile_bounds: Vec<TileMinima>,
    /// The frames' instances of the scene's vertex stages, each beside the
    /// stage it was made from (held, so its address names it).
    pub(crate) stages: Vec<(Arc<dyn VertexStage>, Box<dyn VertexStage>)>,
    /// The shadowed lights' maps of this frame (`shadow`), and the
    /// buffers their depth passes draw with (`shadow_pass`).
    pub shadows: ShadowMaps,
    pub(crate) shadow_buffers: ShadowBuffers,
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

    /// Runs `pass`'s vertex stage for this frame's view into `clip`
    /// (unless `same_stage`: the previous pass ran it, and its positions
    /// are there); the index in `stages` of its instance.
    pub(crate) fn vertex_stage(
        &mut self,
        scene: &SceneData,
        target: &Target,
        pass: &GeometryPass,
        same_stage: bool,
    ) -> usize {
        let stage = self.stage_index(&pass.vertex);
        if !same_stage {
            self.clip.clear();
            let frame = FrameContext {
                view: &self.view,
                ssaa: target.ssaa,
            };
            self.stages[stage]
                .1
                .clip_positions(&frame, &scene.mesh(), &mut self.clip);
        }
        assert_eq!(
            self.clip.len(),
            scene.positions.len(),
            "vertex stage of pass {:?}: one position per vertex",
            pass.name
        );
        stage
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

/// The buffers the shadow maps' depth passes draw with, kept from frame
/// to frame so they are refilled, not reallocated: per light
/// (`scene.lights` order), then the environment's sun, one per map face.
#[derive(Default)]
pub struct ShadowBuffers {
    pub(crate) lights: Vec<Vec<Option<Visibility>>>,
    pub(crate) sun: Vec<Option<Visibility>>,
}

impl Visibility {
    /// Buffers for `target` seen through `view`, nothing drawn yet (the
    /// visibility buffer not cleared: a frame's first pass clears it).
    pub(crate) fn empty(target: &Target, view: View) -> Visibility {
        Visibility {
            vis: VisBuffer::uncleared(target),
            planes: Vec::new(),
            view,
            clip: Vec::new(),
            chunks: Vec::new(),
            depth_planes: Vec::new(),
            outcodes: Vec::new(),
            cull_back: Vec::new(),
            occluder: DepthBounds::default(),
            tile_bounds: Vec::new(),
            stages: Vec::new(),
            shadows: ShadowMaps::default(),
            shadow_buffers: ShadowBuffers::default(),
            blended: Vec::new(),
        }
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
    let stage = out.vertex_stage(scene, target, pass, same_stage);
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
    let cull_back = &out.cull_back[..];
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
                Cull::None if shadow => depth_cull(cull_back, range.start + base + i),
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
