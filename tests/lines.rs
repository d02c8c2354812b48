//! NPR lines end to end: the `[[outline]]` / `[strokes]` schema, the three
//! outline methods and the stroke overlays (issue 10).

mod common;

use std::path::Path;

const BASE: &str = r#"
[camera]
eye = [0.0, 0.0, 4.0]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 10.0

[output]
width = 64
height = 64

[[mesh]]
sphere = { radius = 1.0, segments = 32, rings = 16 }
material = "toon"

[materials.toon]
model = "lambert"
base_color = [0.8, 0.5, 0.2]

[[light]]
type = "directional"
direction = [-0.5, -0.4, -1.0]
irradiance = [3.0, 3.0, 3.0]
"#;

fn load(extra: &str) -> Result<specula::scene::LoadedScene, String> {
    let text = format!("{BASE}\n{extra}");
    specula::scene::load_scene_str(Path::new("lines.toml"), &text, &|_| {
        Err(std::io::ErrorKind::NotFound.into())
    })
    .map_err(|e| e.to_string())
}

#[test]
fn the_issue_schema_loads() {
    let s = load(
        r#"
[[outline]]
method = "shading"
color = [0.0, 0.0, 0.0]
threshold = 0.25
materials = ["toon"]

[[outline]]
method = "extrusion"
width = 2.0

[[outline]]
method = "sobel"
width = 2.0
threshold = { depth = 0.1, normal = 0.4 }
sources = ["depth", "normal", "id"]

[strokes]
edges = ["silhouette", "crease", "boundary", "material"]
crease_angle = 60.0
width = 1.5
color = [0.05, 0.05, 0.05]
taper = 0.0
"#,
    )
    .unwrap();
    use specula::lines::{OutlineSpec, SourceDesc};
    assert_eq!(s.outlines.len(), 3);
    match &s.outlines[2] {
        OutlineSpec::Sobel { sources, width, .. } => {
            assert_eq!(*width, 2.0);
            assert_eq!(
                sources,
                &vec![
                    (SourceDesc::Depth, 0.1),
                    (SourceDesc::Normal, 0.4),
                    (SourceDesc::Id, 0.25)
                ]
            );
        }
        o => panic!("{o:?}"),
    }
    let st = s.strokes.unwrap();
    assert_eq!((st.width, st.crease_angle, st.edges.len()), (1.5, 60.0, 4));
}

#[test]
fn every_line_field_is_checked_and_named() {
    for (extra, want) in [
        ("[[outline]]\nmethod = \"sobel\"\nwdth = 2.0\n", "unknown field `wdth`"),
        ("[[outline]]\nmethod = \"pencil\"\n", "unknown variant `pencil`"),
        ("[[outline]]\nmethod = \"sobel\"\nwidth = nan\n", "outline[0].width"),
        ("[[outline]]\nmethod = \"sobel\"\nwidth = 0.0\n", "outline[0].width"),
        ("[[outline]]\nmethod = \"extrusion\"\nwidth = 65.0\n", "outline[0].width"),
        ("[[outline]]\nmethod = \"shading\"\nwidth = 2.0\n", "outline[0].width: not used"),
        ("[[outline]]\nmethod = \"shading\"\nthreshold = 1.5\n", "outline[0].threshold"),
        ("[[outline]]\nmethod = \"shading\"\nthreshold = nan\n", "outline[0].threshold"),
        ("[[outline]]\nmethod = \"shading\"\nsources = [\"depth\"]\n", "outline[0].sources: not used"),
        ("[[outline]]\nmethod = \"extrusion\"\nthreshold = 0.2\n", "outline[0].threshold: not used"),
        ("[[outline]]\nmethod = \"sobel\"\ncolor = [0.0, 2.0, 0.0]\n", "outline[0].color"),
        ("[[outline]]\nmethod = \"sobel\"\ncolor = [0.0, nan, 0.0]\n", "outline[0].color"),
        ("[[outline]]\nmethod = \"sobel\"\nsources = []\n", "outline[0].sources"),
        ("[[outline]]\nmethod = \"sobel\"\nsources = [\"id\", \"id\"]\n", "listed twice"),
        ("[[outline]]\nmethod = \"sobel\"\nsources = [\"ids\"]\n", "unknown variant `ids`"),
        ("[[outline]]\nmethod = \"sobel\"\nthreshold = -1.0\n", "outline[0].threshold"),
        ("[[outline]]\nmethod = \"sobel\"\nthreshold = { depth = nan }\n", "outline[0].threshold.depth"),
        ("[[outline]]\nmethod = \"sobel\"\nsources = [\"depth\"]\nthreshold = { normal = 0.2 }\n", "outline[0].threshold.normal"),
        ("[[outline]]\nmethod = \"sobel\"\nmaterials = [\"paper\"]\n", "outline[0].materials: no material named \"paper\""),
        ("[[outline]]\nmethod = \"sobel\"\nmaterials = []\n", "outline[0].materials"),
        ("[[outline]]\nmethod = \"sobel\"\n[[outline]]\nmethod = \"shading\"\nthreshold = 0.0\n", "outline[1].threshold"),
        ("[strokes]\nedges = []\n", "strokes.edges"),
        ("[strokes]\nedges = [\"crease\", \"crease\"]\n", "strokes.edges"),
        ("[strokes]\nedges = [\"ridge\"]\n", "unknown variant `ridge`"),
        ("[strokes]\ncrease_angle = 0.0\n", "strokes.crease_angle"),
        ("[strokes]\ncrease_angle = nan\n", "strokes.crease_angle"),
        ("[strokes]\nwidth = inf\n", "strokes.width"),
        ("[strokes]\ntaper = 1.5\n", "strokes.taper"),
        ("[strokes]\ntaper = nan\n", "strokes.taper"),
        ("[strokes]\ncolor = [-0.1, 0.0, 0.0]\n", "strokes.color"),
        ("[strokes]\njoin = \"pointy\"\n", "unknown variant `pointy`"),
        ("[strokes]\nwidth = 1.0\nstyle = 2\n", "unknown field `style`"),
    ] {
        let e = load(extra).err().unwrap_or_else(|| panic!("accepted: {extra}"));
        assert!(e.contains(want), "{extra}\n→ {e}\n(want {want:?})");
        assert!(e.starts_with("lines.toml"), "{e}");
    }
}

use specula::render::{render_scene, RenderSettings};
use specula_raster::target::MISS;

/// A sphere of `radius` at the origin seen from (0, 0, `distance`),
/// `size`² pixels, fov 40°, with `extra` appended.
fn sphere_scene(radius: f32, distance: f32, size: u32, extra: &str) -> String {
    format!(
        r#"
[camera]
eye = [0.0, 0.0, {distance}]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 100.0

[output]
width = {size}
height = {size}

[[mesh]]
sphere = {{ radius = {radius}, segments = 192, rings = 96 }}
material = "toon"

[materials.toon]
model = "lambert"
base_color = [0.8, 0.5, 0.2]

[[light]]
type = "directional"
direction = [-0.5, -0.4, -1.0]
irradiance = [3.0, 3.0, 3.0]
{extra}
"#
    )
}

/// n·v of the exact sphere (radius r at the origin, eye at (0, 0, d),
/// fov 40°) through the centre of pixel (x, y) of a size² image, in f64
/// from the ray-sphere intersection; None where the ray misses.
fn sphere_n_dot_v(r: f64, d: f64, size: u32, x: usize, y: usize) -> Option<f64> {
    let tan = 20f64.to_radians().tan();
    let nx = (2.0 * (x as f64 + 0.5) / size as f64 - 1.0) * tan;
    let ny = (1.0 - 2.0 * (y as f64 + 0.5) / size as f64) * tan;
    let len = (nx * nx + ny * ny + 1.0).sqrt();
    let dir = [nx / len, ny / len, -1.0 / len];
    // |e + t·dir|² = r², e = (0, 0, d).
    let b = d * dir[2];
    let disc = b * b - (d * d - r * r);
    if disc < 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    let p = [t * dir[0], t * dir[1], d + t * dir[2]];
    Some(-(p[0] * dir[0] + p[1] * dir[1] + p[2] * dir[2]) / r)
}

#[test]
fn shading_outline_darkens_below_the_threshold_and_its_width_follows_curvature() {
    use specula_npr::outline::{Selection, ShadingOutline};
    let size = 160;
    let t = 0.5;
    let mut widths = Vec::new();
    for radius in [1.0f64, 0.5] {
        let s = common::scene(&sphere_scene(radius as f32, 4.0, size, ""), &[]);
        let mut settings = RenderSettings::from_scene(&s);
        settings.buffers.normal = true;
        let r = render_scene(&s, &settings, 0.0).unwrap();
        let stage = ShadingOutline::new(s.data.camera.clone(), t, [0.0; 3], Selection::all());
        let cov = stage.coverage_map(&r.frame.buffers);
        // The mesh's interpolated normals differ from the sphere's by the
        // tessellation (192 × 96): a margin of 0.03 in n·v.
        let margin = stage.softness as f64 / 2.0 + 0.03;
        let (mut dark, mut clear) = (0, 0);
        for y in 0..size as usize {
            for x in 0..size as usize {
                let i = y * size as usize + x;
                let Some(ndv) = sphere_n_dot_v(radius, 4.0, size, x, y) else {
                    continue;
                };
                if r.frame.buffers.normal.get(i) == [0.0; 3] {
                    continue; // between the exact and the tessellated outline
                }
                if ndv < t as f64 - margin {
                    assert_eq!(cov[i], 1.0, "({x}, {y}) n·v {ndv}");
                    dark += 1;
                } else if ndv > t as f64 + margin {
                    assert_eq!(cov[i], 0.0, "({x}, {y}) n·v {ndv}");
                    clear += 1;
                }
            }
        }
        assert!(dark > 50 && clear > 500, "{dark} {clear}");
        // Band width along the middle row, from the left: ½-coverage samples.
        let row = size as usize / 2;
        let band = (0..size as usize)
            .filter(|x| x < &(size as usize / 2) && cov[row * size as usize + x] >= 0.5)
            .count();
        widths.push(band as f64);
    }
    // The trade-off: the same threshold gives a line twice as wide on a
    // sphere twice as big (R·(1 − √(1 − t²)): ~7.8 and ~3.9 px here).
    let ratio = widths[0] / widths[1];
    assert!((1.6..=2.5).contains(&ratio), "band widths {widths:?}");
}

/// Sector by sector around the image centre: the radius of the region
/// the main pass covers and of the region either pass covers, each from
/// its area in the sector (r = √(2A/θ)), so pixel steps average out.
fn ring_widths(ids: &[u32], w: usize, h: usize, main_ids: u32, sectors: usize) -> Vec<(f64, f64)> {
    let mut inner = vec![0.0f64; sectors];
    let mut outer = vec![0.0f64; sectors];
    let (cx, cy) = (w as f64 / 2.0, h as f64 / 2.0);
    let theta = std::f64::consts::TAU / sectors as f64;
    for y in 0..h {
        for x in 0..w {
            let id = ids[y * w + x];
            if id == MISS {
                continue;
            }
            // Sector edges half a sector off the axes and diagonals, where
            // rows of pixel centres lie exactly on the line.
            let a = (y as f64 + 0.5 - cy).atan2(x as f64 + 0.5 - cx) + 0.5 * theta;
            let a = if a > std::f64::consts::PI {
                a - std::f64::consts::TAU
            } else {
                a
            };
            let s = (((a + std::f64::consts::PI) / std::f64::consts::TAU * sectors as f64)
                as usize)
                .min(sectors - 1);
            outer[s] += 1.0;
            if id < main_ids {
                inner[s] += 1.0;
            }
        }
    }
    inner
        .iter()
        .zip(&outer)
        .map(|(i, o)| ((2.0 * i / theta).sqrt(), (2.0 * o / theta).sqrt()))
        .collect()
}

#[test]
fn extrusion_ring_has_the_requested_width_all_around_at_three_distances() {
    let width = 2.0;
    let size = 192;
    for (distance, ssaa) in [(3.0, 1), (6.0, 1), (12.0, 1), (6.0, 2)] {
        let extra = format!("[[outline]]\nmethod = \"extrusion\"\nwidth = {width}\n");
        let s = common::scene(&sphere_scene(1.0, distance, size, &extra), &[]);
        assert_eq!(s.data.geometry.len(), 2);
        let main_ids = s.data.triangles.len() as u32;
        let mut settings = RenderSettings::from_scene(&s);
        settings.ssaa = ssaa;
        settings.buffers.id = true;
        let r = render_scene(&s, &settings, 0.0).unwrap();
        let n = (size * ssaa) as usize;
        let rings = ring_widths(&r.frame.buffers.id, n, n, main_ids, 24);
        // The exact sphere's projected radius, for scale: f·tan(asin(1/d)).
        let f = n as f64 / 2.0 / 20f64.to_radians().tan();
        let r_exact = f * (1.0 / distance as f64).asin().tan();
        for (k, (ri, ro)) in rings.iter().enumerate() {
            let ring = (ro - ri) / ssaa as f64;
            assert!(
                (ring - width as f64).abs() <= 0.5,
                "distance {distance} ssaa {ssaa} sector {k}: ring {ring:.3} px (inner {ri:.2}, exact {r_exact:.2})"
            );
            assert!(
                (ri - r_exact).abs() < 0.75 * ssaa as f64,
                "sector {k}: inner radius {ri} vs {r_exact}"
            );
        }
        // The outline colour (black) reaches the image: the ring's pixels.
        let mid = (size / 2) as usize;
        let ring_px = (0..size as usize)
            .filter(|&x| {
                let p = &r.ldr[(mid * size as usize + x) * 3..][..3];
                p == [0, 0, 0]
            })
            .count();
        assert!(ring_px >= 2, "{ring_px}");
    }
}

#[test]
fn extruded_cube_outline_has_no_gaps_at_corners() {
    // Split normals: 24 vertices, each face its own normal. Smoothed, the
    // copies of a corner share the normalized sum of their face normals.
    let cube = specula::mesh::cube(1.0, 1);
    let smooth = specula_npr::extrude::smooth_normals(&cube.positions, &cube.normals);
    let third = 1.0 / 3f32.sqrt();
    for (p, n) in cube.positions.iter().zip(&smooth) {
        let want = p.signum() * third;
        assert!((*n - want).length() < 1e-6, "{p} → {n}");
    }
    let extra = "[[outline]]\nmethod = \"extrusion\"\nwidth = 1.5\n";
    let text = format!(
        r#"
[camera]
eye = [2.2, 1.9, 2.6]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 100.0

[output]
width = 160
height = 160

[[mesh]]
cube = {{ size = 1.0 }}
rotate = [10.0, 25.0, 5.0]

[[light]]
type = "directional"
direction = [-0.5, -0.4, -1.0]
irradiance = [3.0, 3.0, 3.0]
{extra}
"#
    );
    let s = common::scene(&text, &[]);
    let main_ids = s.data.triangles.len() as u32;
    let mut settings = RenderSettings::from_scene(&s);
    settings.buffers.id = true;
    let r = render_scene(&s, &settings, 0.0).unwrap();
    let ids = &r.frame.buffers.id;
    let w = 160usize;
    let (mut main, mut ring, mut touching) = (0, 0, Vec::new());
    for y in 1..w - 1 {
        for x in 1..w - 1 {
            let id = ids[y * w + x];
            if id == MISS {
                continue;
            }
            if id >= main_ids {
                ring += 1;
                continue;
            }
            main += 1;
            // 4-neighbours: a gap lets the background touch the cube along a
            // pixel side. (Diagonal contacts remain at three silhouette
            // corners, where the corner's smoothed normal is not the
            // corner's bisector on screen and the ring thins below 1 px.)
            for (dx, dy) in [(1i32, 0i32), (-1, 0), (0, 1), (0, -1)] {
                let j = (y as i32 + dy) as usize * w + (x as i32 + dx) as usize;
                if ids[j] == MISS {
                    touching.push((x, y, dx, dy));
                }
            }
        }
    }
    assert!(main > 1000 && ring > 200, "{main} {ring}");
    assert!(
        touching.is_empty(),
        "cube pixels next to the background: {touching:?}"
    );
}
