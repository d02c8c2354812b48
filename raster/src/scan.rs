//! Scan conversion of one tile: row spans from exact integer edge functions,
//! then an 8-pixel-wide depth test and visibility-buffer write.

use crate::bin::BinnedChunk;
use crate::setup::{RasterTri, TriPlanes};
use crate::target::{Target, TILE};
use specula_core::Real;
use wide::{f32x8, u32x8};

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
    let (tx, ty) = target.tile_origin(t);
    for chunk in chunks {
        for &i in chunk.tile_items(t) {
            let rt = &chunk.tris[i as usize];
            scan_triangle(
                rt,
                &planes[rt.tri as usize],
                tx as i32,
                ty as i32,
                depth,
                ids,
            );
        }
    }
}

/// Writes `rt` into one tile with origin (tx, ty): for each row, the covered
/// span, depth-tested 8 pixels at a time (z < depth; ties keep the earlier
/// triangle).
pub fn scan_triangle(
    rt: &RasterTri,
    planes: &TriPlanes,
    tx: i32,
    ty: i32,
    depth: &mut [f32],
    ids: &mut [u32],
) {
    let [bx0, by0, bx1, by1] = rt.bbox;
    let x_lo = bx0.max(tx);
    let x_hi = bx1.min(tx + TILE as i32);
    let y_lo = by0.max(ty);
    let y_hi = by1.min(ty + TILE as i32);
    let [za, zb, zc] = planes.z;
    let [ox, oy] = planes.origin;
    let id = u32x8::splat(rt.tri);
    for y in y_lo..y_hi {
        let (x0, x1) = rt.span(y, x_lo, x_hi);
        if x0 >= x1 {
            continue;
        }
        let row_z = zb.mul_add(y as f32 + 0.5 - oy, zc);
        let row = (y - ty) as usize * TILE;
        // Groups of 8 aligned to the tile, so loads never cross a row.
        let mut gx = tx + ((x0 - tx) & !7);
        while gx < x1 {
            let lane_x = f32x8::splat(gx as f32) + f32x8::lane_index();
            let inside = lane_x.ge(f32x8::splat(x0 as f32)) & lane_x.lt(f32x8::splat(x1 as f32));
            let z =
                (lane_x + f32x8::splat(0.5 - ox)).mul_add(f32x8::splat(za), f32x8::splat(row_z));
            let at = row + (gx - tx) as usize;
            let d_old = f32x8::load(&depth[at..at + 8]);
            let pass = inside & z.lt(d_old);
            if pass.any() {
                pass.select(z, d_old).store(&mut depth[at..at + 8]);
                let old: [u32; 8] = ids[at..at + 8].try_into().expect("8 ids");
                let m: u32x8 = bytemuck::cast(pass);
                ids[at..at + 8].copy_from_slice(&m.select(id, u32x8::new(old)).to_array());
            }
            gx += 8;
        }
    }
}
