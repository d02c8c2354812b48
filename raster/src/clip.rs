//! Clipping in homogeneous clip space (f64).
//!
//! Always against the near plane (z ≤ w: reversed depth puts the near plane
//! at NDC depth 1, see `camera.rs`), which also keeps w > 0 for every vertex
//! that reaches projection. Against x/y only at the
//! guard band |x|, |y| ≤ K·w, far outside the image, so that ordinary
//! triangles never pay for it and snapped coordinates fit the fixed-point
//! range (see `fixed.rs`). The far plane needs no clipping: the depth buffer
//! is cleared to 0 (the far plane) and the test is z > depth.
//!
//! Watertightness: a clipped edge's new vertex is always computed from its
//! inside end toward its outside end, so two triangles that share the edge
//! (and walk it in opposite directions) create bit-identical vertices.

/// A clip-space vertex (x, y, z, w).
pub(crate) type ClipVertex = [f64; 4];

/// Most vertices a triangle can have after 5 planes (each adds at most one).
pub(crate) const MAX_CLIPPED: usize = 8;

/// A convex polygon of at most `MAX_CLIPPED` vertices.
#[derive(Clone, Copy)]
pub(crate) struct Polygon {
    pub(crate) v: [ClipVertex; MAX_CLIPPED],
    pub(crate) len: usize,
}

/// Guard band half-widths in NDC units: |x/w| ≤ kx, |y/w| ≤ ky.
#[derive(Clone, Copy, Debug)]
pub struct GuardBand {
    pub(crate) kx: f64,
    pub(crate) ky: f64,
}

impl GuardBand {
    /// NDC extent whose pixels stay within ±GUARD_BAND_PX of the image origin.
    pub fn for_image(width: u32, height: u32) -> GuardBand {
        let g = crate::fixed::GUARD_BAND_PX;
        GuardBand {
            kx: 2.0 * g / width as f64 - 1.0,
            ky: 2.0 * g / height as f64 - 1.0,
        }
    }

    /// Signed distances to the five planes (≥ 0 inside).
    fn distances(&self, v: &ClipVertex) -> [f64; 5] {
        let [x, y, z, w] = *v;
        [
            w - z,
            self.kx * w - x,
            self.kx * w + x,
            self.ky * w - y,
            self.ky * w + y,
        ]
    }

    /// True if any vertex is outside any plane, i.e. clipping is needed.
    pub fn needs_clip(&self, tri: &[ClipVertex; 3]) -> bool {
        tri.iter()
            .any(|v| self.distances(v).iter().any(|&d| d < 0.0))
    }

    /// Sutherland–Hodgman against the planes some vertex violates. The
    /// result may be empty (fewer than 3 vertices).
    pub(crate) fn clip(&self, tri: &[ClipVertex; 3]) -> Polygon {
        let mut poly = Polygon {
            v: [[0.0; 4]; MAX_CLIPPED],
            len: 3,
        };
        poly.v[..3].copy_from_slice(tri);
        for plane in 0..5 {
            if poly.len < 3 {
                break;
            }
            let mut d = [0.0; MAX_CLIPPED];
            for (d, v) in d.iter_mut().zip(&poly.v[..poly.len]) {
                *d = self.distances(v)[plane];
            }
            if d[..poly.len].iter().all(|&x| x >= 0.0) {
                continue;
            }
            let mut out = Polygon {
                v: [[0.0; 4]; MAX_CLIPPED],
                len: 0,
            };
            for i in 0..poly.len {
                let j = (i + 1) % poly.len;
                let (a, b) = (poly.v[i], poly.v[j]);
                let (da, db) = (d[i], d[j]);
                if da >= 0.0 {
                    out.push(a);
                }
                if (da >= 0.0) != (db >= 0.0) {
                    let (inside, outside, di, dout) = if da >= 0.0 {
                        (a, b, da, db)
                    } else {
                        (b, a, db, da)
                    };
                    let t = di / (di - dout);
                    out.push(std::array::from_fn(|k| {
                        inside[k] + t * (outside[k] - inside[k])
                    }));
                }
            }
            poly = out;
        }
        poly
    }
}

impl Polygon {
    fn push(&mut self, v: ClipVertex) {
        // A convex polygon gains at most one vertex per plane: 3 + 5 = 8.
        debug_assert!(self.len < MAX_CLIPPED);
        if self.len < MAX_CLIPPED {
            self.v[self.len] = v;
            self.len += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_plane_cuts_a_triangle_into_a_quad() {
        let gb = GuardBand::for_image(100, 100);
        // One vertex in front of the near plane (z > w), two beyond it.
        let tri = [
            [0.0, 0.0, 1.0, 0.5],
            [1.0, 0.0, 1.0, 2.0],
            [0.0, 1.0, 1.0, 2.0],
        ];
        assert!(gb.needs_clip(&tri));
        let p = gb.clip(&tri);
        assert_eq!(p.len, 4);
        for v in &p.v[..p.len] {
            assert!(v[2] <= v[3] + 1e-12, "vertex before the near plane: {v:?}");
            assert!(v[3] > 0.0);
        }
    }

    #[test]
    fn shared_edge_gives_identical_clip_vertices() {
        let gb = GuardBand::for_image(100, 100);
        let a = [0.3, -0.2, 1.1, 0.4];
        let b = [0.1, 0.9, 1.0, 3.0];
        let t1 = gb.clip(&[a, b, [1.0, 1.0, 1.0, 2.0]]);
        let t2 = gb.clip(&[b, a, [-1.0, 1.0, 1.0, 2.0]]);
        let on_ab = |p: &Polygon| {
            p.v[..p.len]
                .iter()
                .copied()
                .filter(|v| (v[3] - v[2]).abs() < 1e-12)
                .map(|v| v.map(f64::to_bits))
                .collect::<Vec<_>>()
        };
        let (s1, s2) = (on_ab(&t1), on_ab(&t2));
        assert!(s1.iter().any(|v| s2.contains(v)), "{s1:?} vs {s2:?}");
    }
}
