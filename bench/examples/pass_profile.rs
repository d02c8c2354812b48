//! Per-pass profile of rendered frames as a PNG: one stacked bar per
//! `specula render --stats-json` file (median pass times over its frames),
//! segments for vertex, clip + setup, bin, raster, shade and post, with
//! the milliseconds written on them and a time axis.
//!
//! ```text
//! target/release/specula render fixtures/scenes/sphere-grid.toml -o /tmp/g.png \
//!     --threads 1 --repeat 10 --stats-json /tmp/t1.json
//! target/release/specula render fixtures/scenes/sphere-grid.toml -o /tmp/g.png \
//!     --threads 2 --repeat 10 --stats-json /tmp/t2.json
//! cargo run --release -p specula-bench --example pass_profile -- \
//!     docs/frame-profile.png /tmp/t1.json /tmp/t2.json
//! ```

use specula::label::{draw_labels, text_width, LabelDesc};
use specula::render::median;
use tiny_skia::{Color, Paint, PathBuilder, Pixmap, Rect, Stroke, Transform};

/// The passes of a frame, in order, with their JSON keys and colours.
const PASSES: [(&str, &str, [u8; 3]); 6] = [
    ("vertex", "vertex", [120, 120, 120]),
    ("setup", "clip + setup", [214, 96, 77]),
    ("bin", "bin", [244, 165, 130]),
    ("raster", "raster", [253, 219, 199]),
    ("shade", "shade", [67, 147, 195]),
    ("post", "post", [146, 197, 222]),
];

const WIDTH: u32 = 1000;
const LEFT: f32 = 150.0;
const RIGHT: f32 = 40.0;
const TOP: f32 = 50.0;
const BAR: f32 = 44.0;
const GAP: f32 = 18.0;
const TEXT: f32 = 15.0;

/// One file's row: its label and the median time of each pass.
struct Row {
    label: String,
    ms: [f64; 6],
}

fn read_row(path: &str) -> Result<Row, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{path}: {e}"))?;
    let frames = json["frames"]
        .as_array()
        .filter(|f| !f.is_empty())
        .ok_or_else(|| format!("{path}: no \"frames\" array (a --stats-json file?)"))?;
    let mut ms = [0.0; 6];
    for (k, (key, _, _)) in PASSES.iter().enumerate() {
        let values = frames
            .iter()
            .map(|f| {
                f[*key]
                    .as_f64()
                    .ok_or_else(|| format!("{path}: a frame has no {key:?}"))
            })
            .collect::<Result<Vec<f64>, String>>()?;
        // The median `--stats` reports, so the bars match its table.
        ms[k] = median(&values);
    }
    let threads = json["threads"].as_u64().unwrap_or(0);
    let shading = json["shading"].as_str().unwrap_or("");
    // The 8-bit encode ran inside the shading pass: no post bar.
    let fused = if json["post_in_shading"].as_bool() == Some(true) {
        "*"
    } else {
        ""
    };
    Ok(Row {
        label: format!(
            "{threads} thread{} {shading}{fused}",
            if threads == 1 { "" } else { "s" }
        ),
        ms,
    })
}

fn fill(pixmap: &mut Pixmap, rect: Option<Rect>, rgb: [u8; 3]) {
    let mut paint = Paint::default();
    paint.set_color_rgba8(rgb[0], rgb[1], rgb[2], 255);
    if let Some(r) = rect {
        pixmap.fill_rect(r, &paint, Transform::identity(), None);
    }
}

fn label(text: String, at: [f32; 2], color: [f32; 3]) -> LabelDesc {
    LabelDesc {
        text,
        at,
        size: TEXT,
        color,
    }
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [out, inputs @ ..] = args.as_slice() else {
        return Err("usage: pass_profile OUT.png STATS.json...".into());
    };
    if inputs.is_empty() {
        return Err("usage: pass_profile OUT.png STATS.json...".into());
    }
    let rows = inputs
        .iter()
        .map(|p| read_row(p))
        .collect::<Result<Vec<_>, _>>()?;
    let longest = rows
        .iter()
        .map(|r| r.ms.iter().sum::<f64>())
        .fold(0.0, f64::max);
    // Time axis: a round step giving 4–10 ticks.
    let step = [1.0, 2.0, 5.0, 10.0, 20.0, 25.0, 50.0, 100.0, 200.0, 500.0]
        .into_iter()
        .find(|s| longest / s <= 10.0)
        .unwrap_or(1000.0);
    let axis_max = (longest / step).ceil().max(1.0) * step;
    let plot_w = WIDTH as f32 - LEFT - RIGHT;
    let x_of = |ms: f64| LEFT + (ms / axis_max) as f32 * plot_w;
    let legend_y = TOP + rows.len() as f32 * (BAR + GAP) + 40.0;
    let height = (legend_y + 62.0) as u32;

    let mut pixmap = Pixmap::new(WIDTH, height).ok_or("image too large")?;
    pixmap.fill(Color::WHITE);
    let mut texts = vec![label(
        "per-pass frame time (ms, median over frames)".into(),
        [LEFT, 14.0],
        [0.0; 3],
    )];
    // Grid lines and tick values.
    let grid_bottom = TOP + rows.len() as f32 * (BAR + GAP) - GAP + 6.0;
    let mut tick = 0.0;
    while tick <= axis_max + 1e-9 {
        let x = x_of(tick);
        fill(
            &mut pixmap,
            Rect::from_xywh(x, TOP - 6.0, 1.0, grid_bottom - TOP + 6.0),
            [220, 220, 220],
        );
        let t = format!("{tick}");
        texts.push(label(
            t.clone(),
            [x - 0.5 * text_width(&t, TEXT), grid_bottom + 4.0],
            [0.3; 3],
        ));
        tick += step;
    }
    for (i, row) in rows.iter().enumerate() {
        let y = TOP + i as f32 * (BAR + GAP);
        texts.push(label(
            row.label.clone(),
            [10.0, y + 0.5 * (BAR - TEXT)],
            [0.0; 3],
        ));
        let mut t0 = 0.0;
        for (k, (_, _, rgb)) in PASSES.iter().enumerate() {
            let (a, b) = (x_of(t0), x_of(t0 + row.ms[k]));
            fill(
                &mut pixmap,
                Rect::from_xywh(a, y, (b - a).max(0.0), BAR),
                *rgb,
            );
            let v = format!("{:.1}", row.ms[k]);
            if b - a > text_width(&v, TEXT) + 6.0 {
                texts.push(label(
                    v.clone(),
                    [0.5 * (a + b - text_width(&v, TEXT)), y + 0.5 * (BAR - TEXT)],
                    [0.0; 3],
                ));
            }
            t0 += row.ms[k];
        }
        let total = format!("{t0:.1} ms");
        texts.push(label(
            total,
            [x_of(t0) + 6.0, y + 0.5 * (BAR - TEXT)],
            [0.0; 3],
        ));
    }
    // Axis line.
    let mut pb = PathBuilder::new();
    pb.move_to(LEFT, grid_bottom);
    pb.line_to(LEFT + plot_w, grid_bottom);
    if let Some(path) = pb.finish() {
        let mut paint = Paint::default();
        paint.set_color_rgba8(0, 0, 0, 255);
        pixmap.stroke_path(
            &path,
            &paint,
            &Stroke::default(),
            Transform::identity(),
            None,
        );
    }
    // Legend.
    let mut x = LEFT;
    for (_, name, rgb) in PASSES {
        fill(&mut pixmap, Rect::from_xywh(x, legend_y, 14.0, 14.0), rgb);
        texts.push(label(name.into(), [x + 20.0, legend_y - 1.0], [0.0; 3]));
        x += 20.0 + text_width(name, TEXT) + 24.0;
    }
    if rows.iter().any(|r| r.label.ends_with('*')) {
        let note = "* post (exposure, tone map, sRGB encode) ran inside shade";
        texts.push(label(note.into(), [LEFT, legend_y + 22.0], [0.0; 3]));
    }

    let mut rgb8: Vec<u8> = pixmap
        .data()
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    draw_labels(&mut rgb8, WIDTH, height, &texts, 1.0);
    image::save_buffer(out, &rgb8, WIDTH, height, image::ColorType::Rgb8)
        .map_err(|e| format!("{out}: {e}"))
}
