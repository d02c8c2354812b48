//! Draws a frame's shadow maps ([`ShadowMaps`], read by the light loop
//! through `shadow`): each shadowed light's faces fitted to the scene and
//! the view (`fit.rs`), each face a depth-only pass of the scene
//! (`depth_pass.rs`) kept as linear depth, with its window bounds for PCF;
//! and every pixel's factor, for tests and tools that compare the maps
//! with exact visibility (`pixels.rs`).

mod fit;
mod pixels;

pub use crate::depth_pass::DepthSetup;
pub use pixels::{pixel_shadows, pixel_sun_shadows};

use crate::camera::View;
use crate::depth_pass::{depth_pass, LinearDepth};
use crate::scene::SceneData;
use crate::shadow::{Face, LightShadow, ShadowMaps, ShadowSettings};
use crate::stats::{ms_since, FrameStats};
use crate::target::Target;
use crate::visibility::{ShadowBuffers, Visibility};
use fit::{light_faces, Bounds};
use rayon::prelude::*;
use specula_core::light::Light;
use std::time::Instant;

/// Renders every shadowed light's maps of `scene` for the camera's `view`
/// into `maps`, drawing each face with its buffers in `buffers` (those of
/// an earlier frame are refilled); `setup` picks the depth passes' setup
/// (the tests compare the two). `stats.times.shadow` gets the whole of it:
/// the faces' fitting, their depth passes, linear depth and window bounds.
pub fn render_maps(
    scene: &SceneData,
    view: &View,
    setup: DepthSetup,
    maps: &mut ShadowMaps,
    buffers: &mut ShadowBuffers,
    stats: &mut FrameStats,
) {
    let t = Instant::now();
    let n = scene.lights.len();
    maps.lights.resize_with(n, || None);
    buffers.lights.resize_with(n, Vec::new);
    maps.any = false;
    let Some(bounds) = Bounds::of(scene) else {
        maps.lights.iter_mut().for_each(|l| *l = None);
        maps.sun = None;
        *buffers = ShadowBuffers::default();
        // No finite position: nothing drawn, and the scan for bounds is
        // too short to count.
        return;
    };
    // Every face of every light is fitted first, then all are drawn as
    // one parallel loop: a depth pass's own parallel steps end in joins
    // where a thread would wait, and another face's work fills them.
    let mut jobs = Vec::new();
    let lights = maps.lights.iter_mut().zip(&mut buffers.lights);
    for (k, (light, (slot, passes))) in scene.lights.iter().zip(lights).enumerate() {
        let map = Map { slot, passes };
        match scene.shadows.get(k).copied().flatten() {
            Some(settings) => {
                maps.any |= fit_light(map, settings, light, &bounds, view, scene, &mut jobs)
            }
            None => map.clear(),
        }
    }
    // The environment's sun, as the directional light it is shaded as.
    let sun = scene.env_map.as_ref().and_then(|m| m.sun_world());
    let map = Map {
        slot: &mut maps.sun,
        passes: &mut buffers.sun,
    };
    match scene.sun_shadows.zip(sun) {
        Some((settings, sun)) => {
            let light = sun.directional();
            maps.any |= fit_light(map, settings, &light, &bounds, view, scene, &mut jobs);
        }
        None => map.clear(),
    }
    let counts: Vec<FrameStats> = jobs
        .into_par_iter()
        .map(|job| {
            let mut own = FrameStats::default();
            render_face(scene, job, setup, &mut own);
            own
        })
        .collect();
    for own in &counts {
        stats.shadow_passes += own.shadow_passes;
        stats.shadow_faces_blank += own.shadow_faces_blank;
        stats.shadow_counts.add(&own.shadow_counts);
    }
    stats.times.shadow += ms_since(t);
}

/// A face to draw: its map, the buffers of its depth pass, and the side
/// of its PCF windows (none without PCF).
struct FaceJob<'a> {
    face: &'a mut Face,
    pass: &'a mut Option<Visibility>,
    window: Option<u32>,
}

/// One light's maps and the buffers of their depth passes.
struct Map<'a> {
    slot: &'a mut Option<LightShadow>,
    passes: &'a mut Vec<Option<Visibility>>,
}

impl Map<'_> {
    /// No maps, and no buffers kept for them.
    fn clear(self) {
        *self.slot = None;
        self.passes.clear();
    }
}

/// Fits the maps of `light` shadowed with `settings` into `map` (reusing
/// the buffers it holds) when some map covers the scene, adding their
/// faces to `jobs` to be drawn; otherwise clears `map`. Whether `map`
/// holds maps.
fn fit_light<'a>(
    map: Map<'a>,
    settings: ShadowSettings,
    light: &Light,
    bounds: &Bounds,
    view: &View,
    scene: &SceneData,
    jobs: &mut Vec<FaceJob<'a>>,
) -> bool {
    let Some((faces, pick)) = light_faces(&settings, light, bounds, view, scene.camera.near) else {
        map.clear();
        return false;
    };
    let ls = map.slot.get_or_insert_with(LightShadow::default);
    ls.settings = settings;
    ls.pick = pick;
    // The previous frame's depth buffers are refilled, not reallocated.
    let mut faces = faces;
    for (new, old) in faces.iter_mut().zip(ls.faces.drain(..)) {
        new.depth = old.depth;
        new.bounds = old.bounds;
        new.blank = old.blank;
    }
    let window = settings.pcf_window();
    ls.faces = faces;
    map.passes.resize_with(ls.faces.len(), || None);
    let faces = ls.faces.iter_mut().zip(map.passes.iter_mut());
    jobs.extend(faces.map(|(face, pass)| FaceJob { face, pass, window }));
    true
}

/// Draws a face's depth pass and keeps its linear depth, row-major, and
/// with a window its depth bounds over windows of that side. A face that
/// sees nothing gets the map such a pass draws, every texel infinity,
/// without the pass (unless `setup` is the full reference).
fn render_face(scene: &SceneData, job: FaceJob, setup: DepthSetup, stats: &mut FrameStats) {
    let FaceJob { face, pass, window } = job;
    if face.sees_nothing && setup == DepthSetup::DepthOnly {
        stats.shadow_faces_blank += 1;
        if face.blank != Some((face.size, window)) {
            fill_blank(face, window);
        }
        return;
    }
    face.blank = None;
    let target = Target::new(face.size, face.size).expect("map size checked at load");
    // A perspective face's near plane: at `near` along its axis, half as
    // wide as tan_half × near (its texel is 2 tan_half / size).
    let tan_half = 0.5 * face.texel * face.size as f32;
    let corner = face.near * (1.0 + 2.0 * tan_half * tan_half).sqrt();
    let eye = face.perspective.then_some((face.origin, corner));
    let n = face.size as usize;
    crate::buffers::resize_zeroed(&mut face.depth, n * n);
    let linear = if face.perspective {
        LinearDepth::Perspective { near: face.near }
    } else {
        LinearDepth::Orthographic {
            near: face.near,
            span: face.span,
        }
    };
    depth_pass(
        scene,
        &target,
        face.clip,
        eye,
        setup,
        pass,
        &mut face.depth,
        linear,
        stats,
    );
    fill_bounds(face, window);
}

/// Fills `face` with the map of a depth pass that draws nothing, and its
/// bounds over `window`.
fn fill_blank(face: &mut Face, window: Option<u32>) {
    let n = face.size as usize;
    face.depth.clear();
    face.depth.resize(n * n, f32::INFINITY);
    fill_bounds(face, window);
    face.blank = Some((face.size, window));
}

/// Fills `face`'s depth bounds over windows of side `window` from its
/// depth (none without a window).
fn fill_bounds(face: &mut Face, window: Option<u32>) {
    match window {
        Some(window) => {
            let mut bounds = face.bounds.take().unwrap_or_default();
            bounds.fill(&face.depth, face.size as usize, window);
            face.bounds = Some(bounds);
        }
        None => face.bounds = None,
    }
}
