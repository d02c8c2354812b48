//! The per-sample values the detection reads ([`EdgeInput`]): 1/w of the
//! depth, the material label of each id and the luminance of the colour,
//! for the whole frame (the tests' reference) or a band's rows of it.

use rayon::prelude::*;
use specula_core::Real;
use specula_raster::target::MISS;
use specula_raster::Planes3;
use wide::{f32x8, i32x8, u32x8};

/// Read-only views of the buffers a detection reads, at frame size (or a
/// band's rows of them: the detection only reads the rows it is given).
pub(crate) struct EdgeInput<'a> {
    pub(crate) width: usize,
    /// Read by the scalar reference the tests use.
    #[cfg_attr(not(test), allow(dead_code))]
    pub(crate) height: usize,
    /// 1/w of the view depth w, 0 where nothing is hit (`inverse_depth`;
    /// empty if depth is not a source).
    pub(crate) inv_depth: &'a [f32],
    pub(crate) normal: [&'a [f32]; 3],
    /// Material index per sample as a number (exact: indices are below
    /// 2²⁴), −1 where nothing is hit (`material_labels`).
    pub(crate) material: &'a [f32],
    /// Luminance per sample.
    pub(crate) luma: &'a [f32],
}

/// q = 1/w per sample, 0 where nothing is hit (w infinite, NaN or ≤ 0).
#[cfg(test)]
pub(crate) fn inverse_depth(depth: &[f32]) -> Vec<f32> {
    let mut q = vec![0.0f32; depth.len()];
    q.par_chunks_mut(4096)
        .zip(depth.par_chunks(4096))
        .for_each(|(q, d)| inverse_depth_into(d, q));
    q
}

/// `inverse_depth` into `q` (same length).
pub(crate) fn inverse_depth_into(depth: &[f32], q: &mut [f32]) {
    // A plain loop (a select per sample) vectorizes.
    for (q, &d) in q.iter_mut().zip(depth) {
        *q = if d.is_finite() && d > 0.0 {
            1.0 / d
        } else {
            0.0
        };
    }
}

/// The id source's labels: the material index of each sample's id as a
/// number (exact below 2²⁴ materials), −1 where nothing is hit or the id
/// has no material.
#[cfg(test)]
pub(crate) fn material_labels(ids: &[u32], id_material: &[u32]) -> Vec<f32> {
    let mut of_id = Vec::new();
    label_of_id(id_material, &mut of_id);
    let mut labels = vec![-1.0f32; ids.len()];
    labels
        .par_chunks_mut(4096)
        .zip(ids.par_chunks(4096))
        .for_each(|(labels, ids)| labels_into(ids, &of_id, labels));
    labels
}

/// The label of each id once (ids are far fewer than samples), into `out`,
/// then −1 once more: the label of every id past the table (MISS, u32::MAX,
/// among them).
pub(super) fn label_of_id(id_material: &[u32], out: &mut Vec<f32>) {
    out.clear();
    // In parallel: a frame has many ids, and this runs before any band
    // starts.
    out.par_extend(id_material.par_iter().enumerate().map(|(id, &m)| {
        if id as u32 != MISS && m != u32::MAX {
            m as f32
        } else {
            -1.0
        }
    }));
    out.push(-1.0);
}

/// `material_labels` with the per-id labels `of_id` ([`label_of_id`]),
/// into `labels`: a table read a sample, ids past the table clamped to
/// its last entry (−1), so the loop has no branch and no bounds check.
pub(super) fn labels_into(ids: &[u32], of_id: &[f32], labels: &mut [f32]) {
    let last = of_id.len() - 1;
    let table = &of_id[..=last];
    let mut done = 0;
    // 8 at a time by the hardware gather ([`Real::gather`], whose f32
    // index lanes are exact below 2²⁴ ids): the scalar look-up was the
    // largest part of the stage's preparation.
    if last < 1 << 24 {
        let last8 = u32x8::splat(last as u32);
        for (l, i) in labels.chunks_exact_mut(8).zip(ids.chunks_exact(8)) {
            let i = u32x8::new(<[u32; 8]>::try_from(i).unwrap_or_default()).min(last8);
            // Eight samples of one triangle (most chunks: the ground,
            // sphere interiors) read the table once, cheaper than a
            // gather.
            let first = i.to_array()[0];
            if i.simd_eq(u32x8::splat(first)).all() {
                f32x8::splat(table[first as usize]).store(l);
            } else {
                let index = i32x8::new(i.to_array().map(|v| v as i32)).round_float();
                <f32x8 as Real>::gather(table, index).store(l);
            }
            done += 8;
        }
    }
    for (l, &id) in labels[done..].iter_mut().zip(&ids[done..]) {
        *l = table[(id as usize).min(last)];
    }
}

/// The colour source's luminance of samples `range` of `color` into `out`:
/// each channel clamped to [0, 1] (NaN to 0), Rec. 709 weights.
pub(super) fn luma_into(color: &Planes3, range: std::ops::Range<usize>, out: &mut [f32]) {
    let clamp = |v: f32| if v > 0.0 { v.min(1.0) } else { 0.0 };
    let (r, g, b) = (
        &color.r[range.clone()],
        &color.g[range.clone()],
        &color.b[range],
    );
    for (((o, &r), &g), &b) in out.iter_mut().zip(r).zip(g).zip(b) {
        *o = 0.2126 * clamp(r) + 0.7152 * clamp(g) + 0.0722 * clamp(b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Labels by chunks (one table read for a chunk of one id, a gather
    /// otherwise) against a per-sample look-up: runs of one id across and
    /// inside chunks, mixed chunks, misses and ids past the table.
    #[test]
    fn labels_by_chunks_equal_a_look_up_per_sample() {
        let id_material = [0u32, 3, u32::MAX, 1, 2];
        let mut of_id = Vec::new();
        label_of_id(&id_material, &mut of_id);
        let ids: Vec<u32> = (0..203)
            .map(|i| match i / 8 % 4 {
                0 => 1,                   // a chunk of one id
                1 => (i % 3) as u32,      // mixed
                2 => [MISS, 7, 4][i % 3], // a miss, past the table, the last
                _ => {
                    if i % 16 < 12 {
                        3
                    } else {
                        2
                    }
                } // a run ending inside a chunk
            })
            .collect();
        let mut labels = vec![f32::NAN; ids.len()];
        labels_into(&ids, &of_id, &mut labels);
        for (i, (&id, &l)) in ids.iter().zip(&labels).enumerate() {
            let want = match id_material.get(id as usize) {
                Some(&m) if m != u32::MAX => m as f32,
                _ => -1.0,
            };
            assert_eq!(l.to_bits(), want.to_bits(), "sample {i}, id {id}");
        }
    }

    #[test]
    fn labels_read_the_material_of_each_id_and_minus_one_past_the_table() {
        // Materials with holes (u32::MAX: no pass writes the id), ids past
        // the table and MISS, at lengths around the 8-lane packets.
        let id_material: Vec<u32> = (0..37u32)
            .map(|i| if i % 5 == 3 { u32::MAX } else { i % 4 })
            .collect();
        for n in [0usize, 1, 7, 8, 9, 23, 64, 65] {
            let ids: Vec<u32> = (0..n as u32)
                .map(|i| match i % 6 {
                    0 => MISS,
                    1 => 37 + i, // past the table
                    _ => (i * 7) % 37,
                })
                .collect();
            let got = material_labels(&ids, &id_material);
            for (k, &id) in ids.iter().enumerate() {
                let want = match id_material.get(id as usize) {
                    Some(&m) if m != u32::MAX => m as f32,
                    _ => -1.0,
                };
                assert_eq!(got[k], want, "n {n} id {id}");
            }
        }
    }
}
