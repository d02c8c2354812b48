//! Hard shadow maps against exact visibility: on the shadows fixture scene,
//! for each light alone (directional, spot, point, and the generated sky's
//! sun taken out of its map) with hard shadows, every
//! drawn pixel facing the light is classified shadowed or lit twice: by
//! the renderer's shadow factor (< 0.5: shadowed) and by an Embree shadow
//! ray from the pixel's surface point to the light. At least 99.5 % of
//! those pixels agree, and every disagreement lies within 2 pixels of a
//! shadow edge (a pixel Embree classifies the other way, or an unlit or
//! empty one), but for at most 10 pixels a light (docs/accuracy.md).

use glam::Vec3;
use specula::envmap_file::{load_env_map, EnvSettings};
use specula::scene::{load_scene, LoadedScene};
use specula_bench::embree::EmbreeScene;
use specula_bench::{fixtures, pool};
use specula_core::light::{spot_attenuation, spot_scale_offset, Light};
use specula_raster::envmap::IblMethod;
use specula_raster::shadow::{ShadowFilter, ShadowSettings};
use specula_raster::shadow_pass::{pixel_shadows, pixel_sun_shadows};
use specula_raster::{visibility, FrameStats, Target};

const W: u32 = 960;
const H: u32 = 540;

/// Fixture scene `name` with only light `k`, shadowed with `settings`.
fn scene_with_light(name: &str, k: usize, settings: ShadowSettings) -> LoadedScene {
    let mut s = load_scene(&fixtures().join("scenes").join(name)).expect("fixture scene");
    let mut parts = s.data.into_parts();
    let light = parts.lights[k].clone();
    parts.lights = vec![light];
    parts.shadows = vec![Some(settings)];
    s.data = specula_raster::SceneData::new(parts).expect("valid scene");
    s
}

/// Hard shadows with maps `map_size` a side.
fn hard(map_size: u32) -> ShadowSettings {
    ShadowSettings {
        filter: ShadowFilter::Hard,
        map_size,
        ..ShadowSettings::default()
    }
}

/// Per pixel: `Some(true)` shadowed, `Some(false)` lit by Embree's shadow
/// ray; `None` where nothing is drawn or the surface does not face the
/// light (or lies outside a spot light's cone).
fn embree_classes(
    s: &LoadedScene,
    light: &Light,
    points: &[Option<(Vec3, Vec3)>],
) -> Vec<Option<bool>> {
    let extent = 12.0f32;
    let eps = 1e-4 * extent;
    let mut rays = Vec::new();
    let mut which = Vec::new();
    for (i, pn) in points.iter().enumerate() {
        let Some((p, n)) = pn else { continue };
        let (dir, dist, facing) = match light {
            Light::Directional { to_light, .. } => {
                let d = Vec3::from(*to_light);
                (d, f32::INFINITY, true)
            }
            Light::Point { position, .. } => {
                let v = Vec3::from(*position) - *p;
                (v.normalize(), v.length(), true)
            }
            Light::Spot {
                position,
                direction,
                cos_inner,
                cos_outer,
                ..
            } => {
                let v = Vec3::from(*position) - *p;
                let (sc, off) = spot_scale_offset(*cos_inner, *cos_outer);
                let cd = -Vec3::from(*direction).dot(v.normalize());
                (
                    v.normalize(),
                    v.length(),
                    spot_attenuation(cd, sc, off) > 0.0,
                )
            }
            Light::Polygon { .. } => unreachable!(),
        };
        if !facing || n.dot(dir) <= 0.0 {
            continue;
        }
        let o = *p + *n * eps;
        rays.push((o.to_array(), dir.to_array(), 0.0, dist * (1.0 - 1e-4)));
        which.push(i);
    }
    let embree = EmbreeScene::new(&s.data, 2).expect("Embree scene");
    let hit = pool(2).install(|| embree.occluded(&rays));
    let mut out = vec![None; points.len()];
    for (i, h) in which.into_iter().zip(hit) {
        out[i] = Some(h);
    }
    out
}

/// How a light's shadow factors compare with Embree's classes.
struct Agreement {
    /// Pixels facing the light.
    classified: usize,
    /// Of those, shadowed by Embree.
    shadowed: usize,
    /// Classified alike.
    agree: usize,
    /// Disagreeing pixels farther than 2 pixels from an edge of Embree's
    /// shadow.
    far_from_edge: Vec<(i32, i32)>,
}

/// Renders `s` (one shadowed light, or no light and its environment
/// map's sun shadowed) and compares the shadow factors (< 0.5: shadowed)
/// with Embree's shadow rays, pixel by pixel.
fn agreement(s: &LoadedScene, name: &str) -> Agreement {
    let target = Target::new(W, H).unwrap();
    let v = pool(2).install(|| visibility(&s.data, &target, &mut FrameStats::default()));
    let (px, light) = match s.data.lights.first() {
        Some(light) => (pixel_shadows(&s.data, &target, &v, 0), light.clone()),
        None => {
            let sun = s.data.env_map.as_ref().and_then(|m| m.sun_world());
            let light = sun.expect("a light or a sun").directional();
            (pixel_sun_shadows(&s.data, &target, &v), light)
        }
    };
    assert_eq!(px.len(), (W * H) as usize, "{name}: a map for the light");
    let points: Vec<_> = px.iter().map(|p| p.map(|p| (p.p, p.n))).collect();
    let exact = embree_classes(s, &light, &points);
    let (mut classified, mut agree, mut shadowed) = (0usize, 0usize, 0usize);
    let mut far_from_edge = Vec::new();
    for y in 0..H as i32 {
        for x in 0..W as i32 {
            let i = (y * W as i32 + x) as usize;
            let (Some(e), Some(p)) = (exact[i], px[i]) else {
                continue;
            };
            classified += 1;
            shadowed += e as usize;
            let ours = p.factor < 0.5;
            if ours == e {
                agree += 1;
                continue;
            }
            let near_edge = (-2..=2).any(|dy| {
                (-2..=2).any(|dx| {
                    let (xx, yy) = (x + dx, y + dy);
                    if xx < 0 || yy < 0 || xx >= W as i32 || yy >= H as i32 {
                        return true;
                    }
                    exact[(yy * W as i32 + xx) as usize] != Some(e)
                })
            });
            if !near_edge {
                eprintln!(
                    "{name} ({x}, {y}): p {:?} n {:?} factor {} embree {e}",
                    p.p, p.n, p.factor
                );
                far_from_edge.push((x, y));
            }
        }
    }
    Agreement {
        classified,
        shadowed,
        agree,
        far_from_edge,
    }
}

/// Agreement of the hard shadow map of the shadows scene's light `k` with
/// Embree.
fn crosscheck(k: usize, name: &str) {
    expect_agreement(&scene_with_light("shadows.toml", k, hard(2048)), name);
}

/// At least 99.5 % of the pixels facing `s`'s one shadowed source agree
/// with Embree, and at most 10 disagree away from shadow edges.
fn expect_agreement(s: &LoadedScene, name: &str) {
    let Agreement {
        classified,
        shadowed,
        agree,
        far_from_edge,
    } = agreement(s, name);
    let frac = agree as f64 / classified as f64;
    eprintln!(
        "{name}: {classified} pixels facing the light, {shadowed} shadowed by Embree, {:.3} % agree, {} mismatches farther than 2 px from an edge",
        100.0 * frac,
        far_from_edge.len()
    );
    assert!(shadowed > 1000, "{name}: the scene should show shadows");
    assert!(frac >= 0.995, "{name}: {:.3} % agree", 100.0 * frac);
    // The point light's cube map leaves a few floor pixels dark in the
    // corner where the floor meets a side of the turned cube that the
    // light grazes (docs/accuracy.md): at most 10 are allowed.
    assert!(
        far_from_edge.len() <= 10,
        "{name}: mismatches away from shadow edges at {:?}",
        &far_from_edge[..far_from_edge.len().min(20)]
    );
}

#[test]
fn directional_hard_shadows_match_embree() {
    crosscheck(0, "directional");
}

#[test]
fn spot_hard_shadows_match_embree() {
    crosscheck(1, "spot");
}

#[test]
fn point_hard_shadows_match_embree() {
    crosscheck(2, "point");
}

/// A point light at the centre of the shadows scene's clay sphere: Embree
/// finds every surface it faces outside the sphere shadowed, and so must
/// the cube map. The sphere is a closed solid, whose back faces a depth
/// pass culls when the light is outside it; from within its bounds they
/// are drawn, and they are all the light sees.
#[test]
fn a_point_light_inside_a_closed_sphere_is_shadowed_by_it() {
    let mut s = scene_with_light("shadows.toml", 2, hard(1024));
    let mut parts = s.data.into_parts();
    let Light::Point { position, .. } = &mut parts.lights[0] else {
        panic!("the shadows scene's light 2 is a point light");
    };
    *position = [-1.3, 0.6, 0.2];
    s.data = specula_raster::SceneData::new(parts).expect("valid scene");
    let Agreement {
        classified,
        shadowed,
        agree,
        ..
    } = agreement(&s, "inside");
    assert!(classified > 10_000, "{classified} pixels facing the light");
    assert_eq!(
        shadowed, classified,
        "Embree: everything it faces is behind the sphere"
    );
    assert_eq!(
        agree, classified,
        "the cube map shadows every pixel Embree does"
    );
}

/// The shadows scene without its lights, lit by the generated sky
/// (`fixtures/env/sky.hdr`), whose sun is taken out of the map and
/// shadowed with hard maps.
#[test]
fn the_skys_sun_hard_shadows_match_embree() {
    let mut s = load_scene(&fixtures().join("scenes/shadows.toml")).expect("fixture scene");
    let path = fixtures().join("env/sky.hdr");
    let bytes = std::fs::read(&path).expect("fixture sky");
    let settings = EnvSettings {
        intensity: 1.0,
        rotate_deg: 0.0,
        visible: true,
        method: IblMethod::SplitSum,
    };
    let map = load_env_map("sky.hdr", &bytes, &settings).expect("the sky loads");
    assert!(map.sun_world().is_some(), "the sky's sun is taken out");
    let mut parts = s.data.into_parts();
    parts.lights.clear();
    parts.shadows.clear();
    parts.environment = None;
    parts.env_map = Some(std::sync::Arc::new(map));
    parts.sun_shadows = Some(hard(2048));
    s.data = specula_raster::SceneData::new(parts).expect("valid scene");
    expect_agreement(&s, "sun");
}

/// On a long ground plane seen from a low camera, a directional light's
/// hard shadow disagrees with Embree on fewer pixels with 2, 3 and 4
/// cascades than with one map of the same total texels (2048², 1448²
/// each, 1182² each, 1024² each), and with 4 cascades at most 0.5 % of
/// the pixels facing the light disagree (docs/accuracy.md).
#[test]
fn cascades_follow_exact_shadows_closer_at_equal_texels() {
    let total = 2048.0f64 * 2048.0;
    let mut wrong = Vec::new();
    for cascades in 1..=4u32 {
        let side = (total / cascades as f64).sqrt().round() as u32;
        let settings = ShadowSettings {
            cascades,
            ..hard(side)
        };
        let s = scene_with_light("shadows_cascades.toml", 0, settings);
        let name = format!("{cascades} cascade(s) of {side}²");
        let a = agreement(&s, &name);
        let miss = a.classified - a.agree;
        eprintln!(
            "{name}: {} pixels facing the light, {} shadowed by Embree, {miss} disagree ({:.3} %), {} farther than 2 px from an edge",
            a.classified,
            a.shadowed,
            100.0 * miss as f64 / a.classified as f64,
            a.far_from_edge.len()
        );
        assert!(a.shadowed > 1000, "{name}: the scene should show shadows");
        wrong.push((miss, a.classified));
    }
    for (i, (miss, _)) in wrong.iter().enumerate().skip(1) {
        assert!(
            *miss < wrong[0].0,
            "{} cascades: {miss} pixels disagree, one map: {}",
            i + 1,
            wrong[0].0
        );
    }
    let (miss4, n4) = wrong[3];
    assert!(
        miss4 as f64 <= 0.005 * n4 as f64,
        "4 cascades: {miss4} of {n4} disagree"
    );
}

/// A polygon light's soft shadow against traced visibility: on the area
/// shadows fixture (a rectangle light with PCSS shadows), each drawn pixel
/// the rectangle lights gets the renderer's shadow factor and a Monte
/// Carlo estimate of the exact ratio of shadowed to unshadowed diffuse
/// irradiance from the rectangle: 8 × 8 jittered samples over its area,
/// each weighted by its form factor cos θ cos θ' / r² and traced by an
/// Embree shadow ray. Per pixel that estimate's standard error is below
/// 0.5/8 where the light is partly hidden (0 where it is all seen or all
/// hidden); over thousands of pixels the means carry well under 0.01 of
/// it. Measured at 128² to 1024² cube faces, bounded at the fixture's
/// 256² (docs/accuracy.md).
#[test]
fn polygon_soft_shadows_match_traced_visibility() {
    let mut fixture = None;
    for size in [128, 256, 512, 1024] {
        let m = area_errors(size);
        if size == 256 {
            fixture = Some(m);
        }
    }
    let (mean, pen_mean, big, shadowed) = fixture.expect("the fixture's map size");
    assert!(shadowed > 2000, "the scene should show shadows");
    assert!(mean < MEAN_BOUND, "mean error {mean}");
    assert!(
        pen_mean < PENUMBRA_BOUND,
        "mean error in penumbrae {pen_mean}"
    );
    assert!(big < BIG_BOUND, "{big} of the pixels off by more than 0.2");
}

/// [`polygon_soft_shadows_match_traced_visibility`]'s bounds for the
/// fixture's 256² cube faces.
const MEAN_BOUND: f64 = 0.03;
const PENUMBRA_BOUND: f64 = 0.09;
const BIG_BOUND: f64 = 0.02;

/// The polygon light's errors with cube faces `size` a side: the mean
/// |factor − traced| over the pixels it lights and over those in
/// penumbrae, the fraction off by more than 0.2, and how many pixels are
/// partly or wholly shadowed.
fn area_errors(size: u32) -> (f64, f64, f64, usize) {
    const AW: u32 = 480;
    const AH: u32 = 270;
    const N: usize = 8;
    let mut s = load_scene(&fixtures().join("scenes/shadows_area.toml")).expect("area scene");
    let mut parts = s.data.into_parts();
    if let Some(Some(settings)) = parts.shadows.get_mut(0) {
        settings.map_size = size;
    }
    s.data = specula_raster::SceneData::new(parts).expect("valid scene");
    let Light::Polygon { vertices, .. } = &s.data.lights[0] else {
        panic!("the fixture's light is a polygon");
    };
    let [v0, v1, _, v3] = [0, 1, 2, 3].map(|i| Vec3::from(vertices[i]));
    let (e1, e2) = (v1 - v0, v3 - v0);
    let nl = e1.cross(e2).normalize();
    let target = Target::new(AW, AH).unwrap();
    let v = pool(2).install(|| visibility(&s.data, &target, &mut FrameStats::default()));
    let px = pixel_shadows(&s.data, &target, &v, 0);
    assert_eq!(px.len(), (AW * AH) as usize, "a map for the polygon light");
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 40) as f32 / (1u64 << 24) as f32
    };
    let eps = 1e-4 * 12.0;
    let (mut rays, mut weights, mut owner) = (Vec::new(), Vec::new(), Vec::new());
    let mut pixels = Vec::new();
    for (i, p) in px.iter().enumerate() {
        let Some(p) = p else { continue };
        let first = rays.len();
        for j in 0..N * N {
            let (a, b) = (
                ((j % N) as f32 + rnd()) / N as f32,
                ((j / N) as f32 + rnd()) / N as f32,
            );
            let q = v0 + e1 * a + e2 * b;
            let d = q - p.p;
            let r = d.length();
            let w = d.dot(p.n).max(0.0) * (-d).dot(nl).max(0.0) / (r * r * r * r);
            if w > 0.0 {
                let o = p.p + p.n * eps;
                let dir = (q - o).normalize();
                rays.push((
                    o.to_array(),
                    dir.to_array(),
                    0.0,
                    (q - o).length() * (1.0 - 1e-4),
                ));
                weights.push(w);
                owner.push(pixels.len());
            }
        }
        if rays.len() > first {
            pixels.push((i, p.factor));
        }
    }
    let embree = EmbreeScene::new(&s.data, 2).expect("Embree scene");
    let hit = pool(2).install(|| embree.occluded(&rays));
    let mut lit = vec![(0.0f64, 0.0f64); pixels.len()];
    for ((h, w), o) in hit.iter().zip(&weights).zip(&owner) {
        lit[*o].1 += *w as f64;
        if !h {
            lit[*o].0 += *w as f64;
        }
    }
    let (mut sum, mut big, mut pen_sum, mut pen_n, mut shadowed) = (0.0, 0usize, 0.0, 0usize, 0);
    let mut bias = 0.0;
    for ((_, factor), (l, t)) in pixels.iter().zip(&lit) {
        let exact = l / t;
        let err = *factor as f64 - exact;
        sum += err.abs();
        bias += err;
        big += (err.abs() > 0.2) as usize;
        shadowed += (exact < 0.98) as usize;
        if (0.02..0.98).contains(&exact) {
            pen_sum += err.abs();
            pen_n += 1;
        }
    }
    let n = pixels.len() as f64;
    let (mean, pen_mean) = (sum / n, pen_sum / pen_n as f64);
    eprintln!(
        "polygon light, {size}² faces: {} pixels lit by it, {shadowed} partly or wholly shadowed, {pen_n} in penumbrae; mean |factor − traced| {mean:.4} (signed {:.4}), in penumbrae {pen_mean:.4}; {big} pixels ({:.3} %) off by more than 0.2",
        pixels.len(),
        bias / n,
        100.0 * big as f64 / n
    );
    (mean, pen_mean, big as f64 / n, shadowed)
}
