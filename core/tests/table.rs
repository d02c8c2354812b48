//! The table type against plainly written interpolants: round trip at the
//! nodes, the documented interpolant in f64, the tabulated function between
//! nodes, f32 and f32x8 lanes against f64, and exact integrals.

use specula_core::table::{Axis, Nodes, Table1, Table2, Warp};
use specula_core::{f32x8, Real};

fn axes(n: usize) -> Vec<Axis> {
    let mut v = Vec::new();
    for warp in [Warp::Linear, Warp::Sqrt, Warp::Square] {
        for nodes in [Nodes::Ends, Nodes::Centres] {
            let a = Axis::new(n, -0.5, 2.0, warp, nodes);
            v.push(a);
            v.push(a.linear_between_nodes());
        }
    }
    v
}

/// Node i in the user coordinate, written out per warp and node rule.
fn node_x(a: &Axis, i: usize) -> f64 {
    let u = match a.nodes {
        Nodes::Ends => i as f64 / (a.n - 1) as f64,
        Nodes::Centres => (i as f64 + 0.5) / a.n as f64,
    };
    let t = match a.warp {
        Warp::Linear => u,
        Warp::Sqrt => u * u,
        Warp::Square => u.sqrt(),
    };
    a.lo + (a.hi - a.lo) * t
}

/// The module docs' interpolant, with branches: clamp to the outer nodes,
/// find the bracketing nodes by search, weight linear in u or in x.
fn plain_interpolant(a: &Axis, values: &[f64], x: f64) -> f64 {
    let xs: Vec<f64> = (0..a.n).map(|i| node_x(a, i)).collect();
    let warp = |x: f64| {
        let t = ((x - a.lo) / (a.hi - a.lo)).clamp(0.0, 1.0);
        match a.warp {
            Warp::Linear => t,
            Warp::Sqrt => t.sqrt(),
            Warp::Square => t * t,
        }
    };
    if x <= xs[0] {
        return values[0];
    }
    if x >= xs[a.n - 1] {
        return values[a.n - 1];
    }
    let i = (0..a.n - 1).find(|&i| x < xs[i + 1]).unwrap();
    let w = match a.interp {
        specula_core::table::Interp::Warped => {
            (warp(x) - warp(xs[i])) / (warp(xs[i + 1]) - warp(xs[i]))
        }
        specula_core::table::Interp::Linear => (x - xs[i]) / (xs[i + 1] - xs[i]),
    };
    values[i] + (values[i + 1] - values[i]) * w
}

fn f(x: f64) -> [f64; 2] {
    [(1.3 * x).sin() + 0.2, (x + 0.7).sqrt()]
}

#[test]
fn lookup_is_the_documented_interpolant_and_round_trips_at_nodes() {
    for a in axes(17) {
        let t = Table1::build(a, f);
        for i in 0..a.n {
            let x = node_x(&a, i);
            let want = f(x).map(|v| v as f32);
            assert_eq!(t.node_value(i), want, "{a:?} node {i}");
            let got = t.lookup(x);
            for c in 0..2 {
                assert!(
                    (got[c] - want[c] as f64).abs() < 1e-12,
                    "{a:?} round trip at node {i}"
                );
            }
        }
        let vals: [Vec<f64>; 2] =
            core::array::from_fn(|c| (0..a.n).map(|i| t.node_value(i)[c] as f64).collect());
        for k in 0..=2000 {
            let x = -0.7 + 3.0 * k as f64 / 2000.0;
            let got = t.lookup(x);
            for c in 0..2 {
                let want = plain_interpolant(&a, &vals[c], x);
                assert!(
                    (got[c] - want).abs() < 1e-12,
                    "{a:?} x={x} channel {c}: {} vs {want}",
                    got[c]
                );
            }
        }
    }
}

#[test]
fn lookup_follows_the_function_between_nodes() {
    // 257 nodes over [−0.5, 2]; the widest interval (Square warp near lo,
    // √(1/256) of the range: h = 0.156, where |f''| ≤ ¼ 0.2^(−3/2) = 2.8 for
    // √(x + 0.7)) bounds the error by h² |f''| / 8 = 8.5e-3.
    // Square warp interpolated in u is only first order near lo (du/dt = 0
    // there: linear in t² across [0, h] is off by ~ h f'/4), as its doc says.
    let mut worst = 0.0f64;
    for a in axes(257) {
        if a.warp == Warp::Square && a.interp == specula_core::table::Interp::Warped {
            continue;
        }
        let t = Table1::build(a, f);
        for k in 0..=500 {
            let x = node_x(&a, 0) + (node_x(&a, a.n - 1) - node_x(&a, 0)) * k as f64 / 500.0;
            let (got, want) = (t.lookup(x), f(x));
            for c in 0..2 {
                worst = worst.max((got[c] - want[c]).abs());
            }
        }
    }
    eprintln!("worst |lookup − f| between nodes: {worst:.2e}");
    assert!(worst < 8.5e-3, "{worst}");
}

#[test]
fn f32_and_f32x8_lanes_agree_with_f64() {
    let g = |x: f64, y: f64| [(x * 2.0).cos() * y, x * x + y.sqrt(), 1.0 - x * y];
    let ax = Axis::new(23, 0.0, 1.0, Warp::Sqrt, Nodes::Ends).linear_between_nodes();
    let ay = Axis::new(11, 0.0, 1.0, Warp::Sqrt, Nodes::Centres);
    let t2 = Table2::build(ax, ay, g);
    let t1 = Table1::build(ay, |x| g(x, 0.5));
    let mut worst = 0.0f64;
    for k in 0..4000 {
        // Lanes spread over the range and a little past it.
        let xs: [f32; 8] =
            core::array::from_fn(|l| ((k * 8 + l) as f32 * 0.61803).fract() * 1.2 - 0.1);
        let ys: [f32; 8] =
            core::array::from_fn(|l| ((k * 8 + l) as f32 * 0.41421).fract() * 1.2 - 0.1);
        let (vx, vy) = (f32x8::from(xs), f32x8::from(ys));
        let l2 = t2.lookup(vx, vy);
        let l1 = t1.lookup(vx);
        for l in 0..8 {
            let want2 = t2.lookup(xs[l] as f64, ys[l] as f64);
            let want1 = t1.lookup(xs[l] as f64);
            let s2 = t2.lookup(xs[l], ys[l]);
            for c in 0..3 {
                for (got, want) in [
                    (l2[c].lane(l), want2[c]),
                    (s2[c] as f64, want2[c]),
                    (l1[c].lane(l), want1[c]),
                ] {
                    worst = worst.max((got - want).abs());
                    assert!(
                        (got - want).abs() < 2e-6,
                        "lane {l} channel {c} at ({}, {}): {got} vs {want}",
                        xs[l],
                        ys[l]
                    );
                }
            }
        }
    }
    eprintln!("worst f32/f32x8 vs f64 table lookup: {worst:.2e}");
}

#[test]
fn two_d_lookup_is_bilinear_and_slices_agree() {
    let g = |x: f64, y: f64| [x.exp() * (1.0 + y), y * y];
    let ax = Axis::new(9, 0.0, 1.0, Warp::Linear, Nodes::Centres);
    let ay = Axis::new(7, 0.0, 2.0, Warp::Sqrt, Nodes::Ends);
    let t = Table2::build(ax, ay, g);
    for (i, j) in [(0, 0), (3, 5), (8, 6), (4, 2)] {
        let want = g(node_x(&ax, i), node_x(&ay, j)).map(|v| v as f32);
        assert_eq!(t.node_value(i, j), want);
    }
    for k in 0..200 {
        let y = 2.0 * k as f64 / 199.0;
        let s = t.slice_y(y);
        // Along y the slice weights rows as the 2-D lookup does.
        for m in 0..50 {
            let x = m as f64 / 49.0;
            let (a, b) = (s.lookup(x), t.lookup(x, y));
            for c in 0..2 {
                assert!(
                    (a[c] - b[c]).abs() < 1e-6 * b[c].abs().max(1.0),
                    "({x}, {y})"
                );
            }
        }
    }
    // Bilinear: at the centre of four nodes, the mean of the four.
    let (x, y) = (0.5 * (node_x(&ax, 2) + node_x(&ax, 3)), node_x(&ay, 4));
    let (x0, x1) = (t.node_value(2, 4)[0] as f64, t.node_value(3, 4)[0] as f64);
    assert!((t.lookup(x, y)[0] - 0.5 * (x0 + x1)).abs() < 1e-12);
}

#[test]
fn integrate_is_exact_for_the_interpolant() {
    // E linear in x between √-spaced nodes (Kulla–Conty's E axis): the exact
    // moment 2 ∫ E x dx summed segment by segment in closed form.
    let a = Axis::new(12, 0.0, 1.0, Warp::Sqrt, Nodes::Ends).linear_between_nodes();
    let t = Table1::build(a, |x| [1.0 - (-4.0 * x).exp()]);
    let mut want = 0.0;
    for i in 0..a.n - 1 {
        let (x0, x1) = (node_x(&a, i), node_x(&a, i + 1));
        let (e0, e1) = (t.node_value(i)[0] as f64, t.node_value(i + 1)[0] as f64);
        let slope = (e1 - e0) / (x1 - x0);
        let c0 = e0 - slope * x0;
        want += 2.0 * (c0 * (x1 * x1 - x0 * x0) / 2.0 + slope * (x1.powi(3) - x0.powi(3)) / 3.0);
    }
    let [got] = t.integrate(|x| 2.0 * x);
    assert!((got - want).abs() < 1e-14, "{got} vs {want}");
    // Texel centres, linear in u: the constant stretches past the outer
    // centres count too; a fine midpoint sum of the lookup agrees.
    let b = Axis::new(10, 0.0, 1.0, Warp::Linear, Nodes::Centres);
    let t = Table1::build(b, |x| [x * x]);
    let n = 200_000;
    let mid: f64 = (0..n)
        .map(|k| t.lookup((k as f64 + 0.5) / n as f64)[0] / n as f64)
        .sum();
    let [got] = t.integrate(|_| 1.0);
    assert!((got - mid).abs() < 1e-9, "{got} vs {mid}");
}

#[test]
fn cubic_slice_reproduces_quadratics_in_the_node_coordinate() {
    // Catmull–Rom on uniform nodes is exact for quadratics; with a √ warp
    // the node coordinate is u = √y, so f = 1 + 2u − 3u² along y.
    let ax = Axis::new(5, 0.0, 1.0, Warp::Linear, Nodes::Ends);
    let ay = Axis::new(12, 0.0, 1.0, Warp::Sqrt, Nodes::Ends);
    let q = |x: f64, u: f64| 1.0 + 2.0 * u - 3.0 * u * u + x;
    let t = Table2::build(ax, ay, |x, y| [q(x, y.sqrt())]);
    for k in 0..100 {
        // Interior intervals only: the ends repeat the outer rows.
        let u = 1.0 / 11.0 + (9.0 / 11.0) * k as f64 / 99.0;
        let s = t.slice_y_cubic(u * u);
        for i in 0..5 {
            let want = q(i as f64 / 4.0, u);
            assert!(
                (s.node_value(i)[0] as f64 - want).abs() < 1e-6,
                "u={u} node {i}"
            );
        }
    }
}
