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
//!
//! Where things are:
//! - this file: the [`Strokes`] post stage and its [`StrokeStyle`];
//! - `schedule`: how a frame's draws are spread over threads (bands of
//!   rows, each drawn on its own surface) and blended over the image, with
//!   bytes that do not depend on the thread count;
//! - `skia`: everything that talks to tiny-skia (the strokes, the custom
//!   outline for gentle polylines, a band's surface); the only module
//!   that names tiny-skia types;
//! - `svg`: the SVG writer.

mod schedule;
mod skia;
mod svg;

use crate::edges::{chain, visible_pieces, DepthView, EdgeKind, MeshEdges, Polyline};
use crate::outline::ssaa_of;
use specula_raster::post::{HdrImage, PostStage};
use specula_raster::{BufferSet, Camera, FrameBuffers};
use std::sync::Arc;

pub use schedule::Canvases;
pub use skia::{draw, LineCap, LineJoin};
pub use svg::svg;

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

/// The stroke overlay stage. Built once per scene ([`Strokes::new`]): the
/// edges and the camera are fixed, so which edges are drawn (silhouettes
/// included) is found once; a frame tests their visibility, chains and
/// draws them.
pub struct Strokes {
    edges: Arc<MeshEdges>,
    camera: Camera,
    pub style: StrokeStyle,
    /// [`MeshEdges::classify`] from the camera's eye.
    drawn: Arc<Vec<(u32, u32, EdgeKind)>>,
    /// Kept from frame to frame by the post list's instance of the stage.
    canvases: Canvases,
}

/// A clone shares the edges and starts with no canvases.
impl Clone for Strokes {
    fn clone(&self) -> Strokes {
        Strokes {
            edges: self.edges.clone(),
            camera: self.camera.clone(),
            style: self.style,
            drawn: self.drawn.clone(),
            canvases: Canvases::default(),
        }
    }
}

impl std::fmt::Debug for Strokes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Strokes")
            .field("edges", &self.edges.edge_count())
            .field("camera", &self.camera)
            .field("style", &self.style)
            .field("drawn", &self.drawn.len())
            .finish()
    }
}

impl Strokes {
    pub fn new(edges: MeshEdges, camera: Camera, style: StrokeStyle) -> Strokes {
        let drawn = edges.classify(camera.eye);
        Strokes {
            edges: Arc::new(edges),
            camera,
            style,
            drawn: Arc::new(drawn),
            canvases: Canvases::default(),
        }
    }

    /// The visible polylines of a frame (whose buffers hold depth), in
    /// output pixels of a `ssaa`-times smaller image.
    pub fn polylines(&self, frame: &FrameBuffers, ssaa: usize) -> Vec<Polyline> {
        let view = self.camera.view(frame.width, frame.height);
        let depth = DepthView {
            depth: &frame.depth,
            width: frame.width as usize,
            height: frame.height as usize,
            ssaa,
        };
        let pieces = visible_pieces(&self.edges, &self.drawn, &view, self.camera.near, &depth);
        chain(&pieces)
    }
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

    fn instance(&self) -> Box<dyn PostStage> {
        Box::new(self.clone())
    }

    fn apply(&mut self, img: &mut HdrImage, frame: &FrameBuffers) {
        let lines = self.polylines(frame, ssaa_of(img, frame));
        self.canvases.blend(&lines, &self.style, img);
    }
}
