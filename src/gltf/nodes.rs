//! The default scene's node hierarchy (glTF 2.0 spec, "Nodes and
//! Hierarchy"): each node's matrix or TRS, composed down the tree; the
//! meshes, cameras and lights it carries, placed. The hierarchy must be a
//! set of disjoint trees: a node with two parents or on a cycle is an
//! error. The walk is iterative, so a deep hierarchy cannot overflow the
//! stack.

use super::buffers::{read_accessor, Buffers, Elements};
use super::{punctual_light, Ctx, GltfCamera, GltfError, GltfPrimitive, Projection};
use crate::memory;
use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec4};
use gltf::json;
use json::accessor::{ComponentType, Type};
use json::mesh::{Mode, Semantic};
use json::validation::Checked;
use specula_core::light::Light;
use std::collections::BTreeSet;

pub(super) struct Placed {
    pub(super) primitives: Vec<GltfPrimitive>,
    pub(super) cameras: Vec<GltfCamera>,
    pub(super) lights: Vec<Light>,
}

/// A node's local transform: its matrix (column-major), or T · R · S.
fn local(n: &json::Node, at: &str) -> Result<Mat4, GltfError> {
    if let Some(m) = n.matrix {
        if !m.iter().all(|v| v.is_finite()) {
            return Err(GltfError::at(
                &format!("{at}.matrix"),
                "every element must be finite",
            ));
        }
        return Ok(Mat4::from_cols_array(&m));
    }
    let t = n.translation.unwrap_or([0.0; 3]);
    let s = n.scale.unwrap_or([1.0; 3]);
    let r = n.rotation.as_ref().map_or([0.0, 0.0, 0.0, 1.0], |q| q.0);
    for (f, v) in [
        ("translation", &t[..]),
        ("scale", &s[..]),
        ("rotation", &r[..]),
    ] {
        if !v.iter().all(|x| x.is_finite()) {
            return Err(GltfError::at(
                &format!("{at}.{f}"),
                format!("every component must be finite, got {v:?}"),
            ));
        }
    }
    let q = Quat::from_array(r);
    let len = q.length();
    if len.is_nan() || len <= 0.0 {
        return Err(GltfError::at(
            &format!("{at}.rotation"),
            "a zero quaternion is no rotation",
        ));
    }
    Ok(Mat4::from_scale_rotation_translation(
        Vec3::from(s),
        q / len,
        Vec3::from(t),
    ))
}

/// The scene's nodes placed: the default scene (`scene`, else scene 0);
/// without scenes, every node without a parent (with a warning).
pub(super) fn walk(ctx: &mut Ctx, buffers: &Buffers) -> Result<Placed, GltfError> {
    let root = &ctx.root;
    let n = root.nodes.len();
    // Parents, and the one-parent rule.
    let mut parent: Vec<Option<usize>> = vec![None; n];
    for (p, node) in root.nodes.iter().enumerate() {
        for (k, c) in node.children.iter().flatten().enumerate() {
            let c = c.value();
            if c >= n {
                return Err(GltfError::at(
                    &format!("nodes[{p}].children[{k}]"),
                    format!("no node {c}"),
                ));
            }
            if c == p {
                return Err(GltfError::at(
                    &format!("nodes[{p}].children[{k}]"),
                    "the node is its own child (a cycle)",
                ));
            }
            if let Some(q) = parent[c] {
                return Err(GltfError::at(&format!("nodes[{p}].children[{k}]"), format!("node {c} is already a child of nodes[{q}] (the node hierarchy must be a set of disjoint trees)")));
            }
            parent[c] = Some(p);
        }
    }
    // With one parent each, the nodes no walk down from a parentless node
    // reaches are exactly those on (or under) a cycle.
    let mut reached = vec![false; n];
    let mut stack: Vec<usize> = (0..n).filter(|i| parent[*i].is_none()).collect();
    while let Some(i) = stack.pop() {
        reached[i] = true;
        stack.extend(root.nodes[i].children.iter().flatten().map(|c| c.value()));
    }
    if let Some(i) = reached.iter().position(|r| !r) {
        return Err(GltfError::at(
            &format!("nodes[{i}]"),
            format!(
                "the node is on a cycle of the node hierarchy (nodes[{i}] is its own ancestor)"
            ),
        ));
    }
    let roots: Vec<usize> = match root
        .scene
        .map(|s| s.value())
        .or((!root.scenes.is_empty()).then_some(0))
    {
        Some(s) => {
            let scene = root
                .scenes
                .get(s)
                .ok_or_else(|| GltfError::at("scene", format!("no scene {s}")))?;
            scene.nodes.iter().map(|i| i.value()).collect()
        }
        None => {
            ctx.warnings
                .push("the file has no scenes: every node without a parent is shown".into());
            (0..n).filter(|i| parent[*i].is_none()).collect()
        }
    };
    let mut out = Placed {
        primitives: Vec::new(),
        cameras: Vec::new(),
        lights: Vec::new(),
    };
    let mut warned_meshes = BTreeSet::new();
    // Depth first, children in order: the stack holds them reversed.
    let mut stack: Vec<(usize, Mat4)> = roots.iter().rev().map(|&i| (i, Mat4::IDENTITY)).collect();
    let mut visits = 0usize;
    while let Some((i, parent_world)) = stack.pop() {
        visits += 1;
        if visits > n {
            // Scene roots listed twice or below one another.
            return Err(GltfError::at("scene", format!("nodes[{i}] is reached more than once (a scene's nodes must be roots of disjoint trees)")));
        }
        let node = &ctx.root.nodes[i];
        let at = format!("nodes[{i}]");
        let world = parent_world * local(node, &at)?;
        if node.skin.is_some() {
            ctx.warnings.push(format!(
                "{at}.skin: skinning is not supported; drawn in its rest pose"
            ));
        }
        if let Some(m) = node.mesh {
            let m = m.value();
            let mesh = &ctx.root.meshes[m];
            let morph = node.weights.is_some()
                || mesh.weights.is_some()
                || mesh.primitives.iter().any(|p| p.targets.is_some());
            if morph && warned_meshes.insert(m) {
                ctx.warnings.push(format!(
                    "meshes[{m}]: morph targets are not supported; drawn with its base shape"
                ));
            }
            for p in 0..mesh.primitives.len() {
                if let Some(prim) = read_primitive(ctx, buffers, m, p, &world, &at)? {
                    out.primitives.push(prim);
                }
            }
        }
        let node = &ctx.root.nodes[i];
        if let Some(c) = node.camera {
            out.cameras.push(camera(&ctx.root, c.value(), &world, &at)?);
        }
        if let Some(l) = node
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
        {
            let li = l.light.value();
            let lat = format!("extensions.KHR_lights_punctual.lights[{li}]");
            let light = ctx
                .root
                .extensions
                .as_ref()
                .and_then(|e| e.khr_lights_punctual.as_ref())
                .and_then(|k| k.lights.get(li))
                .ok_or_else(|| {
                    GltfError::at(
                        &format!("{at}.extensions.KHR_lights_punctual.light"),
                        format!("no light {li}"),
                    )
                })?;
            out.lights.push(punctual_light(&lat, light, &world)?);
        }
        for c in node.children.iter().flatten().rev() {
            stack.push((c.value(), world));
        }
    }
    Ok(out)
}

/// `cameras[c]` at a node's world transform.
fn camera(root: &json::Root, c: usize, world: &Mat4, node: &str) -> Result<GltfCamera, GltfError> {
    let at = format!("cameras[{c}]");
    let cam = &root.cameras[c];
    let projection = match (&cam.perspective, &cam.orthographic) {
        (Some(p), _) => Projection::Perspective {
            yfov: p.yfov,
            aspect_ratio: p.aspect_ratio,
            znear: p.znear,
            zfar: p.zfar,
        },
        (None, Some(o)) => Projection::Orthographic {
            xmag: o.xmag,
            ymag: o.ymag,
            znear: o.znear,
            zfar: o.zfar,
        },
        (None, None) => return Err(GltfError::at(&at, "neither perspective nor orthographic")),
    };
    let eye = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).try_normalize();
    let up = world.transform_vector3(Vec3::Y).try_normalize();
    let (Some(forward), Some(up)) = (forward, up) else {
        return Err(GltfError::at(
            &format!("{at} (at {node})"),
            "the node's transform has no view direction (zero scale)",
        ));
    };
    Ok(GltfCamera {
        at: format!("{at} (at {node})"),
        eye,
        forward,
        up,
        projection,
    })
}

/// An attribute as `N`-component vectors, its count checked against the
/// positions'.
fn attribute<const N: usize>(
    e: Elements,
    at: &str,
    count: usize,
) -> Result<Vec<[f32; N]>, GltfError> {
    if e.count != count {
        return Err(GltfError::at(
            at,
            format!("{} elements for {count} positions", e.count),
        ));
    }
    let mut out = Vec::with_capacity(count);
    for (k, c) in e.values.chunks_exact(e.components).enumerate() {
        let mut v = [1.0f32; N];
        for (o, x) in v.iter_mut().zip(c) {
            *o = *x as f32;
        }
        if !v.iter().all(|x| x.is_finite()) {
            return Err(GltfError::at(
                at,
                format!("element {k} is not finite ({c:?})"),
            ));
        }
        out.push(v);
    }
    Ok(out)
}

/// One primitive of `meshes[m]` at `world`: `None` (with a warning) for
/// points and lines.
fn read_primitive(
    ctx: &mut Ctx,
    buffers: &Buffers,
    m: usize,
    p: usize,
    world: &Mat4,
    node: &str,
) -> Result<Option<GltfPrimitive>, GltfError> {
    let (root, warnings) = (&ctx.root, &mut ctx.warnings);
    let prim = &root.meshes[m].primitives[p];
    let at = format!("meshes[{m}].primitives[{p}]");
    let mode = match prim.mode {
        Checked::Valid(mode) => mode,
        Checked::Invalid => return Err(GltfError::at(&format!("{at}.mode"), "invalid")),
    };
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        warnings.push(format!(
            "{at} (at {node}): mode {mode:?} skipped: only triangles are rendered"
        ));
        return Ok(None);
    }
    let attr = |s: Semantic| prim.attributes.get(&Checked::Valid(s)).map(|a| a.value());
    let pos_at = format!("{at}.attributes.POSITION");
    let pos = attr(Semantic::Positions).ok_or_else(|| GltfError::at(&pos_at, "missing"))?;
    let positions: Vec<[f32; 3]> = {
        let e = read_accessor(root, buffers, pos, &pos_at, &[Type::Vec3])?;
        let count = e.count;
        attribute(e, &pos_at, count)?
    };
    let nv = positions.len();
    let indices: Vec<u32> = match prim.indices {
        Some(a) => {
            let iat = format!("{at}.indices");
            let acc = &root.accessors[a.value()];
            if !matches!(
                acc.component_type,
                Checked::Valid(json::accessor::GenericComponentType(
                    ComponentType::U8 | ComponentType::U16 | ComponentType::U32
                ))
            ) {
                return Err(GltfError::at(
                    &iat,
                    format!("accessor {a} must hold unsigned bytes, shorts or ints"),
                ));
            }
            let e = read_accessor(root, buffers, a.value(), &iat, &[Type::Scalar])?;
            let mut out = Vec::with_capacity(e.count);
            for (k, v) in e.values.iter().enumerate() {
                if *v >= nv as f64 {
                    return Err(GltfError::at(
                        &iat,
                        format!("index {v} (element {k}) is past the {nv} vertices"),
                    ));
                }
                out.push(*v as u32);
            }
            out
        }
        None => (0..nv as u32).collect(),
    };
    let n = indices.len();
    let mut triangles: Vec<[u32; 3]> = match mode {
        Mode::Triangles => indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
        // pᵢ = {vᵢ, vᵢ₊₁₊ᵢ﹪₂, vᵢ₊₂₋ᵢ﹪₂}: every other triangle reversed to
        // keep the winding.
        Mode::TriangleStrip => (0..n.saturating_sub(2))
            .map(|i| {
                let odd = i % 2;
                [indices[i], indices[i + 1 + odd], indices[i + 2 - odd]]
            })
            .collect(),
        // pᵢ = {vᵢ₊₁, vᵢ₊₂, v₀}.
        _ => (0..n.saturating_sub(2))
            .map(|i| [indices[i + 1], indices[i + 2], indices[0]])
            .collect(),
    };
    memory::reserve(
        &format!("{at} ({nv} vertices, {} triangles)", triangles.len()),
        memory::mesh_bytes(3 * triangles.len().max(nv) as u64, triangles.len() as u64),
    )?;
    let read = |s: Semantic, name: &str, types: &[Type]| -> Result<Option<Elements>, GltfError> {
        attr(s)
            .map(|a| read_accessor(root, buffers, a, &format!("{at}.attributes.{name}"), types))
            .transpose()
    };
    let normals = read(Semantic::Normals, "NORMAL", &[Type::Vec3])?
        .map(|e| attribute::<3>(e, &format!("{at}.attributes.NORMAL"), nv))
        .transpose()?;
    let tangents = read(Semantic::Tangents, "TANGENT", &[Type::Vec4])?
        .map(|e| attribute::<4>(e, &format!("{at}.attributes.TANGENT"), nv))
        .transpose()?;
    let uv0 = read(Semantic::TexCoords(0), "TEXCOORD_0", &[Type::Vec2])?
        .map(|e| attribute::<2>(e, &format!("{at}.attributes.TEXCOORD_0"), nv))
        .transpose()?;
    let uv1 = read(Semantic::TexCoords(1), "TEXCOORD_1", &[Type::Vec2])?
        .map(|e| attribute::<2>(e, &format!("{at}.attributes.TEXCOORD_1"), nv))
        .transpose()?;
    let color0 = read(Semantic::Colors(0), "COLOR_0", &[Type::Vec3, Type::Vec4])?
        .map(|e| attribute::<4>(e, &format!("{at}.attributes.COLOR_0"), nv))
        .transpose()?;

    // The node's transform: points by `world`, normals by its cofactor
    // matrix (det · M⁻ᵀ, defined even for a zero scale) times sign(det),
    // tangents by M; a mirroring transform (det < 0) reverses the winding
    // and the tangent handedness.
    let m3 = Mat3::from_mat4(*world);
    let det = m3.determinant();
    let sign = if det < 0.0 { -1.0 } else { 1.0 };
    let cof = Mat3::from_cols(
        m3.y_axis.cross(m3.z_axis),
        m3.z_axis.cross(m3.x_axis),
        m3.x_axis.cross(m3.y_axis),
    ) * sign;
    let mut out = GltfPrimitive {
        at: format!("{at} (at {node})"),
        material: prim.material.map(|i| i.value()),
        ..Default::default()
    };
    out.positions = positions
        .iter()
        .map(|p| world.transform_point3(Vec3::from(*p)))
        .collect();
    if let Some(k) = out.positions.iter().position(|p| !p.is_finite()) {
        return Err(GltfError::at(
            &pos_at,
            format!("vertex {k} is not finite after the node transforms (at {node})"),
        ));
    }
    out.uv0 = uv0.map(|v| v.into_iter().map(Vec2::from).collect());
    out.uv1 = uv1.map(|v| v.into_iter().map(Vec2::from).collect());
    out.color0 = color0.map(|v| v.into_iter().map(Vec4::from).collect());
    if det < 0.0 {
        for t in &mut triangles {
            t.swap(1, 2);
        }
    }
    match normals {
        Some(ns) => {
            out.normals = ns
                .iter()
                .map(|n| (cof * Vec3::from(*n)).try_normalize().unwrap_or(Vec3::Z))
                .collect();
            out.tangents = tangents.map(|ts| {
                ts.iter()
                    .map(|t| {
                        let v = (m3 * Vec3::new(t[0], t[1], t[2]))
                            .try_normalize()
                            .unwrap_or(Vec3::X);
                        v.extend(if t[3] < 0.0 { -sign } else { sign })
                    })
                    .collect()
            });
            out.triangles = triangles;
        }
        None => flat(&mut out, &triangles),
    }
    Ok(Some(out))
}

/// Flat normals: every triangle gets its own three vertices with its face
/// normal (tangents, if any, are dropped, as the spec says).
fn flat(p: &mut GltfPrimitive, triangles: &[[u32; 3]]) {
    let corners = |t: &[u32; 3]| t.map(|i| i as usize);
    let gather = |v: &[Vec2]| -> Vec<Vec2> {
        triangles
            .iter()
            .flat_map(|t| corners(t).map(|i| v[i]))
            .collect()
    };
    let positions: Vec<Vec3> = triangles
        .iter()
        .flat_map(|t| corners(t).map(|i| p.positions[i]))
        .collect();
    p.normals = positions
        .chunks_exact(3)
        .flat_map(|c| {
            let n = (c[1] - c[0])
                .cross(c[2] - c[0])
                .try_normalize()
                .unwrap_or(Vec3::Z);
            [n; 3]
        })
        .collect();
    p.uv0 = p.uv0.as_deref().map(gather);
    p.uv1 = p.uv1.as_deref().map(gather);
    p.color0 = p.color0.as_deref().map(|v| {
        triangles
            .iter()
            .flat_map(|t| corners(t).map(|i| v[i]))
            .collect()
    });
    p.tangents = None;
    p.triangles = (0..triangles.len() as u32)
        .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
        .collect();
    p.positions = positions;
}
