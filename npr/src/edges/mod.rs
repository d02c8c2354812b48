//! Line extraction from mesh topology, for stroke overlays: which edges to
//! draw (silhouette, crease, boundary, material), which parts of them the
//! eye sees (the depth buffer), and how they chain into polylines.
//!
//! - Topology ([`MeshEdges::new`], once per scene): vertices are welded by
//!   position (quantized to 1e-6 of the scene's extent, so split normals
//!   and uv seams do not cut the mesh), each undirected edge records its
//!   faces. Triangles that weld to zero area are left out.
//! - Kinds: **boundary** (one face), **material** (two faces of different
//!   materials), **crease** (face normals more than `crease_angle` apart),
//!   all fixed; **silhouette** (one face toward the eye, the other away)
//!   per view. An edge that is several kinds is drawn once, as the first
//!   of silhouette, boundary, material, crease that is asked for.
//! - Visibility (`visible_pieces`): points every sample along the
//!   projected edge are compared with the depth buffer; a point is seen
//!   when its view depth is at most (1 + `DEPTH_BIAS`) times the largest
//!   depth of the samples within one output pixel (ssaa samples) around it
//!   (3×3 without supersampling). The largest of the neighbourhood,
//!   not the sample's own, is what keeps a silhouette (whose neighbours
//!   show the background) and an edge where two objects touch (whose
//!   neighbours show the edge's own faces) from being eaten by the bias.
//! - Chaining ([`chain`]): the visible pieces of edges of one kind are
//!   joined where they reach a shared vertex into polylines, going on
//!   through a vertex along the unused piece that turns least on screen; a
//!   piece end that stops short of its vertex (hidden beyond it) ends its
//!   polyline, and a chain that comes back to its start is closed. So a
//!   silhouette partly hidden behind another object is one polyline per
//!   visible run, not one per edge.

use glam::{Vec3, Vec4};
use rayon::prelude::*;
use specula_raster::buffers::prefetch;
use specula_raster::camera::View;
use specula_raster::SceneParts;
use std::collections::HashMap;

/// What an edge is drawn as; the order is the drawing and SVG group order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum EdgeKind {
    Silhouette,
    Boundary,
    Material,
    Crease,
}

impl EdgeKind {
    pub(crate) const ALL: [EdgeKind; 4] = [
        EdgeKind::Silhouette,
        EdgeKind::Boundary,
        EdgeKind::Material,
        EdgeKind::Crease,
    ];

    pub(crate) fn name(self) -> &'static str {
        match self {
            EdgeKind::Silhouette => "silhouette",
            EdgeKind::Boundary => "boundary",
            EdgeKind::Material => "material",
            EdgeKind::Crease => "crease",
        }
    }
}

/// Relative depth tolerance of the visibility test (module docs).
pub(crate) const DEPTH_BIAS: f32 = 0.01;

const NO_FACE: u32 = u32::MAX;

#[derive(Clone, Copy, Debug)]
struct Edge {
    /// Welded vertex indices, a < b.
    a: u32,
    b: u32,
    faces: [u32; 2],
    /// The fixed kind (boundary, material, crease) asked for, if any.
    fixed: Option<EdgeKind>,
}

/// The scene's edges, welded; see the module docs.
#[derive(Clone, Debug)]
pub struct MeshEdges {
    /// Welded vertex positions.
    pub points: Vec<Vec3>,
    edges: Vec<Edge>,
    face_normal: Vec<Vec3>,
    face_point: Vec<Vec3>,
    silhouettes: bool,
}

impl MeshEdges {
    /// Topology of `triangles` (indices into `positions`) with per-triangle
    /// `materials`; `kinds` are the kinds to draw, `crease_angle_deg` the
    /// crease threshold.
    pub fn new(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        materials: &[u32],
        kinds: &[EdgeKind],
        crease_angle_deg: f32,
    ) -> MeshEdges {
        // Weld on a grid of 1e-6 of the extent.
        let extent = positions
            .iter()
            .filter(|p| p.is_finite())
            .fold(0.0f32, |m, p| m.max(p.abs().max_element()));
        let q = (extent * 1e-6).max(f32::MIN_POSITIVE);
        let mut index: HashMap<[i64; 3], u32> = HashMap::new();
        let mut points = Vec::new();
        let mut weld = vec![u32::MAX; positions.len()];
        for (i, p) in positions.iter().enumerate() {
            if !p.is_finite() {
                continue;
            }
            let key = (*p / q).round().to_array().map(|c| c as i64);
            weld[i] = *index.entry(key).or_insert_with(|| {
                points.push(*p);
                points.len() as u32 - 1
            });
        }
        let mut face_normal = Vec::with_capacity(triangles.len());
        let mut face_point = Vec::with_capacity(triangles.len());
        let mut map: HashMap<(u32, u32), usize> = HashMap::new();
        let mut edges: Vec<Edge> = Vec::new();
        let mut extra_faces = vec![0u8; 0];
        for (f, t) in triangles.iter().enumerate() {
            let w = t.map(|v| weld.get(v as usize).copied().unwrap_or(u32::MAX));
            let ok = !w.contains(&u32::MAX) && w[0] != w[1] && w[1] != w[2] && w[0] != w[2];
            let n = if ok {
                let [a, b, c] = w.map(|v| points[v as usize]);
                (b - a).cross(c - a).try_normalize()
            } else {
                None
            };
            face_normal.push(n.unwrap_or(Vec3::ZERO));
            face_point.push(positions[t[0] as usize]);
            if n.is_none() {
                continue;
            }
            for k in 0..3 {
                let (u, v) = (w[k], w[(k + 1) % 3]);
                let key = (u.min(v), u.max(v));
                match map.get(&key) {
                    Some(&e) => {
                        if edges[e].faces[1] == NO_FACE {
                            edges[e].faces[1] = f as u32;
                        } else {
                            // A third face: a non-manifold edge; drawn as a
                            // boundary (it bounds a sheet).
                            extra_faces[e] = 1;
                        }
                    }
                    None => {
                        map.insert(key, edges.len());
                        edges.push(Edge {
                            a: key.0,
                            b: key.1,
                            faces: [f as u32, NO_FACE],
                            fixed: None,
                        });
                        extra_faces.push(0);
                    }
                }
            }
        }
        let cos_crease = crease_angle_deg.to_radians().cos();
        for (e, extra) in edges.iter_mut().zip(&extra_faces) {
            let [f0, f1] = e.faces;
            let boundary = f1 == NO_FACE || *extra > 0;
            let (material, crease) = if boundary {
                (false, false)
            } else {
                let (f0, f1) = (f0 as usize, f1 as usize);
                (
                    materials[f0] != materials[f1],
                    face_normal[f0].dot(face_normal[f1]) < cos_crease,
                )
            };
            // The first kind asked for, in priority order, that applies.
            e.fixed = [
                (EdgeKind::Boundary, boundary),
                (EdgeKind::Material, material),
                (EdgeKind::Crease, crease),
            ]
            .into_iter()
            .find(|(k, on)| *on && kinds.contains(k))
            .map(|(k, _)| k);
        }
        MeshEdges {
            points,
            edges,
            face_normal,
            face_point,
            silhouettes: kinds.contains(&EdgeKind::Silhouette),
        }
    }

    /// The scene's main-pass triangles (the ones the scene's meshes made).
    pub fn from_scene(scene: &SceneParts, kinds: &[EdgeKind], crease_angle_deg: f32) -> MeshEdges {
        MeshEdges::new(
            &scene.positions,
            &scene.triangles,
            &scene.tri_material,
            kinds,
            crease_angle_deg,
        )
    }

    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// Every edge drawn from `eye`, with its kind: (welded a, welded b, kind).
    pub fn classify(&self, eye: Vec3) -> Vec<(u32, u32, EdgeKind)> {
        // Each face's facing once (an edge would test both of its faces,
        // and every face has three edges).
        let facing: Vec<bool> = if self.silhouettes {
            self.face_normal
                .par_iter()
                .zip(self.face_point.par_iter())
                .with_min_len(4096)
                .map(|(n, p)| n.dot(eye - *p) > 0.0)
                .collect()
        } else {
            Vec::new()
        };
        self.edges
            .par_iter()
            .with_min_len(4096)
            .filter_map(|e| self.kind(e, &facing).map(|k| (e.a, e.b, k)))
            .collect()
    }

    fn kind(&self, e: &Edge, facing: &[bool]) -> Option<EdgeKind> {
        if self.silhouettes
            && e.faces[1] != NO_FACE
            && facing[e.faces[0] as usize] != facing[e.faces[1] as usize]
        {
            return Some(EdgeKind::Silhouette);
        }
        e.fixed
    }
}

/// A polyline in output pixels (x right, y down, pixel centres at +½).
#[derive(Clone, Debug, PartialEq)]
pub struct Polyline {
    pub kind: EdgeKind,
    pub points: Vec<[f32; 2]>,
    /// The last point joins the first.
    pub closed: bool,
}

/// A visible stretch of one edge: its points in output pixels and, for
/// each end that is the edge's own end (visible up to its vertex), the
/// welded vertex there (for chaining).
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    pub kind: EdgeKind,
    pub a: [f32; 2],
    pub b: [f32; 2],
    pub ends: [Option<u32>; 2],
}

mod chain;
mod visibility;

pub use chain::chain;
pub(crate) use visibility::{visible_pieces, DepthView};

#[cfg(test)]
/// xorshift64* in [0, 1).
fn rng(seed: u64) -> impl FnMut() -> f32 {
    let mut state = seed.max(1);
    move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
    }
}
