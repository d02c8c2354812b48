//! Blended surfaces (glTF's alphaMode BLEND) composited over the shaded
//! opaque frame.
//!
//! The visibility pass draws nothing of a blended triangle; the camera's
//! first pass keeps, per tile, the blended triangles that touch it
//! (`scan::rasterize_tile_alpha`). Once the opaque frame is shaded, each
//! tile takes its blended triangles back to front and, for each, every
//! covered sample in front of the opaque depth (z > depth: depth-tested,
//! never written): the sample is resolved and shaded by the triangle's
//! material as an opaque one would be, and composited "over" what the
//! colour buffer holds, out = α·c + (1 − α)·dst (c the shaded radiance,
//! α the material's alpha there, clamped to [0, 1]).
//!
//! **Order.** Back to front by the view depth of each triangle's centroid
//! ((centroid − eye) · forward), farther first; equal depths in scene
//! order. The order is total, so every tile (and any thread count) sees
//! the same one. Like every sort of primitives it is wrong where it cannot
//! be right: blended triangles that intersect, or overlap cyclically, or
//! a large triangle whose centroid is nearer than that of a small one it
//! is behind where they overlap; there the nearer surface may be
//! composited first. (Order-independent transparency would fix that;
//! glTF asks for no more than this.)
//!
//! Blended surfaces write no depth, id or normal: the AOVs and the
//! image-space post stages see the opaque frame. They cast no shadows:
//! the shadow maps' depth passes skip them (engines differ; some draw
//! them as MASK, which is wrong for partial alpha either way).

use crate::alpha::AlphaInputs;
use crate::buffers::TileWriter;
use crate::resolve::{PacketTris, ResolveContext};
use crate::scan::{covered_groups, GroupDepth};
use crate::setup::RasterTri;
use crate::shader::{ShadeEnv, ShadeInput, ShadeLanes};
use crate::target::{Target, MISS, TILE, TILE_PIXELS};
use crate::visibility::Visibility;
use specula_core::{f32x8, Mask, Real};

/// Whether the frame has blended samples to composite.
pub(crate) fn any(v: &Visibility) -> bool {
    v.blended.iter().any(|b| !b.is_empty())
}

/// The view depth of triangle `tri`'s centroid (the sort key).
fn centroid_depth(ctx: &ResolveContext, tri: u32) -> f32 {
    let s = ctx.scene;
    let [a, b, c] = s.triangles[tri as usize].map(|i| s.positions[i as usize]);
    let centroid = (a + b + c) / 3.0;
    (centroid - ctx.view.eye).dot(ctx.view.forward)
}

/// Composites tile `t`'s blended triangles over its colour (module docs);
/// returns how many samples were shaded and composited (a sample under k
/// blended surfaces counts k times).
///
/// # Safety
/// The caller hands tile `t` to this call alone (see [`TileWriter`]).
pub(crate) unsafe fn composite_tile<R: ShadeLanes>(
    ctx: &ResolveContext,
    target: &Target,
    v: &Visibility,
    t: usize,
    color: &[TileWriter<'_, f32>; 3],
) -> u64 {
    let Some(blended) = v.blended.get(t).filter(|b| !b.is_empty()) else {
        return 0;
    };
    let scene = ctx.scene;
    let env = ShadeEnv {
        lights: &scene.lights,
        environment: scene.environment,
        env_map: scene.env_map.as_deref(),
        shadows: ctx.shadows,
        pair_packets: ctx.pair_packets,
    };
    let mut order: Vec<(f32, u32, &RasterTri)> = blended
        .iter()
        .map(|rt| {
            let (tri, _) = ctx.ids.look_up(rt.tri, &scene.tri_material);
            (centroid_depth(ctx, tri), rt.tri, rt)
        })
        .collect();
    // Farther first; ties by id (scene order). NaN depths cannot occur
    // (setup skips non-finite vertices), and total_cmp orders them anyway.
    order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let (tx, ty) = target.tile_origin(t);
    let (tx, ty) = (tx as i32, ty as i32);
    let depth = &v.vis.depth[t * TILE_PIXELS..(t + 1) * TILE_PIXELS];
    let lane_bits = (1u32 << R::LANES) - 1;
    let mut shaded = 0u64;
    for (_, id, rt) in order {
        let (_, m) = ctx.ids.look_up(id, &scene.tri_material);
        let material = &scene.materials[m as usize];
        let Some(alpha) = material.alpha.as_deref() else {
            continue;
        };
        let shader = &*material.shader;
        let shader_surface = ctx.needs_surface[m as usize];
        let needs_surface = shader_surface || alpha.needs_surface();
        let p = &v.planes[id as usize];
        let z_at = GroupDepth::new(p);
        covered_groups(rt, rt.tile_bounds(tx, ty), tx, |y, gx, mask| {
            // The depth test of `scan_triangle`, against the opaque depth.
            let z = z_at.at(gx, y);
            let at = (y - ty) as usize * TILE + (gx - tx) as usize;
            let d_old = f32x8::load(&depth[at..at + 8]);
            let front = mask & Real::gt(z, d_old).bits();
            shaded += u64::from(front.count_ones());
            // SAFETY: tile t is this call's alone (the function's contract).
            let rows = unsafe {
                let [r, g, b] = color;
                [r, g, b].map(|w| w.tile_row(tx as usize, y as usize))
            };
            for sub in (0..8).step_by(R::LANES) {
                let lanes = (front >> sub) & lane_bits;
                if lanes == 0 {
                    continue;
                }
                let ids: [u32; 8] =
                    std::array::from_fn(|i| if lanes >> i & 1 == 1 { id } else { MISS });
                let tris = PacketTris::new(&ids, R::LANES, ctx);
                let x = (gx + sub) as u32;
                let frag = ctx.resolve::<R>(x, y as u32, &tris);
                let surface = needs_surface.then(|| ctx.surface(&tris, &frag));
                let input = ShadeInput {
                    frag: &frag,
                    surface: surface.as_ref().filter(|_| shader_surface),
                    lanes,
                    shadow_factors: None,
                };
                let c = R::shade_with(shader, &input, &env);
                let inputs = match &surface {
                    Some(s) => AlphaInputs {
                        uv: s.uv,
                        duv_dx: s.duv_dx,
                        duv_dy: s.duv_dy,
                        vertex_alpha: s.alpha,
                    },
                    None => AlphaInputs {
                        uv: [R::ZERO; 2],
                        duv_dx: [R::ZERO; 2],
                        duv_dy: [R::ZERO; 2],
                        vertex_alpha: R::ONE,
                    },
                };
                // Clamped: a vertex colour's alpha may be given outside
                // [0, 1]; NaN becomes 0 (the surface shows nothing).
                let a = alpha.alpha(&inputs).clamp(R::ZERO, R::ONE);
                let col0 = (x as i32 - tx) as usize;
                for (ch, c) in [c.x, c.y, c.z].into_iter().enumerate() {
                    let row = &mut *rows[ch];
                    let mut dst = [0.0f32; 8];
                    for (i, d) in dst.iter_mut().enumerate().take(R::LANES) {
                        if let Some(v) = row.get(col0 + i) {
                            *d = *v;
                        }
                    }
                    let out = c * a + R::load(&dst) * (R::ONE - a);
                    for i in 0..R::LANES {
                        if lanes >> i & 1 == 1 {
                            row[col0 + i] = out.lane(i) as f32;
                        }
                    }
                }
            }
        });
    }
    shaded
}
