//! The NPR line passes on the benchmark frame (1920×1080), set up once for
//! the `lines` criterion bench and the `line_shares` example, so both time
//! the same work:
//! - the steady benchmark frame (buffers reused, the 8-bit encode inside
//!   the shading pass), as `--stats --repeat` and the llvmpipe ratio time it;
//! - the geometry passes without and with the extrusion outline (back
//!   faces pushed 2 px), steady;
//! - the Sobel stage (depth, normal, id; dilation; anti-aliased blend);
//! - the stroke overlay stage (silhouette, crease and boundary edges, 1.5 px
//!   round strokes), with its canvases kept as from frame to frame.

use crate::benchmark_scene;
use specula::render::RenderSettings;
use specula_npr::edges::{EdgeKind, MeshEdges};
use specula_npr::extrude::{extrusion_passes, Extrude};
use specula_npr::outline::{id_materials, Selection};
use specula_npr::overlay::{LineCap, LineJoin, StrokeStyle, Strokes};
use specula_npr::sobel::{Sobel, Source};
use specula_raster::frame::{
    render_ldr, render_ldr_into, render_with, visibility, visibility_into, Frame, FrameStats,
    ShadePath, Visibility,
};
use specula_raster::post::{HdrImage, LdrEncoding, PostStage};
use specula_raster::{BufferSet, Material, SceneData, Target, Unlit};
use std::sync::Arc;

/// The edge kinds the stroke stage draws.
pub const STROKE_KINDS: [EdgeKind; 3] =
    [EdgeKind::Silhouette, EdgeKind::Crease, EdgeKind::Boundary];

/// The scenes, stages and frame buffers of the line-pass measurements.
pub struct LinePasses {
    /// The benchmark scene.
    pub plain: SceneData,
    /// The benchmark scene with a 2 px black extrusion outline on every
    /// material.
    pub outlined: SceneData,
    pub target: Target,
    /// A rendered frame with depth, normal and id buffers: what the
    /// image-space stages read.
    pub frame: Frame,
    /// That frame's colour, the image the stages draw over.
    pub image: HdrImage,
    pub sobel: Sobel,
    pub strokes: Strokes,
    enc: LdrEncoding,
    set: BufferSet,
}

/// The state a steady frame reuses from the previous one.
pub struct SteadyFrame {
    frame: Frame,
    ldr: Vec<u8>,
}

impl LinePasses {
    /// Loads the scene and renders the frame the stages read, in the
    /// calling rayon pool.
    pub fn new() -> Self {
        let scene = benchmark_scene();
        let plain = scene.data.clone();
        let mut outlined = scene.data.clone().into_parts();
        let m = outlined.materials.len() as u32;
        outlined.materials.push(Material::new(
            "outline",
            Unlit {
                color: [0.0; 3],
                intensity: 1.0,
            },
            true,
        ));
        let stage = Arc::new(Extrude::new(&outlined, 2.0));
        let base = outlined.triangles.len() as u32;
        let passes = extrusion_passes(&outlined, stage, m, base, &|_| true);
        outlined.geometry.extend(passes);
        let outlined = SceneData::new(outlined).expect("outlined scene");
        let target = Target::new(1920, 1080).expect("1080p");

        // As the CLI renders a PNG: no HDR output, so the 8-bit encode
        // runs inside the shading pass.
        let settings = RenderSettings {
            keep_hdr: false,
            ..RenderSettings::from_scene(&scene)
        };
        let enc = settings
            .ldr_in_shading()
            .expect("a PNG output encodes inside the shading pass");
        let set = settings.buffers.union(settings.post().buffers());

        let buffers = BufferSet {
            depth: true,
            normal: true,
            id: true,
        };
        let frame = render_with(&plain, target, ShadePath::Simd, buffers);
        let image = HdrImage {
            width: 1920,
            height: 1080,
            rgb: frame.buffers.color.clone(),
        };
        let sobel = Sobel {
            sources: vec![
                (Source::Depth, 0.1),
                (Source::Normal, 0.4),
                (Source::Id, 0.3),
            ],
            width: 2.0,
            color: [0.0; 3],
            antialias: true,
            id_material: id_materials(&plain),
            selection: Selection::all(),
            scratch: Default::default(),
        };
        let strokes = Strokes::new(
            MeshEdges::from_scene(&plain, &STROKE_KINDS, 60.0),
            plain.camera.clone(),
            StrokeStyle {
                width: 1.5,
                color: [0.0; 3],
                taper: 0.0,
                join: LineJoin::Round,
                cap: LineCap::Round,
            },
        );
        LinePasses {
            plain,
            outlined,
            target,
            frame,
            image,
            sobel,
            strokes,
            enc,
            set,
        }
    }

    /// A first benchmark frame, whose buffers [`LinePasses::frame_again`]
    /// reuses (calling rayon pool).
    pub fn first_frame(&self) -> SteadyFrame {
        let mut ldr = Vec::new();
        let frame = render_ldr(
            &self.plain,
            self.target,
            ShadePath::Simd,
            self.set,
            self.enc,
            &mut ldr,
        );
        SteadyFrame { frame, ldr }
    }

    /// One steady benchmark frame into `st` (calling rayon pool).
    pub fn frame_again(&self, st: &mut SteadyFrame) {
        render_ldr_into(
            &self.plain,
            &mut st.frame,
            ShadePath::Simd,
            self.enc,
            &mut st.ldr,
        );
    }

    /// The visibility of `data` (`plain` or `outlined`), whose buffers
    /// [`LinePasses::visibility_again`] reuses.
    pub fn first_visibility(&self, data: &SceneData) -> Visibility {
        visibility(data, &self.target, &mut FrameStats::default())
    }

    /// The geometry passes of `data` again, into `vis`.
    pub fn visibility_again(&self, data: &SceneData, vis: &mut Visibility) {
        visibility_into(data, &self.target, vis, &mut FrameStats::default());
    }

    /// The Sobel stage `stage` (a run's instance of [`LinePasses::sobel`])
    /// over `image` (a copy of [`LinePasses::image`]).
    pub fn run_sobel(&self, stage: &mut Sobel, image: &mut HdrImage) {
        stage.apply(image, &self.frame.buffers);
    }

    /// The stroke overlay stage `stage` (a run's instance of
    /// [`LinePasses::strokes`], its canvases kept from call to call, as
    /// from frame to frame) over `image`.
    pub fn run_strokes(&self, stage: &mut Strokes, image: &mut HdrImage) {
        stage.apply(image, &self.frame.buffers);
    }
}

impl Default for LinePasses {
    fn default() -> Self {
        Self::new()
    }
}
