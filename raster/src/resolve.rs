//! Resolve: from visibility-buffer ids back to surface attributes at pixel
//! centres, R::LANES horizontally adjacent pixels at a time.

use crate::buffers::prefetch;
use crate::camera::View;
use crate::fragment::{Fragment, Surface};
use crate::geometry::IdMap;
use crate::scene::SceneData;
use crate::setup::TriPlanes;
use crate::target::MISS;
use specula_core::{Mask, Real, ShadingFrame, V3};
use wide::u32x8;

/// Everything resolve and shading read, shared by all tiles.
pub struct ResolveContext<'a> {
    pub(crate) scene: &'a SceneData,
    pub(crate) planes: &'a [TriPlanes],
    pub(crate) view: &'a View,
    pub(crate) ids: IdMap,
    /// Per material: its shader reads the surface (uvs, tangents).
    pub(crate) needs_surface: Vec<bool>,
    /// Some material's shader does.
    pub(crate) any_needs_surface: bool,
    /// 2 / width and 2 / height of the view (pixel → NDC), as `resolve`
    /// rounds them: divided once here instead of in every packet.
    ndc_scale: [f32; 2],
    /// The frame's shadow maps, when some light has shadows.
    pub(crate) shadows: Option<&'a crate::shadow::ShadowMaps>,
    /// [`ShadeEnv::pair_packets`](crate::shader::ShadeEnv::pair_packets).
    pub(crate) pair_packets: bool,
}

impl<'a> ResolveContext<'a> {
    pub fn new(scene: &'a SceneData, planes: &'a [TriPlanes], view: &'a View) -> Self {
        let needs_surface: Vec<bool> = scene
            .materials
            .iter()
            .map(|m| m.shader.needs_surface())
            .collect();
        ResolveContext {
            scene,
            planes,
            view,
            ids: IdMap::new(&scene.geometry),
            any_needs_surface: needs_surface.contains(&true),
            needs_surface,
            ndc_scale: [
                (2.0 / view.width as f64) as f32,
                (2.0 / view.height as f64) as f32,
            ],
            shadows: None,
            pair_packets: false,
        }
    }
}

/// The distinct triangles of one packet and the lanes each covers.
#[derive(Clone, Copy, Debug, Default)]
pub struct PacketTris {
    pub(crate) n: usize,
    /// Visibility-buffer ids.
    pub(crate) id: [u32; 8],
    /// Their source triangles and materials (filled by [`PacketTris::new`]).
    pub(crate) tri: [u32; 8],
    pub(crate) material: [u32; 8],
    /// Bit i set: lane i shows triangle `id[t]`.
    pub(crate) lanes: [u32; 8],
    /// Lanes covered by any triangle.
    pub(crate) covered: u32,
    /// The distinct materials of the packet (filled by [`PacketTris::new`]),
    /// in order of first appearance, and the lanes each covers: the shading
    /// pass calls one shader per entry.
    pub(crate) groups: usize,
    pub(crate) group_material: [u32; 8],
    pub(crate) group_lanes: [u32; 8],
}

impl PacketTris {
    /// Groups the first `lanes` ids (MISS lanes belong to no group) and
    /// looks up each group's source triangle and material.
    #[inline(always)]
    pub fn new(ids: &[u32], lanes: usize, ctx: &ResolveContext) -> PacketTris {
        let mut p = PacketTris::default();
        p.fill(ids, lanes, Some(ctx));
        p
    }

    /// The grouping alone (`tri` and `material` left zero).
    #[cfg(test)]
    pub(crate) fn group(ids: &[u32], lanes: usize) -> PacketTris {
        let mut p = PacketTris::default();
        p.fill(ids, lanes, None);
        p
    }

    /// Whether this grouping holds one triangle over all 8 lanes and the
    /// first 8 of `ids` all show it: then [`PacketTris::fill`] of `ids`
    /// would write what is already here (with the same context). Most
    /// packets of a large triangle follow one of the same triangle.
    #[inline(always)]
    pub(crate) fn is_one_triangle_of(&self, ids: &[u32]) -> bool {
        if self.n != 1 || self.covered != 0xFF {
            return false;
        }
        let Some(ids) = ids.first_chunk::<8>() else {
            return false;
        };
        u32x8::new(*ids)
            .simd_eq(u32x8::splat(self.id[0]))
            .to_bitmask()
            == 0xFF
    }

    /// [`PacketTris::new`] in place: the shading pass keeps one across
    /// packets. (Returning the struct by value cost a third of the pass:
    /// its fields are written by scalar stores and the copy reads them
    /// back with vector loads, which stall on store forwarding.)
    #[inline(always)]
    pub(crate) fn fill(&mut self, ids: &[u32], lanes: usize, ctx: Option<&ResolveContext>) {
        if lanes == 8 {
            // One vector compare per run of lanes showing one triangle,
            // taken in lane order: a run whose triangle an earlier lane
            // shows was grouped with it. Runs are found at once (each lane
            // against its left neighbour), so a round does not wait on the
            // previous one's compare; the counts live in registers until
            // the end, and indices are masked to 0..8 (a no-op: they are
            // bit positions of an 8-bit mask), so the loop has no bounds
            // checks or reloads.
            let ids: [u32; 8] = ids[..8].try_into().expect("8 ids");
            let v = u32x8::new(ids);
            let covered = !v.simd_eq(u32x8::splat(MISS)).to_bitmask() & 0xFF;
            self.covered = covered;
            let same_as_left = v.simd_eq(left_neighbours(v)).to_bitmask();
            let mut starts = (!same_as_left | 1) & covered;
            let mut n = 0;
            while starts != 0 {
                let i = starts.trailing_zeros() as usize & 7;
                starts &= starts - 1;
                let id = ids[i];
                let lanes = v.simd_eq(u32x8::splat(id)).to_bitmask();
                if lanes & ((1 << i) - 1) != 0 {
                    continue;
                }
                self.id[n & 7] = id;
                self.lanes[n & 7] = lanes;
                n += 1;
            }
            self.n = n;
        } else {
            self.n = 0;
            self.covered = 0;
            for (i, &id) in ids[..lanes].iter().enumerate() {
                if id == MISS {
                    continue;
                }
                self.covered |= 1 << i;
                let t = match self.id[..self.n].iter().position(|&x| x == id) {
                    Some(t) => t,
                    None => {
                        self.id[self.n] = id;
                        self.lanes[self.n] = 0;
                        self.n += 1;
                        self.n - 1
                    }
                };
                self.lanes[t] |= 1 << i;
            }
        }
        self.groups = 0;
        let Some(ctx) = ctx else {
            return;
        };
        let mut groups = 0usize;
        for t in 0..self.n.min(8) {
            let (tri, m) = ctx.ids.look_up(self.id[t], &ctx.scene.tri_material);
            (self.tri[t], self.material[t]) = (tri, m);
            // Packets hold one material almost always: the last group is
            // tested first, without the search (which cost ~20
            // instructions a packet).
            let last = groups.wrapping_sub(1) & 7;
            if groups > 0 && self.group_material[last] == m {
                self.group_lanes[last] |= self.lanes[t];
                continue;
            }
            match (0..groups).find(|&g| self.group_material[g] == m) {
                Some(g) => self.group_lanes[g] |= self.lanes[t],
                None => {
                    self.group_material[groups & 7] = m;
                    self.group_lanes[groups & 7] = self.lanes[t];
                    groups += 1;
                }
            }
        }
        self.groups = groups;
    }
}

/// Lane i of the result is lane i − 1 of `v` (lane 0 is lane 0).
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
fn left_neighbours(v: u32x8) -> u32x8 {
    use core::arch::x86_64::{_mm256_permutevar8x32_epi32, _mm256_setr_epi32};
    // SAFETY: AVX2 is enabled (cfg); register operations only.
    unsafe {
        bytemuck::cast(_mm256_permutevar8x32_epi32(
            bytemuck::cast(v),
            _mm256_setr_epi32(0, 0, 1, 2, 3, 4, 5, 6),
        ))
    }
}

/// [`left_neighbours`] lane by lane: the form other targets use, and
/// what the AVX2 form is tested against.
#[cfg(any(test, not(all(target_arch = "x86_64", target_feature = "avx2"))))]
#[inline(always)]
fn left_neighbours_by_lane(v: u32x8) -> u32x8 {
    let a = v.to_array();
    u32x8::new(core::array::from_fn(|i| a[i.saturating_sub(1)]))
}

/// Lane i of the result is lane i − 1 of `v` (lane 0 is lane 0).
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
#[inline(always)]
fn left_neighbours(v: u32x8) -> u32x8 {
    left_neighbours_by_lane(v)
}

/// `c` in every lane.
#[inline(always)]
fn splat<R: Real>(c: f32) -> R {
    R::splat(c as f64)
}

/// The plane k (its x and y slopes and value at the origin) at offsets
/// (`dx`, `dy`) from the origin.
#[inline(always)]
fn plane<R: Real>(k: [f32; 3], dx: R, dy: R) -> R {
    splat::<R>(k[0]).mul_add(dx, splat::<R>(k[1]).mul_add(dy, splat(k[2])))
}

/// Smallest n·wo the shading normal is allowed (see `resolve`).
const MIN_COS_VIEW: f64 = 0.02;

impl ResolveContext<'_> {
    /// Hints the cache to bring in what resolving visibility-buffer id `id`
    /// reads (its planes, source triangle and material), for a packet
    /// shaded soon: a packet's new triangles are scattered through arrays
    /// of the whole scene. No effect on results; MISS reads nothing.
    #[inline(always)]
    pub(crate) fn prefetch(&self, id: u32) {
        let Some(planes) = self.planes.get(id as usize) else {
            return;
        };
        prefetch(planes);
        if self.ids.is_identity() {
            if let Some(m) = self.scene.tri_material.get(id as usize) {
                prefetch(m);
            }
            if let Some(t) = self.scene.triangles.get(id as usize) {
                prefetch(t);
            }
        }
    }

    /// Rebuilds the fragments of pixels (x + lane, y) covered by the
    /// triangles of `tris` (at least one; from [`PacketTris::new`]).
    ///
    /// Packets hold one triangle mostly (the ground) or 3–5 (the spheres'
    /// small ones). Each triangle's data is read once, broadcast, evaluated
    /// at every lane and the result kept in the lanes it covers, in two
    /// rounds: first the barycentric planes, then the normals, which the
    /// planes' values of each lane weight. Evaluating everything of a
    /// triangle at once, or selecting its 21 inputs before evaluating them,
    /// kept more values live than the 16 registers hold: each further
    /// triangle cost more with the spills than it does now. (A
    /// per-lane gather through memory, 8 scalar stores then a vector load,
    /// stalls on store forwarding.) Lanes no triangle covers carry the first
    /// triangle's values, so they stay finite; callers mask them.
    ///
    /// No closures here or in the helpers (functions inlined always): the
    /// sixteen-lane form (`ResolveContext::resolve_pair`) inlines all of
    /// it into code compiled for AVX-512, which a closure not inlined
    /// would leave as calls.
    #[inline(always)]
    pub fn resolve<R: Real>(&self, x: u32, y: u32, tris: &PacketTris) -> Fragment<R> {
        debug_assert!(tris.n > 0);
        let px = R::splat(x as f64 + 0.5) + R::lane_index();
        let py = R::splat(y as f64 + 0.5);
        // k1, k2, Σk (= 1/w) and the facing sign of each lane's triangle.
        let mut k = self.tri_planes(tris.id[0], px, py);
        for t in 1..tris.n {
            let m = R::mask_from_bits(tris.lanes[t]);
            let kt = self.tri_planes(tris.id[t], px, py);
            for (k, kt) in k.iter_mut().zip(kt) {
                *k = R::select(m, kt, *k);
            }
        }
        let [k1, k2, ks, facing] = k;
        // Σk = 1/w > 0 at every covered pixel centre.
        let w = ks.rcp();
        let b1 = k1 * w;
        let b2 = k2 * w;
        // The normal is interpolated with the unnormalized weights k = b·Σk
        // (its direction is the same: Σk > 0), so its chain of dependent
        // steps does not wait for the reciprocal; |k| ≥ |b|/w_far keeps the cancellation
        // test of `normalize_or` meaningful. The facing sign goes into the
        // weights: ±1, so the normal is the same bits as flipping it after.
        // (No array `map` here: its closure was not inlined.)
        let f = [(ks - k1 - k2) * facing, k1 * facing, k2 * facing];
        let mut n_interp = self.tri_normal(tris.tri[0], f);
        for t in 1..tris.n {
            let m = R::mask_from_bits(tris.lanes[t]);
            n_interp = V3::select(m, self.tri_normal(tris.tri[t], f), n_interp);
        }

        // The primary ray through the pixel centre (camera.rs); its point at
        // view depth w is the surface point.
        let v = self.view;
        let (sx, sy) = (
            R::splat(self.ndc_scale[0] as f64),
            R::splat(self.ndc_scale[1] as f64),
        );
        let nx = px * sx - R::ONE;
        let ny = R::ONE - py * sy;
        let ray = V3::from_f32(v.forward.to_array())
            + V3::from_f32(v.right.to_array()) * (nx * R::splat(v.tan_x as f64))
            + V3::from_f32(v.up.to_array()) * (ny * R::splat(v.tan_y as f64));
        let p = ray.mul_add(w, V3::from_f32(v.eye.to_array()));
        let wo = -ray.normalize();
        // Interpolated normals can cancel (opposite vertex normals): such a
        // lane takes the direction toward the eye rather than NaN.
        let n = n_interp.normalize_or(wo);
        // Interpolated normals near a silhouette can face away from the eye,
        // where every BRDF is zero: black speckles along smooth outlines.
        // Bend such normals until n·wo = MIN_COS_VIEW (the usual
        // shading-normal fix; geometry and the eval contract are untouched).
        // Such lanes are few (near silhouettes), so the bend is skipped
        // when a packet has none.
        let cos_v = n.dot(wo);
        let min_cos = R::splat(MIN_COS_VIEW);
        let away = cos_v.lt(min_cos);
        let n = if away.any() {
            let bent = (n - wo * (cos_v - min_cos)).normalize_or(wo);
            V3::select(away, bent, n)
        } else {
            n
        };
        Fragment {
            p,
            n,
            wo,
            w,
            b1,
            b2,
        }
    }

    /// Triangle `id`'s planes k1, k2 and Σk at pixel centres (`px`, `py`),
    /// and its facing sign.
    #[inline(always)]
    fn tri_planes<R: Real>(&self, id: u32, px: R, py: R) -> [R; 4] {
        let p = &self.planes[id as usize];
        let dx = px - splat(p.origin[0]);
        let dy = py - splat(p.origin[1]);
        [
            plane(p.k1, dx, dy),
            plane(p.k2, dx, dy),
            plane(p.ks, dx, dy),
            splat(p.facing),
        ]
    }

    /// Source triangle `tri`'s vertex normals weighted by `f` (one weight
    /// a vertex).
    #[inline(always)]
    fn tri_normal<R: Real>(&self, tri: u32, [f0, f1, f2]: [R; 3]) -> V3<R> {
        let [i0, i1, i2] = self.scene.triangles[tri as usize];
        let n2 = self.vertex_normal::<R>(i2);
        n2.mul_add(
            f2,
            self.vertex_normal(i1)
                .mul_add(f1, self.vertex_normal(i0) * f0),
        )
    }

    /// Vertex `i`'s normal in every lane.
    #[inline(always)]
    fn vertex_normal<R: Real>(&self, i: u32) -> V3<R> {
        let n = self.scene.normals[i as usize];
        V3::new(splat(n.x), splat(n.y), splat(n.z))
    }

    /// [`ResolveContext::resolve`] into `out` of the two packets at pixels x..x + 16
    /// of row y as one sixteen-lane packet, where both show the one
    /// triangle of `tris` in every lane (`tris` the first packet's
    /// grouping). Each lane does what the eight-lane resolve does (the
    /// second packet's pixel centres x + 8.5 + i are exact either way),
    /// so the fragments are the same bits, made with half the
    /// instructions.
    ///
    /// # Safety
    /// The processor has AVX-512F, DQ, VL and BW
    /// ([`crate::packet_pairs::available`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
    pub(crate) unsafe fn resolve_pair(
        &self,
        x: u32,
        y: u32,
        tris: &PacketTris,
        out: &mut [Fragment<specula_core::f32x8>; 2],
    ) {
        use crate::lanes16::{fragment_half, F32x16};
        debug_assert!(tris.n == 1 && tris.covered == 0xFF);
        let f = self.resolve::<F32x16>(x, y, tris);
        *out = [fragment_half::<false>(&f), fragment_half::<true>(&f)];
    }

    /// Interpolated uv, its analytic screen derivatives and the tangent
    /// frame of `frag` (which `resolve` built from the same `tris`). Only
    /// materials that sample textures need these, so it is a separate step.
    #[inline(always)]
    pub fn surface<R: Real>(&self, tris: &PacketTris, frag: &Fragment<R>) -> Surface<R> {
        let scene = self.scene;
        let (color, alpha) = self.vertex_color(tris, frag);
        if scene.uvs.is_empty() {
            return Surface {
                uv: [R::ZERO; 2],
                duv_dx: [R::ZERO; 2],
                duv_dy: [R::ZERO; 2],
                tangent: V3::zero(),
                bitangent_sign: R::ONE,
                frame: ShadingFrame::from_normal(frag.n),
                color,
                alpha,
            };
        }
        // Per triangle: uv0, uv1 − uv0, uv2 − uv0, three tangents (xyz),
        // vertex 0's handedness, and the screen gradients [∂/∂x, ∂/∂y] of
        // the barycentric planes k1, k2 and Σk.
        const N: usize = 6 + 9 + 1 + 6;
        let gathered = |t: usize| -> [f32; N] {
            let p = &self.planes[tris.id[t] as usize];
            let tri = scene.triangles[tris.tri[t] as usize];
            let [uv0, uv1, uv2] = tri.map(|i| scene.uvs[i as usize]);
            let (e1, e2) = (uv1 - uv0, uv2 - uv0);
            let [t0, t1, t2] = tri.map(|i| scene.tangents[i as usize]);
            [
                uv0.x, uv0.y, e1.x, e1.y, e2.x, e2.y, t0.x, t0.y, t0.z, t1.x, t1.y, t1.z, t2.x,
                t2.y, t2.z, t0.w, p.k1[0], p.k1[1], p.k2[0], p.k2[1], p.ks[0], p.ks[1],
            ]
        };
        let mut lanes = gathered(0).map(|c| R::splat(c as f64));
        for t in 1..tris.n {
            let m = R::mask_from_bits(tris.lanes[t]);
            for (l, c) in lanes.iter_mut().zip(gathered(t)) {
                *l = R::select(m, R::splat(c as f64), *l);
            }
        }
        let g = |k: usize| lanes[k];
        let (b1, b2) = (frag.b1, frag.b2);
        let uv = [
            g(2).mul_add(b1, g(4).mul_add(b2, g(0))),
            g(3).mul_add(b1, g(5).mul_add(b2, g(1))),
        ];
        // b = k / Σk with k and Σk affine in screen space, so
        // ∂b/∂x = (∂k/∂x − b ∂Σk/∂x)·w (and likewise for y), analytic.
        let db = |axis: usize, k: usize, b: R| (g(k + axis) - b * g(20 + axis)) * frag.w;
        let d = |axis: usize| {
            let (d1, d2) = (db(axis, 16, b1), db(axis, 18, b2));
            [g(2).mul_add(d1, g(4) * d2), g(3).mul_add(d1, g(5) * d2)]
        };
        let b0 = R::ONE - b1 - b2;
        let vt = |k: usize| V3::new(g(k), g(k + 1), g(k + 2));
        let t = vt(6) * b0 + vt(9) * b1 + vt(12) * b2;
        // Gram–Schmidt against the shading normal.
        let t = (t - frag.n * frag.n.dot(t)).normalize_or(V3::zero());
        let any = ShadingFrame::from_normal(frag.n);
        let tangent_frame = ShadingFrame::from_normal_tangent(frag.n, t, g(15));
        let has = t.length_squared().gt(R::HALF);
        Surface {
            uv,
            duv_dx: d(0),
            duv_dy: d(1),
            tangent: t,
            bitangent_sign: g(15),
            frame: ShadingFrame {
                t: V3::select(has, tangent_frame.t, any.t),
                b: V3::select(has, tangent_frame.b, any.b),
                n: frag.n,
            },
            color,
            alpha,
        }
    }

    /// The vertex colour (RGB, alpha) of `frag`, interpolated with its
    /// perspective-correct barycentrics; 1 where the scene has none.
    #[inline(always)]
    fn vertex_color<R: Real>(&self, tris: &PacketTris, frag: &Fragment<R>) -> (V3<R>, R) {
        let scene = self.scene;
        if scene.colors.is_empty() {
            return (V3::splat(R::ONE), R::ONE);
        }
        // Per triangle: c0, c1 − c0, c2 − c0 (RGBA each).
        let gathered = |t: usize| -> [f32; 12] {
            let tri = scene.triangles[tris.tri[t] as usize];
            let [c0, c1, c2] = tri.map(|i| scene.colors[i as usize]);
            let (e1, e2) = (c1 - c0, c2 - c0);
            [
                c0.x, c0.y, c0.z, c0.w, e1.x, e1.y, e1.z, e1.w, e2.x, e2.y, e2.z, e2.w,
            ]
        };
        let mut lanes = gathered(0).map(|c| R::splat(c as f64));
        for t in 1..tris.n {
            let m = R::mask_from_bits(tris.lanes[t]);
            for (l, c) in lanes.iter_mut().zip(gathered(t)) {
                *l = R::select(m, R::splat(c as f64), *l);
            }
        }
        let (b1, b2) = (frag.b1, frag.b2);
        let c = |k: usize| lanes[k + 4].mul_add(b1, lanes[k + 8].mul_add(b2, lanes[k]));
        (V3::new(c(0), c(1), c(2)), c(3))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packet_grouping_is_the_same_for_8_lanes_and_one_at_a_time() {
        let cases: [[u32; 8]; 4] = [
            [5; 8],
            [MISS, 1, 1, 2, MISS, 2, 3, 1],
            [MISS; 8],
            [0, 1, 2, 3, 4, 5, 6, 7],
        ];
        for ids in cases {
            let p = PacketTris::group(&ids, 8);
            let mut seen = 0u32;
            for t in 0..p.n {
                for lane in 0..8 {
                    let mine = p.lanes[t] & (1 << lane) != 0;
                    assert_eq!(mine, ids[lane] == p.id[t], "{ids:?}");
                }
                assert_eq!(seen & p.lanes[t], 0);
                seen |= p.lanes[t];
            }
            assert_eq!(seen, p.covered);
            let scalar_covered: u32 = (0..8)
                .filter(|&i| PacketTris::group(&ids[i..], 1).n == 1)
                .map(|i| 1 << i)
                .sum();
            assert_eq!(p.covered, scalar_covered, "{ids:?}");
        }
    }

    #[test]
    fn left_neighbours_shift_lanes_up_by_one() {
        for seed in 0..64u32 {
            let v = u32x8::new(core::array::from_fn(|i| {
                (seed.wrapping_mul(2_654_435_761) ^ (i as u32).wrapping_mul(40_503)) % 5
            }));
            let got = left_neighbours(v).to_array();
            assert_eq!(got, left_neighbours_by_lane(v).to_array(), "{v:?}");
            let a = v.to_array();
            assert_eq!(got[0], a[0]);
            assert!((1..8).all(|i| got[i] == a[i - 1]), "{v:?}");
        }
    }

    /// The 8-lane grouping against one built lane by lane here: the
    /// distinct ids in order of first appearance, each with the lanes that
    /// show it; on every packet of ids drawn from three triangles and
    /// MISS, so that a triangle comes back after another or after a gap.
    #[test]
    fn packet_grouping_lists_triangles_in_order_of_first_appearance() {
        let symbols = [7, 9, 11, MISS];
        for code in 0..4u32.pow(8) {
            let ids: [u32; 8] = core::array::from_fn(|i| symbols[(code >> (2 * i)) as usize & 3]);
            let (mut id, mut lanes) = (Vec::new(), Vec::<u32>::new());
            for (lane, &x) in ids.iter().enumerate() {
                if x == MISS {
                    continue;
                }
                match id.iter().position(|&y| y == x) {
                    Some(t) => lanes[t] |= 1 << lane,
                    None => {
                        id.push(x);
                        lanes.push(1 << lane);
                    }
                }
            }
            let p = PacketTris::group(&ids, 8);
            assert_eq!(p.n, id.len(), "{ids:?}");
            assert_eq!(&p.id[..p.n], &id[..], "{ids:?}");
            assert_eq!(&p.lanes[..p.n], &lanes[..], "{ids:?}");
            assert_eq!(p.covered, lanes.iter().fold(0, |a, l| a | l), "{ids:?}");
        }
    }

    #[test]
    fn a_grouping_is_kept_only_where_a_fresh_one_would_be_the_same() {
        let packets: [[u32; 8]; 7] = [
            [5; 8],
            [5; 8],
            [5, 5, 5, 5, 5, 5, 5, 6],
            [MISS, 5, 5, 5, 5, 5, 5, 5],
            [6; 8],
            [MISS; 8],
            [6; 8],
        ];
        let mut kept = PacketTris::default();
        let mut reused = 0;
        for pair in packets.windows(2) {
            let [before, now] = [pair[0], pair[1]];
            kept.fill(&before, 8, None);
            let fresh = PacketTris::group(&now, 8);
            if kept.is_one_triangle_of(&now) {
                reused += 1;
                let k = (kept.n, kept.id[0], kept.lanes[0], kept.covered, kept.groups);
                let f = (
                    fresh.n,
                    fresh.id[0],
                    fresh.lanes[0],
                    fresh.covered,
                    fresh.groups,
                );
                assert_eq!(k, f, "{before:?} -> {now:?}");
            }
        }
        // Only [5; 8] after [5; 8]: not after a packet with a MISS lane or
        // a second triangle, not for another triangle, not after none.
        assert_eq!(reused, 1);
        assert!(!kept.is_one_triangle_of(&[6; 7]), "fewer than 8 ids");
    }
}
