//! Depth precision does not depend on the near/far ratio (reversed depth,
//! raster/src/camera.rs): tiny near planes and an infinite far plane see
//! exactly what an ordinary near/far pair sees.

mod common;

use common::scene;
use specula_raster::frame::{visibility, FrameStats};
use specula_raster::{Target, MISS};

/// A floor reaching 30 m away, two spheres on it 2–4 m from the eye, and a
/// large sphere 5 km away; `near` and `far` are substituted.
fn scene_toml(near: &str, far: &str) -> String {
    format!(
        r#"
[camera]
eye = [0.0, 1.2, 3.0]
target = [0.0, 0.4, -2.0]
fov_y = 50.0
near = {near}
far = {far}
[[mesh]]
plane = {{ size = [60.0, 60.0], segments = [6, 6] }}
material = "a"
[[mesh]]
sphere = {{ radius = 0.5, segments = 48, rings = 24 }}
translate = [0.0, 0.5, 0.0]
material = "a"
[[mesh]]
sphere = {{ radius = 0.3, segments = 32, rings = 16 }}
translate = [0.6, 0.3, 1.0]
material = "a"
[[mesh]]
sphere = {{ radius = 500.0, segments = 32, rings = 16 }}
translate = [0.0, 600.0, -5000.0]
material = "a"
[materials.a]
model = "lambert"
base_color = [0.5, 0.5, 0.5]
"#
    )
}

fn ids(near: &str, far: &str) -> Vec<u32> {
    let s = scene(&scene_toml(near, far), &[]);
    let t = Target::new(320, 180).unwrap();
    visibility(&s.data, &t, &mut FrameStats::default()).vis.id
}

#[test]
fn tiny_near_planes_and_an_infinite_far_plane_lose_no_geometry() {
    let reference = ids("0.01", "10000.0");
    let hit = reference.iter().filter(|&&i| i != MISS).count();
    // The floor, the spheres and the distant sphere all cover pixels.
    assert!(hit > reference.len() / 2, "reference covers {hit} pixels");
    // near = 1e-4 with far = 1e4 lost the floor with conventional depth;
    // near = 1e-8 shaded nothing at all. Ratios down to 1e-12 and an
    // infinite far plane must give the same visibility, up to a handful of
    // pixels where the floor and a sphere meet (depths equal to a few ulps).
    for (near, far) in [
        ("1e-4", "1e4"),
        ("1e-6", "1.0e4"),
        ("1e-8", "1e4"),
        ("0.01", "inf"),
        ("1e-7", "inf"),
    ] {
        let got = ids(near, far);
        let differ = got.iter().zip(&reference).filter(|(a, b)| a != b).count();
        assert!(
            differ <= 8,
            "near {near}, far {far}: {differ} of {} pixels differ",
            got.len()
        );
    }
}

#[test]
fn the_far_plane_still_cuts() {
    // far = 100 drops the sphere 5 km away (and the floor stays).
    let near_far = ids("0.01", "100.0");
    let reference = ids("0.01", "10000.0");
    let lost = near_far
        .iter()
        .zip(&reference)
        .filter(|(a, b)| **a == MISS && **b != MISS)
        .count();
    assert!(lost > 500, "only {lost} pixels lost to the far plane");
    let floor_ok = near_far
        .iter()
        .zip(&reference)
        .filter(|(a, b)| **a != MISS && a == b)
        .count();
    assert!(floor_ok > near_far.len() / 3, "{floor_ok}");
}
