//! Outlines as image-space post stages, and what they share.
//!
//! The course notes name three ways to draw an outline; two of them run
//! here, after the tone map and before the sRGB encode, over the frame
//! buffers at the supersampled size:
//! - [`ShadingOutline`]: darken where the shading normal turns away from
//!   the eye (n·v below a threshold, with a soft edge). Its width follows
//!   the surface's curvature: a band of n·v < t on a sphere of projected
//!   radius R pixels is about R·(1 − √(1 − t²)) wide, so big spheres get
//!   thick lines, small ones thin, and a flat face is all dark or not at
//!   all (the known trade-off; `fixtures/scenes/npr-outlines.toml` shows it).
//! - [`crate::sobel::Sobel`]: edges in the depth, normal, id and colour
//!   buffers.
//!
//! The third, back faces extruded in a second geometry pass, is
//! [`crate::extrude`].
//!
//! Both stages compute a coverage in [0, 1] per sample, average it over
//! each output pixel's ssaa² samples (so a supersampled frame gives
//! anti-aliased lines of the same width in output pixels) and blend the
//! outline colour over the tone-mapped image in linear values:
//! `c = c·(1 − a) + colour·a`.

use rayon::prelude::*;
use specula_raster::geometry::IdMap;
use specula_raster::post::{HdrImage, PostStage};
use specula_raster::target::MISS;
use specula_raster::{BufferSet, Camera, FrameBuffers, SceneParts};

/// Material index of every id the scene's passes write (index = id;
/// u32::MAX for ids no pass writes).
pub fn id_materials(scene: &SceneParts) -> Vec<u32> {
    let end = scene
        .geometry
        .iter()
        .map(|p| p.ids().end)
        .max()
        .unwrap_or(0) as usize;
    let map = IdMap::new(&scene.geometry);
    let mut out = vec![u32::MAX; end];
    for p in &scene.geometry {
        for id in p.ids() {
            out[id as usize] = map.look_up(id as u32, &scene.tri_material).1;
        }
    }
    out
}

/// Which visibility-buffer ids a stage draws on: all, or those whose
/// material is in a set.
#[derive(Clone, Debug, Default)]
pub struct Selection {
    /// Per id: drawn; `None`: every covered pixel.
    ids: Option<Vec<bool>>,
}

impl Selection {
    /// Every covered pixel.
    pub fn all() -> Selection {
        Selection { ids: None }
    }

    /// Pixels whose material is one of `materials`; `id_material` is the
    /// scene's [`id_materials`] (so an outline pass's ids have the outline
    /// material).
    pub fn materials(id_material: &[u32], materials: &[u32]) -> Selection {
        let ids = id_material.iter().map(|m| materials.contains(m)).collect();
        Selection { ids: Some(ids) }
    }

    /// Whether the stage needs the id buffer to decide.
    pub(crate) fn needs_ids(&self) -> bool {
        self.ids.is_some()
    }

    /// Whether a pixel of id `id` (MISS: nothing) is drawn on. With a
    /// material set the frame must hold the id buffer.
    #[inline]
    pub(crate) fn contains(&self, id: u32) -> bool {
        match &self.ids {
            None => id != MISS,
            Some(v) => v.get(id as usize).copied().unwrap_or(false),
        }
    }
}

/// The supersampling factor between the frame buffers and the image a
/// post stage sees (1 when the stage runs before the resolve).
pub(crate) fn ssaa_of(img: &HdrImage, frame: &FrameBuffers) -> usize {
    (frame.width / img.width.max(1)).max(1) as usize
}

/// Blends `color` over `img` with the per-sample `coverage` (frame size,
/// values in [0, 1]) box-averaged over each pixel's ssaa² samples.
pub(crate) fn composite(
    img: &mut HdrImage,
    frame: &FrameBuffers,
    coverage: &[f32],
    color: [f32; 3],
) {
    let ssaa = ssaa_of(img, frame);
    let (w, sw) = (img.width as usize, frame.width as usize);
    let inv = 1.0 / (ssaa * ssaa) as f32;
    let p = &mut img.rgb;
    p.r.par_chunks_mut(w.max(1))
        .zip(p.g.par_chunks_mut(w.max(1)))
        .zip(p.b.par_chunks_mut(w.max(1)))
        .enumerate()
        .for_each_init(Vec::new, |acc, (y, ((r, g), b))| {
            // At ssaa 1 the sum is the sample itself (0 + c = c): read the
            // coverage row in place, no scratch row to clear and copy.
            let acc: &[f32] = if ssaa == 1 {
                &coverage[y * sw..y * sw + r.len()]
            } else {
                sum_samples(acc, r.len(), ssaa, |sy| {
                    &coverage[(y * ssaa + sy) * sw..][..r.len() * ssaa]
                });
                acc
            };
            blend_row([r, g, b], acc, inv, color);
        });
}

/// Each of `n` pixels' coverage summed over its ssaa² samples into `acc`;
/// `sample_row(sy)` is the pixels' sample row sy (n·ssaa samples). Row by
/// row over the pixel's samples: the same sums in the same order as
/// pixel by pixel, without the per-pixel slicing.
pub(crate) fn sum_samples<'a>(
    acc: &mut Vec<f32>,
    n: usize,
    ssaa: usize,
    sample_row: impl Fn(usize) -> &'a [f32],
) {
    acc.clear();
    acc.resize(n, 0.0f32);
    for sy in 0..ssaa {
        for (a, c) in acc.iter_mut().zip(sample_row(sy).chunks_exact(ssaa)) {
            *a += c.iter().sum::<f32>();
        }
    }
}

/// [`blend`] along a row: `acc` is each pixel's summed coverage, `inv`
/// 1/ssaa².
#[inline]
pub(crate) fn blend_row(rgb: [&mut [f32]; 3], acc: &[f32], inv: f32, color: [f32; 3]) {
    let [r, g, b] = rgb;
    // Where a = 0 the blend gives c·1 + colour·0 = c: no branch.
    for (((r, g), b), &a) in r
        .iter_mut()
        .zip(g.iter_mut())
        .zip(b.iter_mut())
        .zip(acc.iter())
    {
        blend([r, g, b], a * inv, color);
    }
}

/// c = c·(1 − a) + colour·a per channel (a pixel's coverage a).
#[inline(always)]
pub(crate) fn blend(rgb: [&mut f32; 3], a: f32, color: [f32; 3]) {
    let [r, g, b] = rgb;
    *r = *r * (1.0 - a) + color[0] * a;
    *g = *g * (1.0 - a) + color[1] * a;
    *b = *b * (1.0 - a) + color[2] * a;
}

/// Outline by shading (module docs): coverage 1 where n·v ≤ t − s/2, 0
/// where n·v ≥ t + s/2, linear between (s = [`ShadingOutline::softness`]).
#[derive(Clone, Debug)]
pub struct ShadingOutline {
    pub(crate) camera: Camera,
    /// n·v threshold in (0, 1): where the coverage is ½.
    pub(crate) threshold: f32,
    /// Width of the soft edge in n·v.
    pub softness: f32,
    pub(crate) color: [f32; 3],
    pub(crate) selection: Selection,
}

impl ShadingOutline {
    /// The stage with the default soft edge: 0.05 in n·v, less for small
    /// thresholds so n·v = 0 is never softened.
    pub fn new(camera: Camera, threshold: f32, color: [f32; 3], selection: Selection) -> Self {
        ShadingOutline {
            camera,
            threshold,
            softness: 0.05f32.min(threshold),
            color,
            selection,
        }
    }

    /// Coverage of one sample from its n·v.
    #[inline]
    pub(crate) fn coverage(&self, n_dot_v: f32) -> f32 {
        ((self.threshold - n_dot_v) / self.softness + 0.5).clamp(0.0, 1.0)
    }

    /// Per-sample coverage over the frame (frame size).
    pub fn coverage_map(&self, frame: &FrameBuffers) -> Vec<f32> {
        let (w, h) = (frame.width as usize, frame.height as usize);
        let view = self.camera.view(frame.width, frame.height);
        let mut out = vec![0.0f32; w * h];
        out.par_chunks_mut(w.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                for (x, c) in row.iter_mut().enumerate() {
                    let i = y * w + x;
                    let n = frame.normal.get(i);
                    let id = frame.id.get(i).copied().unwrap_or(0);
                    if n == [0.0; 3] || !self.selection.contains(id) {
                        continue;
                    }
                    let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
                    let (nx, ny) = (2.0 * px / w as f32 - 1.0, 1.0 - 2.0 * py / h as f32);
                    let d =
                        view.forward + view.right * (nx * view.tan_x) + view.up * (ny * view.tan_y);
                    let wo = -d.normalize();
                    *c = self.coverage(n[0] * wo.x + n[1] * wo.y + n[2] * wo.z);
                }
            });
        out
    }
}

impl PostStage for ShadingOutline {
    fn name(&self) -> &str {
        "outline-shading"
    }

    fn buffers(&self) -> BufferSet {
        BufferSet {
            normal: true,
            id: self.selection.needs_ids(),
            ..BufferSet::default()
        }
    }

    fn instance(&self) -> Box<dyn PostStage> {
        Box::new(self.clone())
    }

    fn apply(&mut self, img: &mut HdrImage, frame: &FrameBuffers) {
        let cov = self.coverage_map(frame);
        composite(img, frame, &cov, self.color);
    }
}
