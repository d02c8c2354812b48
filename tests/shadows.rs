//! Shadow maps end to end: the scene fields' checks, and acne and
//! peter-panning measured against analytic visibility on a floor lit at
//! 10°–80° above the horizon (an empty floor must be lit everywhere; a box
//! standing on it casts a shadow whose exact extent is a ray–box test).

mod common;

use glam::Vec3;
use specula::scene::LoadedScene;
use specula_raster::shadow_pass::pixel_shadows;
use specula_raster::{visibility, FrameStats, Target};

const SIDE: u32 = 256;

/// The camera and output of the floor scenes, and the floor (12 × 12,
/// facing +Y, material "floor"), seen from above at an angle at
/// `SIDE` × `SIDE` (256).
const FLOOR_VIEW: &str = r#"
[camera]
eye = [-1.0, 5.0, 3.0]
target = [-1.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 45.0
near = 0.1
far = 50.0
[output]
width = 256
height = 256
[[mesh]]
plane = { size = [12.0, 12.0] }
material = "floor"
"#;
const _: () = assert!(SIDE == 256, "FLOOR_VIEW's output size is SIDE");

/// A floor (12 × 12, facing +Y), optionally a unit box standing on it at
/// the origin, under one directional light `elevation` degrees above the
/// horizon, seen from above at an angle.
fn floor_scene(elevation: f64, with_box: bool, filter: &str) -> LoadedScene {
    let e = elevation.to_radians();
    // Light travels down toward −x (the shadow falls toward −x).
    let dir = [-e.cos(), -e.sin(), 0.0];
    let cube = if with_box {
        "[[mesh]]\ncube = { size = 1.0 }\ntranslate = [0.0, 0.5, 0.0]\nmaterial = \"floor\"\n"
    } else {
        ""
    };
    let text = format!(
        r#"{FLOOR_VIEW}
{cube}
[materials.floor]
model = "lambert"
base_color = [0.5, 0.5, 0.5]
[[light]]
type = "directional"
direction = [{}, {}, {}]
irradiance = [1.0, 1.0, 1.0]
shadows = "{filter}"
shadow_map_size = 1024
"#,
        dir[0], dir[1], dir[2]
    );
    common::scene(&text, &[])
}

/// Whether the ray from `p` toward `to_light` meets the unit box standing
/// on the floor at the origin (slab test, in f64).
fn box_blocks(p: Vec3, to_light: Vec3) -> bool {
    let (lo, hi) = ([-0.5f64, 0.0, -0.5], [0.5f64, 1.0, 0.5]);
    let (o, d) = (p.as_dvec3().to_array(), to_light.as_dvec3().to_array());
    let (mut t0, mut t1) = (1e-6f64, f64::INFINITY);
    for k in 0..3 {
        if d[k].abs() < 1e-12 {
            if o[k] < lo[k] || o[k] > hi[k] {
                return false;
            }
            continue;
        }
        let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    t0 <= t1
}

struct Measured {
    /// Floor pixels facing the light that are exactly lit.
    lit: usize,
    /// Of those, the ones the map darkens (factor < 0.5): acne.
    wrongly_shadowed: usize,
    /// Exactly shadowed floor pixels next to the box (the contact line).
    contact: usize,
    /// Exactly shadowed floor pixels within 3 px of the box that the map
    /// leaves lit: the gap between the contact and its shadow.
    gap: usize,
}

fn measure(s: &LoadedScene) -> Measured {
    let target = Target::new(SIDE, SIDE).unwrap();
    let v = visibility(&s.data, &target, &mut FrameStats::default());
    let px = pixel_shadows(&s.data, &target, &v, 0);
    let specula_core::light::Light::Directional { to_light, .. } = s.data.lights[0] else {
        unreachable!()
    };
    let to_light = Vec3::from(to_light);
    let on_floor = |i: usize| px[i].is_some_and(|p| p.p.y.abs() < 1e-4);
    let w = SIDE as i32;
    let near_box = |x: i32, y: i32, r: i32| {
        (-r..=r).any(|dy| {
            (-r..=r).any(|dx| {
                let (xx, yy) = (x + dx, y + dy);
                xx >= 0 && yy >= 0 && xx < w && yy < w && {
                    let j = (yy * w + xx) as usize;
                    px[j].is_some() && !on_floor(j)
                }
            })
        })
    };
    let mut m = Measured {
        lit: 0,
        wrongly_shadowed: 0,
        contact: 0,
        gap: 0,
    };
    for y in 0..w {
        for x in 0..w {
            let i = (y * w + x) as usize;
            if !on_floor(i) {
                continue;
            }
            let p = px[i].unwrap();
            if box_blocks(p.p, to_light) {
                if near_box(x, y, 1) {
                    m.contact += 1;
                }
                if p.factor >= 0.5 && near_box(x, y, 3) {
                    m.gap += 1;
                }
            } else {
                m.lit += 1;
                m.wrongly_shadowed += (p.factor < 0.5) as usize;
            }
        }
    }
    m
}

#[test]
fn no_acne_on_a_floor_lit_from_10_to_80_degrees() {
    for filter in ["hard", "pcf"] {
        for elevation in [10.0, 20.0, 30.0, 45.0, 60.0, 80.0] {
            let m = measure(&floor_scene(elevation, false, filter));
            let frac = m.wrongly_shadowed as f64 / m.lit as f64;
            eprintln!(
                "{filter} at {elevation}°: {} of {} lit floor pixels shadowed ({:.4} %)",
                m.wrongly_shadowed,
                m.lit,
                100.0 * frac
            );
            assert!(m.lit > 10_000);
            assert!(frac <= 1e-3, "{filter} at {elevation}°: acne {frac}");
        }
    }
}

#[test]
fn shadows_touch_their_caster() {
    for filter in ["hard", "pcf"] {
        for elevation in [10.0, 20.0, 30.0, 45.0, 60.0, 80.0] {
            let m = measure(&floor_scene(elevation, true, filter));
            let gap = m.gap as f64 / m.contact.max(1) as f64;
            let acne = m.wrongly_shadowed as f64 / m.lit as f64;
            eprintln!(
                "{filter} at {elevation}°: contact line {} px, gap {:.3} px, {:.4} % of lit floor shadowed",
                m.contact,
                gap,
                100.0 * acne
            );
            assert!(
                m.contact > 20,
                "{filter} at {elevation}°: no contact line seen"
            );
            assert!(gap <= 1.0, "{filter} at {elevation}°: gap of {gap} px");
        }
    }
}

/// The scene fields' checks name the field.
#[test]
fn bad_shadow_fields_are_refused_by_name() {
    let base = |extra: &str| {
        format!(
            r#"
[camera]
eye = [0.0, 2.0, 5.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 40.0
near = 0.1
far = 50.0
[[mesh]]
plane = {{ size = [4.0, 4.0] }}
[[light]]
type = "point"
position = [0.0, 3.0, 0.0]
intensity = [1.0, 1.0, 1.0]
[[light]]
type = "spot"
position = [0.0, 3.0, 0.0]
direction = [0.0, -1.0, 0.0]
intensity = [1.0, 1.0, 1.0]
outer_cone = 30.0
shadows = "pcss"
{extra}
"#
        )
    };
    let read = |_: &std::path::Path| -> std::io::Result<Vec<u8>> {
        Err(std::io::ErrorKind::NotFound.into())
    };
    // `shadows = ...` replaces the spot light's own line 21; any other
    // field is added at line 22.
    let load = |extra: &str| {
        let text = if extra.starts_with("shadows") {
            base("").replace("shadows = \"pcss\"", extra)
        } else {
            base(extra)
        };
        specula::scene::load_scene_str(std::path::Path::new("s.toml"), &text, &read)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    for (extra, field) in [
        ("shadow_map_size = 0", "light[1].shadow_map_size"),
        ("shadow_map_size = 8193", "light[1].shadow_map_size"),
        ("shadow_map_size = 1000000000", "light[1].shadow_map_size"),
        ("shadow_map_size = -1", "light[1].shadow_map_size"),
        ("bias = -0.5", "light[1].bias"),
        ("bias = 1001.0", "light[1].bias"),
        ("normal_bias = -1.0", "light[1].normal_bias"),
        ("normal_bias = nan", "light[1].normal_bias"),
        ("light_size = nan", "light[1].light_size"),
        ("light_size = -1.0", "light[1].light_size"),
        ("light_size = 1e10", "light[1].light_size"),
        ("filter_radius = inf", "light[1].filter_radius"),
        ("filter_radius = 64.5", "light[1].filter_radius"),
        ("filter_radius = -1.0", "light[1].filter_radius"),
        ("shadows = \"soft\"", "light[1].shadows"),
        ("shadows = true", "light[1].shadows"),
    ] {
        let e = load(extra);
        assert!(e.contains(field), "{extra}: {e}");
    }
    // Cascades belong to directional lights, 1 to 4 of them.
    let sun = "[[light]]\ntype = \"directional\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = [1.0, 1.0, 1.0]\nshadows = \"pcf\"\n";
    for bad in ["cascades = 0", "cascades = 5", "cascades = -1"] {
        let e = load(&format!("{sun}{bad}"));
        assert!(e.contains("light[2].cascades"), "{bad}: {e}");
    }
    assert!(
        load(&format!("{sun}cascades = 4")).is_empty(),
        "4 cascades load"
    );
    let e = load("cascades = 2");
    assert!(e.contains("cascades"), "a spot light's cascades: {e}");
    // A wrong value or type is placed at its own line.
    let e = load("shadows = \"soft\"");
    assert!(e.contains("line 21"), "{e}");
    let e = load("bias = \"small\"");
    assert!(e.contains("line 22") && e.contains("light[1].bias"), "{e}");
    assert!(load("").is_empty(), "the defaults load");
    // With shadows off the fields are checked all the same (light[0]).
    let off = base("").replacen(
        "intensity = [1.0, 1.0, 1.0]",
        "intensity = [1.0, 1.0, 1.0]\nshadow_map_size = 0",
        1,
    );
    let e = specula::scene::load_scene_str(std::path::Path::new("s.toml"), &off, &read)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(e.contains("light[0].shadow_map_size"), "{e}");
}

/// Each shadow field at both ends of its range, under each filter and
/// each light kind, renders finite in f32x8 and in f32.
#[test]
fn shadow_fields_at_their_range_ends_render_finite() {
    use specula::render::{render_scene, RenderSettings};
    use specula_raster::frame::ShadePath;
    let ends = [
        "shadow_map_size = 1\nbias = 0.0\nnormal_bias = 0.0\nfilter_radius = 64.0\nlight_size = 1e9",
        "shadow_map_size = 512\nbias = 1000.0\nnormal_bias = 1000.0\nfilter_radius = 0.0\nlight_size = 0.0",
    ];
    let lights = [
        "type = \"point\"\nposition = [0.5, 3.0, 0.5]\nintensity = [20.0, 20.0, 20.0]",
        "type = \"spot\"\nposition = [0.5, 3.0, 0.5]\ndirection = [0.0, -1.0, 0.0]\nintensity = [20.0, 20.0, 20.0]\nouter_cone = 40.0",
        "type = \"directional\"\ndirection = [-0.3, -1.0, -0.2]\nirradiance = [2.0, 2.0, 2.0]",
    ];
    for light in lights {
        for filter in ["hard", "pcf", "pcss"] {
            for end in ends {
                let toml = format!(
                    r#"
[camera]
eye = [0.0, 2.0, 5.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 40.0
near = 0.1
far = 50.0
[output]
width = 24
height = 16
[[mesh]]
plane = {{ size = [4.0, 4.0] }}
[[mesh]]
cube = {{ size = 0.5 }}
translate = [0.0, 0.25, 0.0]
[[light]]
{light}
shadows = "{filter}"
{end}
"#
                );
                let scene = common::scene(&toml, &[]);
                let mut settings = RenderSettings::from_scene(&scene);
                for path in [ShadePath::Simd, ShadePath::Scalar] {
                    settings.path = path;
                    let r = render_scene(&scene, &settings, 0.0).expect("renders");
                    let bad = r
                        .hdr()
                        .iter()
                        .filter(|p| !p.iter().all(|c| c.is_finite()))
                        .count();
                    assert_eq!(bad, 0, "{light} {filter} {end} {path:?}");
                }
            }
        }
    }
}

/// `--stats` counts the depth passes' triangles: every pass sets up each
/// of the scene's 14 (a floor of 2, a box of 12), each counted once, and
/// the box's faces turned away from the light are culled (the floor, not
/// closed, is not).
#[test]
fn stats_count_each_depth_pass_triangle_once() {
    use specula::render::{render_scene, RenderSettings};
    let scene = floor_scene(45.0, true, "pcf");
    let r = render_scene(&scene, &RenderSettings::from_scene(&scene), 0.0).expect("renders");
    let report = r.stats.report();
    let number_before = |line: &str, label: &str| -> u64 {
        let at = line
            .find(label)
            .unwrap_or_else(|| panic!("{label:?} in {line}"));
        let head = line[..at].trim_end();
        let start = head.rfind([' ', '(']).map_or(0, |i| i + 1);
        head[start..]
            .parse()
            .unwrap_or_else(|e| panic!("{label:?} in {line}: {e}"))
    };
    let passes = report
        .lines()
        .find(|l| l.starts_with("  shadow ") && l.contains(" depth passes"))
        .map(|l| number_before(l, " depth passes"))
        .expect("a shadow line");
    let line = report
        .lines()
        .find(|l| l.starts_with("shadow triangles"))
        .unwrap_or_else(|| panic!("no shadow triangles line in\n{report}"));
    let n = |label: &str| number_before(line, label);
    assert!(passes >= 1, "{report}");
    assert_eq!(n(" in,"), 14 * passes, "{line}");
    let parts = [
        " back-face culled",
        " outside",
        " invalid",
        " degenerate",
        " clipped",
        " drawn",
        " between texel centres",
    ];
    // A clipped triangle is also counted by what its pieces did.
    let accounted: u64 = parts
        .iter()
        .filter(|p| **p != " clipped")
        .map(|p| n(p))
        .sum();
    assert_eq!(accounted, n(" in,"), "{line}");
    // Of the box's six faces the light (down and toward −x) sees the top
    // and +x ones; −y and −x face away (±z are edge-on).
    assert!(n(" back-face culled") >= 4 * passes, "{line}");
    assert!(n(" drawn") >= 2 * passes, "{line}");
}

/// Area of the intersection of two disks of radii `a` and `b` whose
/// centres are `d` apart.
fn disk_overlap(a: f64, b: f64, d: f64) -> f64 {
    use std::f64::consts::PI;
    if d >= a + b {
        return 0.0;
    }
    if d <= (a - b).abs() {
        return PI * a.min(b).powi(2);
    }
    let ca = ((d * d + a * a - b * b) / (2.0 * d * a))
        .clamp(-1.0, 1.0)
        .acos();
    let cb = ((d * d + b * b - a * a) / (2.0 * d * b))
        .clamp(-1.0, 1.0)
        .acos();
    a * a * (ca - ca.sin() * ca.cos()) + b * b * (cb - cb.sin() * cb.cos())
}

/// The fraction of a spherical light (centre `l`, radius `a`) a floor
/// point `q` sees past a sphere (centre `c`, radius `r`): one minus the
/// overlap of the two disks they subtend (angular radii and the angle
/// between their centres, in the small-angle plane).
fn sphere_light_visible(q: [f64; 3], l: [f64; 3], a: f64, c: [f64; 3], r: f64) -> f64 {
    let sub = |u: [f64; 3], v: [f64; 3]| [u[0] - v[0], u[1] - v[1], u[2] - v[2]];
    let len = |u: [f64; 3]| (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
    let (tl, tc) = (sub(l, q), sub(c, q));
    let (dl, dc) = (len(tl), len(tc));
    let (al, ac) = ((a / dl).asin(), (r / dc).asin());
    let cos = (tl[0] * tc[0] + tl[1] * tc[1] + tl[2] * tc[2]) / (dl * dc);
    let theta = cos.clamp(-1.0, 1.0).acos();
    1.0 - disk_overlap(al, ac, theta) / (std::f64::consts::PI * al * al)
}

/// Where a profile sampled at increasing `x` first reaches `level`
/// (linear between samples).
fn crossing(xs: &[f64], ys: &[f64], level: f64) -> f64 {
    for i in 1..xs.len() {
        if ys[i - 1] < level && ys[i] >= level {
            let t = (level - ys[i - 1]) / (ys[i] - ys[i - 1]);
            return xs[i - 1] + t * (xs[i] - xs[i - 1]);
        }
    }
    f64::NAN
}

/// PCSS against the analytic penumbra of a sphere over a floor under a
/// spherical light: the width over which the shadow goes from 10 % to
/// 90 % of the light, along the floor away from the shadow's centre.
#[test]
fn pcss_penumbra_matches_a_sphere_under_a_spherical_light() {
    let (h_light, a, h_sphere, r) = (4.0f64, 0.3f64, 1.0f64, 0.5f64);
    let text = format!(
        r#"
[camera]
eye = [0.0, 3.0, 3.2]
target = [0.0, 0.0, 0.6]
up = [0.0, 1.0, 0.0]
fov_y = 40.0
near = 0.1
far = 50.0
[output]
width = 512
height = 512
[[mesh]]
plane = {{ size = [8.0, 8.0] }}
[[mesh]]
sphere = {{ radius = {r}, segments = 128, rings = 64 }}
translate = [0.0, {h_sphere}, 0.0]
[[light]]
type = "point"
position = [0.0, {h_light}, 0.0]
intensity = [10.0, 10.0, 10.0]
shadows = "pcss"
light_size = {}
shadow_map_size = 2048
"#,
        2.0 * a
    );
    let s = common::scene(&text, &[]);
    let target = Target::new(512, 512).unwrap();
    let v = visibility(&s.data, &target, &mut FrameStats::default());
    let px = pixel_shadows(&s.data, &target, &v, 0);
    // Mean factor per ring of the floor around the shadow's centre.
    let bin = 0.01;
    let bins = 150;
    let mut sum = vec![0.0f64; bins];
    let mut count = vec![0usize; bins];
    for p in px.iter().flatten() {
        if p.p.y.abs() > 1e-4 {
            continue;
        }
        let rho = (p.p.x as f64).hypot(p.p.z as f64);
        let b = (rho / bin) as usize;
        if b < bins {
            sum[b] += p.factor as f64;
            count[b] += 1;
        }
    }
    let (mut xs, mut ours, mut exact) = (Vec::new(), Vec::new(), Vec::new());
    for b in 0..bins {
        if count[b] < 20 {
            continue;
        }
        let rho = (b as f64 + 0.5) * bin;
        xs.push(rho);
        ours.push(sum[b] / count[b] as f64);
        exact.push(sphere_light_visible(
            [rho, 0.0, 0.0],
            [0.0, h_light, 0.0],
            a,
            [0.0, h_sphere, 0.0],
            r,
        ));
    }
    let width = |ys: &[f64]| crossing(&xs, ys, 0.9) - crossing(&xs, ys, 0.1);
    let (w_ours, w_exact) = (width(&ours), width(&exact));
    eprintln!(
        "PCSS 10–90 % penumbra width {w_ours:.4}, analytic {w_exact:.4} (ratio {:.3})",
        w_ours / w_exact
    );
    assert!(
        (w_ours / w_exact - 1.0).abs() <= 0.2,
        "penumbra width {w_ours} against {w_exact}"
    );
}

/// The 8-lane lookup gives each lane the scalar lookup's bits when the
/// lanes spread over a directional light's cascades and a point light's
/// cube faces (hard and PCF), for PCF radii that take each of its paths
/// (depth windows, texel grid, taps), and for PCSS (lane by lane); on
/// single maps (orthographic and perspective), in the light loop's form
/// too (which looks a packet whose lanes all pick one face or cascade up
/// on that face alone); with points and normals that are now and then not
/// finite.
#[test]
#[allow(clippy::needless_range_loop)]
fn lane_lookups_match_the_scalar_one_across_cascades_and_faces() {
    use specula_core::{f32x8, Real, V3};
    let mut rng = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 40) as f32 / (1u64 << 24) as f32
    };
    // PCF radii: 1.5 (the default) and 1 and 0.5 read a texel grid once,
    // 0.75 and 0 their taps; all first try the depth windows.
    let cases = [
        ("shadows_cascades.toml", 0, 4, "hard", 1.5),
        ("shadows_cascades.toml", 0, 3, "pcf", 1.5),
        ("shadows_cascades.toml", 0, 2, "pcss", 1.5),
        ("shadows.toml", 2, 1, "hard", 1.5),
        ("shadows.toml", 2, 1, "pcf", 1.5),
        ("shadows.toml", 0, 1, "pcf", 1.0),
        ("shadows.toml", 0, 1, "pcf", 0.5),
        ("shadows.toml", 1, 1, "pcf", 0.75),
        ("shadows.toml", 1, 1, "pcf", 0.0),
    ];
    for (file, k, cascades, filter, radius) in cases {
        let mut s = specula::scene::load_scene(&common::fixtures().join("scenes").join(file))
            .expect("fixture scene");
        let mut parts = s.data.into_parts();
        let light = parts.lights[k].clone();
        parts.lights = vec![light];
        let mut settings = parts.shadows[k].expect("a shadowed light");
        settings.cascades = cascades;
        settings.map_size = 256;
        settings.filter_radius = radius;
        settings.filter = match filter {
            "hard" => specula_raster::shadow::ShadowFilter::Hard,
            "pcf" => specula_raster::shadow::ShadowFilter::Pcf,
            _ => specula_raster::shadow::ShadowFilter::Pcss,
        };
        parts.shadows = vec![Some(settings)];
        s.data = specula_raster::SceneData::new(parts).expect("one shadowed light");
        let target = Target::new(96, 54).unwrap();
        let v = visibility(&s.data, &target, &mut FrameStats::default());
        let ls = v.shadows.light(0).expect("the light's maps");
        let (lo, hi) = s
            .data
            .positions
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        let mut shadowed = 0;
        for i in 0..4000 {
            // Points on and above the floor spread over the scene, normals
            // mostly up, some lanes off; every other packet's points
            // within 0.1 of one another across the floor (on it, or at one
            // height above it), as a frame's packets are, so that many
            // share a cube face or cascade, whose lookup then runs alone.
            let mut c = [[0.0f32; 8]; 6];
            let centre = [next(), next() * 2.0, next()];
            for l in 0..8 {
                let y = if next() < 0.7 { 0.0 } else { next() * 2.0 };
                c[0][l] = lo.x + (hi.x - lo.x) * next();
                c[1][l] = y;
                c[2][l] = lo.z + (hi.z - lo.z) * next();
                if i % 2 == 1 {
                    let mut near = |t: f32| t + 0.1 * (next() - 0.5);
                    c[0][l] = near(lo.x + (hi.x - lo.x) * centre[0]);
                    c[1][l] = if y == 0.0 { 0.0 } else { near(centre[1]) };
                    c[2][l] = near(lo.z + (hi.z - lo.z) * centre[2]);
                }
                let n = Vec3::new(next() - 0.5, 2.0, next() - 0.5).normalize();
                (c[3][l], c[4][l], c[5][l]) = (n.x, n.y, n.z);
                // Now and then a coordinate of the point or the normal
                // that is not finite.
                if next() < 0.02 {
                    let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
                    c[(next() * 6.0) as usize][l] = bad[(next() * 3.0) as usize];
                }
            }
            let lanes = (next() * 256.0) as u32 | 1;
            let p = V3::new(f32x8::load(&c[0]), f32x8::load(&c[1]), f32x8::load(&c[2]));
            let n = V3::new(f32x8::load(&c[3]), f32x8::load(&c[4]), f32x8::load(&c[5]));
            let got = ls.visibility_lanes(&p, &n, lanes);
            // The light loop's form, its common end inline.
            let inline = ls.visibility_at(&p, &n, lanes);
            for l in 0..8 {
                let want = if lanes & (1 << l) != 0 {
                    ls.visibility(
                        Vec3::new(c[0][l], c[1][l], c[2][l]),
                        Vec3::new(c[3][l], c[4][l], c[5][l]),
                    )
                } else {
                    1.0
                };
                shadowed += (want < 1.0) as u32;
                assert_eq!(
                    (got.lane(l) as f32).to_bits(),
                    want.to_bits(),
                    "{file} light {k}, {cascades} cascades, {filter} {radius}: lane {l}"
                );
                assert_eq!(
                    (inline.lane(l) as f32).to_bits(),
                    want.to_bits(),
                    "{file} light {k}, {cascades} cascades, {filter} {radius}: lane {l} inline"
                );
            }
        }
        assert!(
            shadowed > 100,
            "{file} {filter} {radius}: some points in shadow"
        );
        assert_eq!(ls.faces(), if k == 2 { 6 } else { cascades as usize });
    }
}

/// The depth-only passes (depth planes alone, outside triangles skipped
/// before setup) give every texel of every map the bits of the camera
/// pass's full setup: a directional light's map and its cascades, a spot
/// light's, a point light's cube and a polygon light's, at a map size of
/// whole tiles and one that cuts them, and again from the buffers of the
/// frame before; faces that see nothing, given their map without a pass,
/// included.
#[test]
fn depth_only_maps_match_the_full_setup_bit_for_bit() {
    use specula_raster::shadow::ShadowMaps;
    use specula_raster::shadow_pass::{render_maps, DepthSetup};
    use specula_raster::ShadowBuffers;
    let cases = [
        ("shadows.toml", None),
        ("shadows.toml", Some(3)),
        ("shadows_cascades.toml", Some(4)),
        ("shadows_area.toml", None),
    ];
    // Faces that see nothing get their map without a pass (the point
    // light's and the polygon light's faces toward the open sky).
    let mut blank = 0;
    for (file, cascades) in cases {
        for size in [256, 1000] {
            let mut s = specula::scene::load_scene(&common::fixtures().join("scenes").join(file))
                .expect("fixture scene");
            let mut parts = s.data.into_parts();
            for st in parts.shadows.iter_mut().flatten() {
                st.map_size = size;
                if let Some(c) = cascades {
                    st.cascades = c;
                }
            }
            s.data = specula_raster::SceneData::new(parts).expect("valid scene");
            let view = s.data.camera.view(320, 180);
            let render = |(maps, buffers): &mut (ShadowMaps, ShadowBuffers), setup| {
                let mut stats = FrameStats::default();
                render_maps(&s.data, &view, setup, maps, buffers, &mut stats);
                stats
            };
            let mut full = Default::default();
            assert_eq!(render(&mut full, DepthSetup::Full).shadow_faces_blank, 0);
            let (full, mut fast) = (full.0, Default::default());
            for frame in 0..2 {
                blank += render(&mut fast, DepthSetup::DepthOnly).shadow_faces_blank;
                let fast = &fast.0;
                let mut lights = 0;
                for k in 0..s.data.lights.len() {
                    let (Some(a), Some(b)) = (full.light(k), fast.light(k)) else {
                        assert!(full.light(k).is_none() && fast.light(k).is_none());
                        continue;
                    };
                    lights += 1;
                    assert_eq!(a.faces(), b.faces(), "{file} light {k}");
                    for i in 0..a.faces() {
                        let ((na, da), (nb, db)) = (a.depth(i), b.depth(i));
                        assert_eq!((na, da.len()), (nb, db.len()));
                        let drawn = da.iter().filter(|d| d.is_finite()).count();
                        assert!(drawn > 0 || a.faces() == 6, "{file} light {k} face {i}");
                        let differ = (da.iter().zip(db))
                            .filter(|(x, y)| x.to_bits() != y.to_bits())
                            .count();
                        assert_eq!(
                            differ, 0,
                            "{file} size {size} frame {frame} light {k} face {i}: texels differ"
                        );
                    }
                }
                assert!(lights > 0, "{file}: some shadowed light");
            }
        }
    }
    assert!(blank > 0, "some face seeing nothing");
}

/// The shadows fixture's closed meshes are found as solids (whose back
/// faces its depth passes cull): its generated spheres (poles and seams
/// welded) and cubes (corners split per face), not the open floor.
#[test]
fn the_shadow_fixtures_spheres_and_cubes_are_closed_solids() {
    let s = specula::scene::load_scene(&common::fixtures().join("scenes/shadows.toml"))
        .expect("fixture scene");
    let solids = s
        .data
        .solids()
        .expect("a scene with shadows finds its solids");
    assert_eq!(
        solids.counts(),
        (5, 4),
        "(parts, solids): a floor, 2 spheres, 2 cubes"
    );

    // Their depth passes cull back faces (the shadow passes alone: the
    // camera pass is not drawn here).
    let mut maps = Default::default();
    let mut buffers = Default::default();
    let mut stats = FrameStats::default();
    let view = s.data.camera.view(320, 180);
    specula_raster::shadow_pass::render_maps(
        &s.data,
        &view,
        specula_raster::shadow_pass::DepthSetup::DepthOnly,
        &mut maps,
        &mut buffers,
        &mut stats,
    );
    let c = &stats.shadow_counts;
    assert!(stats.shadow_passes > 0);
    assert!(
        c.culled_backface > c.triangles / 10,
        "{} of {} triangles culled as back faces",
        c.culled_backface,
        c.triangles
    );
}

/// The floor and unit box of [`floor_scene`] lit by the generated sky
/// (`fixtures/env/sky.hdr`) alone, the floor's material `floor` (TOML
/// lines), the sky's sun shadowed as `[environment.sun]` says (`sun`:
/// its lines, or `None` for no such table).
fn sky_scene(floor: &str, sun: Option<&str>) -> LoadedScene {
    let sun = sun.map_or(String::new(), |s| format!("[environment.sun]\n{s}\n"));
    let text = format!(
        r#"{FLOOR_VIEW}
[environment]
map = "sky.hdr"
{sun}
[[mesh]]
cube = {{ size = 1.0 }}
translate = [0.0, 0.5, 0.0]
material = "box"
[materials.floor]
{floor}
[materials.box]
model = "lambert"
base_color = [0.5, 0.5, 0.5]
"#
    );
    let sky = std::fs::read(common::fixtures().join("env/sky.hdr")).expect("fixture sky");
    let read = move |p: &std::path::Path| -> std::io::Result<Vec<u8>> {
        if p == std::path::Path::new("sky.hdr") {
            Ok(sky.clone())
        } else {
            Err(std::io::ErrorKind::NotFound.into())
        }
    };
    specula::scene::load_scene_str(std::path::Path::new("test.toml"), &text, &read)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Floor pixels away from the box, by the exact visibility of the sun's
/// centre past the box: each one's index, its surface point and the
/// sun's shadow factor, and whether the box hides the sun from it, for
/// the pixels whose 5 × 5 neighbourhood agrees on that (no shadow edge).
fn sun_classes(s: &LoadedScene) -> Vec<(usize, f32, bool)> {
    let target = Target::new(SIDE, SIDE).unwrap();
    let v = visibility(&s.data, &target, &mut FrameStats::default());
    let px = specula_raster::shadow_pass::pixel_sun_shadows(&s.data, &target, &v);
    assert_eq!(px.len(), (SIDE * SIDE) as usize, "the sun has a map");
    let sun = s.data.env_map.as_ref().unwrap().sun_world().unwrap();
    let to_sun = Vec3::from(sun.to_light);
    let w = SIDE as i32;
    let class = |x: i32, y: i32| -> Option<bool> {
        if x < 0 || y < 0 || x >= w || y >= w {
            return None;
        }
        let p = px[(y * w + x) as usize]?;
        (p.p.y.abs() < 1e-4).then(|| box_blocks(p.p, to_sun))
    };
    let mut out = Vec::new();
    for y in 0..w {
        for x in 0..w {
            let Some(c) = class(x, y) else { continue };
            let uniform = (-2..=2).all(|dy| (-2..=2).all(|dx| class(x + dx, y + dy) == Some(c)));
            if uniform {
                let i = (y * w + x) as usize;
                out.push((i, px[i].unwrap().factor, c));
            }
        }
    }
    out
}

/// The generated sky's sun, shadowed: away from shadow edges its map
/// agrees with exact visibility past the box; a floor pixel in the box's
/// shadow receives the sky's light alone (the split sum without the sun,
/// its diffuse part the SH irradiance times the albedo over π), and a
/// pixel in the sun keeps the unshadowed render's value.
#[test]
fn the_suns_shadow_takes_out_the_suns_light_alone() {
    let lambert = "model = \"lambert\"\nbase_color = [0.5, 0.5, 0.5]";
    let shadowed = sky_scene(lambert, Some("shadows = \"hard\"\nshadow_map_size = 1024"));
    let open = sky_scene(lambert, None);
    let classes = sun_classes(&shadowed);
    let in_shadow = classes.iter().filter(|c| c.2).count();
    assert!(
        in_shadow > 500,
        "{in_shadow} floor pixels in the box's shadow"
    );
    for &(i, factor, dark) in &classes {
        assert_eq!(factor, if dark { 0.0 } else { 1.0 }, "pixel {i}");
    }
    let target = || Target::new(SIDE, SIDE).unwrap();
    let a = specula_raster::render(&shadowed.data, target(), Default::default());
    let b = specula_raster::render(&open.data, target(), Default::default());
    let map = shadowed.data.env_map.as_ref().unwrap();
    let up = specula_core::V3::<f64>::new(0.0, 1.0, 0.0);
    let sky = map.sky_irradiance_over_pi(up);
    let sky = [sky.x, sky.y, sky.z].map(|e| 0.5 * e);
    let lit = map.irradiance_over_pi(up);
    let lit = [lit.x, lit.y, lit.z].map(|e| 0.5 * e);
    assert!(
        lit[1] > 2.0 * sky[1],
        "the sun outshines the sky: {lit:?} {sky:?}"
    );
    for &(i, _, dark) in &classes {
        let (ca, cb) = (a.buffers.color.get(i), b.buffers.color.get(i));
        if dark {
            for c in 0..3 {
                let rel = (ca[c] as f64 - sky[c]).abs() / sky[c];
                assert!(rel < 1e-5, "pixel {i}: {ca:?} against the sky's {sky:?}");
            }
        } else {
            assert_eq!(ca, cb, "pixel {i} in the sun");
        }
    }
}

/// Toon bands and hatching tones take the sky's sun's shadow: a floor
/// pixel in the box's shadow is darker than one in the sun, and every
/// floor pixel in the sun keeps the unshadowed render's value.
#[test]
fn npr_shaders_darken_in_the_suns_shadow() {
    let floors = [
        (
            "toon",
            "model = \"toon\"\nbands = 3\nbase_color = [0.5, 0.5, 0.5]",
        ),
        ("hatching", "model = \"hatching\""),
    ];
    for (name, floor) in floors {
        let shadowed = sky_scene(floor, Some("shadows = \"pcf\""));
        let open = sky_scene(floor, None);
        let classes = sun_classes(&shadowed);
        let target = || Target::new(SIDE, SIDE).unwrap();
        let a = specula_raster::render(&shadowed.data, target(), Default::default());
        let b = specula_raster::render(&open.data, target(), Default::default());
        let luma = |c: [f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        let mean = |dark: bool| {
            let v: Vec<f32> = (classes.iter())
                .filter(|c| c.2 == dark)
                .map(|c| luma(a.buffers.color.get(c.0)))
                .collect();
            assert!(v.len() > 500, "{name}: {} pixels", v.len());
            v.iter().sum::<f32>() / v.len() as f32
        };
        let (dark, sunny) = (mean(true), mean(false));
        assert!(
            dark < 0.95 * sunny,
            "{name}: shadow {dark} against sun {sunny}"
        );
        for &(i, _, in_shadow) in &classes {
            if !in_shadow {
                let (ca, cb) = (a.buffers.color.get(i), b.buffers.color.get(i));
                assert_eq!(ca, cb, "{name}: pixel {i} in the sun");
            }
        }
    }
}

/// `[environment.sun]`'s checks name the field: its shadow fields' ranges
/// (checked with shadows off too), a uniform environment, and a map with
/// no sun to take out.
#[test]
fn bad_sun_shadow_fields_are_refused_by_name() {
    let sky = std::fs::read(common::fixtures().join("env/sky.hdr")).expect("fixture sky");
    let flat = std::fs::read(common::fixtures().join("env/royal_esplanade_1k.hdr"))
        .expect("fixture esplanade");
    let read = move |p: &std::path::Path| -> std::io::Result<Vec<u8>> {
        match p.to_str() {
            Some("sky.hdr") => Ok(sky.clone()),
            Some("flat.hdr") => Ok(flat.clone()),
            _ => Err(std::io::ErrorKind::NotFound.into()),
        }
    };
    let load = |environment: &str, sun: &str| {
        let text = format!(
            "[camera]\neye = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\n\
             fov_y = 40.0\nnear = 0.1\nfar = 50.0\n[[mesh]]\nplane = {{ size = [4.0, 4.0] }}\n\
             [environment]\n{environment}\n[environment.sun]\n{sun}\n"
        );
        specula::scene::load_scene_str(std::path::Path::new("s.toml"), &text, &read)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    let map = "map = \"sky.hdr\"";
    for (sun, field) in [
        (
            "shadows = \"pcf\"\nshadow_map_size = 0",
            "environment.sun.shadow_map_size",
        ),
        (
            "shadows = \"pcf\"\nshadow_map_size = 1000000000",
            "environment.sun.shadow_map_size",
        ),
        ("shadow_map_size = 0", "environment.sun.shadow_map_size"),
        ("shadows = \"hard\"\nbias = -1.0", "environment.sun.bias"),
        (
            "shadows = \"pcss\"\nlight_size = nan",
            "environment.sun.light_size",
        ),
        (
            "shadows = \"pcf\"\ncascades = 5",
            "environment.sun.cascades",
        ),
        ("shadows = \"soft\"", "environment.sun.shadows"),
        ("colour = 1", "colour"),
    ] {
        let e = load(map, sun);
        assert!(e.contains(field), "{sun}: {e}");
    }
    for sun in [
        "shadows = \"pcf\"",
        "shadows = \"pcss\"\ncascades = 4",
        "shadows = \"none\"",
    ] {
        let e = load(map, sun);
        assert!(e.is_empty(), "{sun}: {e}");
    }
    let e = load("uniform = [0.1, 0.1, 0.1]", "shadows = \"pcf\"");
    assert!(
        e.contains("environment.sun.shadows") && e.contains("uniform"),
        "{e}"
    );
    let e = load("map = \"flat.hdr\"", "shadows = \"pcf\"");
    assert!(
        e.contains("environment.sun.shadows") && e.contains("no sun"),
        "{e}"
    );
}
