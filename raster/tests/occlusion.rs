//! The occlusion test skips only triangles that write nothing: every
//! triangle it calls hidden is set up and scanned by the rasterizer's own
//! code against the depth buffer the bounds came from, and must leave
//! every depth and id unchanged. Triangles are drawn at depths just in
//! front of and just behind the buffer, flat and steep, small and slivers,
//! so the bound's margins are what decides; a fifth straddle the corners
//! of a checker of two depths, where one block more or less decides (a
//! bounds loop that drops the last block column fails this test).

use rand::{Rng, SeedableRng};
use specula_raster::clip::GuardBand;
use specula_raster::fuzzing::scan_triangle;
use specula_raster::fuzzing::DepthBounds;
use specula_raster::setup::{SetupContext, SetupCounts};
use specula_raster::target::{Target, TILE_PIXELS};
use specula_raster::{Cull, MISS};

const W: u32 = 150;
const H: u32 = 100;

/// Depth of the stand-in for what the main pass drew: flat on the left,
/// a checker of 16-pixel cells (not aligned to the bounds' blocks) at two
/// depths on the right, and a patch of background (0).
fn scene_depth(x: f64, y: f64) -> f32 {
    let near_cell = x >= 75.0 && ((x / 16.0).floor() + (y / 16.0).floor()) as i64 % 2 != 0;
    if x > 130.0 && y < 20.0 {
        0.0
    } else if near_cell {
        0.06
    } else {
        0.05
    }
}

/// The image, its depth buffer (`scene_depth` at pixel centres), the
/// bounds built from it and a setup context.
fn scene() -> (Target, Vec<f32>, DepthBounds, SetupContext) {
    let target = Target::new(W, H).unwrap();
    let mut depth = vec![0.0f32; target.buffer_len()];
    for y in 0..H {
        for x in 0..W {
            depth[target.index(x, y)] = scene_depth(x as f64 + 0.5, y as f64 + 0.5);
        }
    }
    let mut bounds = DepthBounds::default();
    bounds.build(&target, &depth);
    let ctx = SetupContext {
        width: W,
        height: H,
        guard: GuardBand::for_image(W, H),
    };
    (target, depth, bounds, ctx)
}

#[test]
fn triangles_called_hidden_write_no_pixel() {
    let (target, depth, bounds, ctx) = scene();
    let mut rng = rand::rngs::StdRng::seed_from_u64(10);
    let (mut hidden, mut writers) = (0, 0);
    for n in 0..8_000 {
        // A centre on the image, a size from sub-pixel to 40 px, a sliver
        // now and then.
        let (mut cx, mut cy) = (rng.random_range(-5.0..155.0), rng.random_range(-5.0..105.0));
        if n % 5 == 0 {
            // Near a corner of the checker's cells, where a block more or
            // less decides.
            cx = 80.0 + 16.0 * rng.random_range(0..4) as f64 + rng.random_range(-6.0..6.0);
            cy = 16.0 * rng.random_range(1..6) as f64 + rng.random_range(-6.0..6.0);
        }
        let size: f64 = [0.3f64, 3.0, 12.0, 40.0][n % 4].min(if n % 5 == 0 { 8.0 } else { 40.0 });
        let mut p = [[0.0f64; 2]; 3];
        for q in &mut p {
            *q = [
                cx + rng.random_range(-size..size),
                cy + rng.random_range(-size..size),
            ];
        }
        if n % 7 == 0 {
            // Nearly collinear.
            p[2] = [
                (p[0][0] + p[1][0]) * 0.5 + rng.random_range(-0.01..0.01),
                (p[0][1] + p[1][1]) * 0.5 + rng.random_range(-0.01..0.01),
            ];
        }
        // Depth at each vertex: the least of the buffer around the
        // triangle (a block past its box), times a factor just below or
        // above 1 (or a steep spread), so many triangles sit within
        // rounding of the bound.
        let spread = [1e-7, 1e-6, 1e-4, 0.05][n % 4 / 2 + (n % 3 == 0) as usize * 2];
        let lo = |k: usize| p.iter().fold(f64::INFINITY, |m, q| m.min(q[k]));
        let hi = |k: usize| p.iter().fold(f64::NEG_INFINITY, |m, q| m.max(q[k]));
        let px = |v: f64, n: u32| v.clamp(0.0, n as f64 - 1.0) as u32;
        let mut least = f32::INFINITY;
        for y in px(lo(1) - 6.0, H)..=px(hi(1) + 6.0, H) {
            for x in px(lo(0) - 6.0, W)..=px(hi(0) + 6.0, W) {
                least = least.min(depth[target.index(x, y)]);
            }
        }
        let v: [[f32; 4]; 3] = p.map(|[x, y]| {
            // Every fifth between the checker's two depths: hidden only
            // where every block it touches is all near cells (0.06; depth is reversed).
            let base = if n % 5 == 0 { 0.055 } else { least as f64 };
            let z = base * (1.0 + spread * rng.random_range(-2.0..2.0));
            let w: f64 = rng.random_range(0.5..4.0);
            let (nx, ny) = (2.0 * x / W as f64 - 1.0, 1.0 - 2.0 * y / H as f64);
            [(nx * w) as f32, (ny * w) as f32, (z * w) as f32, w as f32]
        });
        let v64 = v.map(|c| c.map(|x| x as f64));
        let says_hidden = bounds.hides(&v64);
        let mut tris = Vec::new();
        let mut counts = SetupCounts::default();
        let Some(planes) = ctx.setup(7, v, Cull::None, &mut tris, &mut counts) else {
            continue;
        };
        let mut d = depth.clone();
        let mut ids = vec![MISS; target.buffer_len()];
        for rt in &tris {
            for t in 0..target.tile_count() {
                let (tx, ty) = target.tile_origin(t);
                let [x0, y0, x1, y1] = rt.bbox;
                let tile = specula_raster::TILE as i32;
                if x1 <= tx as i32
                    || x0 >= tx as i32 + tile
                    || y1 <= ty as i32
                    || y0 >= ty as i32 + tile
                {
                    continue; // not binned to this tile
                }
                let range = t * TILE_PIXELS..(t + 1) * TILE_PIXELS;
                scan_triangle(
                    rt,
                    &planes,
                    tx as i32,
                    ty as i32,
                    (&mut d[range.clone()]).try_into().expect("a tile"),
                    (&mut ids[range]).try_into().expect("a tile"),
                );
            }
        }
        let wrote = ids.iter().filter(|&&i| i != MISS).count() as u64;
        if says_hidden {
            hidden += 1;
            assert_eq!(
                wrote, 0,
                "triangle {n} {v:?} called hidden wrote {wrote} pixels"
            );
        } else if wrote > 0 {
            writers += 1;
        }
    }
    // Not vacuous: most are hidden, and some of the others, as near the
    // buffer, do write.
    assert!(
        hidden > 300 && writers > 100,
        "{hidden} hidden, {writers} writing"
    );
}

/// The 4-wide setup with the occlusion test skips and counts exactly the
/// triangles the per-triangle `setup_occluded` does, and sets up the rest
/// identically: groups of 4 random triangles, some hidden, some in front,
/// some back-facing, compared triangle list, planes and counts.
#[test]
fn four_wide_setup_occludes_like_the_scalar_setup() {
    use specula_raster::setup::TriPlanes;
    let (_, _, bounds, ctx) = scene();
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let mut occluded = 0;
    for group in 0..2_000u32 {
        let v: [[[f32; 4]; 3]; 4] = std::array::from_fn(|_| {
            let (cx, cy) = (rng.random_range(-5.0..155.0), rng.random_range(-5.0..105.0));
            let size: f64 = [0.5f64, 4.0, 20.0][rng.random_range(0..3)];
            // Behind the buffer (0.01), at it, or in front (0.2); reversed depth.
            let z: f64 = [0.01, 0.05, 0.2][rng.random_range(0..3)];
            std::array::from_fn(|_| {
                let (x, y) = (
                    cx + rng.random_range(-size..size),
                    cy + rng.random_range(-size..size),
                );
                let w: f64 = rng.random_range(0.5..4.0);
                let (nx, ny) = (2.0 * x / W as f64 - 1.0, 1.0 - 2.0 * y / H as f64);
                [(nx * w) as f32, (ny * w) as f32, (z * w) as f32, w as f32]
            })
        });
        let cull = [Cull::Back, Cull::None, Cull::Back, Cull::Front];
        let first = group * 4;
        let (mut tris4, mut counts4) = (Vec::new(), SetupCounts::default());
        let mut planes4 = [TriPlanes::default(); 4];
        ctx.setup_x4_occluded(
            first,
            &v,
            cull,
            Some(&bounds),
            &mut planes4,
            &mut tris4,
            &mut counts4,
        );
        let (mut tris1, mut counts1) = (Vec::new(), SetupCounts::default());
        let mut planes1 = [TriPlanes::default(); 4];
        for t in 0..4 {
            let id = first + t as u32;
            if let Some(p) =
                ctx.setup_occluded(id, v[t], cull[t], Some(&bounds), &mut tris1, &mut counts1)
            {
                planes1[t] = p;
            }
        }
        assert_eq!(counts4, counts1, "group {group}");
        assert_eq!(format!("{tris4:?}"), format!("{tris1:?}"), "group {group}");
        assert_eq!(
            format!("{planes4:?}"),
            format!("{planes1:?}"),
            "group {group}"
        );
        occluded += counts1.culled_occluded;
    }
    assert!(occluded > 500, "only {occluded} triangles hidden");
}
