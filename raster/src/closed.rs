//! The closed solids of a scene's mesh, for its shadow maps. A ray from a
//! light outside a closed, outward-facing, opaque solid first meets it
//! where it enters, through a face turned toward the light; so a depth
//! pass seen from outside draws each solid's front faces alone, and the
//! nearest depth at every texel is the one both faces give (rounding
//! aside, along the silhouette). Its back faces are culled in setup, not
//! binned or scanned.
//!
//! A part is a set of triangles joined across shared edges (vertices
//! welded by their exact position, so a seam that splits a vertex's normal
//! or uv does not cut a part; two triangles join across an edge they run
//! opposite ways, when no other triangle runs it the second way). It is a
//! solid when
//! - every edge between two distinct positions is shared by exactly two of
//!   its triangles, once in each direction (closed, consistently wound and
//!   manifold along its edges); triangles with two welded corners alike
//!   have no area and are left out;
//! - its signed volume is positive: counter-clockwise seen from outside,
//!   the winding front faces have;
//! - every material on it is opaque: a masked or blended face may show the
//!   back faces behind it.
//!
//! A point or spot light inside a solid's bounds, or nearer to them than
//! the corners of its map's near plane, keeps both faces of that solid: it
//! may be inside, where every face it sees is a back face and each of them
//! casts, or its near plane may cut the front faces away.

use crate::geometry::{mask_bits4, Cull};
use glam::Vec3;
use rayon::prelude::*;

/// How a depth pass culls triangle `t` given its [`ClosedSolids::cull_back_mask`]:
/// back faces where the triangle's bit is set, nothing elsewhere.
#[inline(always)]
pub(crate) fn depth_cull(mask: &[u64], t: usize) -> Cull {
    match mask_bits4(mask, t) & 1 {
        0 => Cull::None,
        _ => Cull::Back,
    }
}

/// Each triangle's part, and the bounds of the parts that are solids.
#[derive(Clone, Debug, Default)]
pub struct ClosedSolids {
    /// Per triangle, the index of its part.
    part: Vec<u32>,
    /// Per part, the bounds (min, max) of a solid; `None` for a part that
    /// is not one.
    solid: Vec<Option<(Vec3, Vec3)>>,
}

impl ClosedSolids {
    /// The parts of `triangles` over `positions` (indices in range:
    /// [`SceneData::new`](crate::SceneData::new) checks them; a part with
    /// a non-finite position has a NaN volume and is no solid) and which
    /// are solids, triangle `t` having material `tri_material[t]`, opaque
    /// where `opaque[tri_material[t]]`.
    pub fn of(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        tri_material: &[u32],
        opaque: &[bool],
    ) -> ClosedSolids {
        let weld = weld(positions);
        let welded: Vec<[u32; 3]> = (triangles.par_iter())
            .map(|t| t.map(|i| weld[i as usize]))
            .collect();
        let edges = OutEdges::of(&welded, positions.len());
        // Triangles joined across their paired edges; those with an edge
        // whose reverse is missing or repeated noted (a doubled edge is
        // caught at its reverse, whose part holds both).
        let mut parts = Parts::new(triangles.len());
        let mut unpaired = Vec::new();
        for (t, &[a, b, c]) in welded.iter().enumerate() {
            if !has_area(&[a, b, c]) {
                continue;
            }
            for (from, to) in [(a, b), (b, c), (c, a)] {
                match edges.between(to, from) {
                    &[(_, u)] => parts.join(t as u32, u),
                    _ => unpaired.push(t),
                }
            }
        }
        // Parts numbered in the order of their first triangle.
        let mut index = vec![u32::MAX; triangles.len()];
        let mut count = 0;
        let part: Vec<u32> = (0..triangles.len() as u32)
            .map(|t| {
                let root = parts.find(t) as usize;
                if index[root] == u32::MAX {
                    index[root] = count;
                    count += 1;
                }
                index[root]
            })
            .collect();
        let count = count as usize;

        // Closed until shown otherwise.
        let mut closed = vec![true; count];
        for (t, m) in tri_material.iter().enumerate() {
            if !opaque[*m as usize] {
                closed[part[t] as usize] = false;
            }
        }
        for t in unpaired {
            closed[part[t] as usize] = false;
        }

        // Bounds, and signed volumes about a point of each part (any point
        // gives a closed surface's volume).
        let mut origin = vec![None; count];
        let mut bounds = vec![(Vec3::INFINITY, Vec3::NEG_INFINITY); count];
        let mut volume = vec![0.0f64; count];
        for (t, &p) in triangles.iter().zip(&part) {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let (lo, hi) = &mut bounds[p as usize];
            (*lo, *hi) = (lo.min(a.min(b).min(c)), hi.max(a.max(b).max(c)));
            let o = *origin[p as usize].get_or_insert(a.as_dvec3());
            let [a, b, c] = [a, b, c].map(|v| v.as_dvec3() - o);
            volume[p as usize] += a.dot(b.cross(c));
        }
        let solid = (0..count)
            .map(|p| (closed[p] && volume[p] > 0.0).then_some(bounds[p]))
            .collect();
        ClosedSolids { part, solid }
    }

    /// Whether any part is a solid.
    pub fn any(&self) -> bool {
        self.solid.iter().any(Option::is_some)
    }

    /// How many parts there are, and how many of them are solids.
    pub fn counts(&self) -> (usize, usize) {
        let solids = self.solid.iter().filter(|s| s.is_some()).count();
        (self.solid.len(), solids)
    }

    /// Into `mask` (a bit per triangle, 64 a word): the triangles whose
    /// back faces a depth pass from `eye` may cull: those of the solids
    /// whose bounds, grown by `reach`, do not hold `eye`. For a point or
    /// spot light `eye` is its position and `reach` the distance from it
    /// to its map's near plane's corners; `None` for a directional light,
    /// outside everything.
    pub fn cull_back_mask(&self, eye: Option<(Vec3, f32)>, mask: &mut Vec<u64>) {
        let outside = |&(lo, hi): &(Vec3, Vec3)| {
            eye.is_none_or(|(e, reach)| {
                let r = Vec3::splat(reach);
                e.cmplt(lo - r).any() || e.cmpgt(hi + r).any()
            })
        };
        let cull: Vec<bool> = (self.solid.iter())
            .map(|s| s.as_ref().is_some_and(outside))
            .collect();
        mask.clear();
        mask.resize(self.part.len().div_ceil(64), 0);
        mask.par_iter_mut()
            .zip(self.part.par_chunks(64))
            .for_each(|(word, parts)| {
                *word = (parts.iter().enumerate())
                    .fold(0, |w, (i, &p)| w | (cull[p as usize] as u64) << i);
            });
    }
}

/// Per vertex, the index of the first vertex at exactly its position
/// (−0 and +0 alike).
fn weld(positions: &[Vec3]) -> Vec<u32> {
    // Sorted by position bits (x, y, z), then index: one integer key each.
    let mut order: Vec<u128> = (positions.iter().enumerate())
        .map(|(i, p)| {
            let p = *p + Vec3::ZERO;
            let bits = |v: f32| v.to_bits() as u128;
            bits(p.x) << 96 | bits(p.y) << 64 | bits(p.z) << 32 | i as u128
        })
        .collect();
    order.par_sort_unstable();
    let mut weld = vec![0u32; positions.len()];
    let mut first = 0u32;
    for (k, &key) in order.iter().enumerate() {
        let i = key as u32;
        if k == 0 || key >> 32 != order[k - 1] >> 32 {
            first = i;
        }
        weld[i as usize] = first;
    }
    weld
}

/// Whether a triangle of welded corners has area (three distinct
/// corners); one without has no edges.
fn has_area(&[a, b, c]: &[u32; 3]) -> bool {
    a != b && b != c && a != c
}

/// The directed edges of the triangles with area, by the corner they
/// leave: a triangle (a, b, c) leaves a toward b, b toward c and c toward
/// a. Each corner's edges are sorted by the corner they reach.
struct OutEdges {
    /// Corner v's edges are `edges[start[v]..start[v + 1]]`.
    start: Vec<u32>,
    /// (the corner reached, the triangle).
    edges: Vec<(u32, u32)>,
}

impl OutEdges {
    fn of(welded: &[[u32; 3]], vertices: usize) -> OutEdges {
        let mut start = vec![0u32; vertices + 1];
        for t in welded.iter().filter(|t| has_area(t)) {
            for &from in t {
                start[from as usize + 1] += 1;
            }
        }
        for v in 0..vertices {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut edges = vec![(0u32, 0u32); start[vertices] as usize];
        for (t, &[a, b, c]) in welded.iter().enumerate() {
            if !has_area(&[a, b, c]) {
                continue;
            }
            for (from, to) in [(a, b), (b, c), (c, a)] {
                edges[fill[from as usize] as usize] = (to, t as u32);
                fill[from as usize] += 1;
            }
        }
        for v in 0..vertices {
            edges[start[v] as usize..start[v + 1] as usize].sort_unstable();
        }
        OutEdges { start, edges }
    }

    /// The edges from `from` to `to`.
    fn between(&self, from: u32, to: u32) -> &[(u32, u32)] {
        let out =
            &self.edges[self.start[from as usize] as usize..self.start[from as usize + 1] as usize];
        let first = out.partition_point(|e| e.0 < to);
        let end = first + out[first..].partition_point(|e| e.0 == to);
        &out[first..end]
    }
}

/// Disjoint sets of triangles (union by size, paths halved).
struct Parts {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl Parts {
    fn new(n: usize) -> Parts {
        Parts {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }

    fn find(&mut self, mut v: u32) -> u32 {
        while self.parent[v as usize] != v {
            let up = self.parent[self.parent[v as usize] as usize];
            self.parent[v as usize] = up;
            v = up;
        }
        v
    }

    fn join(&mut self, a: u32, b: u32) {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return;
        }
        if self.size[a as usize] < self.size[b as usize] {
            std::mem::swap(&mut a, &mut b);
        }
        self.parent[b as usize] = a;
        self.size[a as usize] += self.size[b as usize];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube at `at` as 6 faces of 4 vertices each (split corners, as
    /// a mesh with per-face normals has them), wound counter-clockwise seen
    /// from outside; `faces` picks which faces are kept.
    fn cube(at: Vec3, faces: &[usize], positions: &mut Vec<Vec3>, tris: &mut Vec<[u32; 3]>) {
        // Each face: its outward axis and two in-face axes with u × v = n.
        let frames = [
            (Vec3::X, Vec3::Y, Vec3::Z),
            (Vec3::NEG_X, Vec3::Z, Vec3::Y),
            (Vec3::Y, Vec3::Z, Vec3::X),
            (Vec3::NEG_Y, Vec3::X, Vec3::Z),
            (Vec3::Z, Vec3::X, Vec3::Y),
            (Vec3::NEG_Z, Vec3::Y, Vec3::X),
        ];
        for &f in faces {
            let (n, u, v) = frames[f];
            assert_eq!(u.cross(v), n);
            let base = positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                positions.push(at + 0.5 * (n + a * u + b * v));
            }
            tris.push([base, base + 1, base + 2]);
            tris.push([base, base + 2, base + 3]);
        }
    }

    /// The solids of one opaque material's triangles.
    fn solids_of(positions: &[Vec3], tris: &[[u32; 3]]) -> ClosedSolids {
        ClosedSolids::of(positions, tris, &vec![0; tris.len()], &[true])
    }

    const ALL: [usize; 6] = [0, 1, 2, 3, 4, 5];

    #[test]
    fn a_cube_with_split_corners_is_a_solid_and_an_open_box_is_not() {
        let (mut p, mut t) = (Vec::new(), Vec::new());
        cube(Vec3::ZERO, &ALL, &mut p, &mut t);
        cube(Vec3::new(3.0, 0.0, 0.0), &ALL[..5], &mut p, &mut t);
        let s = solids_of(&p, &t);
        assert_eq!(s.counts(), (2, 1));
        let mut mask = Vec::new();
        s.cull_back_mask(None, &mut mask);
        assert_eq!(mask, vec![(1 << 12) - 1], "the closed cube's 12 triangles");
    }

    #[test]
    fn an_inside_out_cube_is_not_a_solid() {
        let (mut p, mut t) = (Vec::new(), Vec::new());
        cube(Vec3::ZERO, &ALL, &mut p, &mut t);
        t.iter_mut().for_each(|t| t.swap(1, 2));
        assert_eq!(solids_of(&p, &t).counts(), (1, 0));
    }

    #[test]
    fn a_third_face_on_an_edge_or_a_doubled_face_opens_the_part() {
        let (mut p, mut t) = (Vec::new(), Vec::new());
        cube(Vec3::ZERO, &ALL, &mut p, &mut t);
        // A fin on the cube's edge (0.5, ±0.5, 0.5), out along +x.
        let fin = p.len() as u32;
        p.extend([
            Vec3::new(0.5, -0.5, 0.5),
            Vec3::new(0.5, 0.5, 0.5),
            Vec3::new(1.5, 0.0, 0.5),
        ]);
        let mut finned = t.clone();
        finned.push([fin, fin + 1, fin + 2]);
        assert_eq!(solids_of(&p, &finned).counts(), (1, 0));
        let mut doubled = t.clone();
        doubled.push(t[0]);
        doubled.push([t[0][0], t[0][2], t[0][1]]);
        // Its edges run twice each way: the copies join nothing, and the
        // cube around them is open there.
        assert_eq!(solids_of(&p, &doubled).counts().1, 0);
    }

    #[test]
    fn a_face_not_opaque_keeps_both_faces() {
        let (mut p, mut t) = (Vec::new(), Vec::new());
        cube(Vec3::ZERO, &ALL, &mut p, &mut t);
        let mut tri_material = vec![0; t.len()];
        tri_material[5] = 1;
        let s = ClosedSolids::of(&p, &t, &tri_material, &[true, false]);
        assert_eq!(s.counts(), (1, 0));
    }

    #[test]
    fn a_light_within_a_solids_bounds_or_their_reach_keeps_its_back_faces() {
        let (mut p, mut t) = (Vec::new(), Vec::new());
        cube(Vec3::ZERO, &ALL, &mut p, &mut t);
        let s = solids_of(&p, &t);
        let mut mask = Vec::new();
        for (eye, reach, culled) in [
            (Vec3::ZERO, 0.0, false),
            (Vec3::splat(0.5), 0.0, false),
            (Vec3::new(0.0, 0.0, 0.6), 0.0, true),
            (Vec3::new(0.0, 0.0, 0.6), 0.2, false),
            (Vec3::new(-2.0, 0.1, 0.1), 1.0, true),
        ] {
            s.cull_back_mask(Some((eye, reach)), &mut mask);
            let expect = if culled { (1 << 12) - 1 } else { 0 };
            assert_eq!(mask, vec![expect], "light at {eye}, reach {reach}");
        }
    }

    #[test]
    fn parts_touching_at_a_corner_are_apart() {
        // An outward cube and, sharing its corner (0.5, 0.5, 0.5), a
        // smaller inside-out one: only the first is a solid.
        let (mut p, mut t) = (Vec::new(), Vec::new());
        cube(Vec3::ZERO, &ALL, &mut p, &mut t);
        let first = t.len();
        let (mut q, mut u) = (Vec::new(), Vec::new());
        cube(Vec3::splat(1.0), &ALL, &mut q, &mut u);
        let base = p.len() as u32;
        p.extend(q);
        t.extend(u.iter().map(|t| [base + t[0], base + t[2], base + t[1]]));
        let s = solids_of(&p, &t);
        assert_eq!(s.counts(), (2, 1));
        let mut mask = Vec::new();
        s.cull_back_mask(None, &mut mask);
        assert_eq!(mask, vec![(1 << first) - 1]);
    }

    #[test]
    fn the_mask_has_a_bit_per_triangle_across_words() {
        let (mut p, mut t) = (Vec::new(), Vec::new());
        // 6 cubes of 12 triangles: 72 triangles over two words, every
        // other cube open.
        for k in 0..6 {
            let faces = if k % 2 == 0 { &ALL[..] } else { &ALL[1..] };
            cube(Vec3::new(3.0 * k as f32, 0.0, 0.0), faces, &mut p, &mut t);
        }
        let s = solids_of(&p, &t);
        let mut mask = Vec::new();
        s.cull_back_mask(None, &mut mask);
        let mut at = 0;
        for k in 0..6 {
            let n = if k % 2 == 0 { 12 } else { 10 };
            for i in at..at + n {
                assert_eq!(
                    mask[i / 64] >> (i % 64) & 1,
                    (k % 2 == 0) as u64,
                    "triangle {i}"
                );
            }
            at += n;
        }
        assert_eq!(mask.len(), 2);
    }
}
