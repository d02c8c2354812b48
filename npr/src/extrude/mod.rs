//! Outline by geometry: a second geometry pass draws the scene's back
//! faces pushed outward along their vertex normals, in the outline
//! colour; the front faces of the main pass then cover its inside (the
//! depth test decides, so the passes' order only matters for ties), and
//! what stays visible is a ring around each silhouette.
//!
//! The push is made in clip space so the ring has a constant width in
//! pixels whatever the distance: with p the clip position and n = M·(n, 0)
//! the clip-space normal, the screen direction of the normal is
//! n.xy − (p.xy / p.w)·n.w (the derivative of p.xy / p.w along n), taken
//! to pixels (× viewport / 2) and normalized; the vertex moves `width`
//! pixels that way: p.xy += dir_ndc · p.w. Vertices at or behind the eye
//! (p.w ≤ 0) or whose normal points along the view ray stay put.
//!
//! Meshes with split normals (a cube's 24 vertices) would crack at the
//! corners, each face pushed along its own normal; the pass pushes along
//! smoothed normals instead: every vertex takes the normalized sum of the
//! normals of all vertices at the same position, so copies of a corner
//! move together and the pushed shell stays closed.
//!
//! The smoothed normal's screen direction is not a silhouette corner's
//! bisector: at a cube corner where two silhouette edges meet at an angle
//! on screen, the push along it has a small component across one of the
//! edges, and the ring along that edge thins toward the corner (to under
//! a pixel at 1.5 px). So a vertex where exactly two outline edges meet
//! this frame (silhouette edges: one face toward the eye, one away) moves
//! by the **miter** of their outward screen normals n₁, n₂:
//! m = (n₁ + n₂)/(1 + n₁·n₂), which has m·n₁ = m·n₂ = 1, so both pushed
//! edges lie exactly `width` pixels out and the corner is mitred. The
//! miter is used up to `MITER_LIMIT` (corners of 60° and wider); a
//! sharper turn, or a vertex on one or on three and more outline edges,
//! keeps the smoothed normal. Edges are found once per scene between
//! vertices welded by position (to 1e-6 of the scene's extent, as the
//! stroke edges), faces' facing per frame.
//!
//! **Open meshes** (a lone plane, a sheet, anything with boundary edges:
//! edges with one face) have no back faces behind their front ones, so
//! back faces alone give them no ring (seen from the front) or a filled
//! silhouette (a single-sided sheet seen from behind, which the main pass
//! culls). A triangle whose connected piece of mesh has a boundary edge is
//! drawn the other way: its faces as the main pass draws them (front
//! faces; both sides for double-sided materials, `Cull::Back`), pushed out
//! across the boundary and slightly behind. Boundary edges count as
//! outline edges, outward away from their face; a vertex of an open piece
//! moves by the miter of its outline edges (their normalized sum at three
//! and more or past the limit, the one edge's normal at one) and a vertex
//! on no outline edge stays put, so the copy covers the face and a ring
//! `width` wide outside its boundary. A moved vertex keeps its depth on
//! the plane of its edges' faces (z/w is affine in screen space on a
//! plane, so the copy of a flat sheet lies in the sheet however slanted),
//! and every vertex of the copy is pushed back by `OPEN_DEPTH_PUSH` so
//! the sheet itself wins the depth test.
//!
//! A copy that cannot show is not drawn: a flat open piece (a ground
//! plane) whose boundary lies off screen is covered on screen by its own
//! faces, in front of its copy everywhere (conditions and margins at
//! `copy_hidden`); its pass is reported hidden ([`VertexStage::hidden`])
//! and the frame skips it. On the benchmark scene that is the ground's
//! copy, two screen-filling triangles that wrote no pixel.
//!
//! The width is in output pixels; each frame tells the stage its
//! supersampling ([`FrameContext::ssaa`]) so the ring is `width × ssaa`
//! samples wide and `width` pixels after the resolve.

use glam::{Vec3, Vec4};
use rayon::prelude::*;
use specula_raster::camera::View;
use specula_raster::geometry::{Cull, FrameContext, GeometryPass, VertexStage};
use specula_raster::setup::{front_face_shown, front_faces_shown_x8};
use specula_raster::{SceneMesh, SceneParts};
use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;

mod hidden;
mod topology;

use hidden::copy_hidden;
use topology::{Topology, NONE};

/// Longest miter, in widths: |m| = 1/cos(φ/2) for outward normals φ
/// apart, 2 at φ = 120° (a corner of 60° on screen).
pub(crate) const MITER_LIMIT: f32 = 2.0;

/// Relative depth by which the copy of an open piece of mesh lies behind
/// it: z/w × (1 − push), about that fraction of the view distance (far
/// above f32 rounding of the interpolated depth, ~1e-6).
pub(crate) const OPEN_DEPTH_PUSH: f32 = 1e-3;

/// The vertex stage of an extrusion pass.
#[derive(Debug)]
pub struct Extrude {
    /// Ring width in output pixels.
    pub(crate) width: f32,
    /// What the stage derives from the scene's mesh when it is built,
    /// shared by its instances.
    mesh: Arc<ExtrudeMesh>,
    /// The last view's clip positions and what they were made for (an
    /// outline's passes, closed and open runs, share one vertex stage and
    /// one frame, so the later passes copy them), and the per-view work
    /// vectors (~9.5 MB on the benchmark scene), kept from view to view
    /// by the frames' instance of the stage (`VertexStage::instance`).
    state: ViewState,
}

/// See [`Extrude::mesh`].
#[derive(Debug)]
struct ExtrudeMesh {
    /// Smoothed unit normal per scene vertex (module docs).
    smooth: Vec<Vec3>,
    topo: Topology,
    /// Per triangle, (b − a) × (c − a) of its corners: what its facing
    /// needs besides the eye (the same products a per-view computation
    /// would make, so the same facing).
    face_normals: Vec<Vec3>,
}

/// See [`Extrude::state`].
#[derive(Debug, Default)]
struct ViewState {
    key: Option<FrameKey>,
    out: Vec<[f32; 4]>,
    clip: Vec<Vec4>,
    front: Vec<bool>,
    edge_normals: Vec<Option<EdgeNormal>>,
    moves: Vec<Option<Move>>,
    /// Per flat piece (`Topology::flat`): its copy is hidden this view.
    hidden: Vec<bool>,
    /// Per triangle, a bit where `front_face_shown` holds for `out`
    /// ([`VertexStage::front_faces`]).
    front_mask: Arc<Vec<u64>>,
}

/// An outline edge's outward unit screen normal and the screen gradient
/// of z/w on its face (see [`Extrude::moves`]).
type EdgeNormal = ([f32; 2], [f32; 2]);

/// What the clip positions depend on besides the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
struct FrameKey {
    view_proj: [f32; 16],
    eye: [f32; 3],
    size: [f32; 2],
    px: f32,
    vertices: usize,
}

impl Extrude {
    pub fn new(scene: &SceneParts, width: f32) -> Extrude {
        Extrude {
            width,
            mesh: Arc::new(ExtrudeMesh {
                smooth: smooth_normals(&scene.positions, &scene.normals),
                topo: Topology::new(&scene.positions, &scene.triangles),
                face_normals: scene
                    .triangles
                    .par_iter()
                    .with_min_len(4096)
                    .map(|tri| {
                        let [a, b, c] = tri.map(|v| scene.positions[v as usize]);
                        (b - a).cross(c - a)
                    })
                    .collect(),
            }),
            state: ViewState::default(),
        }
    }

    /// Whether triangle `t`'s connected piece of mesh is open (module
    /// docs): its copy is drawn front side out, not back faces.
    pub(crate) fn is_open(&self, t: usize) -> bool {
        self.mesh.topo.tri_open.get(t).copied().unwrap_or(false)
    }
}

impl ExtrudeMesh {
    /// Per welded vertex, where it moves this frame (module docs): the
    /// offset in widths (screen pixels, y up) and the screen gradient of
    /// z/w (per pixel) of its outline edges' faces, for open pieces, into
    /// `st.moves`. `None`: along the smoothed normal (closed pieces) or
    /// nowhere (open). Reads `st.clip`; fills `st.front` and
    /// `st.edge_normals` on the way (vectors reused from the last view).
    fn moves(&self, scene: &SceneMesh, view: &View, st: &mut ViewState) {
        let t = &self.topo;
        let (hw, hh) = (view.width * 0.5, view.height * 0.5);
        let ViewState {
            clip,
            front,
            edge_normals,
            moves,
            ..
        } = st;
        self.face_normals
            .par_iter()
            .zip(scene.triangles)
            .with_min_len(4096)
            .map(|(n, tri)| n.dot(view.eye - scene.positions[tri[0] as usize]) > 0.0)
            .collect_into_vec(front);
        let (clip, front) = (&*clip, &*front);
        // Screen position (pixels from the centre, y up) and z/w, if in
        // front of the eye.
        let screen = |v: u32| {
            let c = clip.get(v as usize)?;
            (c.w > 0.0).then(|| [c.x / c.w * hw, c.y / c.w * hh, c.z / c.w])
        };
        // Per outline edge: outward unit screen normal, and the gradient
        // of z/w on its face (the front one of a silhouette edge).
        t.edges
            .par_iter()
            .with_min_len(4096)
            .map(|e| {
                let [f0, f1] = e.faces;
                let k = match (f0 != NONE, f1 != NONE) {
                    (true, true) if front[f0 as usize] != front[f1 as usize] => {
                        if front[f0 as usize] {
                            0
                        } else {
                            1
                        }
                    }
                    (true, false) => 0, // a boundary edge
                    _ => return None,
                };
                let a = screen(e.ends[0])?;
                let b = screen(e.ends[1])?;
                let o = screen(e.opposite[k])?;
                let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
                let (fx, fy) = (o[0] - a[0], o[1] - a[1]);
                let len = (ex * ex + ey * ey).sqrt();
                let (nx, ny) = (-ey / len, ex / len);
                let side = nx * fx + ny * fy;
                if !(len > 1e-6 && side.is_finite() && side != 0.0) {
                    return None;
                }
                let n = if side > 0.0 { [-nx, -ny] } else { [nx, ny] };
                // z/w = a + gx·x + gy·y through the face's three corners.
                let det = ex * fy - ey * fx;
                let (dzb, dzo) = (b[2] - a[2], o[2] - a[2]);
                let g = [(dzb * fy - dzo * ey) / det, (ex * dzo - fx * dzb) / det];
                Some((
                    n,
                    if g[0].is_finite() && g[1].is_finite() {
                        g
                    } else {
                        [0.0; 2]
                    },
                ))
            })
            .collect_into_vec(edge_normals);
        let normals = &*edge_normals;
        let cos_limit = 2.0 / (MITER_LIMIT * MITER_LIMIT) - 1.0; // 1 + n₁·n₂ ≥ 2/L²
        (0..t.start.len() - 1)
            .into_par_iter()
            .with_min_len(4096)
            .map(|v| {
                let range = t.start[v] as usize..t.start[v + 1] as usize;
                let on = t.vertex_edges[range]
                    .iter()
                    .filter_map(|&e| normals[e as usize]);
                let (mut count, mut sum, mut grad) = (0, [0.0f32; 2], [0.0f32; 2]);
                let mut first = [[0.0f32; 2]; 2];
                for (n, g) in on {
                    if count < 2 {
                        first[count] = n;
                    }
                    count += 1;
                    sum = [sum[0] + n[0], sum[1] + n[1]];
                    grad = [grad[0] + g[0], grad[1] + g[1]];
                }
                let open = t.vertex_open[v];
                let miter = (count == 2).then(|| {
                    let [n1, n2] = first;
                    let dot = n1[0] * n2[0] + n1[1] * n2[1];
                    (dot >= cos_limit).then(|| {
                        let s = 1.0 / (1.0 + dot);
                        [(n1[0] + n2[0]) * s, (n1[1] + n2[1]) * s]
                    })
                });
                let offset = match miter.flatten() {
                    Some(m) => m,
                    None if open && count > 0 => {
                        let len = (sum[0] * sum[0] + sum[1] * sum[1]).sqrt();
                        if len.is_nan() || len <= 1e-6 {
                            return None;
                        }
                        [sum[0] / len, sum[1] / len]
                    }
                    None => return None,
                };
                let c = count as f32;
                Some(Move {
                    offset,
                    z_gradient: if open {
                        [grad[0] / c, grad[1] / c]
                    } else {
                        [0.0; 2]
                    },
                })
            })
            .collect_into_vec(moves);
    }
}

/// Where a welded vertex moves (see [`Extrude::moves`]).
#[derive(Clone, Copy, Debug)]
struct Move {
    offset: [f32; 2],
    z_gradient: [f32; 2],
}

/// Per vertex, the normalized sum of the normals of every vertex at the
/// same position (bit-equal coordinates, −0 = +0); a sum that cancels
/// keeps the vertex's own normal.
pub fn smooth_normals(positions: &[Vec3], normals: &[Vec3]) -> Vec<Vec3> {
    let key = |p: Vec3| p.to_array().map(|c| (c + 0.0).to_bits());
    let mut sums: HashMap<[u32; 3], Vec3> = HashMap::with_capacity(positions.len());
    for (p, n) in positions.iter().zip(normals) {
        *sums.entry(key(*p)).or_insert(Vec3::ZERO) += *n;
    }
    positions
        .iter()
        .zip(normals)
        .map(|(p, n)| sums[&key(*p)].try_normalize().unwrap_or(*n))
        .collect()
}

impl VertexStage for Extrude {
    fn instance(&self) -> Box<dyn VertexStage> {
        Box::new(Extrude {
            width: self.width,
            mesh: self.mesh.clone(),
            state: ViewState::default(),
        })
    }

    fn clip_positions(&mut self, frame: &FrameContext, scene: &SceneMesh, out: &mut Vec<[f32; 4]>) {
        let view = frame.view;
        let m = view.view_proj;
        let px = self.width * frame.ssaa.max(1) as f32;
        let (hw, hh) = (view.width * 0.5, view.height * 0.5);
        let key = FrameKey {
            view_proj: m.to_cols_array(),
            eye: view.eye.to_array(),
            size: [view.width, view.height],
            px,
            vertices: scene.positions.len(),
        };
        let mesh = &*self.mesh;
        let st = &mut self.state;
        if st.key == Some(key) {
            // In parallel: 16 bytes a vertex (1.5 MB on the benchmark) is
            // worth both threads.
            st.out
                .par_iter()
                .with_min_len(4096)
                .copied()
                .collect_into_vec(out);
            return;
        }
        st.key = None; // until the vectors below are complete
        scene
            .positions
            .par_iter()
            .with_min_len(4096)
            .map(|p| m * Vec4::from((*p, 1.0)))
            .collect_into_vec(&mut st.clip);
        mesh.moves(scene, view, st);
        let (clip, moves) = (&st.clip, &st.moves);
        let t = &mesh.topo;
        (0..clip.len())
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| {
                let c = clip[i];
                let w = t.weld.get(i).copied().unwrap_or(NONE);
                let open = w != NONE && t.vertex_open[w as usize];
                if c.w <= 0.0 {
                    return c.to_array();
                }
                let z = if open {
                    c.z * (1.0 - OPEN_DEPTH_PUSH)
                } else {
                    c.z
                };
                // Offset in pixels (y up): the miter (module docs), else
                // along the smoothed normal's screen direction (closed
                // pieces) or none (open ones).
                let mv = if w != NONE { moves[w as usize] } else { None };
                let (ox, oy, dz) = if let Some(m) = mv {
                    let (ox, oy) = (m.offset[0] * px, m.offset[1] * px);
                    (ox, oy, m.z_gradient[0] * ox + m.z_gradient[1] * oy)
                } else if open {
                    return [c.x, c.y, z, c.w];
                } else {
                    let nc = m * Vec4::from((mesh.smooth[i], 0.0));
                    let dx = (nc.x - c.x / c.w * nc.w) * hw;
                    let dy = (nc.y - c.y / c.w * nc.w) * hh;
                    let len = (dx * dx + dy * dy).sqrt();
                    if !(len > 1e-12 && len.is_finite()) {
                        return c.to_array();
                    }
                    (dx / len * px, dy / len * px, 0.0)
                };
                let z = if open {
                    (c.z + dz * c.w) * (1.0 - OPEN_DEPTH_PUSH)
                } else {
                    z
                };
                [c.x + ox / hw * c.w, c.y + oy / hh * c.w, z, c.w]
            })
            .collect_into_vec(&mut st.out);
        let (w, h) = (view.width as f64, view.height as f64);
        st.hidden = (mesh.topo.flat.iter())
            .map(|p| copy_hidden(scene, p, &st.clip, &st.out, w, h))
            .collect();
        // The closed pieces' pass culls front faces: those shown front
        // facing here (most of them) skip setup (`front_faces`).
        // Groups of 8 with no face toward the eye in world space (`moves`'
        // `front`) are not tried: they are back faces after the push too,
        // nearly always, and a bit left clear only means setup decides.
        let (copy, facing) = (&st.out, &st.front);
        scene
            .triangles
            .par_chunks(64)
            .zip(facing.par_chunks(64))
            .with_min_len(64)
            .map(|(tris, facing)| {
                let (eights, rest) = tris.as_chunks::<8>();
                let mut word = 0u64;
                for (k, (t8, f8)) in eights.iter().zip(facing.chunks(8)).enumerate() {
                    if f8.iter().any(|&f| f) {
                        word |= (front_faces_shown_x8(copy, t8) as u64) << (8 * k);
                    }
                }
                for (k, t) in rest.iter().enumerate() {
                    let v = t.map(|v| copy[v as usize]);
                    word |= (front_face_shown(&v) as u64) << (8 * eights.len() + k);
                }
                word
            })
            .collect_into_vec(Arc::make_mut(&mut st.front_mask));
        st.key = Some(key);
        st.out
            .par_iter()
            .with_min_len(4096)
            .copied()
            .collect_into_vec(out);
    }

    fn front_faces(&self) -> Option<Arc<Vec<u64>>> {
        let st = &self.state;
        st.key.is_some().then(|| st.front_mask.clone())
    }

    /// True when every triangle of `triangles` is on a flat open piece
    /// whose copy `copy_hidden` showed hidden for the last view.
    fn hidden(&self, triangles: Range<u32>) -> bool {
        let st = &self.state;
        st.key.is_some()
            && !triangles.is_empty()
            && triangles.into_iter().all(|t| {
                let k = self
                    .mesh
                    .topo
                    .tri_flat
                    .get(t as usize)
                    .copied()
                    .unwrap_or(NONE);
                k != NONE && st.hidden.get(k as usize).copied().unwrap_or(false)
            })
    }
}

/// The geometry passes of one extrusion outline over the triangles whose
/// material `selected` accepts: one pass per run of consecutive selected
/// triangles of closed or of open pieces (a pass draws a range), back
/// faces only for closed pieces (`Cull::Front`), the main pass's sides
/// for open ones (`Cull::Back`; module docs), shaded by `material`, ids
/// from `id_base` (triangle i writes `id_base + i`).
pub fn extrusion_passes(
    scene: &SceneParts,
    stage: Arc<Extrude>,
    material: u32,
    id_base: u32,
    selected: &dyn Fn(u32) -> bool,
) -> Vec<GeometryPass> {
    let mut passes = Vec::new();
    let n = scene.triangles.len() as u32;
    let mut i = 0;
    while i < n {
        if !selected(scene.tri_material[i as usize]) {
            i += 1;
            continue;
        }
        let (start, open) = (i, stage.is_open(i as usize));
        while i < n && selected(scene.tri_material[i as usize]) && stage.is_open(i as usize) == open
        {
            i += 1;
        }
        passes.push(GeometryPass {
            name: "outline-extrusion".into(),
            vertex: stage.clone(),
            cull: if open { Cull::Back } else { Cull::Front },
            triangles: start..i,
            id_base,
            material: Some(material),
        });
    }
    passes
}
