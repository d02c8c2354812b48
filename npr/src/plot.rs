//! Line plots drawn with tiny-skia (used by `specula furnace`): curves of
//! y over x ∈ [0, 1] on a framed grid. No text: tiny-skia has none, so the
//! caller prints the legend.

use tiny_skia::{Color, Paint, PathBuilder, Pixmap, Rect, Stroke, StrokeDash, Transform};

/// One curve: points (x, y) in data units, RGB colour, dashed or solid.
pub struct Curve {
    pub points: Vec<(f32, f32)>,
    pub rgb: [u8; 3],
    pub dashed: bool,
}

/// Renders `curves` over x ∈ [0, 1], y ∈ [y_min, y_max] into a
/// `width × height` RGBA pixmap, with grid lines every 0.1 in x and every
/// `y_step` in y. Returns None for a size tiny-skia cannot allocate.
pub fn line_plot(
    width: u32,
    height: u32,
    y_min: f32,
    y_max: f32,
    y_step: f32,
    curves: &[Curve],
) -> Option<Pixmap> {
    let mut pm = Pixmap::new(width, height)?;
    pm.fill(Color::WHITE);
    let margin = 0.06 * width.min(height) as f32;
    let (x0, x1) = (margin, width as f32 - margin);
    let (y0, y1) = (height as f32 - margin, margin);
    let sx = |x: f32| x0 + (x1 - x0) * x;
    let sy = |y: f32| y0 + (y1 - y0) * (y - y_min) / (y_max - y_min);
    let mut paint = Paint {
        anti_alias: true,
        ..Paint::default()
    };

    // Grid.
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
    }
    let mut y = y_min;
    while y <= y_max + 1e-6 {
        grid.move_to(x0, sy(y));
        grid.line_to(x1, sy(y));
        y += y_step;
    }
    if let Some(p) = grid.finish() {
        pm.stroke_path(&p, &paint, &thin, Transform::identity(), None);
    }
    // Frame.
    paint.set_color_rgba8(60, 60, 60, 255);
    if let Some(p) = Rect::from_ltrb(x0, y1, x1, y0).map(PathBuilder::from_rect) {
        pm.stroke_path(&p, &paint, &thin, Transform::identity(), None);
    }
    // Curves.
    for c in curves {
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
        let stroke = Stroke {
            width: 2.0,
            dash: if c.dashed {
                StrokeDash::new(vec![8.0, 6.0], 0.0)
            } else {
                None
            },
            ..Stroke::default()
        };
        pm.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
    }
    Some(pm)
}
