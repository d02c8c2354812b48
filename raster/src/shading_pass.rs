//! The shading pass: per tile, R::LANES pixels per packet; per material
//! present in the packet, that material's shader under the lane mask. The
//! results go to the row-major frame buffers (buffers.rs).

use crate::buffers::TileWriter;
use crate::fragment::Fragment;
use crate::post::LdrEncoding;
use crate::resolve::{PacketTris, ResolveContext};
use crate::scene::SceneData;
use crate::shader::{ShadeEnv, ShadeInput, ShadeLanes};
use crate::target::{Target, TILE};
use specula_core::{Real, Rgb, V3};
use std::ops::Range;

/// The frame buffers of one frame, open for tile-parallel writes. Planes
/// that were not requested are empty writers and get nothing.
pub(crate) struct ShadeTargets<'a> {
    pub(crate) color: [TileWriter<'a, f32>; 3],
    pub(crate) depth: TileWriter<'a, f32>,
    pub(crate) normal: [TileWriter<'a, f32>; 3],
    pub(crate) id: TileWriter<'a, u32>,
    /// 8-bit sRGB output encoded here, tile row by tile row (the colour
    /// then goes to the planes only if they are not empty).
    pub(crate) ldr: Option<(LdrEncoding, TileWriter<'a, [u8; 3]>)>,
}

/// Writes the first `out.len()` lanes of `v` (fewer than R::LANES only in
/// the last packet of an image row whose width is not a multiple of it).
#[inline(always)]
fn store<R: Real>(v: R, out: &mut [f32]) {
    if out.len() >= R::LANES {
        v.store(out);
    } else {
        let mut tmp = [0.0f32; 8];
        v.store(&mut tmp);
        out.copy_from_slice(&tmp[..out.len()]);
    }
}

/// Writes the first lanes of `rgb` to the colour rows at `px`.
#[inline(always)]
fn store_rgb<R: Real>(rgb: Rgb<R>, color: &mut [&mut [f32]; 3], px: Range<usize>) {
    store(rgb.x, &mut color[0][px.clone()]);
    store(rgb.y, &mut color[1][px.clone()]);
    store(rgb.z, &mut color[2][px]);
}

/// Every 8 pixels (each packet; every 8th pixel of the scalar twin), the
/// first and last triangles of the 8 after those from `at` in `ids` (a
/// new triangle in a packet is almost always at one of its ends), unless
/// the packet before them resolves the same one (most packets show one
/// large triangle, and the hints are not free).
#[inline(always)]
fn prefetch_next(ctx: &ResolveContext, ids: &[u32], at: usize) {
    if let (Some(&a), Some(&b)) = (ids.get(at + 8), ids.get(at + 15)) {
        if a != ids[at + 7] {
            ctx.prefetch(a);
        }
        if b != a {
            ctx.prefetch(b);
        }
    }
}

/// The lane types [`shade_tile`] runs, with the pair resolve where one has
/// it (here, not in `shader.rs`, which `resolve.rs` depends on).
pub(crate) trait TileLanes: ShadeLanes {
    /// The two packets at pixels x..x + 2 · LANES of row y, both showing
    /// the one triangle of `tris` in every lane, resolved together
    /// ([`ResolveContext::resolve_pair`]) into `out`, where the lane type
    /// has such a form: whether it has.
    ///
    /// # Safety
    /// The processor has AVX-512F, DQ, VL and BW
    /// ([`crate::packet_pairs::available`]).
    unsafe fn resolve_pair(
        _ctx: &ResolveContext,
        _x: u32,
        _y: u32,
        _tris: &PacketTris,
        _out: &mut [Fragment<Self>; 2],
    ) -> bool {
        false
    }
}

impl TileLanes for f32 {}

impl TileLanes for specula_core::f32x8 {
    #[inline(always)]
    unsafe fn resolve_pair(
        ctx: &ResolveContext,
        x: u32,
        y: u32,
        tris: &PacketTris,
        out: &mut [Fragment<Self>; 2],
    ) -> bool {
        // SAFETY: the processor has AVX-512 (this function's contract).
        #[cfg(target_arch = "x86_64")]
        unsafe {
            ctx.resolve_pair(x, y, tris, out)
        };
        cfg!(target_arch = "x86_64")
    }
}

/// Packets the shading pass holds back for one call of their material's
/// shader ([`ShadeLanes::shade_batch_with`]): the runs of packets of one
/// material in a tile row (a 64-pixel row is 8 packets of 8 lanes).
const BATCH: usize = 8;

struct Batch<R: Real> {
    frags: [Fragment<R>; BATCH],
    lanes: [u32; BATCH],
    /// Each packet's pixels in the tile row.
    px: [Range<usize>; BATCH],
    n: usize,
    material: u32,
}

impl<R: Real> Default for Batch<R> {
    fn default() -> Self {
        let zero = V3::zero();
        let frag = Fragment {
            p: zero,
            n: zero,
            wo: zero,
            w: R::ZERO,
            b1: R::ZERO,
            b2: R::ZERO,
        };
        Batch {
            frags: [frag; BATCH],
            lanes: [0; BATCH],
            px: std::array::from_fn(|_| 0..0),
            n: 0,
            material: 0,
        }
    }
}

impl<R: ShadeLanes> Batch<R> {
    /// Adds a packet (the batch is not full) whose fragment `resolve`
    /// writes into its place.
    #[inline(always)]
    fn push(
        &mut self,
        material: u32,
        lanes: u32,
        px: Range<usize>,
        resolve: impl FnOnce() -> Fragment<R>,
    ) -> &Fragment<R> {
        let i = self.n & (BATCH - 1);
        self.material = material;
        self.lanes[i] = lanes;
        self.px[i] = px;
        self.n = i + 1;
        self.frags[i] = resolve();
        &self.frags[i]
    }

    /// Adds two packets of one triangle over all their lanes, at `px` and
    /// the next `px.len()` pixels, whose fragments `resolve` writes into
    /// their places, when it does (it says whether), and when the batch has
    /// room for both (else the caller flushes it first).
    #[inline(always)]
    fn push_pair(
        &mut self,
        material: u32,
        px: Range<usize>,
        resolve: impl FnOnce(&mut [Fragment<R>; 2]) -> bool,
    ) -> bool {
        let i = self.n;
        let Some(slots) = self.frags.get_mut(i..i + 2) else {
            return false;
        };
        if !resolve(slots.try_into().expect("two slots")) {
            return false;
        }
        self.material = material;
        self.lanes[i..i + 2].fill((1 << R::LANES) - 1);
        self.px[i] = px.clone();
        self.px[i + 1] = px.end..px.end + px.len();
        self.n = i + 2;
        true
    }

    /// Shades the held packets and writes their colours (the background in
    /// lanes no triangle covers).
    #[inline(always)]
    fn flush(
        &mut self,
        scene: &SceneData,
        env: &ShadeEnv,
        background: Rgb<R>,
        color: &mut [&mut [f32]; 3],
    ) {
        let n = self.n.min(BATCH);
        if n == 0 {
            return;
        }
        self.n = 0;
        let shader = &*scene.materials[self.material as usize].shader;
        let mut out = [background; BATCH];
        R::shade_batch_with(
            shader,
            &self.frags[..n],
            &self.lanes[..n],
            env,
            &mut out[..n],
        );
        for ((c, &lanes), px) in out.iter().zip(&self.lanes).zip(&self.px).take(n) {
            let rgb = Rgb::select(R::mask_from_bits(lanes), *c, background);
            store_rgb(rgb, color, px.clone());
        }
    }
}

/// The map's radiance along the primary ray of every pixel of a tile row
/// that no triangle covers (`ids` the row's, from pixel `x0` of image row
/// `y`): each pixel's ray turned into the map's (u, v) eight at a time
/// ([`EnvMap::uv_toward`]), then read bilinearly.
#[cold]
fn env_background(
    map: &crate::envmap::EnvMap,
    view: &crate::camera::View,
    (x0, y): (usize, usize),
    ids: &[u32],
    color: &mut [&mut [f32]; 3],
) {
    use specula_core::f32x8;
    let ny = 1.0 - (y as f32 + 0.5) * 2.0 / view.height;
    let row_ray = view.forward + view.up * (ny * view.tan_y);
    let lane = <f32x8 as Real>::lane_index();
    for (k, ids) in ids.chunks(8).enumerate() {
        if ids.iter().all(|&id| id != crate::target::MISS) {
            continue;
        }
        let first = x0 + 8 * k;
        let px = lane + f32x8::splat(first as f32 + 0.5);
        let nx = px * f32x8::splat(2.0 / view.width) - f32x8::ONE;
        let nx = nx * f32x8::splat(view.tan_x);
        let d = V3::new(
            nx.mul_add(f32x8::splat(view.right.x), f32x8::splat(row_ray.x)),
            nx.mul_add(f32x8::splat(view.right.y), f32x8::splat(row_ray.y)),
            nx.mul_add(f32x8::splat(view.right.z), f32x8::splat(row_ray.z)),
        );
        let (u, v) = map.uv_toward(d);
        let (u, v) = (u.to_array(), v.to_array());
        for (l, &id) in ids.iter().enumerate() {
            if id == crate::target::MISS {
                let rgb = map.radiance_at(u[l], v[l]);
                for c in 0..3 {
                    color[c][8 * k + l] = rgb[c];
                }
            }
        }
    }
}

/// Shades tile `t` with lane type R: `ids` is the tile's slice of the
/// visibility buffer. Returns the number of covered pixels.
///
/// # Safety
/// The caller hands tile `t` to this call alone (see [`TileWriter`]).
pub(crate) unsafe fn shade_tile<R: TileLanes>(
    ctx: &ResolveContext,
    target: &Target,
    t: usize,
    ids: &[u32],
    out: &ShadeTargets,
) -> u64 {
    let scene = ctx.scene;
    let env = ShadeEnv {
        lights: &scene.lights,
        environment: scene.environment,
        env_map: scene.env_map.as_deref(),
        shadows: ctx.shadows,
        pair_packets: ctx.pair_packets,
    };
    let (tx, ty) = target.tile_origin(t);
    let background = scene.environment.unwrap_or(scene.background);
    let background_rgb: Rgb<R> = Rgb::from_f32(background);
    let mut covered = 0u64;
    let tile_w = TILE.min((target.width - tx) as usize);
    let mut tris = PacketTris::default();
    // A tile row's colour when the planes are not kept (LDR encoded in
    // place): it stays in L1 from the shading to the encode.
    let mut row_rgb = [[0.0f32; TILE]; 3];
    // Empty at the start of each row (each row flushes it at its end).
    let mut batch = Batch::<R>::default();
    // A packet's shadow factors per light, when it has several materials.
    let mut factors: Vec<R> = Vec::new();
    // Two packets of one triangle resolved as one where the processor has
    // AVX-512 (the fragments are the same bits).
    let pair_resolve = R::LANES == 8 && ctx.pair_packets && crate::packet_pairs::available();
    for plane in out.color.iter().chain(&out.normal).chain([&out.depth]) {
        plane.prefetch_row(tx as usize, ty as usize);
    }
    for row in 0..TILE.min((target.height - ty) as usize) {
        let y = (ty as usize) + row;
        let x0 = tx as usize;
        // SAFETY: tile t is this call's alone (the function's contract).
        let (planes, depth, normal, id_out) = unsafe {
            let [r, g, b] = &out.color;
            let [nx, ny, nz] = &out.normal;
            (
                [r.tile_row(x0, y), g.tile_row(x0, y), b.tile_row(x0, y)],
                out.depth.tile_row(x0, y),
                [nx.tile_row(x0, y), ny.tile_row(x0, y), nz.tile_row(x0, y)],
                out.id.tile_row(x0, y),
            )
        };
        let mut color = if planes[0].is_empty() {
            let [r, g, b] = &mut row_rgb;
            [&mut r[..tile_w], &mut g[..tile_w], &mut b[..tile_w]]
        } else {
            planes
        };
        if !id_out.is_empty() {
            id_out.copy_from_slice(&ids[row * TILE..row * TILE + tile_w]);
        }
        // The next row's lines, fetched while this row is shaded.
        for plane in out.color.iter().chain(&out.normal).chain([&out.depth]) {
            plane.prefetch_row(x0, y + 1);
        }
        if let Some((_, ldr)) = &out.ldr {
            ldr.prefetch_row(x0, y + 1);
        }
        let mut lx = 0;
        while lx < tile_w {
            let at = row * TILE + lx;
            let n_px = R::LANES.min(tile_w - lx);
            if lx % 8 == 0 {
                prefetch_next(ctx, ids, at);
            }
            // A packet showing the previous packet's one triangle in all
            // its lanes keeps that grouping instead of building it again.
            if !(R::LANES == 8 && tris.is_one_triangle_of(&ids[at..])) {
                tris.fill(&ids[at..], R::LANES, Some(ctx));
            }
            let px = lx..lx + n_px;
            lx += R::LANES;
            if tris.n == 0 {
                store_rgb(background_rgb, &mut color, px.clone());
                if !depth.is_empty() {
                    store(R::splat(f64::INFINITY), &mut depth[px.clone()]);
                }
                if !normal[0].is_empty() {
                    store(R::ZERO, &mut normal[0][px.clone()]);
                    store(R::ZERO, &mut normal[1][px.clone()]);
                    store(R::ZERO, &mut normal[2][px.clone()]);
                }
                continue;
            }
            covered += tris.covered.count_ones() as u64;
            // The usual packet, one material whose shader needs no
            // surface, joins the row's run of packets of that material
            // (resolved into its place there). Not in the scalar twin: a
            // 1-pixel packet pays more for its place in the batch than it
            // saves of the call (its shading pass measured 106.3 -> 116.4 M
            // instructions at 480×270 batched).
            let material = tris.group_material[0];
            let batched = R::LANES > 1 && tris.groups == 1 && !ctx.needs_surface[material as usize];
            if batched && (batch.n == BATCH || (batch.n > 0 && batch.material != material)) {
                batch.flush(scene, &env, background_rgb, &mut color);
            }
            // A packet showing one triangle alone is most often followed by
            // another showing it alone: where `pair_resolve`, the two are
            // resolved at once and join the batch together.
            let next = at + R::LANES..at + 2 * R::LANES;
            if batched
                && pair_resolve
                && depth.is_empty()
                && normal[0].is_empty()
                && lx + R::LANES <= tile_w
                && tris.is_one_triangle_of(&ids[next])
            {
                // (A batch of another material was flushed just above.)
                if batch.n + 2 > BATCH {
                    batch.flush(scene, &env, background_rgb, &mut color);
                }
                let x = tx + px.start as u32;
                // SAFETY: `pair_resolve` found AVX-512.
                let resolve =
                    |out: &mut _| unsafe { R::resolve_pair(ctx, x, y as u32, &tris, out) };
                if batch.push_pair(material, px.clone(), resolve) {
                    prefetch_next(ctx, ids, at + R::LANES);
                    covered += R::LANES as u64;
                    lx += R::LANES;
                    continue;
                }
            }
            let resolved;
            let frag = if batched {
                batch.push(material, tris.group_lanes[0], px.clone(), || {
                    ctx.resolve::<R>(tx + px.start as u32, y as u32, &tris)
                })
            } else {
                resolved = ctx.resolve::<R>(tx + px.start as u32, y as u32, &tris);
                &resolved
            };
            if !depth.is_empty() || !normal[0].is_empty() {
                let hit = R::mask_from_bits(tris.covered);
                if !depth.is_empty() {
                    store(
                        R::select(hit, frag.w, R::splat(f64::INFINITY)),
                        &mut depth[px.clone()],
                    );
                }
                if !normal[0].is_empty() {
                    let n = V3::select(hit, frag.n, V3::zero());
                    store(n.x, &mut normal[0][px.clone()]);
                    store(n.y, &mut normal[1][px.clone()]);
                    store(n.z, &mut normal[2][px.clone()]);
                }
            }
            if batched {
                continue;
            }
            // The mesh's uv frame only for shaders that read the surface
            // (anisotropic models, textures); any frame for the rest.
            let groups = 0..tris.groups;
            let needs = |g: usize| ctx.needs_surface[tris.group_material[g] as usize];
            let surface = (ctx.any_needs_surface && groups.clone().any(needs))
                .then(|| ctx.surface(&tris, frag));
            // A packet of several materials (most sit on silhouettes, where
            // a lane's PCF taps straddle two depths and read them all) has
            // its shadow factors looked up once for every covered lane,
            // not once per material.
            let shadow_factors = match ctx.shadows {
                Some(maps) if tris.groups > 1 => {
                    factors.clear();
                    factors.extend((0..scene.lights.len()).map(|k| match maps.light(k) {
                        Some(s) => s.visibility_lanes(&frag.p, &frag.n, tris.covered),
                        None => R::ONE,
                    }));
                    Some(&factors[..])
                }
                _ => None,
            };
            // Shade once per material present, under its lanes' mask.
            let mut rgb = background_rgb;
            for g in groups {
                let input = ShadeInput {
                    frag,
                    surface: surface.as_ref().filter(|_| needs(g)),
                    lanes: tris.group_lanes[g],
                    shadow_factors,
                };
                let shader = &*scene.materials[tris.group_material[g] as usize].shader;
                let c = R::shade_with(shader, &input, &env);
                rgb = Rgb::select(R::mask_from_bits(input.lanes), c, rgb);
            }
            store_rgb(rgb, &mut color, px);
        }
        batch.flush(scene, &env, background_rgb, &mut color);
        if let Some(map) = scene.env_map.as_deref().filter(|m| m.visible) {
            let row_ids = &ids[row * TILE..row * TILE + tile_w];
            env_background(map, ctx.view, (x0, y), row_ids, &mut color);
        }
        if let Some((enc, ldr)) = &out.ldr {
            // SAFETY: as the rows above.
            let bytes = unsafe { ldr.tile_row(x0, y) };
            enc.encode_row(color[0], color[1], color[2], bytes.as_flattened_mut());
        }
    }
    covered
}
