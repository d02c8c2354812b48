//! The exact Smith Λ of GTR against a direct 2-D quadrature of its
//! definition written here, against GGX's closed form at γ = 2, and the
//! white furnace it buys: never above 1 without compensation, 1 with it.

use specula_core::gtr_lambda::GtrLambdaTable;
use specula_core::kulla_conty::KcColor;
use specula_core::masking::lambda_ggx;
use specula_core::models::microfacet::{
    Fresnel, GtrLambda, Microfacet, MicrofacetParams, Ndf, Smith,
};
use specula_core::quadrature::GaussLegendre;
use std::f64::consts::PI;

/// GTR(γ, α) written plainly [Burley12, App. B].
fn d_gtr(gamma: f64, alpha: f64, cos_m: f64) -> f64 {
    let a2 = alpha * alpha;
    if (a2 - 1.0).abs() < 1e-12 {
        return 1.0 / PI;
    }
    let t = 1.0 + (a2 - 1.0) * cos_m * cos_m;
    if (gamma - 1.0).abs() < 1e-12 {
        (a2 - 1.0) / (PI * a2.ln()) / t
    } else if gamma > 1.0 && a2 < 1.0 {
        // The same with a2^(γ−1) factored out of the normalisation, so that
        // large γ neither overflows a2^(1−γ) nor underflows t^γ: t ≥ a2.
        (gamma - 1.0) * (1.0 - a2) / (PI * a2 * (1.0 - a2.powf(gamma - 1.0))) * (a2 / t).powf(gamma)
    } else {
        (gamma - 1.0) * (a2 - 1.0) / (PI * (1.0 - a2.powf(1.0 - gamma))) / t.powf(gamma)
    }
}

/// Λ(μ) = (1/μ) ∫_{v·m < 0} |v·m| D(m) dωm by brute force: v = (s, 0, μ);
/// v·m < 0 needs cos φ < 0 and tan θ > μ / (s |cos φ|); Gauss–Legendre on
/// panels over φ ∈ (π/2, 3π/2) and over θ from that bound to π/2.
/// `panels` per dimension: 24 resolve D for γ ≤ 10 at α ≥ 0.05; γ = 128
/// at α = 0.05 (lobe ~α/√γ wide) needs 64.
fn lambda_direct(gamma: f64, alpha: f64, mu: f64, panels: usize) -> f64 {
    lambda_direct_with(gamma, alpha, mu, panels, |theta_lo| {
        (0..=panels)
            .map(|k| theta_lo + (PI / 2.0 - theta_lo) * k as f64 / panels as f64)
            .collect()
    })
}

/// The quadrature of [`lambda_direct`] with the θ panels' boundaries
/// (from θ_lo to π/2) given per φ by `theta_bounds(θ_lo)`.
fn lambda_direct_with(
    gamma: f64,
    alpha: f64,
    mu: f64,
    panels: usize,
    theta_bounds: impl Fn(f64) -> Vec<f64>,
) -> f64 {
    let s = (1.0 - mu * mu).sqrt();
    let gl = GaussLegendre::new(16);
    let mut sum = 0.0;
    for pp in 0..panels {
        let (p0, p1) = (
            PI / 2.0 + PI * pp as f64 / panels as f64,
            PI / 2.0 + PI * (pp + 1) as f64 / panels as f64,
        );
        let [part] = gl.integrate(p0, p1, |phi| {
            let c = phi.cos();
            if c >= 0.0 {
                return [0.0];
            }
            let theta_lo = (mu / (s * -c)).atan();
            let mut inner = 0.0;
            for w in theta_bounds(theta_lo).windows(2) {
                let [v] = gl.integrate(w[0], w[1], |th| {
                    let vm = s * th.sin() * c + mu * th.cos();
                    [(-vm).max(0.0) * d_gtr(gamma, alpha, th.cos()) * th.sin()]
                });
                inner += v;
            }
            [inner]
        });
        sum += part;
    }
    sum / mu
}

/// The worst error of the Λ table against `direct(γ, α, μ)` over the
/// grid, asserting each point is within 1e-4: relative where Λ ≥ 1e-4,
/// absolute below (Λ below 1e-4 is G1 within 1e-4 of 1).
fn worst_against(
    gammas: &[f64],
    alphas: &[f64],
    mus: &[f64],
    direct: impl Fn(f64, f64, f64) -> f64,
) -> f64 {
    let mut worst = 0.0f64;
    for &gamma in gammas {
        for &alpha in alphas {
            let t = GtrLambdaTable::new(gamma, alpha);
            for &mu in mus {
                let want = direct(gamma, alpha, mu);
                let got = t.lambda(mu);
                let err = if want >= 1e-4 {
                    (got - want).abs() / want
                } else {
                    (got - want).abs()
                };
                worst = worst.max(err);
                assert!(
                    err < 1e-4,
                    "γ {gamma} α {alpha} μ {mu}: table {got:e}, quadrature {want:e}"
                );
            }
        }
    }
    worst
}

#[test]
fn table_matches_a_direct_quadrature() {
    let worst = worst_against(
        &[1.0, 1.5, 2.0, 3.0, 10.0],
        &[0.05, 0.15, 0.5, 1.0],
        &[0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.7, 0.9, 0.97],
        |g, a, mu| lambda_direct(g, a, mu, 24),
    );
    eprintln!("exact GTR Λ: worst error vs direct quadrature {worst:e}");
}

/// The same at the ends of the γ range eval is used with (γ ∈ [¼, 128])
/// and α off the grid above: the table interpolates between sparse
/// quadrature nodes, and large γ is where Λ changes fastest.
#[test]
fn table_matches_a_direct_quadrature_for_extreme_gamma() {
    let mut worst = 0.0f64;
    for gamma in [0.25, 0.6, 30.0, 128.0] {
        for alpha in [0.05, 0.27, 0.8] {
            let t = GtrLambdaTable::new(gamma, alpha);
            for mu in [0.003, 0.02, 0.1, 0.3, 0.6, 0.8, 0.95] {
                let want = lambda_direct(gamma, alpha, mu, 64);
                let got = t.lambda(mu);
                let err = (got - want).abs() / want.max(1e-4);
                worst = worst.max(err);
                assert!(
                    err < 1e-4,
                    "γ {gamma} α {alpha} μ {mu}: table {got:e}, quadrature {want:e}"
                );
            }
        }
    }
    eprintln!("exact GTR Λ, γ ¼ … 128: worst error vs direct quadrature {worst:e}");
}

/// [`lambda_direct`] with the θ panels graded toward the lower bound
/// θ_lo (where a narrow lobe's D is largest inside the region): boundaries
/// at θ_lo + (π/2 − θ_lo) 10^(−8 + 8k/panels), k = 0 … panels, after a
/// first panel from θ_lo.
fn lambda_direct_graded(gamma: f64, alpha: f64, mu: f64, panels: usize) -> f64 {
    lambda_direct_with(gamma, alpha, mu, panels, |theta_lo| {
        let span = PI / 2.0 - theta_lo;
        let mut bounds = vec![theta_lo];
        for k in 0..=panels {
            bounds.push(theta_lo + span * 10f64.powf(-8.0 + 8.0 * k as f64 / panels as f64));
        }
        bounds
    })
}

/// Small α (a material's α goes down to 1e-3; the tables above start at
/// 0.05): a narrow lobe is largest at the region's edge θ_lo, so the
/// direct quadrature's θ panels are graded toward it.
#[test]
fn table_matches_a_direct_quadrature_at_small_alpha() {
    let worst = worst_against(
        &[1.0, 1.5, 3.0, 10.0],
        &[0.001, 0.002, 0.005, 0.01, 0.03],
        &[0.0005, 0.001, 0.002, 0.005, 0.02, 0.1, 0.4, 0.8],
        |g, a, mu| lambda_direct_graded(g, a, mu, 48),
    );
    // Measured: 5.2e-5 (γ 10, α 0.001, μ 5e-4); before the θ integral's
    // first panel was graded, 1.5e-2 (γ 10, α 0.002, μ 5e-4).
    eprintln!("exact GTR Λ, α 0.001 … 0.03: worst error vs direct quadrature {worst:e}");
}

/// γ = 2 is GGX, whose Λ has a closed form.
#[test]
fn gamma_two_is_the_ggx_closed_form() {
    for alpha in [0.01, 0.1, 0.4, 0.9] {
        let t = GtrLambdaTable::new(2.0, alpha);
        for mu in [0.01, 0.1, 0.3, 0.6, 0.95] {
            let want = lambda_ggx(alpha, mu);
            let got = t.lambda(mu);
            let err = (got - want).abs() / want.max(1e-4);
            assert!(err < 1e-4, "α {alpha} μ {mu}: {got} vs {want}");
        }
    }
}

fn white(gamma: f32, alpha: f32, exact: bool) -> MicrofacetParams {
    MicrofacetParams {
        ndf: Ndf::Gtr { gamma },
        alpha,
        smith: Smith::HeightCorrelated,
        fresnel: Fresnel::Schlick { f0: [1.0; 3] },
        diffuse: [0.0; 3],
        gtr_lambda: if exact {
            GtrLambda::exact(gamma, alpha)
        } else {
            GtrLambda::Ggx
        },
    }
}

/// Without compensation a white lobe never reflects more than it
/// receives with the exact Λ; with GGX's Λ, γ < 2 does (printed).
#[test]
fn white_furnace_never_exceeds_one() {
    let mut worst = 0.0f64;
    for gamma in [1.0f32, 1.5, 3.0, 10.0] {
        for alpha in [0.05f32, 0.15, 0.5, 1.0] {
            let p = white(gamma, alpha, true);
            for mu in [0.02, 0.1, 0.3, 0.7, 1.0] {
                let e = p.specular_albedo(mu)[0];
                worst = worst.max(e);
                // The albedo quadrature is good to ~1e-5.
                assert!(e <= 1.0 + 1e-4, "γ {gamma} α {alpha} μ {mu}: E = {e}");
            }
        }
    }
    let borrowed = white(1.5, 0.15, false).specular_albedo(0.1)[0];
    let exact = white(1.5, 0.15, true).specular_albedo(0.1)[0];
    eprintln!("largest E with the exact Λ: {worst:.5}; γ 1.5, α 0.15, μ 0.1: GGX Λ {borrowed:.4}, exact {exact:.4}");
    assert!(borrowed > 1.1);
}

/// With Kulla–Conty compensation (tables built with the exact Λ) a white
/// lobe reflects 1 for GTR too.
#[test]
fn white_furnace_with_compensation_reaches_one() {
    let mut worst = 0.0f64;
    // Each γ builds its own Kulla–Conty table (N_MU × N_ALPHA albedos with
    // the exact Λ): the ends and the middle of γ ∈ [1, 10].
    for gamma in [1.0f32, 3.0, 10.0] {
        for alpha in [0.1f32, 0.4, 1.0] {
            let m = Microfacet::new(white(gamma, alpha, true), Some(KcColor::KullaConty));
            for mu in [0.05f32, 0.1, 0.2, 0.4, 0.7, 1.0] {
                let e = m.albedo_at(mu)[0] as f64;
                worst = worst.max((e - 1.0).abs());
                // Measured: worst |E − 1| = 2.0e-4.
                assert!(
                    (e - 1.0).abs() < 1e-3,
                    "γ {gamma} α {alpha} μ {mu}: E + E_ms = {e}"
                );
            }
        }
    }
    eprintln!("compensated exact-Λ GTR white furnace: worst |E − 1| = {worst:.2e}");
}
