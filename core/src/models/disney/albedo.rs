//! Directional albedos of the Disney lobes: the quadrature behind the
//! compensation and polygon-light terms, and the diffuse lobes' albedo
//! table (see the parent module, "Polygon lights").

use super::*;

impl Disney {
    /// The albedo of the lobes that do not depend on the view's azimuth
    /// (diffuse + sheen, clearcoat, the compensation lobe's exact
    /// factor · (1 − E(μo))), per channel, at μo; and the clearcoat's
    /// part of it (grey).
    pub(super) fn isotropic_albedo(&self, mu_o: f64) -> ([f64; 3], f64) {
        let wo = azimuth_dir(mu_o, 1.0);
        let p = self.prepare(wo);
        let diffuse = self.albedo_quadrature(&p, Lobe::Diffuse);
        let coat = if self.d.clearcoat_weight > 0.0 {
            self.albedo_quadrature(&p, Lobe::Clearcoat)
        } else {
            [0.0; 3]
        };
        let ms = self.kc.as_ref().map_or([0.0; 3], |k| {
            k.factor.map(|f| f as f64 * (1.0 - k.slice.e_at(mu_o)))
        });
        (
            core::array::from_fn(|c| diffuse[c] + coat[c] + ms[c]),
            coat[0],
        )
    }

    /// Single-scattering specular albedo at a local wo (compensation lobe
    /// excluded: `isotropic_albedo` adds its exact albedo).
    pub(super) fn specular_albedo(&self, wo: V3<f64>) -> [f64; 3] {
        let p = self.prepare(wo);
        let without_kc = Disney {
            kc: None,
            ..self.clone()
        };
        without_kc.albedo_quadrature(&p, Lobe::Specular)
    }

    /// ∫ lobe(wi, wo) μi dωi over the hemisphere, in f64, per channel:
    ///
    /// - diffuse + sheen (smooth in wi): Gauss–Legendre in t with μi = t²
    ///   (nodes dense at grazing, where ss has its 1/(μi + μo)) times the
    ///   midpoint rule in φi (periodic, so it converges geometrically);
    /// - specular and clearcoat (sharp around the mirror direction): in
    ///   half-vector space, with (u1, u2) ∈ [0, 1]² the CDF coordinates of
    ///   D(h) cos θh (anisotropic GGX: φh = atan2(αy sin 2πu2, αx cos 2πu2),
    ///   tan²θh = u1 / ((1 − u1) k), k = cos²φh/αx² + sin²φh/αy²; GTR1:
    ///   φh = 2πu2, cos²θh = (1 − (α²)^(1−u1)) / (1 − α²) [Burley12, eq. 2]),
    ///   so D cos θh dωh = du1 du2 and, with dωi = 4 (wo·h) dωh,
    ///   ∫ f μi dωi = ∫∫ f μi 4 (wo·h) / (D cos θh) du1 du2.
    ///   For a fixed φh, wi = 2 (wo·h) h − wo lies above the horizon (and
    ///   wo·h > 0) exactly for θh < (β + π/2)/2, β = atan2(wo_xy·(cos φh,
    ///   sin φh), μo): u1 is integrated by Gauss–Legendre on [0, u1(θmax)],
    ///   where the integrand is smooth, u2 by the midpoint rule.
    ///
    /// `core/tests/disney.rs` checks it against a brute-force quadrature.
    pub fn albedo_quadrature(&self, p: &DisneyPrepared<f64>, lobe: Lobe) -> [f64; 3] {
        const N_T: usize = 32;
        const N_PHI: usize = 64;
        const N_U1: usize = 32;
        let wo = p.o.wo;
        let mut acc = [0.0f64; 3];
        let mut add = |wi: V3<f64>, weight: f64| {
            if wi.z <= 0.0 {
                return;
            }
            let (l, _) = self.lobes(p, wi);
            let v = match lobe {
                Lobe::Diffuse => l.diffuse,
                Lobe::Specular => l.specular,
                Lobe::Clearcoat => Rgb::splat(l.clearcoat),
            };
            acc[0] += v.x * weight;
            acc[1] += v.y * weight;
            acc[2] += v.z * weight;
        };
        if let Lobe::Diffuse = lobe {
            let rule = GaussLegendre::new(N_T);
            for k in 0..N_PHI {
                let phi = TAU * (k as f64 + 0.5) / N_PHI as f64;
                for (t, w) in gl_nodes(&rule, 0.0, 1.0) {
                    let mu = t * t;
                    let s = (1.0 - mu * mu).max(0.0).sqrt();
                    let wi = V3::new(s * phi.cos(), s * phi.sin(), mu);
                    // dωi μi = μi dμi dφ = t² 2t dt dφ.
                    add(wi, w * mu * 2.0 * t * TAU / N_PHI as f64);
                }
            }
            return acc;
        }
        let (ax, ay, a_c) = (self.d.alpha_x, self.d.alpha_y, self.d.clearcoat_alpha);
        let rule = GaussLegendre::new(N_U1);
        for k in 0..N_PHI {
            let u2 = (k as f64 + 0.5) / N_PHI as f64;
            let phi = match lobe {
                Lobe::Specular => (ay * (TAU * u2).sin()).atan2(ax * (TAU * u2).cos()),
                _ => TAU * u2,
            };
            let (cp, sp) = (phi.cos(), phi.sin());
            let beta = (wo.x * cp + wo.y * sp).atan2(wo.z);
            let tan2_max = ((beta + FRAC_PI_2) / 2.0).tan().powi(2);
            // u1 ↔ tan²θh for this φh, and D(h) of the lobe.
            let kk = cp * cp / (ax * ax) + sp * sp / (ay * ay);
            let a2c = a_c * a_c;
            let u1_of = |t2: f64| match lobe {
                Lobe::Specular => t2 * kk / (1.0 + t2 * kk),
                _ => 1.0 - (1.0 - (1.0 - a2c) / (1.0 + t2)).ln() / a2c.ln(),
            };
            let cos2_of = |u1: f64| match lobe {
                Lobe::Specular => 1.0 / (1.0 + u1 / ((1.0 - u1) * kk)),
                _ => (1.0 - a2c.powf(1.0 - u1)) / (1.0 - a2c),
            };
            let u1_max = u1_of(tan2_max);
            for (u1, w) in gl_nodes(&rule, 0.0, u1_max) {
                let c2 = cos2_of(u1).clamp(0.0, 1.0);
                let (ch, sh) = (c2.sqrt(), (1.0 - c2).sqrt());
                let hv = V3::new(sh * cp, sh * sp, ch);
                let oh = wo.dot(hv);
                if oh <= 0.0 || ch <= 0.0 {
                    continue;
                }
                let wi = hv * (2.0 * oh) - wo;
                let d = match lobe {
                    Lobe::Specular => d_ggx_aniso(ax, ay, hv.x * hv.x, hv.y * hv.y, c2),
                    _ => d_gtr(a_c, 1.0, c2, 1.0 - c2),
                };
                add(wi, w * wi.z * 4.0 * oh / (d * ch * N_PHI as f64));
            }
        }
        acc
    }
}

/// Which lobe [`Disney::albedo_quadrature`] integrates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lobe {
    Diffuse,
    Specular,
    Clearcoat,
}

/// The (node, weight) pairs of `rule` mapped onto [a, b].
fn gl_nodes(rule: &GaussLegendre, a: f64, b: f64) -> Vec<(f64, f64)> {
    rule.nodes_weights()
        .map(|(x, w)| (0.5 * (a + b) + 0.5 * (b - a) * x, 0.5 * (b - a) * w))
        .collect()
}

/// The unit local direction with cos θ = μ and cos²φ = c2 (φ ∈ [0, π/2]).
pub(super) fn azimuth_dir(mu: f64, c2: f64) -> V3<f64> {
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    V3::new(s * c2.sqrt(), s * (1.0 - c2).max(0.0).sqrt(), mu)
}

/// μo nodes of the diffuse-albedo table: ends included, dense at grazing.
const DIFFUSE_MU_AXIS: Axis = Axis::new(64, 0.0, 1.0, Warp::Sqrt, Nodes::Ends);

/// The diffuse lobes' directional albedos as polynomials in roughness,
/// over μo, for any Disney material (module docs, "Polygon lights"):
/// ∫ F_d μi dωi = c₀ + c₁ r + c₂ r², ∫ ss μi dωi = c₃ + c₄ r + c₅ r²,
/// ∫ F_H μi dωi = c₆ (F_d and ss are quadratic in r for fixed directions).
/// Built once per process.
pub(crate) fn diffuse_albedo_table() -> &'static Table1<7> {
    static T: OnceLock<Table1<7>> = OnceLock::new();
    T.get_or_init(|| Table1::build(DIFFUSE_MU_AXIS, diffuse_albedo_coefficients))
}

/// The seven coefficients of `diffuse_albedo_table` at μo, by
/// Gauss–Legendre in t with μi = t² (64 nodes) times the midpoint rule in
/// φ over [0, π] (64 nodes; every term is even in φ).
pub fn diffuse_albedo_coefficients(mu_o: f64) -> [f64; 7] {
    const N_PHI: usize = 64;
    let rule = GaussLegendre::new(64);
    let sin_o = (1.0 - mu_o * mu_o).max(0.0).sqrt();
    let w_o = (1.0 - mu_o).powi(5);
    let (a_o, b_o) = (1.0 - 0.5 * w_o, 1.0 - w_o);
    let mut acc = [0.0f64; 7];
    for k in 0..N_PHI {
        let phi = PI * (k as f64 + 0.5) / N_PHI as f64;
        for (t, w) in gl_nodes(&rule, 0.0, 1.0) {
            let mu = t * t;
            let sin_i = (1.0 - mu * mu).max(0.0).sqrt();
            // dωi μi over both halves of φ: μi · 2t dt · 2 dφ.
            let weight = w * mu * 2.0 * t * 2.0 * PI / N_PHI as f64;
            let c2 = (0.5 * (1.0 + sin_i * sin_o * phi.cos() + mu * mu_o)).clamp(0.0, 1.0);
            let w_i = (1.0 - mu).powi(5);
            let (a_i, b_i) = (1.0 - 0.5 * w_i, 1.0 - w_i);
            let kd = 2.0 * c2;
            let q = 1.25 * (1.0 / (mu + mu_o).max(1e-12) - 0.5);
            let terms = [
                a_i * a_o,
                kd * (w_i * a_o + a_i * w_o),
                kd * kd * w_i * w_o,
                b_i * b_o * q + 0.625,
                c2 * (w_i * b_o + b_i * w_o) * q,
                c2 * c2 * w_i * w_o * q,
                (1.0 - c2.sqrt()).powi(5),
            ];
            for (a, t) in acc.iter_mut().zip(terms) {
                *a += t * weight;
            }
        }
    }
    acc
}

impl Disney {
    /// The directional albedo of the diffuse lobes (diffuse, subsurface
    /// blend, sheen; × (1 − metallic)) at μo, per channel, from
    /// `diffuse_albedo_table`.
    #[inline(always)]
    pub fn diffuse_albedo<R: Real>(&self, cos_o: R) -> Rgb<R> {
        diffuse_albedo_of(&self.params(), cos_o)
    }
}

/// [`Disney::diffuse_albedo`] for parameters per lane.
#[inline(always)]
pub(super) fn diffuse_albedo_of<R: Real>(l: &DisneyLaneParams<R>, cos_o: R) -> Rgb<R> {
    let c = diffuse_albedo_table().lookup(cos_o);
    let r = l.roughness;
    let fd = c[2].mul_add(r, c[1]).mul_add(r, c[0]);
    let ss = c[5].mul_add(r, c[4]).mul_add(r, c[3]);
    let base = (ss - fd).mul_add(l.subsurface, fd);
    l.diffuse * base + l.sheen * c[6]
}
