//! The BoxTextured sample (fixtures/models/gltf/): the Khronos file is
//! Draco-compressed (KHR_draco_mesh_compression required), which is
//! refused with a clear error; its decompressed copy
//! (BoxTextured-plain.glb, made by decompress_box.py there) is rendered by
//! `specula render model.glb`: it renders with the documented defaults
//! (camera framing the bounding sphere from +Z, a key light and a uniform
//! environment), and the face toward the camera shows the texture: each
//! pixel matches the texel at its uv under that lighting, computed here in
//! f64 — the geometry and image read with the `gltf` crate's own reader,
//! the BRDF written from glTF's Appendix B, its environment term by
//! quadrature — and the fixture scene placing it with `[[mesh]] gltf`
//! renders too.

mod common;

use std::f64::consts::PI;

type V = [f64; 3];
fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: V) -> V {
    let l = dot(a, a).sqrt();
    a.map(|x| x / l)
}

/// glTF's metallic-roughness BRDF at metallic 0, roughness 1 (α = 1),
/// normal +z: the specular D·V·F and the diffuse weight (1 − F)/π that
/// multiplies the base colour [glTF 2.0, Appendix B].
fn brdf(wi: V, wo: V) -> (f64, f64) {
    let (mi, mo) = (wi[2], wo[2]);
    if mi <= 0.0 || mo <= 0.0 {
        return (0.0, 0.0);
    }
    let h = norm([wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]]);
    let a2 = 1.0f64;
    let nh = h[2];
    let d = a2 / (PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
    let v =
        0.5 / (mo * (mi * mi * (1.0 - a2) + a2).sqrt() + mi * (mo * mo * (1.0 - a2) + a2).sqrt());
    let f = 0.04 + 0.96 * (1.0 - dot(wo, h)).powi(5);
    (d * v * f, (1.0 - f) / PI)
}

/// ∫ f cos θi dω over the hemisphere, as (specular, diffuse weight), by
/// the midpoint rule in (cos θi, φ).
fn albedo(wo: V) -> (f64, f64) {
    let (n, m) = (256, 256);
    let (mut s, mut d) = (0.0, 0.0);
    for i in 0..n {
        let mu = (i as f64 + 0.5) / n as f64;
        let st = (1.0 - mu * mu).sqrt();
        for j in 0..m {
            let phi = 2.0 * PI * (j as f64 + 0.5) / m as f64;
            let (a, b) = brdf([st * phi.cos(), st * phi.sin(), mu], wo);
            s += a * mu;
            d += b * mu;
        }
    }
    let w = 2.0 * PI / (n * m) as f64;
    (s * w, d * w)
}

fn srgb_to_linear(c: u8) -> f64 {
    let c = c as f64 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[test]
fn the_box_renders_with_its_texture_on_the_face_toward_the_camera() {
    let dir = common::temp_dir("gltf_box");
    let draco = common::fixtures().join("models/gltf/BoxTextured.glb");
    let run = common::specula(
        &["render", draco.to_str().unwrap(), "-o", "draco.png"],
        &dir,
    );
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains("BoxTextured.glb: extensionsRequired[0]: \"KHR_draco_mesh_compression\" is required by the file and not supported here"),
        "{stderr}"
    );
    let glb = common::fixtures().join("models/gltf/BoxTextured-plain.glb");
    let (out, exr) = (dir.join("box.png"), dir.join("box.exr"));
    let side = 601u32;
    let run = common::specula(
        &[
            "render",
            glb.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--exr",
            exr.to_str().unwrap(),
            "--width",
            &side.to_string(),
            "--height",
            &side.to_string(),
        ],
        &dir,
    );
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    for said in ["no camera in the file", "no lights in the file"] {
        assert!(stderr.contains(said), "{said:?} not in {stderr}");
    }
    let img = image::open(&exr).unwrap().to_rgb32f();

    // The sample, read independently: the face whose normal the node's
    // matrix (x, y, z) → (x, z, −y) turns to +z is the local −y face.
    let bytes = std::fs::read(&glb).unwrap();
    let g = gltf::Gltf::from_slice(&bytes).unwrap();
    let blob = g.blob.as_deref().unwrap();
    let prim = g.meshes().next().unwrap().primitives().next().unwrap();
    let reader = prim.reader(|_| Some(blob));
    let pos: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
    let nrm: Vec<[f32; 3]> = reader.read_normals().unwrap().collect();
    let uvs: Vec<[f32; 2]> = reader.read_tex_coords(0).unwrap().into_f32().collect();
    // uv at local (x, z) on the face, bilinear between its four corners.
    let corner = |sx: f32, sz: f32| -> [f64; 2] {
        let k = (0..pos.len())
            .find(|&k| nrm[k][1] < -0.9 && pos[k][0] * sx > 0.0 && pos[k][2] * sz > 0.0)
            .expect("face corner");
        uvs[k].map(|t| t as f64)
    };
    let (c00, c10, c01, c11) = (
        corner(-1.0, -1.0),
        corner(1.0, -1.0),
        corner(-1.0, 1.0),
        corner(1.0, 1.0),
    );
    let uv_at = |x: f64, z: f64| -> [f64; 2] {
        let (s, t) = (x + 0.5, z + 0.5);
        let lerp =
            |a: [f64; 2], b: [f64; 2], w: f64| [a[0] + (b[0] - a[0]) * w, a[1] + (b[1] - a[1]) * w];
        lerp(lerp(c00, c10, s), lerp(c01, c11, s), t)
    };
    let gltf::image::Source::View { view, .. } = g.images().next().unwrap().source() else {
        panic!("the image is in the GLB")
    };
    let tex = image::load_from_memory(&blob[view.offset()..view.offset() + view.length()])
        .unwrap()
        .to_rgb8();
    let (tw, th) = (tex.width() as i64, tex.height() as i64);
    // Bilinear on level 0 in linear colour, repeat wrapping; glTF's uv
    // (0, 0) is the image's top-left corner, its first row.
    let texel = |uv: [f64; 2]| -> V {
        let (x, y) = (uv[0] * tw as f64 - 0.5, uv[1] * th as f64 - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let mut c = [0.0; 3];
        for (dx, dy, w) in [
            (0, 0, (1.0 - fx) * (1.0 - fy)),
            (1, 0, fx * (1.0 - fy)),
            (0, 1, (1.0 - fx) * fy),
            (1, 1, fx * fy),
        ] {
            let px = tex.get_pixel(
                (x0 as i64 + dx).rem_euclid(tw) as u32,
                (y0 as i64 + dy).rem_euclid(th) as u32,
            );
            for k in 0..3 {
                c[k] += w * srgb_to_linear(px[k]);
            }
        }
        c
    };

    // The documented defaults: bounding sphere of the unit box (centre 0,
    // radius √3/2) framed from +z at fov 40°; key light toward (1, 2, 2)/3
    // with irradiance 3; uniform environment 0.3.
    let radius = 0.75f64.sqrt();
    let d = radius / 20f64.to_radians().sin();
    let tan = 20f64.to_radians().tan();
    let to_key = [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
    let mut errors = Vec::new();
    let step = 6;
    for j in (0..side).step_by(step) {
        for i in (0..side).step_by(step) {
            let x = (2.0 * (i as f64 + 0.5) / side as f64 - 1.0) * tan;
            let y = (1.0 - 2.0 * (j as f64 + 0.5) / side as f64) * tan;
            // The ray from (0, 0, d) meets the face's plane z = 0.5 at t.
            let t = d - 0.5;
            let p = [x * t, y * t, 0.5];
            // The central 80 % of the face (its edges shade the box's rim).
            if p[0].abs() > 0.4 || p[1].abs() > 0.4 {
                continue;
            }
            let wo = norm(sub([0.0, 0.0, d], p));
            let c = texel(uv_at(p[0], p[1]));
            let (s, dw) = brdf(to_key, wo);
            let (es, ed) = albedo(wo);
            let got = img.get_pixel(i, j);
            for k in 0..3 {
                let want = 3.0 * to_key[2] * (s + dw * c[k]) + 0.3 * (es + ed * c[k]);
                errors.push((got[k] as f64 - want).abs() / want.max(0.05));
            }
        }
    }
    errors.sort_by(f64::total_cmp);
    let at = |q: f64| errors[((errors.len() - 1) as f64 * q) as usize];
    eprintln!(
        "{} channel samples: median relative error {:.2e}, 90th percentile {:.2e}, max {:.2e}",
        errors.len(),
        at(0.5),
        at(0.9),
        at(1.0)
    );
    // The render's texture filter and the split-sum tables' interpolation
    // differ from this reference by a few 1e-3 at most (largest across the
    // logo's sharp edges).
    assert!(errors.len() > 5000);
    assert!(
        at(0.5) < 2e-3 && at(1.0) < 1e-2,
        "median {:e}, max {:e}",
        at(0.5),
        at(1.0)
    );
}

#[test]
fn the_gltf_box_fixture_scene_renders() {
    let scene = specula::scene::load_scene(&common::fixtures().join("scenes/gltf-box.toml"))
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(scene
        .inputs
        .iter()
        .any(|p| p.ends_with("models/gltf/BoxTextured-plain.glb")));
    let set = specula::render::RenderSettings::from_scene(&scene);
    let r = specula::render::render_scene(&scene, &set, 0.0).unwrap();
    let hdr = r.hdr();
    assert!(hdr.iter().all(|p| p.iter().all(|c| c.is_finite())));
    // The texture's colours show: some pixels are far from grey.
    let colourful = hdr
        .iter()
        .filter(|p| (p[0] - p[2]).abs() > 0.1 * (p[0] + p[2]).max(1e-3) && p[0] + p[2] > 0.05)
        .count();
    assert!(colourful > 1000, "{colourful} colourful pixels");
}
