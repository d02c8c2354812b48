//! The lookups of `lookup.rs` on a packet's lanes, bit for bit: hard and
//! PCF on all lanes at once (per face present, under its lanes' mask),
//! PCSS and maps too large for f32 gather indices lane by lane.

use super::settings::ShadowFilter;
use super::{Face, LightShadow};
use glam::Vec3;
use specula_core::{Real, V3};

impl LightShadow {
    /// [`LightShadow::visibility`] of each lane of `p`, `n` in `lanes`
    /// (1 elsewhere), bit for bit. Hard and PCF lookups on maps small
    /// enough for exact f32 gather indices run on all lanes at once
    /// (`visibility_packet`): each lane picks its face (cube
    /// face or cascade) as the scalar lookup does, and each face present
    /// runs once under its lanes' mask. PCSS (whose search and filter
    /// widths differ per lane) and larger maps go lane by lane.
    pub fn visibility_lanes<R: Real>(&self, p: &V3<R>, n: &V3<R>, lanes: u32) -> R {
        if self.settings.filter != ShadowFilter::Pcss && self.faces[0].size <= MAX_PACKET_MAP {
            if self.faces.len() == 1 {
                return self.visibility_packet(&self.faces[0], p, n, lanes);
            }
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
    fn face_masks<R: Real>(&self, p: &V3<R>, lanes: u32) -> [u32; 6] {
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
        let s = &self.settings;
        let k = |x: f32| R::splat(x as f64);
        let finite = p.x.is_finite()
            & p.y.is_finite()
            & p.z.is_finite()
            & n.x.is_finite()
            & n.y.is_finite()
            & n.z.is_finite();
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
        let row = |a: f32, b: f32, c: f32, d: f32| k(a) * p.x + k(b) * p.y + k(c) * p.z + k(d);
        let cx = row(c0.x, c1.x, c2.x, c3.x);
        let cy = row(c0.y, c1.y, c2.y, c3.y);
        let cw = row(c0.w, c1.w, c2.w, c3.w);
        let (x, y) = (cx / cw, cy / cw);
        let inside = cw.gt(R::ZERO) & x.abs().le(R::ONE) & y.abs().le(R::ONE);
        let use_map = finite & inside & R::mask_from_bits(lanes);
        let size = k(face.size as f32);
        let half = R::HALF;
        let u = R::select(use_map, (x + R::ONE) * half * size - half, R::ZERO);
        let v = R::select(use_map, (R::ONE - y) * half * size - half, R::ZERO);
        let d = R::select(
            use_map,
            face.depth_of_lanes(&p) - k(s.bias) * texel,
            R::ZERO,
        );
        let f = match s.filter {
            ShadowFilter::Hard => face.lit_lanes(round_lanes(u), round_lanes(v), d),
            _ => face.pcf_lanes(u, v, d, s.filter_radius),
        };
        R::select(use_map, f, R::ONE)
    }
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
        let k = |x: f32| R::splat(x as f64);
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
