//! Spot lights (`type = "spot"`) end to end: a Lambertian floor rendered
//! under spot lights against an f64 evaluation, written here from
//! KHR_lights_punctual's text, of each pixel's radiance; and the range
//! checks of the scene fields.

mod common;

use specula::render::{render_scene, RenderSettings};
use specula_raster::frame::ShadePath;
use specula_raster::MISS;

/// KHR_lights_punctual's spot falloff, in f64: the ramp between the cosines
/// of the two cone angles, squared ("Inner and Outer Cone Angles").
fn cone(cd: f64, inner_deg: f64, outer_deg: f64) -> f64 {
    let (ci, co) = (inner_deg.to_radians().cos(), outer_deg.to_radians().cos());
    let scale = 1.0 / (ci - co).max(0.001);
    let t = (cd * scale - co * scale).clamp(0.0, 1.0);
    t * t
}

/// The extension's recommended range window, as a factor of 1/d².
fn window(d: f64, range: f64) -> f64 {
    (1.0 - (d / range).powi(4)).clamp(0.0, 1.0)
}

struct Spot {
    position: [f64; 3],
    direction: [f64; 3],
    intensity: f64,
    inner: f64,
    outer: f64,
    range: f64,
}

const ALBEDO: f64 = 0.5;
const SIDE: u32 = 120;
/// The camera: 6 above the floor looking straight down, image top = −z.
const EYE_Y: f64 = 6.0;
const FOV_Y: f64 = 40.0;

fn scene_text(spots: &[Spot]) -> String {
    let mut s = format!(
        r#"
[camera]
eye = [0.0, {EYE_Y}, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov_y = {FOV_Y}
near = 0.1
far = 50.0
[output]
width = {SIDE}
height = {SIDE}
[[mesh]]
plane = {{ size = [6.0, 6.0] }}
material = "floor"
[materials.floor]
model = "lambert"
base_color = [{ALBEDO}, {ALBEDO}, {ALBEDO}]
"#
    );
    for l in spots {
        s += &format!(
            "[[light]]\ntype = \"spot\"\nposition = {:?}\ndirection = {:?}\nintensity = [{i}, {i}, {i}]\ninner_cone = {}\nouter_cone = {}\nrange = {}\n",
            l.position,
            l.direction,
            l.inner,
            l.outer,
            if l.range.is_finite() { l.range.to_string() } else { "inf".into() },
            i = l.intensity,
        );
    }
    s
}

/// The floor point seen through the centre of pixel (i, j): a pinhole
/// camera at (0, 6, 0) looking down −y, right = +x, image up = −z.
fn floor_point(i: u32, j: u32) -> [f64; 3] {
    let t = (FOV_Y / 2.0).to_radians().tan();
    let x = (2.0 * (i as f64 + 0.5) / SIDE as f64 - 1.0) * t;
    let y = (1.0 - 2.0 * (j as f64 + 0.5) / SIDE as f64) * t;
    [EYE_Y * x, 0.0, -EYE_Y * y]
}

/// Radiance of the Lambertian floor (normal +y) at `p`: ρ/π Σ I · cone ·
/// window · cos θ / d².
fn expected(spots: &[Spot], p: [f64; 3]) -> f64 {
    let mut e = 0.0;
    for l in spots {
        let to = [
            l.position[0] - p[0],
            l.position[1] - p[1],
            l.position[2] - p[2],
        ];
        let d = (to[0] * to[0] + to[1] * to[1] + to[2] * to[2]).sqrt();
        let n = (l.direction.iter().map(|v| v * v).sum::<f64>()).sqrt();
        let cd =
            -(to[0] * l.direction[0] + to[1] * l.direction[1] + to[2] * l.direction[2]) / (d * n);
        let cos_theta = (to[1] / d).max(0.0);
        e += l.intensity * cone(cd, l.inner, l.outer) * window(d, l.range) * cos_theta / (d * d);
    }
    ALBEDO / std::f64::consts::PI * e
}

fn render(text: &str, path: ShadePath) -> (Vec<[f32; 3]>, Vec<u32>) {
    let s = common::scene(text, &[]);
    let mut set = RenderSettings::from_scene(&s);
    set.path = path;
    set.buffers.id = true;
    let r = render_scene(&s, &set, 0.0).unwrap();
    let b = &r.frame.buffers;
    (
        (0..b.id.len()).map(|i| b.color.get(i)).collect(),
        b.id.clone(),
    )
}

#[test]
fn a_floor_under_spot_lights_matches_the_extensions_formula() {
    let spots = [
        // Straight down with a range cutting the cone's edge.
        Spot {
            position: [0.0, 2.0, 0.0],
            direction: [0.0, -1.0, 0.0],
            intensity: 8.0,
            inner: 10.0,
            outer: 40.0,
            range: 3.2,
        },
        // Tilted, off centre, no range: an asymmetric pool of light.
        Spot {
            position: [-1.0, 1.5, 1.0],
            direction: [0.6, -1.0, -0.3],
            intensity: 5.0,
            inner: 0.0,
            outer: 25.0,
            range: f64::INFINITY,
        },
    ];
    let text = scene_text(&spots);
    for path in [ShadePath::Simd, ShadePath::Scalar] {
        let (color, id) = render(&text, path);
        let (mut worst, mut lit, mut dark, mut ramp) = (0.0f64, 0, 0, 0);
        for j in 0..SIDE {
            for i in 0..SIDE {
                let k = (j * SIDE + i) as usize;
                assert_ne!(id[k], MISS, "the floor fills the image");
                let want = expected(&spots, floor_point(i, j));
                let got = color[k][0] as f64;
                // Relative where lit, absolute (in units of the brightest
                // radiance, about 0.5) where dark.
                let err = (got - want).abs() / want.max(1e-2);
                worst = worst.max(err);
                if want == 0.0 {
                    dark += 1;
                    assert_eq!(got, 0.0, "{path:?} pixel ({i}, {j}) is outside both cones");
                } else {
                    lit += 1;
                }
                let cd_ramp = expected(&spots[..1], floor_point(i, j));
                if cd_ramp > 0.0 && cd_ramp < 0.9 * expected(&spots[..1], [0.0; 3]) {
                    ramp += 1;
                }
            }
        }
        eprintln!("{path:?}: worst relative error {worst:e}; {lit} lit, {dark} dark, {ramp} on the first falloff");
        assert!(
            lit > 3000 && dark > 1000 && ramp > 500,
            "{lit} {dark} {ramp}"
        );
        assert!(worst < 5e-5, "{path:?}: worst relative error {worst:e}");
    }
}

#[test]
fn bad_spot_fields_are_refused_naming_the_field() {
    let base = |fields: &str| {
        format!(
            "[camera]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 40.0\nnear = 0.1\nfar = 10.0\n[[light]]\ntype = \"spot\"\n{fields}\n"
        )
    };
    let ok =
        "position = [0.0, 1.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\nintensity = [1.0, 1.0, 1.0]\n";
    for (extra, field) in [
        (
            "inner_cone = 30.0\nouter_cone = 20.0",
            "light[0].outer_cone",
        ),
        (
            "inner_cone = -1.0\nouter_cone = 20.0",
            "light[0].inner_cone",
        ),
        ("outer_cone = 91.0", "light[0].outer_cone"),
        ("outer_cone = nan", "light[0].outer_cone"),
        ("outer_cone = 45.0\nrange = 0.0", "light[0].range"),
        ("outer_cone = 45.0\nrange = -2.0", "light[0].range"),
    ] {
        let text = base(&format!("{ok}{extra}"));
        let read = |_: &std::path::Path| -> std::io::Result<Vec<u8>> {
            Err(std::io::ErrorKind::NotFound.into())
        };
        let e = specula::scene::load_scene_str(std::path::Path::new("s.toml"), &text, &read)
            .err()
            .unwrap_or_else(|| panic!("{extra}: accepted"))
            .to_string();
        assert!(e.contains(field), "{extra}: {e}");
    }
    let bad_dir = base("position = [0.0, 1.0, 0.0]\ndirection = [0.0, 0.0, 0.0]\nintensity = [1.0, 1.0, 1.0]\nouter_cone = 45.0");
    let read = |_: &std::path::Path| -> std::io::Result<Vec<u8>> {
        Err(std::io::ErrorKind::NotFound.into())
    };
    let e = specula::scene::load_scene_str(std::path::Path::new("s.toml"), &bad_dir, &read)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("light[0].direction"), "{e}");
}
