//! Stroke overlays: the polylines of [`crate::edges`] drawn with tiny-skia
//! over the image, and written as SVG. (The only place tiny-skia draws
//! lines over a rendered frame.)
//!
//! The overlay is a post stage after the tone map, before the sRGB encode:
//! the strokes are rasterized anti-aliased into an alpha mask at the output
//! size (widths in output pixels whatever the supersampling), and the
//! stroke colour is blended over the tone-mapped image in **linear**
//! values, c = c·(1 − a) + colour·a; the encode then writes sRGB. The SVG
//! has the same polylines (one `<path>` per polyline, in one `<g>` per
//! edge kind) with the colour sRGB-encoded, as SVG colours are; a taper,
//! which one SVG stroke cannot vary, is left out of the SVG.

use crate::edges::{chain, visible_pieces, DepthView, EdgeKind, MeshEdges, Polyline};
use crate::outline::ssaa_of;
use specula_raster::post::{srgb_encode, HdrImage, PostStage};
use specula_raster::{BufferSet, Camera, FrameBuffers};
pub use tiny_skia::{LineCap, LineJoin};
use tiny_skia::{Paint, PathBuilder, Pixmap, Stroke, Transform};

/// How strokes look.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrokeStyle {
    /// Output pixels.
    pub width: f32,
    /// Display-linear RGB in [0, 1].
    pub color: [f32; 3],
    /// 0: constant width; 1: the width falls linearly to 0 at both ends of
    /// an open polyline (over each half of its length).
    pub taper: f32,
    pub join: LineJoin,
    pub cap: LineCap,
}

/// The stroke overlay stage.
#[derive(Clone, Debug)]
pub struct Strokes {
    pub edges: MeshEdges,
    pub camera: Camera,
    pub style: StrokeStyle,
}

impl Strokes {
    /// The visible polylines of a frame (whose buffers hold depth), in
    /// output pixels of a `ssaa`-times smaller image.
    pub fn polylines(&self, frame: &FrameBuffers, ssaa: usize) -> Vec<Polyline> {
        let view = self.camera.view(frame.width, frame.height);
        let edges = self.edges.classify(self.camera.eye);
        let depth = DepthView {
            depth: &frame.depth,
            width: frame.width as usize,
            height: frame.height as usize,
            ssaa,
        };
        let pieces = visible_pieces(&self.edges, &edges, &view, self.camera.near, &depth);
        chain(&pieces)
    }
}

/// Stroke coverage (alpha in [0, 1]) of `lines` on a `width × height`
/// image, row-major.
pub fn draw(lines: &[Polyline], style: &StrokeStyle, width: u32, height: u32) -> Vec<f32> {
    match draw_pixmap(lines, style, width, height) {
        Some(pm) => pm
            .pixels()
            .iter()
            .map(|p| p.alpha() as f32 / 255.0)
            .collect(),
        None => vec![0.0; (width * height) as usize],
    }
}

/// The strokes drawn white on a transparent pixmap (None if tiny-skia
/// cannot make one of that size).
fn draw_pixmap(lines: &[Polyline], style: &StrokeStyle, width: u32, height: u32) -> Option<Pixmap> {
    let mut pm = Pixmap::new(width.max(1), height.max(1))?;
    let mut paint = Paint::default();
    paint.set_color_rgba8(255, 255, 255, 255);
    paint.anti_alias = true;
    let stroke = |w: f32| Stroke {
        width: w,
        line_cap: style.cap,
        line_join: style.join,
        ..Stroke::default()
    };
    for l in lines {
        if l.points.len() < 2 {
            continue;
        }
        if style.taper > 0.0 && !l.closed {
            // Segment by segment with round caps, each at the width of its
            // middle's distance (along the line) from the nearer end.
            let seg_len =
                |a: [f32; 2], b: [f32; 2]| ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            let total: f32 = l.points.windows(2).map(|w| seg_len(w[0], w[1])).sum();
            let mut s = 0.0;
            for w in l.points.windows(2) {
                let len = seg_len(w[0], w[1]);
                let mid = s + len * 0.5;
                s += len;
                let u = if total > 0.0 {
                    (mid.min(total - mid) / (total * 0.5)).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                let wd = style.width * ((1.0 - style.taper) + style.taper * u);
                let mut pb = PathBuilder::new();
                pb.move_to(w[0][0], w[0][1]);
                pb.line_to(w[1][0], w[1][1]);
                if let (Some(path), true) = (pb.finish(), wd > 0.0) {
                    let mut st = stroke(wd);
                    st.line_cap = LineCap::Round;
                    pm.stroke_path(&path, &paint, &st, Transform::identity(), None);
                }
            }
            continue;
        }
        let mut pb = PathBuilder::new();
        pb.move_to(l.points[0][0], l.points[0][1]);
        for p in &l.points[1..] {
            pb.line_to(p[0], p[1]);
        }
        if l.closed {
            pb.close();
        }
        if let Some(path) = pb.finish() {
            pm.stroke_path(
                &path,
                &paint,
                &stroke(style.width),
                Transform::identity(),
                None,
            );
        }
    }
    Some(pm)
}

impl PostStage for Strokes {
    fn name(&self) -> &str {
        "strokes"
    }

    fn buffers(&self) -> BufferSet {
        BufferSet {
            depth: true,
            ..BufferSet::default()
        }
    }

    fn apply(&self, img: &mut HdrImage, frame: &FrameBuffers) {
        let lines = self.polylines(frame, ssaa_of(img, frame));
        let Some(pm) = draw_pixmap(&lines, &self.style, img.width, img.height) else {
            return;
        };
        let c = self.style.color;
        let p = &mut img.rgb;
        // Straight from the alpha bytes (most are 0): the same a as draw's.
        for (i, px) in pm.pixels().iter().enumerate() {
            if px.alpha() != 0 {
                let a = px.alpha() as f32 / 255.0;
                p.r[i] = p.r[i] * (1.0 - a) + c[0] * a;
                p.g[i] = p.g[i] * (1.0 - a) + c[1] * a;
                p.b[i] = p.b[i] * (1.0 - a) + c[2] * a;
            }
        }
    }
}

/// The polylines as an SVG document of `width × height` pixels: one
/// `<g id="kind">` per edge kind present (in [`EdgeKind`] order) holding
/// one `<path>` per polyline.
pub fn svg(lines: &[Polyline], style: &StrokeStyle, width: u32, height: u32) -> String {
    use std::fmt::Write;
    let c = style.color.map(srgb_encode);
    let join = match style.join {
        LineJoin::Miter | LineJoin::MiterClip => "miter",
        LineJoin::Round => "round",
        LineJoin::Bevel => "bevel",
    };
    let cap = match style.cap {
        LineCap::Butt => "butt",
        LineCap::Round => "round",
        LineCap::Square => "square",
    };
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}">"#
    );
    for kind in EdgeKind::ALL {
        let of_kind: Vec<&Polyline> = lines.iter().filter(|l| l.kind == kind).collect();
        if of_kind.is_empty() {
            continue;
        }
        let _ = writeln!(
            s,
            r#"<g id="{}" fill="none" stroke="rgb({},{},{})" stroke-width="{}" stroke-linejoin="{join}" stroke-linecap="{cap}">"#,
            kind.name(),
            c[0],
            c[1],
            c[2],
            style.width
        );
        for l in of_kind {
            let mut d = String::new();
            for (i, p) in l.points.iter().enumerate() {
                let _ = write!(
                    d,
                    "{}{:.3} {:.3}",
                    if i == 0 { "M" } else { " L" },
                    p[0],
                    p[1]
                );
            }
            if l.closed {
                d.push_str(" Z");
            }
            let _ = writeln!(s, r#"<path d="{d}"/>"#);
        }
        let _ = writeln!(s, "</g>");
    }
    s.push_str("</svg>\n");
    s
}
