//! `setup_x4` against the scalar `setup` called per triangle: the same
//! screen triangles in the same order, the same planes (bit for bit) and
//! the same counts, on random triangles and on the inputs that send a lane
//! to the scalar path or to an unusual end of the fast one.

use super::trace::{Paths, PATHS};
use super::LANES;
use crate::clip::GuardBand;
use crate::geometry::Cull;
use crate::setup::{RasterTri, SetupContext, SetupCounts, TriPlanes, MAX_CLIP_COORD};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

type Tri = [[f32; 4]; 3];

fn ctx(width: u32, height: u32) -> SetupContext {
    SetupContext {
        width,
        height,
        guard: GuardBand::for_image(width, height),
    }
}

/// Everything of a screen triangle, floats as bits.
fn raster_bits(r: &RasterTri) -> impl PartialEq + std::fmt::Debug {
    (
        r.edges,
        r.inv_step.map(f64::to_bits),
        r.small,
        r.bbox,
        r.tri,
    )
}

fn plane_bits(p: &TriPlanes) -> Vec<u32> {
    [&p.origin[..], &p.k1, &p.k2, &p.ks, &p.z, &[p.facing]]
        .concat()
        .iter()
        .map(|c| c.to_bits())
        .collect()
}

/// Runs both paths over `tris` (a multiple of 4, grouped in order), asserts
/// they agree, and returns how the 4-wide path's lanes ended.
fn compare(ctx: &SetupContext, tris: &[(Tri, Cull)]) -> Paths {
    assert_eq!(tris.len() % LANES, 0);
    // Planes not written keep this value in both paths.
    let unset = TriPlanes {
        facing: 7.0,
        ..TriPlanes::default()
    };
    let (mut out_s, mut counts_s) = (Vec::new(), SetupCounts::default());
    let mut planes_s = vec![unset; tris.len()];
    for (i, (v, cull)) in tris.iter().enumerate() {
        if let Some(p) = ctx.setup(i as u32, *v, *cull, &mut out_s, &mut counts_s) {
            planes_s[i] = p;
        }
    }
    PATHS.with(|p| p.set(Paths::default()));
    let (mut out_v, mut counts_v) = (Vec::new(), SetupCounts::default());
    let mut planes_v = vec![unset; tris.len()];
    for (g, (group, planes)) in tris
        .chunks_exact(LANES)
        .zip(planes_v.chunks_exact_mut(LANES))
        .enumerate()
    {
        let v = std::array::from_fn(|t| group[t].0);
        let cull = std::array::from_fn(|t| group[t].1);
        let planes = planes.try_into().unwrap();
        let first = (g * LANES) as u32;
        ctx.setup_x4(first, &v, cull, planes, &mut out_v, &mut counts_v);
    }
    let paths = PATHS.with(|p| p.get());
    assert_eq!(counts_v, counts_s);
    assert_eq!(out_v.len(), out_s.len());
    for (a, b) in out_v.iter().zip(&out_s) {
        assert_eq!(raster_bits(a), raster_bits(b), "{:?}", tris[b.tri as usize]);
    }
    for (i, (a, b)) in planes_v.iter().zip(&planes_s).enumerate() {
        assert_eq!(plane_bits(a), plane_bits(b), "planes of {:?}", tris[i]);
    }
    // Every lane ends in exactly one way.
    assert_eq!(paths.0[..6].iter().sum::<u64>(), tris.len() as u64);
    paths
}

/// Clip-space vertex of NDC (nx, ny, nz) at view depth w.
fn clip(nx: f64, ny: f64, nz: f64, w: f64) -> [f32; 4] {
    [(nx * w) as f32, (ny * w) as f32, (nz * w) as f32, w as f32]
}

/// Clip-space vertex of screen position (sx, sy) in pixels.
fn at_pixel(ctx: &SetupContext, sx: f64, sy: f64, w: f64) -> [f32; 4] {
    let nx = 2.0 * sx / ctx.width as f64 - 1.0;
    let ny = 1.0 - 2.0 * sy / ctx.height as f64;
    clip(nx, ny, 0.5, w)
}

fn any_cull(rng: &mut StdRng) -> Cull {
    match rng.random_range(0..4) {
        0 | 1 => Cull::Back,
        2 => Cull::Front,
        _ => Cull::None,
    }
}

/// A small-to-large triangle around a point of (mostly) the screen, as a
/// mesh has them: sizes from 10⁻⁴ to 1 NDC unit, view depths 0.1 to 100.
fn mesh_like(rng: &mut StdRng) -> Tri {
    let (cx, cy) = (rng.random_range(-1.3..1.3), rng.random_range(-1.3..1.3));
    let size = 10f64.powf(rng.random_range(-4.0..0.0));
    let w = 10f64.powf(rng.random_range(-1.0..2.0));
    std::array::from_fn(|_| {
        clip(
            cx + size * rng.random_range(-1.0..1.0),
            cy + size * rng.random_range(-1.0..1.0),
            rng.random_range(0.0..1.0),
            w * rng.random_range(0.9..1.1),
        )
    })
}

/// Anything in a box around the eye: behind it, across the near plane,
/// past the guard band after division.
fn wild(rng: &mut StdRng) -> Tri {
    std::array::from_fn(|_| {
        [
            rng.random_range(-3.0..3.0),
            rng.random_range(-3.0..3.0),
            rng.random_range(-1.0..3.0),
            rng.random_range(-1.0..3.0),
        ]
    })
}

/// Tiny triangles whose vertices sit near pixel centres and corners: many
/// contain no centre, some touch one on an edge (fill rule).
fn pixel_sized(rng: &mut StdRng, ctx: &SetupContext) -> Tri {
    let px = rng.random_range(0..ctx.width) as f64;
    let py = rng.random_range(0..ctx.height) as f64;
    let quarter = |rng: &mut StdRng| rng.random_range(0..5) as f64 * 0.25;
    std::array::from_fn(|_| {
        let (dx, dy) = (quarter(rng), quarter(rng));
        at_pixel(ctx, px + dx, py + dy, 2.0)
    })
}

/// Triangles reaching far into the guard band (up to 2²⁰ pixels from the
/// image): their edges leave the range `edges_x4` computes exactly.
fn guard_sized(rng: &mut StdRng, ctx: &SetupContext) -> Tri {
    let reach = 10f64.powf(rng.random_range(-3.0..0.0));
    let (kx, ky) = (ctx.guard.kx * reach, ctx.guard.ky * reach);
    let w = rng.random_range(0.5..2.0);
    std::array::from_fn(|_| clip(rng.random_range(-kx..kx), rng.random_range(-ky..ky), 0.5, w))
}

fn random_mix(rng: &mut StdRng, ctx: &SetupContext, n: usize) -> Vec<(Tri, Cull)> {
    (0..n)
        .map(|_| {
            let v = match rng.random_range(0..10) {
                0..=4 => mesh_like(rng),
                5 | 6 => wild(rng),
                7 => guard_sized(rng, ctx),
                _ => pixel_sized(rng, ctx),
            };
            (v, any_cull(rng))
        })
        .collect()
}

#[test]
fn random_triangles_match_the_scalar_setup() {
    let mut rng = StdRng::seed_from_u64(12);
    for (w, h) in [(1920, 1080), (37, 23), (1, 1)] {
        let ctx = ctx(w, h);
        let tris = random_mix(&mut rng, &ctx, 12_000);
        let paths = compare(&ctx, &tris);
        let [scalar, outside, culled, drawn, no_samples, _, _] = paths.0;
        assert!(
            scalar > 0 && outside > 0 && culled > 0 && drawn > 0 && no_samples > 0,
            "{w}×{h}: {paths:?}"
        );
        // Most lanes take the fast path on mesh-like input.
        assert!(
            drawn + culled + outside + no_samples > scalar,
            "{w}×{h}: {paths:?}"
        );
    }
}

/// Values that break the usual assumptions, put in one coordinate of an
/// otherwise ordinary triangle.
const ODD: [f32; 16] = [
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    1e30,
    -1e30,
    f32::MAX,
    MAX_CLIP_COORD as f32,
    -(MAX_CLIP_COORD as f32),
    1.0e15 * 1.2,
    0.0,
    -0.0,
    f32::MIN_POSITIVE,
    1e-40,
    -1e-40,
    1e-45,
    1e10,
];

fn edge_cases(rng: &mut StdRng, ctx: &SetupContext) -> Vec<Tri> {
    let mut tris = Vec::new();
    let g = ctx.guard;
    for _ in 0..200 {
        let base = mesh_like(rng);
        // One odd coordinate.
        for odd in ODD {
            let mut v = base;
            v[rng.random_range(0..3)][rng.random_range(0..4)] = odd;
            tris.push(v);
        }
        // One vertex at a subnormal or zero w on the view axis: huge planes.
        for w in [1e-40, 1e-45, 0.0, -1e-40, 1e-30] {
            let mut v = base;
            v[rng.random_range(0..3)] = [0.0, 0.0, 0.0, w];
            tris.push(v);
        }
        // Zero area: a repeated vertex, all three equal, (nearly) collinear.
        let mut v = base;
        v[2] = v[0];
        tris.push(v);
        tris.push([base[1]; 3]);
        let t = rng.random_range(-2.0..2.0);
        let mid: [f32; 4] = std::array::from_fn(|c| {
            (base[0][c] as f64 + t * (base[1][c] as f64 - base[0][c] as f64)) as f32
        });
        tris.push([base[0], base[1], mid]);
        // Back-facing: the same triangle wound the other way.
        tris.push([base[0], base[2], base[1]]);
        // Behind the eye (w < 0), whole or in part.
        tris.push(base.map(|p| p.map(|c| -c)));
        let mut v = base;
        v[0] = v[0].map(|c| -c);
        tris.push(v);
        // On the guard band: x or y at ±k·w, rounded to f32 either way,
        // so the distance test lands on both sides of 0.
        let w = rng.random_range(0.5..4.0f32);
        let (kx, ky) = ((g.kx * w as f64) as f32, (g.ky * w as f64) as f32);
        for (x, y) in [
            (kx, 0.0),
            (-kx, 0.0),
            (0.0, ky),
            (0.0, -ky),
            (kx.next_up(), 0.0),
        ] {
            let mut v = base;
            let i = rng.random_range(0..3);
            v[i] = [x, y, 0.5 * w, w];
            tris.push(v);
            let mut v = base;
            v[i] = [x.next_down(), y.next_down(), 0.5 * w, w];
            tris.push(v);
        }
        // Far away but on screen: large coordinates that stay valid.
        let s = 10f32.powi(rng.random_range(5..14));
        tris.push(base.map(|p| p.map(|c| c * s)));
        // On the near plane exactly (z = w) and on the far plane (z = 0).
        let mut v = base;
        v[0][2] = v[0][3];
        tris.push(v);
        let mut v = base;
        v[1][2] = 0.0;
        tris.push(v);
    }
    tris
}

#[test]
fn edge_cases_match_the_scalar_setup() {
    let mut rng = StdRng::seed_from_u64(1212);
    for (w, h) in [(1920, 1080), (64, 48), (3, 700)] {
        let ctx = ctx(w, h);
        let mut tris: Vec<(Tri, Cull)> = edge_cases(&mut rng, &ctx)
            .into_iter()
            .map(|v| (v, any_cull(&mut rng)))
            .collect();
        // Mixed with ordinary triangles, in every lane position.
        tris.extend(random_mix(&mut rng, &ctx, tris.len()));
        for i in (1..tris.len()).rev() {
            tris.swap(i, rng.random_range(0..=i));
        }
        tris.truncate(tris.len() / LANES * LANES);
        let paths = compare(&ctx, &tris);
        assert!(paths.0.iter().all(|&n| n > 0), "{w}×{h}: {paths:?}");
    }
}

#[test]
fn every_pattern_of_scalar_lanes_matches() {
    let mut rng = StdRng::seed_from_u64(4);
    let ctx = ctx(320, 200);
    let mut tris = Vec::new();
    for _ in 0..50 {
        for pattern in 0..16 {
            for t in 0..LANES {
                // Front-facing in a pass that draws both sides, so ordinary
                // lanes take the fast path.
                let mut v = mesh_like(&mut rng);
                if pattern >> t & 1 != 0 {
                    v[t % 3][t] = f32::NAN;
                }
                tris.push((v, Cull::None));
            }
        }
    }
    let paths = compare(&ctx, &tris);
    assert_eq!(paths.0[0], 50 * 32, "{paths:?}");
}

#[test]
fn snap_matches_the_scalar_snap_at_ties_and_extremes() {
    let g = crate::fixed::GUARD_BAND_PX;
    let mut vs = vec![
        0.0, -0.0, 1e-300, -1e-300, g, -g, 0.5, -0.5, 1.5, -1.5, 2.5, -2.5,
    ];
    let mut rng = StdRng::seed_from_u64(3);
    for _ in 0..4000 {
        // Ties (k + ½)/256, and anything in the band.
        let k = rng.random_range(-(1i64 << 28)..1 << 28) as f64;
        vs.push((k + 0.5) / 256.0);
        vs.push(rng.random_range(-g..=g));
        vs.push(k / 256.0);
    }
    for chunk in vs.chunks_exact(LANES) {
        let v: [f64; LANES] = chunk.try_into().unwrap();
        let fixed = wide::f64x4::splat(crate::fixed::SUBPIXEL_ONE as f64);
        let got = super::snap(wide::f64x4::new(v) * fixed);
        assert_eq!(got, v.map(crate::fixed::snap), "{v:?}");
    }
}

/// `Vertices4::gather` (the frame's loads straight from the clip array)
/// holds the same lanes as `from_arrays` of the same triangles, NaN and
/// infinite coordinates included, and `lane` gives each triangle back.
#[test]
fn gathered_vertices_match_the_arrays() {
    use super::Vertices4;
    let mut rng = StdRng::seed_from_u64(12);
    let special = [f32::NAN, f32::INFINITY, -0.0, f32::MIN_POSITIVE / 4.0, 3e38];
    let clip: Vec<[f32; 4]> = (0..50)
        .map(|i| {
            std::array::from_fn(|c| {
                if i % 7 == 0 && c == i % 4 {
                    special[i % special.len()]
                } else {
                    rng.random_range(-1e3..1e3)
                }
            })
        })
        .collect();
    let bits =
        |v: &Vertices4| [v.x, v.y, v.z, v.w].map(|a| a.map(|c| c.to_array().map(f64::to_bits)));
    for _ in 0..200 {
        let tris: [[u32; 3]; LANES] =
            std::array::from_fn(|_| std::array::from_fn(|_| rng.random_range(0..50u32)));
        let arrays = tris.map(|t| t.map(|i| clip[i as usize]));
        let (g, a) = (
            Vertices4::gather(&clip, &tris),
            Vertices4::from_arrays(&arrays),
        );
        assert_eq!(bits(&g), bits(&a), "{tris:?}");
        for (t, tri) in arrays.iter().enumerate() {
            let back = g.lane(t).map(|p| p.map(f32::to_bits));
            assert_eq!(back, tri.map(|p| p.map(f32::to_bits)));
        }
    }
}

/// `orientation`, which the extrusion outline uses to tell which faces the
/// main pass draws, has the sign `setup` culls by: a valid triangle inside
/// the frustum is culled as a back face exactly when it is negative, and
/// skipped as degenerate when it is 0.
#[test]
fn orientation_is_the_sign_setup_culls_by() {
    use crate::setup::orientation;
    let ctx = ctx(64, 48);
    let mut rng = StdRng::seed_from_u64(11);
    let (mut front, mut back) = (0, 0);
    for n in 0..20_000 {
        let mut v: Tri = std::array::from_fn(|_| {
            let w = rng.random_range(0.5f32..4.0);
            [
                rng.random_range(-0.9..0.9) * w,
                rng.random_range(-0.9..0.9) * w,
                rng.random_range(0.1..0.9) * w,
                w,
            ]
        });
        if n % 17 == 0 {
            v[2] = v[1]; // degenerate
        }
        let mut counts = SetupCounts::default();
        ctx.setup(0, v, Cull::Back, &mut Vec::new(), &mut counts);
        let o = orientation(&v);
        assert_eq!(counts.culled_backface == 1, o < 0.0, "{v:?}: {o}");
        assert_eq!(counts.skipped_degenerate == 1, o == 0.0, "{v:?}: {o}");
        if o > 0.0 {
            front += 1;
        } else if o < 0.0 {
            back += 1;
        }
    }
    assert!(front > 5_000 && back > 5_000, "{front} front, {back} back");
}

/// `front_face_shown` only says "culled" where `setup` with `Cull::Front`
/// does cull (every kind of input: odd coordinates, vertices behind the
/// eye, outside, slivers, huge values, nearly collinear), says it for
/// almost every well-conditioned front face, and the 8-wide version gives
/// the scalar answer lane by lane.
#[test]
fn a_shown_front_face_is_one_setup_culls() {
    use crate::setup::{front_face_shown, front_faces_shown_x8};
    let ctx = ctx(64, 48);
    let mut rng = StdRng::seed_from_u64(23);
    let mut tris: Vec<Tri> = random_mix(&mut rng, &ctx, 40_000)
        .into_iter()
        .map(|(v, _)| v)
        .collect();
    tris.extend(edge_cases(&mut rng, &ctx));
    // Nearly collinear at every scale: the margin decides.
    for _ in 0..20_000 {
        let mut v = mesh_like(&mut rng);
        let t = rng.random_range(-2.0f32..3.0);
        let e = 10f32.powf(rng.random_range(-9.0..-3.0)) * rng.random_range(-1.0f32..1.0);
        let scale = 10f32.powf(rng.random_range(-20.0..14.0));
        v[2] = std::array::from_fn(|c| v[0][c] + t * (v[1][c] - v[0][c]) + e * v[0][c].abs());
        tris.push(v.map(|p| p.map(|c| c * scale)));
    }
    tris.truncate(tris.len() / 8 * 8);
    let (mut shown, mut front_ok) = (0, 0);
    for v in &tris {
        let mut counts = SetupCounts::default();
        ctx.setup(0, *v, Cull::Front, &mut Vec::new(), &mut counts);
        let culled = counts.culled_backface == 1;
        if front_face_shown(v) {
            assert!(culled, "{v:?}: shown front, setup {counts:?}");
            shown += 1;
        }
        // A plain front face: in front of the eye at a usual distance (f32
        // products of the coordinates in range), on screen, not thin.
        let on = v
            .iter()
            .all(|p| p[3] > 1e-3 && p[3] < 1e6 && p[0].abs() < p[3] && p[1].abs() < p[3]);
        let o = crate::setup::orientation(v);
        let s = v.map(|p| [p[0] as f64 / p[3] as f64, p[1] as f64 / p[3] as f64]);
        let area =
            (s[1][0] - s[0][0]) * (s[2][1] - s[0][1]) - (s[2][0] - s[0][0]) * (s[1][1] - s[0][1]);
        let sides =
            [0, 1, 2].map(|k| (s[k][0] - s[(k + 1) % 3][0]).hypot(s[k][1] - s[(k + 1) % 3][1]));
        let long = sides.iter().copied().fold(0.0, f64::max);
        let short = sides.iter().copied().fold(f64::INFINITY, f64::min);
        if on && culled && o > 0.0 && short > 0.02 && area > 0.05 * long * long {
            front_ok += 1;
            assert!(front_face_shown(v), "{v:?}: a plain front face not shown");
        }
    }
    assert!(
        shown > 10_000 && front_ok > 1_000,
        "{shown} shown, {front_ok} plain front faces"
    );
    // Positions in one array, triangles of 8 in random order.
    let clip: Vec<[f32; 4]> = tris.iter().flatten().copied().collect();
    for (g, _) in tris.chunks_exact(8).enumerate() {
        let t8: [[u32; 3]; 8] = std::array::from_fn(|k| {
            let t = (8 * g + (k * 5 + g) % 8) as u32;
            [3 * t, 3 * t + 1, 3 * t + 2]
        });
        let mask = front_faces_shown_x8(&clip, &t8);
        for (k, t) in t8.iter().enumerate() {
            let v = t.map(|i| clip[i as usize]);
            assert_eq!(mask >> k & 1 == 1, front_face_shown(&v), "{v:?}");
        }
    }
}
