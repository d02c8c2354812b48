//! One frame as a list of passes: the scene's geometry passes (each:
//! vertex → clip + setup → bin → raster) into one visibility buffer, then
//! resolve + shade into the frame buffers; post stages (post/) follow.
//! Each pass is timed (geometry passes summed per stage); parallel work is
//! split in fixed pieces (vertex and setup chunks, tiles) so that the result
//! does not depend on the thread count.

pub use crate::stats::{FrameStats, PassTimes};
pub use crate::visibility::Visibility;

use crate::blend;
use crate::buffers::{BufferSet, FrameBuffers, Planes3, TileWriter};
use crate::post::LdrEncoding;
use crate::resolve::ResolveContext;
use crate::scene::SceneData;
use crate::shading_pass::{shade_tile, ShadeTargets};
use crate::shadow::ShadowMaps;
use crate::shadow_pass::{self, DepthSetup};
use crate::stats::ms_since;
use crate::target::{Target, MISS, TILE_PIXELS};
use crate::visibility::{geometry_pass, ShadowBuffers};
use rayon::prelude::*;
use specula_core::f32x8;
use std::sync::Arc;
use std::time::Instant;

/// Every geometry pass of the scene into one visibility buffer, in the
/// calling rayon pool.
pub fn visibility(scene: &SceneData, target: &Target, stats: &mut FrameStats) -> Visibility {
    let mut v = Visibility::empty(target, scene.camera.view(target.width, target.height));
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
    let ids = scene
        .geometry
        .iter()
        .map(|p| p.ids().end)
        .max()
        .unwrap_or(0);
    crate::buffers::resize_zeroed(&mut out.planes, ids as usize);
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
        let (maps, buffers) = (&mut out.shadows, &mut out.shadow_buffers);
        shadow_pass::render_maps(
            scene,
            &out.view,
            DepthSetup::default(),
            maps,
            buffers,
            stats,
        );
    } else if out.shadows.active().is_some() {
        out.shadows = ShadowMaps::default();
        out.shadow_buffers = ShadowBuffers::default();
    }
}

/// Lane width of the shading pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ShadePath {
    /// 8 pixels per packet in f32x8; where the processor has AVX-512,
    /// batches of materials without maps (but Disney's) under point,
    /// spot and directional lights two packets per register
    /// (`packet_pairs`), with the same bits.
    #[default]
    Simd,
    /// [`ShadePath::Simd`] without the packet pairs: f32x8 alone, as on a
    /// processor without AVX-512 (for checks and timing).
    SimdAvx2,
    /// One pixel at a time in f32: the same kernels, for comparison.
    Scalar,
}

/// Whether this processor runs the packet pairs of [`ShadePath::Simd`]
/// (AVX-512F, DQ, VL and BW).
pub fn packet_pairs_available() -> bool {
    crate::packet_pairs::available()
}

/// Whether [`ShadePath::Simd`] shades `scene` two packets per AVX-512
/// register on this processor (`packet_pairs`): the batches of its
/// materials without maps and of a model the pairs take (when it has
/// some), when it has no polygon light and no environment map or one lit
/// by the split sum.
pub fn shades_packet_pairs(scene: &SceneData) -> bool {
    crate::packet_pairs::applies(&scene.lights, scene.env_map.as_deref())
        && scene.materials.iter().any(|m| {
            m.shader
                .as_any()
                .downcast_ref::<crate::Lit>()
                .is_some_and(|l| l.maps().is_empty() && crate::packet_pairs::pairs_model(l.model()))
        })
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
            crate::buffers::resize_zeroed(bytes, target.pixel_count() * 3);
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
    ctx.pair_packets = path == ShadePath::Simd;
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
            crate::buffers::resize_zeroed(bytes, target.pixel_count() * 3);
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
                    ShadePath::Simd | ShadePath::SimdAvx2 => {
                        shade_tile::<f32x8>(&ctx, target, tile, ids, &out)
                    }
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
                        ShadePath::Simd | ShadePath::SimdAvx2 => {
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
