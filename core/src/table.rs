//! Tables of smooth functions over one or two axes, C channels of f32 per
//! node, looked up for f64, f32 and f32x8 from one source.
//!
//! An [`Axis`] maps a user coordinate x to a node position in four
//! documented steps, all in lane arithmetic:
//!
//! 1. t = (x − lo)/(hi − lo), clamped to [0, 1] (a NaN x becomes t = 0,
//!    the [`Real::clamp`] rule, so every index stays in range);
//! 2. u = warp(t): [`Warp::Linear`] u = t, [`Warp::Sqrt`] u = √t (nodes
//!    dense near t = 0, e.g. grazing μ or small α), [`Warp::Square`] u = t²
//!    (dense near t = 1);
//! 3. node position p: [`Nodes::Ends`] p = u (n − 1) (first and last node
//!    on the ends of the range), [`Nodes::Centres`] p = u n − ½ clamped to
//!    [0, n − 1] (texel centres u_i = (i + ½)/n, constant past the outer
//!    centres);
//! 4. lower node i = min(⌊p⌋, n − 2) and the weight w of node i + 1:
//!    [`Interp::Warped`] w = p − i (linear in u, the usual choice), or
//!    [`Interp::Linear`] w = (t − t_i)/(t_{i+1} − t_i) clamped to [0, 1],
//!    linear in the user coordinate between nodes t_i = warp⁻¹(u_i) (for a
//!    closed-form integral of the interpolant in x, as Kulla–Conty's E_avg).
//!
//! The value is v = v_i + (v_{i+1} − v_i) w per channel (fused multiply-add),
//! and for two axes the same along x on the rows y_j and y_{j+1}, then along
//! y. Node values are read with [`Real::gather`]; the f64 lookup evaluates
//! exactly this interpolant on the stored f32 values, which the tests check
//! against a plainly written one.
//! [`SplineY`] reads a 2-D table by a cubic B-spline along y instead,
//! for functions whose kinks at the rows would show.
//!
//! [`Table1::build`] and [`Table2::build`] evaluate a closure at the nodes,
//! so a round trip (lookup at a node == the closure there, to f32) is a test.

use crate::quadrature::GaussLegendre;
use crate::real::{Constant, Real};

/// How an axis spaces its nodes over t ∈ [0, 1]; see the module docs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Warp {
    /// u = t.
    Linear,
    /// u = √t: nodes dense near t = 0.
    Sqrt,
    /// u = t²: nodes dense near t = 1. Interpolated in u it is only first
    /// order next to t = 0 (du/dt = 0 there); use [`Interp::Linear`] if
    /// that end matters.
    Square,
}

/// Where the n nodes sit in u ∈ [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Nodes {
    /// u_i = i/(n − 1): nodes on both ends.
    Ends,
    /// u_i = (i + ½)/n: texel centres.
    Centres,
}

/// What the weight between two nodes is linear in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interp {
    /// The warped coordinate u.
    Warped,
    /// The user coordinate x.
    Linear,
}

/// One table axis; see the module docs. Made by [`Axis::new`] only, so
/// that the constants its lookups broadcast always follow its nodes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Axis {
    /// Number of nodes, ≥ 2.
    n: usize,
    lo: f64,
    hi: f64,
    pub warp: Warp,
    nodes: Nodes,
    pub interp: Interp,
    /// What lookups broadcast, formed once here: lookups run per pixel,
    /// and an f64 division or an f64-to-f32 rounding there is not free.
    /// lo, 1 / (hi − lo), the u spacing of the nodes, n, n − 1 and n − 2.
    lo_c: Constant,
    inv_span: Constant,
    du: Constant,
    count: Constant,
    last: Constant,
    last_but_one: Constant,
}

impl Warp {
    #[inline(always)]
    fn apply<R: Real>(self, t: R) -> R {
        match self {
            Warp::Linear => t,
            Warp::Sqrt => t.sqrt(),
            Warp::Square => t * t,
        }
    }

    #[inline(always)]
    fn invert<R: Real>(self, u: R) -> R {
        match self {
            Warp::Linear => u,
            Warp::Sqrt => u * u,
            Warp::Square => u.sqrt(),
        }
    }
}

impl Axis {
    /// An axis of `n` nodes over [lo, hi], interpolated in the warped
    /// coordinate.
    pub const fn new(n: usize, lo: f64, hi: f64, warp: Warp, nodes: Nodes) -> Axis {
        assert!(n >= 2, "an axis needs two nodes to interpolate");
        assert!(hi > lo, "an axis needs hi > lo");
        Axis {
            n,
            lo,
            hi,
            warp,
            nodes,
            interp: Interp::Warped,
            lo_c: Constant::new(lo),
            inv_span: Constant::new(1.0 / (hi - lo)),
            du: Constant::new(match nodes {
                Nodes::Ends => 1.0 / (n - 1) as f64,
                Nodes::Centres => 1.0 / n as f64,
            }),
            count: Constant::new(n as f64),
            last: Constant::new((n - 1) as f64),
            last_but_one: Constant::new((n - 2) as f64),
        }
    }

    /// Number of nodes.
    pub const fn n(&self) -> usize {
        self.n
    }

    /// The start of the range the nodes cover.
    pub const fn lo(&self) -> f64 {
        self.lo
    }

    /// The end of the range the nodes cover.
    pub const fn hi(&self) -> f64 {
        self.hi
    }

    /// Where the nodes sit.
    pub const fn nodes(&self) -> Nodes {
        self.nodes
    }

    /// The same axis, interpolated linearly in the user coordinate.
    pub const fn linear_between_nodes(self) -> Axis {
        Axis {
            interp: Interp::Linear,
            ..self
        }
    }

    /// u of node i, per lane (i integral).
    #[inline(always)]
    fn node_u<R: Real>(&self, i: R) -> R {
        match self.nodes {
            Nodes::Ends => i * R::constant(self.du),
            Nodes::Centres => (i + R::HALF) * R::constant(self.du),
        }
    }

    /// The user coordinate of node `i`.
    pub fn node(&self, i: usize) -> f64 {
        let t = self.warp.invert(self.node_u(i as f64));
        self.lo + (self.hi - self.lo) * t
    }

    /// Lower node index (as an integral lane value) and the weight of the
    /// next node at x: steps 1–4 of the module docs.
    #[inline(always)]
    pub(crate) fn locate<R: Real>(&self, x: R) -> (R, R) {
        let last = R::constant(self.last);
        let t = ((x - R::constant(self.lo_c)) * R::constant(self.inv_span)).clamp(R::ZERO, R::ONE);
        let u = self.warp.apply(t);
        let p = match self.nodes {
            Nodes::Ends => u * last,
            Nodes::Centres => u
                .mul_add(R::constant(self.count), -R::HALF)
                .clamp(R::ZERO, last),
        };
        let i = p.floor().min(R::constant(self.last_but_one));
        let w = match self.interp {
            Interp::Warped => p - i,
            Interp::Linear => {
                let t0 = self.warp.invert(self.node_u(i));
                let t1 = self.warp.invert(self.node_u(i + R::ONE));
                ((t - t0) / (t1 - t0)).clamp(R::ZERO, R::ONE)
            }
        };
        (i, w)
    }
}

/// v0 + (v1 − v0) w.
#[inline(always)]
fn lerp<R: Real>(v0: R, v1: R, w: R) -> R {
    (v1 - v0).mul_add(w, v0)
}

/// The values at `r` and `r + step` of `data`, interpolated by `w`.
#[inline(always)]
fn lerp_at<R: Real>(data: &[f32], r: R, step: R, w: R) -> R {
    lerp(R::gather(data, r), R::gather(data, r + step), w)
}

/// Largest table an f32 lane can index exactly (integers up to 2²⁴).
const MAX_LEN: usize = 1 << 24;

/// A 1-D table of C channels: value c of node i at `data[i * C + c]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Table1<const C: usize> {
    axis: Axis,
    data: Vec<f32>,
}

impl<const C: usize> Table1<C> {
    /// Evaluates `f` at every node (rounded to f32).
    pub fn build(axis: Axis, mut f: impl FnMut(f64) -> [f64; C]) -> Table1<C> {
        Self::from_nodes(
            axis,
            (0..axis.n)
                .map(|i| f(axis.node(i)).map(|v| v as f32))
                .collect(),
        )
    }

    /// A table from its node values, one `[f32; C]` per node.
    pub(crate) fn from_nodes(axis: Axis, values: Vec<[f32; C]>) -> Table1<C> {
        assert_eq!(values.len(), axis.n, "one value per node");
        assert!(axis.n * C <= MAX_LEN, "table too large for f32 indices");
        Table1 {
            axis,
            data: values.into_iter().flatten().collect(),
        }
    }

    /// The stored values of node i.
    pub fn node_value(&self, i: usize) -> [f32; C] {
        core::array::from_fn(|c| self.data[i * C + c])
    }

    /// The interpolant at x, per lane and channel (module docs).
    #[inline(always)]
    pub fn lookup<R: Real>(&self, x: R) -> [R; C] {
        let (i, w) = self.axis.locate(x);
        let base = i * R::splat(C as f64);
        // Loops, not closures, here and in the other lookups: a closure is
        // a function of its own, compiled without the target features of
        // a caller such as the AVX-512 packet pairs' (raster/src/packet_pairs.rs).
        let mut out = [R::ZERO; C];
        for (c, o) in out.iter_mut().enumerate() {
            let v0 = R::gather(&self.data, base + R::splat(c as f64));
            let v1 = R::gather(&self.data, base + R::splat((C + c) as f64));
            *o = lerp(v0, v1, w);
        }
        out
    }

    /// ∫ over [lo, hi] of lookup(x) g(x) dx, per channel, in f64: 4-point
    /// Gauss–Legendre in u on every node interval (and on the clamped
    /// stretches past outer texel centres), with dx = (hi − lo) dt/du du.
    /// Exact when the interpolant times g dx/du is a polynomial of degree
    /// ≤ 7 in u on each interval: e.g. √ warp, linear in x or in u, g(x) = x.
    pub fn integrate(&self, g: impl Fn(f64) -> f64) -> [f64; C] {
        let rule = GaussLegendre::new(4);
        let a = &self.axis;
        let span = a.hi - a.lo;
        let mut breaks: Vec<f64> = (0..a.n).map(|i| a.node_u(i as f64)).collect();
        breaks.insert(0, 0.0);
        breaks.push(1.0);
        let dt_du = |u: f64| match a.warp {
            Warp::Linear => 1.0,
            Warp::Sqrt => 2.0 * u,
            Warp::Square => 0.5 / u.max(1e-300).sqrt(),
        };
        let mut s = [0.0; C];
        for seg in breaks.windows(2) {
            if seg[1] <= seg[0] {
                continue;
            }
            let part = rule.integrate(seg[0], seg[1], |u| {
                let x = a.lo + span * a.warp.invert(u);
                let k = g(x) * span * dt_du(u);
                self.lookup(x).map(|v| v * k)
            });
            for c in 0..C {
                s[c] += part[c];
            }
        }
        s
    }
}

/// A 2-D table of C channels: value c of node (i along x, j along y) at
/// `data[(j * nx + i) * C + c]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Table2<const C: usize> {
    x: Axis,
    y: Axis,
    data: Vec<f32>,
}

impl<const C: usize> Table2<C> {
    /// Evaluates `f(x, y)` at every node (rounded to f32), row by row in y.
    pub fn build(x: Axis, y: Axis, mut f: impl FnMut(f64, f64) -> [f64; C]) -> Table2<C> {
        let rows: Vec<Vec<[f32; C]>> = (0..y.n)
            .map(|j| {
                (0..x.n)
                    .map(|i| f(x.node(i), y.node(j)).map(|v| v as f32))
                    .collect()
            })
            .collect();
        Self::from_rows(x, y, rows)
    }

    /// A table from its rows (one per y node, each one value per x node).
    pub(crate) fn from_rows(x: Axis, y: Axis, rows: Vec<Vec<[f32; C]>>) -> Table2<C> {
        assert_eq!(rows.len(), y.n, "one row per y node");
        assert!(rows.iter().all(|r| r.len() == x.n), "one value per x node");
        assert!(x.n * y.n * C <= MAX_LEN, "table too large for f32 indices");
        Table2 {
            x,
            y,
            data: rows.into_iter().flatten().flatten().collect(),
        }
    }

    /// The stored values of node (i, j).
    pub fn node_value(&self, i: usize, j: usize) -> [f32; C] {
        core::array::from_fn(|c| self.data[(j * self.x.n + i) * C + c])
    }

    /// The y axis.
    pub fn y_axis(&self) -> Axis {
        self.y
    }

    /// The bilinear interpolant at (x, y), per lane and channel.
    #[inline(always)]
    pub fn lookup<R: Real>(&self, x: R, y: R) -> [R; C] {
        let (i, wx) = self.x.locate(x);
        let (j, wy) = self.y.locate(y);
        let c_ = R::splat(C as f64);
        let row = R::constant(self.x.count) * c_;
        let base = j.mul_add(row, i * c_);
        let mut out = [R::ZERO; C];
        for (c, o) in out.iter_mut().enumerate() {
            let b = base + R::splat(c as f64);
            let v00 = R::gather(&self.data, b);
            let v10 = R::gather(&self.data, b + c_);
            let v01 = R::gather(&self.data, b + row);
            let v11 = R::gather(&self.data, b + row + c_);
            *o = lerp(lerp(v00, v10, wx), lerp(v01, v11, wx), wy);
        }
        out
    }

    /// The 1-D table along x at a fixed y: each x node's value interpolated
    /// along y in f64 (as [`Table2::lookup`] does), rounded to f32. The
    /// slice's lookup then equals this table's lookup at that y up to that
    /// rounding.
    pub fn slice_y(&self, y: f64) -> Table1<C> {
        let (j, w) = self.y.locate(y);
        let j = j as usize;
        let values = (0..self.x.n)
            .map(|i| {
                let (a, b) = (self.node_value(i, j), self.node_value(i, j + 1));
                core::array::from_fn(|c| lerp(a[c] as f64, b[c] as f64, w) as f32)
            })
            .collect();
        Table1::from_nodes(self.x, values)
    }

    /// As [`Table2::slice_y`], but each x node's column is interpolated
    /// along y by the Catmull–Rom cubic in the node coordinate through the
    /// four nearest rows (the outer ones repeated at the ends):
    ///
    /// v = v₁ + ½ w (v₂ − v₀ + w (2v₀ − 5v₁ + 4v₂ − v₃ + w (3(v₁ − v₂) + v₃ − v₀)))
    ///
    /// For per-material slices, where the cost is paid once and a function
    /// curved along y (Kulla–Conty's E at small α) needs more than a lerp.
    /// It can overshoot the node values; callers clamp if that matters.
    pub fn slice_y_cubic(&self, y: f64) -> Table1<C> {
        let (j, w) = self.y.locate(y);
        let j = j as usize;
        let row = |k: isize| k.clamp(0, self.y.n as isize - 1) as usize;
        let values = (0..self.x.n)
            .map(|i| {
                let v = |k: isize| self.node_value(i, row(j as isize + k));
                let (v0, v1, v2, v3) = (v(-1), v(0), v(1), v(2));
                core::array::from_fn(|c| {
                    let [p0, p1, p2, p3] = [v0[c], v1[c], v2[c], v3[c]].map(|x| x as f64);
                    let t = 3.0 * (p1 - p2) + p3 - p0;
                    (p1 + 0.5 * w * (p2 - p0 + w * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3 + w * t)))
                        as f32
                })
            })
            .collect();
        Table1::from_nodes(self.x, values)
    }
}

/// A 2-D table interpolated linearly along x and by a uniform cubic
/// B-spline along y: the value is C² in the y axis's node coordinate p
/// (in y itself where the axis is [`Warp::Linear`]), so a function of it
/// has no kinks at the rows (a bilinear table's value bends at every row).
///
/// Each x node's column of n values f_0 … f_{n−1} becomes n + 2 spline
/// coefficients c_0 … c_{n+1} (stored row k is the coefficient of the
/// B-spline centred on node k − 1), whose value at node j is
/// s_j = (c_j + 4 c_{j+1} + c_{j+2}) / 6. They are solved in f64 from
///
/// - `smoothing` λ = 0 (per channel): s_j = f_j at every node, with not-a-knot ends (the
///   third derivative continuous at nodes 1 and n − 2:
///   c_0 − 4c_1 + 6c_2 − 4c_3 + c_4 = 0 and its mirror), which assume
///   nothing of the function's slope or curvature at the ends;
/// - λ > 0: the least squares Σ_j v_j (s_j − f_j)² + λ Σ_k (Δ³c_k)², a
///   penalized spline with node weights v_j (`weight`). Quadratics pass
///   unchanged (Δ³ of their coefficients is zero); with unit weights a
///   scatter alternating from node to node is scaled by 1/(1 + 576 λ)
///   away from the ends (Δ³ of (−1)^k is 8 and the node value of a unit
///   alternating c is 1/3), while a wave of period P rows, ω = 2π/P, is
///   scaled by 1/(1 + λ (2 sin(ω/2))⁶ / ((2 + cos ω)/3)²): nearly 1 for
///   slow trends. λ is meant to be of order 0.01–10: as λ → 0 the system
///   becomes singular (two coefficients are then fixed by nothing), it
///   does not tend to the λ = 0 spline.
///
/// Between nodes j and j + 1 at weight w (the y axis's `locate`) the value
/// is Σ_k b_k(w) c_{j+k}, k = 0 … 3, with the cubic B-spline's weights
/// b = ((1 − w)³, 3w³ − 6w² + 4, −3w³ + 3w² + 3w + 1, w³) / 6. The x axis
/// and the clamping are [`Table2`]'s. Unlike a bilinear lookup, the value
/// can leave the range of the nodes around it.
#[derive(Clone, Debug, PartialEq)]
pub struct SplineY<const C: usize> {
    x: Axis,
    y: Axis,
    /// Coefficient c of column i, stored row k at `data[(k * nx + i) * C + c]`.
    data: Vec<f32>,
}

impl<const C: usize> SplineY<C> {
    /// The spline of `table`'s columns with smoothing λ ≥ 0 per channel
    /// and, where λ > 0, node j's weight `weight(j)` > 0 (type docs). The
    /// y axis needs four nodes and interpolation weights linear in its node
    /// coordinate ([`Interp::Warped`]).
    pub fn new(
        table: &Table2<C>,
        smoothing: [f64; C],
        weight: impl Fn(usize) -> f64,
    ) -> SplineY<C> {
        let (nx, ny) = (table.x.n, table.y.n);
        assert!(ny >= 4, "a cubic spline along y needs four nodes");
        assert!(
            table.y.interp == Interp::Warped,
            "a uniform spline needs weights linear in the node coordinate"
        );
        let m = ny + 2;
        assert!(m * nx * C <= MAX_LEN, "table too large for f32 indices");
        let mut data = vec![0.0f32; m * nx * C];
        for (c, &lambda) in smoothing.iter().enumerate() {
            let column = |j: usize, i: usize| table.node_value(i, j)[c] as f64;
            let coefficients = fit_columns(nx, ny, lambda, &weight, column);
            for (row, values) in coefficients.chunks_exact(nx).enumerate() {
                for (i, v) in values.iter().enumerate() {
                    data[(row * nx + i) * C + c] = *v as f32;
                }
            }
        }
        SplineY {
            x: table.x,
            y: table.y,
            data,
        }
    }

    /// The interpolant at (x, y), per lane and channel (type docs).
    #[inline(always)]
    pub fn lookup<R: Real>(&self, x: R, y: R) -> [R; C] {
        let (i, wx) = self.x.locate(x);
        let (j, w) = self.y.locate(y);
        let c_ = R::splat(C as f64);
        let row = R::constant(self.x.count) * c_;
        let base = j.mul_add(row, i * c_);
        let sixth = R::splat(1.0 / 6.0);
        let v = R::ONE - w;
        let w2 = w * w;
        let b0 = v * v * v * sixth;
        let b3 = w2 * w * sixth;
        let b1 = (w2 * (w - R::splat(2.0))).mul_add(R::HALF, R::splat(2.0 / 3.0));
        let b2 = R::ONE - b0 - b1 - b3;
        let mut out = [R::ZERO; C];
        for (c, o) in out.iter_mut().enumerate() {
            let b = base + R::splat(c as f64);
            let (r1, r2) = (b + row, b + row + row);
            let (v0, v1) = (
                lerp_at(&self.data, b, c_, wx),
                lerp_at(&self.data, r1, c_, wx),
            );
            let v2 = lerp_at(&self.data, r2, c_, wx);
            let v3 = lerp_at(&self.data, r2 + row, c_, wx);
            *o = v0.mul_add(b0, v1 * b1) + v2.mul_add(b2, v3 * b3);
        }
        out
    }
}

/// The n + 2 spline coefficients of each of `nx` columns of `ny` node
/// values `f(j, i)` (node j of column i), with smoothing `lambda` and node
/// weights ([`SplineY`]): row-major, coefficient row by column.
fn fit_columns(
    nx: usize,
    ny: usize,
    lambda: f64,
    weight: impl Fn(usize) -> f64,
    f: impl Fn(usize, usize) -> f64,
) -> Vec<f64> {
    assert!(lambda >= 0.0, "smoothing is a non-negative weight");
    let m = ny + 2;
    // A c = b for every column at once: A is m × m, b m × nx.
    const NODE: [f64; 3] = [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0];
    let mut a = vec![0.0f64; m * m];
    let mut b = vec![0.0f64; m * nx];
    if lambda == 0.0 {
        const NOT_A_KNOT: [f64; 5] = [1.0, -4.0, 6.0, -4.0, 1.0];
        a[..5].copy_from_slice(&NOT_A_KNOT);
        a[m * m - 5..].copy_from_slice(&NOT_A_KNOT);
        for j in 0..ny {
            a[(j + 1) * m + j..(j + 1) * m + j + 3].copy_from_slice(&NODE);
            for i in 0..nx {
                b[(j + 1) * nx + i] = f(j, i);
            }
        }
    } else {
        // The normal equations (BᵀVB + λ DᵀD) c = BᵀV f, B the node rows,
        // V the node weights and D the third differences.
        const D3: [f64; 4] = [-1.0, 3.0, -3.0, 1.0];
        for j in 0..ny {
            let v = weight(j);
            assert!(v > 0.0, "node weights are positive");
            for (p, bp) in NODE.iter().enumerate() {
                for (q, bq) in NODE.iter().enumerate() {
                    a[(j + p) * m + j + q] += v * bp * bq;
                }
                for i in 0..nx {
                    b[(j + p) * nx + i] += v * bp * f(j, i);
                }
            }
        }
        for j in 0..m - 3 {
            for (p, dp) in D3.iter().enumerate() {
                for (q, dq) in D3.iter().enumerate() {
                    a[(j + p) * m + j + q] += lambda * dp * dq;
                }
            }
        }
    }
    solve_in_place(&mut a, &mut b, m, nx);
    b
}

/// Solves A X = B in place by Gaussian elimination with partial pivoting:
/// A is m × m and B m × k, both row-major; X overwrites B.
fn solve_in_place(a: &mut [f64], b: &mut [f64], m: usize, k: usize) {
    for col in 0..m {
        let pivot = (col..m)
            .max_by(|&p, &q| a[p * m + col].abs().total_cmp(&a[q * m + col].abs()))
            .unwrap_or(col);
        if pivot != col {
            for t in 0..m {
                a.swap(col * m + t, pivot * m + t);
            }
            for t in 0..k {
                b.swap(col * k + t, pivot * k + t);
            }
        }
        let d = a[col * m + col];
        assert!(d != 0.0, "singular spline system");
        for r in col + 1..m {
            let f = a[r * m + col] / d;
            if f == 0.0 {
                continue;
            }
            for t in col..m {
                a[r * m + t] -= f * a[col * m + t];
            }
            for t in 0..k {
                b[r * k + t] -= f * b[col * k + t];
            }
        }
    }
    for col in (0..m).rev() {
        let d = a[col * m + col];
        for t in 0..k {
            let mut s = b[col * k + t];
            for r in col + 1..m {
                s -= a[col * m + r] * b[r * k + t];
            }
            b[col * k + t] = s / d;
        }
    }
}
