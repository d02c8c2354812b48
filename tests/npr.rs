//! NPR styles end to end, from scene files: posterization, hard (toon)
//! shading, hatching and textured base colours.

mod common;

use common::scene;
use specula::render::{render_scene, RenderSettings};
use std::collections::BTreeSet;

const SPHERE_SCENE: &str = r#"
[camera]
eye = [0.0, 0.0, 4.0]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 10.0

[output]
width = 96
height = 96

[[mesh]]
sphere = { radius = 1.0, segments = 96, rings = 48 }
material = "m"

[[light]]
type = "directional"
direction = [-0.5, -0.4, -1.0]
irradiance = [3.0, 3.0, 3.0]
"#;

#[test]
fn posterized_scene_has_at_most_levels_codes_per_channel() {
    for (levels, mode) in [(3, "rgb"), (5, "luminance")] {
        let toml = format!(
            "{SPHERE_SCENE}\n[materials.m]\nmodel = \"lambert\"\nbase_color = [0.8, 0.5, 0.2]\n\n[posterize]\nlevels = {levels}\nmode = \"{mode}\"\n"
        );
        let s = scene(&toml, &[]);
        let r = render_scene(&s, &RenderSettings::from_scene(&s), 0.0).unwrap();
        if mode == "rgb" {
            for c in 0..3 {
                let codes: BTreeSet<u8> = r.ldr.iter().skip(c).step_by(3).copied().collect();
                assert!(codes.len() <= levels, "channel {c}: {codes:?}");
                assert!(codes.len() >= 2, "channel {c}: {codes:?}");
            }
        } else {
            // Hue kept: every pixel's colour is a multiple of the base colour,
            // so the number of distinct colours is the number of levels hit.
            let colours: BTreeSet<[u8; 3]> =
                r.ldr.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
            assert!(colours.len() <= levels, "{colours:?}");
        }
    }
    let bad = format!("{SPHERE_SCENE}\n[materials.m]\nmodel = \"lambert\"\nbase_color = [1, 1, 1]\n[posterize]\nlevels = 1\n");
    let err = specula::scene::load_scene_str(std::path::Path::new("p.toml"), &bad, &|_| {
        Err(std::io::ErrorKind::NotFound.into())
    })
    .err()
    .unwrap()
    .to_string();
    assert!(err.contains("posterize.levels"), "{err}");
}
