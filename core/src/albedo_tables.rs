//! Directional-albedo tables for uniform environment light on the
//! metallic-roughness model (the "split sum" factorization, [Karis13]).
//!
//! With Schlick's F = F0 + (1 − F0) w, w = (1 − wi·h)⁵, and the specular
//! integrand s(wi) = D(h) V(wi, wo) (n·wi) of GGX + height-correlated Smith:
//!
//! - E_spec(μo, α) = F0 · A(μo, α) + B(μo, α),  A = ∫ s (1 − w) dωi,  B = ∫ s w dωi
//! - E_diff(μo)    = (1 − F0) ρd (1 − C(μo)),   C = ∫ w (n·wi)/π dωi  (independent of α)
//!
//! Layout: A, B are `N_MU × N_ALPHA` grids sampled at texel centres,
//! μ_j = (j + ½)/N_MU, √α_k = (k + ½)/N_ALPHA (roughness spacing: the
//! integrals change fastest at small α), bilinear lookup clamped at the edges.
//! C is `N_MU` entries on the same μ axis.
//!
//! Computed once per process by deterministic quadrature (Hammersley points,
//! importance-sampling D(h)(n·h)); see the tests for the measured error.

use crate::fresnel::schlick_weight;
use crate::masking::v_smith_ggx_correlated;
use crate::real::Real;
use std::sync::OnceLock;

pub const N_MU: usize = 32;
pub const N_ALPHA: usize = 32;
/// Quadrature points per table entry.
const SAMPLES: u32 = 2048;

/// The three integrals of the module docs, per lane.
pub struct SplitSum<R> {
    pub a: R,
    pub b: R,
    pub c: R,
}

pub struct AlbedoTables {
    a: Vec<f32>,
    b: Vec<f32>,
    c: Vec<f32>,
}

/// Point `i` of an `n`-point Hammersley set in [0, 1)².
fn hammersley(i: u32, n: u32) -> (f64, f64) {
    (
        (i as f64 + 0.5) / n as f64,
        i.reverse_bits() as f64 / 4294967296.0,
    )
}

/// A, B at (μo, α) by importance sampling h ∝ D(h)(n·h): with
/// pdf(wi) = D(h)(n·h) / (4 wo·h), s/pdf = V (n·wi) 4 (wo·h) / (n·h).
fn integrate_ab(mu_o: f64, alpha: f64) -> (f64, f64) {
    let wo = [(1.0 - mu_o * mu_o).sqrt(), 0.0, mu_o];
    let a2 = alpha * alpha;
    let (mut sa, mut sb) = (0.0, 0.0);
    for i in 0..SAMPLES {
        let (u1, u2) = hammersley(i, SAMPLES);
        // GGX inversion: cos²θh = (1 − u) / (1 + (α² − 1) u).
        let cos_h = ((1.0 - u1) / (1.0 + (a2 - 1.0) * u1)).sqrt();
        let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
        let phi = 2.0 * std::f64::consts::PI * u2;
        let h = [sin_h * phi.cos(), sin_h * phi.sin(), cos_h];
        let o_h = wo[0] * h[0] + wo[2] * h[2];
        if o_h <= 0.0 {
            continue;
        }
        let cos_i = 2.0 * o_h * h[2] - wo[2];
        if cos_i <= 0.0 {
            continue;
        }
        let weight = v_smith_ggx_correlated(alpha, cos_i, mu_o) * cos_i * 4.0 * o_h / cos_h;
        let w = schlick_weight(o_h);
        sa += weight * (1.0 - w);
        sb += weight * w;
    }
    (sa / SAMPLES as f64, sb / SAMPLES as f64)
}

/// C(μo) = ∫ (1 − wi·h)⁵ (n·wi)/π dωi, by cosine-weighted sampling of wi.
fn integrate_c(mu_o: f64) -> f64 {
    let wo = [(1.0 - mu_o * mu_o).sqrt(), 0.0, mu_o];
    let n = SAMPLES * 4;
    let mut s = 0.0;
    for i in 0..n {
        let (u1, u2) = hammersley(i, n);
        let r = u1.sqrt();
        let phi = 2.0 * std::f64::consts::PI * u2;
        let wi = [r * phi.cos(), r * phi.sin(), (1.0 - u1).sqrt()];
        let hv = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
        let len = (hv[0] * hv[0] + hv[1] * hv[1] + hv[2] * hv[2]).sqrt();
        let i_h = (wi[0] * hv[0] + wi[1] * hv[1] + wi[2] * hv[2]) / len;
        s += schlick_weight(i_h);
    }
    s / n as f64
}

/// Bilinear weights on a texel-centre axis of `n` entries over [0, 1].
fn axis(t: f32, n: usize) -> (usize, usize, f32) {
    let x = (t * n as f32 - 0.5).clamp(0.0, (n - 1) as f32);
    let i0 = (x as usize).min(n - 1);
    let i1 = (i0 + 1).min(n - 1);
    (i0, i1, x - i0 as f32)
}

impl AlbedoTables {
    fn build() -> Self {
        let mut a = vec![0.0; N_MU * N_ALPHA];
        let mut b = vec![0.0; N_MU * N_ALPHA];
        let mut c = vec![0.0; N_MU];
        for j in 0..N_MU {
            let mu = (j as f64 + 0.5) / N_MU as f64;
            c[j] = integrate_c(mu) as f32;
            for k in 0..N_ALPHA {
                let r = (k as f64 + 0.5) / N_ALPHA as f64;
                let (ia, ib) = integrate_ab(mu, r * r);
                a[j * N_ALPHA + k] = ia as f32;
                b[j * N_ALPHA + k] = ib as f32;
            }
        }
        AlbedoTables { a, b, c }
    }

    /// The process-wide tables, built on first use (about 10 ms).
    pub fn get() -> &'static AlbedoTables {
        static T: OnceLock<AlbedoTables> = OnceLock::new();
        T.get_or_init(Self::build)
    }

    /// A, B, C for one (μo, α); scalar twin of [`AlbedoTables::ggx_schlick`].
    pub fn lookup(&self, mu_o: f32, alpha: f32) -> [f32; 3] {
        let (j0, j1, tj) = axis(mu_o, N_MU);
        let (k0, k1, tk) = axis(alpha.max(0.0).sqrt(), N_ALPHA);
        let bilerp = |t: &[f32]| {
            let v0 = t[j0 * N_ALPHA + k0] + (t[j0 * N_ALPHA + k1] - t[j0 * N_ALPHA + k0]) * tk;
            let v1 = t[j1 * N_ALPHA + k0] + (t[j1 * N_ALPHA + k1] - t[j1 * N_ALPHA + k0]) * tk;
            v0 + (v1 - v0) * tj
        };
        let c = self.c[j0] + (self.c[j1] - self.c[j0]) * tj;
        [bilerp(&self.a), bilerp(&self.b), c]
    }

    /// A, B, C per lane (a gather: lanes look up independently).
    pub fn ggx_schlick<R: Real>(&self, alpha: f32, mu_o: R) -> SplitSum<R> {
        let mut out = [[0.0f32; 8]; 3];
        for lane in 0..R::LANES {
            let v = self.lookup(mu_o.lane(lane) as f32, alpha);
            for (o, x) in out.iter_mut().zip(v) {
                o[lane] = x;
            }
        }
        SplitSum {
            a: R::load(&out[0]),
            b: R::load(&out[1]),
            c: R::load(&out[2]),
        }
    }
}
