//! Tests of the detection against the scalar measure, of the block bounds
//! and of the whole stage against its parts composited.

use super::block::{block_sources, BlockRows, BLOCK};
use super::detect::detect_edges;
use super::detect::{below_sqrt, Field, Thresholds};
use super::inputs::{inverse_depth, material_labels, EdgeInput};
use super::measure::measure;
use super::measure::measure_lanes;
use super::*;
use crate::dilate::dilate;
use crate::outline::{composite, Selection};
use specula_raster::post::{HdrImage, PostStage};
use specula_raster::target::MISS;
use specula_raster::{FrameBuffers, Planes3};
use wide::f32x8;

/// Depth of a plane seen by a pinhole camera at pixel (x, y): the ray
/// through the pixel centre hits n·p = c at t, w = t · (ray · forward),
/// written here independently of the detector.
fn plane_depth(x: usize, y: usize, w: usize, h: usize, n: [f64; 3], c: f64) -> f32 {
    let tan = (30f64.to_radians()).tan();
    let nx = (2.0 * (x as f64 + 0.5) / w as f64 - 1.0) * tan * w as f64 / h as f64;
    let ny = (1.0 - 2.0 * (y as f64 + 0.5) / h as f64) * tan;
    let d = [nx, ny, -1.0]; // camera at the origin looking down −z
    let t = c / (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]);
    t as f32 // w = t · (d · forward) with d · forward = 1
}

fn edges_of_depth(depth: &[f32], w: usize, h: usize, t: f32) -> Vec<bool> {
    let inv = inverse_depth(depth);
    let input = EdgeInput {
        width: w,
        height: h,
        inv_depth: &inv,
        normal: [&[], &[], &[]],
        material: &[],
        luma: &[],
    };
    detect_edges(&input, &[(Source::Depth, t)], &|_| true)
}

#[test]
fn a_slanted_floor_gives_no_depth_line_and_a_step_does() {
    let (w, h) = (96, 64);
    // A floor y = −1 seen at a grazing angle: depth from ~1 at the
    // bottom rows to ~60 near the horizon, its first derivative large.
    let n = [0.02, 1.0, 0.0f64];
    let n_len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let n = n.map(|v| v / n_len);
    let floor: Vec<f32> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            if y < h / 2 + 2 {
                f32::INFINITY // sky above the horizon
            } else {
                plane_depth(x, y, w, h, n, -1.0 / n_len)
            }
        })
        .collect();
    assert!(floor[(h - 1) * w] < 2.0 && floor[(h / 2 + 2) * w] > 10.0);
    // Plain Sobel's first derivative of depth is large on the floor.
    let first = (floor[(h / 2 + 6) * w + 5] - floor[(h / 2 + 8) * w + 5]).abs();
    assert!(first > 1.0, "{first}");
    let e = edges_of_depth(&floor, w, h, 0.05);
    let on_floor = (h / 2 + 4..h).flat_map(|y| (0..w).map(move |x| (x, y)));
    let lines: Vec<_> = on_floor.filter(|(x, y)| e[y * w + x]).collect();
    assert!(lines.is_empty(), "lines on the floor at {lines:?}");

    // A box in front of a wall: depth 2 inside x in [30, 60), 4 outside.
    let step: Vec<f32> = (0..w * h)
        .map(|i| {
            if (30..60).contains(&(i % w)) {
                2.0
            } else {
                4.0
            }
        })
        .collect();
    let e = edges_of_depth(&step, w, h, 0.25);
    for y in 0..h {
        let row: Vec<usize> = (0..w).filter(|x| e[y * w + x]).collect();
        // 1 − 2/4 = 0.5 > 0.25 on both sides of each step; nothing else.
        assert_eq!(row, vec![29, 30, 59, 60], "row {y}");
    }
    // Above the measure (0.5), the step draws nothing.
    assert!(!edges_of_depth(&step, w, h, 0.55).contains(&true));
}

#[test]
fn normal_and_id_measures_match_their_formulas() {
    let (w, h) = (20, 10);
    // Two faces meeting at x = 10 with normals 90° apart.
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let nx: Vec<f32> = (0..w * h)
        .map(|i| if i % w < 10 { -s } else { s })
        .collect();
    let ny = vec![0.0; w * h];
    let nz = vec![s; w * h];
    let mat: Vec<f32> = (0..w * h).map(|i| (i % w >= 10) as u32 as f32).collect();
    let input = EdgeInput {
        width: w,
        height: h,
        inv_depth: &[],
        normal: [&nx, &ny, &nz],
        material: &mat,
        luma: &[],
    };
    let want = 2.0 * (std::f32::consts::FRAC_PI_4).sin(); // 2 sin(θ/2)
    assert!((measure(&input, Source::Normal, 9, 5) - want).abs() < 1e-6);
    assert!((measure(&input, Source::Normal, 10, 5) - want).abs() < 1e-6);
    assert_eq!(measure(&input, Source::Normal, 8, 5), 0.0);
    assert!((measure(&input, Source::Id, 9, 5) - 1.0 / 3.0).abs() < 1e-6);
    assert_eq!(measure(&input, Source::Id, 3, 5), 0.0);
}

/// A 24-bit hash of (i, k): the tests' noise.
fn hash(i: usize, k: u32) -> u32 {
    let v = (i as u32)
        .wrapping_mul(2654435761)
        .wrapping_add(k.wrapping_mul(97));
    (v ^ (v >> 13)).wrapping_mul(1274126177) >> 8
}

/// [`hash`] as a value in [0, 1).
fn unit(i: usize, k: u32) -> f32 {
    hash(i, k) as f32 / (1u32 << 24) as f32
}

/// Noisy frame fields for the row-kernel tests: misses (q = 0) and
/// noise, plus (`patchy`) flat patches, steps and repeated labels.
struct Fields {
    width: usize,
    height: usize,
    inv: Vec<f32>,
    normal: [Vec<f32>; 3],
    mat: Vec<f32>,
    luma: Vec<f32>,
}

impl Fields {
    fn noisy(width: usize, height: usize, patchy: bool) -> Fields {
        let n = width * height;
        let depth: Vec<f32> = (0..n)
            .map(|i| match hash(i, 1) % 5 {
                0 => f32::INFINITY,
                1 if patchy => 2.0,
                _ => 1.0 + 4.0 * unit(i, 2),
            })
            .collect();
        // Patches: normals shared by 3 samples, labels by 2, of 4.
        let (normal_run, label_run, labels) = if patchy { (3, 2, 4) } else { (1, 1, 3) };
        Fields {
            width,
            height,
            inv: inverse_depth(&depth),
            normal: [0, 1, 2].map(|c| {
                (0..n)
                    .map(|i| unit(i / normal_run, 10 + c) * 2.0 - 1.0)
                    .collect()
            }),
            mat: (0..n)
                .map(|i| (hash(i / label_run, 5) % labels) as f32 - 1.0)
                .collect(),
            luma: (0..n).map(|i| unit(i, 7)).collect(),
        }
    }

    fn input(&self) -> EdgeInput<'_> {
        let [nx, ny, nz] = &self.normal;
        EdgeInput {
            width: self.width,
            height: self.height,
            inv_depth: &self.inv,
            normal: [nx, ny, nz],
            material: &self.mat,
            luma: &self.luma,
        }
    }
}

#[test]
fn packets_give_the_scalar_measure_bit_for_bit() {
    // Noisy buffers with flat patches, steps, misses (q = 0) and
    // repeated labels, at widths around the packet size.
    for (w, h) in [(37, 9), (10, 4), (9, 3), (64, 5)] {
        let fields = Fields::noisy(w, h, true);
        let input = fields.input();
        let all = [Source::Depth, Source::Normal, Source::Id, Source::Color];
        for s in all {
            for y in 0..h {
                let rows = [y.saturating_sub(1) * w, y * w, (y + 1).min(h - 1) * w];
                for x in 1..w.saturating_sub(8) {
                    let lanes = measure_lanes::<f32x8>(&input, s, rows, x);
                    for l in 0..8 {
                        let one = measure(&input, s, x + l, y);
                        let lane = lanes.as_array()[l];
                        assert_eq!(lane.to_bits(), one.to_bits(), "{s:?} ({}, {y})", x + l);
                        let f = measure_lanes::<f32>(&input, s, rows, x + l);
                        assert_eq!(f.to_bits(), one.to_bits());
                    }
                }
            }
            // The mask against the scalar measure at every sample,
            // at thresholds around the measures' values.
            for t in [0.05f32, 0.2, 0.4, 0.7] {
                let e = detect_edges(&input, &[(s, t)], &|i| i % 11 != 4);
                for y in 0..h {
                    for x in 0..w {
                        let want = measure(&input, s, x, y) > t && (y * w + x) % 11 != 4;
                        assert_eq!(e[y * w + x], want, "{s:?} t {t} ({x}, {y})");
                    }
                }
            }
        }
    }
}

#[test]
fn rows_mark_exactly_where_the_scalar_measure_exceeds_a_threshold_at_it() {
    // Thresholds equal to measures at chosen samples and one float
    // below: a sample whose measure is the threshold is unmarked, one
    // float less marks it, so every bit of the row kernels' values is
    // checked there. Widths put 8-sample chunks across 64-sample words
    // and an overlapping last chunk (and rows too narrow for a chunk);
    // a source listed twice marks above the lesser threshold.
    for (w, h) in [(2, 3), (9, 4), (10, 3), (37, 5), (130, 6), (203, 4)] {
        let fields = Fields::noisy(w, h, false);
        let input = fields.input();
        let all = [Source::Depth, Source::Normal, Source::Id, Source::Color];
        for s in all {
            for k in 0..6 {
                let (x, y) = ((k * 29 + 3) % w, k % h);
                let at = measure(&input, s, x, y);
                for t in [at, at.next_down()] {
                    let sources = [(s, t + 0.25), (s, t)];
                    let e = detect_edges(&input, &sources, &|_| true);
                    for yy in 0..h {
                        for xx in 0..w {
                            let want = measure(&input, s, xx, yy) > t;
                            assert_eq!(e[yy * w + xx], want, "{w} {s:?} t {t} ({xx}, {yy})");
                        }
                    }
                    assert_eq!(e[y * w + x], t < at);
                }
            }
        }
    }
}

/// The fields of one block (3 rows of BLOCK + 2 samples) for the block
/// bound tests: `pattern` over a base value per field, with amplitude
/// `eps`: 0 noise, 1 a step across the rows, 2 a diagonal step, 3 a
/// ridge every other column (the largest second difference), 4 one
/// sample off the base and a NaN after it (in the order block_range
/// reads them: a NaN must not drop what came before), 5 noise with a
/// +∞, 6 noise with misses (q = 0) in the first columns, 7 all 0.
fn block_fields(pattern: u32, eps: f32) -> [Vec<f32>; 6] {
    const N: usize = BLOCK + 2;
    [0u32, 1, 2, 3, 4, 5].map(|f| {
        // q small enough that a block's largest can be under 0.1.
        let base = if f == 0 { 0.05 } else { 0.3 + 0.1 * f as f32 };
        (0..3 * N)
            .map(|i| {
                let (x, r) = (i % N, i / N);
                let noise = base + eps * unit(i, f);
                let v = match pattern {
                    1 => base + if x >= 33 { eps } else { 0.0 },
                    2 => base + if x + r >= 34 { eps } else { 0.0 },
                    3 => base + if x % 2 == 0 { eps } else { 0.0 },
                    4 if (x, r) == (8, 0) => base + eps,
                    4 if (x, r) == (40, 1) => f32::NAN,
                    4 => base,
                    5 if (x, r) == (20, 0) => f32::INFINITY,
                    6 if f == Field::InvDepth as u32 && x < 10 => 0.0,
                    7 => 0.0,
                    _ => noise,
                };
                if f == Field::Label as u32 {
                    // Labels (never NaN, EdgeInput): one, or two where
                    // the pattern leaves the base.
                    (v != base) as u32 as f32
                } else {
                    v
                }
            })
            .collect()
    })
}

#[test]
fn a_source_dropped_from_a_block_marks_none_of_its_samples() {
    // The bounds of block_sources against the scalar measure of every
    // sample of the block: a source is dropped only where no measure
    // exceeds its threshold, thresholds from below 0 to just under and
    // at the block's largest measure (a bound smaller than it fails
    // there); the patterns include the ones that reach the bounds
    // (steps, ridges) and NaN, ∞ and missed samples. The mask of
    // detect_edges equals the scalar measure's everywhere.
    const N: usize = BLOCK + 2;
    let all = [Source::Depth, Source::Normal, Source::Id, Source::Color];
    let mut dropped = [0usize; 4];
    for pattern in 0..8 {
        for eps in [0.0f32, 1e-3, 1e-2, 0.1, 0.5] {
            let fields = block_fields(pattern, eps);
            let [q, nx, ny, nz, labels, luma] = &fields;
            let input = EdgeInput {
                width: N,
                height: 3,
                inv_depth: q,
                normal: [nx, ny, nz],
                material: labels,
                luma,
            };
            let a: [BlockRows; 6] = std::array::from_fn(|k| {
                [0, 1, 2].map(|r| <&[f32; N]>::try_from(&fields[k][r * N..][..N]).unwrap())
            });
            let measures =
                |s| -> Vec<f32> { (1..=BLOCK).map(|x| measure(&input, s, x, 1)).collect() };
            let thresholds = |s| -> Vec<f32> {
                let most = measures(s).into_iter().fold(0.0f32, f32::max);
                let ts = [-0.5, 0.0, most.next_down(), most, most * 1.01, most * 3.0];
                ts.into_iter().chain([0.4, f32::INFINITY]).collect()
            };
            for (k, &s) in all.iter().enumerate() {
                for t in thresholds(s) {
                    let out = block_sources(&Thresholds::new(&[(s, t)]), &a);
                    let kept = out.is_some_and(|o| match s {
                        Source::Depth => o.depth.is_some(),
                        Source::Normal => o.normal.is_some(),
                        Source::Id => o.id.is_some(),
                        Source::Color => o.color.is_some(),
                    });
                    if !kept {
                        dropped[k] += 1;
                        let over: Vec<f32> = measures(s).into_iter().filter(|&m| m > t).collect();
                        assert!(over.is_empty(), "{s:?} {pattern} {eps} t {t}: {over:?}");
                    }
                    let e = detect_edges(&input, &[(s, t)], &|_| true);
                    for x in 0..N {
                        let want = measure(&input, s, x, 1) > t;
                        assert_eq!(e[N + x], want, "{s:?} {pattern} {eps} t {t} x {x}");
                    }
                }
            }
            // All sources at once: the tests stop at the first source
            // that may mark; whatever is dropped marks nothing.
            let ts: Vec<Vec<f32>> = all.iter().map(|&s| thresholds(s)).collect();
            for i in 0..ts[0].len() {
                let sources: Vec<(Source, f32)> =
                    all.iter().zip(&ts).map(|(&s, t)| (s, t[i])).collect();
                let out = block_sources(&Thresholds::new(&sources), &a);
                for (&(s, t), kept) in sources.iter().zip(out.map_or([false; 4], |o| {
                    [
                        o.depth.is_some(),
                        o.normal.is_some(),
                        o.id.is_some(),
                        o.color.is_some(),
                    ]
                })) {
                    let none = !measures(s).iter().any(|&m| m > t);
                    assert!(kept || none, "{s:?} {pattern} {eps}");
                }
            }
        }
    }
    // Every source was dropped somewhere (the bounds are not vacuous).
    assert!(dropped.iter().all(|&d| d > 0), "{dropped:?}");
}

#[test]
fn blocks_of_one_label_mark_as_the_scalar_id_measure() {
    // Wide runs of one label (whole 64-sample blocks of one label and
    // their neighbour rows, where every measure is 0), a few single
    // samples of another, a run boundary in mid-block, and a row band
    // of another label; thresholds below 0 mark every sample.
    let (w, h) = (203, 9);
    let mat: Vec<f32> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            if (x, y) == (100, 4) || (x, y) == (170, 1) {
                7.0
            } else if y >= 7 {
                -1.0
            } else {
                (x / 90) as f32
            }
        })
        .collect();
    let input = EdgeInput {
        width: w,
        height: h,
        inv_depth: &[],
        normal: [&[], &[], &[]],
        material: &mat,
        luma: &[],
    };
    for t in [-0.5f32, -0.0, 0.0, 0.1, 1.0 / 3.0, 0.9] {
        let e = detect_edges(&input, &[(Source::Id, t)], &|_| true);
        for y in 0..h {
            for x in 0..w {
                let want = measure(&input, Source::Id, x, y) > t;
                assert_eq!(e[y * w + x], want, "t {t} ({x}, {y})");
            }
        }
        assert_eq!(e.iter().all(|&m| m), t < 0.0, "t {t}");
    }
}

#[test]
fn the_squared_threshold_says_what_the_square_root_says() {
    // Around each threshold's square, f32 by f32, and at the ends.
    for t in [0.0f32, 1e-20, 0.1, 0.25, 0.4, 0.6, 1.0, 3.7, 1e19, 3e19] {
        let x = below_sqrt(t);
        let mut g2 = (t * t).max(f32::MIN_POSITIVE);
        for _ in 0..8 {
            g2 = g2.next_down();
        }
        for _ in 0..16 {
            assert_eq!(g2.sqrt() > t, g2 > x, "t {t} g² {g2}");
            g2 = g2.next_up();
        }
        for g2 in [0.0, f32::MIN_POSITIVE, f32::MAX, f32::INFINITY, f32::NAN] {
            assert_eq!(g2.sqrt() > t, g2 > x, "t {t} g² {g2}");
        }
    }
    for t in [-1.0f32, f32::INFINITY] {
        for g2 in [0.0, 1.0, f32::MAX, f32::INFINITY, f32::NAN] {
            assert_eq!(g2.sqrt() > t, g2 > below_sqrt(t), "t {t} g² {g2}");
        }
    }
}

/// A frame of noisy patches: depth steps and misses, normals, ids whose
/// materials change across patches (some with none), and colour.
fn patchy_frame(w: usize, h: usize) -> (FrameBuffers, Vec<u32>) {
    // Patches of 16 × 12 samples share their values.
    let patch = |i: usize| (i % w) / 16 + 1000 * ((i / w) / 12);
    let n = w * h;
    let plane = |k: u32| -> Vec<f32> { (0..n).map(|i| unit(patch(i), k)).collect() };
    let depth = (0..n)
        .map(|i| match hash(patch(i), 1) % 7 {
            0 => f32::INFINITY,
            1 => 2.0,
            _ => 1.0 + 4.0 * unit(patch(i), 2),
        })
        .collect();
    let ids: Vec<u32> = (0..n)
        .map(|i| match hash(patch(i), 3) % 9 {
            0 => MISS,
            k => k * 3 + (i % 3) as u32, // three ids a patch, one material
        })
        .collect();
    let id_material = (0..40u32)
        .map(|id| if id % 11 == 7 { u32::MAX } else { id / 3 % 4 })
        .collect();
    let rgb = |k: u32| Planes3 {
        r: plane(k),
        g: plane(k + 1),
        b: plane(k + 2),
    };
    let frame = FrameBuffers {
        width: w as u32,
        height: h as u32,
        color: rgb(10),
        depth,
        normal: rgb(20),
        id: ids,
    };
    (frame, id_material)
}

#[test]
fn the_stage_equals_its_parts_composited_bit_for_bit_for_any_thread_count() {
    // The stage (bands with their own 1/w, labels and luminance; the
    // dilation per row straight into a sparse blend; buffers kept from
    // call to call) against the whole-frame parts: detect_edges on
    // whole-frame inputs, dilate, composite.
    let sources = vec![
        (Source::Depth, 0.1),
        (Source::Normal, 0.6),
        (Source::Id, 0.3),
        (Source::Color, 0.45),
    ];
    let pools: Vec<rayon::ThreadPool> = [1, 3]
        .iter()
        .map(|&n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
        })
        .collect();
    for (w, h, ssaa) in [(131, 70, 1), (130, 72, 2), (99, 69, 3)] {
        let (frame, id_material) = patchy_frame(w, h);
        let (iw, ih) = (w / ssaa, h / ssaa);
        let image = |k: usize| -> Vec<f32> {
            (0..iw * ih)
                .map(|i| ((i * 37 + k) % 101) as f32 / 100.0)
                .collect()
        };
        let img0 = HdrImage {
            width: iw as u32,
            height: ih as u32,
            rgb: Planes3 {
                r: image(1),
                g: image(2),
                b: image(3),
            },
        };
        let inv = inverse_depth(&frame.depth);
        let mat = material_labels(&frame.id, &id_material);
        let c = &frame.color;
        let clamp = |v: f32| if v > 0.0 { v.min(1.0) } else { 0.0 };
        let luma: Vec<f32> = (0..w * h)
            .map(|i| 0.2126 * clamp(c.r[i]) + 0.7152 * clamp(c.g[i]) + 0.0722 * clamp(c.b[i]))
            .collect();
        let input = EdgeInput {
            width: w,
            height: h,
            inv_depth: &inv,
            normal: [&frame.normal.r, &frame.normal.g, &frame.normal.b],
            material: &mat,
            luma: &luma,
        };
        let selections = [
            Selection::all(),
            Selection::materials(&id_material, &[1, 2]),
        ];
        for selection in selections {
            for width in [1.0f32, 2.0, 3.5, 9.0, 40.0] {
                for antialias in [true, false] {
                    let mut stage = Sobel {
                        sources: sources.clone(),
                        width,
                        color: [0.1, 0.2, 0.9],
                        antialias,
                        id_material: id_material.clone(),
                        selection: selection.clone(),
                        scratch: Scratch::default(),
                    };
                    let keep = |i: usize| !selection.needs_ids() || selection.contains(frame.id[i]);
                    let mask = detect_edges(&input, &sources, &keep);
                    let cov = dilate(&mask, w, h, width * ssaa as f32, antialias);
                    let mut want = img0.clone();
                    composite(&mut want, &frame, &cov, stage.color);
                    // Ink somewhere, and narrow lines leave samples
                    // without (the blend skips them).
                    assert!(cov.iter().any(|&c| c > 0.0));
                    assert!(width * ssaa as f32 > 4.0 || cov.contains(&0.0));
                    for pool in &pools {
                        // Twice: the second call reuses the buffers.
                        for _ in 0..2 {
                            let mut got = img0.clone();
                            pool.install(|| stage.apply(&mut got, &frame));
                            let planes = |i: &HdrImage| {
                                [&i.rgb.r, &i.rgb.g, &i.rgb.b]
                                    .map(|p| p.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
                            };
                            assert!(
                                planes(&got) == planes(&want),
                                "{w}×{h} ssaa {ssaa} width {width} aa {antialias}"
                            );
                        }
                    }
                }
            }
        }
    }
}
