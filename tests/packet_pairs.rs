//! The AVX-512 packet pairs give f32x8's bits for every kind of light:
//! spot lights with and without cones' overlap and finite ranges,
//! directional lights, point lights with a range, kinds mixed, a single
//! light, none, lights with shadow maps of every filter among unshadowed
//! ones and alone, under a uniform environment and under the fixture maps
//! (split sum, a sun taken out of the sky, shadowed or not), on the
//! models that take them beside Disney's (which keeps f32x8) in one
//! frame, and
//! on odd batches (a packet alone in both halves: the spheres' edges end
//! runs of one material). (The golden test checks the fixture scenes the
//! same way.) Skipped, with a message, where the processor has no
//! AVX-512.

mod common;

use common::{fixtures, temp_dir};
use specula::render::{render_scene, RenderSettings};
use specula::scene::load_scene_str;
use specula_raster::frame::{packet_pairs_available, shades_packet_pairs, ShadePath};
use std::path::Path;

const MATERIALS: &str = r#"
[materials.m0]
model = "metallic_roughness"
base_color = [0.8, 0.5, 0.3]
roughness = 0.35
metallic = 0.4
emissive = [0.02, 0.01, 0.0]
[materials.m1]
model = "microfacet"
ndf = "beckmann"
alpha = 0.3
fresnel = { type = "schlick", f0 = [0.9, 0.7, 0.5] }
[materials.m2]
model = "microfacet"
ndf = "gtr"
gamma = 1.5
alpha = 0.25
fresnel = { type = "schlick", f0 = [0.5, 0.6, 0.9] }
energy_compensation = true
[materials.m3]
model = "disney"
base_color = [0.3, 0.6, 0.8]
roughness = 0.5
clearcoat = 1.0
sheen = 0.5
[materials.m4]
model = "gltf"
base_color_factor = [0.8, 0.8, 0.7]
roughness_factor = 0.6
metallic_factor = 0.0
[materials.floor]
model = "lambert"
base_color = [0.5, 0.5, 0.5]
"#;

/// Five spheres of the five models on a floor, under `lights` and a
/// uniform environment.
fn scene(lights: &str) -> String {
    scene_under(lights, "uniform = [0.05, 0.06, 0.08]")
}

/// [`scene`] under `environment` (the `[environment]` table's body).
fn scene_under(lights: &str, environment: &str) -> String {
    let mut s = String::from(
        r#"
[camera]
eye = [0.0, 3.0, 9.0]
target = [0.0, 0.5, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 40.0
near = 0.5
far = 50.0
[output]
width = 192
height = 108
[environment]
ENVIRONMENT
[[mesh]]
plane = { size = [20.0, 20.0] }
material = "floor"
"#,
    );
    for (i, x) in [-4.0, -2.0, 0.0, 2.0, 4.0].iter().enumerate() {
        s += &format!(
            "[[mesh]]\nsphere = {{ radius = 0.9, segments = 24, rings = 12 }}\n\
             material = \"m{i}\"\ntranslate = [{x}, 1.0, 0.0]\n"
        );
    }
    s.replace("ENVIRONMENT", environment) + MATERIALS + lights
}

/// The lights of each case.
const CASES: [(&str, &str); 7] = [
    (
        "spot lights with and without ranges",
        r#"
[[light]]
type = "spot"
position = [-3.0, 5.0, 3.0]
direction = [0.4, -1.0, -0.4]
intensity = [40.0, 35.0, 30.0]
inner_cone = 10.0
outer_cone = 35.0
range = 9.0
[[light]]
type = "spot"
position = [3.0, 5.0, 3.0]
direction = [-0.4, -1.0, -0.4]
intensity = [30.0, 35.0, 40.0]
outer_cone = 50.0
range = 7.5
[[light]]
type = "spot"
position = [0.0, 6.0, 4.0]
direction = [0.0, -1.0, -0.6]
intensity = [25.0, 25.0, 25.0]
inner_cone = 20.0
outer_cone = 30.0
[[light]]
type = "spot"
position = [0.0, 4.0, -4.0]
direction = [0.0, -0.5, 1.0]
intensity = [20.0, 20.0, 20.0]
inner_cone = 5.0
outer_cone = 60.0
[[light]]
type = "spot"
position = [5.0, 2.0, 2.0]
direction = [-1.0, -0.2, -0.3]
intensity = [15.0, 10.0, 5.0]
outer_cone = 25.0
range = 12.0
"#,
    ),
    (
        "directional lights",
        r#"
[[light]]
type = "directional"
direction = [0.3, -1.0, -0.4]
irradiance = [1.0, 0.9, 0.8]
[[light]]
type = "directional"
direction = [-0.5, -0.6, -0.2]
irradiance = [0.4, 0.5, 0.7]
[[light]]
type = "directional"
direction = [0.0, -0.2, -1.0]
irradiance = [0.3, 0.3, 0.3]
"#,
    ),
    (
        "point lights with and without range, kinds mixed in turn",
        r#"
[[light]]
type = "point"
position = [-4.0, 4.0, 5.0]
intensity = [60.0, 60.0, 60.0]
range = 10.0
[[light]]
type = "point"
position = [4.0, 4.0, 5.0]
intensity = [60.0, 52.0, 45.0]
range = 6.0
[[light]]
type = "point"
position = [0.0, 3.0, 6.0]
intensity = [20.0, 20.0, 30.0]
[[light]]
type = "directional"
direction = [0.3, -1.0, -0.4]
irradiance = [0.5, 0.5, 0.5]
[[light]]
type = "point"
position = [0.0, 2.0, -3.0]
intensity = [10.0, 12.0, 14.0]
range = 4.0
[[light]]
type = "spot"
position = [1.0, 5.0, 1.0]
direction = [0.0, -1.0, 0.0]
intensity = [30.0, 30.0, 30.0]
outer_cone = 45.0
"#,
    ),
    (
        "shadowed lights of every filter among unshadowed ones, two shadowed of a kind in a row",
        r#"
[[light]]
type = "point"
position = [-4.0, 4.0, 5.0]
intensity = [40.0, 40.0, 40.0]
[[light]]
type = "point"
position = [4.0, 4.0, 5.0]
intensity = [40.0, 35.0, 30.0]
[[light]]
type = "spot"
position = [0.0, 6.0, 4.0]
direction = [0.0, -1.0, -0.6]
intensity = [40.0, 40.0, 40.0]
outer_cone = 40.0
shadows = "pcf"
[[light]]
type = "spot"
position = [-2.0, 6.0, 2.0]
direction = [0.3, -1.0, -0.3]
intensity = [30.0, 30.0, 30.0]
outer_cone = 35.0
shadows = "pcss"
light_size = 0.5
[[light]]
type = "directional"
direction = [0.3, -1.0, -0.4]
irradiance = [0.6, 0.6, 0.6]
shadows = "hard"
[[light]]
type = "directional"
direction = [-0.5, -0.6, -0.2]
irradiance = [0.3, 0.3, 0.4]
[[light]]
type = "directional"
direction = [0.0, -0.2, -1.0]
irradiance = [0.2, 0.2, 0.2]
[[light]]
type = "point"
position = [0.0, 3.0, 6.0]
intensity = [20.0, 20.0, 30.0]
shadows = "pcf"
"#,
    ),
    (
        "every light shadowed",
        r#"
[[light]]
type = "point"
position = [-4.0, 4.0, 5.0]
intensity = [40.0, 40.0, 40.0]
shadows = "pcf"
[[light]]
type = "spot"
position = [0.0, 6.0, 4.0]
direction = [0.0, -1.0, -0.6]
intensity = [40.0, 40.0, 40.0]
outer_cone = 40.0
shadows = "hard"
"#,
    ),
    (
        "one point light",
        r#"
[[light]]
type = "point"
position = [2.0, 5.0, 4.0]
intensity = [50.0, 45.0, 40.0]
"#,
    ),
    (
        "a light on the surface (the distance's floor)",
        r#"
[[light]]
type = "point"
position = [0.0, 0.0, 0.0]
intensity = [5.0, 5.0, 5.0]
[[light]]
type = "point"
position = [-2.0, 1.9, 0.0]
intensity = [5.0, 5.0, 5.0]
"#,
    ),
];

/// The frame's linear colour, bit for bit (finer than the 8-bit image,
/// which would hide a term added in another order).
fn render(text: &str, path: ShadePath) -> Vec<u32> {
    let read = |p: &Path| std::fs::read(p);
    let scene =
        load_scene_str(Path::new("pairs.toml"), text, &read).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        path != ShadePath::Simd || shades_packet_pairs(&scene.data),
        "the scene does not take the packet pairs"
    );
    let mut s = RenderSettings::from_scene(&scene);
    s.path = path;
    s.keep_hdr = true;
    let r = render_scene(&scene, &s, 0.0).unwrap_or_else(|e| panic!("{e}"));
    r.hdr().iter().flatten().map(|c| c.to_bits()).collect()
}

#[test]
fn packet_pairs_give_the_f32x8_bits() {
    if !packet_pairs_available() {
        eprintln!("skipped: this processor has no AVX-512F/DQ/VL/BW");
        return;
    }
    // Maps' derived data from this build, in a cache of this run's own
    // (the binary's only test, so nothing else reads the variable).
    std::env::set_var("SPECULA_CACHE_DIR", temp_dir("packet-pairs-table-cache"));
    let map = |name: &str| {
        let path = fixtures().join("env").join(name);
        format!("map = {:?}", path.to_str().expect("a UTF-8 path"))
    };
    let under_maps = [
        (
            "under the esplanade",
            scene_under(CASES[2].1, &map("royal_esplanade_1k.hdr")),
        ),
        (
            "under the sky and its sun",
            scene_under(CASES[0].1, &map("sky.hdr")),
        ),
        (
            "no light under the esplanade",
            scene_under("", &map("royal_esplanade_1k.hdr")),
        ),
        (
            "shadowed lights under the sky, its sun shadowed",
            scene_under(
                CASES[3].1,
                &(map("sky.hdr") + "\n[environment.sun]\nshadows = \"pcf\""),
            ),
        ),
    ];
    let cases = CASES.iter().map(|&(what, lights)| (what, scene(lights)));
    for (what, text) in cases.chain(under_maps) {
        let pairs = render(&text, ShadePath::Simd);
        let alone = render(&text, ShadePath::SimdAvx2);
        assert!(
            pairs.iter().filter(|&&b| f32::from_bits(b) > 0.05).count() > pairs.len() / 4,
            "{what}: the image is mostly dark, so it checks little"
        );
        let differ = pairs.iter().zip(&alone).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "{what}: {differ} colour channels differ");
    }
}
