//! Occlusion culling for the geometry passes after a frame's first: a
//! triangle whose every pixel would fail the depth test against what the
//! earlier passes drew is skipped before setup, so it costs neither setup
//! nor scan. The result is the same visibility buffer, bit for bit: only
//! triangles that cannot write a pixel are skipped.
//!
//! What the earlier passes drew is summed up as the least depth of each
//! 4×4 block of pixels ([`DepthBounds`], taken tile by tile in the first
//! pass's raster sweep and assembled before the second pass).
//! Depth only grows within a frame (the test is z > depth, reversed depth,
//! and a pass writes z only where it passes), so the bounds stay lower
//! bounds for every later pass and need no rebuilding. A triangle is
//! hidden if an upper bound of its depth over its pixels is ≤ the least
//! depth of every block holding a pixel it can cover ([`hides`]: the
//! pixel range of its projected vertices' box, exact up to the snapping).
//!
//! The extrusion outline is what this is for: its back faces lie behind
//! the front faces of their own mesh except within a few pixels of the
//! silhouette, so most of them are hidden and go no further: 73k of the
//! 97k on the benchmark scene (67k when the range was the box grown a
//! pixel each way, 62k that way with 8×8 blocks; the rest lie within a
//! few pixels of a silhouette, where the ring is, and must be drawn).

use crate::target::{Target, TILE, TILE_PIXELS};
use rayon::prelude::*;
use wide::f64x4;

/// Block edge in pixels; a divisor of `TILE`. 4 skips more of the
/// benchmark's back faces than 8, for less work a frame.
pub(crate) const BLOCK: usize = 4;
const PER_TILE: usize = TILE / BLOCK;

/// How far (pixels) a covered pixel's centre may lie outside the box of
/// the projected vertices: the snapping's 1/512, and room for the
/// rounding of a clipped piece's vertices (far below it).
pub(crate) const PIXEL_MARGIN: f64 = 1.0 / 64.0;
/// Covered pixel x satisfies min − `LO_OFFSET` ≤ x ≤ max − `HI_OFFSET`
/// (x + ½ within the box grown by `PIXEL_MARGIN`).
pub(crate) const LO_OFFSET: f64 = 0.5 + PIXEL_MARGIN;
pub(crate) const HI_OFFSET: f64 = 0.5 - PIXEL_MARGIN;

/// Least depth per `BLOCK`² block of a visibility buffer's depth, row-major
/// over the tile grid's padded extent (`tiles_x · 8` blocks a row), and 3
/// more entries past the last row.
#[derive(Clone, Debug, Default)]
pub struct DepthBounds {
    min: Vec<f32>,
    row: usize,
    /// The image's size (read by `hides_x4` in setup_x4.rs too).
    pub(crate) width: u32,
    pub(crate) height: u32,
}

impl DepthBounds {
    /// The bounds of `depth`, a tile-major buffer of `target`, into `self`
    /// (reusing its allocation), in the calling rayon pool. Padding pixels
    /// past the image's edges hold the cleared depth 0, which only makes
    /// the bounds of edge blocks lower (more conservative).
    pub fn build(&mut self, target: &Target, depth: &[f32]) {
        let tiles: Vec<TileMinima> = depth.par_chunks(TILE_PIXELS).map(tile_minima).collect();
        self.build_from_tiles(target, &tiles);
    }

    /// [`DepthBounds::build`] from each tile's [`tile_minima`] (tile
    /// order), which a pass can take while the tile is in cache.
    pub(crate) fn build_from_tiles(&mut self, target: &Target, tiles: &[TileMinima]) {
        let row = self.shape(target);
        let tiles_x = target.tiles_x as usize;
        let blocks = row * target.tiles_y as usize * PER_TILE;
        self.min[..blocks]
            .par_chunks_mut(row * PER_TILE)
            .zip(tiles.par_chunks(tiles_x))
            .for_each(|(out, tiles)| {
                for (tx, m) in tiles.iter().enumerate() {
                    for by in 0..PER_TILE {
                        out[by * row + tx * PER_TILE..][..PER_TILE]
                            .copy_from_slice(&m[by * PER_TILE..][..PER_TILE]);
                    }
                }
            });
    }

    /// Sizes `self` for `target`; returns the blocks a row.
    fn shape(&mut self, target: &Target) -> usize {
        let row = target.tiles_x as usize * PER_TILE;
        self.row = row;
        self.width = target.width;
        self.height = target.height;
        let blocks = row * target.tiles_y as usize * PER_TILE;
        // 3 more: `behind_block_range` reads 4 bounds from any block.
        self.min.resize(blocks + 3, 0.0);
        row
    }

    /// Whether the triangle with clip-space vertices `v` writes no pixel against depth these bounds
    /// bound from below; `false` whenever that is not shown.
    ///
    /// With every w > 0 the triangle's screen projection is the triangle
    /// of its projected vertices (any clipped piece lies inside it) and
    /// its depth z/w is the affine function through the vertices' z/w
    /// (setup's plane, `TriPlanes::z`). The projection here is setup's
    /// (the same operations: x·(1/w), + 1, then × w/2, where setup's × 0.5
    /// then × w rounds the same), and the pixels the rasterizer covers are
    /// centres inside the snapped triangle, whose vertices are within
    /// 1/512 px of those each way (a clipped piece's, up to rounding far
    /// below that). So a covered pixel x has its centre x + ½ within
    /// [min − `PIXEL_MARGIN`, max + `PIXEL_MARGIN`] of the projected
    /// vertices, i.e. x in [⌈min − ½ − m⌉, ⌊max − ½ + m⌋], and likewise y:
    /// the blocks of that pixel range are the ones tested. The plane there
    /// is at most max z_i + (|∂z/∂x| + |∂z/∂y|)/512 (taken as /256). Setup
    /// keeps the plane in f32 and evaluates it with two fused multiply-adds
    /// relative to a corner of the triangle's box: a few ulps of |z| +
    /// |∂z/∂x|·Δx + |∂z/∂y|·Δy, far below the 1e-6 relative margin added
    /// (over the vertices' box grown a pixel each way).
    pub fn hides(&self, v: &[[f64; 4]; 3]) -> bool {
        let [a, b, c] = v;
        if !(a[3] > 0.0 && b[3] > 0.0 && c[3] > 0.0) {
            return false;
        }
        let (w, h) = (self.width as f64, self.height as f64);
        // Setup's projection (up to rounding, which the pixel of margin
        // around the rectangle covers).
        let (hw, hh) = (0.5 * w, 0.5 * h);
        let project = |p: &[f64; 4]| {
            let inv_w = 1.0 / p[3];
            (
                (p[0] * inv_w + 1.0) * hw,
                (1.0 - p[1] * inv_w) * hh,
                p[2] * inv_w,
            )
        };
        let (x0, y0, z0) = project(a);
        let (x1, y1, z1) = project(b);
        let (x2, y2, z2) = project(c);
        let (ux, uy, uz) = (x1 - x0, y1 - y0, z1 - z0);
        let (vx, vy, vz) = (x2 - x0, y2 - y0, z2 - z0);
        // The plane's screen gradient; NaN or infinite coordinates and
        // collinear vertices (d = 0) make it non-finite or NaN, and so z
        // below: not judged.
        let inv_d = 1.0 / (ux * vy - vx * uy);
        let gx = (uz * vy - vz * uy) * inv_d;
        let gy = (ux * vz - vx * uz) * inv_d;
        let min3 = |a: f64, b: f64, c: f64| {
            let m = if b < a { b } else { a };
            if c < m {
                c
            } else {
                m
            }
        };
        let max3 = |a: f64, b: f64, c: f64| -min3(-a, -b, -c);
        let (x_min, x_max) = (min3(x0, x1, x2), max3(x0, x1, x2));
        let (y_min, y_max) = (min3(y0, y1, y2), max3(y0, y1, y2));
        // The covered pixels' range, before ⌈ ⌉ and ⌊ ⌋ (see above).
        let (x_lo, x_hi) = (x_min - LO_OFFSET, x_max - HI_OFFSET);
        let (y_lo, y_hi) = (y_min - LO_OFFSET, y_max - HI_OFFSET);
        // Off the image (setup's business), or NaN: not judged.
        if !(x_hi >= 0.0 && y_hi >= 0.0 && x_lo <= w - 1.0 && y_lo <= h - 1.0) {
            return false;
        }
        let z_hi = max3(z0, z1, z2);
        let (ax, ay) = (gx.abs(), gy.abs());
        let z = z_hi
            + (ax + ay) * (1.0 / 256.0)
            + 1e-6 * (z_hi.abs() + ax * (x_max - x_min + 2.0) + ay * (y_max - y_min + 2.0));
        if !z.is_finite() {
            return false;
        }
        self.behind_blocks([x_lo, x_hi, y_lo, y_hi], z)
    }

    /// The end of [`DepthBounds::hides`]: whether depth bound `z` (finite)
    /// is at most the least depth of every block holding a pixel of
    /// columns ⌈x_lo⌉..=⌊x_hi⌋ and rows ⌈y_lo⌉..=⌊y_hi⌋ (a range that
    /// meets the image: x_hi, y_hi ≥ 0, x_lo ≤ w − 1, y_lo ≤ h − 1).
    #[inline(always)]
    fn behind_blocks(&self, [x_lo, x_hi, y_lo, y_hi]: [f64; 4], z: f64) -> bool {
        let (w, h) = (self.width as f64, self.height as f64);
        // Inside the image: the casts truncate non-negative integers.
        let bx0 = x_lo.ceil().max(0.0) as usize / BLOCK;
        let bx1 = x_hi.floor().min(w - 1.0) as usize / BLOCK;
        let by0 = y_lo.ceil().max(0.0) as usize / BLOCK;
        let by1 = y_hi.floor().min(h - 1.0) as usize / BLOCK;
        self.behind_block_range([bx0, bx1, by0, by1], z)
    }

    /// Whether `z` (finite) is at most the least depth of every block of
    /// columns `bx0..=bx1` and rows `by0..=by1` (`false` if the range is
    /// empty, which happens only past the right or bottom edge).
    ///
    /// The bounds are f32 and `z` f64; for f32 m, m < z exactly when
    /// m < z↑, z rounded up to f32 (z ≤ z↑, and an f32 m ≥ z is ≥ the
    /// least f32 ≥ z), so comparing in f64 is comparing with z↑: a bound
    /// exactly at a block's depth still compares right. Blocks are read 4
    /// at a time (the vector past the row's end reads the next row or the
    /// padding, masked off).
    #[inline(always)]
    pub(crate) fn behind_block_range(&self, [bx0, bx1, by0, by1]: [usize; 4], z: f64) -> bool {
        if bx0 > bx1 || by0 > by1 {
            return false;
        }
        let zs = f64x4::splat(z);
        let span = bx1 - bx0 + 1;
        if span <= 4 {
            // The common case (a rectangle at most 13 pixels wide): one
            // vector a row, one mask for all rows.
            let keep = (1 << span) - 1;
            let mut at = by0 * self.row + bx0;
            for _ in by0..=by1 {
                if widen(&self.min[at..at + 4]).simd_lt(zs).to_bitmask() & keep != 0 {
                    return false;
                }
                at += self.row;
            }
            return true;
        }
        for by in by0..=by1 {
            let mut bx = bx0;
            while bx <= bx1 {
                let at = by * self.row + bx;
                let m = widen(&self.min[at..at + 4]);
                let n = (bx1 + 1 - bx).min(4);
                if m.simd_lt(zs).to_bitmask() & ((1 << n) - 1) != 0 {
                    return false;
                }
                bx += 4;
            }
        }
        true
    }
}

/// The least depth of each `BLOCK`² block of one tile, row-major.
pub(crate) type TileMinima = [f32; PER_TILE * PER_TILE];

/// [`TileMinima`] of a tile's depth (`TILE_PIXELS` entries, row-major).
pub(crate) fn tile_minima(tile: &[f32]) -> TileMinima {
    let mut out = [0.0; PER_TILE * PER_TILE];
    for by in 0..PER_TILE {
        let mut acc = [f32::INFINITY; TILE];
        for r in 0..BLOCK {
            let at = (by * BLOCK + r) * TILE;
            for (a, &d) in acc.iter_mut().zip(&tile[at..at + TILE]) {
                // Not f32::min: this form vectorizes.
                *a = if d < *a { d } else { *a };
            }
        }
        for bx in 0..PER_TILE {
            out[by * PER_TILE + bx] = acc[bx * BLOCK..(bx + 1) * BLOCK]
                .iter()
                .fold(f32::INFINITY, |m, &d| if d < m { d } else { m });
        }
    }
    out
}

/// Block index of a pixel coordinate in [0, 2³¹): truncated, over `BLOCK`.
#[inline(always)]
pub(crate) fn block_index(x: f64x4) -> [usize; 4] {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    let n: [i32; 4] = {
        use core::arch::x86_64::_mm256_cvttpd_epi32;
        // SAFETY: AVX is enabled (cfg). Truncating, as `as`.
        bytemuck::cast(unsafe { _mm256_cvttpd_epi32(bytemuck::cast(x)) })
    };
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
    let n: [i32; 4] = x.to_array().map(|c| c as i32);
    n.map(|c| c as usize / BLOCK)
}

/// 4 f32 (the first 4 of `m`) widened to f64, exactly.
#[inline(always)]
fn widen(m: &[f32]) -> f64x4 {
    let m: &[f32; 4] = m.try_into().expect("4 bounds");
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    {
        use core::arch::x86_64::{_mm256_cvtps_pd, _mm_loadu_ps};
        // SAFETY: AVX is enabled (cfg); `m` is 16 readable bytes.
        bytemuck::cast(unsafe { _mm256_cvtps_pd(_mm_loadu_ps(m.as_ptr())) })
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
    f64x4::new(m.map(f64::from))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setup_x4::{Vertices4, LANES};

    /// A 130×70 target whose depth is 0.5 everywhere but one pixel.
    fn bounds_with_hole(hole: (u32, u32), hole_depth: f32) -> DepthBounds {
        let t = Target::new(130, 70).unwrap();
        let mut depth = vec![0.0; t.buffer_len()];
        for y in 0..t.height {
            for x in 0..t.width {
                depth[t.index(x, y)] = 0.5;
            }
        }
        depth[t.index(hole.0, hole.1)] = hole_depth;
        let mut b = DepthBounds::default();
        b.build(&t, &depth);
        b
    }

    /// Clip-space vertices of a screen triangle at pixel positions with
    /// NDC depth z (w = 2, so the projection divides).
    fn tri(px: [[f64; 2]; 3], z: f64) -> [[f64; 4]; 3] {
        let (w, h) = (130.0, 70.0);
        px.map(|[x, y]| {
            let nx = 2.0 * x / w - 1.0;
            let ny = 1.0 - 2.0 * y / h;
            [nx * 2.0, ny * 2.0, z * 2.0, 2.0]
        })
    }

    #[test]
    fn block_minima_are_the_least_depth_of_each_block() {
        let t = Target::new(130, 70).unwrap();
        let mut depth = vec![0.0; t.buffer_len()];
        for y in 0..t.height {
            for x in 0..t.width {
                depth[t.index(x, y)] = 1.0 + (x * 7 + y * 13) as f32;
            }
        }
        let mut b = DepthBounds::default();
        b.build(&t, &depth);
        for by in 0..70 / BLOCK {
            for bx in 0..130 / BLOCK {
                let want = (0..BLOCK)
                    .flat_map(|r| (0..BLOCK).map(move |c| (bx * BLOCK + c, by * BLOCK + r)))
                    .map(|(x, y)| depth[t.index(x as u32, y as u32)])
                    .fold(f32::INFINITY, f32::min);
                assert_eq!(b.min[by * b.row + bx], want, "block {bx},{by}");
            }
        }
        // The partial blocks past the right edge see the padding's 0.
        assert_eq!(b.min[130 / BLOCK], 0.0);
    }

    /// `hides_x4` answers `hides` lane by lane, for lanes asked about, on
    /// random triangles (hidden, in front, straddling the hole, off the
    /// image) and on the inputs `hides` declines: a vertex at or behind
    /// the eye, NaN and infinite coordinates, collinear vertices.
    #[test]
    fn four_lanes_answer_as_one() {
        use rand::{Rng, SeedableRng};
        let b = bounds_with_hole((100, 60), 0.1);
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let special = [f32::NAN, f32::INFINITY, -f32::INFINITY, 0.0, -0.0, 1e30];
        let (mut yes, mut no) = (0, 0);
        for n in 0..20_000 {
            let v: [[[f32; 4]; 3]; LANES] = std::array::from_fn(|_| {
                let (cx, cy) = (
                    rng.random_range(-20.0..150.0),
                    rng.random_range(-20.0..90.0),
                );
                let size: f64 = [0.5f64, 5.0, 30.0][rng.random_range(0..3)];
                let z: f64 = [0.4, 0.5, 0.6][rng.random_range(0..3)];
                let mut p = tri(
                    std::array::from_fn(|_| {
                        [
                            cx + rng.random_range(-size..size),
                            cy + rng.random_range(-size..size),
                        ]
                    }),
                    z,
                )
                .map(|c| c.map(|x| x as f32));
                if n % 5 == 0 {
                    let (j, c) = (rng.random_range(0..3), rng.random_range(0..4));
                    p[j][c] = special[rng.random_range(0..special.len())];
                }
                if n % 11 == 0 {
                    p[2] = p[1]; // collinear
                }
                p
            });
            let lanes = rng.random_range(0..16u32);
            let v4 = Vertices4::from_arrays(&v);
            let inv_w = v4.w.map(|w| f64x4::ONE / w);
            let got = b.hides_x4(&v4, &inv_w, lanes);
            for (t, tri) in v.iter().enumerate() {
                let want = lanes >> t & 1 != 0 && b.hides(&tri.map(|p| p.map(|c| c as f64)));
                assert_eq!(
                    got >> t & 1 != 0,
                    want,
                    "lane {t} of {v:?}, lanes {lanes:b}"
                );
                if lanes >> t & 1 != 0 {
                    if want {
                        yes += 1;
                    } else {
                        no += 1;
                    }
                }
            }
        }
        assert!(yes > 2_000 && no > 2_000, "{yes} hidden, {no} not");
    }

    /// The block test compares f32 bounds with an f64 depth directly; the
    /// reference rounds the depth up to f32 (`next_up` when the nearest
    /// f32 is below it) and compares in f32, block by block. Depths at,
    /// just above and just below the bounds, and ranges of every width
    /// (the vector reads 4 blocks at a time), up to the last block.
    #[test]
    fn block_range_test_is_the_rounded_up_f32_comparison() {
        use rand::{Rng, SeedableRng};
        let t = Target::new(130, 70).unwrap();
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let mut depth = vec![0.0f32; t.buffer_len()];
        for d in depth.iter_mut() {
            *d = [0.25f32, 0.5, 0.5f32.next_up(), 0.75][rng.random_range(0..4)];
        }
        let mut b = DepthBounds::default();
        b.build(&t, &depth);
        let (cols, rows) = (b.row, b.min.len() / b.row);
        let (mut yes, mut no) = (0, 0);
        for _ in 0..20_000 {
            let (bx0, by0) = (rng.random_range(0..cols), rng.random_range(0..rows));
            let bx1 = (bx0 + rng.random_range(0..11)).min(cols - 1);
            let by1 = (by0 + rng.random_range(0..3)).min(rows - 1);
            let base = [0.25f32, 0.5, 0.75][rng.random_range(0..3)] as f64;
            let z = match rng.random_range(0..4) {
                0 => base,
                1 => base * (1.0 + 1e-12),
                2 => base * (1.0 - 1e-12),
                _ => f64::from((base as f32).next_up()),
            };
            let z32 = {
                let r = z as f32;
                if (r as f64) < z {
                    r.next_up()
                } else {
                    r
                }
            };
            let want = !(by0..=by1).any(|by| (bx0..=bx1).any(|bx| b.min[by * b.row + bx] < z32));
            assert_eq!(
                b.behind_block_range([bx0, bx1, by0, by1], z),
                want,
                "blocks {bx0}..={bx1} × {by0}..={by1}, z {z}"
            );
            if want {
                yes += 1;
            } else {
                no += 1;
            }
        }
        assert!(yes > 1_000 && no > 1_000, "{yes} behind, {no} not");
        assert!(!b.behind_block_range([3, 2, 0, 0], 0.0), "empty range");
    }

    /// Whatever `hides` drops writes no pixel: no pixel centre within
    /// 1/128 px of the triangle (each edge moved out that far) has a depth
    /// below the triangle's largest vertex depth, checked pixel by pixel
    /// on random small triangles around holes of random depth.
    #[test]
    fn a_hidden_triangle_has_no_pixel_in_front_of_the_depth() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(9);
        let t = Target::new(130, 70).unwrap();
        let mut depth = vec![0.5f32; t.buffer_len()];
        for _ in 0..40 {
            let (x, y) = (rng.random_range(0..130), rng.random_range(0..70));
            depth[t.index(x, y)] = rng.random_range(0.0..0.5);
        }
        let mut b = DepthBounds::default();
        b.build(&t, &depth);
        let mut hidden = 0;
        for _ in 0..20_000 {
            let (cx, cy) = (rng.random_range(0.0..130.0), rng.random_range(0.0..70.0));
            let size = [1.5f64, 4.0, 12.0][rng.random_range(0..3)];
            let px: [[f64; 2]; 3] = std::array::from_fn(|_| {
                [
                    cx + rng.random_range(-size..size),
                    cy + rng.random_range(-size..size),
                ]
            });
            let z = rng.random_range(0.3..0.5);
            if !b.hides(&tri(px, z)) {
                continue;
            }
            hidden += 1;
            let [a, bb, c] = px;
            let d = (bb[0] - a[0]) * (c[1] - a[1]) - (bb[1] - a[1]) * (c[0] - a[0]);
            let inside = |x: f64, y: f64| {
                [(a, bb), (bb, c), (c, a)].iter().all(|&(p, q)| {
                    let cross = (q[0] - p[0]) * (y - p[1]) - (q[1] - p[1]) * (x - p[0]);
                    let len = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
                    cross * d.signum() >= -len / 128.0
                })
            };
            for y in 0..70u32 {
                for x in 0..130u32 {
                    let below = (depth[t.index(x, y)] as f64) < z;
                    if below && inside(x as f64 + 0.5, y as f64 + 0.5) {
                        panic!("{px:?} at {z} hides pixel {x},{y}");
                    }
                }
            }
        }
        assert!(hidden > 2_000, "{hidden} hidden");
    }

    #[test]
    fn hides_only_triangles_behind_every_pixel_they_touch() {
        let b = bounds_with_hole((100, 60), 0.1);
        let small = [[20.0, 20.0], [30.0, 20.0], [20.0, 30.0]];
        assert!(b.hides(&tri(small, 0.4)));
        // In front somewhere, or level with the depth: may write.
        assert!(!b.hides(&tri(small, 0.6)));
        assert!(!b.hides(&tri(small, 0.5)));
        // Over the hole (a lower depth there): may write.
        let over = [[95.0, 55.0], [105.0, 55.0], [95.0, 65.0]];
        assert!(!b.hides(&tri(over, 0.4)));
        // The hole's block holds pixels 100..=103 × 60..=63. A box
        // reaching past the centre of pixel (100, 60) by less than
        // `PIXEL_MARGIN` may cover it (snapping): it counts. One ending
        // 0.05 px before that centre covers no pixel of the block: hidden.
        let reach = 100.5 - PIXEL_MARGIN / 2.0;
        let near = [
            [89.0, 50.0],
            [reach, 50.0],
            [89.0, 60.5 - PIXEL_MARGIN / 2.0],
        ];
        assert!(!b.hides(&tri(near, 0.4)));
        let short = [[89.0, 50.0], [100.45, 50.0], [89.0, 60.45]];
        assert!(b.hides(&tri(short, 0.4)));
        // A vertex behind the eye: not judged.
        let mut v = tri(small, 0.4);
        v[0][3] = -1.0;
        assert!(!b.hides(&v));
        // Degenerate (collinear): not judged.
        assert!(!b.hides(&tri([[20.0, 20.0], [30.0, 20.0], [40.0, 20.0]], 0.4)));
    }
}
