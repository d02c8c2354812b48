//! Line plots drawn with tiny-skia (used by `specula furnace`): curves of
//! y over x ∈ [0, 1] on a framed grid, with tick values, axis labels and a
//! legend. tiny-skia draws no text, so the plot returns its text as
//! [`Text`] items placed in pixels, and the caller rasterizes them with its
//! font (the CLI's src/label.rs, the project's one font path).

use tiny_skia::{Color, Paint, PathBuilder, Pixmap, Rect, Stroke, StrokeDash, Transform};

/// One curve: points (x, y) in data units, RGB colour, dashed or solid.
pub struct Curve {
    pub points: Vec<(f32, f32)>,
    pub rgb: [u8; 3],
    pub dashed: bool,
}

/// One legend line: a short stroke in the curve's style, then the text.
pub struct LegendEntry {
    pub text: String,
    pub rgb: [u8; 3],
    pub dashed: bool,
}

/// What to plot: x ∈ [0, 1] (ticks every 0.1), y ∈ [y_min, y_max] (ticks
/// every `y_step`).
pub struct PlotSpec<'a> {
    pub width: u32,
    pub height: u32,
    pub y_min: f32,
    pub y_max: f32,
    pub y_step: f32,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub curves: &'a [Curve],
    pub legend: &'a [LegendEntry],
}

/// Horizontal anchor of a [`Text`]'s x.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    Left,
    Centre,
    Right,
}

/// A line of text to draw: `y` is its top edge, `x` its left edge, centre
/// or right edge per `align`; `size` is the line height in pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct Text {
    pub text: String,
    pub x: f32,
    pub y: f32,
    pub size: f32,
    pub align: Align,
}

/// The frame of the data area in pixels: left, right, bottom, top.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub x0: f32,
    pub x1: f32,
    pub y0: f32,
    pub y1: f32,
}

/// A drawn plot: the lines, and the text still to draw over them.
pub struct Plot {
    pub pixmap: Pixmap,
    pub texts: Vec<Text>,
    pub frame: Frame,
}

/// Text height of ticks, labels and legend, in pixels.
pub(crate) const TEXT_SIZE: f32 = 16.0;
/// Margins around the data area: tick values and the y label on the left,
/// tick values and the x label below, the legend on the right.
const LEFT: f32 = 64.0;
const BOTTOM: f32 = 56.0;
const TOP: f32 = 36.0;
const RIGHT: f32 = 230.0;

/// Draws the plot of `spec`. Returns None for a size tiny-skia cannot
/// allocate or too small for its margins.
pub fn line_plot(spec: &PlotSpec) -> Option<Plot> {
    let (width, height) = (spec.width as f32, spec.height as f32);
    if width < LEFT + RIGHT + 50.0 || height < TOP + BOTTOM + 50.0 {
        return None;
    }
    let mut pm = Pixmap::new(spec.width, spec.height)?;
    pm.fill(Color::WHITE);
    let frame = Frame {
        x0: LEFT,
        x1: width - RIGHT,
        y0: height - BOTTOM,
        y1: TOP,
    };
    let Frame { x0, x1, y0, y1 } = frame;
    let (y_min, y_max) = (spec.y_min, spec.y_max);
    let sx = |x: f32| x0 + (x1 - x0) * x;
    let sy = |y: f32| y0 + (y1 - y0) * (y - y_min) / (y_max - y_min);
    let mut paint = Paint {
        anti_alias: true,
        ..Paint::default()
    };
    let mut texts = Vec::new();
    let text = |s: String, x: f32, y: f32, align: Align| Text {
        text: s,
        x,
        y,
        size: TEXT_SIZE,
        align,
    };

    // Grid and tick values.
    paint.set_color_rgba8(220, 220, 220, 255);
    let thin = Stroke {
        width: 1.0,
        ..Stroke::default()
    };
    let mut grid = PathBuilder::new();
    for i in 0..=10 {
        let x = sx(i as f32 / 10.0);
        grid.move_to(x, y0);
        grid.line_to(x, y1);
        texts.push(text(
            format!("{:.1}", i as f32 / 10.0),
            x,
            y0 + 6.0,
            Align::Centre,
        ));
    }
    // Ticks counted, not accumulated: y_min + k·step stays exact enough
    // for the labels.
    let steps = ((y_max - y_min) / spec.y_step + 1e-4).floor() as i32;
    for k in 0..=steps {
        let y = y_min + k as f32 * spec.y_step;
        grid.move_to(x0, sy(y));
        grid.line_to(x1, sy(y));
        texts.push(text(
            format!("{y:.1}"),
            x0 - 6.0,
            sy(y) - 0.5 * TEXT_SIZE,
            Align::Right,
        ));
    }
    if let Some(p) = grid.finish() {
        pm.stroke_path(&p, &paint, &thin, Transform::identity(), None);
    }
    texts.push(text(
        spec.x_label.into(),
        0.5 * (x0 + x1),
        y0 + 10.0 + TEXT_SIZE,
        Align::Centre,
    ));
    texts.push(text(
        spec.y_label.into(),
        x0,
        y1 - 8.0 - TEXT_SIZE,
        Align::Left,
    ));
    // Frame.
    paint.set_color_rgba8(60, 60, 60, 255);
    if let Some(p) = Rect::from_ltrb(x0, y1, x1, y0).map(PathBuilder::from_rect) {
        pm.stroke_path(&p, &paint, &thin, Transform::identity(), None);
    }
    let stroke_of = |dashed: bool| Stroke {
        width: 2.0,
        dash: if dashed {
            StrokeDash::new(vec![8.0, 6.0], 0.0)
        } else {
            None
        },
        ..Stroke::default()
    };
    // Curves.
    for c in spec.curves {
        let mut pb = PathBuilder::new();
        for (i, &(x, y)) in c.points.iter().enumerate() {
            let (px, py) = (sx(x), sy(y.clamp(y_min, y_max)));
            if i == 0 {
                pb.move_to(px, py);
            } else {
                pb.line_to(px, py);
            }
        }
        let Some(path) = pb.finish() else { continue };
        paint.set_color_rgba8(c.rgb[0], c.rgb[1], c.rgb[2], 255);
        pm.stroke_path(
            &path,
            &paint,
            &stroke_of(c.dashed),
            Transform::identity(),
            None,
        );
    }
    // Legend: a 30 px stroke sample, then the text, one entry per line.
    let lx = x1 + 16.0;
    for (i, e) in spec.legend.iter().enumerate() {
        let top = y1 + i as f32 * (TEXT_SIZE + 8.0);
        let mid = top + 0.5 * TEXT_SIZE;
        let mut pb = PathBuilder::new();
        pb.move_to(lx, mid);
        pb.line_to(lx + 30.0, mid);
        if let Some(path) = pb.finish() {
            paint.set_color_rgba8(e.rgb[0], e.rgb[1], e.rgb[2], 255);
            pm.stroke_path(
                &path,
                &paint,
                &stroke_of(e.dashed),
                Transform::identity(),
                None,
            );
        }
        texts.push(text(e.text.clone(), lx + 38.0, top, Align::Left));
    }
    Some(Plot {
        pixmap: pm,
        texts,
        frame,
    })
}
