//! Polygon lights as scene files and `specula eval` give them: validation
//! (planar, simple, 3 to `MAX_POLYGON_VERTICES` vertices) and the unlit
//! triangles that draw a visible light.

use crate::checks::{FieldError, FieldReason};
use glam::{DVec2, DVec3, Vec3, Vec4};
use specula_core::light::MAX_POLYGON_VERTICES;
use specula_core::models::microfacet::Ndf;
use specula_core::Model;
use specula_raster::{Lit, Material, SceneParts, Unlit};

/// Newell's normal of the polygon (twice its vector area, toward its front)
/// and its size (the largest distance from the first vertex).
fn normal_and_size(p: &[DVec3]) -> (DVec3, f64) {
    let mut n = DVec3::ZERO;
    for k in 0..p.len() {
        n += p[k].cross(p[(k + 1) % p.len()]);
    }
    let size = p.iter().map(|q| (*q - p[0]).length()).fold(0.0, f64::max);
    (n, size)
}

/// The polygon in 2-D coordinates of its plane, counter-clockwise seen from
/// its front (the side its Newell normal points to).
fn in_plane(p: &[DVec3], n: DVec3) -> Vec<DVec2> {
    let n = n.normalize();
    let e1 = n.any_orthonormal_vector();
    let e2 = n.cross(e1);
    p.iter()
        .map(|q| DVec2::new((*q - p[0]).dot(e1), (*q - p[0]).dot(e2)))
        .collect()
}

fn cross2(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Closed segments ab and cd share a point.
fn segments_meet(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let o = |p: DVec2, q: DVec2, r: DVec2| cross2(q - p, r - p);
    let (d1, d2, d3, d4) = (o(c, d, a), o(c, d, b), o(a, b, c), o(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    let on = |p: DVec2, q: DVec2, r: DVec2, side: f64| {
        side == 0.0
            && r.x >= p.x.min(q.x)
            && r.x <= p.x.max(q.x)
            && r.y >= p.y.min(q.y)
            && r.y <= p.y.max(q.y)
    };
    on(c, d, a, d1) || on(c, d, b, d2) || on(a, b, c, d3) || on(a, b, d, d4)
}

/// Checks a polygon light's vertices: 3..=MAX_POLYGON_VERTICES finite
/// points, planar (within 1e-4 of its size), with a non-zero area, and
/// simple (no edge meets another except its neighbours at their shared
/// vertex), so its orientation and its inside are defined. Convex or not.
pub(crate) fn check_polygon(field: &str, v: &[[f32; 3]]) -> Result<(), FieldError> {
    let refuse = |reason| Err(FieldError::new(field, reason));
    if !(3..=MAX_POLYGON_VERTICES).contains(&v.len()) {
        return refuse(FieldReason::PolygonVertexCount {
            max: MAX_POLYGON_VERTICES,
            got: v.len(),
        });
    }
    for (k, p) in v.iter().enumerate() {
        crate::checks::finite(&format!("{field}[{k}]"), p)?;
    }
    let p: Vec<DVec3> = v.iter().map(|q| DVec3::from(q.map(|c| c as f64))).collect();
    let (n, size) = normal_and_size(&p);
    if size == 0.0 || n.length() <= 1e-9 * size * size {
        return refuse(FieldReason::NoArea);
    }
    let un = n.normalize();
    for (k, q) in p.iter().enumerate() {
        if (*q - p[0]).dot(un).abs() > 1e-4 * size {
            return Err(FieldError::new(
                format!("{field}[{k}]"),
                FieldReason::NotPlanar,
            ));
        }
    }
    let q = in_plane(&p, n);
    let m = q.len();
    for i in 0..m {
        for j in i + 1..m {
            if q[i] == q[j] {
                return refuse(FieldReason::SamePoint(i, j));
            }
            // Non-adjacent edges i→i+1 and j→j+1 must not meet.
            let adjacent = j == i + 1 || (i == 0 && j == m - 1);
            if !adjacent && segments_meet(q[i], q[(i + 1) % m], q[j], q[(j + 1) % m]) {
                return refuse(FieldReason::NotSimple(i, j));
            }
        }
    }
    Ok(())
}

/// Why `model` cannot take polygon lights by LTC, if it cannot: the
/// table is fitted to GGX, and Beckmann or GTR lobes through it err by up
/// to 30 % of the albedo (core/tests/ltc_ggx.rs); the glTF sheen lobe has
/// no LTC.
pub(crate) fn ltc_refusal(model: &Model) -> Option<String> {
    match model {
        Model::Microfacet(m) if m.params.ndf != Ndf::Ggx => Some(format!(
            "polygon lights need ndf = \"ggx\" on microfacet materials (the LTC table is fitted to GGX; {:?} through it errs by up to 30 %)",
            m.params.ndf
        )),
        Model::Gltf(m) if m.has_sheen() => Some(
            "polygon lights cannot light a gltf material with sheen (sheen_color_factor above 0): the sheen lobe has no LTC integral here".to_string(),
        ),
        _ => None,
    }
}

/// A material that polygon lights cannot light by LTC, and why
/// ([`ltc_refusal`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("material {material:?}: {reason}")]
pub(crate) struct LtcRefusal {
    pub(crate) material: String,
    pub(crate) reason: String,
}

/// Checks every lit material against polygon lights (see [`ltc_refusal`]).
pub(crate) fn check_materials(materials: &[Material]) -> Result<(), LtcRefusal> {
    for m in materials {
        if let Some(lit) = m.shader.as_any().downcast_ref::<Lit>() {
            if let Some(reason) = ltc_refusal(lit.model()) {
                return Err(LtcRefusal {
                    material: m.name.clone(),
                    reason,
                });
            }
        }
    }
    Ok(())
}

/// Triangles covering a simple planar polygon, by ear clipping in its
/// plane, each turning like the polygon (so front faces stay front faces).
pub(crate) fn triangulate(v: &[[f32; 3]]) -> Vec<[usize; 3]> {
    let p: Vec<DVec3> = v.iter().map(|q| DVec3::from(q.map(|c| c as f64))).collect();
    let (n, _) = normal_and_size(&p);
    let q = in_plane(&p, n);
    let mut idx: Vec<usize> = (0..q.len()).collect();
    let mut out = Vec::with_capacity(q.len() - 2);
    while idx.len() > 3 {
        let m = idx.len();
        let ear = (0..m).find(|&k| {
            let (a, b, c) = (q[idx[(k + m - 1) % m]], q[idx[k]], q[idx[(k + 1) % m]]);
            if cross2(b - a, c - b) <= 0.0 {
                return false; // reflex (or straight) corner
            }
            // No other vertex inside or on the triangle abc.
            idx.iter().all(|&j| {
                let r = q[j];
                if r == a || r == b || r == c {
                    return true;
                }
                !(cross2(b - a, r - a) >= 0.0
                    && cross2(c - b, r - b) >= 0.0
                    && cross2(a - c, r - c) >= 0.0)
            })
        });
        // A simple polygon always has an ear (two, in fact); the fallback
        // only guards against rounding in near-degenerate input.
        let k = ear.unwrap_or(0);
        out.push([idx[(k + m - 1) % m], idx[k], idx[(k + 1) % m]]);
        idx.remove(k);
    }
    out.push([idx[0], idx[1], idx[2]]);
    out
}

/// Adds a visible light's triangles to the scene, drawn by an `unlit`
/// material of the light's radiance (double-sided for two-sided lights;
/// a one-sided light's back is culled). Call after the meshes (uvs and
/// tangents already settled) and before the geometry passes are set.
pub(crate) fn add_visible(
    data: &mut SceneParts,
    materials: &mut Vec<Material>,
    name: &str,
    vertices: &[[f32; 3]],
    radiance: [f32; 3],
    two_sided: bool,
) {
    let p: Vec<DVec3> = vertices
        .iter()
        .map(|q| DVec3::from(q.map(|c| c as f64)))
        .collect();
    let (n, _) = normal_and_size(&p);
    let n = n.normalize().as_vec3();
    let mat = materials.len() as u32;
    materials.push(Material::new(
        name,
        Unlit {
            color: radiance,
            intensity: 1.0,
        },
        two_sided,
    ));
    let base = data.positions.len() as u32;
    data.positions
        .extend(vertices.iter().map(|q| Vec3::from(*q)));
    data.normals.extend(std::iter::repeat_n(n, vertices.len()));
    if !data.uvs.is_empty() {
        data.uvs
            .extend(std::iter::repeat_n(glam::Vec2::ZERO, vertices.len()));
        let t = n.any_orthonormal_vector();
        data.tangents
            .extend(std::iter::repeat_n(Vec4::from((t, 1.0)), vertices.len()));
    }
    if !data.colors.is_empty() {
        data.colors
            .extend(std::iter::repeat_n(Vec4::ONE, vertices.len()));
    }
    for t in triangulate(vertices) {
        data.triangles.push(t.map(|k| base + k as u32));
        data.tri_material.push(mat);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(v: &[[f32; 3]], tris: &[[usize; 3]]) -> f64 {
        tris.iter()
            .map(|t| {
                let [a, b, c] = t.map(|k| DVec3::from(v[k].map(|x| x as f64)));
                (b - a).cross(c - a).z * 0.5
            })
            .sum()
    }

    #[test]
    fn ear_clipping_covers_a_concave_polygon_with_its_turn() {
        // An L in z = 0, counter-clockwise from +z: area 3 + 2 = 5... (1×3 + 2×1).
        let l = [
            [-1.0, -1.0, 0.0],
            [2.0, -1.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [-1.0, 2.0, 0.0],
        ];
        let t = triangulate(&l);
        assert_eq!(t.len(), 4);
        assert!((area(&l, &t) - 5.0).abs() < 1e-12, "{}", area(&l, &t));
        for tri in &t {
            assert!(area(&l, &[*tri]) > 0.0, "{tri:?} turns the wrong way");
        }
        check_polygon("l", &l).unwrap();
    }

    #[test]
    fn self_intersecting_and_repeated_vertices_are_refused() {
        let bow = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.3, 1.4, 0.0],
        ];
        let e = check_polygon("b", &bow).unwrap_err();
        // Edge 1 (x + y = 1) and edge 3 (back to the origin) cross near
        // (0.48, 0.52); edges 0 and 2 lie at y = 0 and y ≥ 1.
        assert_eq!(e.reason, FieldReason::NotSimple(1, 3), "{e}");
        assert_eq!(
            e.to_string(),
            "b: the polygon is not simple (edges 1 and 3 cross)"
        );
        let rep = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        assert!(check_polygon("r", &rep).is_err());
    }
}
