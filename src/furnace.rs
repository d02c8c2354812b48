//! `specula furnace`: the directional albedo E(μo) of a microfacet material
//! for several roughnesses, without and with Kulla–Conty compensation —
//! the white furnace test of the course notes as a table and a plot.

use specula::material_desc::{MaterialDesc, MaterialError, Shading, Tables};
use specula_core::{Model, V3};

/// Albedo curves of one α: (μo, E without, E with compensation), RGB.
pub(crate) struct FurnaceCurve {
    /// The α the curve was computed at (after clamping into [1e-3, 1]).
    pub(crate) alpha: f32,
    /// What building the material adjusted (a clamped α), for stderr.
    pub(crate) notes: Vec<String>,
    pub(crate) points: Vec<(f64, [f64; 3], [f64; 3])>,
}

/// μo values of the table and plot.
pub(crate) fn mus() -> Vec<f64> {
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
pub(crate) fn furnace(material_json: &str, alphas: &[f32]) -> Result<Vec<FurnaceCurve>, String> {
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
                Err(MaterialError::Field(e)) if e.field == "alpha" => {
                    Err(format!("--alpha {alpha}: {e}"))
                }
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
pub(crate) fn table(curves: &[FurnaceCurve]) -> String {
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
/// with compensation, one colour per α; y from 0 to 1.1. Tick values, axis
/// labels and the legend are drawn in the image (src/label.rs).
pub(crate) fn plot_png(curves: &[FurnaceCurve]) -> Result<Vec<u8>, String> {
    plot_png_with(curves, true)
}

/// [`plot_png`], with or without its text (the test compares the two).
fn plot_png_with(curves: &[FurnaceCurve], with_text: bool) -> Result<Vec<u8>, String> {
    let PlotImage {
        width, height, rgb, ..
    } = plot_rgb8(curves, with_text)?;
    let (w, h) = (width, height);
    let mut png = Vec::new();
    image::RgbImage::from_raw(w, h, rgb)
        .ok_or("plot buffer size")?
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| e.to_string())?;
    Ok(png)
}

/// The plot as row-major RGB8, with where its text went.
struct PlotImage {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
    /// Each text as drawn (top-left corner) and its width in pixels.
    #[cfg_attr(not(test), allow(dead_code))]
    labels: Vec<(specula::label::LabelDesc, f32)>,
    #[cfg_attr(not(test), allow(dead_code))]
    frame: specula_npr::plot::Frame,
}

fn plot_rgb8(curves: &[FurnaceCurve], with_text: bool) -> Result<PlotImage, String> {
    use specula::label::{draw_labels, text_width, LabelDesc};
    use specula_npr::plot::{line_plot, Align, Curve, LegendEntry, PlotSpec};
    let mean = |e: &[f64; 3]| ((e[0] + e[1] + e[2]) / 3.0) as f32;
    let mut lines = Vec::new();
    let mut legend = Vec::new();
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
        legend.push(LegendEntry {
            text: format!("α = {}", c.alpha),
            rgb,
            dashed: false,
        });
    }
    for (dashed, text) in [(true, "single scattering"), (false, "compensated")] {
        legend.push(LegendEntry {
            text: text.into(),
            rgb: [90, 90, 90],
            dashed,
        });
    }
    let spec = PlotSpec {
        width: 900,
        height: 600,
        y_min: 0.0,
        y_max: 1.1,
        y_step: 0.1,
        x_label: "μo = cos θo",
        y_label: "E(μo), channel mean",
        curves: &lines,
        legend: &legend,
    };
    let plot = line_plot(&spec).ok_or("cannot allocate the plot")?;
    let (w, h) = (plot.pixmap.width(), plot.pixmap.height());
    // Opaque (a white background), so premultiplied RGBA is plain RGBA.
    let mut rgb: Vec<u8> = plot
        .pixmap
        .data()
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    let labels: Vec<(LabelDesc, f32)> = plot
        .texts
        .iter()
        .map(|t| {
            let width = text_width(&t.text, t.size);
            let shift = match t.align {
                Align::Left => 0.0,
                Align::Centre => 0.5 * width,
                Align::Right => width,
            };
            let label = LabelDesc {
                text: t.text.clone(),
                at: [t.x - shift, t.y],
                size: t.size,
                color: [0.1; 3],
            };
            (label, width)
        })
        .collect();
    if with_text {
        let only: Vec<LabelDesc> = labels.iter().map(|(l, _)| l.clone()).collect();
        draw_labels(&mut rgb, w, h, &only, 1.0);
    }
    Ok(PlotImage {
        width: w,
        height: h,
        rgb,
        labels,
        frame: plot.frame,
    })
}

/// The legend in words, printed beside the plot for logs (the image has
/// its own).
pub(crate) fn legend(curves: &[FurnaceCurve]) -> String {
    let names = ["blue", "orange", "green", "red", "purple", "brown"];
    let mut s = String::from("plot: x = mu_o in [0, 1], y = E in [0, 1.1], grid 0.1; dashed = single scattering, solid = compensated\n");
    for (i, c) in curves.iter().enumerate() {
        s += &format!("  {}: alpha {}\n", names[i % names.len()], c.alpha);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(alpha: f32) -> FurnaceCurve {
        FurnaceCurve {
            alpha,
            notes: vec![],
            points: mus()
                .into_iter()
                .map(|mu| (mu, [0.5 + 0.4 * mu; 3], [1.0; 3]))
                .collect(),
        }
    }

    /// Every tick value, axis label and legend line is drawn where the
    /// plot placed it: its box holds dark text pixels in the labelled
    /// image and none in the same plot drawn without text (so the pixels
    /// are the text's, not grid or curves). Tick values sit outside the
    /// data frame, and the legend holds one line per α plus two styles.
    #[test]
    fn plot_draws_ticks_labels_and_legend() {
        let curves = [curve(0.2), curve(0.6), curve(1.0)];
        let with = plot_rgb8(&curves, true).unwrap();
        let without = plot_rgb8(&curves, false).unwrap();
        let w = with.width as usize;
        let dark = |img: &PlotImage, x0: f32, y0: f32, x1: f32, y1: f32| -> usize {
            let (xa, xb) = (x0.max(0.0) as usize, (x1.ceil() as usize).min(w));
            let (ya, yb) = (
                y0.max(0.0) as usize,
                (y1.ceil() as usize).min(img.height as usize),
            );
            (ya..yb)
                .flat_map(|y| (xa..xb).map(move |x| (y * w + x) * 3))
                .filter(|&k| img.rgb[k..k + 3].iter().all(|&c| c < 128))
                .count()
        };
        let f = with.frame;
        // 11 x ticks, 12 y ticks (0.0 … 1.1), 2 axis labels, 3 + 2 legend lines.
        assert_eq!(with.labels.len(), 11 + 12 + 2 + 5);
        for (l, width) in &with.labels {
            let (x0, y0) = (l.at[0], l.at[1]);
            let (x1, y1) = (x0 + width, y0 + l.size * 1.2);
            let n = dark(&with, x0, y0, x1, y1);
            assert!(n >= 10, "{:?}: {n} text pixels at {:?}", l.text, l.at);
            assert_eq!(dark(&without, x0, y0, x1, y1), 0, "{:?}", l.text);
            let inside = x1 > f.x0 && x0 < f.x1 && y1 > f.y1 && y0 < f.y0;
            assert!(!inside, "{:?} overlaps the data frame", l.text);
        }
        for t in [
            "0.0",
            "0.5",
            "1.0",
            "1.1",
            "α = 0.6",
            "single scattering",
            "compensated",
        ] {
            assert!(with.labels.iter().any(|(l, _)| l.text == t), "no {t:?}");
        }
        // The x tick "0.5" is centred under the frame's middle.
        let (half, wd) = with.labels.iter().find(|(l, _)| l.text == "0.5").unwrap();
        assert!((half.at[0] + wd / 2.0 - (f.x0 + f.x1) / 2.0).abs() < 1.0);
    }
}
