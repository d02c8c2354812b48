//! The glTF-style material maps end to end, from scene files: a
//! normal-mapped plane against the displaced surface it stands for,
//! metallic/roughness from a texture against constant materials,
//! occlusion on the environment term only, emission, MikkTSpace tangents
//! through the loader, and field errors.

use specula::render::{render_scene, RenderSettings};
use specula::scene::LoadedScene;
use std::f64::consts::PI;
use std::path::Path;

/// Reads files from a list of (name, bytes).
fn files(list: Vec<(String, Vec<u8>)>) -> impl Fn(&Path) -> std::io::Result<Vec<u8>> {
    move |p| {
        list.iter()
            .find(|(n, _)| Path::new(n) == p)
            .map(|(_, b)| b.clone())
            .ok_or_else(|| std::io::ErrorKind::NotFound.into())
    }
}

fn load(
    toml: &str,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<LoadedScene, String> {
    specula::scene::load_scene_str(Path::new("t.toml"), toml, read).map_err(|e| e.to_string())
}

fn png(w: u32, h: u32, px: impl Fn(u32, u32) -> [u8; 3]) -> Vec<u8> {
    let mut img = image::RgbImage::new(w, h);
    for (x, y, p) in img.enumerate_pixels_mut() {
        *p = image::Rgb(px(x, y));
    }
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

fn hdr(s: &LoadedScene) -> Vec<[f32; 3]> {
    render_scene(s, &RenderSettings::from_scene(s), 0.0)
        .unwrap()
        .hdr()
}

/// The largest |a − b| / max(|b|, floor) over all pixels and channels.
fn worst_relative(a: &[[f32; 3]], b: &[[f32; 3]], floor: f64) -> f64 {
    let mut worst = 0.0f64;
    for (p, q) in a.iter().zip(b) {
        for c in 0..3 {
            let (p, q) = (p[c] as f64, q[c] as f64);
            worst = worst.max((p - q).abs() / q.abs().max(floor));
        }
    }
    worst
}

const ROW_CAMERA: &str = r#"
[camera]
eye = [0.0, 0.0, 6.0]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 20.0

[output]
width = 160
height = 64
"#;

#[test]
fn metallic_roughness_from_a_texture_equals_constant_materials() {
    // Three spheres, each with a one-texel map (G = roughness, B =
    // metallic; nearest filtering), against the same spheres with the
    // texel values as constants, under a point light, a directional light
    // and the environment.
    let texels = [[0u8, 60, 255], [0, 140, 90], [0, 230, 0]];
    let lights = "[[light]]\ntype = \"point\"\nposition = [1.0, 2.0, 3.0]\nintensity = [6, 5, 4]\n\n[[light]]\ntype = \"directional\"\ndirection = [0.3, -0.5, -1.0]\nirradiance = [1.0, 1.0, 1.0]\n\n[environment]\nuniform = [0.2, 0.25, 0.3]\n";
    let mut textured = format!("{ROW_CAMERA}{lights}");
    let mut plain = textured.clone();
    let mut list = Vec::new();
    for (i, t) in texels.iter().enumerate() {
        let x = (i as f64 - 1.0) * 1.6;
        let mesh = format!("[[mesh]]\nsphere = {{ radius = 0.7 }}\ntranslate = [{x}, 0.0, 0.0]\nmaterial = \"m{i}\"\n\n");
        textured += &mesh;
        plain += &mesh;
        textured += &format!("[materials.m{i}]\nmodel = \"metallic_roughness\"\nbase_color = [0.8, 0.5, 0.3]\nroughness = 1.0\nmetallic = 1.0\nmetallic_roughness_texture = \"mr{i}.png\"\ntexture_filter = \"nearest\"\n\n");
        let (r, m) = (t[1] as f64 / 255.0, t[2] as f64 / 255.0);
        plain += &format!("[materials.m{i}]\nmodel = \"metallic_roughness\"\nbase_color = [0.8, 0.5, 0.3]\nroughness = {r}\nmetallic = {m}\n\n");
        let t = *t;
        list.push((format!("mr{i}.png"), png(1, 1, move |_, _| t)));
    }
    let read = files(list);
    let a = hdr(&load(&textured, &read).unwrap());
    let b = hdr(&load(&plain, &read).unwrap());
    // The same model at the same parameters: only the shading frame's
    // tangent differs (uv tangents vs any tangent), which an isotropic
    // model does not see beyond f32 rounding.
    let worst = worst_relative(&a, &b, 0.05);
    assert!(worst < 1e-4, "relative difference {worst}");
}

const SPHERE: &str = r#"
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
sphere = { radius = 1.0 }
material = "m"
"#;

#[test]
fn occlusion_darkens_the_environment_term_only() {
    let occ = 100u8;
    let strength = 0.7;
    let read = files(vec![("o.png".into(), png(2, 2, |_, _| [occ, 0, 0]))]);
    let material = "[materials.m]\nmodel = \"metallic_roughness\"\nbase_color = [0.7, 0.6, 0.5]\nroughness = 0.4\nmetallic = 0.3\n";
    let with = format!("occlusion_texture = \"o.png\"\nocclusion_strength = {strength}\n");
    let point = "[[light]]\ntype = \"point\"\nposition = [1.0, 2.0, 3.0]\nintensity = [6, 5, 4]\n";
    let env = "[environment]\nuniform = [0.4, 0.5, 0.6]\n";
    // A point light alone: the map changes nothing.
    let a = hdr(&load(&format!("{SPHERE}{point}{material}{with}"), &read).unwrap());
    let b = hdr(&load(&format!("{SPHERE}{point}{material}"), &read).unwrap());
    let worst = worst_relative(&a, &b, 0.05);
    assert!(worst < 1e-4, "point light: relative difference {worst}");
    // The environment alone: every covered pixel scaled by
    // 1 + strength · (occlusion − 1), the background not.
    let k = 1.0 + strength * (occ as f64 / 255.0 - 1.0);
    let a = hdr(&load(&format!("{SPHERE}{env}{material}{with}"), &read).unwrap());
    let b = hdr(&load(&format!("{SPHERE}{env}{material}"), &read).unwrap());
    let background = [0.4f32, 0.5, 0.6];
    let (mut covered, mut worst) = (0, 0.0f64);
    for (p, q) in a.iter().zip(&b) {
        if *q == background {
            assert_eq!(p, q);
            continue;
        }
        covered += 1;
        for c in 0..3 {
            let want = q[c] as f64 * k;
            worst = worst.max((p[c] as f64 - want).abs() / want.max(1e-3));
        }
    }
    assert!(covered > 1000, "{covered}");
    assert!(worst < 1e-4, "environment: relative difference {worst}");
}

#[test]
fn emission_adds_the_emissive_colour_times_its_texture() {
    let t = [200u8, 100, 50];
    let read = files(vec![("e.png".into(), png(2, 2, move |_, _| t))]);
    let srgb = |b: u8| {
        let c = b as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let emissive = [2.0, 1.0, 0.5];
    for texture in [false, true] {
        let mut m = format!("[materials.m]\nmodel = \"lambert\"\nbase_color = [0.5, 0.5, 0.5]\nemissive = {emissive:?}\n");
        if texture {
            m += "emissive_texture = \"e.png\"\n";
        }
        // No lights, no environment: the emission alone.
        let img = hdr(&load(&format!("{SPHERE}{m}"), &read).unwrap());
        let centre = img[32 * 64 + 32];
        for c in 0..3 {
            let want = emissive[c] * if texture { srgb(t[c]) } else { 1.0 };
            assert!(
                (centre[c] as f64 - want).abs() < 1e-5 * want,
                "texture {texture}: {centre:?} channel {c} vs {want}"
            );
        }
    }
}

/// A height field h(x, y) = A (sin ωx + sin ωy) and its gradient.
const A: f64 = 0.03;
const OMEGA: f64 = 2.0 * PI;

fn height(x: f64, y: f64) -> f64 {
    A * ((OMEGA * x).sin() + (OMEGA * y).sin())
}

fn unit_normal(x: f64, y: f64) -> [f64; 3] {
    let (hx, hy) = (A * OMEGA * (OMEGA * x).cos(), A * OMEGA * (OMEGA * y).cos());
    let l = (hx * hx + hy * hy + 1.0).sqrt();
    [-hx / l, -hy / l, 1.0 / l]
}

/// Half the side of the plane, centred on the origin in z = 0.
const HALF: f64 = 1.2;

#[test]
fn a_normal_mapped_plane_shades_like_the_displaced_surface() {
    // The normal map of h over the plane, uv = ((x, y) + HALF) / 2 HALF,
    // texel centres at (i + ½)/N; PNG rows run top (v = 1) down. Tangent
    // space is (x, y, z): the tangent runs along +u = +x and the
    // bitangent along +v = +y.
    let n = 256u32;
    let map = png(n, n, |i, row| {
        let u = (i as f64 + 0.5) / n as f64;
        let v = 1.0 - (row as f64 + 0.5) / n as f64;
        let (x, y) = (-HALF + 2.0 * HALF * u, -HALF + 2.0 * HALF * v);
        unit_normal(x, y).map(|c| ((c + 1.0) / 2.0 * 255.0).round() as u8)
    });
    let flat = format!(
        "v {m} {m} 0\nv {p} {m} 0\nv {p} {p} 0\nv {m} {p} 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n",
        m = -HALF,
        p = HALF
    );
    // The displaced surface, finely tessellated, with analytic normals.
    let cells = 240;
    let mut obj = String::new();
    for j in 0..=cells {
        for i in 0..=cells {
            let x = -HALF + 2.0 * HALF * i as f64 / cells as f64;
            let y = -HALF + 2.0 * HALF * j as f64 / cells as f64;
            let nn = unit_normal(x, y);
            obj += &format!(
                "v {x} {y} {}\nvn {} {} {}\n",
                height(x, y),
                nn[0],
                nn[1],
                nn[2]
            );
        }
    }
    let at = |i: usize, j: usize| j * (cells + 1) + i + 1;
    for j in 0..cells {
        for i in 0..cells {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            obj += &format!("f {a}//{a} {b}//{b} {c}//{c}\nf {a}//{a} {c}//{c} {d}//{d}\n");
        }
    }
    let read = files(vec![
        ("n.png".into(), map),
        ("flat.obj".into(), flat.into_bytes()),
        ("bumps.obj".into(), obj.into_bytes()),
    ]);
    // Seen from straight above and far (a narrow field of view), so the
    // displaced points (at most 2A off the plane) land within a fraction
    // of a pixel of the flat ones; two oblique directional lights.
    let scene = |mesh: &str, material: &str| {
        format!(
            "[camera]\neye = [0.0, 0.0, 10.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nfov_y = 12.0\nnear = 1.0\nfar = 20.0\n\n[output]\nwidth = 128\nheight = 128\n\n[[mesh]]\nobj = \"{mesh}\"\nmaterial = \"m\"\n\n[materials.m]\nmodel = \"lambert\"\nbase_color = [0.8, 0.8, 0.8]\n{material}\n[[light]]\ntype = \"directional\"\ndirection = [-0.6, -0.4, -1.0]\nirradiance = [3.0, 3.0, 3.0]\n\n[[light]]\ntype = \"directional\"\ndirection = [0.5, -0.7, -1.0]\nirradiance = [1.0, 1.5, 2.0]\n"
        )
    };
    let mapped = hdr(&load(
        &scene(
            "flat.obj",
            "normal_texture = \"n.png\"\ntexture_filter = \"bilinear\"\n",
        ),
        &read,
    )
    .unwrap());
    let displaced = hdr(&load(&scene("bumps.obj", ""), &read).unwrap());
    let plain = hdr(&load(&scene("flat.obj", ""), &read).unwrap());
    let rel = |a: &[[f32; 3]], b: &[[f32; 3]]| -> Vec<f64> {
        a.iter()
            .zip(b)
            .flat_map(|(p, q)| (0..3).map(move |c| ((p[c] - q[c]) as f64).abs() / q[c] as f64))
            .collect()
    };
    let mut errors = rel(&mapped, &displaced);
    errors.sort_by(f64::total_cmp);
    let mean = errors.iter().sum::<f64>() / errors.len() as f64;
    let p99 = errors[errors.len() * 99 / 100];
    // Stated tolerance: 8-bit texels move each normal component by up to
    // 1/510, the map's bilinear texels and the mesh's interpolated normals
    // differ by their curvature, and the displaced points sit up to 2A
    // off the plane: under 1 % on average, 3 % at the 99th percentile.
    assert!(mean < 0.01, "mean relative difference {mean}");
    assert!(p99 < 0.03, "99th percentile {p99}");
    // And the map does something: the flat plane without it is far off.
    let flat_mean = rel(&plain, &displaced).iter().sum::<f64>() / errors.len() as f64;
    assert!(flat_mean > 5.0 * mean, "flat {flat_mean} vs mapped {mean}");
}

/// The OBJ's triangles as corners (position, normal, uv), read here
/// (v, vt, vn and triangular f lines only).
fn obj_corners(text: &str) -> Vec<[[f32; 8]; 3]> {
    let (mut v, mut vt, mut vn) = (Vec::new(), Vec::new(), Vec::new());
    let mut faces = Vec::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        let nums = |it: std::str::SplitWhitespace| -> Vec<f32> {
            it.map(|s| s.parse().unwrap()).collect()
        };
        match it.next() {
            Some("v") => v.push(nums(it)),
            Some("vt") => vt.push(nums(it)),
            Some("vn") => vn.push(nums(it)),
            Some("f") => {
                let c: Vec<[f32; 8]> = it
                    .map(|k| {
                        let i: Vec<usize> = k
                            .split('/')
                            .map(|s| s.parse::<usize>().unwrap() - 1)
                            .collect();
                        let (p, t, n) = (&v[i[0]], &vt[i[1]], &vn[i[2]]);
                        [p[0], p[1], p[2], n[0], n[1], n[2], t[0], t[1]]
                    })
                    .collect();
                faces.push([c[0], c[1], c[2]]);
            }
            _ => {}
        }
    }
    faces
}

struct Direct {
    corners: Vec<[[f32; 8]; 3]>,
    tangents: Vec<[f32; 4]>,
}

impl mikktspace::Geometry for Direct {
    fn num_faces(&self) -> usize {
        self.corners.len()
    }
    fn num_vertices_of_face(&self, _: usize) -> usize {
        3
    }
    fn position(&self, f: usize, v: usize) -> [f32; 3] {
        let c = self.corners[f][v];
        [c[0], c[1], c[2]]
    }
    fn normal(&self, f: usize, v: usize) -> [f32; 3] {
        let c = self.corners[f][v];
        [c[3], c[4], c[5]]
    }
    fn tex_coord(&self, f: usize, v: usize) -> [f32; 2] {
        let c = self.corners[f][v];
        [c[6], c[7]]
    }
    fn set_tangent_encoded(&mut self, t: [f32; 4], f: usize, v: usize) {
        self.tangents[f * 3 + v] = t;
    }
}

#[test]
fn loaded_tangents_are_mikktspace_s_on_a_mirrored_uv_mesh() {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/models");
    let text = std::fs::read_to_string(dir.join("mirrored-uv.obj")).unwrap();
    // MikkTSpace called directly on the OBJ's corners.
    let corners = obj_corners(&text);
    let mut direct = Direct {
        tangents: vec![[0.0; 4]; corners.len() * 3],
        corners,
    };
    assert!(mikktspace::generate_tangents(&mut direct));
    // The loader: welded vertices, MikkTSpace, split seams, placed.
    let read = files(vec![
        ("m.obj".into(), text.clone().into_bytes()),
        ("n.png".into(), png(1, 1, |_, _| [128, 128, 255])),
    ]);
    let toml = "[camera]\neye = [0.0, 0.0, 4.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 40.0\nnear = 0.1\nfar = 10.0\n\n[[mesh]]\nobj = \"m.obj\"\nmaterial = \"m\"\n\n[materials.m]\nmodel = \"lambert\"\nbase_color = [0.5, 0.5, 0.5]\nnormal_texture = \"n.png\"\n";
    let s = load(toml, &read).unwrap();
    let d = &s.data;
    assert_eq!(d.triangles.len(), direct.corners.len());
    let mut seen_signs = std::collections::BTreeSet::new();
    for (t, tri) in d.triangles.iter().enumerate() {
        for (k, &vi) in tri.iter().enumerate() {
            let c = direct.corners[t][k];
            let p = d.positions[vi as usize];
            assert!((p - glam::Vec3::new(c[0], c[1], c[2])).length() < 1e-6);
            let got = d.tangents[vi as usize];
            let want = direct.tangents[3 * t + k];
            for i in 0..4 {
                assert!(
                    (got[i] - want[i]).abs() < 1e-6,
                    "triangle {t} corner {k}: {got} vs {want:?}"
                );
            }
            seen_signs.insert(want[3] as i32);
        }
    }
    // The mirrored half has the other handedness, and the 3 vertices of
    // the seam were split in two.
    assert_eq!(seen_signs.into_iter().collect::<Vec<_>>(), [-1, 1]);
    assert_eq!(d.positions.len(), 15 + 3);
}

#[test]
fn bad_map_fields_are_named() {
    let read = files(vec![("t.png".into(), png(1, 1, |_, _| [1, 2, 3]))]);
    let base = format!("{SPHERE}[materials.m]\nbase_color = [0.5, 0.5, 0.5]\n");
    for (extra, field) in [
        ("model = \"lambert\"\nmetallic_roughness_texture = \"t.png\"\n", "materials.m.metallic_roughness_texture"),
        ("model = \"lambert\"\nocclusion_texture = \"t.png\"\nocclusion_strength = 2.0\n", "materials.m.occlusion_strength"),
        ("model = \"lambert\"\nnormal_texture = \"t.png\"\nnormal_scale = nan\n", "materials.m.normal_scale"),
        ("model = \"lambert\"\nemissive = [-1.0, 0.0, 0.0]\n", "materials.m.emissive"),
        ("model = \"lambert\"\nbase_color_texture = \"t.png\"\ntexture_filter = \"anisotropic:17\"\n", "materials.m.texture_filter"),
        ("model = \"lambert\"\nnormal_texture = \"missing.png\"\n", "materials.m.normal_texture"),
        ("model = \"metallic_roughness\"\nroughness = 0.5\nmetallic_roughness_texture = \"missing.png\"\n", "materials.m.metallic_roughness_texture"),
        (
            "model = \"lambert\"\ntexture_wrap = [\"repeat\", \"sideways\"]\n",
            "materials.m.texture_wrap",
        ),
    ] {
        let err = load(&format!("{base}{extra}"), &read).err().unwrap();
        assert!(err.contains(field), "{field}: {err}");
    }
}

#[test]
fn texture_maps_fixture_renders_and_shading_paths_agree() {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/scenes/texture-maps.toml");
    let s = specula::scene::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let mut settings = RenderSettings::from_scene(&s);
    (settings.width, settings.height) = (320, 180);
    let a = render_scene(&s, &settings, 0.0).unwrap().hdr();
    settings.path = specula_raster::frame::ShadePath::Scalar;
    let b = render_scene(&s, &settings, 0.0).unwrap().hdr();
    assert!(a.iter().flatten().all(|v| v.is_finite()));
    // The same kernels one lane at a time: equal up to f32 rounding (and
    // the rare anisotropic tap count or mip level that rounds the other
    // way at an integer).
    let off = a
        .iter()
        .zip(&b)
        .filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > 1e-3 * q[c].abs().max(0.05)))
        .count();
    assert!(off * 1000 < a.len(), "{off} pixels differ");
}

#[test]
fn a_forced_filter_replaces_every_material_s_own() {
    // A material asking for nearest, forced to trilinear, renders as the
    // same material asking for trilinear.
    let checker = png(16, 16, |x, y| {
        if (x / 2 + y / 2) % 2 == 0 {
            [250, 250, 250]
        } else {
            [10, 10, 10]
        }
    });
    let read = files(vec![("c.png".into(), checker)]);
    let light = "[[light]]\ntype = \"directional\"\ndirection = [0.0, -0.3, -1.0]\nirradiance = [2.0, 2.0, 2.0]\n";
    let scene = |filter: &str| {
        format!("{SPHERE}{light}[materials.m]\nmodel = \"lambert\"\nbase_color = [1, 1, 1]\nbase_color_texture = \"c.png\"\ntexture_filter = \"{filter}\"\n")
    };
    let mut forced = load(&scene("nearest"), &read).unwrap();
    let nearest = hdr(&forced);
    forced
        .data
        .force_texture_filter(specula_raster::texture::Filter::Trilinear);
    let trilinear = hdr(&load(&scene("trilinear"), &read).unwrap());
    assert_eq!(hdr(&forced), trilinear);
    assert_ne!(nearest, trilinear);
}

/// The ray from `o` along `d` against the triangle (a, b, c): the
/// barycentrics (b0, b1, b2) of the hit, if any (Möller–Trumbore).
fn hit_triangle(o: [f64; 3], d: [f64; 3], p: [[f64; 3]; 3]) -> Option<[f64; 3]> {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (e1, e2) = (sub(p[1], p[0]), sub(p[2], p[0]));
    let h = cross(d, e2);
    let det = dot(e1, h);
    if det.abs() < 1e-12 {
        return None;
    }
    let s = sub(o, p[0]);
    let u = dot(s, h) / det;
    let q = cross(s, e1);
    let v = dot(d, q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && dot(e2, q) / det > 0.0).then_some([1.0 - u - v, u, v])
}

#[test]
fn mikktspace_tangents_reach_the_shading_frame_through_the_raster() {
    // The mirrored-uv patch under a uniform normal map that tilts the
    // normal toward the tangent, seen from above: each pixel's radiance
    // is the Lambertian one of the normal bent in the frame interpolated
    // (as the raster does, at the ray's hit) from the corner tangents the
    // mikktspace crate gives directly. The mirrored half tilts the other
    // way; a lost handedness or tangent would show there.
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/models");
    let text = std::fs::read_to_string(dir.join("mirrored-uv.obj")).unwrap();
    let corners = obj_corners(&text);
    let mut direct = Direct {
        tangents: vec![[0.0; 4]; corners.len() * 3],
        corners,
    };
    assert!(mikktspace::generate_tangents(&mut direct));
    let texel = [191u8, 128, 238];
    let read = files(vec![
        ("m.obj".into(), text.into_bytes()),
        ("n.png".into(), png(1, 1, move |_, _| texel)),
    ]);
    let size = 64u32;
    let toml = format!("[camera]\neye = [0.0, 0.0, 4.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nfov_y = 40.0\nnear = 0.1\nfar = 10.0\n\n[output]\nwidth = {size}\nheight = {size}\n\n[[mesh]]\nobj = \"m.obj\"\nmaterial = \"m\"\n\n[materials.m]\nmodel = \"lambert\"\nbase_color = [0.5, 0.5, 0.5]\nnormal_texture = \"n.png\"\n\n[[light]]\ntype = \"directional\"\ndirection = [-1.0, 0.0, -1.0]\nirradiance = [1.0, 1.0, 1.0]\n");
    let img = hdr(&load(&toml, &read).unwrap());
    let m: [f64; 3] = texel.map(|b| 2.0 * b as f64 / 255.0 - 1.0);
    let l = [0.5f64.sqrt(), 0.0, 0.5f64.sqrt()];
    let norm = |a: [f64; 3]| {
        let k = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        a.map(|c| c / k)
    };
    let (mut checked, mut mirrored) = (0, 0);
    let ty = (20.0f64).to_radians().tan();
    for y in 0..size {
        for x in 0..size {
            let nx = (x as f64 + 0.5) * 2.0 / size as f64 - 1.0;
            let ny = 1.0 - (y as f64 + 0.5) * 2.0 / size as f64;
            let d = norm([nx * ty, ny * ty, -1.0]);
            let o = [0.0, 0.0, 4.0];
            let hit = direct.corners.iter().enumerate().find_map(|(t, c)| {
                let p = c.map(|k| [k[0] as f64, k[1] as f64, k[2] as f64]);
                hit_triangle(o, d, p).map(|b| (t, b))
            });
            let Some((t, b)) = hit else { continue };
            let c = direct.corners[t];
            let at = |k: usize| -> [f64; 3] {
                core::array::from_fn(|i| (0..3).map(|j| b[j] * c[j][k + i] as f64).sum())
            };
            let hx = at(0)[0];
            // Away from the seam (where the frame jumps between pixels)
            // and the border.
            if hx.abs() < 0.1 || hx.abs() > 0.9 || at(0)[1].abs() > 0.9 {
                continue;
            }
            let n = norm(at(3));
            let tan: [f64; 3] = core::array::from_fn(|i| {
                (0..3)
                    .map(|j| b[j] * direct.tangents[3 * t + j][i] as f64)
                    .sum()
            });
            let k = tan[0] * n[0] + tan[1] * n[1] + tan[2] * n[2];
            let tan = norm([tan[0] - n[0] * k, tan[1] - n[1] * k, tan[2] - n[2] * k]);
            let sign = direct.tangents[3 * t][3] as f64;
            let bit = [
                sign * (n[1] * tan[2] - n[2] * tan[1]),
                sign * (n[2] * tan[0] - n[0] * tan[2]),
                sign * (n[0] * tan[1] - n[1] * tan[0]),
            ];
            let bent = norm(core::array::from_fn(|i| {
                tan[i] * m[0] + bit[i] * m[1] + n[i] * m[2]
            }));
            let cos = (bent[0] * l[0] + bent[1] * l[1] + bent[2] * l[2]).max(0.0);
            let want = 0.5 / PI * cos;
            let got = img[(y * size + x) as usize][0] as f64;
            assert!(
                (got - want).abs() < 1e-3 * want.max(0.01),
                "pixel ({x}, {y}) at x = {hx:.3}: {got} vs {want}"
            );
            checked += 1;
            mirrored += (sign < 0.0) as usize;
        }
    }
    assert!(
        checked > 1000 && mirrored > 400,
        "{checked} pixels, {mirrored} mirrored"
    );
}
