//! Timing in alternation, for ratios on a noisy host. The project's
//! machines run in phases of tens of seconds whose speeds differ by up to
//! ~35 % (the same frame reads 23 ms in one and 31 ms in the next), so two
//! criterion benchmarks run one after the other can land in different
//! phases and their ratio is off by that much. Here every round times each
//! item once (the median of `k` calls), in an order rotated from round to
//! round, so both sides of a ratio taken per round share a phase.

use specula::render::median;
use std::time::Instant;

/// Times `items` over `rounds` rounds: `result[item][round]` is the median
/// of `k` consecutive calls of the item in that round, in milliseconds.
pub fn rounds(rounds: usize, k: usize, items: &mut [&mut dyn FnMut()]) -> Vec<Vec<f64>> {
    let n = items.len();
    let k = k.max(1);
    let mut times = vec![Vec::with_capacity(rounds); n];
    let mut calls = Vec::with_capacity(k);
    for round in 0..rounds {
        for j in 0..n {
            let item = (round + j) % n;
            calls.clear();
            for _ in 0..k {
                let t = Instant::now();
                items[item]();
                calls.push(t.elapsed().as_secs_f64() * 1e3);
            }
            times[item].push(median(&calls));
        }
    }
    times
}

/// The lower quartile, the median and the upper quartile of `v` (nearest
/// rank); NaN for an empty `v`.
pub fn quartiles(v: &[f64]) -> (f64, f64, f64) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let at = |q: f64| s[((s.len() - 1) as f64 * q).round() as usize];
    (at(0.25), at(0.5), at(0.75))
}

/// The whole number at position `i` of the command line, `default` when
/// there is none; exits with `usage` when it is not one.
pub fn arg(i: usize, default: usize, usage: &str) -> usize {
    match std::env::args().nth(i) {
        None => default,
        Some(a) => a.parse().unwrap_or_else(|_| {
            eprintln!("{usage}: {a:?} is not a whole number");
            std::process::exit(2)
        }),
    }
}

/// `a[r] / b[r]` for each round r.
pub fn ratios(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x / y).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quartiles_by_nearest_rank() {
        let v: Vec<f64> = (1..=9).rev().map(f64::from).collect();
        assert_eq!(quartiles(&v), (3.0, 5.0, 7.0));
        assert_eq!(quartiles(&[2.0, 1.0]).1, 2.0);
        assert!(quartiles(&[]).1.is_nan());
    }

    #[test]
    fn every_item_is_timed_once_a_round_in_rotated_order() {
        let order = std::cell::RefCell::new(Vec::new());
        let (mut a, mut b, mut c) = (
            || order.borrow_mut().push('a'),
            || order.borrow_mut().push('b'),
            || order.borrow_mut().push('c'),
        );
        let t = rounds(3, 2, &mut [&mut a, &mut b, &mut c]);
        assert_eq!(t.len(), 3);
        assert!(t.iter().all(|r| r.len() == 3));
        let seen: String = order.into_inner().into_iter().collect();
        assert_eq!(seen, "aabbccbbccaaccaabb");
    }
}
