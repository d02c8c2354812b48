//! The project's own LTC fit of the Disney clearcoat lobe, loaded from
//! `core/data/ltc_coat.bin`, which `specula fit-ltc-coat` writes
//! (src/fit_ltc_coat.rs; rerun it to regenerate) \[Heitz16\].
//!
//! **The lobe.** f_r μi with f_r = F_r D_r G_r / (4 μi μo) (models/disney/
//! without its weight ¼ clearcoat): D_r GTR1 at α ∈ [0.001, 0.1], G_r
//! separable Smith GGX at α = 0.25, F_r Schlick with F0 = 0.04. Every
//! constant but α is fixed, so the Fresnel factor is fitted into the
//! shape (no split), and the table runs over (α, μo) alone.
//!
//! **Why three cosines.** GTR1's tail falls as 1/sin²θh; a linearly
//! transformed cosine's, like GGX's, as 1/sin⁴: GTR1's D cos θh mass is
//! spread evenly over ln tan θh from ln α to 0 (half of it beyond
//! tan θh = √α, against α for GGX). One LTC cannot hold both the peak and
//! the tail (one GGX at any α errs by up to 77 % of the albedo), so each
//! cell is a mixture
//!
//! f_r μi / n ≈ w₁ D₁(ω) + w₂ D₂(ω) + w₃ D₃(ω),  Σ wₖ = 1,
//!
//! each Dₖ the clamped cosine pushed through Mₖ = [[a, 0, b], [0, c, 0],
//! [d, 0, 1]] as in ltc/ggx.rs, the fourteen parameters fitted together
//! to the lobe at that view (L1 distance, Nelder–Mead,
//! src/fit_ltc_coat.rs). At α = 0.001, whose mass spans three decades of
//! tan θh, two cosines leave an L1 distance of 0.41 at the normal view
//! (0.53 at μo = 0.06) and three 0.17 (0.30); at α = 0.1 two leave 0.045.
//! n = ∫ f_r μi dωi is the lobe's directional albedo (F_r and G_r
//! included), by the model's own quadrature (`Disney::albedo_quadrature`).
//! A polygon then costs [`K`] clipped-polygon integrals.
//!
//! **File format** (`ltc_coat.bin`): ASCII header lines, the first
//! `specula-ltc-coat 2 NX NY 16`, then `#` comment lines (the command, the
//! axes, the fit's error), then a line `end`; then NX × NY × 16 f32
//! little-endian values, rows in y (view), x inside a row, 16 channels per
//! node: c M₁⁻¹'s m00, m02, m20, m22 (scaled so that m11 = 1), the same
//! for M₂ and M₃, w₁, w₂, w₃, n. Axes (table.rs, nodes on the ends,
//! bilinear):
//! - x = ln α over [ln 0.001, ln 0.1] ([`X_AXIS`]): GTR1's shape changes
//!   by the same amount per factor of α at any α;
//! - y = √(1 − μo) over [0, 1] ([`Y_AXIS`]), as in ltc/ggx.rs.
//!
//! Measured (core/tests/disney_ltc.rs, `disney_ltc_error_of_each_lobe_alone`
//! and `coat_ltc_error_by_gloss_and_view`): see the README's Disney
//! section.

use crate::light::PolygonLocal;
use crate::ltc::ggx::{Cell, LtcGgx};
use crate::real::Real;
use crate::table::{Axis, Nodes, Table2, Warp};
use crate::vec3::V3;
use std::f64::consts::LN_10;
use std::sync::OnceLock;

/// Cosines per cell.
pub const K: usize = 3;
/// Nodes in ln α.
pub const NX: usize = 12;
/// Nodes in √(1 − μo).
pub const NY: usize = 32;
/// Channels per node (module docs): 4 per cosine, its weight, n.
pub(crate) const CHANNELS: usize = 5 * K + 1;

/// The range of the clearcoat's α: mix(0.1, 0.001, clearcoat_gloss).
pub(crate) const ALPHA_LO: f64 = 0.001;
pub(crate) const ALPHA_HI: f64 = 0.1;
/// ln α: see the module docs (ln 0.001 = −3 ln 10 to ln 0.1 = −ln 10;
/// checked by a test).
pub const X_AXIS: Axis = Axis::new(NX, -3.0 * LN_10, -LN_10, Warp::Linear, Nodes::Ends);
/// √(1 − μo).
pub const Y_AXIS: Axis = Axis::new(NY, 0.0, 1.0, Warp::Linear, Nodes::Ends);

/// The first header line's prefix.
pub(crate) const MAGIC: &str = "specula-ltc-coat 2";

/// The committed table.
static DATA: &[u8] = include_bytes!("../../data/ltc_coat.bin");

/// One fitted cell: the transforms, their weights and the lobe's albedo.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoatCell {
    /// (a, b, c, d) of each Mₖ.
    pub m: [[f64; 4]; K],
    /// wₖ, summing to 1.
    pub w: [f64; K],
    pub n: f64,
}

impl CoatCell {
    /// The stored channels (module docs).
    pub fn channels(&self) -> [f32; CHANNELS] {
        let mut out = [0.0; CHANNELS];
        for (k, m) in self.m.iter().enumerate() {
            let inv = Cell {
                a: m[0],
                b: m[1],
                c: m[2],
                d: m[3],
                n: 0.0,
                n_w: 0.0,
            }
            .channels();
            out[4 * k..4 * k + 4].copy_from_slice(&inv[..4]);
            out[4 * K + k] = self.w[k] as f32;
        }
        out[5 * K] = self.n as f32;
        out
    }
}

/// The table file's bytes for cells in row order (y outer, x inner), with
/// `comments` (lines without the leading `#`) in the header (format in
/// `ltc::file`).
pub fn encode(cells: &[Vec<CoatCell>], comments: &[String]) -> Vec<u8> {
    let (nx, ny) = (NX, NY);
    let cells = cells.iter().flatten().map(|c| c.channels());
    crate::ltc::file::encode(MAGIC, nx, ny, cells, comments)
}

/// Reads a table file (format in `ltc::file`).
pub(crate) fn decode(bytes: &[u8]) -> Result<Table2<CHANNELS>, String> {
    crate::ltc::file::decode(bytes, MAGIC, (X_AXIS, Y_AXIS))
}

/// The committed table, decoded once.
pub fn table() -> &'static Table2<CHANNELS> {
    static T: OnceLock<Table2<CHANNELS>> = OnceLock::new();
    // The file is part of the crate and checked by tests; a bad one is a
    // build defect, not an input error.
    T.get_or_init(|| decode(DATA).expect("core/data/ltc_coat.bin is malformed"))
}

/// The clearcoat's LTCs at one view: what a Disney material with a coat
/// looks up once per pixel.
#[derive(Clone, Copy, Debug)]
pub struct LtcCoat<R> {
    pub ltc: [LtcGgx<R>; K],
    /// The lobe's albedo times wₖ: what multiplies each integral.
    pub scale: [R; K],
}

impl<R: Real> LtcCoat<R> {
    /// The lookup at `ln_alpha` = ln α (clamped into the table) and the
    /// unit local view `wo` (μo clamped into [0, 1]).
    #[inline(always)]
    pub(crate) fn new(ln_alpha: R, wo: V3<R>) -> LtcCoat<R> {
        let mu = wo.z.clamp(R::ZERO, R::ONE);
        let y = (R::ONE - mu).sqrt();
        let v = table().lookup(ln_alpha, y);
        let n = v[5 * K];
        // The weights are fitted in (0, 1); interpolation keeps them there.
        // The Fresnel factor is in the fitted shape: no Schlick part n_w.
        LtcCoat {
            ltc: core::array::from_fn(|k| {
                let m = [v[4 * k], v[4 * k + 1], v[4 * k + 2], v[4 * k + 3]];
                LtcGgx::from_inverse(m, n, R::ZERO, wo)
            }),
            scale: core::array::from_fn(|k| n * v[4 * K + k]),
        }
    }

    /// Σ scaleₖ ∫ Dₖ over the polygon. Not inlined: [`K`] clipped
    /// polygon integrals dwarf a call, and the light loop of materials
    /// without a coat stays smaller.
    #[inline(never)]
    pub(crate) fn integral(&self, poly: &PolygonLocal<R>) -> R {
        let mut c = R::ZERO;
        for (l, s) in self.ltc.iter().zip(self.scale) {
            c = s.mul_add(l.integral(poly), c);
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_axis_spans_the_coats_alpha_range() {
        assert!((X_AXIS.node(0) - ALPHA_LO.ln()).abs() < 1e-15);
        assert!((X_AXIS.node(NX - 1) - ALPHA_HI.ln()).abs() < 1e-15);
    }

    #[test]
    fn the_committed_table_decodes_and_its_cells_are_sane() {
        let t = table();
        for j in 0..NY {
            for i in 0..NX {
                let v = t.node_value(i, j);
                // Weights in (0, 1) summing to 1, n a positive albedo
                // below 1 (weight 1).
                let w = &v[4 * K..5 * K];
                assert!(
                    w.iter().all(|w| *w > 0.0 && *w < 1.0),
                    "({i}, {j}): w {w:?}"
                );
                assert!(
                    (w.iter().sum::<f32>() - 1.0).abs() < 1e-5,
                    "({i}, {j}): {w:?}"
                );
                let n = v[5 * K];
                assert!(n > 0.0 && n < 1.0, "({i}, {j}): n {n}");
                // Every M⁻¹ has a positive determinant (orientation kept).
                for k in 0..K {
                    let m = &v[4 * k..4 * k + 4];
                    let det = m[0] * m[3] - m[1] * m[2];
                    assert!(det > 0.0, "({i}, {j}): det {det}");
                }
            }
        }
    }

    #[test]
    fn encode_then_decode_is_the_identity_to_f32() {
        let cell = |i: usize, j: usize| CoatCell {
            m: [
                [0.1 + i as f64, -0.2 * j as f64, 0.3, 0.01],
                [1.0, 0.5, 0.7 + j as f64, -0.02],
                [2.0, -1.5, 1.1, 0.3],
            ],
            w: [0.4, 0.35, 0.25],
            n: 0.03 + 0.001 * i as f64,
        };
        let cells: Vec<Vec<CoatCell>> = (0..NY)
            .map(|j| (0..NX).map(|i| cell(i, j)).collect())
            .collect();
        let t = decode(&encode(&cells, &["test".into()])).expect("decodes");
        for (j, row) in cells.iter().enumerate() {
            for (i, c) in row.iter().enumerate() {
                assert_eq!(t.node_value(i, j), c.channels());
            }
        }
        assert!(decode(b"specula-ltc-coat 1 12 32 10\nend\n").is_err());
    }
}
