//! NPR lines end to end: the `[[outline]]` / `[strokes]` schema, the three
//! outline methods and the stroke overlays.

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
        ("[[outline]]\nmethod = \"shading\"\nantialias = false\n", "outline[0].antialias: not used"),
        ("[[outline]]\nmethod = \"sobel\"\nantialias = 1\n", "antialias"),
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
use specula_raster::FrameContext;

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
                (ring - width).abs() <= 0.5,
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
    let ssaa = 4usize;
    settings.ssaa = ssaa as u32;
    let r = render_scene(&s, &settings, 0.0).unwrap();
    let ids = &r.frame.buffers.id;
    let n = 160 * ssaa;
    let (main, ring) = ids.iter().fold((0, 0), |(m, k), &id| match id {
        MISS => (m, k),
        id if id < main_ids => (m + 1, k),
        _ => (m, k + 1),
    });
    assert!(
        main > 1000 * ssaa * ssaa && ring > 200 * ssaa * ssaa,
        "{main} {ring}"
    );
    let widths = min_ring_widths(ids, n, main_ids, ssaa);
    let (min, at) =
        widths
            .iter()
            .map(|&(d, x, y)| (d, (x, y)))
            .fold(
                (f64::INFINITY, (0, 0)),
                |a, b| if b.0 < a.0 { b } else { a },
            );
    let max = widths.iter().map(|w| w.0).fold(0.0, f64::max);
    // Sample centres are within a sample (¼ px) of the edges they lie
    // next to: the ring measured between centres is within ±¼ px of its
    // width; the smoothed normal alone thinned it to < 1 px at 3 corners.
    assert!(
        min >= 1.5 - 0.3 && max <= 1.5 + 0.5,
        "ring width {min:.3}..{max:.3} px (thinnest at sample {at:?}), want ≈ 1.5"
    );
}

/// The extrusion stage keeps its per-view vectors from view to view and
/// reuses the last view's positions: moved back and forth between views
/// (and widths, through the supersampling), it gives each exactly what a
/// fresh stage gives, bit for bit, on a closed mesh and an open one.
#[test]
fn an_extrusion_stage_moved_between_views_matches_a_fresh_one() {
    use specula_npr::extrude::Extrude;
    use specula_raster::geometry::VertexStage;
    let s = load(
        "[[mesh]]\nplane = { size = [3.0, 2.0], segments = [3, 2] }\n\
         translate = [0.0, 0.0, -1.5]\nmaterial = \"toon\"\n",
    )
    .unwrap();
    let data = &s.data;
    let view = |x: f32, ssaa: u32| {
        let mut camera = data.camera.clone();
        camera.eye.x += x;
        (camera.view(64 * ssaa, 64 * ssaa), ssaa)
    };
    let views = [
        view(0.0, 1),
        view(0.7, 1),
        view(0.0, 1),
        view(-1.3, 2),
        view(0.7, 1),
    ];
    let bits = |v: &[[f32; 4]]| v.iter().map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
    let mut moving = Extrude::new(data, 2.0);
    let mut out = Vec::new();
    for (i, (view, ssaa)) in views.iter().enumerate() {
        let frame = FrameContext { view, ssaa: *ssaa };
        for _ in 0..2 {
            out.clear();
            moving.clip_positions(&frame, &data.mesh(), &mut out);
            let mut fresh = Extrude::new(data, 2.0);
            let mut want = Vec::new();
            fresh.clip_positions(&frame, &data.mesh(), &mut want);
            assert_eq!(out.len(), data.positions.len());
            assert!(bits(&out) == bits(&want), "view {i}");
        }
    }
}

#[test]
fn a_lone_plane_gets_an_extrusion_ring_from_the_front_and_none_from_behind() {
    // An open mesh has no back faces behind its front ones: its copy is
    // drawn front side out, pushed across its boundary and just behind it.
    let scene = |eye: &str, double_sided: bool, outline: bool| {
        let extra = if outline {
            "[[outline]]\nmethod = \"extrusion\"\nwidth = 1.5\n"
        } else {
            ""
        };
        format!(
            r#"
[camera]
eye = {eye}
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 100.0

[output]
width = 160
height = 160

[[mesh]]
plane = {{ size = [1.6, 1.1], segments = [3, 2] }}
rotate = [0.0, 20.0, 0.0]
material = "sheet"

[materials.sheet]
model = "lambert"
base_color = [0.8, 0.5, 0.2]
double_sided = {double_sided}

[[light]]
type = "directional"
direction = [-0.5, -0.4, -1.0]
irradiance = [3.0, 3.0, 3.0]
{extra}
"#
        )
    };
    let ssaa = 4usize;
    let n = 160 * ssaa;
    let ids_of = |text: &str| {
        let s = common::scene(text, &[]);
        let mut settings = RenderSettings::from_scene(&s);
        settings.buffers.id = true;
        settings.ssaa = ssaa as u32;
        let r = render_scene(&s, &settings, 0.0).unwrap();
        (r.frame.buffers.id.clone(), s.data.triangles.len() as u32)
    };
    let above = "[1.2, 2.0, 3.2]"; // the plane faces +y: seen slanted from its front
    let below = "[1.2, -2.0, 3.2]";
    for (eye, double_sided, want_ring) in [
        (above, false, true),
        (below, false, false),
        (below, true, true),
    ] {
        let (ids, main_ids) = ids_of(&scene(eye, double_sided, true));
        let (plain, _) = ids_of(&scene(eye, double_sided, false));
        // The sheet itself wins the depth test everywhere it is drawn.
        for (i, (a, b)) in ids.iter().zip(&plain).enumerate() {
            assert_eq!(
                *a < main_ids,
                *b < main_ids && *b != MISS,
                "sample {i}: {a} vs {b}"
            );
        }
        let ring = ids
            .iter()
            .filter(|&&id| id != MISS && id >= main_ids)
            .count();
        if !want_ring {
            // A single-sided sheet seen from behind: nothing, and no ring.
            assert_eq!(ring, 0, "{eye}");
            assert!(!plain.iter().any(|&id| id != MISS));
            continue;
        }
        let widths = min_ring_widths(&ids, n, main_ids, ssaa);
        assert!(widths.len() > 400, "{}", widths.len());
        let min = widths.iter().map(|w| w.0).fold(f64::INFINITY, f64::min);
        let max = widths.iter().map(|w| w.0).fold(0.0, f64::max);
        assert!(
            min >= 1.5 - 0.3 && max <= 1.5 + 0.5,
            "{eye} double-sided {double_sided}: ring width {min:.3}..{max:.3} px, want ≈ 1.5"
        );
    }
}

/// For every sample of the main pass next to a sample that is not (the
/// object's outline on screen), the distance in output pixels from its
/// centre to the nearest background sample's centre: the ring's width
/// there. (distance, x, y) per such sample of an `n × n` id buffer.
fn min_ring_widths(ids: &[u32], n: usize, main_ids: u32, ssaa: usize) -> Vec<(f64, usize, usize)> {
    let main = |x: usize, y: usize| ids[y * n + x] != MISS && ids[y * n + x] < main_ids;
    let reach = 6 * ssaa as i64;
    let mut out = Vec::new();
    for y in 1..n - 1 {
        for x in 1..n - 1 {
            if !main(x, y)
                || [(1, 0), (0, 1), (-1, 0), (0, -1)]
                    .iter()
                    .all(|&(dx, dy)| main((x as i64 + dx) as usize, (y as i64 + dy) as usize))
            {
                continue;
            }
            let mut best = f64::INFINITY;
            for dy in -reach..=reach {
                for dx in -reach..=reach {
                    let (xx, yy) = (x as i64 + dx, y as i64 + dy);
                    if xx < 0 || yy < 0 || xx >= n as i64 || yy >= n as i64 {
                        continue;
                    }
                    if ids[yy as usize * n + xx as usize] == MISS {
                        best = best.min(((dx * dx + dy * dy) as f64).sqrt());
                    }
                }
            }
            out.push((best / ssaa as f64, x, y));
        }
    }
    out
}

use specula_npr::edges::{chain, EdgeKind, MeshEdges, Piece};

fn edges_of(mesh: &specula::mesh::MeshData, kinds: &[EdgeKind], crease: f32) -> MeshEdges {
    MeshEdges::new(
        &mesh.positions,
        &mesh.triangles,
        &mesh.tri_material,
        kinds,
        crease,
    )
}

fn count(es: &[(u32, u32, EdgeKind)], k: EdgeKind) -> usize {
    es.iter().filter(|e| e.2 == k).count()
}

#[test]
fn edge_extraction_on_a_cube_and_a_plane() {
    let eye = glam::Vec3::new(3.0, 2.5, 2.0);
    // A cube's 12 edges are 90° creases; its 6 face diagonals are flat.
    let cube = specula::mesh::cube(1.0, 1);
    let e = edges_of(&cube, &[EdgeKind::Crease], 60.0);
    assert_eq!(e.edge_count(), 18);
    assert_eq!(count(&e.classify(eye), EdgeKind::Crease), 12);
    assert_eq!(
        edges_of(&cube, &[EdgeKind::Crease], 95.0)
            .classify(eye)
            .len(),
        0
    );
    // Subdivided, the cube still has 12 creases, cut into 3 edges each.
    let cube3 = specula::mesh::cube(1.0, 3);
    assert_eq!(
        count(
            &edges_of(&cube3, &[EdgeKind::Crease], 60.0).classify(eye),
            EdgeKind::Crease
        ),
        36
    );

    // From a corner, three faces look at the eye and three away: the
    // silhouette is the hexagon between them, one closed loop of 6 edges.
    let e = edges_of(&cube, &[EdgeKind::Silhouette], 60.0);
    let sil = e.classify(eye);
    assert_eq!(count(&sil, EdgeKind::Silhouette), 6);
    let pieces: Vec<Piece> = sil
        .iter()
        .map(|&(a, b, kind)| {
            let s = |v: u32| [e.points[v as usize].x, e.points[v as usize].y];
            Piece {
                kind,
                a: s(a),
                b: s(b),
                ends: [Some(a), Some(b)],
            }
        })
        .collect();
    let lines = chain(&pieces);
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(lines[0].closed && lines[0].points.len() == 6);

    // A plane has 4 boundary edges; a 3 × 2 grid of cells 10.
    let plane = specula::mesh::plane([1.0, 1.0], [1, 1]);
    let e = edges_of(&plane, &[EdgeKind::Boundary, EdgeKind::Crease], 60.0);
    assert_eq!(count(&e.classify(eye), EdgeKind::Boundary), 4);
    assert_eq!(e.classify(eye).len(), 4);
    let grid = specula::mesh::plane([1.0, 1.0], [3, 2]);
    assert_eq!(
        count(
            &edges_of(&grid, &[EdgeKind::Boundary], 60.0).classify(eye),
            EdgeKind::Boundary
        ),
        10
    );
}

const STROKE_SPHERE: &str =
    "[strokes]\nedges = [\"silhouette\"]\nwidth = 2.0\ncolor = [0.0, 0.0, 1.0]\n";

#[test]
fn uv_sphere_silhouette_is_one_closed_polyline_and_the_svg_matches_the_png() {
    let s = common::scene(&sphere_scene(1.0, 4.0, 160, STROKE_SPHERE), &[]);
    let settings = RenderSettings::from_scene(&s);
    let r = render_scene(&s, &settings, 0.0).unwrap();
    let st = s.lines.strokes.as_ref().unwrap();
    let lines = st.polylines(&r.frame.buffers, 1);
    assert_eq!(
        lines.len(),
        1,
        "{:?}",
        lines.iter().map(|l| l.points.len()).collect::<Vec<_>>()
    );
    assert!(lines[0].closed && lines[0].points.len() > 100);
    // Each point lies on the exact sphere's outline, radius f·tan(asin(1/4)).
    let f = 80.0 / 20f64.to_radians().tan();
    let r_exact = f * 0.25f64.asin().tan();
    for p in &lines[0].points {
        let d = ((p[0] as f64 - 80.0).powi(2) + (p[1] as f64 - 80.0).powi(2)).sqrt();
        assert!((d - r_exact).abs() < 0.5, "{p:?} at {d} vs {r_exact}");
    }

    let doc = specula_npr::overlay::svg(&lines, &st.style, r.width, r.height);
    let xml = roxmltree::Document::parse(&doc).expect("SVG parses");
    let root = xml.root_element();
    assert_eq!(root.tag_name().name(), "svg");
    assert_eq!(root.attribute("width"), Some("160"));
    let groups: Vec<_> = root.children().filter(|n| n.has_tag_name("g")).collect();
    assert_eq!(groups.len(), 1);
    assert_eq!(groups[0].attribute("id"), Some("silhouette"));
    let paths: Vec<_> = groups[0]
        .children()
        .filter(|n| n.has_tag_name("path"))
        .collect();
    assert_eq!(paths.len(), 1);
    // The path's vertices fall on stroke-coloured (blue) pixels of the PNG.
    let d = paths[0].attribute("d").unwrap();
    let nums: Vec<f32> = d
        .split(|c: char| c == ' ' || c.is_ascii_alphabetic())
        .filter(|t| !t.is_empty())
        .map(|t| t.parse().unwrap())
        .collect();
    assert!(d.ends_with('Z') && nums.len() == 2 * lines[0].points.len());
    for xy in nums.chunks(2) {
        let (x, y) = (xy[0] as usize, xy[1] as usize);
        let px = &r.ldr[(y * 160 + x) * 3..][..3];
        assert!(
            px[2] > 200 && px[0] < 80 && px[1] < 80,
            "({x}, {y}): {px:?}"
        );
    }
}

/// Random polylines over a `w × h` image (some reaching past its edges),
/// from a xorshift64* generator seeded with `seed`.
fn random_polylines(seed: u64, n: usize, w: f32, h: f32) -> Vec<specula_npr::edges::Polyline> {
    let mut state = seed.max(1);
    let mut next = move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..n)
        .map(|_| {
            let mut p = [next() * (w + 40.0) - 20.0, next() * (h + 40.0) - 20.0];
            let len = 2 + (next() * 30.0) as usize;
            let points = (0..len)
                .map(|_| {
                    p = [p[0] + next() * 30.0 - 15.0, p[1] + next() * 30.0 - 15.0];
                    p
                })
                .collect();
            specula_npr::edges::Polyline {
                kind: EdgeKind::Silhouette,
                points,
                closed: next() < 0.3,
            }
        })
        .collect()
}

#[test]
fn the_banded_stroke_drawing_is_close_to_one_surface_and_alike_for_any_thread_count() {
    use specula_npr::overlay::{draw, Canvases, LineCap, LineJoin, StrokeStyle};
    use specula_raster::post::HdrImage;
    use specula_raster::Planes3;
    // Frames in sequence on the same canvases (cleared for each frame), in
    // several styles: plain, tapered and wide with miters, thin (≤ 1 px),
    // and an image of another size.
    let style = |width, taper, join, cap| StrokeStyle {
        width,
        color: [0.1, 0.7, 0.3],
        taper,
        join,
        cap,
    };
    let frames = [
        (
            320u32,
            180u32,
            style(1.5, 0.0, LineJoin::Round, LineCap::Round),
        ),
        (320, 180, style(4.0, 0.6, LineJoin::Miter, LineCap::Butt)),
        (320, 180, style(0.8, 0.0, LineJoin::Bevel, LineCap::Square)),
        (
            211,
            97,
            style(2.5, 0.0, LineJoin::MiterClip, LineCap::Square),
        ),
        (320, 180, style(1.5, 1.0, LineJoin::Round, LineCap::Round)),
    ];
    let mut canvases: Vec<(usize, Canvases)> = [1, 2, 3, 5]
        .into_iter()
        .map(|t| (t, Canvases::default()))
        .collect();
    for (f, (w, h, style)) in frames.iter().enumerate() {
        let n = (*w * *h) as usize;
        let base = Planes3 {
            r: (0..n).map(|i| (i % 7) as f32 * 0.1).collect(),
            g: (0..n).map(|i| (i % 11) as f32 * 0.05).collect(),
            b: vec![0.5; n],
        };
        let mut lines = random_polylines(f as u64 + 1, 60, *w as f32, *h as f32);
        // With miter-clip joins tiny-skia strokes this open line with a
        // spike reaching from (148, 68) up to (205, 0), far past w/2 × the
        // miter limit: a band must find it from the outline.
        let spike = [
            [133.54846, 73.255135],
            [122.72453, 71.96292],
            [137.09325, 70.19038],
            [131.85338, 78.02054],
            [129.19615, 90.21964],
            [135.63847, 90.2817],
            [144.09708, 79.71104],
            [138.30843, 87.255394],
            [145.40562, 94.43113],
            [150.02773, 103.904434],
            [139.26172, 94.97095],
            [141.4594, 80.00783],
            [147.84268, 82.69324],
            [148.95003, 68.15663],
        ];
        lines.push(specula_npr::edges::Polyline {
            kind: EdgeKind::Silhouette,
            points: spike.to_vec(),
            closed: false,
        });
        // The plain drawing: every draw on one surface of the whole image,
        // the coverage blended pixel by pixel.
        let cov = draw(&lines, style, *w, *h);
        let mut reference = base.clone();
        let c = style.color;
        for (i, &a) in cov.iter().enumerate() {
            if a > 0.0 {
                reference.r[i] = reference.r[i] * (1.0 - a) + c[0] * a;
                reference.g[i] = reference.g[i] * (1.0 - a) + c[1] * a;
                reference.b[i] = reference.b[i] * (1.0 - a) + c[2] * a;
            }
        }
        let stroked = cov.iter().filter(|&&a| a > 0.0).count();
        assert!(stroked > n / 20, "frame {f}: few strokes");
        // Against the plain drawing: a band clips the paths that cross
        // its surface's edges, and tiny-skia steps a clipped edge from
        // where the clip cut it, so along such an edge a pixel may gain or
        // lose one of its 16 supersamples (coverage 16/255; at most 1 % of
        // the stroked pixels); a stroke lost or drawn twice at a band's
        // edge would differ by far more. Between thread counts: the same
        // bits.
        let mut first: Option<Planes3> = None;
        for (threads, cv) in canvases.iter_mut() {
            let mut img = HdrImage {
                width: *w,
                height: *h,
                rgb: base.clone(),
            };
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(*threads)
                .build()
                .unwrap();
            pool.install(|| cv.blend(&lines, style, &mut img));
            let (mut differ, mut worst) = (0usize, 0f32);
            for i in 0..n {
                let d = [
                    (img.rgb.r[i] - reference.r[i]).abs(),
                    (img.rgb.g[i] - reference.g[i]).abs(),
                    (img.rgb.b[i] - reference.b[i]).abs(),
                ];
                let d = d[0].max(d[1]).max(d[2]);
                differ += usize::from(d > 0.0);
                worst = worst.max(d);
            }
            assert!(
                worst <= 16.0 / 255.0 + 1e-6 && differ * 100 <= stroked,
                "frame {f}, {threads} threads: {differ} of {stroked} stroked pixels differ, worst {worst}"
            );
            match &first {
                None => first = Some(img.rgb),
                Some(want) => {
                    for (name, got, want) in [
                        ("r", &img.rgb.r, &want.r),
                        ("g", &img.rgb.g, &want.g),
                        ("b", &img.rgb.b, &want.b),
                    ] {
                        let bad = got
                            .iter()
                            .zip(want.iter())
                            .position(|(a, b)| a.to_bits() != b.to_bits());
                        assert!(
                            bad.is_none(),
                            "frame {f}, {threads} threads: {name} differs from 1 thread's at pixel {bad:?}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn a_partly_hidden_silhouette_is_one_polyline_per_visible_run() {
    // A sphere whose outline a box hides on the right and a thin bar
    // crosses on the left: two visible arcs, top and bottom.
    let extra = format!(
        r#"
[[mesh]]
cube = {{ size = 0.8 }}
translate = [0.7, 0.0, 1.5]
material = "toon"

[[mesh]]
cube = {{ size = 1.0 }}
scale = [0.3, 2.0, 0.08]
translate = [-0.6, 0.0, 1.5]
material = "toon"

{STROKE_SPHERE}"#
    );
    let s = common::scene(&sphere_scene(1.0, 4.0, 640, &extra), &[]);
    let r = render_scene(&s, &RenderSettings::from_scene(&s), 0.0).unwrap();
    let lines = s
        .lines
        .strokes
        .as_ref()
        .unwrap()
        .polylines(&r.frame.buffers, 1);
    // The sphere's polylines: every point on its exact outline.
    let f = 320.0 / 20f64.to_radians().tan();
    let r_exact = f * 0.25f64.asin().tan();
    let on_sphere = |p: &[f32; 2]| {
        let d = ((p[0] as f64 - 320.0).powi(2) + (p[1] as f64 - 320.0).powi(2)).sqrt();
        (d - r_exact).abs() < 0.75
    };
    let arcs: Vec<_> = lines
        .iter()
        .filter(|l| l.points.iter().filter(|p| on_sphere(p)).count() * 2 > l.points.len())
        .collect();
    assert_eq!(
        arcs.len(),
        2,
        "{:?}",
        arcs.iter()
            .map(|l| (l.points.len(), l.points[0]))
            .collect::<Vec<_>>()
    );
    for a in &arcs {
        assert!(!a.closed && a.points.len() > 20, "{a:?}");
        assert!(a.points.iter().all(on_sphere), "{a:?}");
    }
    // The two runs cover the visible outline: their ends lie at the box
    // and the bar, one arc above the centre, one below.
    let mut tops: Vec<bool> = arcs
        .iter()
        .map(|a| a.points[a.points.len() / 2][1] < 320.0)
        .collect();
    tops.sort();
    assert_eq!(tops, vec![false, true]);
    // And the whole overlay is few polylines (the box and the bar's
    // outlines besides), not one per partly hidden edge.
    assert!(
        lines.len() <= 6,
        "{} polylines: {:?}",
        lines.len(),
        lines.iter().map(|l| l.points.len()).collect::<Vec<_>>()
    );
}

#[test]
fn an_edge_behind_another_object_is_dropped_and_one_in_front_kept() {
    let text = r#"
[camera]
eye = [0.0, 0.0, 6.0]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 100.0

[output]
width = 160
height = 160

[[mesh]]
sphere = { radius = 1.0, segments = 64, rings = 32 }

# Behind the sphere, hidden by it.
[[mesh]]
plane = { size = [0.4, 0.4] }
rotate = [90.0, 0.0, 0.0]
translate = [0.0, 0.0, -3.0]

# In front of it, seen.
[[mesh]]
plane = { size = [0.4, 0.4] }
rotate = [90.0, 0.0, 0.0]
translate = [0.0, 0.5, 2.0]

[[light]]
type = "directional"
direction = [0.0, 0.0, -1.0]
irradiance = [3.0, 3.0, 3.0]

[strokes]
edges = ["boundary"]
"#;
    let s = common::scene(text, &[]);
    let r = render_scene(&s, &RenderSettings::from_scene(&s), 0.0).unwrap();
    let lines = s
        .lines
        .strokes
        .as_ref()
        .unwrap()
        .polylines(&r.frame.buffers, 1);
    // Project a world point as the camera does (independently, f64).
    let f = 80.0 / 20f64.to_radians().tan();
    let proj = |p: [f64; 3]| {
        [
            80.0 + f * p[0] / (6.0 - p[2]),
            80.0 - f * p[1] / (6.0 - p[2]),
        ]
    };
    let near = |q: [f32; 2], p: [f64; 2]| {
        ((q[0] as f64 - p[0]).abs() < 1.0) && ((q[1] as f64 - p[1]).abs() < 1.0)
    };
    let front: Vec<[f64; 2]> = [[-0.2, 0.3], [0.2, 0.3], [0.2, 0.7], [-0.2, 0.7]]
        .map(|[x, y]| proj([x, y, 2.0]))
        .to_vec();
    let back: Vec<[f64; 2]> = [[-0.2, -0.2], [0.2, -0.2], [0.2, 0.2], [-0.2, 0.2]]
        .map(|[x, y]| proj([x, y, -3.0]))
        .to_vec();
    let all: Vec<[f32; 2]> = lines.iter().flat_map(|l| l.points.clone()).collect();
    // The front square: one closed polyline through its four corners.
    assert!(lines.iter().any(|l| l.closed
        && l.points.len() == 4
        && front.iter().all(|c| l.points.iter().any(|q| near(*q, *c)))));
    // Nothing of the hidden square (its corners project inside the sphere).
    for c in &back {
        assert!(
            !all.iter().any(|q| near(*q, *c)),
            "hidden corner {c:?} drawn"
        );
    }
    // A cube resting on a floor: its bottom front edge touches the floor,
    // whose depth there equals the edge's; the bias must not eat it.
    let text = r#"
[camera]
eye = [0.0, 2.0, 6.0]
target = [0.0, 0.3, 0.0]
fov_y = 40.0
near = 0.1
far = 100.0

[output]
width = 160
height = 160

[[mesh]]
plane = { size = [20.0, 20.0] }

[[mesh]]
cube = { size = 1.0 }
translate = [0.0, 0.5, 0.0]

[[light]]
type = "directional"
direction = [0.0, -1.0, -1.0]
irradiance = [3.0, 3.0, 3.0]

[strokes]
edges = ["crease"]
"#;
    let s = common::scene(text, &[]);
    let r = render_scene(&s, &RenderSettings::from_scene(&s), 0.0).unwrap();
    let lines = s
        .lines
        .strokes
        .as_ref()
        .unwrap()
        .polylines(&r.frame.buffers, 1);
    let view = s.data.camera.view(160, 160);
    let proj = |p: glam::Vec3| {
        let c = view.view_proj * p.extend(1.0);
        [
            (c.x / c.w * 0.5 + 0.5) * 160.0,
            (0.5 - c.y / c.w * 0.5) * 160.0,
        ]
    };
    // Points every 0.05 along the bottom front edge are each within a
    // pixel of a drawn segment.
    let seg_dist = |p: [f32; 2], a: [f32; 2], b: [f32; 2]| {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy).max(1e-12))
            .clamp(0.0, 1.0);
        ((a[0] + t * dx - p[0]).powi(2) + (a[1] + t * dy - p[1]).powi(2)).sqrt()
    };
    for k in 0..=20 {
        let p = proj(glam::Vec3::new(-0.5 + k as f32 * 0.05, 0.0, 0.5));
        let d = lines
            .iter()
            .flat_map(|l| {
                let n = l.points.len();
                let segs = if l.closed { n } else { n - 1 };
                (0..segs).map(move |i| (l.points[i], l.points[(i + 1) % n]))
            })
            .map(|(a, b)| seg_dist(p, a, b))
            .fold(f32::INFINITY, f32::min);
        assert!(
            d < 1.0,
            "contact edge point {k} at {p:?}: nearest line {d} px"
        );
    }
}

#[test]
fn svg_lines_flag_writes_the_overlay_and_refuses_scenes_without_strokes() {
    let dir = common::temp_dir("svg-lines");
    std::fs::write(
        dir.join("s.toml"),
        sphere_scene(1.0, 4.0, 64, STROKE_SPHERE),
    )
    .unwrap();
    std::fs::write(dir.join("plain.toml"), sphere_scene(1.0, 4.0, 64, "")).unwrap();
    let out = common::specula(
        &["render", "s.toml", "-o", "s.png", "--svg-lines", "s.svg"],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc = std::fs::read_to_string(dir.join("s.svg")).unwrap();
    let xml = roxmltree::Document::parse(&doc).unwrap();
    assert_eq!(
        xml.descendants().filter(|n| n.has_tag_name("path")).count(),
        1
    );
    let out = common::specula(
        &[
            "render",
            "plain.toml",
            "-o",
            "p.png",
            "--svg-lines",
            "p.svg",
        ],
        &dir,
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--svg-lines") && err.contains("[strokes]"),
        "{err}"
    );
    assert!(!dir.join("p.png").exists());
    // An output naming the scene itself is refused like any other output.
    let out = common::specula(
        &["render", "s.toml", "-o", "t.png", "--svg-lines", "s.toml"],
        &dir,
    );
    assert!(!out.status.success());
}

#[test]
fn outline_and_stroke_scenes_bytes_do_not_depend_on_the_thread_count() {
    let dir = common::fixtures().join("scenes");
    for (file, w, h, ssaa) in [
        ("npr-outlines.toml", 480, 270, 2),
        ("npr-strokes.toml", 320, 180, 2),
    ] {
        let s = specula::scene::load_scene(&dir.join(file)).unwrap_or_else(|e| panic!("{e}"));
        let mut images = Vec::new();
        let mut svgs = Vec::new();
        for threads in [1, 2, 8] {
            let mut settings = RenderSettings::from_scene(&s);
            settings.width = w;
            settings.height = h;
            settings.ssaa = ssaa;
            settings.threads = Some(threads);
            let r = render_scene(&s, &settings, 0.0).expect("render");
            if let Some(st) = &s.lines.strokes {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let lines = pool.install(|| st.polylines(&r.frame.buffers, ssaa as usize));
                assert!(lines.len() > 10, "{file}: {} polylines", lines.len());
                svgs.push(specula_npr::overlay::svg(&lines, &st.style, w, h));
            }
            images.push(r.ldr);
        }
        // Lines were drawn: the line colour (near black) is in the image.
        let dark = images[0]
            .chunks(3)
            .filter(|p| p.iter().all(|&c| c < 90))
            .count();
        assert!(dark > 200, "{file}: {dark} dark pixels");
        for (i, im) in images.iter().enumerate().skip(1) {
            assert!(
                im == &images[0],
                "{file}: bytes differ between 1 thread and run {i}"
            );
        }
        for (i, sv) in svgs.iter().enumerate().skip(1) {
            assert!(
                sv == &svgs[0],
                "{file}: SVG differs between 1 thread and run {i}"
            );
        }
    }
}

#[test]
fn sobel_outline_leaves_a_slanted_floor_clean_and_outlines_a_box_on_it() {
    let scene = |with_box: bool| {
        format!(
            r#"
[camera]
eye = [0.0, 1.0, 6.0]
target = [0.0, 0.4, 0.0]
fov_y = 40.0
near = 0.1
far = 100.0

[output]
width = 160
height = 120

[[mesh]]
plane = {{ size = [200.0, 200.0] }}
rotate = [0.0, 30.0, 0.0]

{}

[[light]]
type = "directional"
direction = [-0.3, -1.0, -0.4]
irradiance = [1.0, 1.0, 1.0]

[[outline]]
method = "sobel"
width = 1.5
color = [1.0, 0.0, 0.0]
sources = ["depth", "normal", "id"]
threshold = {{ depth = 0.05, normal = 0.2, id = 0.3 }}
"#,
            if with_box {
                "[[mesh]]\ncube = { size = 1.0 }\ntranslate = [0.0, 0.5, 0.0]\nmaterial = \"box\"\n\n[materials.box]\nmodel = \"lambert\"\nbase_color = [0.2, 0.2, 0.8]"
            } else {
                ""
            }
        )
    };
    let red = |px: &[u8]| px[0] > 150 && px[1] < 60 && px[2] < 60;
    // The floor alone: from a grazing 9.5° its depth runs from ~6 to ~100
    // down the image, but it is a plane: no line below its horizon.
    let s = common::scene(&scene(false), &[]);
    let r = render_scene(&s, &RenderSettings::from_scene(&s), 0.0).unwrap();
    let horizon = (0..120)
        .find(|y| r.frame.buffers.depth[y * 160 + 80].is_finite())
        .unwrap();
    assert!(horizon > 20 && horizon < 70, "horizon row {horizon}");
    let lines_below: usize = (horizon + 3..120)
        .map(|y| {
            (0..160)
                .filter(|x| red(&r.ldr[(y * 160 + x) * 3..][..3]))
                .count()
        })
        .sum();
    assert_eq!(lines_below, 0);
    // With a box standing on it: its outline is drawn.
    let s = common::scene(&scene(true), &[]);
    let r = render_scene(&s, &RenderSettings::from_scene(&s), 0.0).unwrap();
    let lines: usize = (horizon + 3..120)
        .map(|y| {
            (0..160)
                .filter(|x| red(&r.ldr[(y * 160 + x) * 3..][..3]))
                .count()
        })
        .sum();
    assert!(lines > 50, "{lines} line pixels");
}

#[test]
fn outline_materials_limit_each_method_to_their_objects() {
    // Two spheres side by side, materials "a" (left) and "b" (right); each
    // outline names "a" only.
    let two = |outline: &str| {
        format!(
            r#"
[camera]
eye = [0.0, 0.0, 6.0]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 100.0

[output]
width = 160
height = 96

[[mesh]]
sphere = {{ radius = 0.8, segments = 64, rings = 32 }}
translate = [-1.2, 0.0, 0.0]
material = "a"

[[mesh]]
sphere = {{ radius = 0.8, segments = 64, rings = 32 }}
translate = [1.2, 0.0, 0.0]
material = "b"

[materials.a]
model = "unlit"
color = [1.0, 1.0, 1.0]

[materials.b]
model = "unlit"
color = [1.0, 1.0, 1.0]

[environment]
uniform = [1.0, 1.0, 1.0]

[[outline]]
{outline}
color = [0.0, 0.0, 0.0]
materials = ["a"]
"#
        )
    };
    for method in [
        "method = \"extrusion\"\nwidth = 2.0",
        "method = \"sobel\"\nwidth = 2.0",
        "method = \"shading\"\nthreshold = 0.4",
    ] {
        let s = common::scene(&two(method), &[]);
        let r = render_scene(&s, &RenderSettings::from_scene(&s), 0.0).unwrap();
        // White everywhere but the lines: count dark pixels per half.
        let dark = |x0: usize, x1: usize| {
            (0..96)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .filter(|(x, y)| r.ldr[(y * 160 + x) * 3] < 128)
                .count()
        };
        let (left, right) = (dark(0, 80), dark(80, 160));
        assert!(
            left > 60 && right == 0,
            "{method}: {left} left, {right} right"
        );
    }
}

/// A vertex stage with its shortcuts off, to compare a frame with and
/// without them: no front-face mask (setup decides every face), and, with
/// `keep_hidden` false, no pass reported hidden (every pass drawn).
#[derive(Debug)]
struct Shortcuts {
    inner: Box<dyn specula_raster::VertexStage>,
    keep_hidden: bool,
}

impl Shortcuts {
    fn without_hidden(inner: Box<dyn specula_raster::VertexStage>) -> Shortcuts {
        Shortcuts {
            inner,
            keep_hidden: false,
        }
    }

    fn without_mask(inner: Box<dyn specula_raster::VertexStage>) -> Shortcuts {
        Shortcuts {
            inner,
            keep_hidden: true,
        }
    }
}

impl specula_raster::VertexStage for Shortcuts {
    fn instance(&self) -> Box<dyn specula_raster::VertexStage> {
        Box::new(Shortcuts {
            inner: self.inner.instance(),
            keep_hidden: self.keep_hidden,
        })
    }

    fn clip_positions(
        &mut self,
        frame: &FrameContext,
        scene: &specula_raster::SceneMesh,
        out: &mut Vec<[f32; 4]>,
    ) {
        self.inner.clip_positions(frame, scene, out)
    }

    fn hidden(&self, triangles: std::ops::Range<u32>) -> bool {
        self.keep_hidden && self.inner.hidden(triangles)
    }
}

/// A flat open piece's copy (the ground under a sphere) whose boundary is
/// off screen cannot show: the stage reports its pass hidden and the frame
/// skips it, with the same visibility buffer bit for bit as drawing it
/// (a stage that never reports hidden). With the boundary on screen the
/// copy is drawn and its ring shows.
#[test]
fn an_open_plane_copy_is_skipped_only_when_its_boundary_is_off_screen() {
    use specula_raster::frame::{visibility, FrameStats};
    use specula_raster::geometry::{Cull, GeometryPass};
    use specula_raster::Target;
    use std::sync::Arc;

    let scene = |size: f32| {
        format!(
            r#"
[camera]
eye = [0.3, 8.0, 1.0]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 100.0

[output]
width = 96
height = 72

[[mesh]]
plane = {{ size = [{size}, {size}] }}
rotate = [0.0, 25.0, 0.0]
material = "ground"

[[mesh]]
sphere = {{ radius = 0.5, segments = 24, rings = 12 }}
translate = [0.0, 0.5, 0.0]
material = "ground"

[materials.ground]
model = "lambert"
base_color = [0.8, 0.5, 0.2]

[[light]]
type = "directional"
direction = [-0.5, -1.0, -0.4]
irradiance = [3.0, 3.0, 3.0]

[[outline]]
method = "extrusion"
width = 1.5
"#
        )
    };
    for (size, off_screen) in [(20.0, true), (3.0, false)] {
        let s = common::scene(&scene(size), &[]);
        let data = &s.data;
        let target = Target::new(96, 72).unwrap();
        let main_ids = data.triangles.len() as u32;
        // The open pieces' pass: the outline's front-face one.
        let open: Vec<&GeometryPass> = (data.geometry.iter())
            .filter(|p| p.name == "outline-extrusion" && p.cull == Cull::Back)
            .collect();
        assert_eq!(open.len(), 1, "size {size}");
        let view = data.camera.view(96, 72);
        let frame = FrameContext {
            view: &view,
            ssaa: 1,
        };
        let mut stage = open[0].vertex.instance();
        stage.clip_positions(&frame, &data.mesh(), &mut Vec::new());
        assert_eq!(
            stage.hidden(open[0].triangles.clone()),
            off_screen,
            "size {size}"
        );
        let mut drawn = data.clone().into_parts();
        for p in drawn.geometry.iter_mut().skip(1) {
            p.vertex = Arc::new(Shortcuts::without_hidden(p.vertex.instance()));
        }
        let drawn = specula_raster::SceneData::new(drawn).unwrap();
        let (mut st_a, mut st_b) = (FrameStats::default(), FrameStats::default());
        let a = visibility(data, &target, &mut st_a);
        let b = visibility(&drawn, &target, &mut st_b);
        let bits = |d: &[f32]| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(a.vis.id == b.vis.id, "size {size}: ids differ");
        assert!(bits(&a.vis.depth) == bits(&b.vis.depth), "size {size}");
        let skipped = st_a.counts.culled_occluded - st_b.counts.culled_occluded;
        let copy = open[0].triangles.len() as u64;
        assert_eq!(skipped, if off_screen { copy } else { 0 });
        // The sphere's ring shows either way; the plane's only when its
        // boundary is on screen.
        let ring = |lo: u32, hi: u32| (a.vis.id.iter()).filter(|&&id| id >= lo && id < hi).count();
        let plane_ids = open[0].ids();
        assert!(ring(main_ids, u32::MAX - 1) > 50, "size {size}");
        let plane_ring = ring(plane_ids.start as u32, plane_ids.end as u32);
        assert_eq!(plane_ring > 0, !off_screen, "size {size}: {plane_ring}");
    }
}

/// The front faces the extrusion stage shows culled skip setup in the
/// outline's back-face pass: the visibility buffer (depth and id bits) and
/// every setup count are those of the same passes set up triangle by
/// triangle, in views where the meshes are whole, cut by the image's
/// edges, crossing the near plane and seen with supersampling; and most
/// of the front faces are skipped (a third at least; those off the image
/// or too small for the f32 test go to setup).
#[test]
fn extrusion_front_faces_skipped_before_setup_change_nothing() {
    use specula_raster::frame::{visibility, FrameStats};
    use specula_raster::geometry::Cull;
    use specula_raster::Target;
    use std::sync::Arc;

    let scene = |eye: [f32; 3], ssaa: u32| {
        format!(
            r#"
[camera]
eye = {eye:?}
target = [0.0, 0.0, 0.0]
fov_y = 50.0
near = 0.3
far = 100.0

[output]
width = 80
height = 60
ssaa = {ssaa}

[[mesh]]
sphere = {{ radius = 1.0, segments = 48, rings = 24 }}
material = "toon"

[[mesh]]
cube = {{ size = 1.2 }}
translate = [1.8, 0.4, -0.5]
rotate = [20.0, 35.0, 0.0]
material = "toon"

[[mesh]]
sphere = {{ radius = 0.6, segments = 16, rings = 8 }}
translate = [-2.2, -0.3, 0.8]
material = "toon"

[materials.toon]
model = "lambert"
base_color = [0.8, 0.5, 0.2]

[[light]]
type = "directional"
direction = [-0.5, -0.4, -1.0]
irradiance = [3.0, 3.0, 3.0]

[[outline]]
method = "extrusion"
width = 2.0
"#
        )
    };
    let views = [
        ([0.0, -1.0, 5.0], 1),  // all on screen
        ([0.5, 0.3, 2.2], 1),   // cut by the image's edges
        ([-1.9, -0.2, 1.2], 1), // the small sphere across the near plane
        ([3.0, -4.0, 2.5], 2),  // supersampled
    ];
    for (eye, ssaa) in views {
        let s = common::scene(&scene(eye, ssaa), &[]);
        let data = &s.data;
        let target = Target::new(80 * ssaa, 60 * ssaa).unwrap().with_ssaa(ssaa);
        let mut plain = data.clone().into_parts();
        for p in plain.geometry.iter_mut().skip(1) {
            p.vertex = Arc::new(Shortcuts::without_mask(p.vertex.instance()));
        }
        let plain = specula_raster::SceneData::new(plain).unwrap();
        let (mut st_a, mut st_b) = (FrameStats::default(), FrameStats::default());
        let a = visibility(data, &target, &mut st_a);
        let b = visibility(&plain, &target, &mut st_b);
        let bits = |d: &[f32]| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(a.vis.id == b.vis.id, "eye {eye:?}: ids differ");
        assert!(bits(&a.vis.depth) == bits(&b.vis.depth), "eye {eye:?}");
        assert_eq!(st_a.counts, st_b.counts, "eye {eye:?}");
        assert_eq!(st_a.raster_triangles, st_b.raster_triangles);
        // The mask of the back-face pass (right after the frame's view).
        let pass = (data.geometry.iter())
            .find(|p| p.name == "outline-extrusion" && p.cull == Cull::Front)
            .expect("a back-face pass");
        let mask = (a.stage(&pass.vertex))
            .and_then(|stage| stage.front_faces())
            .expect("a mask for the frame's view");
        let skipped: u32 = (pass.triangles.clone())
            .map(|t| (mask[t as usize / 64] >> (t % 64) & 1) as u32)
            .sum();
        // Half the faces culled are the main pass's back faces, about.
        let culled = st_a.counts.culled_backface as f64 / 2.0;
        assert!(
            skipped as f64 > 0.3 * culled,
            "eye {eye:?}: {skipped} of ~{culled} front faces shown"
        );
    }
}
