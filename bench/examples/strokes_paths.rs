//! What fewer path vertices or other joins would save in tiny-skia: draws
//! a scene's stroke polylines (one frame's, with `[strokes]` width and
//! cap) on one pixmap as the overlay does (stroke, then fill the outline),
//! with the join `JOIN` (round, bevel or miter) and the polylines first
//! simplified (Douglas–Peucker, tolerance `TOL` px; 0 = as they are), and
//! writes the alpha bytes to `OUT` (raw, row-major) for comparing drawings.
//! Count the drawing's instructions with callgrind:
//!
//! ```text
//! valgrind --tool=callgrind --toggle-collect='*draw_strokes*' \
//!     target/release/examples/strokes_paths SCENE.toml JOIN TOL OUT
//! ```

use specula::render::{render_scene, RenderSettings};
use specula_npr::edges::Polyline;
use tiny_skia::{FillRule, LineJoin, Paint, PathBuilder, Pixmap, Stroke, Transform};

fn seg_dist(p: [f32; 2], a: [f32; 2], b: [f32; 2]) -> f32 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((p[0] - a[0] - t * dx).powi(2) + (p[1] - a[1] - t * dy).powi(2)).sqrt()
}
fn dp(pts: &[[f32; 2]], tol: f32, keep: &mut Vec<bool>, lo: usize, hi: usize) {
    if hi <= lo + 1 {
        return;
    }
    let (mut best, mut bi) = (0.0, lo);
    for i in lo + 1..hi {
        let d = seg_dist(pts[i], pts[lo], pts[hi]);
        if d > best {
            best = d;
            bi = i;
        }
    }
    if best > tol {
        keep[bi] = true;
        dp(pts, tol, keep, lo, bi);
        dp(pts, tol, keep, bi, hi);
    }
}

#[inline(never)]
fn draw_strokes(lines: &[Polyline], st: &Stroke, pm: &mut Pixmap) {
    let mut paint = Paint::default();
    paint.set_color_rgba8(255, 255, 255, 255);
    paint.anti_alias = true;
    for l in lines {
        let mut pb = PathBuilder::new();
        pb.move_to(l.points[0][0], l.points[0][1]);
        for p in &l.points[1..] {
            pb.line_to(p[0], p[1]);
        }
        if l.closed {
            pb.close();
        }
        let path = pb.finish().unwrap();
        let o = path.stroke(st, 1.0).unwrap();
        pm.fill_path(&o, &paint, FillRule::Winding, Transform::identity(), None);
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = specula::scene::load_scene(std::path::Path::new(&args[0])).unwrap();
    let stage = scene.lines.strokes.clone().unwrap();
    let r = render_scene(&scene, &RenderSettings::from_scene(&scene), 0.0).expect("render");
    let mut lines = stage.polylines(&r.frame.buffers, r.ssaa as usize);
    let tol: f32 = args[2].parse().unwrap();
    if tol > 0.0 {
        for l in &mut lines {
            let n = l.points.len();
            let mut keep = vec![false; n];
            keep[0] = true;
            keep[n - 1] = true;
            dp(&l.points, tol, &mut keep, 0, n - 1);
            l.points = l
                .points
                .iter()
                .zip(&keep)
                .filter(|(_, k)| **k)
                .map(|(p, _)| *p)
                .collect();
        }
    }
    let join = match args[1].as_str() {
        "bevel" => LineJoin::Bevel,
        "miter" => LineJoin::Miter,
        _ => LineJoin::Round,
    };
    let st = Stroke {
        width: stage.style.width,
        line_cap: stage.style.cap,
        line_join: join,
        ..Stroke::default()
    };
    let mut pm = Pixmap::new(r.width, r.height).unwrap();
    draw_strokes(&lines, &st, &mut pm);
    let alpha: Vec<u8> = pm.pixels().iter().map(|p| p.alpha()).collect();
    std::fs::write(&args[3], &alpha).unwrap();
    println!(
        "pts {}",
        lines.iter().map(|l| l.points.len()).sum::<usize>()
    );
}
