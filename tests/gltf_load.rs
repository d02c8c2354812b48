//! glTF input: small files written here (JSON with base64 data URIs, and
//! GLB containers) loaded through `specula::gltf` and scenes, their
//! geometry checked against hand-computed expectations (matrices written
//! out by hand, the spec's strip and fan orders); bad files refused with
//! the JSON path; lights and cameras placed by their nodes.

mod common;

use base64::Engine;
use serde_json::{json, Value};
use specula::core::light::Light;
use specula::gltf::{load, GltfError, GltfScene};
use std::path::Path;

use common::gltf_doc::Buf;

fn no_files(_: &Path) -> std::io::Result<Vec<u8>> {
    Err(std::io::ErrorKind::NotFound.into())
}

fn load_json(doc: &Value) -> Result<GltfScene, String> {
    load(Path::new("t.gltf"), doc.to_string().as_bytes(), &no_files).map_err(|e| e.to_string())
}

fn loaded(doc: &Value) -> GltfScene {
    load_json(doc).unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: [f32; 3], b: [f64; 3], tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| (*x as f64 - y).abs() <= tol)
}

/// The unit square in z = 0 as two triangles, with normals +z.
fn square(b: &mut Buf) -> (usize, usize) {
    let pos = b.floats(
        &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0],
        "VEC3",
    );
    let nrm = b.floats(&[0.0, 0.0, 1.0].repeat(4), "VEC3");
    (pos, nrm)
}

#[test]
fn node_hierarchy_transforms_match_hand_written_matrices() {
    let mut b = Buf::default();
    let (pos, nrm) = square(&mut b);
    let idx = b.u16s(&[0, 1, 2, 0, 2, 3]);
    // Parent: translate (1, 2, 3), rotate 90° about +z, scale 2.
    // Child: a column-major matrix translating by (0, 0, 5) and scaling y by 3.
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let doc = b.doc(json!({
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx}]}],
        "nodes": [
            {"translation": [1.0, 2.0, 3.0], "rotation": [0.0, 0.0, s, s], "scale": [2.0, 2.0, 2.0], "children": [1]},
            {"matrix": [1,0,0,0, 0,3,0,0, 0,0,1,0, 0,0,5,1], "mesh": 0}
        ],
        "scenes": [{"nodes": [0]}],
        "scene": 0
    }));
    let g = loaded(&doc);
    assert_eq!(g.primitives.len(), 1);
    let p = &g.primitives[0];
    // By hand: child (x, y, z) → (x, 3y, z + 5); parent scale 2 →
    // (2x, 6y, 2z + 10); rotation 90° about z: (x, y) → (−y, x) →
    // (−6y, 2x, 2z + 10); translation → (1 − 6y, 2 + 2x, 2z + 13).
    let corners = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    for (k, [x, y]) in corners.iter().enumerate() {
        let want = [1.0 - 6.0 * y, 2.0 + 2.0 * x, 13.0];
        assert!(
            close(p.positions[k].to_array(), want, 1e-5),
            "vertex {k}: {} vs {want:?}",
            p.positions[k]
        );
        // Normals: +z stays +z (rotation about z, positive scales).
        assert!(close(p.normals[k].to_array(), [0.0, 0.0, 1.0], 1e-6));
    }
    assert_eq!(p.triangles, vec![[0, 1, 2], [0, 2, 3]]);
}

#[test]
fn a_mirroring_node_flips_the_winding_and_keeps_normals_outward() {
    let mut b = Buf::default();
    let (pos, nrm) = square(&mut b);
    let idx = b.u8s(&[0, 1, 2, 0, 2, 3]);
    let doc = b.doc(json!({
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx}]}],
        "nodes": [{"scale": [1.0, 1.0, -1.0], "mesh": 0}],
        "scenes": [{"nodes": [0]}]
    }));
    let g = loaded(&doc);
    let p = &g.primitives[0];
    // Mirrored in z: the surface's normal becomes −z, and each triangle,
    // seen from −z, must still run counter-clockwise: its geometric
    // normal (b − a) × (c − a) along the vertex normals.
    for t in &p.triangles {
        let [a, b2, c] = t.map(|i| p.positions[i as usize]);
        let n = (b2 - a).cross(c - a);
        for &i in t {
            assert!(close(
                p.normals[i as usize].to_array(),
                [0.0, 0.0, -1.0],
                1e-6
            ));
            assert!(
                n.dot(p.normals[i as usize]) > 0.0,
                "triangle {t:?} faces away"
            );
        }
    }
    // u8 indices read as the same two triangles, reversed.
    assert_eq!(p.triangles, vec![[0, 2, 1], [0, 3, 2]]);
}

#[test]
fn strips_and_fans_follow_the_spec_order_and_missing_normals_are_flat() {
    let mut b = Buf::default();
    // Five points on a zig-zag in z = 0.
    let pos = b.floats(
        &[
            0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 2.0, 0.0, 0.0,
        ],
        "VEC3",
    );
    let strip_idx = b.u16s(&[0, 2, 1, 3, 4]);
    let doc = b.doc(json!({
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": pos}, "mode": 5},
            {"attributes": {"POSITION": pos}, "mode": 6},
            {"attributes": {"POSITION": pos}, "indices": strip_idx, "mode": 5},
            {"attributes": {"POSITION": pos}, "mode": 0},
            {"attributes": {"POSITION": pos}, "mode": 1}
        ]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    }));
    let g = loaded(&doc);
    assert_eq!(g.primitives.len(), 3, "points and lines are skipped");
    for m in ["mode Points", "mode Lines"] {
        assert!(
            g.warnings
                .iter()
                .any(|w| w.contains(m) && w.contains("meshes[0].primitives[")),
            "{m}: {:?}",
            g.warnings
        );
    }
    // Without NORMAL, every triangle has its own three vertices (flat
    // normals), so a triangle is read back as its three positions.
    let tris = |p: &specula::gltf::GltfPrimitive| -> Vec<[[f32; 3]; 3]> {
        p.triangles
            .iter()
            .map(|t| t.map(|i| p.positions[i as usize].to_array()))
            .collect()
    };
    let v = |i: usize| -> [f32; 3] {
        [
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [2.0, 0.0, 0.0],
        ][i]
    };
    // Strip: pᵢ = {vᵢ, vᵢ₊₁₊ᵢ﹪₂, vᵢ₊₂₋ᵢ﹪₂}.
    assert_eq!(
        tris(&g.primitives[0]),
        vec![[v(0), v(1), v(2)], [v(1), v(3), v(2)], [v(2), v(3), v(4)]]
    );
    // Fan: pᵢ = {vᵢ₊₁, vᵢ₊₂, v₀}.
    assert_eq!(
        tris(&g.primitives[1]),
        vec![[v(1), v(2), v(0)], [v(2), v(3), v(0)], [v(3), v(4), v(0)]]
    );
    // Indexed strip over 0, 2, 1, 3, 4.
    let w = [0, 2, 1, 3, 4].map(v);
    assert_eq!(
        tris(&g.primitives[2]),
        vec![[w[0], w[1], w[2]], [w[1], w[3], w[2]], [w[2], w[3], w[4]]]
    );
    for p in &g.primitives {
        for (k, t) in p.triangles.iter().enumerate() {
            let [a, b2, c] = t.map(|i| p.positions[i as usize]);
            let n = (b2 - a).cross(c - a).normalize();
            for &i in t {
                assert!(
                    (p.normals[i as usize] - n).length() < 1e-6,
                    "{} triangle {k}",
                    p.at
                );
            }
        }
    }
}

#[test]
fn sparse_and_interleaved_accessors_are_read() {
    let mut b = Buf::default();
    // Interleaved position + uv, stride 20.
    let mut inter = Vec::new();
    let verts = [
        ([0.0f32, 0.0, 0.0], [0.0f32, 1.0]),
        ([1.0, 0.0, 0.0], [1.0, 1.0]),
        ([1.0, 1.0, 0.0], [1.0, 0.0]),
        ([0.0, 1.0, 0.0], [0.0, 0.0]),
    ];
    for (p, t) in verts {
        for x in p.iter().chain(&t) {
            inter.extend_from_slice(&x.to_le_bytes());
        }
    }
    let view = b.view(&inter, Some(20));
    let pos =
        b.accessor(json!({"bufferView": view, "componentType": 5126, "count": 4, "type": "VEC3"}));
    let uv = b.accessor(json!({"bufferView": view, "byteOffset": 12, "componentType": 5126, "count": 4, "type": "VEC2"}));
    // Sparse: vertices 1 and 3 of the positions moved up in z.
    let si: Vec<u8> = [1u16, 3].iter().flat_map(|x| x.to_le_bytes()).collect();
    let sv: Vec<u8> = [1.0f32, 0.0, 7.0, 0.0, 1.0, 9.0]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let iv = b.view(&si, None);
    let vv = b.view(&sv, None);
    let sparse_pos = b.accessor(json!({
        "bufferView": view, "componentType": 5126, "count": 4, "type": "VEC3",
        "sparse": {"count": 2, "indices": {"bufferView": iv, "componentType": 5123}, "values": {"bufferView": vv}}
    }));
    // Sparse without a buffer view: zeros, then the substitutions.
    let zero_pos = b.accessor(json!({
        "componentType": 5126, "count": 4, "type": "VEC3",
        "sparse": {"count": 2, "indices": {"bufferView": iv, "componentType": 5123}, "values": {"bufferView": vv}}
    }));
    let idx = b.u16s(&[0, 1, 2, 0, 2, 3]);
    let doc = b.doc(json!({
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": pos, "TEXCOORD_0": uv}, "indices": idx},
            {"attributes": {"POSITION": sparse_pos}, "indices": idx},
            {"attributes": {"POSITION": zero_pos}, "indices": idx}
        ]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    }));
    let g = loaded(&doc);
    // Without normals every triangle has its own vertices (flat normals):
    // read the vertices back through the triangles.
    let p0 = &g.primitives[0];
    let corners: Vec<usize> = p0.triangles.iter().flatten().map(|&i| i as usize).collect();
    for (c, k) in [0, 1, 2, 0, 2, 3].iter().enumerate() {
        assert_eq!(p0.positions[corners[c]].to_array(), verts[*k].0);
        assert_eq!(p0.uv0.as_ref().unwrap()[corners[c]].to_array(), verts[*k].1);
    }
    let by_tri = |p: &specula::gltf::GltfPrimitive| -> Vec<[f32; 3]> {
        p.triangles
            .iter()
            .flat_map(|t| t.map(|i| p.positions[i as usize].to_array()))
            .collect()
    };
    let expect = |base: [[f32; 3]; 4]| -> Vec<[f32; 3]> {
        [0, 1, 2, 0, 2, 3].iter().map(|&i| base[i]).collect()
    };
    assert_eq!(
        by_tri(&g.primitives[1]),
        expect([
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 7.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 9.0]
        ])
    );
    assert_eq!(
        by_tri(&g.primitives[2]),
        expect([[0.0; 3], [1.0, 0.0, 7.0], [0.0; 3], [0.0, 1.0, 9.0]])
    );
}

/// A one-triangle document, with `edit` applied to it, must be refused
/// with a message containing `needle`.
fn refused(edit: impl Fn(&mut Value), needle: &str) {
    let mut b = Buf::default();
    let pos = b.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], "VEC3");
    let idx = b.u16s(&[0, 1, 2]);
    let mut doc = b.doc(json!({
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    }));
    edit(&mut doc);
    match load_json(&doc) {
        Ok(_) => panic!("accepted; expected an error with {needle:?}"),
        Err(e) => assert!(e.contains(needle), "{e:?} lacks {needle:?}"),
    }
}

#[test]
fn bad_files_are_refused_naming_the_json_path() {
    // An accessor index out of range.
    refused(
        |d| d["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(9),
        "meshes[0].primitives[0].attributes.POSITION",
    );
    // An index past the vertices.
    refused(
        |d| {
            let mut b = Buf::default();
            let pos = b.floats(&[0.0; 9], "VEC3");
            let idx = b.u16s(&[0, 1, 5]);
            *d = b.doc(json!({
                "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}],
                "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}]
            }));
        },
        "meshes[0].primitives[0].indices: index 5",
    );
    // NaN positions.
    refused(
        |d| {
            let mut b = Buf::default();
            let pos = b.floats(&[0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, 0.0, 1.0, 0.0], "VEC3");
            *d = b.doc(json!({
                "meshes": [{"primitives": [{"attributes": {"POSITION": pos}}]}],
                "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}]
            }));
        },
        "meshes[0].primitives[0].attributes.POSITION: element 1 is not finite",
    );
    // An accessor running past its buffer view.
    refused(|d| d["accessors"][0]["count"] = json!(1000), "accessors[0]");
    refused(
        |d| d["accessors"][0]["count"] = json!(4_000_000_000u64),
        "accessors[0]",
    );
    refused(
        |d| d["bufferViews"][0]["byteLength"] = json!(1 << 20),
        "bufferViews[0]",
    );
    // A node cycle, and a node with two parents.
    refused(
        |d| {
            d["nodes"] = json!([{"mesh": 0}, {"children": [2]}, {"children": [1]}]);
        },
        "cycle",
    );
    refused(
        |d| d["nodes"] = json!([{"mesh": 0, "children": [1]}, {}, {"children": [1]}]),
        "nodes[2].children[0]: node 1 is already a child of nodes[0]",
    );
    // Buffers: not base64, missing file, too short.
    refused(
        |d| d["buffers"][0]["uri"] = json!("data:application/octet-stream,AAAA"),
        "buffers[0].uri: data URI",
    );
    refused(
        |d| d["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,@@@"),
        "buffers[0].uri: data URI: invalid base64",
    );
    refused(
        |d| d["buffers"][0]["uri"] = json!("missing.bin"),
        "buffers[0].uri: cannot read missing.bin",
    );
    // Extensions: required and unknown is an error.
    refused(
        |d| {
            d["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
            d["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
        },
        "extensionsRequired[0]: \"KHR_draco_mesh_compression\"",
    );
    // Wrong JSON types name their path.
    refused(
        |d| d["nodes"][0]["translation"] = json!("up"),
        "nodes[0].translation",
    );
    refused(
        |d| d["nodes"][0]["translation"] = json!([1.0, 2.0]),
        "nodes[0].translation",
    );
}

#[test]
fn unknown_used_extensions_are_warnings() {
    let mut b = Buf::default();
    let pos = b.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], "VEC3");
    let doc = b.doc(json!({
        "extensionsUsed": ["EXT_fancy_thing", "KHR_lights_punctual"],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    }));
    let g = loaded(&doc);
    assert_eq!(
        g.warnings
            .iter()
            .filter(|w| w.contains("extensionsUsed"))
            .collect::<Vec<_>>(),
        vec!["extensionsUsed: \"EXT_fancy_thing\" is not supported and is ignored"]
    );
}

/// A GLB container of `json` and `bin`.
fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |v: &[u8], fill: u8| {
        let mut v = v.to_vec();
        while !v.len().is_multiple_of(4) {
            v.push(fill);
        }
        v
    };
    let (j, b) = (pad(json, b' '), pad(bin, 0));
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((12 + 8 + j.len() + 8 + b.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&b);
    out
}

#[test]
fn glb_files_load_and_broken_ones_are_refused() {
    let mut b = Buf::default();
    let pos = b.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], "VEC3");
    let mut doc = b.doc(json!({
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    }));
    doc["buffers"][0] = json!({"byteLength": b.bytes.len()});
    let file = glb(doc.to_string().as_bytes(), &b.bytes);
    let g = load(Path::new("t.glb"), &file, &no_files).unwrap();
    assert_eq!(g.primitives[0].positions[1].to_array(), [1.0, 0.0, 0.0]);
    for cut in [3, 12, 30, file.len() - 5] {
        let e = load(Path::new("t.glb"), &file[..cut], &no_files)
            .err()
            .unwrap();
        assert!(matches!(e, GltfError::Glb(_)), "{cut}: {e}");
        assert!(e.to_string().starts_with("GLB: truncated"), "{cut}: {e}");
    }
    let mut bad = file.clone();
    bad[..4].copy_from_slice(b"gLTF");
    let e = load(Path::new("t.glb"), &bad, &no_files).err().unwrap();
    assert_eq!(
        e.to_string(),
        "GLB: wrong magic \"gLTF\" (expected \"glTF\")"
    );
}

#[test]
fn punctual_lights_and_cameras_are_placed_by_their_nodes() {
    let mut b = Buf::default();
    let pos = b.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], "VEC3");
    // Rotation of 90° about +x: local −z (the light's axis) → +y… written
    // as (x, y, z) → (x, −z, y); local −z = (0, 0, −1) → (0, 1, 0).
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let doc = b.doc(json!({
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "spot", "color": [1.0, 0.5, 0.25], "intensity": 8.0, "range": 20.0,
             "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}},
            {"type": "directional", "intensity": 2.0},
            {"type": "point", "intensity": 3.0}
        ]}},
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}}]}],
        "cameras": [
            {"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}},
            {"type": "orthographic", "orthographic": {"xmag": 2.0, "ymag": 1.5, "znear": 0.1, "zfar": 50.0}}
        ],
        "nodes": [
            {"mesh": 0, "children": [1, 2, 3, 4]},
            {"translation": [1.0, 2.0, 3.0], "rotation": [s, 0.0, 0.0, s],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"rotation": [s, 0.0, 0.0, s], "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"translation": [0.0, 0.0, 4.0], "camera": 0, "extensions": {"KHR_lights_punctual": {"light": 2}}},
            {"translation": [0.0, 5.0, 0.0], "rotation": [-s, 0.0, 0.0, s], "camera": 1}
        ],
        "scenes": [{"nodes": [0]}]
    }));
    let g = loaded(&doc);
    assert_eq!(g.lights.len(), 3);
    let Light::Spot {
        position,
        direction,
        intensity,
        cos_inner,
        cos_outer,
        range,
    } = &g.lights[0]
    else {
        panic!("{:?}", g.lights[0])
    };
    assert!(close(*position, [1.0, 2.0, 3.0], 1e-6));
    assert!(close(*direction, [0.0, 1.0, 0.0], 1e-6), "{direction:?}");
    assert_eq!(*intensity, [8.0, 4.0, 2.0]);
    assert!((*cos_inner as f64 - 0.2f64.cos()).abs() < 1e-6);
    assert!((*cos_outer as f64 - 0.6f64.cos()).abs() < 1e-6);
    assert_eq!(*range, 20.0);
    // Directional: travels along +y, so toward the light is −y.
    let Light::Directional {
        to_light,
        irradiance,
    } = &g.lights[1]
    else {
        panic!()
    };
    assert!(close(*to_light, [0.0, -1.0, 0.0], 1e-6), "{to_light:?}");
    assert_eq!(*irradiance, [2.0; 3]);
    assert_eq!(
        g.lights[2],
        Light::Point {
            position: [0.0, 0.0, 4.0],
            intensity: [3.0; 3],
            range: f32::INFINITY
        }
    );
    // Cameras, in node order: the first at (0, 0, 4) looking down −z.
    assert_eq!(g.cameras.len(), 2);
    assert!(close(g.cameras[0].eye.to_array(), [0.0, 0.0, 4.0], 1e-6));
    assert!(close(
        g.cameras[0].forward.to_array(),
        [0.0, 0.0, -1.0],
        1e-6
    ));
    // The second: rotated −90° about x, so it looks down −y from y = 5
    // ((x, y, z) → (x, z, −y): −z → −y, and +y → +z).
    assert!(close(
        g.cameras[1].forward.to_array(),
        [0.0, -1.0, 0.0],
        1e-6
    ));
    assert!(close(g.cameras[1].up.to_array(), [0.0, 0.0, -1.0], 1e-6));

    // Rendered on its own: camera 0 is the default, --camera 1 the other.
    let text = doc.to_string();
    let read = |p: &Path| -> std::io::Result<Vec<u8>> {
        if p == Path::new("t.gltf") {
            Ok(text.clone().into_bytes())
        } else {
            Err(std::io::ErrorKind::NotFound.into())
        }
    };
    use specula::scene::{load_gltf_str, GltfOptions};
    let s = load_gltf_str(Path::new("t.gltf"), &read, &GltfOptions::default()).unwrap();
    assert_eq!(s.data.camera.eye.to_array(), [0.0, 0.0, 4.0]);
    assert!((s.data.camera.fov_y_deg as f64 - 0.5f64.to_degrees()).abs() < 1e-4);
    assert_eq!(s.data.camera.far, f32::INFINITY);
    assert_eq!(s.data.lights, g.lights);
    let s1 = load_gltf_str(
        Path::new("t.gltf"),
        &read,
        &GltfOptions {
            camera: Some(1),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(s1.warnings.iter().any(|w| w.contains("orthographic")));
    let e = load_gltf_str(
        Path::new("t.gltf"),
        &read,
        &GltfOptions {
            camera: Some(2),
            ..Default::default()
        },
    )
    .err()
    .unwrap();
    assert!(
        matches!(
            e,
            specula::scene::GltfSceneError::NoSuchCamera { index: 2, count: 2 }
        ),
        "{e}"
    );
    assert_eq!(e.to_string(), "--camera 2: the file has 2 cameras (0 to 1)");
    // Bad light fields name their path.
    for (edit, needle) in [
        (
            json!({"type": "spot", "spot": {"innerConeAngle": 0.7, "outerConeAngle": 0.6}}),
            "lights[0].spot.outerConeAngle",
        ),
        (json!({"type": "point", "range": 0.0}), "lights[0].range"),
        (
            json!({"type": "point", "intensity": -1.0}),
            "lights[0].color × intensity",
        ),
    ] {
        let mut d = doc.clone();
        d["extensions"]["KHR_lights_punctual"]["lights"][0] = edit;
        let e = load_json(&d)
            .err()
            .unwrap_or_else(|| panic!("{needle}: accepted"));
        assert!(e.contains(needle), "{e}");
    }
}

/// A 2×2 RGB PNG: top row red, green; bottom row blue, white.
fn png_2x2() -> Vec<u8> {
    let img = image::RgbImage::from_raw(2, 2, vec![255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255])
        .unwrap();
    let mut out = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

/// A unit quad facing +z with uvs spanning the image (glTF: v = 0 at the
/// top), its base colour texture the 2×2 PNG, sampled nearest.
fn textured_quad_doc() -> Value {
    let mut b = Buf::default();
    let pos = b.floats(
        &[
            -1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0,
        ],
        "VEC3",
    );
    let nrm = b.floats(&[0.0, 0.0, 1.0].repeat(4), "VEC3");
    // Bottom-left of the quad shows the bottom-left of the image: v = 1.
    let uv = b.floats(&[0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0], "VEC2");
    let idx = b.u16s(&[0, 1, 2, 0, 2, 3]);
    let png = base64::engine::general_purpose::STANDARD.encode(png_2x2());
    b.doc(json!({
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv}, "indices": idx, "material": 0}]}],
        "materials": [{"name": "tex", "pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0}, "metallicFactor": 0.0, "roughnessFactor": 1.0},
            "occlusionTexture": {"index": 0}}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9728, "minFilter": 9728, "wrapS": 33071, "wrapT": 33071}],
        "images": [{"uri": format!("data:image/png;base64,{png}")}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    }))
}

#[test]
fn a_textured_quad_in_a_toml_scene_shows_its_texels_the_right_way_up() {
    let doc = textured_quad_doc().to_string();
    // Lit head-on by a directional light along the view, no environment:
    // a Lambertian-plus-GGX surface at wi = wo = n with roughness 1 (α = 1)
    // reflects f = (1 − F0) c/π + D V F0 = (0.96 c + 0.01)/π, F0 = 0.04,
    // D(n) = 1/π, V = 1/4 (G2 = 1 at normal incidence).
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
    // The occlusion map is rendered (no warning names it) and, with no
    // environment, leaves the lit pixels as they are.
    let s = common::scene(toml, &[("quad.gltf", &doc)]);
    assert!(
        !s.warnings.iter().any(|w| w.contains("occlusionTexture")),
        "{:?}",
        s.warnings
    );
    let set = specula::render::RenderSettings::from_scene(&s);
    let r = specula::render::render_scene(&s, &set, 0.0).unwrap();
    let px = |x: usize, y: usize| r.frame.buffers.color.get(y * 64 + x);
    let want = |c: [f64; 3]| c.map(|c| 2.0 * (0.96 * c + 0.01) / std::f64::consts::PI);
    // Image quadrants (the quad fills the middle of the view): top-left
    // red, top-right green, bottom-left blue, bottom-right white.
    let q = 16;
    let mid = 32;
    for ((x, y), c) in [
        ((mid - q / 2, mid - q / 2), [1.0, 0.0, 0.0]),
        ((mid + q / 2, mid - q / 2), [0.0, 1.0, 0.0]),
        ((mid - q / 2, mid + q / 2), [0.0, 0.0, 1.0]),
        ((mid + q / 2, mid + q / 2), [1.0, 1.0, 1.0]),
    ] {
        let got = px(x, y);
        let w = want(c);
        for k in 0..3 {
            assert!(
                (got[k] as f64 - w[k]).abs() < 1e-3 * w[k].max(0.01) + 1e-4,
                "pixel ({x}, {y}): {got:?} vs {w:?}"
            );
        }
    }
}

#[test]
fn absurd_counts_are_refused_by_the_memory_budget_before_allocating() {
    let mut b = Buf::default();
    let pos = b.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], "VEC3");
    let mut doc = b.doc(json!({
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    }));
    // 400 million positions (9.6 GB as f64 triples) in a 36-byte view.
    doc["accessors"][0]["count"] = json!(400_000_000u64);
    let dir = common::temp_dir("gltf_memory");
    std::fs::write(dir.join("huge.gltf"), doc.to_string()).unwrap();
    let run = common::specula(
        &[
            "render",
            "huge.gltf",
            "-o",
            "out.png",
            "--max-memory",
            "256M",
        ],
        &dir,
    );
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains("huge.gltf: accessors[0] (400000000 elements of Vec3) needs about")
            && stderr.contains("--max-memory"),
        "{stderr}"
    );
    assert!(!dir.join("out.png").exists());
}

#[test]
fn missing_images_and_uv_sets_are_errors_naming_the_file_and_path() {
    let toml = "[camera]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 40.0\nnear = 0.1\nfar = 10.0\n[[mesh]]\ngltf = \"q.gltf\"\n";
    let try_load = |doc: &Value| -> String {
        let text = doc.to_string();
        let read = move |p: &Path| -> std::io::Result<Vec<u8>> {
            if p == Path::new("q.gltf") {
                Ok(text.clone().into_bytes())
            } else {
                Err(std::io::ErrorKind::NotFound.into())
            }
        };
        specula::scene::load_scene_str(Path::new("s.toml"), toml, &read)
            .err()
            .expect("refused")
            .to_string()
    };
    let mut doc = textured_quad_doc();
    doc["images"][0] = json!({"uri": "textures/missing.png"});
    let e = try_load(&doc);
    assert!(
        e.contains("mesh[0].gltf: q.gltf: materials[0].pbrMetallicRoughness.baseColorTexture: images[0].uri: cannot read textures/missing.png"),
        "{e}"
    );
    let mut doc = textured_quad_doc();
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = json!(1);
    let e = try_load(&doc);
    assert!(
        e.contains("meshes[0].primitives[0]") && e.contains("TEXCOORD_1"),
        "{e}"
    );
}

/// A 1×1 PNG of one colour (sRGB bytes as given).
fn png_1x1(rgb: [u8; 3]) -> String {
    let img = image::RgbImage::from_raw(1, 1, rgb.to_vec()).unwrap();
    let mut out = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(out)
    )
}

/// The unit quad of `textured_quad_doc` with `material` and `images`.
fn quad_doc(material: Value, images: Value) -> String {
    quad_doc_with_normal(material, images, [0.0, 0.0, 1.0])
}

/// [`quad_doc`] with `normal` as every vertex's NORMAL.
fn quad_doc_with_normal(material: Value, images: Value, normal: [f32; 3]) -> String {
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
    let n = images.as_array().map_or(0, |a| a.len());
    let textures: Vec<Value> = (0..n).map(|i| json!({"source": i, "sampler": 0})).collect();
    b.doc(json!({
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv}, "indices": idx, "material": 0}]}],
        "materials": [material],
        "textures": textures,
        "samplers": [{"magFilter": 9728, "minFilter": 9728}],
        "images": images,
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    }))
    .to_string()
}

/// The quad seen head-on under a point light off its axis and a uniform
/// environment, 32 × 32: every pixel's radiance.
fn render_quad(doc: &str, environment: bool) -> Vec<[f32; 3]> {
    let mut toml = r#"
[camera]
eye = [0.0, 0.0, 10.0]
target = [0.0, 0.0, 0.0]
fov_y = 10.0
near = 1.0
far = 100.0
[output]
width = 32
height = 32
[[mesh]]
gltf = "quad.gltf"
[[light]]
type = "point"
position = [1.0, 0.5, 3.0]
intensity = [5.0, 5.0, 5.0]
"#
    .to_string();
    if environment {
        toml += "[environment]\nuniform = [0.3, 0.3, 0.3]\n";
    }
    let s = common::scene(&toml, &[("quad.gltf", doc)]);
    let set = specula::render::RenderSettings::from_scene(&s);
    let r = specula::render::render_scene(&s, &set, 0.0).unwrap();
    (0..32 * 32).map(|i| r.frame.buffers.color.get(i)).collect()
}

/// glTF's maps reach the pixels as the specification defines them: a
/// metallicRoughnessTexture texel (B metallic, G roughness, linear) times
/// the factors gives the pixels of those products as constant factors; a
/// flat normal map ((128, 128, 255): the unperturbed normal up to 8-bit
/// rounding) changes a rough surface by less than 1 %; the emissive factor
/// times KHR_materials_emissive_strength times the emissive texel (sRGB)
/// is added to every pixel.
#[test]
fn gltf_maps_match_their_constant_equivalents() {
    // B = 255 → metallic 1 × 0.8; G = 51 → roughness 0.2 × 1.0 (linear).
    let mapped = quad_doc(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.6, 0.3, 1.0],
            "metallicFactor": 0.8, "roughnessFactor": 1.0,
            "metallicRoughnessTexture": {"index": 0}}}),
        json!([{"uri": png_1x1([0, 51, 255])}]),
    );
    let constant = quad_doc(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.6, 0.3, 1.0],
            "metallicFactor": 0.8, "roughnessFactor": 0.2}}),
        json!([]),
    );
    let (a, b) = (render_quad(&mapped, true), render_quad(&constant, true));
    let mut lit = 0;
    for (i, (p, q)) in a.iter().zip(&b).enumerate() {
        lit += usize::from(q[0] > 0.0);
        for c in 0..3 {
            assert!(
                (p[c] - q[c]).abs() <= 1e-5 * q[c].max(1e-3),
                "metallic-roughness map, pixel {i}: {p:?} vs {q:?}"
            );
        }
    }
    assert!(lit > 200, "{lit} lit pixels");

    // A rough dielectric, so that the ~0.3° tilt of 128/255 (1/255 off
    // 0.5) moves a pixel by well under 1 %.
    let rough = json!({"baseColorFactor": [0.9, 0.6, 0.3, 1.0],
        "metallicFactor": 0.0, "roughnessFactor": 1.0});
    let plain = render_quad(
        &quad_doc(json!({"pbrMetallicRoughness": rough}), json!([])),
        true,
    );
    let flat = quad_doc(
        json!({"pbrMetallicRoughness": rough, "normalTexture": {"index": 0}}),
        json!([{"uri": png_1x1([128, 128, 255])}]),
    );
    let n = render_quad(&flat, true);
    for (i, (p, q)) in n.iter().zip(&plain).enumerate() {
        for c in 0..3 {
            assert!(
                (p[c] - q[c]).abs() <= 0.01 * q[c].max(1e-3),
                "flat normal map, pixel {i}: {p:?} vs {q:?}"
            );
        }
    }

    // A constant tilted map: texel (255, 128, 255) is the tangent-space
    // normal (1, 1/255, 1); the quad's uvs run along +x and +y, so the
    // shading normal is that vector in world space: the pixels of the
    // same quad with it as its vertex normal and no map.
    let t = [1.0f32, 1.0 / 255.0, 1.0];
    let len = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
    let tilted = render_quad(
        &quad_doc(
            json!({"pbrMetallicRoughness": rough, "normalTexture": {"index": 0}}),
            json!([{"uri": png_1x1([255, 128, 255])}]),
        ),
        true,
    );
    let by_vertex = render_quad(
        &quad_doc_with_normal(
            json!({"pbrMetallicRoughness": rough}),
            json!([]),
            t.map(|c| c / len),
        ),
        true,
    );
    for (i, (p, q)) in tilted.iter().zip(&by_vertex).enumerate() {
        for c in 0..3 {
            assert!(
                (p[c] - q[c]).abs() <= 1e-3 * q[c].max(1e-3),
                "tilted normal map, pixel {i}: {p:?} vs vertex normal {q:?}"
            );
        }
    }
    assert!(
        (tilted[16 * 32 + 16][0] - plain[16 * 32 + 16][0]).abs() > 0.01 * plain[16 * 32 + 16][0],
        "a 45° tilt shows: {:?} vs {:?}",
        tilted[16 * 32 + 16],
        plain[16 * 32 + 16]
    );

    // Emission: factor (1, 0.5, 0.25) × strength 2 × texel sRGB (255, 188, 255)
    // = (2, 0.5 × decode(188), 0.5) added to the lit pixels.
    let emissive = quad_doc(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.6, 0.3, 1.0],
            "metallicFactor": 0.8, "roughnessFactor": 0.2},
            "emissiveFactor": [1.0, 0.5, 0.25], "emissiveTexture": {"index": 0},
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2.0}}}),
        json!([{"uri": png_1x1([255, 188, 255])}]),
    );
    let decode = |v: f64| {
        let v = v / 255.0;
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    let add = [2.0, 1.0 * decode(188.0), 0.5];
    let e = render_quad(&emissive, true);
    for (i, (p, q)) in e.iter().zip(&b).enumerate() {
        if q[0] == 0.0 {
            continue; // background
        }
        for c in 0..3 {
            let want = q[c] as f64 + add[c];
            assert!(
                (p[c] as f64 - want).abs() <= 1e-4 * want,
                "emission, pixel {i}: {p:?} vs {q:?} + {add:?}"
            );
        }
    }
}
