//! Triangle setup: culling, clipping, snapping, edge functions (top-left
//! rule) and the per-triangle planes that depth testing and shading evaluate.

use crate::clip::{ClipVertex, GuardBand};
use crate::fixed::{pixel_centre, snap, GUARD_BAND_PX, SUBPIXEL_BITS, SUBPIXEL_HALF, SUBPIXEL_ONE};
use crate::geometry::Cull;
use crate::occlusion::DepthBounds;

/// An edge function E(X, Y) = A·X + B·Y + C over fixed-point coordinates,
/// positive inside. `c` already holds the fill-rule bias, so a pixel centre is
/// covered iff E ≥ 0 for all three edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    pub(crate) a: i64,
    pub(crate) b: i64,
    pub(crate) c: i64,
}

/// A screen-space triangle ready for scan conversion (a clipped triangle
/// becomes several, all with the id of the triangle they came from).
///
/// The fields the scan of a small triangle reads (`small`, `bbox`, `tri`)
/// come first, in the struct's first 60 bytes (`repr(C)` keeps the order):
/// with the compiler's own order they lay at both ends of the 160, so a
/// small triangle's scan touched two or three cache lines of it instead of
/// one or two.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct RasterTri {
    /// For triangles whose vertices span at most `SMALL_PX` pixels each
    /// way: the edge values at the centre of pixel (bbox x0, bbox y0) in
    /// i32, the form the 8-wide coverage test of `scan` evaluates.
    pub small: Option<SmallEdges>,
    /// Covered pixel range candidates [x0, x1) × [y0, y1), inside the image.
    pub bbox: [i32; 4],
    /// Id of the source triangle (its index in the scene).
    pub tri: u32,
    pub edges: [Edge; 3],
    /// 1 / (256·|A|) per edge (0 where A = 0): see `RasterTri::span`.
    pub inv_step: [f64; 3],
}

/// How a triangle covers a rectangle of pixels ([`RasterTri::rect_coverage`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RectCoverage {
    /// No pixel centre of the rectangle is covered.
    Outside,
    /// Every one is.
    Inside,
    /// Some may be: the rows' spans decide.
    Partial,
}

/// Largest vertex extent (pixels, each axis) of a triangle whose edge
/// values are evaluated in i32. Relative to a pixel centre inside the
/// vertices' box, |A|, |B| ≤ (SMALL_PX + 1)·256 < 2¹⁴·¹ and offsets likewise,
/// so E = A·dx + B·dy + E(origin) stays below 2³¹ (3 terms of < 2²⁹·²).
pub(crate) const SMALL_PX: i64 = 64;

/// i32 edge functions relative to the bounding box's first pixel centre:
/// E_k(x, y) = `e0[k] + a[k]·(x − x0) + b[k]·(y − y0)`, x, y in pixels
/// (`a`, `b` already scaled by 256), bias included.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SmallEdges {
    pub(crate) e0: [i32; 3],
    pub(crate) a: [i32; 3],
    pub(crate) b: [i32; 3],
}

/// Screen-space affine functions of one source triangle, each evaluated as
/// `p[0]·(x − ox) + p[1]·(y − oy) + p[2]` at pixel-centre coordinates (x, y) in
/// pixels. Relative to a nearby origin so f32 keeps the small values of
/// small triangles accurate.
///
/// With k = M⁻¹(nx, ny, 1), M the matrix whose columns are the clip-space
/// (x, y, w) of the vertices \[Olano97\]: b_i = k_i / Σk are the
/// perspective-correct barycentrics, Σk = 1/w, and Σ k_i z_i = z/w (NDC depth).
/// All are affine in screen space, and the same for every clipped piece.
#[derive(Clone, Copy, Debug, Default)]
pub struct TriPlanes {
    pub origin: [f32; 2],
    pub k1: [f32; 3],
    pub k2: [f32; 3],
    /// Σk = 1/w (w = view depth).
    pub ks: [f32; 3],
    /// NDC depth z/w.
    pub z: [f32; 3],
    /// +1 front-facing, −1 back-facing (drawn only when double-sided).
    pub facing: f32,
}

// SAFETY: every field is f32, whose all-zero bits are 0.0 (the Default).
unsafe impl bytemuck::Zeroable for TriPlanes {}

// SAFETY: every field is f32, whose all-zero bits are 0.0 (the Default).
unsafe impl bytemuck::Zeroable for DepthPlanes {}

impl TriPlanes {
    #[inline]
    pub fn eval(p: &[f32; 3], origin: [f32; 2], x: f32, y: f32) -> f32 {
        p[0].mul_add(x - origin[0], p[1].mul_add(y - origin[1], p[2]))
    }
}

/// What a depth-only pass (a shadow map's) keeps of a triangle's
/// [`TriPlanes`]: the depth plane and its origin, a third of the bytes,
/// so its setup writes and its scan reads less.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DepthPlanes {
    pub(crate) origin: [f32; 2],
    /// NDC depth z/w, as `TriPlanes::z`.
    pub(crate) z: [f32; 3],
}

/// The planes a setup writes per triangle: all of them ([`TriPlanes`]),
/// or only depth ([`DepthPlanes`]). Setup computes every plane either
/// way (each is bounded, see `SetupContext::setup`, and the depth plane
/// is formed from the barycentric ones), so a triangle gets the same
/// depth bits and is dropped or kept alike in both; the depth-only form
/// skips storing (and the compiler computing) what nothing reads.
pub trait SetupPlanes: Copy + Default + Send + Sync {
    fn from_planes(p: TriPlanes) -> Self;
    /// The depth plane and its origin.
    fn depth(&self) -> ([f32; 3], [f32; 2]);
}

impl SetupPlanes for TriPlanes {
    #[inline(always)]
    fn from_planes(p: TriPlanes) -> Self {
        p
    }
    #[inline(always)]
    fn depth(&self) -> ([f32; 3], [f32; 2]) {
        (self.z, self.origin)
    }
}

impl SetupPlanes for DepthPlanes {
    #[inline(always)]
    fn from_planes(p: TriPlanes) -> Self {
        DepthPlanes {
            origin: p.origin,
            z: p.z,
        }
    }
    #[inline(always)]
    fn depth(&self) -> ([f32; 3], [f32; 2]) {
        (self.z, self.origin)
    }
}

/// Largest clip-space coordinate magnitude accepted (2⁵⁰ ≈ 1.1e15). Beyond
/// it an f32 position's spacing exceeds 1e8 units: such a vertex (1e30, say)
/// carries no usable position, so its triangle is skipped and counted like a
/// NaN one instead of being clipped into a meaningless sliver.
pub const MAX_CLIP_COORD: f64 = (1u64 << 50) as f64;

/// Largest magnitude a triangle's planes (`TriPlanes`) may reach at any
/// pixel of the image; beyond it the triangle is skipped as degenerate
/// (see `SetupContext::setup`).
pub(crate) const MAX_PLANE_VALUE: f64 = 1e30;

/// What happened to triangles in setup; sums over chunks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SetupCounts {
    pub triangles: u64,
    /// Skipped by the pass's cull mode (back faces, or front faces in a
    /// pass with `Cull::Front`).
    pub culled_backface: u64,
    pub culled_outside: u64,
    /// Behind what earlier passes drew at every pixel it touches
    /// (`occlusion`); only in passes after a frame's first.
    pub culled_occluded: u64,
    /// A vertex is NaN, infinite or beyond `MAX_CLIP_COORD`.
    pub skipped_invalid: u64,
    pub skipped_degenerate: u64,
    pub clipped: u64,
    /// Reached the rasterizer with at least one candidate pixel.
    pub drawn: u64,
    /// Visible but too small to contain any pixel centre.
    pub no_samples: u64,
}

impl SetupCounts {
    pub(crate) fn add(&mut self, o: &SetupCounts) {
        self.triangles += o.triangles;
        self.culled_backface += o.culled_backface;
        self.culled_outside += o.culled_outside;
        self.culled_occluded += o.culled_occluded;
        self.skipped_invalid += o.skipped_invalid;
        self.skipped_degenerate += o.skipped_degenerate;
        self.clipped += o.clipped;
        self.drawn += o.drawn;
        self.no_samples += o.no_samples;
    }
}

/// Everything setup needs to know about the image.
#[derive(Clone, Copy, Debug)]
pub struct SetupContext {
    pub width: u32,
    pub height: u32,
    pub guard: GuardBand,
}

/// ⌊n / 256⌋: the arithmetic shift rounds toward −∞.
#[inline]
fn floor_px(n: i64) -> i64 {
    n >> SUBPIXEL_BITS
}

/// ⌈n / 256⌉.
#[inline]
fn ceil_px(n: i64) -> i64 {
    -((-n) >> SUBPIXEL_BITS)
}

/// Frustum outcode: one bit per plane the vertex is outside of.
fn outcode(v: &ClipVertex) -> u8 {
    let [x, y, z, w] = *v;
    (x < -w) as u8
        | ((x > w) as u8) << 1
        | ((y < -w) as u8) << 2
        | ((y > w) as u8) << 3
        | ((z > w) as u8) << 4
        | ((z < 0.0) as u8) << 5
}

/// [`outcode`] of an f32 clip-space vertex: the same bits (widening to
/// f64 is exact, and so are negation and comparison in either width).
/// Setup culls a triangle as outside when its three vertices share a bit,
/// so a depth pass may skip such triangles before setup (`frame.rs`).
#[inline(always)]
pub(crate) fn outcode_f32(v: &[f32; 4]) -> u8 {
    let [x, y, z, w] = *v;
    (x < -w) as u8
        | ((x > w) as u8) << 1
        | ((y < -w) as u8) << 2
        | ((y > w) as u8) << 3
        | ((z > w) as u8) << 4
        | ((z < 0.0) as u8) << 5
}

fn cross3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The 2D-homogeneous determinant `setup` decides a triangle's facing by
/// (clip-space vertices `v`): > 0 counter-clockwise on screen (front),
/// < 0 clockwise, 0 or not finite degenerate. The same operations as in
/// `setup`, so the same value.
pub fn orientation(v: &[[f32; 4]; 3]) -> f64 {
    let cols = v.map(|p| [p[0] as f64, p[1] as f64, p[3] as f64]);
    dot3(cols[0], cross3(cols[1], cols[2]))
}

/// Relative margin of [`front_face_shown`]'s f32 determinant: its
/// rounding error is below 5·2⁻²⁴ ≈ 3e-7 of the sum of the terms' sizes
/// (to first order), so a value above 2e-6 of that sum has the exact
/// determinant's sign with ~6× slack. (A triangle under ~0.2 % of the
/// view across has too little area against its terms in f32 and is left
/// to setup.)
const FRONT_MARGIN: f32 = 2e-6;

/// Whether `setup` (and `setup_x4`) with `Cull::Front` would skip the
/// triangle of clip-space vertices `v` as culled by its facing, shown in
/// f32: every coordinate valid (not NaN, |c| ≤ `MAX_CLIP_COORD`, which is
/// 2⁵⁰, exact in f32), the vertices not all beyond one clip plane
/// (`outcode`'s comparisons, exact in f32 as in f64), and the determinant
/// `orientation` evaluates positive. The last is shown from the same
/// expression in f32, d, and the sum of its terms' sizes,
/// P = |x₀|(|y₁w₂| + |w₁y₂|) + |y₀|(|w₁x₂| + |x₁w₂|) + |w₀|(|x₁y₂| + |y₁x₂|):
/// d − D is below 5·2⁻²⁴·P to first order for D the exact determinant, and
/// `orientation`'s f64 value is within 5·2⁻⁵³·P of D, so d > 2e-6·P gives
/// D > 0 and a positive, finite f64 determinant (its products stay far
/// below f64's range for valid coordinates). Overflow (inf or NaN in f32)
/// fails the comparison; d > 1e-20 keeps clear of f32's subnormals (their
/// absolute error, ~1e-45, times coordinates up to 2⁵⁰ stays below 1e-29).
/// `false` says nothing: `setup` decides. Tested against `setup` itself.
#[inline(always)]
pub fn front_face_shown(v: &[[f32; 4]; 3]) -> bool {
    let [[x0, y0, _, w0], [x1, y1, _, w1], [x2, y2, _, w2]] = *v;
    let (a, b) = (y1 * w2, w1 * y2);
    let (c, d) = (w1 * x2, x1 * w2);
    let (e, f) = (x1 * y2, y1 * x2);
    let det = x0 * (a - b) + y0 * (c - d) + w0 * (e - f);
    let size = x0.abs() * (a.abs() + b.abs())
        + y0.abs() * (c.abs() + d.abs())
        + w0.abs() * (e.abs() + f.abs());
    if !(det > FRONT_MARGIN * size && det > 1e-20) {
        return false;
    }
    const MAX: f32 = MAX_CLIP_COORD as f32;
    let valid = v.iter().flatten().all(|c| c.abs() <= MAX);
    let all3 = |f: fn(&[f32; 4]) -> bool| f(&v[0]) && f(&v[1]) && f(&v[2]);
    let outside = all3(|p| p[0] < -p[3])
        || all3(|p| p[0] > p[3])
        || all3(|p| p[1] < -p[3])
        || all3(|p| p[1] > p[3])
        || all3(|p| p[2] > p[3])
        || all3(|p| p[2] < 0.0);
    valid && !outside
}

/// Vertex `j` of the 8 triangles `tris` as (x, y, z, w) columns, lane k
/// for `tris[k]`: one 16-byte load a vertex, transposed in registers.
#[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
#[inline(always)]
fn corners_x8(clip: &[[f32; 4]], tris: &[[u32; 3]; 8], j: usize) -> [wide::f32x8; 4] {
    use core::arch::x86_64::{
        __m128, _mm256_set_m128, _mm256_shuffle_ps, _mm256_unpackhi_ps, _mm256_unpacklo_ps,
        _mm_loadu_ps,
    };
    let load = |k: usize| -> __m128 {
        let p: &[f32; 4] = &clip[tris[k][j] as usize];
        // SAFETY: AVX is enabled (cfg); `p` is 16 readable bytes.
        unsafe { _mm_loadu_ps(p.as_ptr()) }
    };
    // SAFETY: AVX is enabled (cfg). Rows (x, y, z, w) of triangles k and
    // k + 4 share a register; a 4×4 transpose in each 128-bit half.
    unsafe {
        let t0 = _mm256_set_m128(load(4), load(0));
        let t1 = _mm256_set_m128(load(5), load(1));
        let t2 = _mm256_set_m128(load(6), load(2));
        let t3 = _mm256_set_m128(load(7), load(3));
        let (u0, u1) = (_mm256_unpacklo_ps(t0, t1), _mm256_unpackhi_ps(t0, t1));
        let (u2, u3) = (_mm256_unpacklo_ps(t2, t3), _mm256_unpackhi_ps(t2, t3));
        [
            bytemuck::cast(_mm256_shuffle_ps::<0x44>(u0, u2)),
            bytemuck::cast(_mm256_shuffle_ps::<0xEE>(u0, u2)),
            bytemuck::cast(_mm256_shuffle_ps::<0x44>(u1, u3)),
            bytemuck::cast(_mm256_shuffle_ps::<0xEE>(u1, u3)),
        ]
    }
}

/// See the AVX version.
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
#[inline(always)]
fn corners_x8(clip: &[[f32; 4]], tris: &[[u32; 3]; 8], j: usize) -> [wide::f32x8; 4] {
    let p: [[f32; 4]; 8] = std::array::from_fn(|k| clip[tris[k][j] as usize]);
    std::array::from_fn(|c| wide::f32x8::new(std::array::from_fn(|k| p[k][c])))
}

/// [`front_face_shown`] of the 8 triangles `tris` (indices into
/// `clip`): bit k for `tris[k]`. The same f32 operations lane by lane, so
/// the same answers (tested); about a tenth of the instructions. Panics,
/// as indexing does, on an index past `clip`.
#[inline]
pub fn front_faces_shown_x8(clip: &[[f32; 4]], tris: &[[u32; 3]; 8]) -> u32 {
    use wide::f32x8;
    let [x0, y0, z0, w0] = corners_x8(clip, tris, 0);
    let [x1, y1, z1, w1] = corners_x8(clip, tris, 1);
    let [x2, y2, z2, w2] = corners_x8(clip, tris, 2);
    let (a, b) = (y1 * w2, w1 * y2);
    let (c, d) = (w1 * x2, x1 * w2);
    let (e, f) = (x1 * y2, y1 * x2);
    let det = x0 * (a - b) + y0 * (c - d) + w0 * (e - f);
    let size = x0.abs() * (a.abs() + b.abs())
        + y0.abs() * (c.abs() + d.abs())
        + w0.abs() * (e.abs() + f.abs());
    let shown = det.simd_gt(f32x8::splat(FRONT_MARGIN) * size) & det.simd_gt(f32x8::splat(1e-20));
    if shown.to_bitmask() == 0 {
        return 0;
    }
    let max = f32x8::splat(MAX_CLIP_COORD as f32);
    let mut valid = shown;
    for v in [x0, y0, z0, w0, x1, y1, z1, w1, x2, y2, z2, w2] {
        valid &= v.abs().simd_le(max);
    }
    let zero = f32x8::ZERO;
    let outside = (x0.simd_lt(-w0) & x1.simd_lt(-w1) & x2.simd_lt(-w2))
        | (x0.simd_gt(w0) & x1.simd_gt(w1) & x2.simd_gt(w2))
        | (y0.simd_lt(-w0) & y1.simd_lt(-w1) & y2.simd_lt(-w2))
        | (y0.simd_gt(w0) & y1.simd_gt(w1) & y2.simd_gt(w2))
        | (z0.simd_gt(w0) & z1.simd_gt(w1) & z2.simd_gt(w2))
        | (z0.simd_lt(zero) & z1.simd_lt(zero) & z2.simd_lt(zero));
    valid.to_bitmask() & !outside.to_bitmask()
}

impl SetupContext {
    /// Sets up the triangle of id `tri` (clip-space vertices `v`), skipping
    /// it if `cull` says its facing is not drawn. Pushes its
    /// screen triangles to `out` and returns its planes, or `None` if it
    /// draws nothing; `counts` says why.
    ///
    /// The reference for `setup_x4` (4 triangles at once, bit-identical,
    /// what the frame runs): change both together.
    pub fn setup(
        &self,
        tri: u32,
        v: [[f32; 4]; 3],
        cull: Cull,
        out: &mut Vec<RasterTri>,
        counts: &mut SetupCounts,
    ) -> Option<TriPlanes> {
        self.setup_occluded(tri, v, cull, None, out, counts)
    }

    /// [`SetupContext::setup`], skipping the triangle too if `occluder`
    /// shows it writes no pixel (see `occlusion`).
    pub fn setup_occluded(
        &self,
        tri: u32,
        v: [[f32; 4]; 3],
        cull: Cull,
        occluder: Option<&DepthBounds>,
        out: &mut Vec<RasterTri>,
        counts: &mut SetupCounts,
    ) -> Option<TriPlanes> {
        counts.triangles += 1;
        let v: [ClipVertex; 3] = v.map(|p| p.map(|c| c as f64));
        if v.iter()
            .flatten()
            .any(|c| c.is_nan() || c.abs() > MAX_CLIP_COORD)
        {
            counts.skipped_invalid += 1;
            return None;
        }
        if outcode(&v[0]) & outcode(&v[1]) & outcode(&v[2]) != 0 {
            counts.culled_outside += 1;
            return None;
        }
        // Orientation from the 2D-homogeneous determinant: det > 0 is
        // counter-clockwise in NDC (y up), i.e. front-facing, and its sign
        // is right even for vertices behind the eye [Olano97].
        let cols = v.map(|p| [p[0], p[1], p[3]]);
        let adj = [
            cross3(cols[1], cols[2]),
            cross3(cols[2], cols[0]),
            cross3(cols[0], cols[1]),
        ];
        let det = dot3(cols[0], adj[0]);
        if det == 0.0 || !det.is_finite() {
            counts.skipped_degenerate += 1;
            return None;
        }
        let culled = match cull {
            Cull::Back => det < 0.0,
            Cull::Front => det > 0.0,
            Cull::None => false,
        };
        if culled {
            counts.culled_backface += 1;
            return None;
        }
        if occluder.is_some_and(|o| o.hides(&v)) {
            counts.culled_occluded += 1;
            return None;
        }

        let (w, h) = (self.width as f64, self.height as f64);
        let mut screen = [[0i64; 2]; crate::clip::MAX_CLIPPED];
        let (mut min_x, mut min_y) = (f64::INFINITY, f64::INFINITY);
        let mut finite = true;
        // Clipping puts every vertex inside the guard band up to rounding,
        // but only relative to w: at a subnormal w (1e-45, say) a clipped
        // vertex can land at w = 0 (x/w infinite) or millions of pixels
        // past the band (found by fuzzing; fixed.rs's i64 bounds assume
        // the band). Such a vertex carries no position: its triangle is
        // skipped as invalid; the others are clamped into the band, which
        // moves only vertices that rounding pushed out of it.
        let mut project = |i: usize, p: &ClipVertex| {
            let inv_w = 1.0 / p[3];
            let sx = (p[0] * inv_w + 1.0) * 0.5 * w;
            let sy = (1.0 - p[1] * inv_w) * 0.5 * h;
            finite &= sx.is_finite() && sy.is_finite();
            let (sx, sy) = (
                sx.clamp(-GUARD_BAND_PX, GUARD_BAND_PX),
                sy.clamp(-GUARD_BAND_PX, GUARD_BAND_PX),
            );
            min_x = min_x.min(sx);
            min_y = min_y.min(sy);
            screen[i] = [snap(sx), snap(sy)];
        };
        let n = if self.guard.needs_clip(&v) {
            counts.clipped += 1;
            let poly = self.guard.clip(&v);
            for (i, p) in poly.v[..poly.len].iter().enumerate() {
                project(i, p);
            }
            poly.len
        } else {
            for (i, p) in v.iter().enumerate() {
                project(i, p);
            }
            3
        };
        if n < 3 {
            counts.culled_outside += 1;
            return None;
        }
        if !finite {
            counts.skipped_invalid += 1;
            return None;
        }

        let before = out.len();
        for i in 1..n - 1 {
            if let Some(rt) = self.edges(tri, screen[0], screen[i], screen[i + 1]) {
                out.push(rt);
            }
        }
        if out.len() == before {
            counts.no_samples += 1;
            return None;
        }

        // Planes: rows of M⁻¹ = adj / det, composed with pixel → NDC
        // (nx = 2x/W − 1, ny = 1 − 2y/H) and moved to the origin.
        let ox = min_x.clamp(0.0, w);
        let oy = min_y.clamp(0.0, h);
        let (to_nx, to_ny) = (2.0 / w, -2.0 / h);
        let plane = |r: [f64; 3]| -> [f64; 3] {
            let (a, b) = (r[0] * to_nx, r[1] * to_ny);
            let c = -r[0] + r[1] + r[2];
            [a, b, a * ox + b * oy + c]
        };
        let inv_det = 1.0 / det;
        let k = adj.map(|r| plane(r.map(|x| x * inv_det)));
        let ks: [f32; 3] = std::array::from_fn(|c| (k[0][c] + k[1][c] + k[2][c]) as f32);
        let z: [f32; 3] = std::array::from_fn(|c| {
            (k[0][c] * v[0][2] + k[1][c] * v[1][2] + k[2][c] * v[2][2]) as f32
        });
        let planes = TriPlanes {
            origin: [ox as f32, oy as f32],
            k1: k[1].map(|x| x as f32),
            k2: k[2].map(|x| x as f32),
            ks,
            z,
            facing: if det > 0.0 { 1.0 } else { -1.0 },
        };
        // A vertex at a subnormal w (found by fuzzing) makes det tiny and
        // the planes' gradients huge: beyond f32, or finite but
        // overflowing when evaluated a few pixels from the origin, so
        // depth, barycentrics and 1/w would be inf or inf/inf = NaN at its
        // pixels. Such a triangle has no usable perspective: drop the
        // screen triangles it pushed and count it as degenerate. The
        // bound, on any pixel of the image, leaves f32 room for the
        // products shading forms; ordinary planes stay near 1/near
        // (1e8 at near = 1e-8).
        let (span_x, span_y) = (w + 1.0, h + 1.0);
        let bounded = [planes.k1, planes.k2, planes.ks, planes.z].iter().all(|p| {
            let m =
                (p[0] as f64).abs() * span_x + (p[1] as f64).abs() * span_y + (p[2] as f64).abs();
            m <= MAX_PLANE_VALUE
        });
        if !bounded {
            out.truncate(before);
            counts.skipped_degenerate += 1;
            return None;
        }
        counts.drawn += 1;
        Some(planes)
    }

    /// Edge functions and pixel bounds of one snapped screen triangle, or
    /// `None` if it has zero area or contains no pixel centre candidate.
    pub fn edges(
        &self,
        tri: u32,
        p0: [i64; 2],
        mut p1: [i64; 2],
        mut p2: [i64; 2],
    ) -> Option<RasterTri> {
        let area2 = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0]);
        if area2 == 0 {
            return None;
        }
        if area2 < 0 {
            std::mem::swap(&mut p1, &mut p2);
        }
        let edge = |pa: [i64; 2], pb: [i64; 2]| {
            let a = pa[1] - pb[1];
            let b = pb[0] - pa[0];
            // Top-left rule (y down): a left edge has the interior to its
            // right (A > 0), a top edge is horizontal with the interior below
            // (A = 0, B > 0). Centres exactly on other edges are not covered:
            // E > 0 there, i.e. E − 1 ≥ 0 in integers.
            let top_left = a > 0 || (a == 0 && b > 0);
            let c = -(a * pa[0] + b * pa[1]) - if top_left { 0 } else { 1 };
            Edge { a, b, c }
        };
        let xs = [p0[0], p1[0], p2[0]];
        let ys = [p0[1], p1[1], p2[1]];
        let bound = |lo: i64, hi: i64, n: u32| {
            let first = ceil_px(lo - SUBPIXEL_HALF).max(0);
            let end = (floor_px(hi - SUBPIXEL_HALF) + 1).min(n as i64);
            (first, end)
        };
        let (x0, x1) = bound(*xs.iter().min()?, *xs.iter().max()?, self.width);
        let (y0, y1) = bound(*ys.iter().min()?, *ys.iter().max()?, self.height);
        if x0 >= x1 || y0 >= y1 {
            return None;
        }
        let edges = [edge(p0, p1), edge(p1, p2), edge(p2, p0)];
        let extent = (xs.iter().max()? - xs.iter().min()?).max(ys.iter().max()? - ys.iter().min()?);
        let small = (extent <= SMALL_PX * SUBPIXEL_ONE).then(|| {
            let (cx, cy) = (pixel_centre(x0), pixel_centre(y0));
            SmallEdges {
                e0: edges.map(|e| (e.a * cx + e.b * cy + e.c) as i32),
                a: edges.map(|e| (e.a * SUBPIXEL_ONE) as i32),
                b: edges.map(|e| (e.b * SUBPIXEL_ONE) as i32),
            }
        });
        Some(RasterTri {
            small,
            inv_step: edges.map(|e| {
                if e.a == 0 {
                    0.0
                } else {
                    1.0 / (e.a.abs() * SUBPIXEL_ONE) as f64
                }
            }),
            edges,
            bbox: [x0 as i32, y0 as i32, x1 as i32, y1 as i32],
            tri,
        })
    }
}

impl RasterTri {
    /// Its pixel bounding box cut to the tile with origin (tx, ty), as
    /// [`crate::scan::covered_groups`] takes it: [x_lo, x_hi, y_lo, y_hi).
    #[inline(always)]
    pub(crate) fn tile_bounds(&self, tx: i32, ty: i32) -> [i32; 4] {
        let [bx0, by0, bx1, by1] = self.bbox;
        let tile = crate::target::TILE as i32;
        [
            bx0.max(tx),
            bx1.min(tx + tile),
            by0.max(ty),
            by1.min(ty + tile),
        ]
    }

    /// The covered pixels [x_first, x_end) of row `y` within [xa, xb)
    /// (empty: x_first ≥ x_end).
    ///
    /// Each edge's boundary is the root of 256·A·x + r = 0. It is estimated
    /// with one f64 multiply by the stored 1/(256|A|), clamped into [xa, xb),
    /// and then made exact by stepping with the integer edge value (the
    /// estimate is within one pixel, |r| < 2⁶⁰ having 53 good bits): exact
    /// like an integer division, without a division per edge and row.
    #[inline]
    pub(crate) fn span(&self, y: i32, xa: i32, xb: i32) -> (i32, i32) {
        let yc = pixel_centre(y as i64);
        let (mut lo, mut hi) = (xa as i64, xb as i64);
        for (e, inv) in self.edges.iter().zip(self.inv_step) {
            // E at the centre of pixel x is A·(256x + 128) + B·Yc + C
            // = 256·A·x + r; covered iff that is ≥ 0.
            let r = e.a * SUBPIXEL_HALF + e.b * yc + e.c;
            let step = e.a * SUBPIXEL_ONE;
            let f = |x: i64| step * x + r;
            if e.a > 0 {
                // f increases: the first x with f(x) ≥ 0.
                let mut q = ((-r) as f64 * inv).ceil().clamp(lo as f64, hi as f64) as i64;
                while q < hi && f(q) < 0 {
                    q += 1;
                }
                while q > lo && f(q - 1) >= 0 {
                    q -= 1;
                }
                lo = q;
            } else if e.a < 0 {
                // f decreases: the first x with f(x) < 0.
                let mut q = ((r as f64 * inv).floor() + 1.0).clamp(lo as f64, hi as f64) as i64;
                while q > lo && f(q - 1) < 0 {
                    q -= 1;
                }
                while q < hi && f(q) >= 0 {
                    q += 1;
                }
                hi = q;
            } else if r < 0 {
                return (0, 0);
            }
            if lo >= hi {
                return (0, 0);
            }
        }
        (lo as i32, hi as i32)
    }

    /// Whether the triangle covers every pixel centre of the rectangle
    /// [x0, x1) × [y0, y1) (non-empty), none of them, or some. Exact: each
    /// edge function is linear, so over the rectangle's pixel centres it
    /// takes its extremes at the four corner ones.
    pub fn rect_coverage(&self, [x0, x1, y0, y1]: [i32; 4]) -> RectCoverage {
        let xs = [pixel_centre(x0 as i64), pixel_centre(x1 as i64 - 1)];
        let ys = [pixel_centre(y0 as i64), pixel_centre(y1 as i64 - 1)];
        let mut all_inside = true;
        for e in &self.edges {
            let inside = |x: i64, y: i64| e.a * x + e.b * y + e.c >= 0;
            let n = [(0, 0), (0, 1), (1, 0), (1, 1)]
                .iter()
                .filter(|&&(i, j)| inside(xs[i], ys[j]))
                .count();
            if n == 0 {
                return RectCoverage::Outside;
            }
            all_inside &= n == 4;
        }
        if all_inside {
            RectCoverage::Inside
        } else {
            RectCoverage::Partial
        }
    }

    /// True if the centre of pixel (x, y) is covered: the direct test that
    /// `RasterTri::span` solves for a whole row (tests compare the two).
    pub fn covers(&self, x: i32, y: i32) -> bool {
        let (px, py) = (pixel_centre(x as i64), pixel_centre(y as i64));
        self.edges.iter().all(|e| e.a * px + e.b * py + e.c >= 0)
    }
}
