//! Rendering a loaded scene: thread pool, repeats, supersampling, tone
//! mapping, AOVs and the statistics `--stats` prints.

use crate::scene::LoadedScene;
use serde::Serialize;
use specula_raster::frame::{
    render_into, render_ldr, render_ldr_into, render_with, Frame, FrameStats, ShadePath,
};
use specula_raster::post::{downsample, LdrEncoding, Post, PostOutput, PostStage, Stage, Tonemap};
use specula_raster::{BufferSet, Target};
use std::sync::Arc;
use std::time::Instant;

#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub ssaa: u32,
    pub tonemap: Tonemap,
    pub exposure: f32,
    pub path: ShadePath,
    /// Worker threads; `None`: one per core.
    pub threads: Option<usize>,
    /// Frames to render (timed separately); the last one is kept.
    pub repeat: u32,
    /// Optional frame buffers to keep for AOVs (post stages add theirs).
    pub buffers: BufferSet,
    /// Image-space stages run after the tone map, before the encode.
    pub post_stages: Vec<Arc<dyn PostStage>>,
    /// Keep the linear colour of the last frame ([`Rendered::hdr`]: EXR
    /// outputs). Without it, a frame whose post list is the standard one
    /// at ssaa 1 is encoded to 8 bits inside the shading pass, tile row by
    /// tile row, with no colour planes written and read back (the same
    /// bytes; `post` then times nothing).
    pub keep_hdr: bool,
}

impl RenderSettings {
    /// The scene's own output settings.
    pub fn from_scene(s: &LoadedScene) -> RenderSettings {
        RenderSettings {
            width: s.output.width,
            height: s.output.height,
            ssaa: s.output.ssaa,
            tonemap: s.output.tonemap.into(),
            exposure: s.output.exposure,
            path: ShadePath::Simd,
            threads: None,
            repeat: 1,
            buffers: BufferSet::default(),
            post_stages: s.post_stages.clone(),
            keep_hdr: true,
        }
    }

    /// The post stages of a frame: resolve, exposure, tone map, the
    /// custom stages, encode (fused when there are no custom stages).
    pub fn post(&self) -> Post {
        let mut p = Post::standard(self.ssaa, self.exposure, self.tonemap);
        let encode = p.stages.pop();
        p.stages
            .extend(self.post_stages.iter().map(|s| Stage::Custom(s.instance())));
        p.stages.extend(encode);
        p
    }

    /// The 8-bit encoding the shading pass runs itself, when the post list
    /// allows it and no HDR output needs the linear colour.
    pub fn ldr_in_shading(&self) -> Option<LdrEncoding> {
        self.post().ldr_in_shading().filter(|_| !self.keep_hdr)
    }

    /// The supersampled render target; checks sizes before anything is
    /// allocated.
    pub fn target(&self) -> Result<Target, RenderError> {
        if self.ssaa == 0 || self.ssaa > 16 {
            return Err(RenderError::Ssaa(self.ssaa));
        }
        let w = self.width.checked_mul(self.ssaa);
        let h = self.height.checked_mul(self.ssaa);
        match (w, h) {
            (Some(w), Some(h)) if self.width > 0 && self.height > 0 => Target::new(w, h)
                .map(|t| t.with_ssaa(self.ssaa))
                .map_err(RenderError::from),
            _ => Err(RenderError::Size {
                width: self.width,
                height: self.height,
                ssaa: self.ssaa,
            }),
        }
    }
}

/// Why a frame cannot be rendered at its settings, or an AOV taken from it.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// A supersampling factor outside 1..=16.
    #[error("ssaa {0} is out of range: it must be 1..=16")]
    Ssaa(u32),
    /// An image side that is 0, or too large once supersampled.
    #[error(
        "image size {width}×{height} with ssaa {ssaa} is out of range: width and height must be ≥ 1 and at most {} after supersampling",
        specula_raster::target::MAX_DIM
    )]
    Size { width: u32, height: u32, ssaa: u32 },
    /// The render target refused its size (its message).
    #[error(transparent)]
    Target(#[from] specula_raster::target::TargetError),
    /// `--threads 0`.
    #[error("--threads must be at least 1")]
    Threads,
    /// The thread pool could not start.
    #[error("cannot start worker threads: {0}")]
    Pool(rayon::ThreadPoolBuildError),
    /// `--repeat 0`.
    #[error("--repeat must be at least 1")]
    Repeat,
    /// The post stages refused the frame.
    #[error(transparent)]
    Post(#[from] specula_raster::post::PostError),
    /// No frame was rendered.
    #[error("no frame rendered")]
    NoFrame,
    /// An AOV whose buffer the frame does not hold (`depth`, `normal`,
    /// `id`).
    #[error("the {0} AOV needs the {0} buffer (BufferSet::{0})")]
    MissingBuffer(&'static str),
}

/// The seam for the callers whose errors are still `String`s: `?` turns
/// the error into its message.
impl From<RenderError> for String {
    fn from(e: RenderError) -> String {
        e.to_string()
    }
}

/// Per-frame timings (ms) as `--stats` and `--stats-json` report them.
#[derive(Clone, Debug, Serialize)]
pub(crate) struct FrameTimes {
    pub(crate) vertex: f64,
    pub(crate) setup: f64,
    pub(crate) bin: f64,
    pub(crate) raster: f64,
    pub(crate) shade: f64,
    /// The shadow maps: fitting, depth passes, linear depth and PCF
    /// window bounds (0 without shadowed lights).
    pub(crate) shadow: f64,
    /// The post stages: supersampling resolve + exposure + tone mapping +
    /// sRGB encode (in memory).
    pub(crate) post: f64,
    /// The whole frame: vertex through post.
    pub(crate) frame: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct RunStats {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) ssaa: u32,
    pub(crate) threads: usize,
    pub(crate) shading: &'static str,
    /// The standard post list ran inside the shading pass (see
    /// [`RenderSettings::keep_hdr`]): `shade` includes it, `post` is 0.
    pub post_in_shading: bool,
    pub(crate) triangles_in: u64,
    pub(crate) culled_backface: u64,
    pub(crate) culled_outside: u64,
    pub(crate) culled_occluded: u64,
    pub(crate) skipped_invalid: u64,
    pub(crate) skipped_degenerate: u64,
    pub(crate) clipped: u64,
    pub(crate) drawn: u64,
    pub(crate) no_samples: u64,
    pub(crate) raster_triangles: u64,
    pub pixels_shaded: u64,
    /// Samples of blended surfaces shaded and composited (see
    /// [`specula_raster::frame::FrameStats::blended_samples`]).
    pub blended_samples: u64,
    /// Shadow-map depth passes per frame.
    pub(crate) shadow_passes: u32,
    /// Shadow-map faces per frame that see nothing (no depth pass).
    pub(crate) shadow_faces_blank: u32,
    /// What setup did with the triangles of a frame's depth passes, all
    /// of them together (each pass sets up the whole scene).
    pub(crate) shadow_triangles: ShadowTriangles,
    /// One entry per repeat.
    pub(crate) frame_ms: Vec<f64>,
    pub(crate) frames: Vec<FrameTimes>,
    /// Median frame's pixels (samples) per second, in millions.
    pub(crate) mpixels_per_s: f64,
    pub(crate) load_ms: f64,
    /// Writing files (PNG/EXR/AOVs); filled in by the caller.
    pub encode_ms: f64,
}

/// Setup's counts over a frame's shadow-map depth passes.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct ShadowTriangles {
    pub(crate) triangles_in: u64,
    pub(crate) culled_backface: u64,
    pub(crate) culled_outside: u64,
    pub(crate) skipped_invalid: u64,
    pub(crate) skipped_degenerate: u64,
    pub(crate) clipped: u64,
    pub(crate) drawn: u64,
    pub(crate) no_samples: u64,
}

impl ShadowTriangles {
    fn of(c: &specula_raster::setup::SetupCounts) -> ShadowTriangles {
        ShadowTriangles {
            triangles_in: c.triangles,
            culled_backface: c.culled_backface,
            culled_outside: c.culled_outside,
            skipped_invalid: c.skipped_invalid,
            skipped_degenerate: c.skipped_degenerate,
            clipped: c.clipped,
            drawn: c.drawn,
            no_samples: c.no_samples,
        }
    }
}

pub struct Rendered {
    pub width: u32,
    pub height: u32,
    pub ssaa: u32,
    /// Tone-mapped sRGB, 8-bit RGB row-major.
    pub ldr: Vec<u8>,
    pub frame: Frame,
    pub stats: RunStats,
}

impl Rendered {
    /// Linear HDR, row-major, after the supersampling resolve (for EXR).
    pub fn hdr(&self) -> Vec<[f32; 3]> {
        let b = &self.frame.buffers;
        assert!(
            !b.color.is_empty(),
            "the linear colour was not kept (RenderSettings::keep_hdr)"
        );
        downsample(&b.color, b.width, b.height, self.ssaa).interleaved()
    }
}

/// Median of a non-empty list.
pub fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[s.len() / 2]
}

/// Renders `settings.repeat` frames of the scene and keeps the last.
pub fn render_scene(
    scene: &LoadedScene,
    settings: &RenderSettings,
    load_ms: f64,
) -> Result<Rendered, RenderError> {
    let target = settings.target()?;
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = settings.threads {
        if n == 0 {
            return Err(RenderError::Threads);
        }
        // The frame's parallel work comes in tiles: threads beyond their
        // count (or the machine's cores, if more) would only be started
        // and left idle. The pixels do not depend on the count.
        let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
        pool = pool.num_threads(n.min(target.tile_count().max(cores)));
    }
    let pool = pool.build().map_err(RenderError::Pool)?;
    if settings.repeat == 0 {
        return Err(RenderError::Repeat);
    }
    let repeat = settings.repeat;
    let mut post = settings.post();
    post.validate(target.width, target.height)
        .map_err(RenderError::Post)?;
    let buffers = settings.buffers.union(post.buffers());
    let in_shading = settings.ldr_in_shading();
    pool.install(|| {
        let mut frames = Vec::new();
        let mut last: Option<(PostOutput, Frame)> = None;
        for _ in 0..repeat {
            let t0 = Instant::now();
            // Later frames reuse the previous frame's buffers, as a renderer
            // drawing frame after frame would.
            let (frame, out, post) = if let Some(enc) = in_shading {
                let (recycled, frame) = match last.take() {
                    Some((out, f)) => (out, Some(f)),
                    None => (PostOutput::default(), None),
                };
                let mut ldr = recycled.ldr.unwrap_or_default();
                let frame = match frame {
                    Some(mut f) => {
                        render_ldr_into(&scene.data, &mut f, settings.path, enc, &mut ldr);
                        f
                    }
                    None => render_ldr(&scene.data, target, settings.path, buffers, enc, &mut ldr),
                };
                let out = PostOutput {
                    width: target.width,
                    height: target.height,
                    hdr: None,
                    ldr: Some(ldr),
                };
                (frame, out, 0.0)
            } else {
                let (frame, recycled) = match last.take() {
                    Some((out, mut f)) => {
                        render_into(&scene.data, &mut f, settings.path);
                        (f, out)
                    }
                    None => (
                        render_with(&scene.data, target, settings.path, buffers),
                        PostOutput::default(),
                    ),
                };
                let tp = Instant::now();
                let out = post
                    .run_reusing(&frame.buffers, recycled)
                    .map_err(RenderError::Post)?;
                (frame, out, tp.elapsed().as_secs_f64() * 1e3)
            };
            let total = t0.elapsed().as_secs_f64() * 1e3;
            let t = frame.stats.times;
            frames.push(FrameTimes {
                vertex: t.vertex,
                setup: t.setup,
                bin: t.bin,
                raster: t.raster,
                shade: t.shade,
                shadow: t.shadow,
                post,
                frame: total,
            });
            last = Some((out, frame));
        }
        let (out, frame) = last.ok_or(RenderError::NoFrame)?;
        let mut ldr = out.ldr.unwrap_or_default();
        // Labels are placed in the scene's own pixels; --width rescales.
        let scale = settings.width as f32 / scene.output.width.max(1) as f32;
        crate::label::draw_labels(
            &mut ldr,
            settings.width,
            settings.height,
            &scene.output.labels,
            scale,
        );
        let frame_ms: Vec<f64> = frames.iter().map(|f| f.frame).collect();
        let stats = run_stats(
            &frame.stats,
            settings,
            rayon::current_num_threads(),
            frame_ms,
            frames,
            load_ms,
            target,
        );
        Ok(Rendered {
            width: settings.width,
            height: settings.height,
            ssaa: settings.ssaa,
            ldr,
            frame,
            stats,
        })
    })
}

fn run_stats(
    s: &FrameStats,
    settings: &RenderSettings,
    threads: usize,
    frame_ms: Vec<f64>,
    frames: Vec<FrameTimes>,
    load_ms: f64,
    target: Target,
) -> RunStats {
    let c = s.counts;
    RunStats {
        width: settings.width,
        height: settings.height,
        ssaa: settings.ssaa,
        threads,
        shading: match settings.path {
            ShadePath::Simd => "simd",
            ShadePath::SimdAvx2 => "simd-avx2",
            ShadePath::Scalar => "scalar",
        },
        post_in_shading: settings.ldr_in_shading().is_some(),
        triangles_in: c.triangles,
        culled_backface: c.culled_backface,
        culled_outside: c.culled_outside,
        culled_occluded: c.culled_occluded,
        skipped_invalid: c.skipped_invalid,
        skipped_degenerate: c.skipped_degenerate,
        clipped: c.clipped,
        drawn: c.drawn,
        no_samples: c.no_samples,
        raster_triangles: s.raster_triangles,
        pixels_shaded: s.pixels_shaded,
        blended_samples: s.blended_samples,
        shadow_passes: s.shadow_passes,
        shadow_faces_blank: s.shadow_faces_blank,
        shadow_triangles: ShadowTriangles::of(&s.shadow_counts),
        mpixels_per_s: target.pixel_count() as f64 / (median(&frame_ms) * 1e3),
        frame_ms,
        frames,
        load_ms,
        encode_ms: 0.0,
    }
}

impl RunStats {
    /// The human-readable report of `--stats`.
    pub fn report(&self) -> String {
        let mut s = String::new();
        let f = |v: &[f64]| median(v);
        let col =
            |pick: fn(&FrameTimes) -> f64| f(&self.frames.iter().map(pick).collect::<Vec<_>>());
        s += &format!(
            "{}×{} (ssaa {}), {} thread(s), {} shading, {} frame(s)\n",
            self.width,
            self.height,
            self.ssaa,
            self.threads,
            self.shading,
            self.frames.len()
        );
        s += &format!(
            "triangles: {} in, {} back-face culled, {} outside, {} hidden by earlier passes, {} invalid (NaN/huge), {} degenerate, {} clipped, {} drawn ({} screen triangles), {} between pixel centres\n",
            self.triangles_in,
            self.culled_backface,
            self.culled_outside,
            self.culled_occluded,
            self.skipped_invalid,
            self.skipped_degenerate,
            self.clipped,
            self.drawn,
            self.raster_triangles,
            self.no_samples
        );
        if self.shadow_passes > 0 {
            let t = &self.shadow_triangles;
            s += &format!(
                "shadow triangles (all depth passes): {} in, {} back-face culled, {} outside, {} invalid, {} degenerate, {} clipped, {} drawn, {} between texel centres\n",
                t.triangles_in,
                t.culled_backface,
                t.culled_outside,
                t.skipped_invalid,
                t.skipped_degenerate,
                t.clipped,
                t.drawn,
                t.no_samples
            );
        }
        s += &format!("pixels shaded: {}\n", self.pixels_shaded);
        if self.blended_samples > 0 {
            s += &format!("blended samples shaded: {}\n", self.blended_samples);
        }
        s += "pass times (ms, median over frames):\n";
        for (name, v) in [
            ("vertex", col(|t| t.vertex)),
            ("clip+setup", col(|t| t.setup)),
            ("bin", col(|t| t.bin)),
            ("raster", col(|t| t.raster)),
            ("shadow", col(|t| t.shadow)),
            ("shade", col(|t| t.shade)),
            ("post", col(|t| t.post)),
        ] {
            // Scenes without shadow maps; one whose shadowed lights cover
            // nothing still shows the time spent finding that out.
            if name == "shadow" && self.shadow_passes == 0 && v == 0.0 {
                continue;
            }
            s += &format!("  {name:<11}{v:9.2}");
            if name == "shadow" {
                s += &format!("   ({} depth passes", self.shadow_passes);
                if self.shadow_faces_blank > 0 {
                    s += &format!(", {} faces seeing nothing", self.shadow_faces_blank);
                }
                s += ")";
            }
            if name == "post" && self.post_in_shading {
                s += "   (exposure, tone map, sRGB encode ran inside shade)";
            }
            s += "\n";
        }
        s += &format!("  {:<11}{:9.2}\n", "encode", self.encode_ms);
        s += &format!(
            "  {:<11}{:9.2}   ({:.1} Mpixel/s)\n",
            "frame",
            col(|t| t.frame),
            self.mpixels_per_s
        );
        s += &format!("  {:<11}{:9.2}\n", "load", self.load_ms);
        if self.frames.len() > 1 {
            let list: Vec<String> = self.frame_ms.iter().map(|v| format!("{v:.2}")).collect();
            s += &format!("frame times (ms): {}\n", list.join(" "));
        }
        s
    }
}

/// Linear view depth per sample (+inf where nothing is hit), row-major at
/// the supersampled size; the frame must hold the depth buffer.
pub fn depth_aov(frame: &Frame) -> Result<Vec<[f32; 3]>, RenderError> {
    let d = &frame.buffers.depth;
    if d.is_empty() {
        return Err(RenderError::MissingBuffer("depth"));
    }
    Ok(d.iter().map(|&v| [v; 3]).collect())
}

/// World-space shading normal per sample (0 where nothing is hit); the
/// frame must hold the normal buffer.
pub fn normal_aov(frame: &Frame) -> Result<Vec<[f32; 3]>, RenderError> {
    let n = &frame.buffers.normal;
    if n.is_empty() {
        return Err(RenderError::MissingBuffer("normal"));
    }
    Ok((0..n.len()).map(|i| n.get(i)).collect())
}

/// Visibility-buffer ids per sample, row-major; the frame must hold the id
/// buffer.
pub fn id_aov(frame: &Frame) -> Result<&[u32], RenderError> {
    let ids = &frame.buffers.id;
    if ids.is_empty() {
        return Err(RenderError::MissingBuffer("id"));
    }
    Ok(ids)
}
