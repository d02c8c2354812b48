//! Replays the committed fuzz corpus (fixtures/fuzz/<target>/: the
//! minimized corpus of each cargo-fuzz target and every input that once
//! crashed it, `crash-*`) through the same entry points the fuzzer ran
//! (specula::fuzzing), on stable, so CI keeps every case found. A broken
//! guarantee panics inside the entry point; the test names the file.
//! See docs/ROBUSTNESS.md for how the corpus is made and extended.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The scene targets share the process-wide memory budget: one at a time.
static BUDGET: Mutex<()> = Mutex::new(());

fn corpus(target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/fuzz")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    assert!(!files.is_empty(), "{}: no corpus", dir.display());
    files
}

/// Runs every corpus file of `target` through `f`, naming the file of
/// the first broken guarantee; prints how many were accepted.
fn replay(target: &str, f: fn(&[u8]) -> Result<(), String>) {
    let files = corpus(target);
    let mut accepted = 0;
    for p in &files {
        let data = std::fs::read(p).unwrap();
        match std::panic::catch_unwind(|| f(&data)) {
            Ok(r) => accepted += usize::from(r.is_ok()),
            Err(_) => panic!(
                "{target}: {} breaks a guarantee (the panic above says which); reproduce with \
                 `cargo +nightly fuzz run {target} {}` or this test",
                p.display(),
                p.display()
            ),
        }
    }
    eprintln!(
        "{target}: {} inputs, {accepted} accepted, the others refused with a message",
        files.len()
    );
}

#[test]
fn scene_toml_corpus() {
    let _one = BUDGET.lock().unwrap_or_else(|e| e.into_inner());
    replay("scene_toml", specula::fuzzing::scene_toml);
}

#[test]
fn obj_mtl_corpus() {
    let _one = BUDGET.lock().unwrap_or_else(|e| e.into_inner());
    replay("obj_mtl", specula::fuzzing::obj_mtl);
}

#[test]
fn gltf_corpus() {
    let _one = BUDGET.lock().unwrap_or_else(|e| e.into_inner());
    replay("gltf", specula::fuzzing::gltf);
}

#[test]
fn envmap_corpus() {
    let _one = BUDGET.lock().unwrap_or_else(|e| e.into_inner());
    replay("envmap", specula::fuzzing::envmap);
}

#[test]
fn eval_line_corpus() {
    replay("eval_line", specula::fuzzing::eval_line);
}

#[test]
fn raster_corpus() {
    replay("raster", specula::fuzzing::raster);
}

/// An `.hdr` file of `w`×`h` texels made by `texel(i, j)`.
fn hdr_bytes(w: usize, h: usize, texel: impl Fn(usize, usize) -> [f32; 3]) -> Vec<u8> {
    let px: Vec<image::Rgb<f32>> = (0..w * h)
        .map(|k| image::Rgb(texel(k % w, k / w)))
        .collect();
    let mut out = Vec::new();
    image::codecs::hdr::HdrEncoder::new(&mut out)
        .encode(&px, w, h)
        .expect("encode HDR");
    out
}

/// An OpenEXR file (f32 RGB) of `w`×`h` texels made by `texel(i, j)`.
fn exr_bytes(w: u32, h: u32, texel: impl Fn(u32, u32) -> [f32; 3]) -> Vec<u8> {
    let img = image::Rgb32FImage::from_fn(w, h, |i, j| image::Rgb(texel(i, j)));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::OpenExr)
        .expect("encode EXR");
    out.into_inner()
}

/// A sky-like gradient: bright at the top, a warm spot near the horizon.
fn sky(i: f32, j: f32, w: f32, h: f32) -> [f32; 3] {
    let up = 1.0 - j / h;
    let spot = if (i / w - 0.3).abs() < 0.15 && (j / h - 0.4).abs() < 0.15 {
        20.0
    } else {
        0.0
    };
    [0.2 + up + spot, 0.3 + up + 0.5 * spot, 0.6 + up]
}

/// The `envmap` seeds (fixtures/fuzz/envmap/seed-*): small valid maps in
/// both formats and broken ones, each named for what it holds. Run with
/// `cargo test --test fuzz_corpus -- --ignored write_envmap_seeds` to
/// write them again.
#[test]
#[ignore]
fn write_envmap_seeds() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/fuzz/envmap");
    std::fs::create_dir_all(&dir).unwrap();
    let hdr_4x2 = hdr_bytes(4, 2, |i, j| sky(i as f32, j as f32, 4.0, 2.0));
    // At 8 to 32767 texels a row, rows are run-length coded.
    let hdr_16x8 = hdr_bytes(16, 8, |i, j| sky(i as f32, j as f32, 16.0, 8.0));
    let exr_4x2 = exr_bytes(4, 2, |i, j| sky(i as f32, j as f32, 4.0, 2.0));
    let exr_16x8 = exr_bytes(16, 8, |i, j| sky(i as f32, j as f32, 16.0, 8.0));
    let header =
        |size: &str| format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n{size}\n").into_bytes();
    let special = [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        -1.0,
        1e30,
        f32::MAX,
        1e-45,
        0.5,
    ];
    let exr_special = exr_bytes(4, 2, |i, j| {
        let k = (j * 4 + i) as usize;
        [special[k], special[(k + 3) % 8], special[(k + 5) % 8]]
    });
    // Radiance's largest exponent (255): 2^119 times the mantissa.
    let mut hdr_huge_exponent = hdr_4x2.clone();
    let n = hdr_huge_exponent.len();
    for t in 0..8 {
        hdr_huge_exponent[n - 4 * t - 1] = 255;
    }
    // The EXR's data window (box2i: xmin, ymin, xmax, ymax) made 70000²
    // and −1 wide.
    let window = |exr: &[u8], xmax: i32, ymax: i32| {
        let key = b"dataWindow\0box2i\0";
        let at = exr
            .windows(key.len())
            .position(|w| w == key)
            .expect("a data window")
            + key.len()
            + 4;
        let mut b = exr.to_vec();
        b[at + 8..at + 12].copy_from_slice(&xmax.to_le_bytes());
        b[at + 12..at + 16].copy_from_slice(&ymax.to_le_bytes());
        b
    };
    let mut wrong_magic_exr = exr_4x2.clone();
    wrong_magic_exr[0] ^= 0xff;
    let mut png = std::io::Cursor::new(Vec::new());
    image::RgbImage::from_pixel(4, 2, image::Rgb([200, 100, 50]))
        .write_to(&mut png, image::ImageFormat::Png)
        .unwrap();
    let seeds: Vec<(&str, Vec<u8>)> = vec![
        ("seed-valid-4x2.hdr", hdr_4x2.clone()),
        ("seed-valid-16x8-rle.hdr", hdr_16x8.clone()),
        ("seed-valid-4x2.exr", exr_4x2.clone()),
        ("seed-valid-16x8.exr", exr_16x8.clone()),
        ("seed-texels-nan-inf-negative.exr", exr_special),
        ("seed-texels-exponent-255.hdr", hdr_huge_exponent),
        (
            "seed-truncated.hdr",
            hdr_16x8[..hdr_16x8.len() / 2].to_vec(),
        ),
        (
            "seed-truncated.exr",
            exr_16x8[..exr_16x8.len() / 2].to_vec(),
        ),
        ("seed-truncated-header.hdr", hdr_4x2[..20].to_vec()),
        ("seed-wrong-magic.hdr", {
            let mut b = hdr_4x2.clone();
            b[2] = b'X';
            b
        }),
        ("seed-wrong-magic.exr", wrong_magic_exr),
        ("seed-a-png.png", png.into_inner()),
        ("seed-1x1.hdr", hdr_bytes(1, 1, |_, _| [1.0, 1.0, 1.0])),
        ("seed-1x1.exr", exr_bytes(1, 1, |_, _| [1.0, 1.0, 1.0])),
        ("seed-0x4.hdr", header("-Y 0 +X 4")),
        ("seed-4x0.hdr", header("-Y 4 +X 0")),
        ("seed-huge-header.hdr", header("-Y 65536 +X 131072")),
        ("seed-over-budget-header.hdr", header("-Y 16384 +X 32768")),
        ("seed-negative-size.hdr", header("-Y -4 +X 8")),
        ("seed-huge-window.exr", window(&exr_4x2, 69_999, 69_999)),
        ("seed-inverted-window.exr", window(&exr_4x2, -2, 1)),
    ];
    for (name, bytes) in seeds {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
}
