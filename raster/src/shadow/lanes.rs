//! The lookups of `lookup.rs` on a packet's lanes, bit for bit: hard and
//! PCF on all lanes at once (per face present, under its lanes' mask),
//! PCSS and maps too large for f32 gather indices lane by lane.

use super::settings::ShadowFilter;
use super::{DepthWindows, Face, LightShadow, Pick};
use glam::Vec3;
use specula_core::{Mask, Real, V3};
#[cfg(target_arch = "x86_64")]
use {
    crate::lanes16::{v3_hi, v3_lo, F32x16},
    specula_core::f32x8,
};

impl LightShadow {
    /// [`LightShadow::visibility_lanes`] for a light whose part at each
    /// lane is `part`, looked up only where `part` is not zero (1
    /// elsewhere): a factor is finite and in [0, 1], so there
    /// `part` × factor and `part` × 1 are the same zero, and lanes a light
    /// does not reach (outside a spot's cone, facing away) cost nothing.
    #[inline(always)]
    pub fn visibility_where<R: Real>(&self, part: &V3<R>, p: &V3<R>, n: &V3<R>, lanes: u32) -> R {
        self.visibility_at(p, n, lanes & reached(part))
    }

    /// [`LightShadow::visibility_where`] of two packets, one in each half
    /// of sixteen lanes (the packet pairs'): each half's factor, the same
    /// bits. On a single hard or PCF map, or on the one face of several
    /// that every lane picks ([`LightShadow::one_face_of`]), the
    /// projection and the near bounds' verdict "every lane wholly lit" run
    /// in sixteen lanes, each half ending on it as its own lookup would,
    /// and only a half it leaves open goes on (out of line, in f32x8).
    /// Other packets look each half up in f32x8.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub(crate) fn visibility_where_pair(
        &self,
        part: &V3<F32x16>,
        p: &V3<F32x16>,
        n: &V3<F32x16>,
        lanes: u32,
    ) -> F32x16 {
        let lanes = lanes & reached(part);
        let one = <f32x8 as Real>::ONE;
        if lanes == 0 {
            return F32x16::both(one);
        }
        let (lanes_lo, lanes_hi) = (lanes & 0xFF, lanes >> 8);
        // (`match`, not `or_else`: a closure is compiled without the
        // packet pairs' AVX-512 features.)
        let face = match self.packet_face() {
            Some(face) => Some(face),
            None => self.one_face_of(p, lanes),
        };
        let Some(face) = face else {
            return F32x16::from_halves(
                self.visibility_at(&v3_lo(p), &v3_lo(n), lanes_lo),
                self.visibility_at(&v3_hi(p), &v3_hi(n), lanes_hi),
            );
        };
        let at = self.project(face, p, n, lanes);
        let s = &self.settings;
        // The lanes the near bounds show wholly lit (or not using the map).
        let lit = match s.filter {
            ShadowFilter::Pcf => match face.pcf_lit_lanes(&at, s.filter_radius) {
                Some(m) => m.bits(),
                None => 0,
            },
            _ => 0,
        };
        if lit == 0xFFFF {
            return F32x16::both(one);
        }
        let [lo, hi] = at.halves();
        // A half ends where its own lookup would: with no lanes, or with
        // every lane lit by the near bounds.
        let (open_lo, open_hi) = (
            lanes_lo != 0 && lit & 0xFF != 0xFF,
            lanes_hi != 0 && lit >> 8 != 0xFF,
        );
        F32x16::from_halves(
            if open_lo {
                self.finish_packet(face, &lo)
            } else {
                one
            },
            if open_hi {
                self.finish_packet(face, &hi)
            } else {
                one
            },
        )
    }

    /// [`LightShadow::visibility_lanes`] of the lanes in `lanes`, with the
    /// common lookups' end inline in the caller: on a single hard or PCF
    /// map (or one face that every lane picks), the projection and the
    /// near bounds' "every lane wholly lit" verdict, the rest out of line.
    /// The same bits.
    #[inline(always)]
    pub fn visibility_at<R: Real>(&self, p: &V3<R>, n: &V3<R>, lanes: u32) -> R {
        if lanes == 0 {
            return R::ONE;
        }
        let face = match self.packet_face() {
            Some(face) => Some(face),
            None => self.one_face_of(p, lanes),
        };
        match face {
            Some(face) => self.visibility_packet_split(face, p, n, lanes),
            None => self.visibility_lanes(p, n, lanes),
        }
    }

    /// For a light of several faces whose lookups run on all lanes at once
    /// (a cube map's, cascades), the face that every lane in `lanes` (not
    /// none) picks, if they all pick one: most packets lie within one face.
    /// [`LightShadow::visibility_lanes`] runs that face's lookup alone
    /// then, under the lanes' mask, which is what the single-face path
    /// does with it (the same bits).
    #[inline(always)]
    fn one_face_of<R: Real>(&self, p: &V3<R>, lanes: u32) -> Option<&Face> {
        if self.faces.len() < 2 || !self.packet_lookups() {
            return None;
        }
        let masks = self.face_masks(p, lanes);
        let k = masks.iter().position(|&m| m == lanes)?;
        self.faces.get(k)
    }

    /// The face of a light whose lookups run on all lanes at once with
    /// one face (hard or PCF, a single map small enough for f32 gather
    /// indices), if this light is one.
    #[inline(always)]
    fn packet_face(&self) -> Option<&Face> {
        match self.faces.as_slice() {
            [face] if self.packet_lookups() => Some(face),
            _ => None,
        }
    }

    /// Whether this light's lookups run on all lanes at once: hard or PCF,
    /// on maps small enough for f32 gather indices (a light's faces share
    /// their size).
    #[inline(always)]
    fn packet_lookups(&self) -> bool {
        self.settings.filter != ShadowFilter::Pcss && self.faces[0].size <= MAX_PACKET_MAP
    }

    /// [`LightShadow::visibility_packet`] with the common end inline:
    /// the projection and, for PCF, the near bounds' verdict "every lane
    /// wholly lit" ([`Face::pcf_all_lit`]) here, in the caller's light
    /// loop; the rest of the lookup out of line
    /// ([`LightShadow::finish_packet`]). The same bits.
    #[inline(always)]
    fn visibility_packet_split<R: Real>(&self, face: &Face, p: &V3<R>, n: &V3<R>, lanes: u32) -> R {
        let at = self.project(face, p, n, lanes);
        let s = &self.settings;
        if s.filter == ShadowFilter::Pcf && face.pcf_all_lit(&at, s.filter_radius) {
            return R::ONE;
        }
        self.finish_packet(face, &at)
    }

    /// [`LightShadow::visibility`] of each lane of `p`, `n` in `lanes`
    /// (1 elsewhere), bit for bit. Hard and PCF lookups on maps small
    /// enough for exact f32 gather indices run on all lanes at once
    /// (`visibility_packet`): each lane picks its face (cube
    /// face or cascade) as the scalar lookup does, and each face present
    /// runs once under its lanes' mask. PCSS (whose search and filter
    /// widths differ per lane) and larger maps go lane by lane.
    pub fn visibility_lanes<R: Real>(&self, p: &V3<R>, n: &V3<R>, lanes: u32) -> R {
        if let Some(face) = self.packet_face() {
            return self.visibility_packet(face, p, n, lanes);
        }
        if self.packet_lookups() {
            let masks = self.face_masks(p, lanes);
            let mut out = R::ONE;
            for (face, m) in self.faces.iter().zip(masks) {
                if m != 0 {
                    let f = self.visibility_packet(face, p, n, m);
                    out = R::select(R::mask_from_bits(m), f, out);
                }
            }
            return out;
        }
        let mut c = [[0.0f32; 8]; 6];
        for (out, v) in c.iter_mut().zip([p.x, p.y, p.z, n.x, n.y, n.z]) {
            v.store(out);
        }
        let mut f = [1.0f32; 8];
        for (i, f) in f.iter_mut().enumerate().take(R::LANES) {
            if lanes & (1 << i) != 0 {
                *f = self.visibility(
                    Vec3::new(c[0][i], c[1][i], c[2][i]),
                    Vec3::new(c[3][i], c[4][i], c[5][i]),
                );
            }
        }
        R::load(&f)
    }

    /// Per face, the mask of the `lanes` whose point it sees (a lane with
    /// a non-finite point goes to face 0, whose lookup gives it 1).
    /// Inline: the packet pairs call it on sixteen lanes, which exist only
    /// in their AVX-512 function.
    #[inline(always)]
    fn face_masks<R: Real>(&self, p: &V3<R>, lanes: u32) -> [u32; 6] {
        if let (Pick::Cube(c), false) = (&self.pick, R::EXACT) {
            return cube_face_masks(p, *c, lanes);
        }
        let mut masks = [0u32; 6];
        for i in (0..R::LANES).filter(|i| lanes & (1 << i) != 0) {
            let q = Vec3::new(p.x.lane(i) as f32, p.y.lane(i) as f32, p.z.lane(i) as f32);
            let f = if q.is_finite() { self.face_index(q) } else { 0 };
            masks[f] |= 1 << i;
        }
        masks
    }

    /// [`LightShadow::visibility`] on every lane at once, for a hard or
    /// PCF light whose lanes all use `face`: the same operations in the
    /// same order (no fused multiply-adds), so the same bits.
    #[inline(always)]
    fn visibility_packet<R: Real>(&self, face: &Face, p: &V3<R>, n: &V3<R>, lanes: u32) -> R {
        let at = self.project(face, p, n, lanes);
        self.filter_packet(face, &at)
    }

    /// [`LightShadow::filter_packet`] out of line: the part of a lookup
    /// that the light loop does not inline.
    #[inline(never)]
    fn finish_packet<R: Real>(&self, face: &Face, at: &MapPoint<R>) -> R {
        self.filter_packet(face, at)
    }

    /// The lanes' factors from their map coordinates `at` (1 on lanes
    /// that do not use the map).
    #[inline(always)]
    fn filter_packet<R: Real>(&self, face: &Face, at: &MapPoint<R>) -> R {
        let s = &self.settings;
        let MapPoint { u, v, d, use_map } = at.masked();
        let f = match s.filter {
            ShadowFilter::Hard => face.lit_lanes(round_lanes(u), round_lanes(v), d),
            _ => match face.pcf_decided(u, v, d, s.filter_radius, use_map) {
                Some(f) => f,
                None => face
                    .pcf_grid(u, v, d, s.filter_radius, use_map)
                    .unwrap_or_else(|| face.pcf_lanes(u, v, d, s.filter_radius)),
            },
        };
        R::select(use_map, f, R::ONE)
    }

    /// The lanes' texel coordinates and biased depths on `face`, as the
    /// scalar lookup computes them, and the lanes in `lanes` that use the
    /// map. A lane whose point or normal is not finite does not: its
    /// shifted point has a NaN or infinite coordinate, which every row of
    /// the projection takes (times 0 it is NaN), so its x is not within
    /// ±1 (the scalar lookup's finiteness test, without its cost).
    #[inline(always)]
    fn project<R: Real>(&self, face: &Face, p: &V3<R>, n: &V3<R>, lanes: u32) -> MapPoint<R> {
        let s = &self.settings;
        let k = splat::<R>;
        let texel = if face.perspective {
            k(face.texel) * face.depth_of_lanes(p).max(k(face.near))
        } else {
            k(face.texel)
        };
        let radius = match s.filter {
            ShadowFilter::Hard => 0.0,
            _ => s.filter_radius,
        };
        let push = k(s.normal_bias) * texel * k(1.0 + radius);
        let p = V3::new(p.x + n.x * push, p.y + n.y * push, p.z + n.z * push);
        // face.clip × (p, 1), column by column as glam's Mat4 × Vec4 adds.
        let [c0, c1, c2, c3] = [
            face.clip.x_axis,
            face.clip.y_axis,
            face.clip.z_axis,
            face.clip.w_axis,
        ];
        let cx = row(&p, [c0.x, c1.x, c2.x, c3.x]);
        let cy = row(&p, [c0.y, c1.y, c2.y, c3.y]);
        // An affine map's w is 0·x + 0·y + 0·z + 1 = 1 at every finite
        // point, and x / 1 = x: its division is skipped (the other lanes
        // are out of the map by their x, as above).
        let affine = [c0.w, c1.w, c2.w] == [0.0; 3] && c3.w == 1.0;
        let (x, y, inside) = if affine {
            (cx, cy, inside_unit(cx, cy))
        } else {
            let cw = row(&p, [c0.w, c1.w, c2.w, c3.w]);
            let (x, y) = (cx / cw, cy / cw);
            (x, y, cw.gt(R::ZERO) & inside_unit(x, y))
        };
        let size = k(face.size as f32);
        let half = R::HALF;
        MapPoint {
            u: (x + R::ONE) * half * size - half,
            v: (R::ONE - y) * half * size - half,
            d: face.depth_of_lanes(&p) - k(s.bias) * texel,
            use_map: inside & R::mask_from_bits(lanes),
        }
    }
}

/// The lanes where a light's `part` is not zero (its factor is read only
/// there: [`LightShadow::visibility_where`]).
#[inline(always)]
fn reached<R: Real>(part: &V3<R>) -> u32 {
    (part.x.abs().gt(R::ZERO) | part.y.abs().gt(R::ZERO) | part.z.abs().gt(R::ZERO)).bits()
}

// Helpers as functions, not closures: the packet pairs inline these
// lookups into a function compiled for AVX-512, and a closure is compiled
// without its caller's features (each sixteen-lane operation in it became
// a call).

/// `x` in every lane.
#[inline(always)]
fn splat<R: Real>(x: f32) -> R {
    R::splat(x as f64)
}

/// One row of a matrix (its x, y, z and w columns' entries) times (p, 1),
/// added column by column as glam's Mat4 × Vec4 adds.
#[inline(always)]
fn row<R: Real>(p: &V3<R>, [a, b, c, d]: [f32; 4]) -> R {
    splat::<R>(a) * p.x + splat::<R>(b) * p.y + splat::<R>(c) * p.z + splat::<R>(d)
}

/// The lanes where `v` < 0.
#[inline(always)]
fn negative<R: Real>(v: R) -> R::Mask {
    v.lt(R::ZERO)
}

/// The lanes with |x| ≤ 1 and |y| ≤ 1.
#[inline(always)]
fn inside_unit<R: Real>(x: R, y: R) -> R::Mask {
    x.abs().le(R::ONE) & y.abs().le(R::ONE)
}

/// A packet's lanes on one face: continuous texel coordinates (texel
/// centres at integers), the biased depth to compare, and the lanes that
/// read the map (the others get the factor 1; their coordinates may be
/// anything, even NaN, until [`MapPoint::masked`]).
#[derive(Clone, Copy)]
struct MapPoint<R: Real> {
    u: R,
    v: R,
    d: R,
    use_map: R::Mask,
}

#[cfg(target_arch = "x86_64")]
impl MapPoint<F32x16> {
    /// Each half's point as its own projection makes it (the same
    /// operations per lane), its lanes those of this one in the half.
    #[inline(always)]
    fn halves(&self) -> [MapPoint<f32x8>; 2] {
        let bits = self.use_map.bits();
        [
            MapPoint {
                u: self.u.lo(),
                v: self.v.lo(),
                d: self.d.lo(),
                use_map: <f32x8 as Real>::mask_from_bits(bits & 0xFF),
            },
            MapPoint {
                u: self.u.hi(),
                v: self.v.hi(),
                d: self.d.hi(),
                use_map: <f32x8 as Real>::mask_from_bits(bits >> 8),
            },
        ]
    }
}

impl<R: Real> MapPoint<R> {
    /// The point with 0 on the lanes that do not use the map, as the
    /// filters read it (a verdict on `use_map`'s lanes alone, as
    /// [`Face::pcf_all_lit`]'s, needs no mask: its reads clamp NaN).
    #[inline(always)]
    fn masked(self) -> Self {
        let m = |x: R| R::select(self.use_map, x, R::ZERO);
        MapPoint {
            u: m(self.u),
            v: m(self.v),
            d: m(self.d),
            use_map: self.use_map,
        }
    }
}

/// [`LightShadow::face_index`] of a cube around `c` on all lanes at once,
/// as masks: the same comparisons in f32 (lanes of f32 are the scalar
/// pick's own values; not for f64 lanes, which it rounds to f32 first).
#[inline(always)]
fn cube_face_masks<R: Real>(p: &V3<R>, c: Vec3, lanes: u32) -> [u32; 6] {
    let k = splat::<R>;
    let d = V3::new(p.x - k(c.x), p.y - k(c.y), p.z - k(c.z));
    let a = V3::new(d.x.abs(), d.y.abs(), d.z.abs());
    let finite = p.x.is_finite() & p.y.is_finite() & p.z.is_finite();
    let on_x = a.x.ge(a.y) & a.x.ge(a.z);
    let on_y = !on_x & a.y.ge(a.z);
    let on_z = !(on_x | on_y);
    let neg = negative::<R>;
    // A lane with a non-finite point goes to face 0, as `face_masks` does.
    let bits = |m: R::Mask| m.bits() & lanes;
    let pos_x = bits(!finite | (on_x & !neg(d.x)));
    [
        pos_x,
        bits(finite & on_x & neg(d.x)),
        bits(finite & on_y & !neg(d.y)),
        bits(finite & on_y & neg(d.y)),
        bits(finite & on_z & !neg(d.z)),
        bits(finite & on_z & neg(d.z)),
    ]
}

/// Largest map side whose texel indices (up to side² − 1) are exact in
/// f32, the index type of the lanes' gathers.
const MAX_PACKET_MAP: u32 = 4096;

/// f32's `round` (half away from zero) for values that are then clamped
/// to texels ≥ 0: below 0 it may differ, but only among values that
/// clamp to texel 0 alike. (The fraction u − ⌊u⌋ is exact.)
#[inline(always)]
fn round_lanes<R: Real>(u: R) -> R {
    let t = u.floor();
    R::select((u - t).ge(R::HALF), t + R::ONE, t)
}

impl Face {
    /// [`Face::depth_of`] per lane, with its operations in its order.
    #[inline(always)]
    fn depth_of_lanes<R: Real>(&self, p: &V3<R>) -> R {
        let k = splat::<R>;
        let (o, a) = (self.origin, self.axis);
        (p.x - k(o.x)) * k(a.x) + (p.y - k(o.y)) * k(a.y) + (p.z - k(o.z)) * k(a.z)
    }

    /// 1 where `d` ≤ the map's depth at integer texel (x, y) (clamped to
    /// the map), 0 elsewhere: [`Face::at`]'s comparison per lane.
    #[inline(always)]
    fn lit_lanes<R: Real>(&self, x: R, y: R, d: R) -> R {
        let last = R::splat((self.size - 1) as f64);
        let (x, y) = (x.clamp(R::ZERO, last), y.clamp(R::ZERO, last));
        let depth = R::gather(&self.depth, y * R::splat(self.size as f64) + x);
        R::select(d.le(depth), R::ONE, R::ZERO)
    }

    /// [`Face::compare_bilinear`] per lane.
    #[inline(always)]
    fn compare_bilinear_lanes<R: Real>(&self, u: R, v: R, d: R) -> R {
        let (x0, y0) = (u.floor(), v.floor());
        let (fx, fy) = (u - x0, v - y0);
        let (x1, y1) = (x0 + R::ONE, y0 + R::ONE);
        let top = self.lit_lanes(x0, y0, d) * (R::ONE - fx) + self.lit_lanes(x1, y0, d) * fx;
        let bottom = self.lit_lanes(x0, y1, d) * (R::ONE - fx) + self.lit_lanes(x1, y1, d) * fx;
        top * (R::ONE - fy) + bottom * fy
    }

    /// Whether the near bounds alone show every lane of `at` that uses
    /// the map wholly lit: [`Face::pcf_decided`]'s first verdict, which
    /// most lookups end on (its far bounds and taps are then not read).
    #[inline(always)]
    fn pcf_all_lit<R: Real>(&self, at: &MapPoint<R>, radius: f32) -> bool {
        matches!(self.pcf_lit_lanes(at, radius), Some(m) if m.all())
    }

    /// The lanes [`Face::pcf_all_lit`]'s verdict holds on (wholly lit by
    /// the near bounds, or not using the map); `None` when the face has
    /// no bounds.
    #[inline(always)]
    fn pcf_lit_lanes<R: Real>(&self, at: &MapPoint<R>, radius: f32) -> Option<R::Mask> {
        let b = self.bounds.as_ref()?;
        let (i, fits) = self.window_of(b, at.u, at.v, radius);
        let lit = fits & at.d.le(R::gather(&b.near, i));
        Some(!at.use_map | lit)
    }

    /// The index of the window of `b` that holds the texels of PCF taps
    /// of `radius` around (u, v), and the lanes whose taps it holds.
    #[inline(always)]
    fn window_of<R: Real>(&self, b: &DepthWindows, u: R, v: R, radius: f32) -> (R, R::Mask) {
        let last = R::splat((self.size - 1) as f64);
        let reach = R::splat((b.window - 1) as f64);
        // The taps' texels along one axis: from the lowest tap's x0 to the
        // highest tap's x0 + 1, computed as `pcf_lanes` computes them,
        // then clamped as `at` clamps. The window from the lowest, and
        // whether it also holds the highest.
        let (x, fits_x) = window_span(u, radius, last, reach);
        let (y, fits_y) = window_span(v, radius, last, reach);
        (y * R::splat(self.size as f64) + x, fits_x & fits_y)
    }

    /// [`Face::pcf`] of every lane in `lanes` without reading its taps,
    /// when each such lane is wholly lit or wholly shadowed: `Some(1)`
    /// where `d` is at most the nearest depth of the window that holds
    /// every texel its taps read ([`DepthWindows`]), `Some(0)` where it is
    /// beyond the farthest; `None` when a lane is neither (or the face has
    /// no bounds), and the taps decide. (Lanes outside `lanes` get 1 or 0
    /// alike: the caller drops them.)
    ///
    /// Exact, so the same bits as [`Face::pcf_lanes`]: all comparisons 0
    /// give 0; all 1 give 1, since every bilinear weight pair
    /// fl(1 − x) + x rounds to 1 for 0 ≤ x ≤ 1 (fl(1 − x) is exact for
    /// x ≥ ½; below, its error is at most a quarter ulp of 1, which the
    /// sum rounds away), and 9 × 1 / 9 = 1.
    #[inline(always)]
    fn pcf_decided<R: Real>(&self, u: R, v: R, d: R, radius: f32, lanes: R::Mask) -> Option<R> {
        let b = self.bounds.as_ref()?;
        let (i, fits) = self.window_of(b, u, v, radius);
        // Mostly lit: then the far bounds are not read.
        let lit = fits & d.le(R::gather(&b.near, i));
        if (!lanes | lit).all() {
            return Some(R::ONE);
        }
        let dark = fits & d.gt(R::gather(&b.far, i));
        (!lanes | lit | dark)
            .all()
            .then(|| R::select(lit, R::ONE, R::ZERO))
    }

    /// [`Face::pcf_lanes`] reading each texel once, when the lanes in
    /// `lanes` share the taps' layout: 2r a whole number k ≤ 3 of texels,
    /// so that the taps at u − r, u and u + r start at texels x, x + ⌊r⌋
    /// or x + ⌊r⌋ + 1 (per lane) and x + k, inside a grid of k + 2 texels
    /// from x = ⌊u − r⌋ (both axes; the default radius 1.5 reads 5 × 5
    /// texels instead of 9 × 4). Each tap's comparisons are picked from
    /// the grid's, and its weights and the sum are `pcf_lanes`'s, so the
    /// bits are the same. `None` when a lane's taps fall otherwise (an
    /// addition rounded across a texel edge) or for other radii: then the
    /// taps read alone.
    #[inline(always)]
    fn pcf_grid<R: Real>(&self, u: R, v: R, d: R, radius: f32, lanes: R::Mask) -> Option<R> {
        match (2.0 * radius, radius.floor()) {
            (3.0, 1.0) => self.pcf_grid_k::<R, 3, 1>(u, v, d, radius, lanes),
            (2.0, 1.0) => self.pcf_grid_k::<R, 2, 1>(u, v, d, radius, lanes),
            (1.0, 0.0) => self.pcf_grid_k::<R, 1, 0>(u, v, d, radius, lanes),
            _ => None,
        }
    }

    /// [`Face::pcf_grid`] for 2r = `K`, ⌊r⌋ = `M`.
    #[inline(always)]
    fn pcf_grid_k<R: Real, const K: usize, const M: usize>(
        &self,
        u: R,
        v: R,
        d: R,
        radius: f32,
        lanes: R::Mask,
    ) -> Option<R> {
        const MAX: usize = 5;
        // Per axis: the taps' coordinates as `pcf_lanes` adds them, the
        // grid's first texel, and which lanes' middle tap starts one on.
        let axis = |t: R| {
            let taps = [-1.0f32, 0.0, 1.0].map(|i| t + R::splat((i * radius) as f64));
            let first = taps[0].floor();
            let (mid, end) = (taps[1].floor() - first, taps[2].floor() - first);
            let (m, k) = (R::splat(M as f64), R::splat(K as f64));
            let laid = end.le(k) & end.ge(k) & mid.ge(m) & mid.le(m + R::ONE);
            (taps, first, mid.gt(m), laid)
        };
        let (tu, x, mx, laid_x) = axis(u);
        let (tv, y, my, laid_y) = axis(v);
        if !(!lanes | (laid_x & laid_y)).all() {
            return None;
        }
        // The grid's comparisons, lit[row][column], its texels clamped as
        // `at` clamps them.
        let last = R::splat((self.size - 1) as f64);
        let size = R::splat(self.size as f64);
        // Where no lane's columns reach past the map's sides (where they
        // would clamp), each row's texels are a run from its first (lanes
        // not looked up start at column 0); otherwise each is gathered at
        // its clamped column.
        let edge = !lanes | x.ge(R::ZERO) & (x + R::splat((MAX - 1) as f64)).le(last);
        let runs = edge.all();
        let x = if runs {
            R::select(lanes, x, R::ZERO)
        } else {
            x
        };
        let cols: [R; MAX] = std::array::from_fn(|i| (x + R::splat(i as f64)).clamp(R::ZERO, last));
        let mut lit = [[R::ZERO; MAX]; MAX];
        for (j, row) in lit.iter_mut().enumerate().take(K + 2) {
            let base = (y + R::splat(j as f64)).clamp(R::ZERO, last) * size;
            let texels: [R; MAX] = match runs {
                true => R::gather_run::<MAX>(&self.depth, base + x),
                false => std::array::from_fn(|i| R::gather(&self.depth, base + cols[i])),
            };
            for (l, &t) in row.iter_mut().zip(&texels).take(K + 2) {
                *l = R::select(d.le(t), R::ONE, R::ZERO);
            }
        }
        // Tap row by tap row: its two texel rows picked from the grid's
        // (a pick is a select, so rows before columns gives the same
        // comparisons), then each tap's columns; summed in `pcf_lanes`'s
        // order.
        let mut sum = R::ZERO;
        for (tj, &tv) in tv.iter().enumerate() {
            let mut rows = [[R::ZERO; MAX]; 2];
            for (e, row) in rows.iter_mut().enumerate() {
                for (c, l) in row.iter_mut().enumerate().take(K + 2) {
                    *l = tap_texel::<R, K, M>(tj, my, e, |k| lit[k][c]);
                }
            }
            let fy = tv - tv.floor();
            for (ti, &tu) in tu.iter().enumerate() {
                // `compare_bilinear_lanes` on the grid's comparisons.
                let fx = tu - tu.floor();
                let pick = |r: &[R; MAX], e| tap_texel::<R, K, M>(ti, mx, e, |k| r[k]);
                let (l00, l10) = (pick(&rows[0], 0), pick(&rows[0], 1));
                let (l01, l11) = (pick(&rows[1], 0), pick(&rows[1], 1));
                let top = l00 * (R::ONE - fx) + l10 * fx;
                let bottom = l01 * (R::ONE - fx) + l11 * fx;
                sum += top * (R::ONE - fy) + bottom * fy;
            }
        }
        Some(sum / R::splat(9.0))
    }

    /// [`Face::pcf`] per lane.
    #[inline(always)]
    fn pcf_lanes<R: Real>(&self, u: R, v: R, d: R, radius: f32) -> R {
        if radius <= 0.0 {
            return self.compare_bilinear_lanes(u, v, d);
        }
        let mut sum = R::ZERO;
        for j in -1..=1 {
            for i in -1..=1 {
                let (du, dv) = (i as f32 * radius, j as f32 * radius);
                sum += self.compare_bilinear_lanes(
                    u + R::splat(du as f64),
                    v + R::splat(dv as f64),
                    d,
                );
            }
        }
        sum / R::splat(9.0)
    }
}

/// In [`Face::window_of`], along one axis: the first texel of the window
/// (clamped to 0..=`last`) and whether its `reach` also holds the last.
#[inline(always)]
fn window_span<R: Real>(t: R, radius: f32, last: R, reach: R) -> (R, R::Mask) {
    let first = (t + R::splat(-radius as f64)).floor().clamp(R::ZERO, last);
    let end = ((t + R::splat(radius as f64)).floor() + R::ONE).clamp(R::ZERO, last);
    (first, end.le(first + reach))
}

/// In [`Face::pcf_grid_k`] (2r = `K`, ⌊r⌋ = `M`): tap `t`'s texel
/// t0 + `e` along one axis, where t0 is 0, M or M + 1 (by `mid`) or K,
/// read from the grid by `at`.
#[inline(always)]
fn tap_texel<R: Real, const K: usize, const M: usize>(
    t: usize,
    mid: R::Mask,
    e: usize,
    at: impl Fn(usize) -> R,
) -> R {
    match t {
        0 => at(e),
        1 => R::select(mid, at(M + 1 + e), at(M + e)),
        _ => at(K + e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tap grid ([`Face::pcf_grid`]: each row's texels read as runs
    /// where no lane's columns reach past the map's sides, clamped
    /// gathers where one does) against the taps read one by one
    /// ([`Face::pcf_lanes`]), bit for bit, at points all over a map of
    /// random depths (some texels empty) and past its four sides, with
    /// some lanes not looked up.
    #[test]
    fn the_tap_grid_reads_what_the_taps_read_up_to_the_maps_sides() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let mut next = move || rng.random::<f32>();
        let n = 24u32;
        let depth = (0..n * n)
            .map(|_| match next() {
                x if x < 0.1 => f32::INFINITY,
                x => 1.0 + 2.0 * x,
            })
            .collect();
        let face = Face {
            size: n,
            depth,
            ..Face::default()
        };
        let (mut runs, mut sides) = (0, 0);
        for radius in [1.5f32, 1.0, 0.5] {
            for trial in 0..3000 {
                // Every other packet's lanes inside the map, the others
                // anywhere from two texels before it to two past it.
                let (lo, hi) = match trial % 2 {
                    0 => (radius + 0.5, n as f32 - 4.5 + radius),
                    _ => (-2.0, n as f32 + 1.0),
                };
                let mut at = || f32x8::from([(); 8].map(|_| lo + (hi - lo) * next()));
                let (u, v) = (at(), at());
                let d = f32x8::from([(); 8].map(|_| 1.0 + 2.0 * next()));
                let lanes = (next() * 256.0) as u32 | 1;
                let mask = <f32x8 as Real>::mask_from_bits(lanes);
                let x = (u - f32x8::splat(radius)).floor();
                let last = f32x8::splat((n - 1) as f32);
                let inside = !mask | x.ge(f32x8::ZERO) & (x + f32x8::splat(4.0)).le(last);
                let Some(got) = face.pcf_grid(u, v, d, radius, mask) else {
                    continue;
                };
                match inside.all() {
                    true => runs += 1,
                    false => sides += 1,
                }
                let want = face.pcf_lanes(u, v, d, radius);
                for l in (0..8).filter(|l| lanes & (1 << l) != 0) {
                    assert_eq!(
                        (got.lane(l) as f32).to_bits(),
                        (want.lane(l) as f32).to_bits(),
                        "radius {radius}, lane {l}: u {u:?}, v {v:?}, d {d:?}"
                    );
                }
            }
        }
        assert!(
            runs > 1000 && sides > 1000,
            "{runs} packets read as runs, {sides} at the sides"
        );
    }
}
