//! After shading: a list of named post stages ([`Post`]) over the frame
//! buffers: downsampling the supersamples (box filter, in linear HDR), exposure,
//! tone mapping and the one sRGB encode at the very end, plus any custom
//! image-space stage ([`PostStage`]) where the list puts it. The standard
//! list runs fused in one pass over the samples (`downsample_ldr_into`).
//!
//! This file holds the stage list and how it runs ([`Post`], [`Stage`],
//! [`PostStage`], [`HdrImage`]); the tone curves are in `tonemap`, the sRGB
//! transfer function and its 8-bit encoders in `srgb`, the fused 8-bit
//! encode ([`LdrEncoding`], [`encode_ldr`]) in `encode` and the
//! downsampling of the supersamples ([`downsample`], `downsample_ldr_into`,
//! `downsample_hdr_into`) in `downsample`.

mod downsample;
mod encode;
mod srgb;
mod tonemap;

pub use downsample::downsample;
pub(crate) use downsample::{downsample_hdr_into, downsample_ldr_into};
pub(crate) use encode::encode_ldr_into;
pub use encode::{encode_ldr, LdrEncoding};
pub use srgb::{srgb_curve_inverse, srgb_encode};
pub use tonemap::Tonemap;

use crate::buffers::{BufferSet, FrameBuffers, Planes3};
use rayon::prelude::*;

/// A linear HDR image between post stages: row-major planes.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrImage {
    pub width: u32,
    pub height: u32,
    pub rgb: Planes3,
}

impl HdrImage {
    /// Interleaved [r, g, b] per pixel, row-major (for image writers).
    pub fn interleaved(&self) -> Vec<[f32; 3]> {
        (0..self.rgb.len()).map(|i| self.rgb.get(i)).collect()
    }
}

/// An image-space stage from outside this crate (npr's Sobel outlines,
/// posterization, ...). It runs where the post list puts it: on the
/// supersampled image before [`Stage::Downsample`], on the output image after
/// it (`img.width` tells), in linear HDR before [`Stage::Tonemap`] and in
/// tone-mapped [0, 1] values after it.
///
/// A scene holds each stage as built; a [`Post`] list runs its own
/// instance ([`PostStage::instance`]), which may keep buffers in its own
/// fields from frame to frame.
pub trait PostStage: std::fmt::Debug + Send + Sync {
    fn name(&self) -> &str;
    /// The frame buffers the stage reads (colour is always there).
    fn buffers(&self) -> BufferSet {
        BufferSet::default()
    }
    /// A stage for a run of frames: the same construction, none of an
    /// earlier frame's buffers.
    fn instance(&self) -> Box<dyn PostStage>;
    /// Transforms `img`; `frame` holds the shading pass's buffers at the
    /// supersampled size.
    fn apply(&mut self, img: &mut HdrImage, frame: &FrameBuffers);
}

/// Why [`Post::validate`] refused a stage list.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PostError {
    #[error("post: \"encode\" must be the last stage")]
    EncodeNotLast,
    #[error("post: resolve factor {ssaa} does not divide the {width}×{height} frame")]
    ResolveFactor { ssaa: u32, width: u32, height: u32 },
    #[error("post: more than one resolve stage")]
    TwoResolves,
}

/// One named step of the post list.
#[derive(Debug)]
pub enum Stage {
    /// Box-filters ssaa × ssaa samples into one pixel (linear HDR).
    Downsample {
        ssaa: u32,
    },
    /// Multiplies radiance by 2^stops.
    Exposure {
        stops: f32,
    },
    /// Per channel tone curve into [0, 1]; NaN and negatives become 0.
    Tonemap(Tonemap),
    /// sRGB encoding to 8 bits; the last stage when present.
    Encode,
    Custom(Box<dyn PostStage>),
}

/// A copy of a list runs fresh instances of its custom stages.
impl Clone for Stage {
    fn clone(&self) -> Stage {
        match self {
            Stage::Downsample { ssaa } => Stage::Downsample { ssaa: *ssaa },
            Stage::Exposure { stops } => Stage::Exposure { stops: *stops },
            Stage::Tonemap(t) => Stage::Tonemap(*t),
            Stage::Encode => Stage::Encode,
            Stage::Custom(c) => Stage::Custom(c.instance()),
        }
    }
}

/// What the post list produced: the final HDR image (after the last stage
/// before `Encode`) unless the fused path ran, and the 8-bit sRGB pixels
/// (RGB, row-major) if the list encodes.
#[derive(Debug, Default)]
pub struct PostOutput {
    pub width: u32,
    pub height: u32,
    pub hdr: Option<HdrImage>,
    pub ldr: Option<Vec<u8>>,
}

/// The post stages of a frame, in order.
#[derive(Clone, Debug)]
pub struct Post {
    pub stages: Vec<Stage>,
    /// Run `downsample_ldr_into` (one pass over the samples, no HDR image in
    /// between) when the list is exactly downsample, exposure, tone map,
    /// encode. Off only to measure what fusing is worth.
    pub fuse: bool,
}

impl Post {
    /// The default list: downsample, exposure, tone map, encode.
    pub fn standard(ssaa: u32, stops: f32, tonemap: Tonemap) -> Post {
        Post {
            stages: vec![
                Stage::Downsample { ssaa },
                Stage::Exposure { stops },
                Stage::Tonemap(tonemap),
                Stage::Encode,
            ],
            fuse: true,
        }
    }

    /// The optional frame buffers the stages read.
    pub fn buffers(&self) -> BufferSet {
        self.stages
            .iter()
            .fold(BufferSet::default(), |acc, s| match s {
                Stage::Custom(c) => acc.union(c.buffers()),
                _ => acc,
            })
    }

    /// Checks the list: `Encode` only last, one `Resolve` at most, whose
    /// factor divides the frame size.
    pub fn validate(&self, width: u32, height: u32) -> Result<(), PostError> {
        let n = self.stages.len();
        let mut resolves = 0;
        for (i, s) in self.stages.iter().enumerate() {
            match s {
                Stage::Encode if i + 1 != n => return Err(PostError::EncodeNotLast),
                Stage::Downsample { ssaa } => {
                    resolves += 1;
                    if *ssaa == 0 || !width.is_multiple_of(*ssaa) || !height.is_multiple_of(*ssaa) {
                        return Err(PostError::ResolveFactor {
                            ssaa: *ssaa,
                            width,
                            height,
                        });
                    }
                }
                _ => {}
            }
        }
        if resolves > 1 {
            return Err(PostError::TwoResolves);
        }
        Ok(())
    }

    /// The fused form's parameters, if the list has that shape.
    fn fused_form(&self) -> Option<(u32, f32, Tonemap)> {
        match self.stages.as_slice() {
            [Stage::Downsample { ssaa }, Stage::Exposure { stops }, Stage::Tonemap(t), Stage::Encode]
                if self.fuse =>
            {
                Some((*ssaa, *stops, *t))
            }
            _ => None,
        }
    }

    /// The list as an encoding the shading pass can run itself: the fused
    /// standard list at ssaa 1 (no downsampling, no custom stage).
    pub fn ldr_in_shading(&self) -> Option<LdrEncoding> {
        match self.fused_form()? {
            (1, stops, tonemap) => Some(LdrEncoding::new(tonemap, stops)),
            _ => None,
        }
    }

    /// The fused head's parameters when the list starts downsample, exposure,
    /// tone map (custom stages and the encode after them).
    fn fused_head(&self) -> Option<(u32, f32, Tonemap)> {
        match self.stages.as_slice() {
            [Stage::Downsample { ssaa }, Stage::Exposure { stops }, Stage::Tonemap(t), ..]
                if self.fuse =>
            {
                Some((*ssaa, *stops, *t))
            }
            _ => None,
        }
    }

    /// Runs the stages over the frame's colour.
    pub fn run(&mut self, frame: &FrameBuffers) -> Result<PostOutput, PostError> {
        self.run_reusing(frame, PostOutput::default())
    }

    /// [`Post::run`] writing into the buffers of `recycled`, an earlier
    /// frame's output, whose allocations are reused (their contents are
    /// all overwritten): a fresh frame's 8-bit pixels and HDR planes are
    /// thousands of pages, each a page fault in which the kernel zeroes
    /// what the post then overwrites anyway (`perf stat -e page-faults`
    /// over `--repeat 10` shows it).
    ///
    /// With `fuse` set, the standard list runs as one pass over the samples
    /// (`downsample_ldr_into`), and a list that starts with downsample, exposure and
    /// tone map and then has custom stages runs that head as one pass into
    /// the HDR image (`downsample_hdr_into`); both give the bytes of the
    /// stage-by-stage list (tested).
    pub fn run_reusing(
        &mut self,
        frame: &FrameBuffers,
        recycled: PostOutput,
    ) -> Result<PostOutput, PostError> {
        self.validate(frame.width, frame.height)?;
        let mut ldr_buf = recycled.ldr.unwrap_or_default();
        if let Some((ssaa, stops, tonemap)) = self.fused_form() {
            downsample_ldr_into(frame, ssaa, tonemap, stops, &mut ldr_buf);
            return Ok(PostOutput {
                width: frame.width / ssaa,
                height: frame.height / ssaa,
                hdr: None,
                ldr: Some(ldr_buf),
            });
        }
        let mut rgb = recycled.hdr.map(|h| h.rgb).unwrap_or_default();
        let (mut img, rest) = match self.fused_head() {
            Some((ssaa, stops, tonemap)) => {
                downsample_hdr_into(frame, ssaa, tonemap, stops, &mut rgb);
                let img = HdrImage {
                    width: frame.width / ssaa,
                    height: frame.height / ssaa,
                    rgb,
                };
                (img, &mut self.stages[3..])
            }
            None => {
                copy_planes(&frame.color, &mut rgb);
                let img = HdrImage {
                    width: frame.width,
                    height: frame.height,
                    rgb,
                };
                (img, &mut self.stages[..])
            }
        };
        let mut ldr = None;
        for s in rest {
            match s {
                Stage::Downsample { ssaa: 1 } => {}
                Stage::Downsample { ssaa } => {
                    img = downsample(&img.rgb, img.width, img.height, *ssaa)
                }
                Stage::Exposure { stops } => {
                    let k = stops.exp2();
                    for p in [&mut img.rgb.r, &mut img.rgb.g, &mut img.rgb.b] {
                        p.par_iter_mut().for_each(|v| *v *= k);
                    }
                }
                Stage::Tonemap(t) => {
                    let t = *t;
                    for p in [&mut img.rgb.r, &mut img.rgb.g, &mut img.rgb.b] {
                        p.par_iter_mut().for_each(|v| *v = t.apply(*v));
                    }
                }
                Stage::Encode => {
                    encode_ldr_into(&img.rgb, &mut ldr_buf);
                    ldr = Some(std::mem::take(&mut ldr_buf));
                }
                Stage::Custom(c) => c.apply(&mut img, frame),
            }
        }
        Ok(PostOutput {
            width: img.width,
            height: img.height,
            hdr: Some(img),
            ldr,
        })
    }
}

/// Copies `src` into `dst`, reusing `dst`'s allocations.
fn copy_planes(src: &Planes3, dst: &mut Planes3) {
    for (d, s) in [
        (&mut dst.r, &src.r),
        (&mut dst.g, &src.g),
        (&mut dst.b, &src.b),
    ] {
        d.clear();
        d.extend_from_slice(s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fused_post_equals_the_stage_list() {
        let t = crate::Target::new(150, 90).unwrap();
        let mut fb = FrameBuffers::new(&t, BufferSet::default());
        // Values across the curves' whole range, negatives, NaN and inf
        // included; 150 and 50 pixels wide exercise the 8-pixel path and
        // its scalar tail.
        let f = |i: usize, c: f32| match i % 97 {
            0 => f32::NAN,
            1 => f32::INFINITY,
            2 => -1.0,
            _ => ((i as f32 * 0.37 + c).sin() * 2.0).max(0.0) * (1 + i % 5) as f32,
        };
        for i in 0..fb.color.len() {
            fb.color.r[i] = f(i, 0.0);
            fb.color.g[i] = f(i, 1.0);
            fb.color.b[i] = f(i, 2.0);
        }
        for ssaa in [1, 3] {
            for tonemap in [Tonemap::Clamp, Tonemap::Reinhard, Tonemap::Aces] {
                let mut fused = Post::standard(ssaa, 0.5, tonemap);
                let mut staged = fused.clone();
                staged.fuse = false;
                let (a, b) = (fused.run(&fb).unwrap(), staged.run(&fb).unwrap());
                assert!(a.hdr.is_none() && b.hdr.is_some());
                assert_eq!((a.width, a.height), (150 / ssaa, 90 / ssaa));
                assert_eq!(a.ldr, b.ldr, "ssaa {ssaa} {tonemap:?}");
            }
        }
    }

    /// A custom stage for the tests: scales each pixel by a factor that
    /// depends on its position, so a stage that saw the wrong image, size
    /// or stale values would change the output.
    #[derive(Debug)]
    struct Ramp;

    impl PostStage for Ramp {
        fn name(&self) -> &str {
            "ramp"
        }

        fn instance(&self) -> Box<dyn PostStage> {
            Box::new(Ramp)
        }

        fn apply(&mut self, img: &mut HdrImage, _frame: &FrameBuffers) {
            let w = img.width as usize;
            for p in [&mut img.rgb.r, &mut img.rgb.g, &mut img.rgb.b] {
                for (i, v) in p.iter_mut().enumerate() {
                    *v *= 0.5 + (i % w) as f32 / w as f32;
                }
            }
        }
    }

    #[test]
    fn fused_head_equals_the_stage_list_and_reuses_dirty_buffers() {
        let t = crate::Target::new(150, 90).unwrap();
        let mut fb = FrameBuffers::new(&t, BufferSet::default());
        for i in 0..fb.color.len() {
            let v = |c: f32| match i % 89 {
                0 => f32::NAN,
                1 => f32::INFINITY,
                2 => -0.5,
                _ => ((i as f32 * 0.23 + c).cos() * 1.7).abs() * (1 + i % 3) as f32,
            };
            fb.color.r[i] = v(0.0);
            fb.color.g[i] = v(1.0);
            fb.color.b[i] = v(2.0);
        }
        for ssaa in [1, 3] {
            for tonemap in [Tonemap::Clamp, Tonemap::Reinhard, Tonemap::Aces] {
                let mut fused = Post::standard(ssaa, -0.75, tonemap);
                let encode = fused.stages.pop().unwrap();
                fused.stages.push(Stage::Custom(Box::new(Ramp)));
                fused.stages.push(encode);
                let mut staged = fused.clone();
                staged.fuse = false;
                let want = staged.run(&fb).unwrap();
                // Buffers of another size full of garbage, as a recycled
                // frame of a different scene would leave.
                let dirty = || PostOutput {
                    width: 7,
                    height: 3,
                    hdr: Some(HdrImage {
                        width: 7,
                        height: 3,
                        rgb: Planes3 {
                            r: vec![9.0; 60_000],
                            g: vec![f32::NAN; 21],
                            b: vec![],
                        },
                    }),
                    ldr: Some(vec![0x5A; 100]),
                };
                for got in [
                    fused.run(&fb).unwrap(),
                    fused.run_reusing(&fb, dirty()).unwrap(),
                ] {
                    let tag = format!("ssaa {ssaa} {tonemap:?}");
                    assert_eq!((got.width, got.height), (150 / ssaa, 90 / ssaa), "{tag}");
                    assert!(got.hdr == want.hdr, "HDR image, {tag}");
                    assert!(got.ldr == want.ldr, "8-bit image, {tag}");
                }
                let staged_reused = staged.run_reusing(&fb, dirty()).unwrap();
                assert!(staged_reused.hdr == want.hdr && staged_reused.ldr == want.ldr);
            }
        }
    }

    #[test]
    fn post_lists_are_checked() {
        let t = crate::Target::new(150, 90).unwrap();
        let fb = FrameBuffers::new(&t, BufferSet::default());
        let mut p = Post::standard(4, 0.0, Tonemap::Clamp);
        let ssaa4 = PostError::ResolveFactor {
            ssaa: 4,
            width: 150,
            height: 90,
        };
        assert_eq!(p.run(&fb).unwrap_err(), ssaa4);
        p.stages = vec![Stage::Encode, Stage::Tonemap(Tonemap::Clamp)];
        assert_eq!(p.run(&fb).unwrap_err(), PostError::EncodeNotLast);
    }
}
