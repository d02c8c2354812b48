//! The closed solids of a scene's mesh, for its shadow maps. A ray from a
//! light outside a closed, outward-facing, opaque solid first meets it
//! where it enters, through a face turned toward the light; so a depth
//! pass seen from outside draws each solid's front faces alone, and the
//! nearest depth at every texel is the one both faces give (rounding
//! aside, along the silhouette). Its back faces are culled in setup, not
//! binned or scanned.
//!
//! A part is a set of triangles joined through shared positions (vertices
//! welded by their exact position, so a seam that splits a vertex's normal
//! or uv does not cut a part). It is a solid when
//! - every edge between two distinct positions is shared by exactly two of
//!   its triangles, once in each direction (closed, consistently wound and
//!   manifold along its edges); triangles with two welded corners alike
//!   have no area and are left out;
//! - its signed volume is positive: counter-clockwise seen from outside,
//!   the winding front faces have;
//! - every material on it is opaque: a masked or blended face may show the
//!   back faces behind it.
//!
//! A point or spot light inside a solid's bounds (or on them) keeps both
//! faces of that solid: it may be inside, where every face it sees is a
//! back face and each of them casts.

use glam::Vec3;
use rayon::prelude::*;

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
    /// The parts of `triangles` over `positions` (finite, indices in
    /// range: [`SceneData::new`](crate::SceneData::new) checks them) and
    /// which are solids, triangle `t` having material `tri_material[t]`,
    /// opaque where `opaque[tri_material[t]]`.
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
        let mut parts = Parts::new(positions.len());
        for &[a, b, c] in &welded {
            parts.join(a, b);
            parts.join(a, c);
        }
        // Parts numbered in the order of their first triangle.
        let mut index = vec![u32::MAX; positions.len()];
        let mut count = 0;
        let part: Vec<u32> = (welded.iter())
            .map(|t| {
                let root = parts.find(t[0]) as usize;
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
        for t in unpaired_edges(&welded, positions.len()) {
            closed[part[t as usize] as usize] = false;
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
    /// back faces a depth pass from `eye` (a point or spot light's
    /// position; `None` for a directional light, outside everything) may
    /// cull: those of the solids whose bounds do not hold `eye`.
    pub fn cull_back_mask(&self, eye: Option<Vec3>, mask: &mut Vec<u64>) {
        let outside =
            |&(lo, hi): &(Vec3, Vec3)| eye.is_none_or(|e| e.cmplt(lo).any() || e.cmpgt(hi).any());
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

/// At least one triangle of each part with an edge that is not shared by
/// exactly two of its triangles running opposite ways (those whose edge's
/// reverse is missing or repeated), given the triangles' `welded` corners
/// (indices below `vertices`). Triangles with two corners alike have no
/// area and no edges.
fn unpaired_edges(welded: &[[u32; 3]], vertices: usize) -> Vec<u32> {
    let has_area = |&[a, b, c]: &[u32; 3]| a != b && b != c && a != c;
    // Each vertex's outgoing edges (their ends), in one array: a triangle
    // (a, b, c) leaves a toward b, b toward c and c toward a.
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
    let mut to = vec![0u32; start[vertices] as usize];
    for &[a, b, c] in welded.iter().filter(|t| has_area(t)) {
        for (from, end) in [(a, b), (b, c), (c, a)] {
            to[fill[from as usize] as usize] = end;
            fill[from as usize] += 1;
        }
    }
    // An edge a → b pairs when b → a is there exactly once. Checking that
    // for every edge also catches a doubled a → b (at its reverse's
    // check), whose triangles are in the same part.
    let reversed_once = |&[a, b, c]: &[u32; 3]| {
        let once = |from: u32, end: u32| {
            let out = &to[start[from as usize] as usize..start[from as usize + 1] as usize];
            out.iter().filter(|&&e| e == end).count() == 1
        };
        once(b, a) && once(c, b) && once(a, c)
    };
    (welded.par_iter().enumerate())
        .filter(|(_, t)| has_area(t) && !reversed_once(t))
        .map(|(k, _)| k as u32)
        .collect()
}

/// Disjoint sets of welded vertices (union by size, paths halved).
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
        assert_eq!(solids_of(&p, &doubled).counts(), (1, 0));
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
    fn a_light_within_a_solids_bounds_keeps_its_back_faces() {
        let (mut p, mut t) = (Vec::new(), Vec::new());
        cube(Vec3::ZERO, &ALL, &mut p, &mut t);
        let s = solids_of(&p, &t);
        let mut mask = Vec::new();
        for (eye, culled) in [
            (Vec3::ZERO, false),
            (Vec3::splat(0.5), false),
            (Vec3::new(0.0, 0.0, 0.6), true),
            (Vec3::new(-2.0, 0.1, 0.1), true),
        ] {
            s.cull_back_mask(Some(eye), &mut mask);
            let expect = if culled { (1 << 12) - 1 } else { 0 };
            assert_eq!(mask, vec![expect], "light at {eye}");
        }
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
