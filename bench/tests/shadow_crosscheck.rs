//! Hard shadow maps against exact visibility: on the shadows fixture scene,
//! for each light alone (directional, spot, point) with hard shadows, every
//! drawn pixel facing the light is classified shadowed or lit twice: by
//! the renderer's shadow factor (< 0.5: shadowed) and by an Embree shadow
//! ray from the pixel's surface point to the light. At least 99.5 % of
//! those pixels agree, and every disagreement lies within 2 pixels of a
//! shadow edge (a pixel Embree classifies the other way, or an unlit or
//! empty one), but for at most 10 pixels a light (docs/accuracy.md).

use glam::Vec3;
use specula::scene::{load_scene, LoadedScene};
use specula_bench::embree::EmbreeScene;
use specula_bench::{fixtures, pool};
use specula_core::light::{spot_attenuation, spot_scale_offset, Light};
use specula_raster::shadow::{pixel_shadows, ShadowFilter, ShadowSettings};
use specula_raster::{visibility, FrameStats, Target};

const W: u32 = 960;
const H: u32 = 540;

/// The fixture scene with only light `k`, shadowed with `filter`.
fn scene_with_light(k: usize, filter: ShadowFilter) -> LoadedScene {
    let mut s = load_scene(&fixtures().join("scenes/shadows.toml")).expect("shadows scene");
    let light = s.data.lights[k].clone();
    s.data.lights = vec![light];
    s.data.shadows = vec![Some(ShadowSettings {
        filter,
        map_size: 2048,
        ..ShadowSettings::default()
    })];
    s.data.validate().expect("valid scene");
    s
}

/// Per pixel: `Some(true)` shadowed, `Some(false)` lit by Embree's shadow
/// ray; `None` where nothing is drawn or the surface does not face the
/// light (or lies outside a spot light's cone).
fn embree_classes(s: &LoadedScene, points: &[Option<(Vec3, Vec3)>]) -> Vec<Option<bool>> {
    let light = &s.data.lights[0];
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

/// Agreement of the hard shadow map of light `k` with Embree.
fn crosscheck(k: usize, name: &str) {
    let s = scene_with_light(k, ShadowFilter::Hard);
    let target = Target::new(W, H).unwrap();
    let v = pool(2).install(|| visibility(&s.data, &target, &mut FrameStats::default()));
    let px = pixel_shadows(&s.data, &target, &v, 0);
    assert_eq!(px.len(), (W * H) as usize, "{name}: a map for the light");
    let points: Vec<_> = px.iter().map(|p| p.map(|p| (p.p, p.n))).collect();
    let exact = embree_classes(&s, &points);
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
    let frac = agree as f64 / classified as f64;
    eprintln!(
        "{name}: {classified} pixels facing the light, {shadowed} shadowed by Embree, {:.3} % agree, {} mismatches farther than 2 px from an edge",
        100.0 * frac,
        far_from_edge.len()
    );
    assert!(shadowed > 1000, "{name}: the scene should show shadows");
    assert!(frac >= 0.995, "{name}: {:.3} % agree", 100.0 * frac);
    // The point light's cube map leaves a few isolated floor pixels dark
    // near the cube's shadow (docs/accuracy.md): at most 10 are allowed.
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
