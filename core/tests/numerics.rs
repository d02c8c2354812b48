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

/// `gather_run` against its definition, a gather of index + c per float
/// of the run (each lane's own value, the scalar gather's): runs read by
/// loads (every lane's 8 floats in the table, integral indices) and runs
/// that fall back to gathers (a lane near the table's end, before its
/// start, between two floats, NaN), for runs of 5 and 8 floats, and the
/// sixteen floats of a table too short for one load.
#[test]
fn gather_run_is_a_gather_of_each_float_of_the_run() {
    fn check<const N: usize>(table: &[f32], idx: [f32; 8]) {
        let got = f32x8::gather_run::<N>(table, f32x8::from(idx));
        for (c, got) in got.iter().enumerate() {
            let got = got.to_array();
            for l in 0..8 {
                let want = f32x8::gather(table, f32x8::splat(idx[l] + c as f32)).to_array()[0];
                assert_eq!(
                    got[l].to_bits(),
                    want.to_bits(),
                    "lane {l} float {c} of {idx:?}"
                );
                // An integral index whose float is in the table reads it.
                let at = (idx[l] as usize).saturating_add(c);
                if idx[l] >= 0.0 && idx[l].fract() == 0.0 && at < table.len() {
                    assert_eq!(want, table[at]);
                }
            }
        }
    }
    let table: Vec<f32> = (0..61).map(|i| (i as f32 * 0.37).sin()).collect();
    for start in 0..60 {
        // Every lane's run inside the table for small starts, some lanes'
        // past its end for large ones.
        let idx: [f32; 8] = core::array::from_fn(|l| ((start + 7 * l) % 61) as f32);
        check::<5>(&table, idx);
        check::<8>(&table, idx);
    }
    let inside: [f32; 8] = core::array::from_fn(|l| (3 * l) as f32);
    check::<5>(&table, inside);
    for bad in [-1.0, -0.5, 53.5, 54.0, f32::NAN, f32::INFINITY, -0.0] {
        let mut idx = inside;
        idx[5] = bad;
        check::<5>(&table, idx);
        check::<8>(&table, idx);
    }
    check::<5>(&table[..7], [0.0; 8]);
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

/// GTR D(m) from Burley's c and base^(−γ) [Burley12, App. B], combined in
/// f64 logs: ln D = ln c − γ ln base, with ln c written per branch so that
/// (α²)^(1−γ) never overflows (for γ > 1 it is factored out of
/// 1 − (α²)^(1−γ)).
fn d_gtr_oracle(alpha: f64, gamma: f64, c2: f64, s2: f64) -> f64 {
    let pi = std::f64::consts::PI;
    let a2 = alpha * alpha;
    let base = c2 * a2 + s2;
    if alpha == 1.0 {
        return base.powf(-gamma) / pi;
    }
    let ln_c = if gamma == 1.0 {
        ((a2 - 1.0) / (pi * a2.ln())).ln()
    } else if gamma > 1.0 {
        // 1 − (α²)^(1−γ) = −(α²)^(1−γ) (1 − (α²)^(γ−1))
        (gamma - 1.0).ln() + (1.0 - a2).ln()
            - pi.ln()
            - ((1.0 - gamma) * a2.ln() + (1.0 - a2.powf(gamma - 1.0)).ln())
    } else {
        ((gamma - 1.0) * (a2 - 1.0) / (pi * (1.0 - a2.powf(1.0 - gamma)))).ln()
    };
    (ln_c - gamma * base.ln()).exp()
}

#[test]
fn d_gtr_is_finite_and_accurate_at_extreme_alpha_and_gamma() {
    use specula_core::ndf::d_gtr;
    let gammas = [
        0.5, 0.75, 0.999, 1.0, 1.001, 1.5, 2.0, 3.0, 5.5, 10.0, 16.0, 33.3, 64.0, 100.0,
    ];
    let alphas = [
        1e-3f32, 2e-3, 5e-3, 0.01, 0.02, 0.05, 0.1, 0.25, 0.5, 0.9, 0.999, 1.0,
    ];
    let (mut worst, mut at) = (0.0f64, String::new());
    for gamma in gammas {
        for alpha in alphas {
            // θ = (π/2) k³/n³: dense near the peak.
            let n = 400;
            let thetas: Vec<f64> = (0..=n)
                .map(|k| std::f64::consts::FRAC_PI_2 * (k as f64 / n as f64).powi(3))
                .collect();
            for chunk in thetas.chunks(8) {
                let c2: [f32; 8] =
                    core::array::from_fn(|l| chunk.get(l).map_or(1.0, |t| t.cos().powi(2)) as f32);
                let s2: [f32; 8] =
                    core::array::from_fn(|l| chunk.get(l).map_or(0.0, |t| t.sin().powi(2)) as f32);
                let lanes =
                    d_gtr(f32x8::splat(alpha), gamma, f32x8::from(c2), f32x8::from(s2)).to_array();
                for l in 0..8 {
                    let want = d_gtr_oracle(alpha as f64, gamma, c2[l] as f64, s2[l] as f64);
                    let scalar = d_gtr(alpha, gamma, c2[l], s2[l]);
                    let wide = d_gtr(alpha as f64, gamma, c2[l] as f64, s2[l] as f64);
                    assert!(
                        want < 1e-25 || (wide - want).abs() <= 1e-10 * want,
                        "f64 at α={alpha} γ={gamma}: {wide} vs {want}"
                    );
                    for got in [scalar, lanes[l]] {
                        let got = got as f64;
                        let where_ = format!(
                            "α={alpha} γ={gamma} cos²={} sin²={}: {got} vs {want}",
                            c2[l], s2[l]
                        );
                        assert!(got.is_finite() && got >= 0.0, "{where_}");
                        if want >= 1e-25 {
                            let rel = (got - want).abs() / want;
                            if rel > worst {
                                (worst, at) = (rel, where_.clone());
                            }
                        } else {
                            // Past f32's useful range: only finite and tiny.
                            assert!(got <= 2e-25, "{where_}");
                        }
                    }
                }
            }
        }
    }
    eprintln!("worst d_gtr f32/f32x8 vs f64 relative error: {worst:.2e} at {at}");
    assert!(worst <= 1e-5, "{worst:e} at {at}");
}
