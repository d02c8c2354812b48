//! Posterization: the number of 8-bit codes per channel after the encode,
//! the level values against the sRGB formula, luminance mode keeping hue,
//! and the stage in a post list next to the fused standard path.

use specula_npr::posterize::{Posterize, PosterizeMode};
use specula_raster::post::{Post, Stage, Tonemap};
use specula_raster::{BufferSet, FrameBuffers, Target};
use std::collections::BTreeSet;

/// A 240 × 120 frame whose red ramps 0 → 1.2 along x, green along y, blue
/// through the whole frame: every tone-mapped value of [0, 1] occurs.
fn ramp_frame() -> FrameBuffers {
    let t = Target::new(240, 120).unwrap();
    let mut fb = FrameBuffers::new(&t, BufferSet::default());
    for y in 0..120 {
        for x in 0..240 {
            let i = y * 240 + x;
            fb.color.r[i] = 1.2 * x as f32 / 239.0;
            fb.color.g[i] = y as f32 / 119.0;
            fb.color.b[i] = i as f32 / (240.0 * 120.0 - 1.0);
        }
    }
    fb
}

fn with_stage(stage: Posterize) -> Post {
    let mut p = Post::standard(1, 0.0, Tonemap::Clamp);
    p.stages.insert(3, Stage::Custom(Box::new(stage)));
    p
}

#[test]
fn rgb_mode_leaves_exactly_levels_codes_per_channel() {
    let fb = ramp_frame();
    for levels in [2u32, 3, 4, 7, 16] {
        let out = with_stage(Posterize::new(levels, PosterizeMode::Rgb).unwrap())
            .run(&fb)
            .unwrap();
        let ldr = out.ldr.unwrap();
        for c in 0..3 {
            let codes: BTreeSet<u8> = ldr.iter().skip(c).step_by(3).copied().collect();
            assert_eq!(
                codes.len(),
                levels as usize,
                "levels {levels} channel {c}: {codes:?}"
            );
            // Level k encodes to 255 k/(L − 1), rounded (either way at a tie).
            for (k, code) in codes.iter().enumerate() {
                let want = 255.0 * k as f64 / (levels - 1) as f64;
                assert!(
                    (*code as f64 - want).abs() <= 0.5 + 1e-9,
                    "{levels}: {code} vs {want}"
                );
            }
        }
    }
}

#[test]
fn values_go_to_the_level_nearest_in_encoded_terms() {
    let p = Posterize::new(5, PosterizeMode::Rgb).unwrap();
    let srgb = |v: f64| {
        if v <= 0.0031308 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        }
    };
    for i in 0..=1000 {
        let v = i as f32 / 1000.0;
        let k = (srgb(v as f64) * 4.0).round();
        let got = srgb(p.quantize(v) as f64) * 4.0;
        // Off by one level only exactly at a cut (a tie).
        let tie = ((srgb(v as f64) * 4.0).fract() - 0.5).abs() < 1e-5;
        assert!(tie || (got - k).abs() < 1e-4, "v {v}: level {got} vs {k}");
    }
    assert_eq!(p.quantize(f32::NAN), 0.0);
    assert_eq!(p.quantize(-3.0), 0.0);
    assert_eq!(p.quantize(7.0), 1.0);
    let err = Posterize::new(1, PosterizeMode::Rgb).unwrap_err();
    assert_eq!(err.field, "levels");
    assert!(err.to_string().starts_with("levels: "), "{err}");
}

#[test]
fn luminance_mode_quantizes_y_and_keeps_hue() {
    let fb = ramp_frame();
    let levels = 4;
    let stage = Posterize::new(levels, PosterizeMode::Luminance).unwrap();
    let values: Vec<f64> = stage.level_values().iter().map(|&v| v as f64).collect();
    let mut post = with_stage(stage);
    post.stages.pop(); // keep the HDR image after the stage
    let out = post.run(&fb).unwrap().hdr.unwrap();
    let mut seen = BTreeSet::new();
    for i in 0..out.rgb.r.len() {
        let before = [fb.color.r[i], fb.color.g[i], fb.color.b[i]].map(|v| v.min(1.0) as f64);
        let after = out.rgb.get(i).map(|v| v as f64);
        let y = 0.2126 * after[0] + 0.7152 * after[1] + 0.0722 * after[2];
        let max = after.iter().cloned().fold(0.0, f64::max);
        let capped = (max - 1.0).abs() < 1e-6;
        if !capped {
            let k = values
                .iter()
                .position(|v| (v - y).abs() < 2e-5)
                .unwrap_or_else(|| panic!("pixel {i}: luminance {y} is not a level of {values:?}"));
            seen.insert(k);
        }
        // Hue kept: after = k · before for one k ≥ 0.
        let bmax = before.iter().cloned().fold(0.0, f64::max);
        if bmax > 1e-3 && max > 1e-3 {
            let k = max / bmax;
            for c in 0..3 {
                assert!(
                    (after[c] - k * before[c]).abs() < 1e-4,
                    "pixel {i}: {before:?} → {after:?}"
                );
            }
        }
    }
    assert!(seen.len() <= levels as usize && seen.len() >= 3, "{seen:?}");
}

#[test]
fn a_list_with_posterize_runs_unfused_and_256_levels_change_almost_nothing() {
    let fb = ramp_frame();
    let plain = Post::standard(1, 0.0, Tonemap::Clamp).run(&fb).unwrap();
    assert!(plain.hdr.is_none(), "the standard list is fused");
    let out = with_stage(Posterize::new(256, PosterizeMode::Rgb).unwrap())
        .run(&fb)
        .unwrap();
    assert!(
        out.hdr.is_some(),
        "a list with a custom stage runs stage by stage"
    );
    let (a, b) = (plain.ldr.unwrap(), out.ldr.unwrap());
    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    let off_by_more = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| x.abs_diff(**y) > 1)
        .count();
    // 256 levels are the 8-bit codes themselves: only ties may round apart.
    assert_eq!(off_by_more, 0);
    assert!(
        differ * 1000 < a.len(),
        "{differ} of {} values differ",
        a.len()
    );
}
