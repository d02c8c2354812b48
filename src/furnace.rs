//! `specula furnace`: the directional albedo E(μo) of a microfacet material
//! for several roughnesses, without and with Kulla–Conty compensation —
//! the white furnace test of the course notes as a table and a plot.

use crate::material_desc::{MaterialDesc, Shading, Tables};
use specula_core::{Model, V3};

/// Albedo curves of one α: (μo, E without, E with compensation), RGB.
pub struct FurnaceCurve {
    /// The α the curve was computed at (after clamping into [1e-3, 1]).
    pub alpha: f32,
    /// What building the material adjusted (a clamped α), for stderr.
    pub notes: Vec<String>,
    pub points: Vec<(f64, [f64; 3], [f64; 3])>,
}

/// μo values of the table and plot.
pub fn mus() -> Vec<f64> {
    (1..=40).map(|i| i as f64 / 40.0).collect()
}

fn albedo(m: &Model, mu: f64) -> [f64; 3] {
    let wo = V3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let n = V3::new(0.0, 0.0, 1.0);
    let e = match m {
        Model::Microfacet(m) => specula_core::Brdf::albedo(m, n, wo),
        _ => unreachable!("checked by furnace()"),
    };
    [e.x, e.y, e.z]
}

/// Builds the material at each α (its own α is replaced), without and with
/// compensation, and samples the tabulated directional albedo.
pub fn furnace(material_json: &str, alphas: &[f32]) -> Result<Vec<FurnaceCurve>, String> {
    let desc: MaterialDesc =
        serde_json::from_str(material_json).map_err(|e| format!("--material: {e}"))?;
    let MaterialDesc::Microfacet(base) = desc else {
        return Err("--material: the furnace needs a \"microfacet\" material".into());
    };
    let mut curves = Vec::new();
    for &alpha in alphas {
        let mut notes = Vec::new();
        let mut build = |ec: bool| -> Result<Model, String> {
            let mut d = base.clone();
            d.alpha = alpha;
            d.energy_compensation = ec;
            match MaterialDesc::Microfacet(d).build_shading(Tables::Build, &mut notes) {
                Ok((Shading::Lit(m), _)) => Ok(m),
                Ok(_) => unreachable!("a microfacet description builds a model"),
                Err(e) if e.starts_with("alpha") => Err(format!("--alpha {alpha}: {e}")),
                Err(e) => Err(format!("--material.{e}")),
            }
        };
        let (plain, comp) = (build(false)?, build(true)?);
        notes.dedup();
        let Model::Microfacet(m) = &plain else {
            unreachable!("a microfacet description builds a microfacet model")
        };
        let alpha = m.params.alpha;
        let points = mus()
            .into_iter()
            .map(|mu| (mu, albedo(&plain, mu), albedo(&comp, mu)))
            .collect();
        curves.push(FurnaceCurve {
            alpha,
            notes,
            points,
        });
    }
    Ok(curves)
}

/// Tab-separated table: alpha, mu, E (r g b), E compensated (r g b).
pub fn table(curves: &[FurnaceCurve]) -> String {
    let mut s = String::from("alpha\tmu\tE_r\tE_g\tE_b\tEc_r\tEc_g\tEc_b\n");
    for c in curves {
        for (mu, e, ec) in &c.points {
            s += &format!(
                "{:.3}\t{mu:.3}\t{:.5}\t{:.5}\t{:.5}\t{:.5}\t{:.5}\t{:.5}\n",
                c.alpha, e[0], e[1], e[2], ec[0], ec[1], ec[2]
            );
        }
    }
    s
}

/// Plot palette, one colour per α (cycled).
const PALETTE: [[u8; 3]; 6] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
];

/// PNG bytes of the plot: E(μo) of channel mean, dashed without and solid
/// with compensation, one colour per α; y from 0 to 1.1.
pub fn plot_png(curves: &[FurnaceCurve]) -> Result<Vec<u8>, String> {
    use specula_npr::plot::{line_plot, Curve};
    let mean = |e: &[f64; 3]| ((e[0] + e[1] + e[2]) / 3.0) as f32;
    let mut lines = Vec::new();
    for (i, c) in curves.iter().enumerate() {
        let rgb = PALETTE[i % PALETTE.len()];
        for (dashed, pick) in [(true, 0usize), (false, 1)] {
            let points = c
                .points
                .iter()
                .map(|(mu, e, ec)| (*mu as f32, mean(if pick == 0 { e } else { ec })))
                .collect();
            lines.push(Curve {
                points,
                rgb,
                dashed,
            });
        }
    }
    let pm = line_plot(900, 600, 0.0, 1.1, 0.1, &lines).ok_or("cannot allocate the plot")?;
    pm.encode_png().map_err(|e| e.to_string())
}

/// The legend printed beside the plot (it has no text of its own).
pub fn legend(curves: &[FurnaceCurve]) -> String {
    let names = ["blue", "orange", "green", "red", "purple", "brown"];
    let mut s = String::from("plot: x = mu_o in [0, 1], y = E in [0, 1.1], grid 0.1; dashed = single scattering, solid = compensated\n");
    for (i, c) in curves.iter().enumerate() {
        s += &format!("  {}: alpha {}\n", names[i % names.len()], c.alpha);
    }
    s
}
