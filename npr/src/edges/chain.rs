//! Joining visible edge pieces into polylines (see the parent module).

use super::{EdgeKind, Piece, Polyline};

/// Chains pieces into polylines (module docs), kinds in [`EdgeKind`]
/// order; deterministic for a given piece order.
pub fn chain(pieces: &[Piece]) -> Vec<Polyline> {
    let mut out = Vec::new();
    for kind in EdgeKind::ALL {
        let ps: Vec<&Piece> = pieces.iter().filter(|p| p.kind == kind).collect();
        let point = |i: usize, end: usize| if end == 0 { ps[i].a } else { ps[i].b };
        // The piece ends at vertices, (vertex, piece, end) sorted (packed
        // in a u64, vertex high: a piece index is below 2³¹): the ends at a
        // vertex are a run, in piece order.
        let mut ends: Vec<u64> = ps
            .iter()
            .enumerate()
            .flat_map(|(i, p)| {
                (0..2).filter_map(move |end| {
                    p.ends[end].map(|v| (v as u64) << 32 | (i as u64) << 1 | end as u64)
                })
            })
            .collect();
        sort_by_vertex(&mut ends);
        let unpack = |k: u64| ((k >> 32) as u32, (k as u32 >> 1) as usize, (k & 1) as usize);
        // Each vertex once, ascending, with its run of ends; and the run of
        // each piece end at a vertex (piece i's end e at 2i + e).
        let mut runs: Vec<(u32, std::ops::Range<usize>)> = Vec::new();
        let mut run_of = vec![u32::MAX; 2 * ps.len()];
        for (k, &key) in ends.iter().enumerate() {
            let (v, i, e) = unpack(key);
            match runs.last_mut() {
                Some((u, r)) if *u == v => r.end = k + 1,
                _ => runs.push((v, k..k + 1)),
            }
            run_of[2 * i + e] = runs.len() as u32 - 1;
        }
        // The ends at the vertex of piece i's end e (which has one).
        let at = |i: usize, e: usize| {
            ends[runs[run_of[2 * i + e] as usize].1.clone()]
                .iter()
                .map(move |&k| (unpack(k).1, unpack(k).2))
        };
        let mut used = vec![false; ps.len()];
        // Walks from end `end` of piece `first` through the pieces after it.
        let walk = |first: usize, end: usize, used: &mut [bool]| {
            let start = ps[first].ends[end];
            let mut points = vec![point(first, end)];
            let (mut piece, mut from) = (first, end);
            let mut closed = false;
            loop {
                used[piece] = true;
                let to = 1 - from;
                points.push(point(piece, to));
                let Some(v) = ps[piece].ends[to] else { break };
                if Some(v) == start && points.len() > 2 {
                    closed = true;
                    break;
                }
                // Go on along the unused piece that turns least on screen.
                let (p, q) = (point(piece, from), point(piece, to));
                let dir = norm2([q[0] - p[0], q[1] - p[1]]);
                let next = at(piece, to)
                    .filter(|(i, _)| !used[*i])
                    .map(|(i, e)| {
                        let r = point(i, 1 - e);
                        let d = norm2([r[0] - q[0], r[1] - q[1]]);
                        (d[0] * dir[0] + d[1] * dir[1], i, e)
                    })
                    .max_by(|x, y| x.0.total_cmp(&y.0).then(y.1.cmp(&x.1)));
                match next {
                    Some((_, i, e)) => (piece, from) = (i, e),
                    None => break,
                }
            }
            if closed {
                points.pop();
            }
            Polyline {
                kind,
                points,
                closed,
            }
        };
        // Open chains first: from piece ends short of a vertex, then from
        // vertices with an odd number of piece ends; then loops.
        for i in 0..ps.len() {
            if used[i] {
                continue;
            }
            if let Some(end) = ps[i].ends.iter().position(|v| v.is_none()) {
                out.push(walk(i, end, &mut used));
            }
        }
        let odd = runs.iter().filter(|(_, r)| r.len() % 2 == 1);
        let starts: Vec<std::ops::Range<usize>> =
            odd.chain(runs.iter()).map(|(_, r)| r.clone()).collect();
        for r in starts {
            while let Some(&k) = ends[r.clone()].iter().find(|&&k| !used[unpack(k).1]) {
                let (_, i, e) = unpack(k);
                out.push(walk(i, e, &mut used));
            }
        }
    }
    out
}

/// Sorts piece-end keys (vertex in the high 32 bits, ascending in their
/// low bits as [`chain`] makes them) ascending: a stable least-significant
/// digit radix sort on the vertex, 11 bits a pass and only as many passes
/// as the largest vertex needs (two for 4 million vertices). The low bits
/// being ascending already, stable passes on the vertex alone give the
/// order of a sort on the whole key, in a few counting passes instead of
/// a comparison sort's n·log n.
fn sort_by_vertex(keys: &mut Vec<u64>) {
    const BITS: u32 = 11;
    let top = keys.iter().map(|k| k >> 32).max().unwrap_or(0);
    let passes = (u64::BITS - top.leading_zeros()).div_ceil(BITS);
    let mut out = vec![0u64; keys.len()];
    for pass in 0..passes {
        let digit = |k: u64| ((k >> (32 + pass * BITS)) & ((1 << BITS) - 1)) as usize;
        let mut at = [0usize; 1 << BITS];
        for &k in keys.iter() {
            at[digit(k)] += 1;
        }
        let mut sum = 0;
        for a in at.iter_mut() {
            (*a, sum) = (sum, sum + *a);
        }
        for &k in keys.iter() {
            out[at[digit(k)]] = k;
            at[digit(k)] += 1;
        }
        std::mem::swap(keys, &mut out);
    }
}

fn norm2(v: [f32; 2]) -> [f32; 2] {
    let l = (v[0] * v[0] + v[1] * v[1]).sqrt();
    if l > 0.0 {
        [v[0] / l, v[1] / l]
    } else {
        [0.0; 2]
    }
}

#[cfg(test)]
mod tests {
    use super::super::rng;
    use super::*;

    #[test]
    fn piece_ends_sorted_by_vertex_are_sorted_whole() {
        // Keys as `chain` makes them (low bits ascending), vertices from a
        // few to millions apart (one to three radix passes), against the
        // comparison sort of the whole key.
        let mut next = rng(5);
        for (case, top) in [1u64, 7, 2047, 2048, 100_000, 5_000_000, u32::MAX as u64]
            .into_iter()
            .enumerate()
        {
            let mut keys = Vec::new();
            for i in 0..3000u64 {
                if next() < 0.8 {
                    let v = ((next() as f64 * top as f64) as u64).min(top);
                    keys.push(v << 32 | i);
                }
            }
            let mut want = keys.clone();
            want.sort_unstable();
            let mut got = keys;
            sort_by_vertex(&mut got);
            assert_eq!(got, want, "case {case}");
        }
        let mut empty = Vec::new();
        sort_by_vertex(&mut empty);
        assert!(empty.is_empty());
    }
}
