//! glTF alphaMode MASK and BLEND as they reach the pixels. Every expected
//! value comes from another render (the same scene without the surface,
//! or with an OPAQUE copy of it, or the same shape built as geometry) or
//! from the analytic projection of the cutout; none from the code under
//! test.

mod common;

use common::gltf_doc::{png_rgba_uri, Buf};
use serde_json::{json, Value};
use specula::render::RenderSettings;
use specula::scene::LoadedScene;
use specula_raster::{AlphaMode, ShadePath};

/// Pixels per side of the renders.
const SIZE: usize = 64;

/// A glTF document of one mesh: `positions` (xyz), one `normal` for all,
/// `uvs` (glTF's convention), optional COLOR_0 (RGBA floats), triangles
/// `indices`, under `material`, with an optional RGBA image (`w` × `h`
/// bytes, top row first) as texture 0 under `sampler`.
struct Mesh<'a> {
    positions: &'a [[f32; 3]],
    normal: [f32; 3],
    uvs: &'a [[f32; 2]],
    colors: Option<&'a [[f32; 4]]>,
    indices: &'a [u16],
    material: Value,
    image: Option<(u32, u32, Vec<u8>)>,
    sampler: Value,
}

impl Mesh<'_> {
    fn doc(&self) -> String {
        let mut b = Buf::default();
        let pos = b.floats(self.positions.as_flattened(), "VEC3");
        let n = self.positions.len();
        let nrm = b.floats(&self.normal.repeat(n), "VEC3");
        let uv = b.floats(self.uvs.as_flattened(), "VEC2");
        let idx = b.u16s(self.indices);
        let mut attributes = json!({"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv});
        if let Some(c) = self.colors {
            attributes["COLOR_0"] = json!(b.floats(c.as_flattened(), "VEC4"));
        }
        let (textures, images) = match &self.image {
            Some((w, h, rgba)) => (
                json!([{"source": 0, "sampler": 0}]),
                json!([{ "uri": png_rgba_uri(*w, *h, rgba) }]),
            ),
            None => (json!([]), json!([])),
        };
        b.doc(json!({
            "extensionsUsed": ["KHR_materials_unlit"],
            "meshes": [{"primitives": [{"attributes": attributes, "indices": idx, "material": 0}]}],
            "materials": [self.material],
            "textures": textures,
            "samplers": [self.sampler],
            "images": images,
            "nodes": [{"mesh": 0}],
            "scenes": [{"nodes": [0]}]
        }))
        .to_string()
    }
}

/// The corners of a 2 × 2 quad facing +z, and their glTF uvs.
const QUAD: [[f32; 3]; 4] = [
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
];
const QUAD_UV: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
const QUAD_IDX: [u16; 6] = [0, 1, 2, 0, 2, 3];

/// A quad facing +z with `material` (and the image, if any).
fn quad(
    material: Value,
    image: Option<(u32, u32, Vec<u8>)>,
    colors: Option<&[[f32; 4]]>,
) -> String {
    Mesh {
        positions: &QUAD,
        normal: [0.0, 0.0, 1.0],
        uvs: &QUAD_UV,
        colors,
        indices: &QUAD_IDX,
        material,
        image,
        sampler: json!({}),
    }
    .doc()
}

/// An unlit material of colour `rgba` and `mode`, with texture 0 as its
/// base colour texture when `textured`.
fn unlit(rgba: [f32; 4], mode: &str, cutoff: Option<f32>, textured: bool) -> Value {
    let mut pbr = json!({ "baseColorFactor": rgba });
    if textured {
        pbr["baseColorTexture"] = json!({"index": 0});
    }
    let mut m = json!({
        "pbrMetallicRoughness": pbr,
        "alphaMode": mode,
        "extensions": {"KHR_materials_unlit": {}}
    });
    if let Some(c) = cutoff {
        m["alphaCutoff"] = json!(c);
    }
    m
}

/// The opaque unlit backdrop every scene here has: a grey quad 4 units
/// behind the origin, larger than the view.
fn backdrop() -> String {
    let positions = QUAD.map(|[x, y, _]| [x * 4.0, y * 4.0, -4.0]);
    Mesh {
        positions: &positions,
        normal: [0.0, 0.0, 1.0],
        uvs: &QUAD_UV,
        colors: None,
        indices: &QUAD_IDX,
        material: unlit([0.2, 0.3, 0.4, 1.0], "OPAQUE", None, false),
        image: None,
        sampler: json!({}),
    }
    .doc()
}

/// Renders the backdrop and each of `meshes` (glTF text, translation)
/// seen head-on from z = 10 (the quad at z = 1 fills the middle ~58 of
/// 64 pixels), lit by a directional light; every pixel's linear radiance,
/// and the scene's warnings.
fn render(meshes: &[(String, [f32; 3])], extra: &str) -> (Vec<[f32; 3]>, Vec<String>) {
    let s = scene_of(meshes, extra);
    let set = RenderSettings::from_scene(&s);
    let r = specula::render::render_scene(&s, &set, 0.0).unwrap();
    (r.hdr(), s.warnings.clone())
}

/// The scene [`render`] renders.
fn scene_of(meshes: &[(String, [f32; 3])], extra: &str) -> LoadedScene {
    let mut toml = format!(
        r#"
[camera]
eye = [0.0, 0.0, 10.0]
target = [0.0, 0.0, 0.0]
fov_y = 14.0
near = 1.0
far = 100.0
[output]
width = {SIZE}
height = {SIZE}
{extra}
[[light]]
type = "directional"
direction = [0.0, 0.0, -1.0]
irradiance = [2.0, 2.0, 2.0]
[[mesh]]
gltf = "backdrop.gltf"
"#
    );
    let mut files = vec![("backdrop.gltf".to_string(), backdrop())];
    for (k, (doc, t)) in meshes.iter().enumerate() {
        let name = format!("m{k}.gltf");
        toml += &format!("[[mesh]]\ngltf = \"{name}\"\ntranslate = {t:?}\n");
        files.push((name, doc.clone()));
    }
    let files: Vec<(&str, &str)> = files
        .iter()
        .map(|(a, b)| (a.as_str(), b.as_str()))
        .collect();
    common::scene(&toml, &files)
}

/// Pixel (i, j)'s centre on the plane z = `z` (world x, y), by the
/// camera above: a pinhole at z = 10 with a vertical field of 14°.
fn on_plane(i: usize, j: usize, z: f64) -> (f64, f64) {
    let t = (7.0f64).to_radians().tan();
    let nx = (i as f64 + 0.5) / (SIZE as f64 / 2.0) - 1.0;
    let ny = 1.0 - (j as f64 + 0.5) / (SIZE as f64 / 2.0);
    let d = 10.0 - z;
    (nx * t * d, ny * t * d)
}

#[test]
fn a_mask_below_its_cutoff_vanishes_and_above_it_is_opaque() {
    let without = render(&[], "").0;
    let at = [0.0, 0.0, 1.0];
    for (alpha, cutoff) in [(0.4, None), (0.49, Some(0.5)), (0.2, Some(0.25))] {
        let m = unlit([0.9, 0.5, 0.1, alpha], "MASK", cutoff, false);
        let (px, warnings) = render(&[(quad(m, None, None), at)], "");
        assert!(
            px == without,
            "alpha {alpha} < cutoff: the quad must vanish"
        );
        assert!(
            warnings.iter().all(|w| !w.contains("alpha")),
            "{warnings:?}"
        );
    }
    for (alpha, cutoff) in [(0.5, None), (0.6, Some(0.5)), (0.3, Some(0.25))] {
        let m = unlit([0.9, 0.5, 0.1, alpha], "MASK", cutoff, false);
        let opaque = unlit([0.9, 0.5, 0.1, alpha], "OPAQUE", None, false);
        let px = render(&[(quad(m, None, None), at)], "").0;
        let expected = render(&[(quad(opaque, None, None), at)], "").0;
        assert!(
            px == expected,
            "alpha {alpha} ≥ cutoff: the quad must be opaque"
        );
        assert!(px != without);
        // A constant alpha at or above the cutoff leaves the material
        // opaque (no per-sample test); a texture's alpha keeps the mask.
        let modes = |m: Value, image| {
            let s = scene_of(&[(quad(m, image, None), at)], "");
            s.data
                .materials
                .iter()
                .map(|m| m.alpha_mode())
                .collect::<Vec<_>>()
        };
        let m = unlit([0.9, 0.5, 0.1, alpha], "MASK", cutoff, false);
        assert!(modes(m, None).iter().all(Option::is_none));
        let m = unlit([0.9, 0.5, 0.1, alpha], "MASK", cutoff, true);
        assert!(modes(m, Some(disk_image(8, 0.3)))
            .iter()
            .any(|m| matches!(m, Some(AlphaMode::Mask { .. }))));
    }
}

/// An RGBA image of `n` × `n` texels, white, whose alpha is 255 inside
/// the disk of radius `r` around uv (½, ½) and 0 outside (texel centres).
fn disk_image(n: u32, r: f64) -> (u32, u32, Vec<u8>) {
    let mut rgba = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (u, v) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
            let inside = (u - 0.5).hypot(v - 0.5) < r;
            rgba.extend_from_slice(&[255, 255, 255, if inside { 255 } else { 0 }]);
        }
    }
    (n, n, rgba)
}

#[test]
fn a_masked_texture_cuts_out_its_disk() {
    // Disk of radius 0.35 in uv = 0.7 world units on the quad at z = 1.
    let m = unlit([1.0; 4], "MASK", None, true);
    let doc = quad(m, Some(disk_image(256, 0.35)), None);
    for ssaa in [1, 3] {
        let extra = format!("ssaa = {ssaa}");
        let (px, warnings) = render(&[(doc.clone(), [0.0, 0.0, 1.0])], &extra);
        assert!(
            warnings.iter().all(|w| !w.contains("alpha")),
            "{warnings:?}"
        );
        // One pixel on the plane z = 1 is 2 · 9 tan 7° / 64 ≈ 0.035 units.
        let pixel = 2.0 * 9.0 * (7.0f64).to_radians().tan() / SIZE as f64;
        let (mut near_edge, mut wrong) = (0, 0);
        for j in 0..SIZE {
            for i in 0..SIZE {
                let (x, y) = on_plane(i, j, 1.0);
                let r = x.hypot(y);
                let white = px[j * SIZE + i][0] > 0.5;
                if (r - 0.7).abs() < pixel {
                    near_edge += 1;
                    continue;
                }
                if white != (r < 0.7) {
                    wrong += 1;
                }
            }
        }
        eprintln!("ssaa {ssaa}: {wrong} wrong pixels away from the edge, {near_edge} within 1 px");
        assert_eq!(
            wrong, 0,
            "ssaa {ssaa}: pixels off the cutout, away from its edge"
        );
        assert!(near_edge > 100, "{near_edge}");
        if ssaa > 1 {
            // Supersampled: edge pixels are partly covered.
            let partial = px.iter().filter(|p| p[0] > 0.21 && p[0] < 0.99).count();
            assert!(
                partial > 50,
                "ssaa {ssaa}: {partial} antialiased edge pixels"
            );
        }
    }
}

#[test]
fn vertex_alpha_and_texture_alpha_multiply() {
    // COLOR_0 alpha 0.7 and texel alpha 153/255 = 0.6 each pass a cutoff
    // of 0.5; their product 0.42 does not (and passes 0.4).
    let colors = [[1.0, 1.0, 1.0, 0.7]; 4];
    let image = (2, 2, [255, 255, 255, 153].repeat(4));
    let at = [0.0, 0.0, 1.0];
    let without = render(&[], "").0;
    let doc = |cutoff: f32, mode: &str| {
        let m = unlit([0.9, 0.5, 0.1, 1.0], mode, Some(cutoff), true);
        quad(m, Some(image.clone()), Some(&colors))
    };
    assert!(render(&[(doc(0.5, "MASK"), at)], "").0 == without);
    let shown = render(&[(doc(0.4, "MASK"), at)], "").0;
    assert!(shown == render(&[(doc(0.4, "OPAQUE"), at)], "").0);
    assert!(shown != without);
    // Each alone passes 0.5: without the texture, and without COLOR_0.
    let m = unlit([0.9, 0.5, 0.1, 1.0], "MASK", Some(0.5), false);
    let vertex_only = quad(m.clone(), None, Some(&colors));
    assert!(render(&[(vertex_only, at)], "").0 != without);
    let m = unlit([0.9, 0.5, 0.1, 1.0], "MASK", Some(0.5), true);
    let texture_only = quad(m, Some(image.clone()), None);
    assert!(render(&[(texture_only, at)], "").0 != without);
}

/// The radiance of `a` over `b` with alpha `alpha`, in f64.
fn over(alpha: f64, a: [f32; 3], b: [f32; 3]) -> [f64; 3] {
    std::array::from_fn(|c| alpha * a[c] as f64 + (1.0 - alpha) * b[c] as f64)
}

fn close(got: [f32; 3], want: [f64; 3]) -> bool {
    (0..3).all(|c| (got[c] as f64 - want[c]).abs() <= 1e-6 * want[c].abs().max(1.0))
}

/// A lit (metallic-roughness) material of colour `rgba` and `mode`.
fn lit(rgba: [f32; 4], mode: &str) -> Value {
    json!({
        "pbrMetallicRoughness": {"baseColorFactor": rgba, "metallicFactor": 0.0, "roughnessFactor": 0.5},
        "alphaMode": mode
    })
}

#[test]
fn a_blended_quad_is_its_opaque_render_over_the_frame() {
    let at = [0.0, 0.0, 1.0];
    let without = render(&[], "").0;
    for a in [0.3f32, 0.75] {
        let blended = render(
            &[(quad(lit([0.9, 0.5, 0.1, a], "BLEND"), None, None), at)],
            "",
        )
        .0;
        let opaque = render(
            &[(quad(lit([0.9, 0.5, 0.1, a], "OPAQUE"), None, None), at)],
            "",
        )
        .0;
        let mut covered = 0;
        for i in 0..SIZE * SIZE {
            let want = if opaque[i] == without[i] {
                without[i].map(|c| c as f64)
            } else {
                covered += 1;
                over(a as f64, opaque[i], without[i])
            };
            assert!(
                close(blended[i], want),
                "pixel {i}: {:?} vs {want:?}",
                blended[i]
            );
        }
        assert!(covered > 2500, "{covered}");
    }
}

/// Two unlit blended quads, a red one (alpha ½) behind a green one
/// (alpha 0.4), overlapping.
fn stacked() -> [(String, [f32; 3]); 2] {
    let (a1, a2) = (0.5f32, 0.4f32);
    let far = (
        quad(unlit([1.0, 0.0, 0.0, a1], "BLEND", None, false), None, None),
        [0.3, 0.0, 0.5],
    );
    let near = (
        quad(unlit([0.0, 1.0, 0.0, a2], "BLEND", None, false), None, None),
        [-0.3, 0.0, 1.5],
    );
    [far, near]
}

#[test]
fn stacked_blended_quads_composite_back_to_front_in_any_file_order() {
    let (a1, a2) = (0.5f32, 0.4f32);
    let [far, near] = stacked();
    let opaque = |m: &(String, [f32; 3])| (m.0.replace("BLEND", "OPAQUE"), m.1);
    let without = render(&[], "").0;
    let far_opaque = render(&[opaque(&far)], "").0;
    let near_opaque = render(&[opaque(&near)], "").0;
    let in_order = render(&[far.clone(), near.clone()], "").0;
    let reversed = render(&[near, far], "").0;
    assert!(in_order == reversed, "the file order must not matter");
    let mut both = 0;
    for i in 0..SIZE * SIZE {
        let mut want = without[i].map(|c| c as f64);
        if far_opaque[i] != without[i] {
            want = over(a1 as f64, far_opaque[i], want.map(|c| c as f32));
        }
        if near_opaque[i] != without[i] {
            both += (far_opaque[i] != without[i]) as usize;
            want = over(a2 as f64, near_opaque[i], want.map(|c| c as f32));
        }
        assert!(
            close(in_order[i], want),
            "pixel {i}: {:?} vs {want:?}",
            in_order[i]
        );
    }
    assert!(both > 1000, "{both}");
    // Each quad's samples are shaded once where it is in front of the
    // backdrop: the pixels its opaque twin changes.
    let changed = |img: &[[f32; 3]]| (0..SIZE * SIZE).filter(|&i| img[i] != without[i]).count();
    let s = scene_of(&stacked(), "");
    let r = specula::render::render_scene(&s, &RenderSettings::from_scene(&s), 0.0).unwrap();
    assert_eq!(
        r.stats.blended_samples as usize,
        changed(&far_opaque) + changed(&near_opaque)
    );
}

/// A horizontal mesh (normal +y) at height `h`: `xz` corners with uvs.
fn horizontal(
    xz: &[[f32; 2]],
    uvs: &[[f32; 2]],
    indices: &[u16],
    material: Value,
    image: Option<(u32, u32, Vec<u8>)>,
) -> String {
    let positions: Vec<[f32; 3]> = xz.iter().map(|[x, z]| [*x, 0.0, *z]).collect();
    Mesh {
        positions: &positions,
        normal: [0.0, 1.0, 0.0],
        uvs,
        colors: None,
        indices,
        material,
        image,
        sampler: json!({}),
    }
    .doc()
}

/// A floor lit by a shadowing directional light at 45°, seen from above,
/// with `caster` 2 units above it: the floor's pixels.
fn shadow_scene(caster: &str) -> Vec<[f32; 3]> {
    let toml = r#"
[camera]
eye = [-1.0, 12.0, 0.0]
target = [-1.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov_y = 30.0
near = 1.0
far = 100.0
[output]
width = 96
height = 96
[[mesh]]
plane = { size = [12.0, 12.0] }
material = "floor"
[materials.floor]
model = "lambert"
base_color = [0.5, 0.5, 0.5]
[[light]]
type = "directional"
direction = [-1.0, -1.0, 0.0]
irradiance = [1.0, 1.0, 1.0]
shadows = "hard"
shadow_map_size = 2048
[[mesh]]
gltf = "caster.gltf"
translate = [0.0, 2.0, 0.0]
"#;
    let s = common::scene(toml, &[("caster.gltf", caster)]);
    let set = specula::render::RenderSettings::from_scene(&s);
    specula::render::render_scene(&s, &set, 0.0).unwrap().hdr()
}

#[test]
fn a_masked_quad_casts_the_shadow_of_its_cutout() {
    let material = |mode: &str, textured: bool| {
        let mut m = lit([1.0, 1.0, 1.0, 1.0], mode);
        m["doubleSided"] = json!(true);
        if textured {
            m["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
        }
        m
    };
    // The quad spans [−1, 1]² in x, z; uv (u, v) = ((x + 1)/2, (z + 1)/2).
    let corners = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let uvs = corners.map(|[x, z]| [(x + 1.0) / 2.0, (z + 1.0) / 2.0]);
    let masked = horizontal(
        &corners,
        &uvs,
        &[0, 2, 1, 0, 3, 2],
        material("MASK", true),
        Some(disk_image(256, 0.35)),
    );
    // The same disk (radius 0.7) as a fan of 256 triangles.
    let n = 256;
    let mut xz = vec![[0.0f32, 0.0]];
    for k in 0..n {
        let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
        xz.push([(0.7 * t.cos()) as f32, (0.7 * t.sin()) as f32]);
    }
    let idx: Vec<u16> = (0..n as u16)
        .flat_map(|k| [0, 1 + (k + 1) % n as u16, 1 + k])
        .collect();
    let geometry = horizontal(
        &xz,
        &vec![[0.0; 2]; xz.len()],
        &idx,
        material("OPAQUE", false),
        None,
    );
    let a = shadow_scene(&masked);
    let b = shadow_scene(&geometry);
    let differ = a
        .iter()
        .zip(&b)
        .filter(|(p, q)| (p[0] - q[0]).abs() > 0.02)
        .count();
    // The shadow: floor pixels far darker than the lit floor's
    // 0.5/π · cos 45° ≈ 0.11 (no environment: shadowed floor is black).
    let dark = b.iter().filter(|p| p[0] < 0.05).count();
    // The disk's area over a pixel's (2 · 12 tan 15° / 96)²: ~340.
    eprintln!("{dark} shadowed floor pixels; {differ} pixels differ from the geometry's");
    assert!(dark > 250, "{dark} shadowed pixels");
    // Only along the outlines (the caster's and its shadow's: about
    // 2 · 2π · 0.7 units at ~0.07 units a pixel, ~130 pixels) may differ.
    assert!(differ <= 40, "{differ} pixels differ (of {dark} in shadow)");
}

#[test]
fn masking_and_blending_are_the_same_on_every_path_and_thread_count() {
    let [far, near] = stacked();
    let m = unlit([1.0, 1.0, 0.0, 1.0], "MASK", None, true);
    let masked = (quad(m, Some(disk_image(64, 0.3)), None), [0.0, -0.4, 2.0]);
    let s = scene_of(&[far, masked, near], "");
    let run = |f: &dyn Fn(&mut RenderSettings)| {
        let mut set = RenderSettings::from_scene(&s);
        f(&mut set);
        specula::render::render_scene(&s, &set, 0.0).unwrap().ldr
    };
    let reference = run(&|_| {});
    // Encoded in the shading pass (no colour planes kept): composited first.
    assert!(run(&|s| s.keep_hdr = false) == reference, "fused encode");
    for t in [1, 3] {
        assert!(run(&|s| s.threads = Some(t)) == reference, "{t} threads");
    }
    assert!(run(&|s| s.path = ShadePath::Scalar) == reference, "scalar");
}
