//! The project's own LTC fit of the GGX lobe (height-correlated Smith,
//! F = 1), loaded from `core/data/ltc_ggx.bin`, which `specula fit-ltc`
//! writes (src/fit_ltc.rs; rerun it to regenerate), and its use on a
//! polygon \[Heitz16\].
//!
//! **The lobe and its transform.** Per (α, view), with the view in the
//! local xz-plane (x ≥ 0), the normalized lobe f(wi, wo) cos θi / n is
//! approximated by the clamped cosine D_o = max(0, z)/π pushed through
//!
//! M = [[a, 0, b], [0, c, 0], [d, 0, 1]]:  D(ω) = D_o(M⁻¹ω/|M⁻¹ω|) |det M⁻¹| / |M⁻¹ω|³
//!
//! (the general isotropic LTC, four degrees of freedom). Its integral over
//! a polygon is the form factor of the polygon transformed by M⁻¹ and
//! clipped to the cosine's horizon (polygon.rs). Where d ≠ 0 that horizon
//! is tilted from the surface's, and D has a little mass below the
//! surface: the fit (src/fit_ltc.rs) measures its error over the whole
//! sphere, that mass included, so it fits exactly what the runtime
//! computes. (A fit with d = 0, which keeps D above the surface, was
//! tried: its L1 error was larger at every cell probed, 0.048 against
//! 0.012 at α = 0.1, μo = 0.9, and 0.29 against 0.26 at μo = 0.2.)
//!
//! **The lobe's correction.** A transformed cosine D follows the lobe p
//! only roughly away from its peak, so under a small light (whose
//! integral is about p(ω) times its solid angle) the plain LTC value is
//! off by D(ω)/p(ω), and that error scatters from node to node with the
//! fit. Where the transform stands
//! for a GGX lobe (`lobe`), the integral I = ∫_P D is multiplied by
//!
//!   1 + w (r − 1),  r ≈ p(ω̄) / D(ω̄),  w = max(0, 1 − 2 |F|)²,
//!
//! where F is the vector form factor of the mapped, clipped polygon
//! (polygon.rs) and ω̄ the direction it points to, mapped back by M: the
//! D-weighted mean direction of the polygon to first order. For a polygon
//! small against the lobe, ∫_P p ≈ r ∫_P D with an error of second order
//! in its size; w fades the correction out as the polygon fills more of
//! the cosine (|F| → 1 for the whole hemisphere), where I is already the
//! normalized lobe's share and a ratio at one direction would not stand
//! for the polygon; w is squared so that a growing polygon never gets
//! darker. The ratio q = p(ω̄)/D(ω̄) grows without bound as ω̄ nears the
//! horizon, so r is q bent softly into [1/4, 4]: q on [1/2, 2], 4 − 4/q
//! above, 1/(4 − 4q) below, slope-continuous at both knees (a hard clamp
//! would put a corner in the view sweep where q crosses it). p is
//! the lobe with F = 1 divided by the table's n, with height-correlated
//! Smith (the fitted lobe) or separable Smith
//! (`LtcGgx::with_separable_smith`); D(ω̄) comes from the mapped
//! direction's length (the transform's Jacobian). Only isotropic GGX
//! lobes are corrected: anisotropic ones (disney/polygons.rs stretches the
//! transform, or Disney's α beyond 1) and other cosines (Disney's
//! clearcoat fit, ltc/coat.rs) are not; the glTF clearcoat, a GGX lobe
//! about its own normal, is.
//!
//! **Measured error**: core/tests/ltc_ggx.rs measures the table against
//! the reference as a fraction of n over many polygons and views, and per
//! pixel under a small light (small_light.rs); the figures are in
//! docs/accuracy.md.
//!
//! **Magnitude and Fresnel.** n(α, μo) = ∫ f cos θi dωi with F = 1 and
//! n_w = ∫ f cos θi (1 − wi·h)⁵ dωi, so that with Schlick's F
//! ∫ f_F cos θi = F0 (n − n_w) + n_w over the hemisphere [Hill and Heitz's
//! second table]; over a polygon both are scaled by the LTC integral.
//!
//! **File format** (`ltc_ggx.bin`): ASCII header lines, the first
//! `specula-ltc 1 NX NY 6`, then `#` comment lines (the command that made
//! it, the axes, the fit's error), then a line `end`; then NX × NY × 6 f32
//! little-endian values, row by row in y (view), x (roughness) inside a
//! row, 6 channels per node: c M⁻¹'s entries m00, m02, m20, m22 (M⁻¹ scaled
//! so that its m11 is 1: the form factor does not see the scale), n, n_w.
//! Axes (table.rs, nodes
//! on the ends of each range):
//! - x = √α over [√ALPHA_MIN, 1] ([`X_AXIS`]), α clamped into it;
//! - y = √(1 − μo) over [0, 1] ([`Y_AXIS`]): about uniform in θo (θo/√2
//!   near the normal, 1 − μo/2 near grazing), so grazing views get as many
//!   nodes as any others.
//!
//! **Interpolation** ([`lookup`], [`Lookup`]). Linear in x. Along y the
//! transform's four channels are read by a cubic B-spline (table.rs,
//! [`SplineY`]) fitted to each column with a small penalty on its third
//! differences ([`SMOOTHING`]; the grazing row held to its node,
//! [`GRAZING_WEIGHT`]). A bilinear lookup bends at every row, and the LTC
//! / reference ratio under a small light then kinks there (a seam on a
//! smooth sphere); a spline through the nodes is C² but bends around the
//! fit's scatter from row to row, putting its curvature at the nodes
//! again. The smoothed spline is C² and damps that scatter (its effect on
//! the errors: docs/accuracy.md, "Seams"). n and n_w are quadratures
//! with no scatter to damp: they take the spline through their nodes
//! (λ = 0; bilinear, they would leave kinks where the correction fades).
//! At the smallest α, n drops steeply on the last row (the lobe's
//! albedo at μo = 0) and the spline rings over the rows before it, above
//! 1 and a little below the nodes; n is held to at most 1 (an albedo),
//! which leaves a corner in n there, and n_w to at least 0.

use crate::brdf::{ShadingFrame, ALPHA_MIN};
use crate::light::PolygonLocal;
use crate::ltc::polygon::{
    form_factor_pair_signed, form_factor_pair_vector, form_factor_signed_mapped,
    form_factor_vector_mapped, sided,
};
use crate::real::Real;
use crate::table::{Axis, Nodes, SplineY, Table2, Warp};
use crate::vec3::V3;
use std::sync::OnceLock;

/// Nodes per axis.
pub const N: usize = 64;
/// Channels per node: m00, m02, m20, m22, n, n_w (module docs).
pub(crate) const CHANNELS: usize = 6;

/// √α: see the module docs.
pub const X_AXIS: Axis = Axis::new(N, 0.031_622_776_601_683_79, 1.0, Warp::Linear, Nodes::Ends);
/// √(1 − μo): see the module docs.
pub const Y_AXIS: Axis = Axis::new(N, 0.0, 1.0, Warp::Linear, Nodes::Ends);

const _: () =
    assert!((0.031_622_776_601_683_79f64 * 0.031_622_776_601_683_79 - ALPHA_MIN as f64) < 1e-9);

/// The first header line's prefix.
pub(crate) const MAGIC: &str = "specula-ltc 1";

/// The committed table.
static DATA: &[u8] = include_bytes!("../../data/ltc_ggx.bin");

/// One fitted cell: the transform's parameters (a, b, c, d) of M, the
/// magnitude n and the Schlick part n_w.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    pub a: f64,
    pub b: f64,
    pub c: f64,
    pub d: f64,
    pub n: f64,
    pub n_w: f64,
}

impl Cell {
    /// The stored channels: c M⁻¹ (m00, m02, m20, m22) with
    /// M⁻¹ = [[1, 0, −b], [0, (a − b d)/c, 0], [−d, 0, a]] / (a − b d).
    pub fn channels(&self) -> [f32; CHANNELS] {
        let k = self.c / (self.a - self.b * self.d);
        [
            k as f32,
            (-self.b * k) as f32,
            (-self.d * k) as f32,
            (self.a * k) as f32,
            self.n as f32,
            self.n_w as f32,
        ]
    }
}

/// The table file's bytes for cells in row order (y outer, x inner), with
/// `comments` (lines without the leading `#`) in the header (format in
/// `ltc::file`).
pub fn encode(cells: &[Vec<Cell>], comments: &[String]) -> Vec<u8> {
    let (nx, ny) = (N, N);
    let cells = cells.iter().flatten().map(|c| c.channels());
    crate::ltc::file::encode(MAGIC, nx, ny, cells, comments)
}

/// Reads a table file (format in `ltc::file`).
pub fn decode(bytes: &[u8]) -> Result<Table2<CHANNELS>, String> {
    crate::ltc::file::decode(bytes, MAGIC, (X_AXIS, Y_AXIS))
}

/// The committed table, decoded once.
pub fn table() -> &'static Table2<CHANNELS> {
    static T: OnceLock<Table2<CHANNELS>> = OnceLock::new();
    // The file is part of the crate and checked by tests; a bad one is a
    // build defect, not an input error.
    T.get_or_init(|| decode(DATA).expect("core/data/ltc_ggx.bin is malformed"))
}

/// The committed table as the runtime reads it (module docs,
/// "Interpolation"), formed once.
pub fn lookup() -> &'static Lookup {
    static S: OnceLock<Lookup> = OnceLock::new();
    S.get_or_init(|| Lookup::new(table()))
}

/// A table as the runtime reads it: the transform's four channels by a
/// smoothed spline along the view, n and n_w by the spline through their
/// nodes (module docs, "Interpolation").
#[derive(Clone, Debug)]
pub struct Lookup(SplineY<CHANNELS>);

impl Lookup {
    /// The lookup of `table` (the committed one or a candidate fit).
    pub fn new(table: &Table2<CHANNELS>) -> Lookup {
        let s = SMOOTHING;
        let last = table.y_axis().n() - 1;
        Lookup(SplineY::new(table, [s, s, s, s, 0.0, 0.0], |j| {
            if j == last {
                GRAZING_WEIGHT
            } else {
                1.0
            }
        }))
    }

    /// The six channels (m00, m02, m20, m22, n, n_w) at x = √α,
    /// y = √(1 − μo), per lane; n held to at most 1 and n_w to at least 0
    /// (module docs, "Interpolation").
    #[inline(always)]
    pub fn get<R: Real>(&self, x: R, y: R) -> [R; CHANNELS] {
        let [m00, m02, m20, m22, n, n_w] = self.0.lookup(x, y);
        [m00, m02, m20, m22, n.min(R::ONE), n_w.max(R::ZERO)]
    }
}

/// The view spline's smoothing λ (table.rs, [`SplineY`]): it damps the
/// fit's scatter from row to row (an alternating one by 1/(1 + 576 λ)),
/// which any spline through the nodes would bend around, and keeps a wave
/// of period eight rows at 93 %.
pub const SMOOTHING: f64 = 0.3;

/// The weight of the last row (μo = 0) in the view spline's fit, the
/// others' being 1. There the transform degenerates (m00 → 0 as the lobe
/// flattens onto the horizon at small α) and, at unit weight, the penalty
/// pulls the spline across zero up to and at that node, turning the
/// transform into a reflection; held near the node, it keeps m00, m22
/// and the determinant positive (core/tests/ltc_ggx.rs sweeps the
/// lookup).
pub const GRAZING_WEIGHT: f64 = 100.0;

/// What a GGX material looks up once per pixel (once for all of its
/// polygon lights): the map from local coordinates into the cosine's,
/// M⁻¹ R(−φo) (the rotation taking the view into the xz-plane, then M⁻¹),
/// as three rows, and the magnitude and Schlick part.
#[derive(Clone, Copy, Debug)]
pub struct LtcGgx<R> {
    /// Rows of M⁻¹ R(−φo): X = rx·v, Y = ry·v, Z = rz·v.
    pub(crate) rx: V3<R>,
    pub(crate) ry: V3<R>,
    pub(crate) rz: V3<R>,
    pub(crate) n: R,
    pub(crate) n_w: R,
    /// The GGX lobe the transform stands for, where it is one (module
    /// docs, "The lobe's correction"); `None` for other cosines (the
    /// coat's) and transforms changed after the lookup (the anisotropic
    /// stretch).
    pub(crate) lobe: Option<Lobe<R>>,
}

/// What the lobe's correction needs of one lookup: the local view, α²,
/// the view's azimuth and the inverse of the table's c M⁻¹.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lobe<R> {
    wo: V3<R>,
    /// μo, floored at [`MU_MIN`].
    mu_o: R,
    a2: R,
    /// √(μo² + α²(1 − μo²)): μo times Smith's Λ-root of the view.
    ao: R,
    cos_phi: R,
    sin_phi: R,
    /// (c M⁻¹)⁻¹'s entries m00, m02, m20, m22 (its m11 is 1).
    inv: [R; 4],
    /// det(c M⁻¹) (positive).
    det: R,
    /// The lobe's Smith term is separable (G1(i) G1(o)) rather than
    /// height-correlated (the fitted one).
    separable: bool,
}

impl<R: Real> LtcGgx<R> {
    /// The lookup at roughness α (any; clamped into the table) and unit
    /// local view `wo` (μo clamped into [0, 1]).
    #[inline(always)]
    pub(crate) fn new(alpha: R, wo: V3<R>) -> LtcGgx<R> {
        let mu = wo.z.clamp(R::ZERO, R::ONE);
        let x = alpha.max(R::ZERO).sqrt();
        let y = (R::ONE - mu).sqrt();
        LtcGgx::from_table(lookup(), alpha, x, y, wo)
    }

    /// The lookup in `table` at x = √α, y = √(1 − μo), with the lobe's
    /// correction for roughness `alpha` (clamped into the table).
    #[inline(always)]
    pub(crate) fn from_table(table: &Lookup, alpha: R, x: R, y: R, wo: V3<R>) -> LtcGgx<R> {
        let [m00, m02, m20, m22, n, n_w] = table.get(x, y);
        let mut l = LtcGgx::from_inverse([m00, m02, m20, m22], n, n_w, wo);
        let alpha = alpha.clamp(R::splat(ALPHA_MIN as f64), R::ONE);
        let a2 = alpha * alpha;
        let mu = wo.z.max(R::splat(MU_MIN));
        let det = m00.mul_add(m22, -(m02 * m20));
        let k = det.rcp();
        l.lobe = Some(Lobe {
            wo,
            mu_o: mu,
            a2,
            ao: (mu * mu).mul_add(R::ONE - a2, a2).sqrt(),
            cos_phi: l.ry.y,
            sin_phi: -l.ry.x,
            inv: [m22 * k, -m02 * k, -m20 * k, m00 * k],
            det,
            separable: false,
        });
        l
    }

    /// The same lookup for a lobe with separable Smith masking (the fit's
    /// transform; the correction toward that lobe).
    #[inline(always)]
    pub(crate) fn with_separable_smith(mut self) -> LtcGgx<R> {
        if let Some(lobe) = &mut self.lobe {
            lobe.separable = true;
        }
        self
    }

    /// The same lookup without the lobe's correction (a transform that no
    /// longer stands for the isotropic GGX lobe).
    #[inline(always)]
    pub(crate) fn without_lobe(mut self) -> LtcGgx<R> {
        self.lobe = None;
        self
    }

    /// Any isotropic LTC fitted with the view in the xz-plane (as this
    /// table's and ltc/coat.rs's cells are): c M⁻¹'s entries m00, m02,
    /// m20, m22 (m11 = 1), the magnitudes n and n_w, turned to the
    /// azimuth of the unit local view `wo`.
    #[inline(always)]
    pub(crate) fn from_inverse(m: [R; 4], n: R, n_w: R, wo: V3<R>) -> LtcGgx<R> {
        let [m00, m02, m20, m22] = m;
        // cos φo, sin φo of the view's azimuth (1, 0 at the normal).
        let r2 = wo.x.mul_add(wo.x, wo.y * wo.y);
        let ok = r2.gt(R::splat(1e-20));
        let inv = r2.max(R::splat(1e-20)).rsqrt();
        let (c, s) = (
            R::select(ok, wo.x * inv, R::ONE),
            R::select(ok, wo.y * inv, R::ZERO),
        );
        // R(−φo) v = (c x + s y, c y − s x, z); then M⁻¹ (m11 = 1).
        LtcGgx {
            rx: V3::new(m00 * c, m00 * s, m02),
            ry: V3::new(-s, c, R::ZERO),
            rz: V3::new(m20 * c, m20 * s, m22),
            n,
            n_w,
            lobe: None,
        }
    }

    /// The same lookup for vertices given in an outer frame in which
    /// `frame` (its axes in outer coordinates) is the lobe's local frame:
    /// each row r becomes r.x t + r.y b + r.z n, so [`LtcGgx::map`] of an
    /// outer vertex equals the map of its coordinates in `frame`.
    #[inline(always)]
    pub(crate) fn in_frame(self, frame: &ShadingFrame<R>) -> LtcGgx<R> {
        let row = |r: V3<R>| frame.t * r.x + frame.b * r.y + frame.n * r.z;
        LtcGgx {
            rx: row(self.rx),
            ry: row(self.ry),
            rz: row(self.rz),
            ..self
        }
    }

    /// `v` (local) in the cosine's coordinates.
    #[inline(always)]
    pub(crate) fn map(&self, v: V3<R>) -> V3<R> {
        V3::new(self.rx.dot(v), self.ry.dot(v), self.rz.dot(v))
    }

    /// ∫ D over the polygon (module docs): the LTC's share of the lobe
    /// that the polygon receives, in [0, 1]. M⁻¹ has a positive
    /// determinant, so the polygon keeps its orientation (its front).
    /// With the lobe's correction where the transform has a lobe (still
    /// in [0, 1]: the integral is at most |F| and r at most 4, so where
    /// the correction acts the product is at most |F| (1 + 3 (1 − 2 |F|)²)
    /// ≤ 1/2).
    #[inline(always)]
    pub fn integral(&self, poly: &PolygonLocal<R>) -> R {
        match &self.lobe {
            Some(lobe) => {
                let f = form_factor_vector_mapped(poly.vertices(), |v| self.map(v));
                lobe.corrected(self.n, f, poly.two_sided)
            }
            None => sided(
                form_factor_signed_mapped(poly.vertices(), |v| self.map(v)),
                poly.two_sided,
            ),
        }
    }

    /// The polygon's form factor (sided) and [`LtcGgx::integral`], in
    /// one pass where the polygon needs no clipping
    /// ([`form_factor_pair_signed`], [`form_factor_pair_vector`]).
    #[inline(always)]
    pub(crate) fn form_factor_and_integral(&self, poly: &PolygonLocal<R>) -> (R, R) {
        match &self.lobe {
            Some(lobe) => {
                let (ff, f) = form_factor_pair_vector(poly.vertices(), |v| self.map(v));
                (
                    sided(ff, poly.two_sided),
                    lobe.corrected(self.n, f, poly.two_sided),
                )
            }
            None => {
                let (ff, spec) = form_factor_pair_signed(poly.vertices(), |v| self.map(v));
                (sided(ff, poly.two_sided), sided(spec, poly.two_sided))
            }
        }
    }

    /// F0 (n − n_w) + n_w: the lobe's albedo under Schlick's F.
    #[inline(always)]
    pub(crate) fn schlick_albedo(&self, f0: R) -> R {
        f0.mul_add(self.n - self.n_w, self.n_w)
    }
}

impl<R: Real> Lobe<R> {
    /// The LTC integral sided(f.z) of a polygon whose mapped vector form
    /// factor is `f`, times 1 + w (r − 1) (module docs, "The lobe's
    /// correction"); `n` is the lookup's albedo.
    #[inline(always)]
    fn corrected(&self, n: R, f: V3<R>, two_sided: bool) -> R {
        let i = sided(f.z, two_sided);
        // F's direction u, turned toward the polygon's lit side (its back
        // for a two-sided light seen from behind), in the cosine's space;
        // ω' = R(φo) (c M⁻¹)⁻¹ u is the direction in local coordinates.
        let len2 = f.length_squared();
        let inv_len = len2.max(R::splat(TINY)).rsqrt();
        let len = len2 * inv_len;
        let u = f * R::select(f.z.lt(R::ZERO), -inv_len, inv_len);
        let [i00, i02, i20, i22] = self.inv;
        let tx = i00.mul_add(u.x, i02 * u.z);
        let tz = i20.mul_add(u.x, i22 * u.z);
        let (c, s) = (self.cos_phi, self.sin_phi);
        let w = V3::new(c.mul_add(tx, -(s * u.y)), s.mul_add(tx, c * u.y), tz);
        let l2 = w.length_squared().max(R::splat(TINY));
        let inv_l = l2.rsqrt();
        let l3 = l2 * l2 * inv_l;
        // D at ω̂ = ω'/|ω'| (Jacobian of the transform): (u.z/π)
        // det(c M⁻¹) |ω'|³.
        // The lobe there (F = 1): f cos θi = D(h) V μi, with the half
        // vector h = ω̂ + ωo unnormalized (|h|² = h2), so D(h) = α² h2² /
        // (π (h.z² (α² − 1) + h2)²), and height-correlated Smith's V = 1 /
        // (2 (μi ao + μo ai)) or separable Smith's 1 / ((μo + ao)(μi + ai)).
        // r = f cos θi / (n D): one division, π cancelling.
        let wi = w * inv_l;
        let mu_i = wi.z.max(R::ZERO);
        let mu_o = self.mu_o;
        let h = wi + self.wo;
        let h2 = h.length_squared();
        let a2 = self.a2;
        let den = (h.z * h.z).mul_add(a2 - R::ONE, h2);
        let ai = (mu_i * mu_i).mul_add(R::ONE - a2, a2).sqrt();
        let vis_den = if self.separable {
            (mu_o + self.ao) * (mu_i + ai)
        } else {
            R::splat(2.0) * mu_i.mul_add(self.ao, mu_o * ai)
        };
        let num = a2 * h2 * h2 * mu_i;
        let den = den * den * vis_den * n * u.z * self.det * l3;
        let valid = len2.gt(R::splat(TINY)) & den.gt(R::splat(TINY)) & den.lt(R::splat(1.0 / TINY));
        let r = R::select(valid, soft_bound(num, den), R::ONE);
        let fade = R::splat(FADE).mul_add(-len, R::ONE).max(R::ZERO);
        let weight = fade * fade;
        i * weight.mul_add(r - R::ONE, R::ONE)
    }
}

/// Floor of the correction's squared lengths and denominators.
const TINY: f64 = 1e-30;
/// Smallest μo the lobe is evaluated at, by the correction here and by
/// the fit (src/fit_ltc.rs).
pub const MU_MIN: f64 = 1e-3;
/// The knee k of the correction's soft bound ([`soft_bound`]).
const KNEE: f64 = 2.0;

/// The correction's ratio r from q = num / den (num ≥ 0, den > 0): q on
/// [1/k, k], 2k − k²/q above, 1/(2k − k² q) below, for the knee k =
/// [`KNEE`]; r lies in [1/(2k), 2k] (1/(2k) at num = 0) with a continuous
/// slope. Written as one quotient a / b: above the knee (2k num − k² den)
/// / num, below it den / (2k den − k² num), both denominators positive
/// where they are taken.
#[inline(always)]
pub(crate) fn soft_bound<R: Real>(num: R, den: R) -> R {
    let (k, k2, bound) = (R::splat(KNEE), R::splat(KNEE * KNEE), R::splat(2.0 * KNEE));
    let above = num.gt(k * den);
    let below = (k * num).lt(den);
    let a = R::select(
        above,
        bound.mul_add(num, -(k2 * den)),
        R::select(below, den, num),
    );
    let b = R::select(
        above,
        num,
        R::select(below, bound.mul_add(den, -(k2 * num)), den),
    );
    a / b
}
/// The correction's weight, max(0, 1 − FADE |F|)²: full for small parts,
/// none from |F| = 1/FADE on, slope-continuous there, and squared so that
/// a growing polygon never gets darker (with I ≈ |F| and r ≤ 4,
/// I (1 + w (r − 1)) increases with |F|; a linear fade does not).
const FADE: f64 = 2.0;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::f32x8;

    /// The documented piecewise map, written out.
    fn map(q: f64) -> f64 {
        if q > 2.0 {
            4.0 - 4.0 / q
        } else if q < 0.5 {
            1.0 / (4.0 - 4.0 * q)
        } else {
            q
        }
    }

    #[test]
    fn the_soft_bound_is_the_documented_map_continuous_in_value_and_slope() {
        for (num, den) in [(0.0, 1.0), (0.5, 1.0), (2.0, 1.0), (1e6, 1.0), (3.0, 1e-3)] {
            let q = num / den;
            assert!(
                (soft_bound(num, den) - map(q)).abs() < 1e-12 * map(q),
                "q {q}"
            );
        }
        assert_eq!(soft_bound(0.0, 1.0), 0.25);
        let e = 1e-6;
        for knee in [0.5, 2.0] {
            let (l, r) = (soft_bound(knee - e, 1.0), soft_bound(knee + e, 1.0));
            assert!((r - l - 2.0 * e).abs() < 1e-9, "slope at the knee {knee}");
        }
        let mut last = 0.0;
        for k in 0..2000 {
            let q = 1e-3 * 1.01f64.powi(k);
            let r = soft_bound(q, 1.0);
            assert!((0.25..=4.0).contains(&r) && r > last, "q {q}: {r}");
            assert!((r - map(q)).abs() < 1e-12 * map(q), "q {q}");
            last = r;
            let lanes = soft_bound(f32x8::splat(q as f32), f32x8::splat(1.0));
            assert!(
                (lanes.lane(3) - map(q)).abs() < 1e-6 * map(q),
                "f32x8 q {q}"
            );
        }
    }
}
