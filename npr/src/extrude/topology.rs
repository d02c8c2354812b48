//! The scene mesh as the extrusion outline sees it: vertices welded by
//! position, edges with their faces, connected pieces open or closed, and
//! the flat open pieces whose copy may be hidden (see the parent module).

use glam::Vec3;
use std::collections::HashMap;

/// Welded vertices and edges of the scene's triangles (module docs).
#[derive(Debug, Default)]
pub(super) struct Topology {
    /// Welded index of each scene vertex.
    pub(super) weld: Vec<u32>,
    /// Per edge: welded ends, its faces (u32::MAX: none), and per face the
    /// scene vertex opposite the edge.
    pub(super) edges: Vec<TopoEdge>,
    /// Edges at each welded vertex: `vertex_edges[start[v]..start[v + 1]]`.
    pub(super) start: Vec<u32>,
    pub(super) vertex_edges: Vec<u32>,
    /// Per triangle: its connected piece has a boundary edge (open).
    pub(super) tri_open: Vec<bool>,
    /// Per welded vertex: on an open piece.
    pub(super) vertex_open: Vec<bool>,
    /// Open pieces flat on a plane of constant x, y or z (see
    /// [`FlatPiece`]), and per triangle the index of its piece among
    /// them (`NONE`: not on one).
    pub(super) flat: Vec<FlatPiece>,
    pub(super) tri_flat: Vec<u32>,
}

/// An open piece of mesh whose vertices all have the same x, y or z (a
/// ground plane, a wall): the one kind whose copy [`Extrude::hidden`]
/// may show hidden. Every edge of its triangles has one or two of them.
#[derive(Debug, Default)]
pub(super) struct FlatPiece {
    pub(super) tris: Vec<u32>,
    /// Scene vertices of its triangles, each once.
    pub(super) vertices: Vec<u32>,
    /// Scene vertices at the ends of its boundary edges.
    pub(super) boundary: Vec<[u32; 2]>,
}

#[derive(Clone, Copy, Debug)]
pub(super) struct TopoEdge {
    pub(super) a: u32,
    pub(super) b: u32,
    pub(super) faces: [u32; 2],
    pub(super) opposite: [u32; 2],
    /// A scene vertex of welded ends a and b: the corners of the edge's
    /// first face.
    pub(super) ends: [u32; 2],
}

/// No face, vertex or piece.
pub(super) const NONE: u32 = u32::MAX;

impl Topology {
    pub(super) fn new(positions: &[Vec3], triangles: &[[u32; 3]]) -> Topology {
        // Welded on a grid of 1e-6 of the extent, as the stroke edges
        // (edges/): a mesh from elsewhere may repeat a seam's positions
        // with different last bits (sin 2π ≠ 0 in f32), which must not
        // make it open.
        let extent = positions
            .iter()
            .filter(|p| p.is_finite())
            .fold(0.0f32, |m, p| m.max(p.abs().max_element()));
        let q = (extent * 1e-6).max(f32::MIN_POSITIVE);
        let key = |p: Vec3| (p / q).round().to_array().map(|c| c as i64);
        let mut ids: HashMap<[i64; 3], u32> = HashMap::with_capacity(positions.len());
        let weld: Vec<u32> = positions
            .iter()
            .map(|p| {
                let n = ids.len() as u32;
                *ids.entry(key(*p)).or_insert(n)
            })
            .collect();
        let mut map: HashMap<(u32, u32), u32> = HashMap::with_capacity(triangles.len() * 2);
        let mut edges: Vec<TopoEdge> = Vec::new();
        for (f, t) in triangles.iter().enumerate() {
            let w = t.map(|v| weld.get(v as usize).copied().unwrap_or(NONE));
            if w.contains(&NONE) || w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
                continue;
            }
            for k in 0..3 {
                let (u, v) = (w[k], w[(k + 1) % 3]);
                let opp = t[(k + 2) % 3];
                let e = *map.entry((u.min(v), u.max(v))).or_insert_with(|| {
                    let (k1, k2) = (k, (k + 1) % 3);
                    let ends = if u < v {
                        [t[k1], t[k2]]
                    } else {
                        [t[k2], t[k1]]
                    };
                    edges.push(TopoEdge {
                        a: u.min(v),
                        b: u.max(v),
                        faces: [NONE; 2],
                        opposite: [NONE; 2],
                        ends,
                    });
                    edges.len() as u32 - 1
                });
                let e = &mut edges[e as usize];
                if e.faces[0] == NONE {
                    e.faces[0] = f as u32;
                    e.opposite[0] = opp;
                } else if e.faces[1] == NONE {
                    e.faces[1] = f as u32;
                    e.opposite[1] = opp;
                } else {
                    // A third face: non-manifold; not an outline edge.
                    e.faces = [NONE, f as u32];
                }
            }
        }
        let mut count = vec![0u32; ids.len() + 1];
        for e in &edges {
            count[e.a as usize + 1] += 1;
            count[e.b as usize + 1] += 1;
        }
        for i in 1..count.len() {
            count[i] += count[i - 1];
        }
        let mut fill = count.clone();
        let mut vertex_edges = vec![0u32; *count.last().unwrap_or(&0) as usize];
        for (i, e) in edges.iter().enumerate() {
            for v in [e.a, e.b] {
                vertex_edges[fill[v as usize] as usize] = i as u32;
                fill[v as usize] += 1;
            }
        }
        // Connected pieces (triangles sharing an edge), union-find; a
        // piece with a boundary or non-manifold edge is open.
        let mut parent: Vec<u32> = (0..triangles.len() as u32).collect();
        fn root(parent: &mut [u32], mut i: u32) -> u32 {
            while parent[i as usize] != i {
                parent[i as usize] = parent[parent[i as usize] as usize];
                i = parent[i as usize];
            }
            i
        }
        for e in &edges {
            let [f0, f1] = e.faces;
            if f0 != NONE && f1 != NONE {
                let (a, b) = (root(&mut parent, f0), root(&mut parent, f1));
                parent[a.max(b) as usize] = a.min(b);
            }
        }
        let mut piece_open = vec![false; triangles.len()];
        for e in &edges {
            if let Some(&f) = e.faces.iter().find(|&&f| f != NONE) {
                if e.faces.contains(&NONE) {
                    let r = root(&mut parent, f);
                    piece_open[r as usize] = true;
                }
            }
        }
        let tri_open: Vec<bool> = (0..triangles.len() as u32)
            .map(|f| piece_open[root(&mut parent, f) as usize])
            .collect();
        let mut vertex_open = vec![false; ids.len()];
        for (t, open) in triangles.iter().zip(&tri_open) {
            if *open {
                for v in t {
                    if let Some(&w) = weld.get(*v as usize) {
                        vertex_open[w as usize] = true;
                    }
                }
            }
        }
        let (flat, tri_flat) = flat_pieces(positions, triangles, &edges, &tri_open, |f| {
            root(&mut parent, f)
        });
        Topology {
            weld,
            edges,
            start: count,
            vertex_edges,
            tri_open,
            vertex_open,
            flat,
            tri_flat,
        }
    }
}

/// The open pieces of [`FlatPiece`]'s kind, and per triangle its index
/// among them. A piece qualifies if its triangles' vertices share one
/// coordinate exactly and each of its triangles has its three edges in
/// `edges`, every edge naming only triangles of the piece (so no edge of
/// three faces, whose record names just the third, and no triangle
/// collapsed by the weld).
fn flat_pieces(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    edges: &[TopoEdge],
    tri_open: &[bool],
    mut root: impl FnMut(u32) -> u32,
) -> (Vec<FlatPiece>, Vec<u32>) {
    let mut index: HashMap<u32, u32> = HashMap::new();
    let mut pieces: Vec<FlatPiece> = Vec::new();
    let mut tri_flat = vec![NONE; triangles.len()];
    for (f, open) in tri_open.iter().enumerate() {
        if *open {
            let r = root(f as u32);
            let k = *index.entry(r).or_insert_with(|| {
                pieces.push(FlatPiece::default());
                pieces.len() as u32 - 1
            });
            pieces[k as usize].tris.push(f as u32);
            tri_flat[f] = k;
        }
    }
    // Edge records per piece: 3 per triangle counted once per face named.
    let mut named = vec![0usize; pieces.len()];
    let mut ok = vec![true; pieces.len()];
    for e in edges {
        let piece = |f: u32| (f != NONE).then(|| tri_flat[f as usize]);
        match (piece(e.faces[0]), piece(e.faces[1])) {
            (Some(a), None) if a != NONE && e.faces[1] == NONE => {
                named[a as usize] += 1;
                pieces[a as usize].boundary.push(e.ends);
            }
            (Some(a), Some(b)) if a == b && a != NONE => named[a as usize] += 2,
            (a, b) => {
                for k in [a, b].into_iter().flatten().filter(|&k| k != NONE) {
                    ok[k as usize] = false;
                }
            }
        }
    }
    for (k, p) in pieces.iter_mut().enumerate() {
        let mut vertices: Vec<u32> = p.tris.iter().flat_map(|&f| triangles[f as usize]).collect();
        vertices.sort_unstable();
        vertices.dedup();
        let same = |c: usize| {
            let at = |v: &u32| positions.get(*v as usize).map(|p| p.to_array()[c]);
            let first = vertices.first().and_then(at);
            vertices.iter().all(|v| at(v) == first && first.is_some())
        };
        ok[k] &= named[k] == 3 * p.tris.len() && (0..3).any(same);
        p.vertices = vertices;
    }
    let keep: Vec<u32> = (0..pieces.len() as u32)
        .scan(0, |next, k| {
            Some(if ok[k as usize] {
                *next += 1;
                *next - 1
            } else {
                NONE
            })
        })
        .collect();
    for t in tri_flat.iter_mut().filter(|t| **t != NONE) {
        *t = keep[*t as usize];
    }
    let pieces = pieces
        .into_iter()
        .zip(&ok)
        .filter_map(|(p, &ok)| ok.then_some(p))
        .collect();
    (pieces, tri_flat)
}
