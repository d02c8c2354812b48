//! The textures of KHR_materials_specular, _clearcoat and _sheen as they
//! reach the pixels: each factor texture against the constant material
//! of factor × texel, the clearcoat normal map against an f64 oracle
//! written here from the specifications' text, and the 8-lane shading
//! against the scalar one.

mod common;

use common::gltf_doc::{png_rgba_uri, srgb_decode, Buf};
use serde_json::{json, Value};
use specula::render::{render_scene, RenderSettings};
use specula_raster::frame::ShadePath;
use std::f64::consts::PI;

/// Pixels per side of the renders.
const SIZE: usize = 64;

/// A 2 × 2 quad facing +z at z = 1 (after the scene's translate) with
/// `material`, its textures reading `images` in order through one
/// `sampler`; uvs in glTF's convention ((0, 0) at the image's top-left)
/// run along +x and −y, so the image's left half lands on the quad's
/// left half and the tangent frame is (+x, +y, +z).
fn quad_doc(material: Value, images: &[String], sampler: Value) -> String {
    quad_doc_with_normal(material, images, sampler, [0.0, 0.0, 1.0])
}

/// [`quad_doc`] with `normal` as every vertex's NORMAL.
fn quad_doc_with_normal(
    material: Value,
    images: &[String],
    sampler: Value,
    normal: [f32; 3],
) -> String {
    let mut b = Buf::default();
    let pos = b.floats(
        &[
            -1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0,
        ],
        "VEC3",
    );
    let nrm = b.floats(&normal.repeat(4), "VEC3");
    let uv = b.floats(&[0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0], "VEC2");
    let idx = b.u16s(&[0, 1, 2, 0, 2, 3]);
    let textures: Vec<Value> = (0..images.len())
        .map(|i| json!({"source": i, "sampler": 0}))
        .collect();
    let images: Vec<Value> = images.iter().map(|u| json!({ "uri": u })).collect();
    b.doc(json!({
        "extensionsUsed": ["KHR_materials_clearcoat", "KHR_materials_sheen",
            "KHR_materials_specular"],
        "meshes": [{"primitives": [{"attributes":
            {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv},
            "indices": idx, "material": 0}]}],
        "materials": [material],
        "textures": textures,
        "samplers": [sampler],
        "images": images,
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    }))
    .to_string()
}

fn nearest() -> Value {
    json!({"magFilter": 9728, "minFilter": 9728})
}

/// The camera of every render: 10 units up +z looking at the origin,
/// 14° vertical field of view; the quad fills the middle ~58 pixels.
const CAMERA: &str = r#"
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
"#;

/// Lights for the factor tests: an oblique directional light, a point
/// light and a uniform environment (the albedo path).
const LIGHTS: &str = r#"
[[light]]
type = "directional"
direction = [-0.4, -0.3, -1.0]
irradiance = [2.0, 2.0, 2.0]
[[light]]
type = "point"
position = [1.5, 0.5, 4.0]
intensity = [8.0, 8.0, 8.0]
[environment]
uniform = [0.3, 0.3, 0.3]
"#;

/// Every pixel's linear radiance of `doc` under `lights`, and the
/// scene's warnings.
fn render(doc: &str, lights: &str, path: ShadePath) -> (Vec<[f32; 3]>, Vec<String>) {
    let s = common::scene(&format!("{CAMERA}{lights}"), &[("quad.gltf", doc)]);
    let mut set = RenderSettings::from_scene(&s);
    set.path = path;
    let r = render_scene(&s, &set, 0.0).unwrap();
    let px = (0..SIZE * SIZE)
        .map(|i| r.frame.buffers.color.get(i))
        .collect();
    (px, s.warnings.clone())
}

fn px(doc: &str) -> Vec<[f32; 3]> {
    let (p, w) = render(doc, LIGHTS, ShadePath::Simd);
    assert!(w.is_empty(), "{w:?}");
    p
}

/// The base every test material starts from.
fn base() -> Value {
    json!({"pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.5, 0.4, 1.0],
        "metallicFactor": 0.0, "roughnessFactor": 0.5}})
}

/// `base()` with `ext` as its `extensions`.
fn material(ext: Value) -> Value {
    let mut m = base();
    m["extensions"] = ext;
    m
}

/// One factor texture: how the material names it, and the constant
/// material its texel's value stands for.
struct Slot {
    name: &'static str,
    /// The material with the texture (index 0) and factor `f`.
    textured: fn(f: f64) -> Value,
    /// The material with no texture and factor f × (what the texel
    /// `rgba` gives the slot).
    constant: fn(f: f64, rgba: [u8; 4]) -> Value,
}

fn lin(b: u8) -> f64 {
    b as f64 / 255.0
}

/// `f` times the sRGB-decoded RGB of `rgba`.
fn srgb3(f: f64, rgba: [u8; 4]) -> [f64; 3] {
    [0, 1, 2].map(|c| f * srgb_decode(rgba[c]))
}

/// The clearcoat and sheen layers on (for the slots that scale them),
/// with values that differ from every slot's test factor.
fn coat(extra: Value) -> Value {
    let mut c = json!({"clearcoatFactor": 0.8, "clearcoatRoughnessFactor": 0.4});
    for (k, v) in extra.as_object().unwrap() {
        c[k] = v.clone();
    }
    json!({ "KHR_materials_clearcoat": c })
}

fn sheen(extra: Value) -> Value {
    let mut c = json!({"sheenColorFactor": [0.7, 0.5, 0.9], "sheenRoughnessFactor": 0.5});
    for (k, v) in extra.as_object().unwrap() {
        c[k] = v.clone();
    }
    json!({ "KHR_materials_sheen": c })
}

fn specular(extra: Value) -> Value {
    let mut c = json!({"specularFactor": 0.9, "specularColorFactor": [1.0, 0.8, 0.6]});
    for (k, v) in extra.as_object().unwrap() {
        c[k] = v.clone();
    }
    json!({ "KHR_materials_specular": c })
}

fn slots() -> Vec<Slot> {
    vec![
        Slot {
            name: "clearcoatTexture (R)",
            textured: |f| {
                material(coat(
                    json!({"clearcoatFactor": f, "clearcoatTexture": {"index": 0}}),
                ))
            },
            constant: |f, t| material(coat(json!({"clearcoatFactor": f * lin(t[0])}))),
        },
        Slot {
            name: "clearcoatRoughnessTexture (G)",
            textured: |f| {
                material(coat(json!({"clearcoatRoughnessFactor": f,
                    "clearcoatRoughnessTexture": {"index": 0}})))
            },
            constant: |f, t| material(coat(json!({"clearcoatRoughnessFactor": f * lin(t[1])}))),
        },
        Slot {
            name: "sheenColorTexture (sRGB RGB)",
            textured: |f| {
                material(sheen(json!({"sheenColorFactor": [f, f, f],
                    "sheenColorTexture": {"index": 0}})))
            },
            constant: |f, t| material(sheen(json!({"sheenColorFactor": srgb3(f, t)}))),
        },
        Slot {
            name: "sheenRoughnessTexture (A)",
            textured: |f| {
                material(sheen(json!({"sheenRoughnessFactor": f,
                    "sheenRoughnessTexture": {"index": 0}})))
            },
            constant: |f, t| material(sheen(json!({"sheenRoughnessFactor": f * lin(t[3])}))),
        },
        Slot {
            name: "specularTexture (A)",
            textured: |f| {
                material(specular(
                    json!({"specularFactor": f, "specularTexture": {"index": 0}}),
                ))
            },
            constant: |f, t| material(specular(json!({"specularFactor": f * lin(t[3])}))),
        },
        Slot {
            name: "specularColorTexture (sRGB RGB)",
            textured: |f| {
                material(specular(json!({"specularColorFactor": [f, f, f],
                    "specularColorTexture": {"index": 0}})))
            },
            constant: |f, t| material(specular(json!({"specularColorFactor": srgb3(f, t)}))),
        },
    ]
}

/// The largest |a − b| / max(|b|, floor) over the pixels `keep` selects.
fn worst(a: &[[f32; 3]], b: &[[f32; 3]], keep: impl Fn(usize, usize) -> bool) -> f64 {
    let mut w = 0.0f64;
    for (i, (p, q)) in a.iter().zip(b).enumerate() {
        if !keep(i % SIZE, i / SIZE) {
            continue;
        }
        for c in 0..3 {
            let (x, y) = (p[c] as f64, q[c] as f64);
            w = w.max((x - y).abs() / y.abs().max(1e-3));
        }
    }
    w
}

/// Texels whose four channels differ from each other (so a slot reading
/// the wrong channel shows).
const TEXEL_A: [u8; 4] = [200, 90, 150, 60];
const TEXEL_B: [u8; 4] = [70, 230, 40, 210];

/// Each factor texture holding one value v, with factor f, renders as the
/// same quad with factor f·v and no texture; a texture whose left and
/// right halves hold two values renders each half as its constant
/// material (away from the seam). Both sides multiply f32 factors, so
/// they agree to f32 rounding (1e-6 relative).
#[test]
fn each_factor_texture_equals_its_constant_material() {
    let f = 0.9;
    let one = vec![png_rgba_uri(1, 1, &TEXEL_A)];
    let halves = vec![png_rgba_uri(2, 1, &[TEXEL_A, TEXEL_B].concat())];
    let inside = |x: usize, y: usize| (6..58).contains(&x) && (6..58).contains(&y);
    let plain = px(&quad_doc(base(), &[], nearest()));
    for slot in slots() {
        let textured = (slot.textured)(f);
        let a = px(&quad_doc((slot.constant)(f, TEXEL_A), &[], nearest()));
        let b = px(&quad_doc((slot.constant)(f, TEXEL_B), &[], nearest()));
        let single = px(&quad_doc(textured.clone(), &one, nearest()));
        let w1 = worst(&single, &a, inside);
        let split = px(&quad_doc(textured, &halves, nearest()));
        let left = worst(&split, &a, |x, y| inside(x, y) && x < 29);
        let right = worst(&split, &b, |x, y| inside(x, y) && x > 35);
        eprintln!(
            "{}: single {w1:e}, left {left:e}, right {right:e}",
            slot.name
        );
        assert!(w1 < 1e-6, "{}: single value {w1:e}", slot.name);
        assert!(
            left < 1e-6 && right < 1e-6,
            "{}: {left:e} {right:e}",
            slot.name
        );
        // The slot changes the picture: the two values render apart, and
        // the layer shows against the plain base.
        let apart = worst(&a, &b, inside);
        assert!(apart > 1e-2, "{}: values indistinct {apart:e}", slot.name);
        assert!(worst(&a, &plain, inside) > 1e-2, "{}", slot.name);
    }
}

// ---- The clearcoat normal map against an f64 oracle -------------------

type Vec3 = [f64; 3];

fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalize(a: Vec3) -> Vec3 {
    let l = dot(a, a).sqrt();
    a.map(|x| x / l)
}

/// glTF Appendix B's specular_brdf(α) about the unit normal `n`:
/// D_GGX · V_GGX (height-correlated Smith) = G D / (4 |N·L| |N·V|).
fn specular_brdf(alpha: f64, n: Vec3, l: Vec3, v: Vec3) -> f64 {
    let h = normalize([l[0] + v[0], l[1] + v[1], l[2] + v[2]]);
    let (nl, nv, nh) = (dot(n, l), dot(n, v), dot(n, h));
    let a2 = alpha * alpha;
    let d = a2 / (PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
    let vis =
        0.5 / (nl * (nv * nv * (1.0 - a2) + a2).sqrt() + nv * (nl * nl * (1.0 - a2) + a2).sqrt());
    d * vis
}

/// What the quad of [`oracle_material`] reflects toward `v` under a
/// directional light toward `l` of irradiance `e`, from the
/// specifications: the base (Appendix B, metallic 0, IOR 1.5: F_d =
/// 0.04 + 0.96 (1 − |V·H|)⁵, dielectric = (1 − F_d) c/π + F_d
/// specular_brdf(roughness²)) about its normal `n`, lit by N·L;
/// KHR_materials_clearcoat's coat over it, coated = base (1 − c F_c) +
/// c F_c specular_brdf(clearcoatRoughness²) about N_c, with
/// F_c = 0.04 + 0.96 (1 − V·N_c)⁵, its lobe lit by N_c·L (the coat's own
/// cosine, as the Khronos sample viewer shades it).
fn oracle_radiance(n: Vec3, nc: Vec3, l: Vec3, v: Vec3, e: f64) -> [f64; 3] {
    let (base, rough, c, coat_rough) = ([0.6, 0.5, 0.4], 0.6f64, 1.0, 0.3f64);
    let h = normalize([l[0] + v[0], l[1] + v[1], l[2] + v[2]]);
    let fd = 0.04 + 0.96 * (1.0 - dot(v, h).abs()).powi(5);
    let spec = specular_brdf(rough * rough, n, l, v);
    let fc = 0.04 + 0.96 * (1.0 - dot(v, nc)).powi(5);
    let coat = if dot(nc, l) > 0.0 {
        specular_brdf(coat_rough * coat_rough, nc, l, v) * dot(nc, l)
    } else {
        0.0
    };
    base.map(|b| {
        let under = (1.0 - fd) * b / PI + fd * spec;
        e * (under * (1.0 - c * fc) * dot(n, l) + c * fc * coat)
    })
}

/// The material of the oracle; `normal` and `coat_normal` are texture
/// infos of the normal maps it has.
fn oracle_material(normal: Option<Value>, coat_normal: Option<Value>) -> Value {
    let mut cc = json!({"clearcoatFactor": 1.0, "clearcoatRoughnessFactor": 0.3});
    if let Some(t) = coat_normal {
        cc["clearcoatNormalTexture"] = t;
    }
    let mut m = json!({"pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.5, 0.4, 1.0],
        "metallicFactor": 0.0, "roughnessFactor": 0.6},
        "extensions": {"KHR_materials_clearcoat": cc}});
    if let Some(t) = normal {
        m["normalTexture"] = t;
    }
    m
}

/// The tilt every normal-map test uses: texel (200, 100, 230) at scale
/// 0.8, n = normalize((2t − 1)·(s, s, 1)) in the tangent frame (+x, +y,
/// +z) of the quad (glTF's normalTextureInfo), about 30° off +z.
const TILT_TEXEL: [u8; 4] = [200, 100, 230, 255];
const TILT_SCALE: f64 = 0.8;

fn tilt() -> Vec3 {
    let m = |b: u8| 2.0 * lin(b) - 1.0;
    normalize([
        m(TILT_TEXEL[0]) * TILT_SCALE,
        m(TILT_TEXEL[1]) * TILT_SCALE,
        m(TILT_TEXEL[2]),
    ])
}

const DIRECTIONAL: &str = r#"
[[light]]
type = "directional"
direction = [-0.4, -0.3, -1.0]
irradiance = [2.0, 2.0, 2.0]
"#;

/// The oracle at every pixel of the middle 48 × 48 of a render, for
/// base normal `n` and coat normal `nc`: the ray through the pixel's
/// centre from the eye met with the plane z = 1 gives the point and the
/// view. Returns the worst relative error of `got`.
fn against_oracle(got: &[[f32; 3]], n: Vec3, nc: Vec3) -> f64 {
    let l = normalize([0.4, 0.3, 1.0]);
    let eye = [0.0, 0.0, 10.0];
    let tan = (7.0f64).to_radians().tan();
    let mut worst = 0.0f64;
    for y in 8..56 {
        for x in 8..56 {
            let ndc = [
                2.0 * (x as f64 + 0.5) / SIZE as f64 - 1.0,
                1.0 - 2.0 * (y as f64 + 0.5) / SIZE as f64,
            ];
            let d = [ndc[0] * tan, ndc[1] * tan, -1.0];
            let t = (1.0 - eye[2]) / d[2];
            let p = [eye[0] + t * d[0], eye[1] + t * d[1], 1.0];
            let v = normalize([eye[0] - p[0], eye[1] - p[1], eye[2] - p[2]]);
            let want = oracle_radiance(n, nc, l, v, 2.0);
            let g = got[y * SIZE + x];
            for c in 0..3 {
                worst = worst.max((g[c] as f64 - want[c]).abs() / want[c]);
            }
        }
    }
    worst
}

const Z: Vec3 = [0.0, 0.0, 1.0];

/// A plane whose clearcoatNormalTexture holds a constant tilt (and no
/// base normal map) against the oracle: the coat's lobe about the tilt,
/// the base about the geometric normal. Within 2e-6 relative (f32
/// shading; the worst is printed), where the untilted coat is 5 % off.
#[test]
fn a_clearcoat_normal_map_tilts_the_coat_alone() {
    let images = vec![png_rgba_uri(1, 1, &TILT_TEXEL)];
    let info = json!({"index": 0, "scale": TILT_SCALE});
    let doc = quad_doc(oracle_material(None, Some(info)), &images, nearest());
    let (got, warnings) = render(&doc, DIRECTIONAL, ShadePath::Simd);
    assert!(warnings.is_empty(), "{warnings:?}");
    let nc = tilt();
    assert!(nc[2] < 0.9, "a real tilt: {nc:?}");
    let worst = against_oracle(&got, Z, nc);
    let untilted = against_oracle(&got, Z, Z);
    eprintln!("coat normal map vs oracle: worst relative {worst:e} (untilted coat: {untilted:e})");
    assert!(untilted > 0.05, "the tilt must show: {untilted}");
    assert!(worst < 2e-6, "{worst:e}");
}

/// The base's normalTexture alone tilts the base and not the coat
/// (KHR_materials_clearcoat: "If clearcoatNormalTexture is not given, no
/// normal mapping is applied to the clear coat layer, even if normal
/// mapping is applied to the base material"); the same tilt in both maps
/// tilts both. Each against the oracle (2e-6 relative), and both maps
/// against the same quad with the tilt as its vertex normals and no map
/// (the constant path: 2e-6 relative, the f32 normal's rounding).
#[test]
fn the_base_normal_map_leaves_the_coat_unmapped() {
    let images = vec![png_rgba_uri(1, 1, &TILT_TEXEL)];
    let info = json!({"index": 0, "scale": TILT_SCALE});
    let n = tilt();
    let base_only = quad_doc(
        oracle_material(Some(info.clone()), None),
        &images,
        nearest(),
    );
    let (a, w) = render(&base_only, DIRECTIONAL, ShadePath::Simd);
    assert!(w.is_empty(), "{w:?}");
    let worst_base = against_oracle(&a, n, Z);
    let both = quad_doc(
        oracle_material(Some(info.clone()), Some(info)),
        &images,
        nearest(),
    );
    let (b, _) = render(&both, DIRECTIONAL, ShadePath::Simd);
    let worst_both = against_oracle(&b, n, n);
    let tilted = quad_doc_with_normal(
        oracle_material(None, None),
        &[],
        nearest(),
        n.map(|x| x as f32),
    );
    let (c, _) = render(&tilted, DIRECTIONAL, ShadePath::Simd);
    let vertex = worst(&b, &c, |_, _| true);
    let coat_follows = against_oracle(&a, n, n);
    eprintln!(
        "base map alone vs oracle {worst_base:e} (coat tilted too: {coat_follows:e}); \
         both maps vs oracle {worst_both:e}, vs vertex normals {vertex:e}"
    );
    assert!(
        coat_follows > 0.05,
        "the coat's normal must show: {coat_follows}"
    );
    assert!(worst_base < 2e-6, "{worst_base:e}");
    assert!(worst_both < 2e-6, "{worst_both:e}");
    assert!(vertex < 2e-6, "{vertex:e}");
}

/// Every layer texture at once, varying over the quad (a 4 × 4 RGBA
/// image, trilinear), with both normal maps: the 8-lane shading equals
/// the scalar path's (the same kernels one lane at a time) to f32
/// rounding, as tests/texture_maps.rs checks the base maps.
#[test]
fn layer_textures_agree_between_simd_and_scalar_paths() {
    let texels: Vec<u8> = (0..16u32)
        .flat_map(|i| {
            let (x, y) = (i % 4, i / 4);
            [
                (40 + 60 * x) as u8,
                (30 + 70 * y) as u8,
                (200 - 20 * (x + y)) as u8,
                (60 + 45 * ((x + 2 * y) % 4)) as u8,
            ]
        })
        .collect();
    let images = vec![png_rgba_uri(4, 4, &texels)];
    let t = json!({"index": 0});
    let m = json!({"pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.5, 0.4, 1.0],
        "metallicFactor": 0.2, "roughnessFactor": 0.6},
        "normalTexture": {"index": 0, "scale": 0.5},
        "extensions": {
            "KHR_materials_clearcoat": {"clearcoatFactor": 1.0, "clearcoatTexture": t,
                "clearcoatRoughnessFactor": 0.6, "clearcoatRoughnessTexture": t,
                "clearcoatNormalTexture": {"index": 0, "scale": 0.7}},
            "KHR_materials_sheen": {"sheenColorFactor": [1.0, 1.0, 1.0],
                "sheenColorTexture": t, "sheenRoughnessFactor": 1.0,
                "sheenRoughnessTexture": t},
            "KHR_materials_specular": {"specularFactor": 1.0, "specularTexture": t,
                "specularColorFactor": [1.0, 1.0, 1.0], "specularColorTexture": t}}});
    let sampler = json!({"magFilter": 9729, "minFilter": 9987});
    let doc = quad_doc(m, &images, sampler);
    let (a, w) = render(&doc, LIGHTS, ShadePath::Simd);
    assert!(w.is_empty(), "{w:?}");
    let (b, _) = render(&doc, LIGHTS, ShadePath::Scalar);
    assert!(a.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
    let off = a
        .iter()
        .zip(&b)
        .filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > 1e-3 * q[c].abs().max(0.05)))
        .count();
    assert!(off * 1000 < a.len(), "{off} pixels differ");
}

/// The error of loading `doc` as the scene's quad.
fn load_error(doc: &str) -> String {
    let text = doc.to_string();
    let read = move |p: &std::path::Path| -> std::io::Result<Vec<u8>> {
        if p == std::path::Path::new("quad.gltf") {
            Ok(text.clone().into_bytes())
        } else {
            Err(std::io::ErrorKind::NotFound.into())
        }
    };
    specula::scene::load_scene_str(std::path::Path::new("s.toml"), CAMERA, &read)
        .err()
        .expect("refused")
        .to_string()
}

/// A bad texture reference inside an extension is refused naming its
/// JSON path.
#[test]
fn bad_layer_textures_are_named() {
    let images = vec![png_rgba_uri(1, 1, &TILT_TEXEL)];
    for (ext, key, value, path) in [
        (
            "KHR_materials_clearcoat",
            "clearcoatTexture",
            json!({"index": 3}),
            "materials[0].extensions.KHR_materials_clearcoat.clearcoatTexture.index",
        ),
        (
            "KHR_materials_clearcoat",
            "clearcoatNormalTexture",
            json!({"scale": 1.0}),
            "materials[0].extensions.KHR_materials_clearcoat.clearcoatNormalTexture",
        ),
        (
            "KHR_materials_sheen",
            "sheenRoughnessTexture",
            json!({"index": 0, "extensions": {"KHR_texture_transform": {"offset": "up"}}}),
            "materials[0].extensions.KHR_materials_sheen.sheenRoughnessTexture",
        ),
        (
            "KHR_materials_specular",
            "specularColorTexture",
            json!({"index": -1}),
            "materials[0].extensions.KHR_materials_specular",
        ),
    ] {
        let mut e = json!({});
        e[ext] = json!({ key: value });
        let doc = quad_doc(material(e), &images, nearest());
        let err = load_error(&doc);
        assert!(err.contains(path), "{key}: {err}");
    }
}
