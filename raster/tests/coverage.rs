//! Watertightness and fill rule: every pixel centre inside a mesh's
//! silhouette is covered exactly once, none twice, none outside; shared
//! edges through pixel centres go to exactly one side.

use glam::{Mat3, Vec3};
use rand::{Rng, SeedableRng};
use specula_raster::clip::GuardBand;
use specula_raster::fuzzing::covered_groups;
use specula_raster::fuzzing::{pixel_centre, SUBPIXEL_ONE};
use specula_raster::setup::{RasterTri, SetupContext, SetupCounts};
use specula_raster::Cull;

const W: u32 = 96;
const H: u32 = 80;

fn ctx() -> SetupContext {
    SetupContext {
        width: W,
        height: H,
        guard: GuardBand::for_image(W, H),
    }
}

/// Per-pixel write counts of a list of screen triangles, enumerated by the
/// scan pass's own coverage walk (`covered_groups`), each lane checked
/// against the direct edge-function test, and nothing covered left out.
fn write_counts(tris: &[RasterTri]) -> Vec<u32> {
    let mut c = vec![0u32; (W * H) as usize];
    let (mut small, mut large) = (0, 0);
    for t in tris {
        if t.small.is_some() {
            small += 1;
        } else {
            large += 1;
        }
        let [x0, y0, x1, y1] = t.bbox;
        let mut mine = vec![0u32; (W * H) as usize];
        covered_groups(t, [x0, x1, y0, y1], 0, |y, gx, mask| {
            for lane in 0..8 {
                if mask & (1 << lane) != 0 {
                    let x = gx + lane;
                    assert!(
                        t.covers(x, y),
                        "walk and direct edge test disagree at ({x}, {y})"
                    );
                    mine[(y as u32 * W + x as u32) as usize] += 1;
                }
            }
        });
        for y in y0..y1 {
            for x in x0..x1 {
                let i = (y as u32 * W + x as u32) as usize;
                assert_eq!(
                    mine[i],
                    t.covers(x, y) as u32,
                    "pixel ({x}, {y}) walked {} times",
                    mine[i]
                );
                c[i] += mine[i];
            }
        }
    }
    assert!(tris.is_empty() || small + large > 0);
    c
}

/// Clip-space vertex for a screen point (pixels) at depth z with w = 1.
fn clip_of(sx: f64, sy: f64, z: f32) -> [f32; 4] {
    [
        (2.0 * sx / W as f64 - 1.0) as f32,
        (1.0 - 2.0 * sy / H as f64) as f32,
        z,
        1.0,
    ]
}

/// Fixed-point screen position setup will snap a clip vertex to.
fn snapped(v: [f32; 4]) -> [i64; 2] {
    let (x, y, w) = (v[0] as f64, v[1] as f64, v[3] as f64);
    let sx = (x / w + 1.0) * 0.5 * W as f64;
    let sy = (1.0 - y / w) * 0.5 * H as f64;
    [
        specula_raster::fuzzing::snap(sx),
        specula_raster::fuzzing::snap(sy),
    ]
}

/// Signed distance (fixed units, scaled) of point p from the line a→b.
fn side(a: [i64; 2], b: [i64; 2], p: [i64; 2]) -> i128 {
    (b[0] - a[0]) as i128 * (p[1] - a[1]) as i128 - (b[1] - a[1]) as i128 * (p[0] - a[0]) as i128
}

/// Is pixel centre p strictly inside the convex polygon (any winding), at
/// least `margin` fixed units from every edge? Returns None when it is
/// within the margin of the boundary (ambiguous by the fill rule).
fn inside_convex(poly: &[[i64; 2]], p: [i64; 2], margin: f64) -> Option<bool> {
    let n = poly.len();
    let mut sign = 0i32;
    let mut near = false;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let s = side(a, b, p);
        let len = (((b[0] - a[0]) as f64).powi(2) + ((b[1] - a[1]) as f64).powi(2)).sqrt();
        if (s as f64).abs() / len.max(1.0) <= margin {
            near = true;
            continue;
        }
        let sg = if s > 0 { 1 } else { -1 };
        if sign == 0 {
            sign = sg;
        } else if sg != sign {
            return Some(false);
        }
    }
    if near {
        None
    } else {
        Some(true)
    }
}

/// Convex hull (monotone chain) of fixed-point points.
fn hull(mut pts: Vec<[i64; 2]>) -> Vec<[i64; 2]> {
    pts.sort();
    pts.dedup();
    let mut lower: Vec<[i64; 2]> = Vec::new();
    for &p in &pts {
        while lower.len() >= 2 && side(lower[lower.len() - 2], lower[lower.len() - 1], p) <= 0 {
            lower.pop();
        }
        lower.push(p);
    }
    let mut upper: Vec<[i64; 2]> = Vec::new();
    for &p in pts.iter().rev() {
        while upper.len() >= 2 && side(upper[upper.len() - 2], upper[upper.len() - 1], p) <= 0 {
            upper.pop();
        }
        upper.push(p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

#[test]
fn triangle_fans_are_watertight_at_random_offsets_and_rotations() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let ctx = ctx();
    for trial in 0..300 {
        let n = rng.random_range(3..24);
        let cx = 48.0 + rng.random_range(-0.5..0.5);
        let cy = 40.0 + rng.random_range(-0.5..0.5);
        let r = rng.random_range(5.0..38.0);
        let rot = rng.random_range(0.0..std::f64::consts::TAU);
        // A fan around the centre; front-facing (counter-clockwise in NDC,
        // i.e. clockwise on screen with y down).
        let rim: Vec<[f32; 4]> = (0..n)
            .map(|k| {
                let a = rot - std::f64::consts::TAU * k as f64 / n as f64;
                clip_of(cx + r * a.cos(), cy + r * a.sin(), 0.5)
            })
            .collect();
        let centre = clip_of(cx, cy, 0.5);
        let mut tris = Vec::new();
        let mut counts = SetupCounts::default();
        for k in 0..n {
            let v = [centre, rim[k], rim[(k + 1) % n]];
            ctx.setup(k as u32, v, Cull::Back, &mut tris, &mut counts);
        }
        assert_eq!(
            counts.culled_backface, 0,
            "trial {trial}: fan should be front-facing"
        );
        let c = write_counts(&tris);
        let poly: Vec<[i64; 2]> = rim.iter().map(|v| snapped(*v)).collect();
        for y in 0..H {
            for x in 0..W {
                let p = [pixel_centre(x as i64), pixel_centre(y as i64)];
                let got = c[(y * W + x) as usize];
                assert!(
                    got <= 1,
                    "trial {trial}: pixel ({x}, {y}) written {got} times"
                );
                match inside_convex(&poly, p, 0.5) {
                    Some(true) => assert_eq!(
                        got, 1,
                        "trial {trial}: pixel ({x}, {y}) inside the fan was missed"
                    ),
                    Some(false) => assert_eq!(
                        got, 0,
                        "trial {trial}: pixel ({x}, {y}) outside the fan was written"
                    ),
                    None => {}
                }
            }
        }
    }
}

#[test]
fn closed_convex_mesh_covers_its_silhouette_exactly_once() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let ctx = ctx();
    // An icosphere-like closed convex mesh: a UV sphere without degenerate
    // pole triangles.
    let (seg, rings) = (14u32, 9u32);
    let mut pos = Vec::new();
    for r in 0..=rings {
        let th = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..seg {
            let ph = std::f64::consts::TAU * s as f64 / seg as f64;
            pos.push(Vec3::new(
                (th.sin() * ph.cos()) as f32,
                th.cos() as f32,
                (th.sin() * ph.sin()) as f32,
            ));
        }
    }
    let at = |s: u32, r: u32| (r * seg + s % seg) as usize;
    let mut faces = Vec::new();
    for r in 0..rings {
        for s in 0..seg {
            let (a, b, c, d) = (at(s, r), at(s + 1, r), at(s + 1, r + 1), at(s, r + 1));
            if r != 0 {
                faces.push([a, b, c]);
            }
            if r != rings - 1 {
                faces.push([a, c, d]);
            }
        }
    }
    for trial in 0..100 {
        let rot = Mat3::from_euler(
            glam::EulerRot::XYZ,
            rng.random_range(0.0..6.3),
            rng.random_range(0.0..6.3),
            rng.random_range(0.0..6.3),
        );
        let (cx, cy) = (
            48.0 + rng.random_range(-1.0..1.0),
            40.0 + rng.random_range(-1.0..1.0),
        );
        let radius = rng.random_range(8.0..35.0);
        // Orthographic-style projection: screen = centre + radius·(x, −y),
        // depth from z; mesh seen from +z.
        let clip: Vec<[f32; 4]> = pos
            .iter()
            .map(|p| {
                let q = rot * *p;
                clip_of(
                    cx + radius * q.x as f64,
                    cy - radius * q.y as f64,
                    0.5 - 0.25 * q.z,
                )
            })
            .collect();
        for double_sided in [false, true] {
            let mut tris = Vec::new();
            let mut counts = SetupCounts::default();
            for (i, f) in faces.iter().enumerate() {
                ctx.setup(
                    i as u32,
                    f.map(|k| clip[k]),
                    if double_sided { Cull::None } else { Cull::Back },
                    &mut tris,
                    &mut counts,
                );
            }
            let c = write_counts(&tris);
            let h = hull(clip.iter().map(|v| snapped(*v)).collect());
            let layers = if double_sided { 2 } else { 1 };
            for y in 0..H {
                for x in 0..W {
                    let p = [pixel_centre(x as i64), pixel_centre(y as i64)];
                    let got = c[(y * W + x) as usize];
                    match inside_convex(&h, p, 1.0) {
                        Some(true) => assert_eq!(got, layers, "trial {trial} ds={double_sided}: ({x}, {y}) inside written {got} times"),
                        Some(false) => assert_eq!(got, 0, "trial {trial}: ({x}, {y}) outside written"),
                        None => assert!(got <= layers),
                    }
                }
            }
        }
    }
}

/// Screen triangle straight from fixed-point pixel coordinates.
fn tri(ctx: &SetupContext, p: [[f64; 2]; 3]) -> Option<RasterTri> {
    let f = |q: [f64; 2]| {
        [
            (q[0] * SUBPIXEL_ONE as f64) as i64,
            (q[1] * SUBPIXEL_ONE as f64) as i64,
        ]
    };
    ctx.edges(0, f(p[0]), f(p[1]), f(p[2]))
}

fn covered(t: &Option<RasterTri>, x: i32, y: i32) -> bool {
    t.as_ref().is_some_and(|t| {
        let [x0, y0, x1, y1] = t.bbox;
        (x0..x1).contains(&x) && (y0..y1).contains(&y) && t.covers(x, y)
    })
}

#[test]
fn fill_rule_on_edges_through_pixel_centres() {
    let ctx = ctx();
    // Square [10.5, 20.5]² (edges through pixel centres) split along its
    // diagonal, which also passes through centres.
    let a = tri(&ctx, [[10.5, 10.5], [20.5, 10.5], [20.5, 20.5]]);
    let b = tri(&ctx, [[10.5, 10.5], [20.5, 20.5], [10.5, 20.5]]);
    for y in 5..25 {
        for x in 5..25 {
            let n = covered(&a, x, y) as u32 + covered(&b, x, y) as u32;
            // Left and top edges (x = 10, y = 10) belong to the square,
            // right and bottom (x = 20, y = 20) do not.
            let inside = (10..20).contains(&x) && (10..20).contains(&y);
            assert_eq!(n, inside as u32, "pixel ({x}, {y}) covered {n} times");
        }
    }
    // A horizontal top edge through centres is drawn, a bottom one is not.
    let top = tri(&ctx, [[30.5, 30.5], [40.5, 30.5], [35.5, 36.0]]);
    assert!(
        covered(&top, 35, 30),
        "top edge through a centre must be covered"
    );
    let bottom = tri(&ctx, [[35.5, 30.0], [40.5, 36.5], [30.5, 36.5]]);
    assert!(
        !covered(&bottom, 35, 36),
        "bottom edge through a centre must not be covered"
    );
    assert!(covered(&bottom, 35, 35));
    // Shared vertical edge x = 50.5 through centres: the pixel column goes to
    // the triangle on its right (where the edge is a left edge).
    let left = tri(&ctx, [[45.0, 40.0], [50.5, 40.0], [50.5, 50.0]]);
    let right = tri(&ctx, [[50.5, 40.0], [56.0, 45.0], [50.5, 50.0]]);
    for y in 41..49 {
        assert!(
            !covered(&left, 50, y),
            "left triangle must not own its right edge at y={y}"
        );
        assert!(
            covered(&right, 50, y),
            "right triangle must own its left edge at y={y}"
        );
    }
}

#[test]
fn zero_area_triangles_are_skipped() {
    let ctx = ctx();
    assert!(tri(&ctx, [[1.0, 1.0], [5.0, 5.0], [9.0, 9.0]]).is_none());
    let mut out = Vec::new();
    let mut counts = SetupCounts::default();
    let v = clip_of(10.0, 10.0, 0.5);
    assert!(ctx
        .setup(
            0,
            [v, v, clip_of(20.0, 10.0, 0.5)],
            Cull::Back,
            &mut out,
            &mut counts
        )
        .is_none());
    assert_eq!(counts.skipped_degenerate, 1);
    assert!(out.is_empty());
}

/// Found by the `raster` fuzz target (docs/ROBUSTNESS.md): vertices with
/// subnormal w clip to a vertex at w = 0 and to others millions of pixels
/// past the guard band, whose snapped coordinates overflowed the i64 edge
/// setup (a panic with overflow checks, wrapped coverage without). Now
/// the triangle is skipped as invalid.
#[test]
fn subnormal_w_clipped_past_the_guard_band_is_skipped() {
    let (w, h) = (32, 32);
    let ctx = SetupContext {
        width: w,
        height: h,
        guard: GuardBand::for_image(w, h),
    };
    let bits: [[u32; 4]; 3] = [
        [0x10101010, 0x10101010, 0x10101010, 0x10101010],
        [0xbf10, 0x3f00, 0x80000000, 0x8000003f],
        [0x80000037, 0xbf, 0x8000003f, 0x33bf],
    ];
    let v = bits.map(|p| p.map(f32::from_bits));
    let mut out = Vec::new();
    let mut counts = SetupCounts::default();
    let planes = ctx.setup(0, v, Cull::Front, &mut out, &mut counts);
    assert!(planes.is_none(), "{planes:?}");
    assert_eq!(counts.skipped_invalid, 1, "{counts:?}");
    assert!(out.is_empty());
}

/// Found by the `raster` fuzz target: a vertex at a subnormal w gave
/// plane gradients beyond f32 (1/w = inf at its pixels, NaN barycentrics).
/// Such a triangle is now skipped as degenerate, its screen triangles
/// withdrawn.
#[test]
fn planes_beyond_f32_are_skipped() {
    let (w, h) = (101, 101);
    let ctx = SetupContext {
        width: w,
        height: h,
        guard: GuardBand::for_image(w, h),
    };
    let bits: [[u32; 4]; 3] = [
        [0x29bee8a2, 0x3f46e2, 0x3f0000, 0x263f8000],
        [0xbf591689, 0x3e9a5ccf, 0x3f000000, 0x3f800000],
        [0x1, 0x0, 0x8000, 0x10000],
    ];
    let v = bits.map(|p| p.map(f32::from_bits));
    let mut out = Vec::new();
    let mut counts = SetupCounts::default();
    let planes = ctx.setup(3, v, Cull::None, &mut out, &mut counts);
    assert!(planes.is_none(), "{planes:?}");
    assert_eq!(counts.skipped_degenerate, 1, "{counts:?}");
    assert!(out.is_empty());
}

/// Found by the `raster` fuzz target: planes finite in f32 but so steep
/// (a vertex at w ≈ 1e-43) that depth evaluated a few dozen pixels from
/// their origin overflowed to inf. Every plane a triangle is drawn with
/// must now evaluate finite at every pixel of the image.
#[test]
fn planes_evaluate_finite_over_the_whole_image() {
    use specula_raster::setup::TriPlanes;
    let (w, h) = (101, 101);
    let ctx = SetupContext {
        width: w,
        height: h,
        guard: GuardBand::for_image(w, h),
    };
    let tris: [[[u32; 4]; 3]; 2] = [
        [
            [0x49010000, 0x0, 0x0, 0x80],
            [0x0, 0x10, 0x2, 0x0],
            [0x80, 0x0, 0x3f000000, 0x3f800000],
        ],
        [
            [0xbee8a212, 0x3f46e229, 0x3f000000, 0x3f800000],
            [0xbf210000, 0x3f000000, 0x89000000, 0x9ebf5916],
            [0x5ccf00, 0x80, 0xbf611689, 0x8000ff],
        ],
    ];
    for (id, bits) in tris.iter().enumerate() {
        let v = bits.map(|p| p.map(f32::from_bits));
        let mut out = Vec::new();
        let mut counts = SetupCounts::default();
        let Some(p) = ctx.setup(id as u32, v, Cull::None, &mut out, &mut counts) else {
            continue;
        };
        for y in 0..h {
            for x in 0..w {
                let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
                for plane in [&p.k1, &p.k2, &p.ks, &p.z] {
                    let e = TriPlanes::eval(plane, p.origin, px, py);
                    assert!(e.is_finite(), "triangle {id} at ({x}, {y}): {e} from {p:?}");
                }
            }
        }
    }
}

/// `q` on half-pixel positions for every third `i` (edges through pixel
/// centres), unchanged for the others.
fn snapped_every_third(i: usize, q: [f64; 2]) -> [f64; 2] {
    if i.is_multiple_of(3) {
        q.map(|v| (v * 2.0).round() / 2.0)
    } else {
        q
    }
}

/// Walks `t` over the pixel rectangle `r` ([x0, x1, y0, y1]) with groups
/// aligned to `align`, as the scan does for one tile, and checks that the
/// walk covers exactly the pixels the direct edge test does, each once, and
/// nothing outside `r`. Returns the number of pixels walked.
fn walk_rectangle(t: &RasterTri, r: [i32; 4], align: i32) -> usize {
    let mut walked = std::collections::HashSet::new();
    covered_groups(t, r, align, |y, gx, mask| {
        assert_eq!((gx - align).rem_euclid(8), 0, "group not aligned");
        for lane in 0..8 {
            if mask & (1 << lane) != 0 {
                assert!(walked.insert((gx + lane, y)), "pixel walked twice");
            }
        }
    });
    for y in r[2]..r[3] {
        for x in r[0]..r[1] {
            assert_eq!(
                walked.contains(&(x, y)),
                t.covers(x, y),
                "pixel ({x}, {y}), rectangle {r:?}, groups from {align}"
            );
        }
    }
    assert!(walked
        .iter()
        .all(|&(x, y)| x >= r[0] && x < r[1] && y >= r[2] && y < r[3]));
    walked.len()
}

/// The scan walks large triangles tile by tile, and decides a tile the
/// triangle covers entirely (or misses) from its four corners alone
/// (`RasterTri::rect_coverage`). Over random large triangles, some with
/// edges through pixel centres, and rectangles of several sizes and
/// offsets, the walk covers exactly the pixels the direct edge test does,
/// and both shortcuts are taken.
#[test]
fn large_triangles_walked_by_rectangles_cover_exactly_their_pixels() {
    use specula_raster::setup::RectCoverage;
    let ctx = ctx();
    let mut rng = rand::rngs::StdRng::seed_from_u64(12);
    let mut seen = [0usize; 3];
    for i in 0..300 {
        // Vertices far outside the image, on half-pixel positions for a
        // third of the triangles (edges through pixel centres).
        let mut p = || {
            let q = [
                rng.random_range(-150.0..250.0),
                rng.random_range(-150.0..230.0),
            ];
            snapped_every_third(i, q)
        };
        let Some(t) = tri(&ctx, [p(), p(), p()]) else {
            continue;
        };
        if t.small.is_some() {
            continue;
        }
        let size = [4, 8, 13, 16][i % 4];
        let [bx0, by0, bx1, by1] = t.bbox;
        for ry in (by0..by1).step_by(size) {
            for rx in (bx0..bx1).step_by(size) {
                let r = [
                    rx,
                    (rx + size as i32).min(bx1),
                    ry,
                    (ry + size as i32).min(by1),
                ];
                match t.rect_coverage(r) {
                    RectCoverage::Outside => seen[0] += 1,
                    RectCoverage::Inside => seen[1] += 1,
                    RectCoverage::Partial => seen[2] += 1,
                }
                walk_rectangle(&t, r, rx);
            }
        }
    }
    assert!(
        seen.iter().all(|&n| n > 100),
        "outside/inside/partial: {seen:?}"
    );
}

/// Small triangles (i32 edge functions, stepped row by row and group by
/// group) walked tile by tile as the scan does: groups aligned to the
/// tile's origin, the rectangle the bounding box clipped to the tile and to
/// a random window (`walk_rectangle`).
#[test]
fn small_triangles_walked_by_tiles_cover_exactly_their_pixels() {
    let ctx = ctx();
    let mut rng = rand::rngs::StdRng::seed_from_u64(13);
    let mut walked_pixels = 0usize;
    let mut clipped = 0usize;
    for i in 0..2000 {
        // A triangle up to ~40 px across somewhere in the image, on
        // half-pixel positions for a third (edges through pixel centres).
        let c = [rng.random_range(0.0..200.0), rng.random_range(0.0..180.0)];
        let s: f64 = rng.random_range(0.5..40.0);
        let mut p = || {
            let q = [
                c[0] + rng.random_range(-s..s),
                c[1] + rng.random_range(-s..s),
            ];
            snapped_every_third(i, q)
        };
        let Some(t) = tri(&ctx, [p(), p(), p()]) else {
            continue;
        };
        if t.small.is_none() {
            continue;
        }
        let tile = [8, 16, 64][i % 3];
        let [bx0, by0, bx1, by1] = t.bbox;
        let first = |v: i32| v.div_euclid(tile) * tile;
        for ty in (first(by0)..by1).step_by(tile as usize) {
            for tx in (first(bx0)..bx1).step_by(tile as usize) {
                // Also cut by a random window (as the image's edges cut a
                // triangle's box): lanes of a group outside it are dropped
                // even where the triangle covers them.
                let (wx0, wx1) = (
                    rng.random_range(bx0 - 4..bx1),
                    rng.random_range(bx0..bx1 + 4),
                );
                let r = [
                    bx0.max(tx).max(wx0),
                    bx1.min(tx + tile).min(wx1),
                    by0.max(ty),
                    by1.min(ty + tile),
                ];
                if r[0] >= r[1] || r[2] >= r[3] {
                    continue;
                }
                clipped += (r[0] > bx0 || r[1] < bx1) as usize;
                walked_pixels += walk_rectangle(&t, r, tx);
            }
        }
    }
    assert!(
        walked_pixels > 10_000 && clipped > 500,
        "{walked_pixels} pixels, {clipped} clipped rectangles"
    );
}
