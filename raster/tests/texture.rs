//! The texture sampler against plain f64 formulas written here: bilinear
//! weights, wrap modes, the box-filtered mip chain, level selection on a
//! slanted plane, and f32x8 against the scalar twin lane by lane.

use rand::{Rng, SeedableRng};
use specula_core::{f32x8, Real};
use specula_raster::texture::{Encoding, Filter, Sampler, Texture, TextureError, Wrap};

/// Texel index i wrapped into 0..n, the textbook way.
fn wrap_ref(mode: Wrap, i: i64, n: i64) -> i64 {
    match mode {
        Wrap::Clamp => i.clamp(0, n - 1),
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::Mirror => {
            let r = i.rem_euclid(2 * n);
            if r < n {
                r
            } else {
                2 * n - 1 - r
            }
        }
    }
}

/// Bilinear value of a single-level image `img` (w × h, one channel) at uv:
/// texel centres at (i + ½)/w.
fn bilinear_ref(img: &[f64], w: i64, h: i64, mode: Wrap, u: f64, v: f64) -> f64 {
    let (x, y) = (u * w as f64 - 0.5, v * h as f64 - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let t = |i: i64, j: i64| {
        let (i, j) = (wrap_ref(mode, i, w), wrap_ref(mode, j, h));
        img[(j * w + i) as usize]
    };
    let (i, j) = (x0 as i64, y0 as i64);
    (1.0 - fx) * (1.0 - fy) * t(i, j)
        + fx * (1.0 - fy) * t(i + 1, j)
        + (1.0 - fx) * fy * t(i, j + 1)
        + fx * fy * t(i + 1, j + 1)
}

const MODES: [Wrap; 3] = [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror];

#[test]
fn bilinear_weights_match_the_formula_in_every_wrap_mode() {
    let (w, h) = (3usize, 2usize);
    let img: Vec<f64> = (0..w * h).map(|k| (k * k) as f64 * 0.25 + 1.0).collect();
    let tex = Texture::from_f32(w, h, 1, img.iter().map(|&v| v as f32).collect()).unwrap();
    // A hand-checked case: 2 × 1 values (1, 3) at u = 0.375 (x = 0.25
    // between the centres 0 and 1): 0.75 · 1 + 0.25 · 3 = 1.5.
    let two = Texture::from_f32(2, 1, 1, vec![1.0, 3.0]).unwrap();
    let s = Sampler::new(Wrap::Clamp, Filter::Bilinear);
    let [v]: [f64; 1] = two.sample_lod(&s, [0.375, 0.5], 0.0);
    assert!((v - 1.5).abs() < 1e-7, "{v}");
    // Repeat at u = 0.1: x = −0.3 blends texel 1 (0.3) with texel 0 (0.7).
    let s = Sampler::new(Wrap::Repeat, Filter::Bilinear);
    let [v]: [f64; 1] = two.sample_lod(&s, [0.1, 0.5], 0.0);
    assert!((v - (0.3 * 3.0 + 0.7 * 1.0)).abs() < 1e-7, "{v}");

    for mode in MODES {
        let s = Sampler::new(mode, Filter::Bilinear);
        for k in 0..400 {
            let u = -1.7 + k as f64 * 0.0113;
            let v = 2.3 - k as f64 * 0.0131;
            let want = bilinear_ref(&img, w as i64, h as i64, mode, u, v);
            let [got]: [f64; 1] = tex.sample_lod(&s, [u, v], 0.0);
            assert!(
                (got - want).abs() < 1e-6,
                "{mode:?} at ({u}, {v}): {got} vs {want}"
            );
        }
    }
}

#[test]
fn wrap_modes_pick_the_expected_texels() {
    let tex = Texture::from_f32(4, 1, 1, vec![0.0, 1.0, 2.0, 3.0]).unwrap();
    // (u, repeat, clamp, mirror), by hand: repeat reads u mod 1, clamp the
    // edge, mirror reads 2 − u on [1, 2).
    let cases = [
        (0.1, 0.0, 0.0, 0.0),
        (0.6, 2.0, 2.0, 2.0),
        (1.1, 0.0, 3.0, 3.0),
        (1.6, 2.0, 3.0, 1.0),
        (-0.1, 3.0, 0.0, 0.0),
        (-0.6, 1.0, 0.0, 2.0),
        (2.1, 0.0, 3.0, 0.0),
        (-1.1, 3.0, 0.0, 3.0),
    ];
    for (u, rep, cla, mir) in cases {
        for (mode, want) in [(Wrap::Repeat, rep), (Wrap::Clamp, cla), (Wrap::Mirror, mir)] {
            let s = Sampler::new(mode, Filter::Nearest);
            let [got]: [f32; 1] = tex.sample_lod(&s, [u, 0.5], 0.0);
            assert_eq!(got, want, "{mode:?} at u = {u}");
            let [got64]: [f64; 1] = tex.sample_lod(&s, [u as f64, 0.5], 0.0);
            assert_eq!(got64, want as f64, "{mode:?} at u = {u} (f64)");
        }
    }
}

#[test]
fn mip_levels_are_area_averages_and_keep_the_mean() {
    // 4 × 4 → 2 × 2: each the mean of a 2 × 2 block.
    let img: Vec<f32> = (0..16).map(|k| k as f32).collect();
    let t = Texture::from_f32(4, 4, 1, img.clone()).unwrap();
    assert_eq!(t.level_count(), 3);
    assert_eq!(t.level_size(1), (2, 2));
    let block = |x: usize, y: usize| {
        (img[y * 8 + x * 2]
            + img[y * 8 + x * 2 + 1]
            + img[y * 8 + x * 2 + 4]
            + img[y * 8 + x * 2 + 5])
            / 4.0
    };
    for (x, y) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        assert!((t.texel(1, x, y, 0) - block(x, y)).abs() < 1e-6);
    }
    assert!((t.texel(2, 0, 0, 0) - 7.5).abs() < 1e-6);

    // 5 × 3 → 2 × 1: target column 0 covers source [0, 2.5): texels 0 and 1
    // whole, half of texel 2; each row weighs 1/3.
    let img: Vec<f32> = (0..15).map(|k| ((k * 7) % 11) as f32).collect();
    let t = Texture::from_f32(5, 3, 1, img.clone()).unwrap();
    assert_eq!(t.level_size(1), (2, 1));
    let col = |x: usize| (0..3).map(|y| img[y * 5 + x] as f64).sum::<f64>() / 3.0;
    let want0 = (col(0) + col(1) + 0.5 * col(2)) / 2.5;
    let want1 = (0.5 * col(2) + col(3) + col(4)) / 2.5;
    assert!((t.texel(1, 0, 0, 0) as f64 - want0).abs() < 1e-5);
    assert!((t.texel(1, 1, 0, 0) as f64 - want1).abs() < 1e-5);

    // Every level of an odd-sized, 3-channel image keeps the mean.
    let (w, h, c) = (37, 11, 3);
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    let img: Vec<f32> = (0..w * h * c).map(|_| rng.random::<f32>()).collect();
    let t = Texture::from_f32(w, h, c, img).unwrap();
    assert_eq!(t.level_size(t.level_count() - 1), (1, 1));
    for ch in 0..c {
        let mean = |l: usize| {
            let (lw, lh) = t.level_size(l);
            let mut s = 0.0f64;
            for y in 0..lh {
                for x in 0..lw {
                    s += t.texel(l, x, y, ch) as f64;
                }
            }
            s / (lw * lh) as f64
        };
        let m0 = mean(0);
        for l in 1..t.level_count() {
            assert!((mean(l) - m0).abs() < 1e-5, "channel {ch} level {l}");
        }
    }
}

#[test]
fn srgb_texels_are_decoded_and_alpha_is_not() {
    let t = Texture::from_u8(1, 1, 4, &[188, 0, 255, 128], Encoding::Srgb).unwrap();
    // sRGB 188/255 = 0.7373 decodes to ((0.7373 + 0.055)/1.055)^2.4.
    let want = ((188.0f64 / 255.0 + 0.055) / 1.055).powf(2.4);
    assert!((t.texel(0, 0, 0, 0) as f64 - want).abs() < 1e-6);
    assert_eq!(t.texel(0, 0, 0, 1), 0.0);
    assert_eq!(t.texel(0, 0, 0, 2), 1.0);
    assert!((t.texel(0, 0, 0, 3) as f64 - 128.0 / 255.0).abs() < 1e-7);
    let t = Texture::from_u8(1, 1, 1, &[51], Encoding::Linear).unwrap();
    assert!((t.texel(0, 0, 0, 0) - 0.2).abs() < 1e-7);
}

#[test]
fn bad_textures_are_refused_with_reasons() {
    let refused = |r: Result<Texture, TextureError>| r.unwrap_err().to_string();
    assert!(refused(Texture::from_f32(0, 3, 1, vec![])).contains("≥ 1"));
    assert!(refused(Texture::from_f32(2, 2, 1, vec![0.0; 3])).contains("3 values"));
    assert!(refused(Texture::from_f32(1, 1, 1, vec![f32::NAN])).contains("finite"));
    let levels = vec![(4, 4, vec![0.0; 16]), (3, 2, vec![0.0; 6])];
    assert!(refused(Texture::from_levels(1, levels)).contains("must be 2×2"));
    let big = Texture::from_f32(5000, 5000, 1, vec![0.0; 25_000_000]);
    assert!(refused(big).contains("too large"));
}

/// A texture of `levels` levels (64 × 64 down) whose level l holds l
/// everywhere: trilinear filtering then returns λ itself.
fn level_ramp(levels: usize) -> Texture {
    let mut v = Vec::new();
    let mut n = 64;
    for l in 0..levels {
        v.push((n, n, vec![l as f32; n * n]));
        n /= 2;
    }
    Texture::from_levels(1, v).unwrap()
}

#[test]
fn mip_level_on_a_slanted_plane() {
    // A plane at distance d, tilted by θ away from the view direction about
    // the image's x axis, seen at the image centre through a pinhole of
    // focal length f pixels: one pixel spans d/f across and d/(f cos θ)
    // along the slope. With uv = position / S on a W-texel texture the
    // footprint is (W d/(f S)) × (W d/(f S cos θ)) texels, so
    // λ = log₂(W d / (f S cos θ)), the larger axis.
    let tex = level_ramp(7);
    let s = Sampler::new(Wrap::Repeat, Filter::Trilinear);
    let (w, f, big_s) = (64.0f64, 500.0, 0.4);
    for (d, theta_deg) in [
        (10.0, 0.0),
        (10.0, 60.0),
        (20.0, 75.0),
        (3.0, 30.0),
        (6.0, 80.0),
    ] {
        let cos_t = f64::to_radians(theta_deg).cos();
        let du_dx = d / (f * big_s);
        let dv_dy = d / (f * big_s * cos_t);
        let want = (w * d / (f * big_s * cos_t)).log2().clamp(0.0, 6.0);
        let lod64 = tex.lod([du_dx, 0.0], [0.0, dv_dy]);
        assert!(
            (lod64 - want).abs() < 1e-12,
            "θ {theta_deg}: {lod64} vs {want}"
        );
        let [v]: [f32; 1] = tex.sample(&s, [0.3f32, 0.7], [du_dx as f32, 0.0], [0.0, dv_dy as f32]);
        assert!(
            (v as f64 - want).abs() < 2e-6,
            "θ {theta_deg}: {v} vs {want}"
        );
        // Rotating the footprint in uv does not change ρ.
        let (c, sn) = (0.6f64, 0.8f64);
        let lod_rot = tex.lod([du_dx * c, du_dx * sn], [-dv_dy * sn, dv_dy * c]);
        assert!((lod_rot - want).abs() < 1e-12);
    }
    // Magnification, zero, NaN and infinite derivatives stay in range.
    assert_eq!(tex.lod([1e-4f64, 0.0], [0.0, 1e-4]), 0.0);
    assert_eq!(tex.lod([0.0f64, 0.0], [0.0, 0.0]), 0.0);
    assert_eq!(tex.lod([f64::NAN, 0.0], [0.0, 0.0]), 0.0);
    assert_eq!(tex.lod([f64::INFINITY, 0.0], [0.0, 0.0]), 6.0);
}

#[test]
fn f32x8_lookups_equal_the_scalar_twin_lane_by_lane() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let (w, h, c) = (13, 9, 3);
    let img: Vec<f32> = (0..w * h * c).map(|_| rng.random::<f32>()).collect();
    let tex = Texture::from_f32(w, h, c, img).unwrap();
    let specials = [
        f32::NAN,
        f32::INFINITY,
        -f32::INFINITY,
        1e30,
        -1e30,
        -0.0,
        1.0,
        0.999_999_9,
    ];
    for mode in MODES {
        for filter in [
            Filter::Nearest,
            Filter::Bilinear,
            Filter::Trilinear,
            Filter::Anisotropic(4),
            Filter::Anisotropic(16),
        ] {
            let s = Sampler {
                wrap_u: mode,
                wrap_v: MODES[(mode as usize + 1) % 3],
                filter,
            };
            for round in 0..200 {
                let mut lane = |k: usize| -> [f32; 6] {
                    let mut v: [f32; 6] = core::array::from_fn(|i| {
                        if i < 2 {
                            rng.random_range(-3.0..3.0)
                        } else {
                            rng.random_range(-0.3..0.3)
                        }
                    });
                    if round < 8 {
                        v[k % 6] = specials[(round + k) % specials.len()];
                    }
                    v
                };
                let lanes: [[f32; 6]; 8] = core::array::from_fn(&mut lane);
                let col = |i: usize| f32x8::new(core::array::from_fn(|l| lanes[l][i]));
                let got: [f32x8; 3] =
                    tex.sample(&s, [col(0), col(1)], [col(2), col(3)], [col(4), col(5)]);
                let ch = f32x8::new(core::array::from_fn(|l| (l % 4) as f32));
                let lod = tex.lod([col(2), col(3)], [col(4), col(5)]);
                let one = tex.sample_channel(&s, [col(0), col(1)], lod, ch);
                for (l, x) in lanes.iter().enumerate() {
                    let want: [f32; 3] = tex.sample(&s, [x[0], x[1]], [x[2], x[3]], [x[4], x[5]]);
                    let want64: [f64; 3] = tex.sample(
                        &s,
                        [x[0] as f64, x[1] as f64],
                        [x[2] as f64, x[3] as f64],
                        [x[4] as f64, x[5] as f64],
                    );
                    for k in 0..3 {
                        let g = got[k].lane(l);
                        assert!(g.is_finite(), "{s:?} lane {l}: {x:?}");
                        assert!(
                            (g - want[k] as f64).abs() < 2e-5,
                            "{s:?} lane {l} channel {k}: {g} vs {} for {x:?}",
                            want[k]
                        );
                        // f64 lanes reduce uv in f64, so huge uvs land on
                        // other texels; compare only moderate ones (and
                        // moderate derivatives for the anisotropic taps,
                        // which sit at uv plus a derivative's multiple).
                        let taps_at_uv = !matches!(filter, Filter::Anisotropic(_));
                        if x[..2].iter().all(|v| v.abs() < 10.0)
                            && (taps_at_uv || x[2..].iter().all(|v| v.abs() < 10.0))
                        {
                            assert!(
                                (g - want64[k]).abs() < 1e-4,
                                "{s:?} lane {l} channel {k}: f32x8 {g} vs f64 {}",
                                want64[k]
                            );
                        }
                    }
                    let scalar_lod = tex.lod([x[2], x[3]], [x[4], x[5]]);
                    let want_one = tex.sample_channel(&s, [x[0], x[1]], scalar_lod, (l % 4) as f32);
                    assert!((one.lane(l) - want_one as f64).abs() < 2e-5);
                }
            }
        }
    }
}

#[test]
fn blended_channel_pair_equals_two_lookups() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    let (w, h, c) = (16, 8, 5);
    let img: Vec<f32> = (0..w * h * c).map(|_| rng.random::<f32>()).collect();
    let tex = Texture::from_f32(w, h, c, img).unwrap();
    for filter in [Filter::Nearest, Filter::Bilinear, Filter::Trilinear] {
        let s = Sampler::new(Wrap::Repeat, filter);
        for _ in 0..500 {
            let uv = [rng.random_range(-2.0..2.0f64), rng.random_range(-2.0..2.0)];
            let lod = rng.random_range(-1.0..5.0f64);
            let ch = rng.random_range(0..c + 1) as f64;
            let wt = rng.random::<f64>();
            let a = tex.sample_channel(&s, uv, lod, ch);
            let b = tex.sample_channel(&s, uv, lod, ch + 1.0);
            let got = tex.sample_channel_blend(&s, uv, lod, ch, wt);
            assert!((got - (a + (b - a) * wt)).abs() < 1e-9, "{filter:?}");
        }
    }
}
