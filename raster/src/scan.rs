//! Scan conversion of one tile: row spans from exact integer edge functions,
//! then an 8-pixel-wide depth test and visibility-buffer write.

use crate::alpha::{vertex_inputs, AlphaInputs, AlphaMode, MaterialAlpha};
use crate::bin::BinnedChunk;
use crate::buffers::prefetch;
use crate::geometry::IdMap;
use crate::scene::SceneData;
use crate::setup::{DepthPlanes, RasterTri, RectCoverage, SetupPlanes, TriPlanes};
use crate::target::{Target, TILE, TILE_PIXELS};
use specula_core::Real;
use wide::{f32x8, i32x8, u32x8};

/// Rasterizes every triangle binned to tile `t`, in scene order, into the
/// tile's slices of the depth and id buffers (`TILE_PIXELS` entries each).
pub fn rasterize_tile(
    target: &Target,
    t: usize,
    chunks: &[BinnedChunk],
    planes: &[TriPlanes],
    depth: &mut [f32],
    ids: &mut [u32],
) {
    let depth: &mut [f32; TILE_PIXELS] = depth.try_into().expect("a tile of depth");
    let ids: &mut [u32; TILE_PIXELS] = ids.try_into().expect("a tile of ids");
    let (tx, ty) = target.tile_origin(t);
    for_each_triangle::<_, CAMERA_AHEAD>(t, chunks, planes, |rt, p| {
        scan_triangle(rt, p, tx as i32, ty as i32, depth, ids)
    });
}

/// [`rasterize_tile`] of a depth-only pass (a shadow map's): the same
/// depth, no ids written.
pub(crate) fn rasterize_tile_depth(
    target: &Target,
    t: usize,
    chunks: &[BinnedChunk],
    planes: &[DepthPlanes],
    depth: &mut [f32],
) {
    let depth: &mut [f32; TILE_PIXELS] = depth.try_into().expect("a tile of depth");
    let (tx, ty) = target.tile_origin(t);
    for_each_triangle::<_, DEPTH_AHEAD>(t, chunks, planes, |rt, p| {
        let keep = |_, _, pass| pass;
        depth_test_groups(rt, p, tx as i32, ty as i32, depth, keep, |_, _| {});
    });
}

/// [`rasterize_tile`] in a scene with masked or blended materials
/// (alpha.rs): a masked triangle's samples are covered only where its
/// alpha passes the cutoff; a blended one draws nothing and, where
/// `alpha` records them, is appended to `blended` for `blend.rs`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn rasterize_tile_alpha(
    target: &Target,
    t: usize,
    chunks: &[BinnedChunk],
    planes: &[TriPlanes],
    depth: &mut [f32],
    ids: &mut [u32],
    alpha: &AlphaScan,
    blended: &mut Vec<RasterTri>,
) {
    let depth: &mut [f32; TILE_PIXELS] = depth.try_into().expect("a tile of depth");
    let ids: &mut [u32; TILE_PIXELS] = ids.try_into().expect("a tile of ids");
    let (tx, ty) = target.tile_origin(t);
    let (tx, ty) = (tx as i32, ty as i32);
    for_each_triangle::<_, CAMERA_AHEAD>(t, chunks, planes, |rt, p| match alpha.of(rt.tri) {
        None => scan_triangle(rt, p, tx, ty, depth, ids),
        Some((tri, a)) => match a.mode {
            AlphaMode::Mask { cutoff } => {
                let (uvs, alphas) = alpha.vertex_inputs(tri);
                let test = |x: u32, y: u32| {
                    let i = AlphaInputs::<f32x8>::at(p, uvs, alphas, x, y);
                    Real::ge(a.alpha(&i), f32x8::splat(cutoff))
                };
                scan_triangle_masked(rt, p, [tx, ty], depth, ids, test);
            }
            AlphaMode::Blend => {
                if alpha.record_blend {
                    blended.push(*rt);
                }
            }
        },
    });
}

/// How far ahead a camera pass's scan fetches a tile's triangles.
const CAMERA_AHEAD: usize = 2;
/// How far ahead a depth pass's scan fetches a tile's triangles.
const DEPTH_AHEAD: usize = 8;

/// Calls `scan(rt, planes)` for every triangle binned to tile `t`, in
/// scene order.
///
/// A tile's triangles are scattered through their chunks (a few from each)
/// and their planes through the frame's: the triangle `AHEAD` places on,
/// across chunk boundaries, is fetched ahead, and the planes of the one
/// half as far (whose triangle is in cache by then). A depth pass's
/// scan of a small triangle is much shorter than a miss and looks
/// further ahead ([`DEPTH_AHEAD`]) than the camera's ([`CAMERA_AHEAD`]),
/// whose longer scans a deeper look-ahead only slows.
#[inline(always)]
fn for_each_triangle<P, const AHEAD: usize>(
    t: usize,
    chunks: &[BinnedChunk],
    planes: &[P],
    mut scan: impl FnMut(&RasterTri, &P),
) {
    const { assert!(AHEAD >= 2 && AHEAD.is_power_of_two()) };
    let mut tris = chunks
        .iter()
        .flat_map(move |c| c.tile_items(t).iter().map(move |&i| &c.tris[i as usize]));
    // The next AHEAD triangles, one walk of the chunks' lists: a slot is
    // fetched as it is filled, and the planes of the triangle AHEAD / 2
    // places on when it is that near. While triangle i is scanned, slot
    // (head + k) mod AHEAD holds triangle i + k; head has moved on by one
    // when the planes are fetched, hence the − 1.
    let mut ring: [Option<&RasterTri>; AHEAD] = [None; AHEAD];
    for slot in ring.iter_mut() {
        *slot = tris.next();
        if let Some(rt) = *slot {
            prefetch(rt);
        }
    }
    let mut head = 0;
    while let Some(rt) = ring[head] {
        let next = tris.next();
        if let Some(next) = next {
            prefetch(next);
        }
        ring[head] = next;
        head = (head + 1) & (AHEAD - 1);
        if let Some(soon) = ring[(head + AHEAD / 2 - 1) & (AHEAD - 1)] {
            prefetch(&planes[soon.tri as usize]);
        }
        scan(rt, &planes[rt.tri as usize]);
    }
}

/// What the visibility pass needs to know of masked and blended
/// materials; built once per geometry pass, only for scenes that have
/// some.
pub(crate) struct AlphaScan<'a> {
    scene: &'a SceneData,
    ids: IdMap,
    /// Per material.
    materials: Vec<Option<&'a MaterialAlpha>>,
    /// Blended triangles are recorded for compositing (the camera's first
    /// pass) rather than only skipped (shadow maps, later passes).
    pub(crate) record_blend: bool,
}

impl<'a> AlphaScan<'a> {
    /// `None` when no material of the scene is masked or blended.
    pub(crate) fn new(scene: &'a SceneData, record_blend: bool) -> Option<AlphaScan<'a>> {
        let materials: Vec<Option<&MaterialAlpha>> =
            scene.materials.iter().map(|m| m.alpha.as_deref()).collect();
        materials.iter().any(Option::is_some).then(|| AlphaScan {
            scene,
            ids: IdMap::new(&scene.geometry),
            materials,
            record_blend,
        })
    }

    /// The source triangle and alpha of visibility id `id`, if its
    /// material has one.
    #[inline(always)]
    fn of(&self, id: u32) -> Option<(u32, &'a MaterialAlpha)> {
        let (tri, m) = self.ids.look_up(id, &self.scene.tri_material);
        self.materials[m as usize].map(|a| (tri, a))
    }

    fn vertex_inputs(&self, tri: u32) -> ([glam::Vec2; 3], [f32; 3]) {
        let s = self.scene;
        vertex_inputs(&s.uvs, &s.colors, s.triangles[tri as usize])
    }
}

/// Calls `emit(y, gx, mask)` for every row y in [y_lo, y_hi) and every
/// 8-pixel group starting at gx (aligned to `align`, mod 8) that holds a
/// covered pixel of [x_lo, x_hi); `mask` is the covered lanes. This is the
/// coverage the scan writes; tests enumerate it too.
///
/// Small triangles (see `SmallEdges`): the three edge functions are
/// evaluated for the 8 lanes of each group in i32x8 (three adds and compares
/// per group). Larger ones: the row's exact span from `RasterTri::span`,
/// then masks for its groups.
#[inline(always)]
pub fn covered_groups(
    rt: &RasterTri,
    [x_lo, x_hi, y_lo, y_hi]: [i32; 4],
    align: i32,
    mut emit: impl FnMut(i32, i32, u32),
) {
    let first_group = |x: i32| align + ((x - align) & !7);
    if let Some(se) = &rt.small {
        let [bx0, by0, ..] = rt.bbox;
        let lanes = i32x8::new([0, 1, 2, 3, 4, 5, 6, 7]);
        let lane_a = [0, 1, 2].map(|k| lanes * i32x8::splat(se.a[k]));
        let step = [0, 1, 2].map(|k| i32x8::splat(8 * se.a[k]));
        let gx0 = first_group(x_lo);
        // Lanes of the first group left of x_lo (only it can have any).
        let first = 0xFFu32 << (x_lo - gx0);
        let row_step = [0, 1, 2].map(|k| i32x8::splat(se.b[k]));
        // The three edge functions at the first row's first group, then
        // stepped by b per row and 8·a per group: the same integers as
        // evaluating each group afresh (SmallEdges' range keeps them
        // exact), with no broadcasts or multiplies inside the loops.
        let mut row_e = [0, 1, 2].map(|k| {
            i32x8::splat(se.e0[k] + se.b[k] * (y_lo - by0) + se.a[k] * (gx0 - bx0)) + lane_a[k]
        });
        for y in y_lo..y_hi {
            let mut e = row_e;
            for k in 0..3 {
                row_e[k] += row_step[k];
            }
            let mut gx = gx0;
            let mut range = first;
            while gx < x_hi {
                // A pixel is inside when no edge function is negative: the
                // sign bit of their OR. Lanes at or right of x_hi are cut
                // off by `range` (only the last group has any).
                let outside = (e[0] | e[1] | e[2]).simd_lt(i32x8::splat(0)).to_bitmask();
                let mask = !outside & range & (0xFF >> (8 - (x_hi - gx).min(8)));
                if mask != 0 {
                    emit(y, gx, mask);
                }
                for k in 0..3 {
                    e[k] += step[k];
                }
                range = 0xFF;
                gx += 8;
            }
        }
    } else {
        // Large triangles (the ground quad's two span the whole frame)
        // cover most tiles they touch entirely or not at all: an edge
        // function is linear, so its sign at the four corner pixel centres
        // of the rectangle decides every pixel inside when they agree.
        let whole = match rt.rect_coverage([x_lo, x_hi, y_lo, y_hi]) {
            RectCoverage::Outside => return,
            RectCoverage::Inside => true,
            RectCoverage::Partial => false,
        };
        for y in y_lo..y_hi {
            let (x0, x1) = if whole {
                (x_lo, x_hi)
            } else {
                rt.span(y, x_lo, x_hi)
            };
            let mut gx = first_group(x0);
            while gx < x1 {
                let lo = (x0 - gx).max(0);
                let hi = (x1 - gx).min(8);
                emit(y, gx, (0xFFu32 >> (8 - (hi - lo))) << lo);
                gx += 8;
            }
        }
    }
}

/// Writes `rt` into one tile with origin (tx, ty): the covered pixels of
/// each row, depth-tested 8 at a time (z > depth, reversed depth; ties keep the earlier
/// triangle).
pub fn scan_triangle(
    rt: &RasterTri,
    planes: &TriPlanes,
    tx: i32,
    ty: i32,
    depth: &mut [f32; TILE_PIXELS],
    ids: &mut [u32; TILE_PIXELS],
) {
    let id = u32x8::splat(rt.tri);
    let keep = |_, _, pass| pass;
    depth_test_groups(rt, planes, tx, ty, depth, keep, |at, pass| {
        write_ids(ids, at, pass, id)
    });
}

/// A triangle's depth plane on 8-pixel groups: its z at the centres of
/// the group of 8 pixels from (gx, y), as the scan, its alpha test and
/// blend.rs's depth test all evaluate it (same operations, same bits).
pub(crate) struct GroupDepth {
    za8: f32x8,
    zb: f32,
    zc: f32,
    oy: f32,
    lane_x: f32x8,
}

impl GroupDepth {
    #[inline(always)]
    pub(crate) fn new<P: SetupPlanes>(planes: &P) -> GroupDepth {
        let ([za, zb, zc], [ox, oy]) = planes.depth();
        GroupDepth {
            za8: f32x8::splat(za),
            zb,
            zc,
            oy,
            lane_x: f32x8::lane_index() + f32x8::splat(0.5 - ox),
        }
    }

    #[inline(always)]
    pub(crate) fn at(&self, gx: i32, y: i32) -> f32x8 {
        let row_z = self.zb.mul_add(y as f32 + 0.5 - self.oy, self.zc);
        (self.lane_x + f32x8::splat(gx as f32)).mul_add(self.za8, f32x8::splat(row_z))
    }
}

/// The depth test and write of [`scan_triangle`]: for each group of 8 at
/// tile offset `at` where some covered sample passes the depth test,
/// `keep(gx, y, pass)` may take lanes out of `pass` (an alpha test), and
/// where some remain their depth is written and `passed(at, pass)` is
/// called.
#[inline(always)]
fn depth_test_groups<P: SetupPlanes>(
    rt: &RasterTri,
    planes: &P,
    tx: i32,
    ty: i32,
    depth: &mut [f32; TILE_PIXELS],
    mut keep: impl FnMut(i32, i32, <f32x8 as Real>::Mask) -> <f32x8 as Real>::Mask,
    mut passed: impl FnMut(usize, <f32x8 as Real>::Mask),
) {
    let z_at = GroupDepth::new(planes);
    // Groups are aligned to the tile, so loads never cross a row.
    covered_groups(rt, rt.tile_bounds(tx, ty), tx, |y, gx, mask| {
        let z = z_at.at(gx, y);
        let at = (y - ty) as usize * TILE + (gx - tx) as usize;
        // Groups are aligned to 8 inside the tile, so `at` is a multiple of
        // 8 below TILE_PIXELS and the mask changes nothing; it lets the
        // compiler drop the bounds checks of the two 8-wide accesses.
        debug_assert!(at.is_multiple_of(8) && at < TILE_PIXELS);
        let at = at & (TILE_PIXELS - 8);
        let d_old = f32x8::load(&depth[at..at + 8]);
        let pass = f32x8::mask_from_bits(mask) & z.gt(d_old);
        if pass.any() {
            let pass = keep(gx, y, pass);
            if pass.any() {
                pass.select(z, d_old).store(&mut depth[at..at + 8]);
                passed(at, pass);
            }
        }
    });
}

/// `id` into the lanes of `pass` of the 8 ids from `at`.
#[inline(always)]
fn write_ids(ids: &mut [u32; TILE_PIXELS], at: usize, pass: <f32x8 as Real>::Mask, id: u32x8) {
    let old: [u32; 8] = ids[at..at + 8].try_into().expect("8 ids");
    let m: u32x8 = bytemuck::cast(pass);
    ids[at..at + 8].copy_from_slice(&m.select(id, u32x8::new(old)).to_array());
}

/// [`scan_triangle`] of a masked triangle: a sample that passes the depth
/// test is written only where `test(x, y)` (the alpha test of the 8
/// samples from (x, y)) passes too. Depth first: the alpha costs a
/// texture lookup, the depth test a load.
fn scan_triangle_masked(
    rt: &RasterTri,
    planes: &TriPlanes,
    [tx, ty]: [i32; 2],
    depth: &mut [f32; TILE_PIXELS],
    ids: &mut [u32; TILE_PIXELS],
    test: impl Fn(u32, u32) -> <f32x8 as Real>::Mask,
) {
    let id = u32x8::splat(rt.tri);
    let keep = |gx: i32, y: i32, pass| pass & test(gx as u32, y as u32);
    depth_test_groups(rt, planes, tx, ty, depth, keep, |at, pass| {
        write_ids(ids, at, pass, id)
    });
}
