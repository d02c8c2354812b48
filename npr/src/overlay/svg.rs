//! The overlay's polylines as an SVG document.

use super::{LineCap, LineJoin, StrokeStyle};
use crate::edges::{EdgeKind, Polyline};
use specula_raster::post::srgb_encode;

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
