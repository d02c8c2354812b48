//! Golden images: every fixtures/scenes/*.toml rendered 320 pixels wide
//! (the scene's aspect ratio, its own supersampling), through the SIMD and
//! the scalar shading paths, the 8-bit pixels checked against the SHA-256
//! in fixtures/golden/hashes.toml. Where the processor has AVX-512, each
//! scene whose packets the SIMD path shades two packets per register
//! (`specula_raster::frame::shades_packet_pairs`) is rendered once more
//! with f32x8 alone (`ShadePath::SimdAvx2`): the bytes must be the same.
//!
//! `SPECULA_BLESS=1 cargo test --test golden` rewrites the hashes and the
//! golden PNGs after an intended change: fixtures/golden/SCENE.png (the
//! SIMD path's image) and SCENE.scalar.png only where the scalar path's
//! pixels differ from it.
//! Environment maps' derived data are computed afresh (a table cache of
//! this run's own), never read from the user's cache.
//! A failing check writes the new image, a copy of the golden one and a
//! FLIP heat map of the two into the target folder and prints their paths.

mod common;

use common::{fixtures, temp_dir};
use specula::batch::sha256_hex;
use specula::diff::load::{DiffImage, Encoding};
use specula::diff::{compare, heatmap_png, FlipSettings};
use specula::render::{render_scene, RenderSettings};
use specula::scene::load_scene;
use specula_raster::frame::ShadePath;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const WIDTH: u32 = 320;
const HASHES: &str = "golden/hashes.toml";

type Hashes = BTreeMap<String, BTreeMap<String, String>>;

fn scenes() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(fixtures().join("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    v
}

/// Renders a scene at the golden size through one shading path: (w, h, rgb8).
fn render(path: &Path, shading: ShadePath) -> (u32, u32, Vec<u8>) {
    let scene = load_scene(path).unwrap_or_else(|e| panic!("{e}"));
    let mut s = RenderSettings::from_scene(&scene);
    s.height = ((WIDTH as f64 * s.height as f64 / s.width as f64).round() as u32).max(1);
    s.width = WIDTH;
    s.path = shading;
    s.keep_hdr = false;
    let r = render_scene(&scene, &s, 0.0).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (r.width, r.height, r.ldr)
}

/// Whether the SIMD path shades some of the scene's packets two at a time
/// per AVX-512 register.
fn pairs_packets(path: &Path) -> bool {
    let scene = load_scene(path).unwrap_or_else(|e| panic!("{e}"));
    specula_raster::frame::shades_packet_pairs(&scene.data)
}

/// The hash of an image: SHA-256 of its size (two little-endian u32) and
/// its RGB8 bytes, row-major.
fn pixel_hash(w: u32, h: u32, rgb: &[u8]) -> String {
    let mut b = Vec::with_capacity(8 + rgb.len());
    b.extend_from_slice(&w.to_le_bytes());
    b.extend_from_slice(&h.to_le_bytes());
    b.extend_from_slice(rgb);
    sha256_hex(&b)
}

fn as_diff_image(path: PathBuf, w: u32, h: u32, rgb: &[u8]) -> DiffImage {
    DiffImage {
        path,
        width: w as usize,
        height: h as usize,
        channels: 3,
        alpha: false,
        encoding: Encoding::Display,
        rgb: rgb
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]].map(|v| v as f32 / 255.0))
            .collect(),
    }
}

fn write_hashes(path: &Path, hashes: &Hashes) {
    let mut text = String::from(
        "# SHA-256 of the 8-bit pixels (width and height as little-endian u32,\n\
         # then RGB row-major) of every fixtures/scenes/*.toml rendered 320 pixels\n\
         # wide, per shading path. Written by `SPECULA_BLESS=1 cargo test --test\n\
         # golden`; checked by tests/golden.rs.\n",
    );
    text += &toml::to_string(hashes).unwrap();
    std::fs::write(path, text).unwrap();
}

#[test]
fn every_fixture_scene_renders_its_golden_pixels() {
    // The hashes hold for x86-64-v3 builds (.cargo/config.toml); other
    // targets round differently (docs/accuracy.md, "Golden images").
    if !(cfg!(target_arch = "x86_64")
        && cfg!(target_feature = "avx2")
        && cfg!(target_feature = "fma"))
    {
        eprintln!("skipped: the golden hashes are for x86-64 builds with AVX2 and FMA");
        return;
    }
    // Maps' derived data from this build, not from a table cache another
    // build wrote under the same key. This binary's only test, so no
    // other thread reads the environment while it is set.
    std::env::set_var("SPECULA_CACHE_DIR", temp_dir("golden-table-cache"));
    let bless = std::env::var_os("SPECULA_BLESS").is_some_and(|v| v == "1");
    let hash_path = fixtures().join(HASHES);
    let golden: Hashes = std::fs::read_to_string(&hash_path)
        .ok()
        .map(|t| toml::from_str(&t).expect("fixtures/golden/hashes.toml parses"))
        .unwrap_or_default();
    let out = temp_dir("golden");
    if bless {
        std::fs::create_dir_all(fixtures().join("golden")).unwrap();
    }
    let mut now: Hashes = BTreeMap::new();
    let mut failures = Vec::new();
    let mut paired = Vec::new();
    for scene in scenes() {
        let name = scene.file_stem().unwrap().to_str().unwrap().to_string();
        for (label, shading) in [("simd", ShadePath::Simd), ("scalar", ShadePath::Scalar)] {
            let (w, h, rgb) = render(&scene, shading);
            if shading == ShadePath::Simd && pairs_packets(&scene) {
                paired.push(name.clone());
                if render(&scene, ShadePath::SimdAvx2) != (w, h, rgb.clone()) {
                    failures.push(format!(
                        "{name}: the AVX-512 packet pairs and f32x8 alone give different pixels"
                    ));
                }
            }
            let hash = pixel_hash(w, h, &rgb);
            let dir = fixtures().join("golden");
            let own = dir.join(format!("{name}.{label}.png"));
            let golden_png = if own.exists() {
                own.clone()
            } else {
                dir.join(format!("{name}.png"))
            };
            let entry = now.entry(name.clone()).or_default();
            entry.insert(label.to_string(), hash.clone());
            if bless {
                let _ = std::fs::remove_file(&own);
                if label == "simd" {
                    specula::image_file::write_png(&dir.join(format!("{name}.png")), w, h, rgb)
                        .unwrap();
                } else if entry.get("simd") != Some(&hash) {
                    specula::image_file::write_png(&own, w, h, rgb).unwrap();
                }
                continue;
            }
            let want = golden.get(&name).and_then(|m| m.get(label));
            if want == Some(&hash) {
                continue;
            }
            let new_png = out.join(format!("{name}.{label}.new.png"));
            specula::image_file::write_png(&new_png, w, h, rgb.clone()).unwrap();
            let mut msg = format!(
                "{name} ({label}): pixels changed (hash {hash}, golden {}); new image {}",
                want.map_or("none", |s| s.as_str()),
                new_png.display()
            );
            let old_copy = out.join(format!("{name}.{label}.old.png"));
            if std::fs::copy(&golden_png, &old_copy).is_ok() {
                msg += &format!(", golden image {}", old_copy.display());
            }
            if let Ok(old) = specula::diff::load::load(&golden_png) {
                let new = as_diff_image(new_png.clone(), w, h, &rgb);
                let settings = FlipSettings {
                    ppd: specula::diff::flip::default_ppd(),
                    exposures: None,
                    curve: specula::diff::flip::ToneCurve::Aces,
                };
                if let Ok(report) = compare(old, new, settings, None, false) {
                    let heat = out.join(format!("{name}.{label}.heatmap.png"));
                    std::fs::write(&heat, heatmap_png(&report).unwrap()).unwrap();
                    msg += &format!(
                        ", heat map {} (mean FLIP {:.5}, max abs {:.4})",
                        heat.display(),
                        report.metrics.flip_mean,
                        report.metrics.max_abs
                    );
                }
            }
            failures.push(msg);
        }
    }
    if specula_raster::frame::packet_pairs_available() {
        eprintln!(
            "{} scene(s) shaded with AVX-512 packet pairs, the same bytes as f32x8 alone checked: {}",
            paired.len(),
            paired.join(", ")
        );
        if paired.len() < 3 {
            failures.push(format!(
                "only {} fixture scene(s) take the packet pairs: too few to check them",
                paired.len()
            ));
        }
    } else {
        eprintln!("packet pairs not checked: this processor has no AVX-512F/DQ/VL/BW");
    }
    if bless {
        write_hashes(&hash_path, &now);
        eprintln!("blessed {} scenes into {}", now.len(), hash_path.display());
        return;
    }
    for stale in golden.keys().filter(|k| !now.contains_key(*k)) {
        failures.push(format!(
            "{stale}: in {HASHES} but no fixtures/scenes/{stale}.toml (bless to drop it)"
        ));
    }
    assert!(
        failures.is_empty(),
        "{} golden image(s) differ; if the change is intended, run SPECULA_BLESS=1 cargo test --test golden\n{}",
        failures.len(),
        failures.join("\n")
    );
}
