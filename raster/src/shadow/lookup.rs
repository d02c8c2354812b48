//! The scalar lookups: the face a shaded point falls on (cube face or
//! cascade), the biased depth it is compared at, and the filters: hard
//! (nearest texel), PCF (bilinear comparisons over a square) and PCSS
//! (a blocker search, then PCF over the penumbra's width).

use super::settings::{ShadowFilter, PCSS_MAX_RADIUS};
use super::{Face, LightShadow, Pick};
use glam::Vec3;

impl Face {
    /// Linear depth of `p`.
    pub(super) fn depth_of(&self, p: Vec3) -> f32 {
        (p - self.origin).dot(self.axis)
    }

    /// The map's depth at integer texel (x, y), clamped to the map.
    fn at(&self, x: i32, y: i32) -> f32 {
        let n = self.size as i32;
        self.depth[(y.clamp(0, n - 1) * n + x.clamp(0, n - 1)) as usize]
    }

    /// Bilinear mean of the comparisons `d <= depth` at continuous texel
    /// coordinates (u, v) (texel centres at integers).
    fn compare_bilinear(&self, u: f32, v: f32, d: f32) -> f32 {
        let (x0, y0) = (u.floor(), v.floor());
        let (fx, fy) = (u - x0, v - y0);
        let (x0, y0) = (x0 as i32, y0 as i32);
        let lit = |x, y| (d <= self.at(x, y)) as u32 as f32;
        let top = lit(x0, y0) * (1.0 - fx) + lit(x0 + 1, y0) * fx;
        let bottom = lit(x0, y0 + 1) * (1.0 - fx) + lit(x0 + 1, y0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// Mean of bilinear comparisons over a 3 × 3 grid of half-width
    /// `radius` texels around (u, v).
    fn pcf(&self, u: f32, v: f32, d: f32, radius: f32) -> f32 {
        if radius <= 0.0 {
            return self.compare_bilinear(u, v, d);
        }
        let mut sum = 0.0;
        for j in -1..=1 {
            for i in -1..=1 {
                sum += self.compare_bilinear(u + i as f32 * radius, v + j as f32 * radius, d);
            }
        }
        sum / 9.0
    }

    /// Mean of bilinear comparisons over the taps of a 7 × 7 grid that
    /// lie in a disk of radius `radius` texels around (u, v): the shape of
    /// a round light's footprint, for PCSS.
    fn pcf_disk(&self, u: f32, v: f32, d: f32, radius: f32) -> f32 {
        let step = radius / 3.0;
        let (mut sum, mut n) = (0.0, 0u32);
        for j in -3i32..=3 {
            for i in -3i32..=3 {
                if i * i + j * j <= 9 {
                    sum += self.compare_bilinear(u + i as f32 * step, v + j as f32 * step, d);
                    n += 1;
                }
            }
        }
        sum / n as f32
    }

    /// The mean depth of the texels nearer than `d` in a square of
    /// half-width `radius` texels around (u, v), if any.
    fn blockers(&self, u: f32, v: f32, d: f32, radius: f32) -> Option<f32> {
        let step = radius / 3.0;
        let (mut sum, mut count) = (0.0, 0u32);
        for j in -3..=3 {
            for i in -3..=3 {
                let z = self.at(
                    (u + i as f32 * step).round() as i32,
                    (v + j as f32 * step).round() as i32,
                );
                if z < d {
                    sum += z;
                    count += 1;
                }
            }
        }
        (count > 0).then(|| sum / count as f32)
    }
}

impl LightShadow {
    /// The index of the face that sees `p`.
    pub(super) fn face_index(&self, p: Vec3) -> usize {
        match &self.pick {
            Pick::One => 0,
            Pick::Cube(c) => {
                let d = p - *c;
                let a = d.abs();
                if a.x >= a.y && a.x >= a.z {
                    (d.x < 0.0) as usize
                } else if a.y >= a.z {
                    2 + (d.y < 0.0) as usize
                } else {
                    4 + (d.z < 0.0) as usize
                }
            }
            Pick::Cascades {
                eye,
                forward,
                splits,
            } => {
                let depth = (p - *eye).dot(*forward);
                splits.iter().filter(|s| **s <= depth).count()
            }
        }
    }

    /// The face that sees `p`.
    fn face_for(&self, p: Vec3) -> &Face {
        &self.faces[self.face_index(p)]
    }

    /// The fraction of the light reaching world point `p` with unit
    /// normal `n`: 0 in shadow, 1 lit (between: filtered).
    pub fn visibility(&self, p: Vec3, n: Vec3) -> f32 {
        if !(p.is_finite() && n.is_finite()) {
            return 1.0;
        }
        let face = self.face_for(p);
        let s = &self.settings;
        let scale = if face.perspective {
            face.depth_of(p).max(face.near)
        } else {
            1.0
        };
        let texel = face.texel * scale;
        let radius = match s.filter {
            ShadowFilter::Hard => 0.0,
            _ => s.filter_radius,
        };
        let p = p + n * (s.normal_bias * texel * (1.0 + radius));
        let c = face.clip * p.extend(1.0);
        if c.w <= 0.0 {
            return 1.0;
        }
        let (x, y) = (c.x / c.w, c.y / c.w);
        if !(x.abs() <= 1.0 && y.abs() <= 1.0) {
            return 1.0;
        }
        let size = face.size as f32;
        let u = (x + 1.0) * 0.5 * size - 0.5;
        let v = (1.0 - y) * 0.5 * size - 0.5;
        let d = face.depth_of(p) - s.bias * texel;
        match s.filter {
            ShadowFilter::Hard => (d <= face.at(u.round() as i32, v.round() as i32)) as u32 as f32,
            ShadowFilter::Pcf => face.pcf(u, v, d, s.filter_radius),
            ShadowFilter::Pcss => self.pcss(face, u, v, d, texel),
        }
    }

    /// Blocker search over the light's footprint, penumbra width
    /// w = (d_receiver − d_blocker) · size / d_blocker (perspective; the
    /// size itself for directional lights, as an angle), then PCF over w.
    fn pcss(&self, face: &Face, u: f32, v: f32, d: f32, texel: f32) -> f32 {
        let s = &self.settings;
        let size = s.light_size;
        // Search half-width: the cone from the receiver to the light, at
        // blockers half way to the light (perspective) or anywhere up to
        // the map's near side (directional), in texels at the receiver.
        let search = if face.perspective {
            0.5 * size / texel
        } else {
            0.5 * size * (d - face.near).max(0.0) / texel
        };
        let search = search.clamp(1.0, PCSS_MAX_RADIUS);
        let Some(blocker) = face.blockers(u, v, d, search) else {
            return 1.0;
        };
        let width = if face.perspective {
            (d - blocker) * size / blocker.max(1e-12)
        } else {
            (d - blocker) * size
        };
        // Half the penumbra in texels at the receiver.
        let radius = (0.5 * width / texel).clamp(0.0, PCSS_MAX_RADIUS);
        face.pcf_disk(u, v, d, radius.max(s.filter_radius.min(1.0)))
    }
}
