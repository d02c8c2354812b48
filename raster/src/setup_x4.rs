//! Triangle setup of 4 source triangles at once in f64x4: the common case of
//! [`SetupContext::setup`] (every vertex valid and inside the guard band, so
//! no clipping), bit for bit.
//!
//! Each lane performs the scalar path's IEEE operations in the scalar path's
//! order (no FMA where it multiplies and adds, no reassociation, `snap`'s
//! ties-to-even, f64 → f32 rounding to nearest), so it produces the same
//! bits: the invalid check, the outcodes and trivial reject, the
//! 2D-homogeneous adjugate and determinant (orientation, cull), the
//! guard-band test, projection and snapping, the planes and their bound.
//! The integer edge functions are computed in f64x4 too, where f64 holds
//! every intermediate exactly (vertices within 2¹⁶ pixels of the origin,
//! see `EXACT_FIXED`); a lane beyond it calls the i64
//! [`SetupContext::edges`]. A lane the fast path does not cover (a NaN,
//! infinite or huge coordinate, a zero or non-finite determinant, a
//! triangle that needs clipping, a non-finite projection) is set up by the
//! scalar [`SetupContext::setup`] instead, in its turn, so the screen
//! triangles reach `out` in source order and the counts are the scalar
//! ones. The scalar `setup` stays the reference: a change to it must be
//! made here too, and `setup_x4/tests.rs` (random and hand-picked
//! triangles, every outcome of each lane) fails until it is.

use crate::fixed::{GUARD_BAND_PX, SUBPIXEL_HALF, SUBPIXEL_ONE};
use crate::geometry::Cull;
use crate::occlusion::{block_index, DepthBounds, HI_OFFSET, LO_OFFSET};
use crate::setup::{
    Edge, RasterTri, SetupContext, SetupCounts, SetupPlanes, SmallEdges, TriPlanes, MAX_CLIP_COORD,
    MAX_PLANE_VALUE, SMALL_PX,
};
use wide::f64x4;

/// Triangles per call of [`SetupContext::setup_x4`].
pub const LANES: usize = 4;

/// What the first, cheap part of setup decided for one lane.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Lane {
    /// Set up by the scalar path (rare inputs; see the module doc).
    Scalar,
    /// All three vertices outside one frustum plane.
    Outside,
    /// Its facing is not drawn by the pass.
    Culled,
    /// Behind what earlier passes drew (`occlusion`).
    Occluded,
    /// Projected, snapped and given planes here.
    Fast,
}

/// How each lane ended, counted per thread by the tests so they can show
/// the fast path ran (a suite that always fell back would pass too).
#[cfg(test)]
mod trace {
    use std::cell::Cell;
    /// Scalar, outside, culled, fast drawn, fast no samples, fast
    /// unbounded; and apart, fast lanes whose edges were scalar.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
    pub(super) struct Paths(pub(super) [u64; 7]);
    thread_local!(pub(super) static PATHS: Cell<Paths> = Cell::new(Paths::default()));
    pub(super) fn hit(i: usize) {
        PATHS.with(|p| {
            let mut v = p.get();
            v.0[i] += 1;
            p.set(v);
        });
    }
}

#[cfg(test)]
use trace::hit;
#[cfg(not(test))]
#[inline(always)]
fn hit(_: usize) {}

/// Lane `t` of a mask as a bool.
#[inline(always)]
fn bit(mask: u32, t: usize) -> bool {
    mask >> t & 1 != 0
}

/// f64 → f32 per lane, rounding to nearest like `as f32`, and back to f64.
#[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
#[inline(always)]
fn to_f32(x: f64x4) -> ([f32; 4], f64x4) {
    use core::arch::x86_64::{_mm256_cvtpd_ps, _mm256_cvtps_pd};
    // SAFETY: AVX is enabled (cfg). vcvtpd2ps rounds by MXCSR, nearest by
    // default, as the scalar cvtsd2ss of `as f32` does.
    unsafe {
        let n = _mm256_cvtpd_ps(bytemuck::cast(x));
        (bytemuck::cast(n), bytemuck::cast(_mm256_cvtps_pd(n)))
    }
}

#[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
#[inline(always)]
fn to_f32(x: f64x4) -> ([f32; 4], f64x4) {
    let n = x.to_array().map(|c| c as f32);
    (n, f64x4::new(n.map(f64::from)))
}

/// Clip-space vertices of 4 triangles, structure of arrays in f64 (exact:
/// they come from f32): `x[j]` holds vertex j's x of the 4 triangles.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Vertices4 {
    pub(crate) x: [f64x4; 3],
    pub(crate) y: [f64x4; 3],
    pub(crate) z: [f64x4; 3],
    pub(crate) w: [f64x4; 3],
}

impl Vertices4 {
    /// From per-triangle arrays `v[t][j]` (vertex j of triangle t).
    #[inline(always)]
    pub(crate) fn from_arrays(v: &[[[f32; 4]; 3]; LANES]) -> Vertices4 {
        let coord = |j: usize, c: usize| f64x4::new(std::array::from_fn(|t| v[t][j][c] as f64));
        Vertices4 {
            x: std::array::from_fn(|j| coord(j, 0)),
            y: std::array::from_fn(|j| coord(j, 1)),
            z: std::array::from_fn(|j| coord(j, 2)),
            w: std::array::from_fn(|j| coord(j, 3)),
        }
    }

    /// The vertices of triangles `tris` (indices into `clip`), read
    /// straight into registers: one 16-byte load a vertex, widened to
    /// f64 and transposed. (Copying them into an array of triangles first,
    /// as `from_arrays` takes them, cost the frame's setup loop a
    /// store-forwarding stall a vertex: `perf annotate`, about a third of
    /// its time.) Panics, as indexing does, on an index past `clip`.
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    #[inline(always)]
    pub(crate) fn gather(clip: &[[f32; 4]], tris: &[[u32; 3]; LANES]) -> Vertices4 {
        use core::arch::x86_64::{
            __m256d, _mm256_cvtps_pd, _mm256_permute2f128_pd, _mm256_unpackhi_pd,
            _mm256_unpacklo_pd, _mm_loadu_ps,
        };
        let load = |i: u32| -> __m256d {
            let p: &[f32; 4] = &clip[i as usize];
            // SAFETY: AVX is enabled (cfg); `p` is 16 readable bytes.
            unsafe { _mm256_cvtps_pd(_mm_loadu_ps(p.as_ptr())) }
        };
        // Vertex j of the 4 triangles: (a, b, c, d) rows of (x, y, z, w)
        // to columns: unpack pairs, then swap 128-bit halves.
        let column = |j: usize| -> [f64x4; 4] {
            let (a, b) = (load(tris[0][j]), load(tris[1][j]));
            let (c, d) = (load(tris[2][j]), load(tris[3][j]));
            // SAFETY: AVX is enabled (cfg).
            unsafe {
                let (ab_xz, ab_yw) = (_mm256_unpacklo_pd(a, b), _mm256_unpackhi_pd(a, b));
                let (cd_xz, cd_yw) = (_mm256_unpacklo_pd(c, d), _mm256_unpackhi_pd(c, d));
                [
                    bytemuck::cast(_mm256_permute2f128_pd::<0x20>(ab_xz, cd_xz)),
                    bytemuck::cast(_mm256_permute2f128_pd::<0x20>(ab_yw, cd_yw)),
                    bytemuck::cast(_mm256_permute2f128_pd::<0x31>(ab_xz, cd_xz)),
                    bytemuck::cast(_mm256_permute2f128_pd::<0x31>(ab_yw, cd_yw)),
                ]
            }
        };
        let (c0, c1, c2) = (column(0), column(1), column(2));
        Vertices4 {
            x: [c0[0], c1[0], c2[0]],
            y: [c0[1], c1[1], c2[1]],
            z: [c0[2], c1[2], c2[2]],
            w: [c0[3], c1[3], c2[3]],
        }
    }

    /// See the AVX version.
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
    #[inline(always)]
    pub(crate) fn gather(clip: &[[f32; 4]], tris: &[[u32; 3]; LANES]) -> Vertices4 {
        Vertices4::from_arrays(&tris.map(|t| t.map(|i| clip[i as usize])))
    }

    /// Triangle `t`'s vertices as f32 (exact: they were f32).
    #[inline(always)]
    pub(crate) fn lane(&self, t: usize) -> [[f32; 4]; 3] {
        std::array::from_fn(|j| {
            [self.x[j], self.y[j], self.z[j], self.w[j]].map(|c| c.to_array()[t] as f32)
        })
    }
}

impl SetupContext {
    /// [`SetupContext::setup`] of the 4 triangles of ids `first..first + 4`
    /// (clip-space vertices `v[t]`, cull mode `cull[t]`), as if called for
    /// each in turn: the same screen triangles in `out` in the same order,
    /// the same counts, and `planes[t]` set to the planes `setup` returns
    /// (left as it was where it returns `None`).
    pub fn setup_x4(
        &self,
        first: u32,
        v: &[[[f32; 4]; 3]; LANES],
        cull: [Cull; LANES],
        planes: &mut [TriPlanes; LANES],
        out: &mut Vec<RasterTri>,
        counts: &mut SetupCounts,
    ) {
        self.setup_x4_occluded(first, v, cull, None, planes, out, counts);
    }

    /// [`SetupContext::setup_x4`] as [`SetupContext::setup_occluded`] per
    /// triangle: lanes the occlusion test hides (after the facing cull, as
    /// there) are counted and skipped.
    #[allow(clippy::too_many_arguments)]
    pub fn setup_x4_occluded(
        &self,
        first: u32,
        v: &[[[f32; 4]; 3]; LANES],
        cull: [Cull; LANES],
        occluder: Option<&DepthBounds>,
        planes: &mut [TriPlanes; LANES],
        out: &mut Vec<RasterTri>,
        counts: &mut SetupCounts,
    ) {
        let v = Vertices4::from_arrays(v);
        self.setup_x4_vertices(first, &v, cull, occluder, planes, out, counts);
    }

    /// [`SetupContext::setup_x4_occluded`] of vertices already in
    /// structure-of-arrays form (`Vertices4::gather` reads them straight
    /// from a clip-position array, as the frame does), keeping all planes
    /// ([`TriPlanes`]) or only depth's ([`crate::setup::DepthPlanes`]).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn setup_x4_vertices<P: SetupPlanes>(
        &self,
        first: u32,
        v: &Vertices4,
        cull: [Cull; LANES],
        occluder: Option<&DepthBounds>,
        planes: &mut [P; LANES],
        out: &mut Vec<RasterTri>,
        counts: &mut SetupCounts,
    ) {
        let Vertices4 { x, y, z, w } = *v;

        // `!(|c| ≤ MAX)` is the scalar `c.is_nan() || c.abs() > MAX`.
        let max = f64x4::splat(MAX_CLIP_COORD);
        let mut valid = valid_all();
        for j in 0..3 {
            for c in [x[j], y[j], z[j], w[j]] {
                valid &= c.abs().simd_le(max);
            }
        }

        // Outcodes: outside if all three vertices are beyond one plane.
        let zero = f64x4::ZERO;
        let outside = all3(|j| x[j].simd_lt(-w[j]))
            | all3(|j| x[j].simd_gt(w[j]))
            | all3(|j| y[j].simd_lt(-w[j]))
            | all3(|j| y[j].simd_gt(w[j]))
            | all3(|j| z[j].simd_gt(w[j]))
            | all3(|j| z[j].simd_lt(zero));

        // The 2D-homogeneous adjugate, columns (x, y, w) per vertex, as
        // `cross3` and `dot3` evaluate it.
        let cross = |a: usize, b: usize| {
            [
                y[a] * w[b] - w[a] * y[b],
                w[a] * x[b] - x[a] * w[b],
                x[a] * y[b] - y[a] * x[b],
            ]
        };
        let adj = [cross(1, 2), cross(2, 0), cross(0, 1)];
        let det = x[0] * adj[0][0] + y[0] * adj[0][1] + w[0] * adj[0][2];
        let degenerate = det.simd_eq(zero) | !det.is_finite();

        let (valid, outside, degenerate) = (
            valid.to_bitmask(),
            outside.to_bitmask(),
            degenerate.to_bitmask(),
        );
        let (negative, positive) = (
            det.simd_lt(zero).to_bitmask(),
            det.simd_gt(zero).to_bitmask(),
        );
        // Lane masks, decided in `setup`'s order: invalid, outside,
        // degenerate, culled, clipped.
        let with = |c: Cull| (0..LANES).fold(0, |m, t| m | ((cull[t] == c) as u32) << t);
        let outside = valid & outside;
        let kept = valid & !outside & !degenerate;
        let culled = kept & (with(Cull::Back) & negative | with(Cull::Front) & positive);
        let drawn = kept & !culled;
        // 1/w per vertex, for the occlusion test and the projection below
        // (the same division in both); not needed by a group culled whole.
        let one = f64x4::ONE;
        let inv_w: [f64x4; 3] = if drawn != 0 {
            std::array::from_fn(|j| one / w[j])
        } else {
            [one; 3]
        };
        let occluded = occluder.map_or(0, |o| o.hides_x4(v, &inv_w, drawn));
        // Guard band: `GuardBand::needs_clip`'s distances, any below 0
        // (only lanes still to draw need it: the outline passes' culled
        // and hidden groups skip it).
        let clip = if drawn & !occluded != 0 {
            let (kx, ky) = (f64x4::splat(self.guard.kx), f64x4::splat(self.guard.ky));
            let mut clip = f64x4::ZERO;
            for j in 0..3 {
                clip |= (w[j] - z[j]).simd_lt(zero)
                    | (kx * w[j] - x[j]).simd_lt(zero)
                    | (kx * w[j] + x[j]).simd_lt(zero)
                    | (ky * w[j] - y[j]).simd_lt(zero)
                    | (ky * w[j] + y[j]).simd_lt(zero);
            }
            clip.to_bitmask()
        } else {
            0
        };
        let fast = drawn & !occluded & !clip;
        let lanes: [Lane; LANES] = std::array::from_fn(|t| {
            if bit(fast, t) {
                Lane::Fast
            } else if bit(outside, t) {
                Lane::Outside
            } else if bit(culled, t) {
                Lane::Culled
            } else if bit(occluded, t) {
                Lane::Occluded
            } else {
                Lane::Scalar
            }
        });

        if fast == 0 {
            // Neighbouring triangles of a mesh often share their facing:
            // a group culled together skips the projection entirely.
            for (t, &lane) in lanes.iter().enumerate() {
                self.finish_lane(lane, first, t, v, cull, &mut planes[t], out, counts);
            }
            return;
        }

        // Projection and snapping, as `setup`'s `project`.
        let (wd, hd) = (self.width as f64, self.height as f64);
        let half = f64x4::splat(0.5);
        let (ws, hs) = (f64x4::splat(wd), f64x4::splat(hd));
        let (lo, hi) = (f64x4::splat(-GUARD_BAND_PX), f64x4::splat(GUARD_BAND_PX));
        let fixed = f64x4::splat(SUBPIXEL_ONE as f64);
        let mut finite = valid_all();
        let mut min_x = f64x4::splat(f64::INFINITY);
        let mut min_y = f64x4::splat(f64::INFINITY);
        let mut snapped = [[f64x4::ZERO; 2]; 3];
        for j in 0..3 {
            let sx = (x[j] * inv_w[j] + one) * half * ws;
            let sy = (one - y[j] * inv_w[j]) * half * hs;
            finite &= sx.is_finite() & sy.is_finite();
            // Lanes that are not finite go to the scalar path; on the others
            // max/min are `f64::clamp` and `f64::min` (no NaN, and no −0:
            // `a + 1` and `1 − a` are +0 when zero).
            let sx = sx.fast_max(lo).fast_min(hi);
            let sy = sy.fast_max(lo).fast_min(hi);
            min_x = min_x.fast_min(sx);
            min_y = min_y.fast_min(sy);
            // `snap`'s rounding; the integers stay in f64 (exact) for
            // `edges_x4`.
            snapped[j] = [
                (sx * fixed).round_ties_even(),
                (sy * fixed).round_ties_even(),
            ];
        }
        let finite = finite.to_bitmask();
        let exact = within_exact_range(&snapped);
        let edges = edges_x4(self.width, self.height, &snapped);

        // Planes: rows of M⁻¹ = adj / det, composed with pixel → NDC and
        // moved to the origin, as `setup`'s `plane`.
        let ox = min_x.fast_max(zero).fast_min(ws);
        let oy = min_y.fast_max(zero).fast_min(hs);
        let (to_nx, to_ny) = (f64x4::splat(2.0 / wd), f64x4::splat(-2.0 / hd));
        let inv_det = one / det;
        let plane = |row: &[f64x4; 3]| {
            let r = [row[0] * inv_det, row[1] * inv_det, row[2] * inv_det];
            let (a, b) = (r[0] * to_nx, r[1] * to_ny);
            let c = -r[0] + r[1] + r[2];
            [a, b, a * ox + b * oy + c]
        };
        let k = [plane(&adj[0]), plane(&adj[1]), plane(&adj[2])];
        let ks: [f64x4; 3] = std::array::from_fn(|c| k[0][c] + k[1][c] + k[2][c]);
        let zp: [f64x4; 3] =
            std::array::from_fn(|c| k[0][c] * z[0] + k[1][c] * z[1] + k[2][c] * z[2]);

        // f32 planes and the bound on them (`setup`'s `bounded`).
        let (span_x, span_y) = (f64x4::splat(wd + 1.0), f64x4::splat(hd + 1.0));
        let bound = f64x4::splat(MAX_PLANE_VALUE);
        let mut bounded = valid_all();
        let mut narrow = |p: &[f64x4; 3]| -> [[f32; 4]; 3] {
            let (p0, q0) = to_f32(p[0]);
            let (p1, q1) = to_f32(p[1]);
            let (p2, q2) = to_f32(p[2]);
            bounded &= (q0.abs() * span_x + q1.abs() * span_y + q2.abs()).simd_le(bound);
            [p0, p1, p2]
        };
        let k1 = narrow(&k[1]);
        let k2 = narrow(&k[2]);
        let ks = narrow(&ks);
        let zp = narrow(&zp);
        let bounded = bounded.to_bitmask();
        let (ox, _) = to_f32(ox);
        let (oy, _) = to_f32(oy);

        for (t, &lane) in lanes.iter().enumerate() {
            if lane != Lane::Fast {
                self.finish_lane(lane, first, t, v, cull, &mut planes[t], out, counts);
                continue;
            }
            if !bit(finite, t) {
                hit(0);
                if let Some(p) = self.setup(first + t as u32, v.lane(t), cull[t], out, counts) {
                    planes[t] = P::from_planes(p);
                }
                continue;
            }
            counts.triangles += 1;
            let id = first + t as u32;
            let rt = if bit(exact, t) {
                None
            } else {
                hit(6);
                let [p0, p1, p2] = snapped.map(|[sx, sy]| [to_int(sx)[t], to_int(sy)[t]]);
                self.edges(id, p0, p1, p2)
            };
            if !(bit(exact, t) && bit(edges.some, t) || rt.is_some()) {
                counts.no_samples += 1;
                hit(4);
                continue;
            }
            // Planes beyond the bound (a vertex at a subnormal w, say):
            // skipped as degenerate, see `setup`.
            if !bit(bounded, t) {
                counts.skipped_degenerate += 1;
                hit(5);
                continue;
            }
            // The exact lanes' triangle is built in the push: made on the
            // stack by narrow stores and then copied with wide loads, it
            // stalled on store forwarding.
            out.push(rt.unwrap_or_else(|| edges.lane(t, id)));
            counts.drawn += 1;
            hit(3);
            let lane3 = |p: &[[f32; 4]; 3]| [p[0][t], p[1][t], p[2][t]];
            planes[t] = P::from_planes(TriPlanes {
                origin: [ox[t], oy[t]],
                k1: lane3(&k1),
                k2: lane3(&k2),
                ks: lane3(&ks),
                z: lane3(&zp),
                facing: if bit(positive, t) { 1.0 } else { -1.0 },
            });
        }
    }

    /// A lane the fast path does not project: counted here, or set up by
    /// the scalar path.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn finish_lane<P: SetupPlanes>(
        &self,
        lane: Lane,
        first: u32,
        t: usize,
        v: &Vertices4,
        cull: [Cull; LANES],
        plane: &mut P,
        out: &mut Vec<RasterTri>,
        counts: &mut SetupCounts,
    ) {
        match lane {
            Lane::Outside => {
                hit(1);
                counts.triangles += 1;
                counts.culled_outside += 1;
            }
            Lane::Culled => {
                hit(2);
                counts.triangles += 1;
                counts.culled_backface += 1;
            }
            Lane::Occluded => {
                counts.triangles += 1;
                counts.culled_occluded += 1;
            }
            Lane::Scalar | Lane::Fast => {
                hit(0);
                if let Some(p) = self.setup(first + t as u32, v.lane(t), cull[t], out, counts) {
                    *plane = P::from_planes(p);
                }
            }
        }
    }
}

/// Lanes where a per-vertex mask holds for all three vertices.
#[inline(always)]
fn all3(f: impl Fn(usize) -> f64x4) -> f64x4 {
    f(0) & f(1) & f(2)
}

/// `snap` of `v` = 256·(a screen coordinate): rounded half to even, as
/// `round_ties_even`, then to integer.
#[cfg(test)]
fn snap(v: f64x4) -> [i64; LANES] {
    to_int(v.round_ties_even())
}

/// Integral lanes |v| < 2⁵¹ to i64: v + 1.5·2⁵² is exact and its low
/// mantissa bits are v (two's complement once the constant's bits are
/// subtracted); −0 gives 0.
#[inline(always)]
fn to_int(v: f64x4) -> [i64; LANES] {
    const MAGIC: f64 = 6755399441055744.0; // 1.5·2⁵²
    let bits = (v + f64x4::splat(MAGIC)).to_bits().to_array();
    bits.map(|b| b.wrapping_sub(MAGIC.to_bits()) as i64)
}

/// Largest |X|, |Y| (fixed point: 2¹⁶ pixels) for which [`edges_x4`] is
/// exact in f64: then |A|, |B| ≤ 2²⁵, |A·X|, |B·Y| ≤ 2⁴⁹, |C| ≤ 2⁵⁰ + 1,
/// the doubled area below 2⁵¹ and the edge value at a pixel centre of the
/// image (< 2²³ fixed units) below 2⁵¹: integers f64 holds exactly, so
/// every operation gives the i64 result. A vertex beyond it (far out in
/// the guard band) sends its lane to the i64 [`SetupContext::edges`].
const EXACT_FIXED: f64 = (1u64 << 24) as f64;

/// Lanes whose snapped vertices are all within ±`EXACT_FIXED`.
#[inline(always)]
fn within_exact_range(p: &[[f64x4; 2]; 3]) -> u32 {
    let bound = f64x4::splat(EXACT_FIXED);
    let mut m = valid_all();
    for c in p.iter().flatten() {
        m &= c.abs().simd_le(bound);
    }
    m.to_bitmask()
}

/// [`SetupContext::edges`] of 4 snapped triangles, structure of arrays;
/// lanes beyond `EXACT_FIXED` hold garbage.
struct EdgesX4 {
    a: [[i64; LANES]; 3],
    b: [[i64; LANES]; 3],
    c: [[i64; LANES]; 3],
    inv_step: [[f64; LANES]; 3],
    /// Edge values at the centre of pixel (x0, y0), for `small` lanes.
    e0: [[i64; LANES]; 3],
    /// x0, y0, x1, y1.
    bbox: [[i64; LANES]; 4],
    /// Lanes that give a screen triangle (nonzero area, a candidate pixel).
    some: u32,
    /// Lanes at most `SMALL_PX` pixels each way.
    small: u32,
}

impl EdgesX4 {
    /// Lane `t`'s screen triangle, as `edges` builds it.
    #[inline(always)]
    ///
    /// Arrays spelled out element by element: `array::from_fn` and `map`
    /// here compiled to copies through the stack.
    fn lane(&self, t: usize, tri: u32) -> RasterTri {
        let edge = |k: usize| Edge {
            a: self.a[k][t],
            b: self.b[k][t],
            c: self.c[k][t],
        };
        let (e0, e1, e2) = (edge(0), edge(1), edge(2));
        let fixed = |v: i64| (v * SUBPIXEL_ONE) as i32;
        RasterTri {
            small: bit(self.small, t).then(|| SmallEdges {
                e0: [
                    self.e0[0][t] as i32,
                    self.e0[1][t] as i32,
                    self.e0[2][t] as i32,
                ],
                a: [fixed(e0.a), fixed(e1.a), fixed(e2.a)],
                b: [fixed(e0.b), fixed(e1.b), fixed(e2.b)],
            }),
            inv_step: [
                self.inv_step[0][t],
                self.inv_step[1][t],
                self.inv_step[2][t],
            ],
            edges: [e0, e1, e2],
            bbox: [
                self.bbox[0][t] as i32,
                self.bbox[1][t] as i32,
                self.bbox[2][t] as i32,
                self.bbox[3][t] as i32,
            ],
            tri,
        }
    }
}

/// `edges` in f64x4 on integral coordinates `p[j] = [X, Y]` of vertex j:
/// the same integer operations, exact (see `EXACT_FIXED`); ⌊n/256⌋ and
/// ⌈n/256⌉ are `floor` and `ceil` of an exact division by a power of two.
#[inline(always)]
fn edges_x4(width: u32, height: u32, p: &[[f64x4; 2]; 3]) -> EdgesX4 {
    let (zero, one) = (f64x4::ZERO, f64x4::ONE);
    let [[x0, y0], [x1, y1], [x2, y2]] = *p;
    let area2 = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0);
    // Clockwise on screen: swap p1 and p2.
    let flip = area2.simd_lt(zero);
    let (x1, x2) = (flip.select(x2, x1), flip.select(x1, x2));
    let (y1, y2) = (flip.select(y2, y1), flip.select(y1, y2));

    let edge = |xa: f64x4, ya: f64x4, xb: f64x4, yb: f64x4| {
        let a = ya - yb;
        let b = xb - xa;
        // Top-left rule, see `edges`.
        let top_left = a.simd_gt(zero) | (a.simd_eq(zero) & b.simd_gt(zero));
        let c = -(a * xa + b * ya) - top_left.select(zero, one);
        [a, b, c]
    };
    let e = [
        edge(x0, y0, x1, y1),
        edge(x1, y1, x2, y2),
        edge(x2, y2, x0, y0),
    ];

    let px = f64x4::splat(SUBPIXEL_ONE as f64);
    let half = f64x4::splat(SUBPIXEL_HALF as f64);
    let bound = |lo: f64x4, hi: f64x4, n: u32| {
        let first = ((lo - half) / px).ceil().fast_max(zero);
        let end = (((hi - half) / px).floor() + one).fast_min(f64x4::splat(n as f64));
        (first, end)
    };
    let (min_x, max_x) = (x0.fast_min(x1).fast_min(x2), x0.fast_max(x1).fast_max(x2));
    let (min_y, max_y) = (y0.fast_min(y1).fast_min(y2), y0.fast_max(y1).fast_max(y2));
    let (bx0, bx1) = bound(min_x, max_x, width);
    let (by0, by1) = bound(min_y, max_y, height);
    let none = area2.simd_eq(zero) | bx0.simd_ge(bx1) | by0.simd_ge(by1);
    let extent = (max_x - min_x).fast_max(max_y - min_y);
    let small = extent.simd_le(f64x4::splat((SMALL_PX * SUBPIXEL_ONE) as f64));

    let (cx, cy) = (bx0 * px + half, by0 * px + half);
    EdgesX4 {
        a: e.map(|[a, _, _]| to_int(a)),
        b: e.map(|[_, b, _]| to_int(b)),
        c: e.map(|[_, _, c]| to_int(c)),
        inv_step: e.map(|[a, _, _]| {
            let inv = one / (a.abs() * px);
            a.simd_eq(zero).select(zero, inv).to_array()
        }),
        e0: e.map(|[a, b, c]| to_int(a * cx + b * cy + c)),
        bbox: [bx0, by0, bx1, by1].map(to_int),
        some: !none.to_bitmask() & 0xf,
        small: small.to_bitmask(),
    }
}

/// A mask with every lane set.
#[inline(always)]
fn valid_all() -> f64x4 {
    f64x4::splat(f64::from_bits(u64::MAX))
}

/// The occlusion test of 4 triangles at once, beside the 4-lane setup that
/// calls it (occlusion.rs has the one-triangle form it follows).
impl DepthBounds {
    /// [`DepthBounds::hides`] of the 4 triangles `v` whose bits are set in
    /// `lanes`, given `inv_w[j] = 1 / v.w[j]`: bit t of the result is
    /// `hides` of triangle t (0 outside `lanes`). The same IEEE operations
    /// in the same order, lane by lane, so the same answers (tested); the
    /// block loop runs per lane.
    pub(crate) fn hides_x4(&self, v: &Vertices4, inv_w: &[f64x4; 3], lanes: u32) -> u32 {
        if lanes == 0 {
            return 0;
        }
        let (zero, one) = (f64x4::ZERO, f64x4::ONE);
        let ahead = v.w[0].simd_gt(zero) & v.w[1].simd_gt(zero) & v.w[2].simd_gt(zero);
        let (w, h) = (self.width as f64, self.height as f64);
        let (hw, hh) = (f64x4::splat(0.5 * w), f64x4::splat(0.5 * h));
        let project = |j: usize| {
            (
                (v.x[j] * inv_w[j] + one) * hw,
                (one - v.y[j] * inv_w[j]) * hh,
                v.z[j] * inv_w[j],
            )
        };
        let (x0, y0, z0) = project(0);
        let (x1, y1, z1) = project(1);
        let (x2, y2, z2) = project(2);
        let (ux, uy, uz) = (x1 - x0, y1 - y0, z1 - z0);
        let (vx, vy, vz) = (x2 - x0, y2 - y0, z2 - z0);
        let inv_d = one / (ux * vy - vx * uy);
        let gx = (uz * vy - vz * uy) * inv_d;
        let gy = (ux * vz - vx * uz) * inv_d;
        // `hides`' min3 and max3, NaN cases included.
        let min3 = |a: f64x4, b: f64x4, c: f64x4| {
            let m = b.simd_lt(a).select(b, a);
            c.simd_lt(m).select(c, m)
        };
        let max3 = |a: f64x4, b: f64x4, c: f64x4| -min3(-a, -b, -c);
        let (x_min, x_max) = (min3(x0, x1, x2), max3(x0, x1, x2));
        let (y_min, y_max) = (min3(y0, y1, y2), max3(y0, y1, y2));
        let (lo, hi) = (f64x4::splat(LO_OFFSET), f64x4::splat(HI_OFFSET));
        let (x_lo, x_hi) = (x_min - lo, x_max - hi);
        let (y_lo, y_hi) = (y_min - lo, y_max - hi);
        let (wm, hm) = (f64x4::splat(w - 1.0), f64x4::splat(h - 1.0));
        let on_image =
            x_hi.simd_ge(zero) & y_hi.simd_ge(zero) & x_lo.simd_le(wm) & y_lo.simd_le(hm);
        let z_hi = max3(z0, z1, z2);
        let (ax, ay) = (gx.abs(), gy.abs());
        let two = f64x4::splat(2.0);
        let z = z_hi
            + (ax + ay) * f64x4::splat(1.0 / 256.0)
            + f64x4::splat(1e-6)
                * (z_hi.abs() + ax * (x_max - x_min + two) + ay * (y_max - y_min + two));
        let judged = (ahead & on_image & z.is_finite()).to_bitmask() & lanes;
        if judged == 0 {
            return 0;
        }
        // `behind_blocks`' block range, 4 lanes at once (the same
        // operations: on judged lanes the range is not NaN and meets the
        // image, so every value converted lies in [0, w − 1] or [0, h − 1]).
        let bx0 = block_index(x_lo.ceil().fast_max(zero));
        let bx1 = block_index(x_hi.floor().fast_min(wm));
        let by0 = block_index(y_lo.ceil().fast_max(zero));
        let by1 = block_index(y_hi.floor().fast_min(hm));
        let z = z.to_array();
        let mut hidden = 0;
        let mut left = judged;
        while left != 0 {
            let t = left.trailing_zeros() as usize;
            left &= left - 1;
            if self.behind_block_range([bx0[t], bx1[t], by0[t], by1[t]], z[t]) {
                hidden |= 1 << t;
            }
        }
        hidden
    }
}

#[cfg(test)]
mod tests;
