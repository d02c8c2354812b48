//! glTF's texture and material extensions and vertex attributes as they
//! reach the pixels: KHR_texture_transform against the same uvs
//! transformed in the file and against the extension's own examples.
//! Every expected value is computed here from the specifications' text.

mod common;

use common::gltf_doc::{png_uri, srgb_decode, Buf};
use serde_json::{json, Value};
use std::f64::consts::PI;

/// A quad's uvs in glTF's convention ((0, 0) at the top-left of the
/// image), its corners in the order (−1, −1), (1, −1), (1, 1), (−1, 1).
const QUAD_UV: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];

/// What a test quad carries besides its material.
#[derive(Clone, Default)]
struct Quad {
    uv: Option<[[f32; 2]; 4]>,
    /// NORMAL of every vertex (default +z).
    normal: Option<[f32; 3]>,
    /// Extra attributes by name.
    attributes: Vec<(&'static str, Attr)>,
    images: Vec<String>,
    /// The glTF sampler every texture uses.
    sampler: Option<Value>,
}

/// An attribute's values.
#[derive(Clone)]
enum Attr {
    /// Float components, and the accessor type ("VEC3", …).
    Floats(Vec<f32>, &'static str),
    /// Little-endian bytes of normalized integers: the bytes, the
    /// componentType, the element count and the accessor type.
    Normalized(Vec<u8>, u32, usize, &'static str),
}

/// A 2 × 2 unit quad facing +z with `material`, as a glTF document.
fn quad_doc(material: Value, q: &Quad) -> String {
    let mut b = Buf::default();
    let pos = b.floats(
        &[
            -1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0,
        ],
        "VEC3",
    );
    let nrm = b.floats(&q.normal.unwrap_or([0.0, 0.0, 1.0]).repeat(4), "VEC3");
    let uv = b.floats(q.uv.unwrap_or(QUAD_UV).as_flattened(), "VEC2");
    let idx = b.u16s(&[0, 1, 2, 0, 2, 3]);
    let mut attributes = json!({"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv});
    for (name, attr) in &q.attributes {
        let a = match attr {
            Attr::Floats(values, ty) => b.floats(values, ty),
            Attr::Normalized(bytes, component, count, ty) => {
                let view = b.view(bytes, None);
                b.accessor(json!({"bufferView": view, "componentType": component,
                    "normalized": true, "count": count, "type": ty}))
            }
        };
        attributes[*name] = json!(a);
    }
    let textures: Vec<Value> = (0..q.images.len())
        .map(|i| json!({"source": i, "sampler": 0}))
        .collect();
    let images: Vec<Value> = q.images.iter().map(|u| json!({ "uri": u })).collect();
    let sampler = q
        .sampler
        .clone()
        .unwrap_or(json!({"magFilter": 9728, "minFilter": 9728}));
    b.doc(json!({
        "extensionsUsed": ["KHR_texture_transform", "KHR_materials_unlit"],
        "meshes": [{"primitives": [{"attributes": attributes, "indices": idx, "material": 0}]}],
        "materials": [material],
        "textures": textures,
        "samplers": [sampler],
        "images": images,
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    }))
    .to_string()
}

/// Pixels of the rendered images (linear radiance, row-major).
const SIZE: usize = 64;

/// The quad 9 units in front of the camera, filling the middle ~58 pixels
/// of 64, lit head-on by a directional light of irradiance 2 (no
/// environment); every pixel's radiance, and the scene's warnings.
fn render(doc: &str) -> (Vec<[f32; 3]>, Vec<String>) {
    let toml = r#"
[camera]
eye = [0.0, 0.0, 10.0]
target = [0.0, 0.0, 0.0]
fov_y = 14.0
near = 1.0
far = 100.0
[output]
width = 64
height = 64
[[mesh]]
gltf = "quad.gltf"
translate = [0.0, 0.0, 1.0]
[[light]]
type = "directional"
direction = [0.0, 0.0, -1.0]
irradiance = [2.0, 2.0, 2.0]
"#;
    let s = common::scene(toml, &[("quad.gltf", doc)]);
    let set = specula::render::RenderSettings::from_scene(&s);
    let r = specula::render::render_scene(&s, &set, 0.0).unwrap();
    let px = (0..SIZE * SIZE)
        .map(|i| r.frame.buffers.color.get(i))
        .collect();
    (px, s.warnings.clone())
}

/// Radiance of the head-on lit rough dielectric (metallic 0, roughness 1)
/// of base colour c, seen along the normal: E · ((1 − F0) c/π + D V F0)
/// with F0 = 0.04, D(n) = 1/π (α = 1), V = 1/4, E = 2.
fn lit_rough(c: f64) -> f64 {
    2.0 * (0.96 * c + 0.01) / PI
}

/// The 4 × 4 test image: texel (column i, row j from the top) is
/// (32 + 64 i, 32 + 64 j, 96 + 32 (i + j)) in sRGB bytes; every texel
/// differs from every other.
fn image_4x4() -> (Vec<u8>, impl Fn(usize, usize) -> [u8; 3]) {
    let texel = |i: usize, j: usize| {
        [
            (32 + 64 * i) as u8,
            (32 + 64 * j) as u8,
            (96 + 32 * (i + j)).min(255) as u8,
        ]
    };
    let bytes = (0..4)
        .flat_map(|j| (0..4).flat_map(move |i| texel(i, j)))
        .collect();
    (bytes, texel)
}

fn rough_textured(extension: Option<Value>) -> Value {
    let mut tex = json!({"index": 0});
    if let Some(e) = extension {
        tex["extensions"] = json!({ "KHR_texture_transform": e });
    }
    json!({"pbrMetallicRoughness": {"baseColorTexture": tex,
        "metallicFactor": 0.0, "roughnessFactor": 1.0}})
}

/// The pixel at the centre of each quarter of the quad, in the order
/// top-left, top-right, bottom-left, bottom-right (the quad spans pixels
/// ~3 to ~61; their centres are 13.5 pixels from the image's middle).
const QUARTERS: [(usize, usize); 4] = [(18, 18), (45, 18), (18, 45), (45, 45)];

/// KHR_texture_transform's first example: offset (0, 1), rotation π/2,
/// scale ½ "utilizes only the lower left quadrant of the source image,
/// rotated clockwise 90°". The lower-left quadrant of the 4 × 4 image is
/// columns 0–1, rows 2–3; turned clockwise a quarter turn, its bottom-left
/// texel comes to the top-left, its top-left to the top-right, its
/// bottom-right to the bottom-left and its top-right to the bottom-right.
/// The second example, offset (0, 1) and scale (1, −1), "inverts the T
/// axis": the image upside down.
#[test]
fn texture_transform_follows_the_extension_examples() {
    let (bytes, texel) = image_4x4();
    let q = Quad {
        images: vec![png_uri(4, 4, &bytes)],
        ..Default::default()
    };
    let check = |doc: &str, want: [(usize, usize); 4], what: &str| {
        let (px, warnings) = render(doc);
        assert!(
            !warnings.iter().any(|w| w.contains("KHR_texture_transform")),
            "{what}: {warnings:?}"
        );
        for ((x, y), (i, j)) in QUARTERS.into_iter().zip(want) {
            let w = texel(i, j).map(|b| lit_rough(srgb_decode(b)));
            let got = px[y * SIZE + x];
            for c in 0..3 {
                // The view is up to ~5° off the normal at these pixels,
                // which moves the specular term by ~1e-5.
                assert!(
                    (got[c] as f64 - w[c]).abs() <= 1e-3 * w[c] + 1e-4,
                    "{what}: pixel ({x}, {y}) {got:?}, want texel ({i}, {j}) = {w:?}"
                );
            }
        }
    };
    let example1 = quad_doc(
        rough_textured(Some(
            // The example writes π/2 as 1.57079632679.
            json!({"offset": [0, 1], "rotation": std::f64::consts::FRAC_PI_2, "scale": [0.5, 0.5]}),
        )),
        &q,
    );
    // Quarter centres sample the middle of each texel of the quadrant.
    check(
        &example1,
        [(0, 3), (0, 2), (1, 3), (1, 2)],
        "lower-left quadrant, clockwise",
    );
    let example2 = quad_doc(
        rough_textured(Some(json!({"offset": [0, 1], "scale": [1, -1]}))),
        &q,
    );
    // Without the transform the quarters show texels (1, 1), (2, 1),
    // (1, 2), (2, 2); upside down, rows 1 and 2 swap.
    check(
        &example2,
        [(1, 2), (2, 2), (1, 1), (2, 1)],
        "T axis inverted",
    );
    let plain = quad_doc(rough_textured(None), &q);
    check(&plain, [(1, 1), (2, 1), (1, 2), (2, 2)], "no transform");
}

/// A 3 × 3 matrix product (row-major).
fn mul3(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// T(offset) · R(rotation) · S(scale) as the extension defines it, with
/// R = [[cos, sin], [−sin, cos]] (the rotation its first example needs).
fn spec_matrix(offset: [f64; 2], rotation: f64, scale: [f64; 2]) -> [[f64; 3]; 3] {
    let t = [
        [1.0, 0.0, offset[0]],
        [0.0, 1.0, offset[1]],
        [0.0, 0.0, 1.0],
    ];
    let (s, c) = rotation.sin_cos();
    let r = [[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]];
    let sc = [[scale[0], 0.0, 0.0], [0.0, scale[1], 0.0], [0.0, 0.0, 1.0]];
    mul3(mul3(t, r), sc)
}

/// A transformed texture shows what the same quad shows with its uvs
/// transformed in the file, pixel for pixel (up to the rounding of the
/// uvs: 1e-4 relative), through a filtered (bilinear, mipmapped) repeating
/// sampler so that the comparison also covers the derivatives the level
/// of detail comes from. On every slot: base colour, and emissive (an
/// unlit-independent, additive one).
#[test]
fn texture_transform_equals_uvs_transformed_in_the_file() {
    let (bytes, _) = image_4x4();
    let sampler = json!({"magFilter": 9729, "minFilter": 9987});
    let (offset, rotation, scale) = ([0.3, -0.2], 0.7, [1.5, 0.8]);
    let m = spec_matrix(offset, rotation, scale);
    let moved: [[f32; 2]; 4] = QUAD_UV.map(|[u, v]| {
        let (u, v) = (u as f64, v as f64);
        [
            (m[0][0] * u + m[0][1] * v + m[0][2]) as f32,
            (m[1][0] * u + m[1][1] * v + m[1][2]) as f32,
        ]
    });
    let ext = json!({"offset": offset, "rotation": rotation, "scale": scale});
    let images = vec![png_uri(4, 4, &bytes)];
    let with_ext = |slot: &str, ext: Option<&Value>| {
        let mut tex = json!({"index": 0});
        if let Some(e) = ext {
            tex["extensions"] = json!({ "KHR_texture_transform": e });
        }
        match slot {
            "base" => json!({"pbrMetallicRoughness": {"baseColorTexture": tex,
                "metallicFactor": 0.0, "roughnessFactor": 1.0}}),
            _ => json!({"pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.2, 0.2, 1.0],
                "metallicFactor": 0.0, "roughnessFactor": 1.0},
                "emissiveFactor": [1.0, 1.0, 1.0], "emissiveTexture": tex}),
        }
    };
    for slot in ["base", "emissive"] {
        let transformed = quad_doc(
            with_ext(slot, Some(&ext)),
            &Quad {
                images: images.clone(),
                sampler: Some(sampler.clone()),
                ..Default::default()
            },
        );
        let in_file = quad_doc(
            with_ext(slot, None),
            &Quad {
                uv: Some(moved),
                images: images.clone(),
                sampler: Some(sampler.clone()),
                ..Default::default()
            },
        );
        let untransformed = quad_doc(
            with_ext(slot, None),
            &Quad {
                images: images.clone(),
                sampler: Some(sampler.clone()),
                ..Default::default()
            },
        );
        let (a, _) = render(&transformed);
        let (b, _) = render(&in_file);
        let (c, _) = render(&untransformed);
        let mut lit = 0;
        let mut moved_px = 0;
        for (i, ((p, q), r)) in a.iter().zip(&b).zip(&c).enumerate() {
            lit += usize::from(q[0] > 0.0);
            moved_px += usize::from((0..3).any(|k| (q[k] - r[k]).abs() > 0.01 * r[k]));
            for k in 0..3 {
                assert!(
                    (p[k] - q[k]).abs() <= 1e-4 * q[k].max(1e-3),
                    "{slot}: pixel {i}: {p:?} vs uvs in the file {q:?}"
                );
            }
        }
        assert!(lit > 2500, "{slot}: {lit} lit pixels");
        assert!(
            moved_px > 1000,
            "{slot}: the transform shows ({moved_px} pixels)"
        );
    }
    // The extension's texCoord overrides the reference's: the moved uvs
    // as TEXCOORD_1 (TEXCOORD_0 all zero) read through {"texCoord": 1}
    // show what they show as TEXCOORD_0.
    let over = quad_doc(
        with_ext("base", Some(&json!({"texCoord": 1}))),
        &Quad {
            uv: Some([[0.0; 2]; 4]),
            attributes: vec![(
                "TEXCOORD_1",
                Attr::Floats(moved.as_flattened().to_vec(), "VEC2"),
            )],
            images: images.clone(),
            sampler: Some(sampler.clone()),
            ..Default::default()
        },
    );
    let in_file = quad_doc(
        with_ext("base", None),
        &Quad {
            uv: Some(moved),
            images,
            sampler: Some(sampler),
            ..Default::default()
        },
    );
    let (a, _) = render(&over);
    let (b, _) = render(&in_file);
    assert_eq!(a, b, "texCoord override");
}

/// KHR_materials_unlit shows base colour factor × texel (sRGB decoded, as
/// the spec's base colour texture is) whatever the light: the pixels at
/// the quarters' centres are those products, computed here.
#[test]
fn unlit_shows_factor_times_texel() {
    let (bytes, texel) = image_4x4();
    let factor = [0.5, 0.8, 1.0];
    let doc = quad_doc(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.8, 1.0, 1.0],
            "baseColorTexture": {"index": 0}},
            "extensions": {"KHR_materials_unlit": {}}}),
        &Quad {
            images: vec![png_uri(4, 4, &bytes)],
            ..Default::default()
        },
    );
    let (px, warnings) = render(&doc);
    assert!(
        !warnings.iter().any(|w| w.contains("unlit")),
        "{warnings:?}"
    );
    for ((x, y), (i, j)) in QUARTERS.into_iter().zip([(1, 1), (2, 1), (1, 2), (2, 2)]) {
        let t = texel(i, j);
        let got = px[y * SIZE + x];
        for c in 0..3 {
            let want = factor[c] * srgb_decode(t[c]);
            assert!(
                (got[c] as f64 - want).abs() <= 1e-5 * want.max(1e-3),
                "pixel ({x}, {y}): {got:?}, want {factor:?} × texel {t:?}"
            );
        }
    }
    // Without a texture: the factor alone, on every pixel of the quad.
    let plain = quad_doc(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.25, 0.5, 0.75, 1.0]},
            "extensions": {"KHR_materials_unlit": {}}}),
        &Quad::default(),
    );
    let (px, _) = render(&plain);
    let on_quad = px.iter().filter(|p| p[0] > 0.0).count();
    assert!(on_quad > 2500, "{on_quad}");
    for p in px.iter().filter(|p| p[0] > 0.0) {
        assert_eq!(*p, [0.25, 0.5, 0.75], "unlit constant");
    }
}

/// COLOR_0 multiplies the base colour: a quad whose every vertex has the
/// colour k renders as the same quad with k folded into its
/// baseColorFactor (pixel for pixel), for float RGB, normalized u8 RGBA
/// and normalized u16 RGBA colours (k = v/255 and v/65535 computed here),
/// lit and unlit, with a base colour texture.
#[test]
fn a_vertex_colour_equals_the_same_factor_in_base_color_factor() {
    let (bytes, _) = image_4x4();
    let images = vec![png_uri(4, 4, &bytes)];
    let base = [0.9, 0.7, 0.5];
    let material = |factor: [f64; 3], unlit: bool| {
        let mut m = json!({"pbrMetallicRoughness": {
            "baseColorFactor": [factor[0], factor[1], factor[2], 1.0],
            "baseColorTexture": {"index": 0},
            "metallicFactor": 0.0, "roughnessFactor": 0.6}});
        if unlit {
            m["extensions"] = json!({"KHR_materials_unlit": {}});
        }
        m
    };
    let u8s: Vec<u8> = [128u8, 64, 255, 200].repeat(4);
    let u16s: Vec<u8> = [40000u16, 1000, 65535, 7]
        .repeat(4)
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let cases = [
        (
            "float VEC3",
            [0.5, 0.25, 1.0],
            Attr::Floats([0.5f32, 0.25, 1.0].repeat(4), "VEC3"),
        ),
        (
            "u8 VEC4",
            [128.0 / 255.0, 64.0 / 255.0, 1.0],
            Attr::Normalized(u8s, 5121, 4, "VEC4"),
        ),
        (
            "u16 VEC4",
            [40000.0 / 65535.0, 1000.0 / 65535.0, 1.0],
            Attr::Normalized(u16s, 5123, 4, "VEC4"),
        ),
    ];
    for (what, k, attr) in cases {
        for unlit in [false, true] {
            let coloured = quad_doc(
                material(base, unlit),
                &Quad {
                    images: images.clone(),
                    attributes: vec![("COLOR_0", attr.clone())],
                    ..Default::default()
                },
            );
            let folded = quad_doc(
                material(core::array::from_fn(|c| base[c] * k[c]), unlit),
                &Quad {
                    images: images.clone(),
                    ..Default::default()
                },
            );
            let (a, warnings) = render(&coloured);
            assert!(
                !warnings.iter().any(|w| w.contains("COLOR_0")),
                "{what}: {warnings:?}"
            );
            let (b, _) = render(&folded);
            let mut lit = 0;
            for (i, (p, q)) in a.iter().zip(&b).enumerate() {
                lit += usize::from(q[0] > 0.0);
                for c in 0..3 {
                    assert!(
                        (p[c] - q[c]).abs() <= 2e-6 * q[c].max(1e-3),
                        "{what}, unlit {unlit}: pixel {i}: {p:?} vs folded {q:?}"
                    );
                }
            }
            assert!(lit > 2500, "{what}: {lit}");
        }
    }
}

/// Vertex colours are interpolated perspective-correctly: an unlit quad
/// tilted in depth (z = 0.75 y) whose vertex colours are an affine
/// function of position, c(x, y) = (0.5 + 0.4 x, 0.5 + 0.4 y,
/// 0.5 + 0.2 x − 0.2 y), shows at every pixel c of the point its ray
/// hits, found here by intersecting the pixel centre's ray with the plane
/// (both triangles interpolate the same affine function, so the answer
/// does not depend on the diagonal). Interpolating in screen space
/// instead would be off by more than 1e-3 (checked below).
#[test]
fn vertex_colours_are_interpolated_perspective_correctly() {
    let c = |x: f64, y: f64| [0.5 + 0.4 * x, 0.5 + 0.4 * y, 0.5 + 0.2 * x - 0.2 * y];
    let corners = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let mut b = Buf::default();
    let pos: Vec<f32> = corners
        .iter()
        .flat_map(|[x, y]| [*x as f32, *y as f32, (0.75 * y) as f32])
        .collect();
    let pos = b.floats(&pos, "VEC3");
    let n = {
        let l = (0.75f64 * 0.75 + 1.0).sqrt();
        [0.0, (-0.75 / l) as f32, (1.0 / l) as f32]
    };
    let nrm = b.floats(&n.repeat(4), "VEC3");
    let col: Vec<f32> = corners
        .iter()
        .flat_map(|[x, y]| c(*x, *y).map(|v| v as f32))
        .collect();
    let col = b.floats(&col, "VEC3");
    let idx = b.u16s(&[0, 1, 2, 0, 2, 3]);
    let doc = b.doc(json!({
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm, "COLOR_0": col},
            "indices": idx, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {}, "extensions": {"KHR_materials_unlit": {}}}],
        "extensionsUsed": ["KHR_materials_unlit"],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    }));
    let toml = r#"
[camera]
eye = [0.0, 0.0, 10.0]
target = [0.0, 0.0, 0.0]
fov_y = 14.0
near = 1.0
far = 100.0
[output]
width = 64
height = 64
[[mesh]]
gltf = "quad.gltf"
"#;
    let s = common::scene(toml, &[("quad.gltf", &doc.to_string())]);
    let set = specula::render::RenderSettings::from_scene(&s);
    let r = specula::render::render_scene(&s, &set, 0.0).unwrap();
    let t = (7.0f64).to_radians().tan();
    let mut checked = 0;
    let mut worst_screen = 0.0f64;
    for y in 0..SIZE {
        for x in 0..SIZE {
            // The ray through the pixel centre: eye + s (nx t, ny t, −1).
            let nx = 2.0 * (x as f64 + 0.5) / SIZE as f64 - 1.0;
            let ny = 1.0 - 2.0 * (y as f64 + 0.5) / SIZE as f64;
            let s = 10.0 / (1.0 + 0.75 * ny * t);
            let (px, py) = (s * nx * t, s * ny * t);
            if px.abs() > 0.95 || py.abs() > 0.95 {
                continue;
            }
            let want = c(px, py);
            let got = r.frame.buffers.color.get(y * SIZE + x);
            for k in 0..3 {
                assert!(
                    (got[k] as f64 - want[k]).abs() <= 2e-5,
                    "pixel ({x}, {y}): {got:?}, want {want:?} at ({px}, {py})"
                );
            }
            // Screen-space interpolation would take y affine in ny
            // between the projections of the top (y = 1, z = 0.75) and
            // bottom (y = −1, z = −0.75) edges.
            let (top, bottom) = (1.0 / (9.25 * t), -1.0 / (10.75 * t));
            let y_screen = -1.0 + 2.0 * (ny - bottom) / (top - bottom);
            worst_screen = worst_screen.max(0.4 * (y_screen - py).abs());
            checked += 1;
        }
    }
    assert!(checked > 2000, "{checked} pixels checked");
    assert!(
        worst_screen > 1e-3,
        "the tilt tells perspective-correct from screen-space: {worst_screen}"
    );
}

/// [`render`] under a point light off the axis (so normals tilted along x
/// and along y light differently) and a uniform environment.
fn render_off_axis(doc: &str) -> Vec<[f32; 3]> {
    let toml = r#"
[camera]
eye = [0.0, 0.0, 10.0]
target = [0.0, 0.0, 0.0]
fov_y = 14.0
near = 1.0
far = 100.0
[output]
width = 64
height = 64
[[mesh]]
gltf = "quad.gltf"
translate = [0.0, 0.0, 1.0]
[[light]]
type = "point"
position = [1.5, 0.5, 4.0]
intensity = [8.0, 8.0, 8.0]
[environment]
uniform = [0.2, 0.2, 0.2]
"#;
    let s = common::scene(toml, &[("quad.gltf", doc)]);
    let set = specula::render::RenderSettings::from_scene(&s);
    let r = specula::render::render_scene(&s, &set, 0.0).unwrap();
    (0..SIZE * SIZE)
        .map(|i| r.frame.buffers.color.get(i))
        .collect()
}

/// Given TANGENTs are used instead of MikkTSpace's. The quad's uvs run
/// along +x and +y, so generated tangents are t = +x, b = +y. Given
/// t = +y with w = −1, glTF's bitangent w (n × t) = −(z × y) = +x: the
/// map's x and y swap. So the constant texel (255, 128, 255), the
/// tangent-space normal (1, 1/255, 1), bends the normal toward
/// (1/255, 1, 1) instead of (1, 1/255, 1); with w = +1 the bitangent is
/// −x, and the texel (128, 255, 255), (1/255, 1, 1) in tangent space,
/// bends it toward (−1, 1/255, 1): mirrored. Each render equals the same
/// quad with that world normal as its vertex normal and no map.
#[test]
fn given_tangents_are_used_with_their_handedness() {
    let rough = json!({"baseColorFactor": [0.9, 0.6, 0.3, 1.0],
        "metallicFactor": 0.0, "roughnessFactor": 0.5});
    let mapped = |texel: [u8; 3], tangent: Option<[f32; 4]>| {
        let mut attributes = Vec::new();
        if let Some(t) = tangent {
            attributes.push(("TANGENT", Attr::Floats(t.repeat(4), "VEC4")));
        }
        render_off_axis(&quad_doc(
            json!({"pbrMetallicRoughness": rough, "normalTexture": {"index": 0}}),
            &Quad {
                images: vec![png_uri(1, 1, &texel)],
                attributes,
                ..Default::default()
            },
        ))
    };
    let by_normal = |n: [f64; 3]| {
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        render_off_axis(&quad_doc(
            json!({"pbrMetallicRoughness": rough}),
            &Quad {
                normal: Some(n.map(|c| (c / l) as f32)),
                ..Default::default()
            },
        ))
    };
    let e = 1.0 / 255.0;
    let same = |a: &[[f32; 3]], b: &[[f32; 3]], what: &str| {
        let mut lit = 0;
        for (i, (p, q)) in a.iter().zip(b).enumerate() {
            lit += usize::from(q[0] > 0.0);
            for c in 0..3 {
                assert!(
                    (p[c] - q[c]).abs() <= 1e-3 * q[c].max(1e-3),
                    "{what}: pixel {i}: {p:?} vs vertex normal {q:?}"
                );
            }
        }
        assert!(lit > 2500, "{what}: {lit}");
    };
    let generated = mapped([255, 128, 255], None);
    same(&generated, &by_normal([1.0, e, 1.0]), "generated tangents");
    let given = mapped([255, 128, 255], Some([0.0, 1.0, 0.0, -1.0]));
    same(&given, &by_normal([e, 1.0, 1.0]), "given t = +y, w = −1");
    let mirrored = mapped([128, 255, 255], Some([0.0, 1.0, 0.0, 1.0]));
    same(
        &mirrored,
        &by_normal([-1.0, e, 1.0]),
        "given t = +y, w = +1",
    );
    // The three differ where the light is off the axis.
    let mid = 32 * SIZE + 32;
    for (a, b) in [(&generated, &given), (&given, &mirrored)] {
        assert!(
            (a[mid][0] - b[mid][0]).abs() > 0.05 * a[mid][0],
            "{:?} vs {:?}",
            a[mid],
            b[mid]
        );
    }
}

/// The error of loading `doc` as the quad of a scene.
fn load_error(doc: &str) -> String {
    let toml = "[camera]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 40.0\nnear = 0.1\nfar = 10.0\n[[mesh]]\ngltf = \"q.gltf\"\n";
    let text = doc.to_string();
    let read = move |p: &std::path::Path| -> std::io::Result<Vec<u8>> {
        if p == std::path::Path::new("q.gltf") {
            Ok(text.clone().into_bytes())
        } else {
            Err(std::io::ErrorKind::NotFound.into())
        }
    };
    specula::scene::load_scene_str(std::path::Path::new("s.toml"), toml, &read)
        .err()
        .expect("refused")
        .to_string()
}

/// A transform that is not finite (a scale beyond f32) or not of the
/// extension's form is refused naming its JSON path; float COLOR_0
/// values outside [0, 1] are clamped with a warning.
#[test]
fn bad_extension_values_are_refused_or_clamped() {
    let images = vec![png_uri(1, 1, &[128, 128, 255])];
    let q = Quad {
        images: images.clone(),
        ..Default::default()
    };
    let huge = quad_doc(rough_textured(Some(json!({"scale": [1e39, 1.0]}))), &q);
    let e = load_error(&huge);
    assert!(
        e.contains(
            "materials[0].pbrMetallicRoughness.baseColorTexture.extensions.KHR_texture_transform"
        ),
        "{e}"
    );
    let malformed = quad_doc(
        json!({"normalTexture": {"index": 0,
            "extensions": {"KHR_texture_transform": {"offset": "up"}}}}),
        &q,
    );
    let e = load_error(&malformed);
    assert!(
        e.contains("materials[0].normalTexture.extensions.KHR_texture_transform"),
        "{e}"
    );
    let bright = quad_doc(
        json!({"pbrMetallicRoughness": {}}),
        &Quad {
            attributes: vec![(
                "COLOR_0",
                Attr::Floats([1.5f32, 0.5, -0.25].repeat(4), "VEC3"),
            )],
            ..Default::default()
        },
    );
    let (px, warnings) = render(&bright);
    assert!(
        warnings.iter().any(|w| w.contains("COLOR_0 of 4 vertices")),
        "{warnings:?}"
    );
    assert!(px.iter().flatten().all(|c| c.is_finite() && *c >= 0.0));
}
