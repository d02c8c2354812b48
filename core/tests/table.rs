//! The table type against plainly written interpolants: round trip at the
//! nodes, the documented interpolant in f64, the tabulated function between
//! nodes, f32 and f32x8 lanes against f64, exact integrals, and the spline
//! along y against polynomials and its documented damping.

use specula_core::table::{Axis, Nodes, SplineY, Table1, Table2, Warp};
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
    let u = match a.nodes() {
        Nodes::Ends => i as f64 / (a.n() - 1) as f64,
        Nodes::Centres => (i as f64 + 0.5) / a.n() as f64,
    };
    let t = match a.warp {
        Warp::Linear => u,
        Warp::Sqrt => u * u,
        Warp::Square => u.sqrt(),
    };
    a.lo() + (a.hi() - a.lo()) * t
}

/// The module docs' interpolant, with branches: clamp to the outer nodes,
/// find the bracketing nodes by search, weight linear in u or in x.
fn plain_interpolant(a: &Axis, values: &[f64], x: f64) -> f64 {
    let xs: Vec<f64> = (0..a.n()).map(|i| node_x(a, i)).collect();
    let warp = |x: f64| {
        let t = ((x - a.lo()) / (a.hi() - a.lo())).clamp(0.0, 1.0);
        match a.warp {
            Warp::Linear => t,
            Warp::Sqrt => t.sqrt(),
            Warp::Square => t * t,
        }
    };
    if x <= xs[0] {
        return values[0];
    }
    if x >= xs[a.n() - 1] {
        return values[a.n() - 1];
    }
    let i = (0..a.n() - 1).find(|&i| x < xs[i + 1]).unwrap();
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
        for i in 0..a.n() {
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
            core::array::from_fn(|c| (0..a.n()).map(|i| t.node_value(i)[c] as f64).collect());
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
            let x = node_x(&a, 0) + (node_x(&a, a.n() - 1) - node_x(&a, 0)) * k as f64 / 500.0;
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
    for i in 0..a.n() - 1 {
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

/// u = (y − lo)/(hi − lo) in node units of a linear `Ends` axis.
fn node_coordinate(a: &Axis, y: f64) -> f64 {
    (y - a.lo()) / (a.hi() - a.lo()) * (a.n() - 1) as f64
}

#[test]
fn spline_y_reproduces_cubics_through_the_nodes_and_quadratics_when_smoothed() {
    let ax = Axis::new(4, 0.0, 1.0, Warp::Linear, Nodes::Ends);
    let ay = Axis::new(11, -1.0, 2.0, Warp::Linear, Nodes::Ends);
    // Polynomials in the node coordinate u (0 … 10), linear in x.
    let cubic = |x: f64, u: f64| 0.5 + x + 0.3 * u - 0.08 * u * u + 0.006 * u * u * u;
    let quadratic = |x: f64, u: f64| 2.0 - x + 0.4 * u - 0.05 * u * u;
    let t = Table2::build(ax, ay, |x, y| {
        let u = node_coordinate(&ay, y);
        [cubic(x, u), quadratic(x, u), cubic(x, u)]
    });
    // Channel 0 through the nodes, channel 1 smoothed: each channel takes
    // its own λ (a smoothed cubic is not reproduced: channel 2 shows it).
    let s = SplineY::new(&t, [0.0, 0.3, 0.3], |_| 1.0);
    let mut cubic_smoothed_off = 0.0f64;
    for k in 0..=300 {
        // End intervals included: not-a-knot and the penalty assume
        // nothing there.
        let y = -1.0 + 3.0 * k as f64 / 300.0;
        let u = node_coordinate(&ay, y);
        for x in [0.0, 0.37, 1.0] {
            let got = s.lookup(x, y);
            for (c, want) in [(0, cubic(x, u)), (1, quadratic(x, u))] {
                assert!(
                    (got[c] - want).abs() < 2e-6 * want.abs().max(1.0),
                    "channel {c}, ({x}, {y}): {} vs {want}",
                    got[c]
                );
            }
            cubic_smoothed_off = cubic_smoothed_off.max((got[2] - cubic(x, u)).abs());
        }
    }
    assert!(cubic_smoothed_off > 1e-3, "{cubic_smoothed_off}");
}

#[test]
fn spline_y_is_twice_differentiable_across_rows() {
    let ax = Axis::new(3, 0.0, 1.0, Warp::Linear, Nodes::Ends);
    let ay = Axis::new(9, 0.0, 1.0, Warp::Sqrt, Nodes::Ends);
    // Nodes scattered by a fixed pseudo-random pattern: no smooth function
    // behind them to lean on.
    let t = Table2::build(ax, ay, |x, y| {
        let j = (y.sqrt() * 8.0).round();
        [x + ((j * 12.9898).sin() * 43758.5453).fract()]
    });
    for smoothing in [0.0, 0.3] {
        let s = SplineY::new(&t, [smoothing], |_| 1.0);
        let v = |u: f64| s.lookup(0.5, u * u)[0];
        for j in 1..8 {
            // One-sided value, slope and curvature in u on each side.
            let (u, e) = (j as f64 / 8.0, 1e-4);
            let slope_l = (v(u) - v(u - e)) / e;
            let slope_r = (v(u + e) - v(u)) / e;
            let left = [
                2.0 * v(u - e) - v(u - 2.0 * e),
                slope_l,
                (v(u) - 2.0 * v(u - e) + v(u - 2.0 * e)) / (e * e),
            ];
            let right = [
                2.0 * v(u + e) - v(u + 2.0 * e),
                slope_r,
                (v(u + 2.0 * e) - 2.0 * v(u + e) + v(u)) / (e * e),
            ];
            // The value extrapolated linearly to the node from each side
            // (off by O(e²) of the curvature); slope and curvature scale as
            // 8 and 64 per unit of value, and one-sided differences are off
            // by O(e) of the next derivative.
            let tol = [1e-5, 0.05, 30.0];
            for d in 0..3 {
                assert!(
                    (left[d] - right[d]).abs() <= tol[d],
                    "λ {smoothing}, row {j}, derivative {d}: {} vs {}",
                    left[d],
                    right[d]
                );
            }
        }
        // The nodes are kept without smoothing.
        if smoothing == 0.0 {
            for j in 0..9 {
                let want = t.node_value(1, j)[0] as f64;
                assert!((v(j as f64 / 8.0) - want).abs() < 1e-6, "node {j}");
            }
        }
    }
}

#[test]
fn smoothing_damps_an_alternating_scatter_as_documented() {
    let ax = Axis::new(2, 0.0, 1.0, Warp::Linear, Nodes::Ends);
    let ay = Axis::new(201, 0.0, 1.0, Warp::Linear, Nodes::Ends);
    let eps = 0.1;
    let smooth = |y: f64| 1.0 + y - 0.5 * y * y;
    let sign = |y: f64| {
        if (node_coordinate(&ay, y).round() as i32) % 2 == 0 {
            1.0
        } else {
            -1.0
        }
    };
    let t = Table2::build(ax, ay, |_, y| [smooth(y) + eps * sign(y)]);
    for smoothing in [0.01, 0.3, 3.0] {
        let s = SplineY::new(&t, [smoothing], |_| 1.0);
        let keep = 1.0 / (1.0 + 576.0 * smoothing);
        // Away from the ends, each node keeps 1/(1 + 576 λ) of the scatter,
        // with its sign.
        for j in 90..110 {
            let y = ay.node(j);
            let left = s.lookup(0.0, y)[0] - smooth(y);
            let want = eps * keep * sign(y);
            assert!(
                (left - want).abs() < 0.02 * eps * keep + 1e-7,
                "λ {smoothing}, node {j}: {left:.4e} left vs {want:.4e}"
            );
        }
    }
    // A heavy node weight holds the spline to that node.
    let held = SplineY::new(&t, [0.3], |j| if j == 200 { 1e6 } else { 1.0 });
    let free = SplineY::new(&t, [0.3], |_| 1.0);
    let miss = |s: &SplineY<1>| (s.lookup(0.0, 1.0)[0] - t.node_value(0, 200)[0] as f64).abs();
    assert!(miss(&held) < 1e-4 * eps, "weighted: {:.3e}", miss(&held));
    assert!(miss(&free) > 0.1 * eps, "unweighted: {:.3e}", miss(&free));
}

#[test]
fn spline_y_lanes_agree_with_f64() {
    let ax = Axis::new(7, 0.0, 1.0, Warp::Linear, Nodes::Ends);
    let ay = Axis::new(12, 0.0, 1.0, Warp::Linear, Nodes::Ends);
    let t = Table2::build(ax, ay, |x, y| [(3.0 * y).sin() + x, (x * y).exp()]);
    let s = SplineY::new(&t, [0.3, 0.0], |_| 1.0);
    let mut worst = 0.0f64;
    for k in 0..64 {
        let xs: [f32; 8] =
            core::array::from_fn(|l| ((k * 8 + l) as f32 * 0.618).fract() * 1.2 - 0.1);
        let ys: [f32; 8] =
            core::array::from_fn(|l| ((k * 8 + l) as f32 * 0.414).fract() * 1.2 - 0.1);
        let lanes = s.lookup(f32x8::from(xs), f32x8::from(ys));
        for l in 0..8 {
            let want = s.lookup(xs[l] as f64, ys[l] as f64);
            let scalar = s.lookup(xs[l], ys[l]);
            for c in 0..2 {
                let got = lanes[c].lane(l);
                worst = worst.max((got - want[c]).abs());
                assert_eq!(got, scalar[c] as f64, "lane {l} channel {c}");
            }
        }
    }
    assert!(worst < 2e-6, "{worst}");
}
