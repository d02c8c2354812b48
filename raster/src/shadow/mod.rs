//! Shadow maps: per shadowed light, depth-only passes of the scene through
//! the light's view (the camera passes' setup, binning and scan keeping
//! depth alone, `depth_pass.rs`), and the per-lane lookups the light loop
//! multiplies a light's contribution by. The sun taken out of an
//! environment map (`envmap_sun.rs`) is shadowed as the directional light
//! it is shaded as; its factor multiplies the sun's part of the map's
//! light alone (the sky stays unshadowed).
//!
//! A directional light gets one orthographic map, fitted across its
//! direction to the part of the scene's bounds the camera can see (the
//! receivers) and along it to the whole scene (every caster); a spot light
//! one perspective map covering its outer cone; a point light a cube map
//! (six perspective maps of a little over 90°, so a filter near a face's
//! edge stays inside that face). Maps store linear depth along the light's
//! axis (infinity where nothing was drawn), so biases are in world units.
//!
//! Biases are given in texels and scaled by the world size of a texel at
//! the shaded point: `bias` moves the compared depth toward the light,
//! `normal_bias` moves the shaded point along its normal (times
//! 1 + the filter's radius, since a wider filter reads the surface farther
//! from the point). The factor is 1 outside a map.
//!
//! The pieces: [`ShadowSettings`] and their checks (`settings.rs`); the
//! cascades' split depths (`cascades.rs`); each light kind's maps fitted
//! to the scene and the view, and their depth passes (`passes.rs`); the
//! scalar lookups with their filters, hard, PCF and PCSS (`lookup.rs`);
//! the same lookups on a packet's lanes (`lanes.rs`); and every pixel's
//! factor for tests and tools (`pixels.rs`).

mod cascades;
mod lanes;
mod lookup;
mod passes;
mod pixels;
mod settings;

pub use crate::depth_pass::DepthSetup;
pub use cascades::{cascade_splits, CASCADE_LAMBDA, MAX_CASCADES};
pub use passes::polygon_light_size;
pub use pixels::{pixel_shadows, pixel_sun_shadows, PixelShadow};
pub use settings::{ShadowFilter, ShadowSettings, MAX_MAP_SIZE};

use crate::camera::View;
use crate::frame::{FrameStats, Visibility};
use crate::scene::SceneData;
use glam::{Mat4, Vec3};
use passes::{light_faces, render_face, Bounds};
use specula_core::light::Light;

/// One shadow map: a light's view and the depth it saw.
#[derive(Clone, Debug, Default)]
struct Face {
    /// World → the light's clip space.
    clip: Mat4,
    size: u32,
    /// Row-major linear depth (along `axis` from `origin`); infinity where
    /// nothing was drawn.
    depth: Vec<f32>,
    origin: Vec3,
    axis: Vec3,
    /// World size of a texel (perspective maps: at unit depth).
    texel: f32,
    perspective: bool,
    /// Perspective maps: the near distance (NDC depth = near / depth).
    /// Orthographic: NDC depth = 1 − (depth − near) / span.
    near: f32,
    span: f32,
    /// PCF lights: the depth bounds that decide wholly lit and wholly
    /// shadowed lookups without their taps (`lanes.rs`).
    blocks: Option<DepthBlocks>,
}

/// A face's nearest and farthest depth over every 2 × 2 blocks of
/// `side` × `side` texels, row-major by the first block: `near[j·count +
/// i]` is the least depth of the texels of blocks i..=i+1 across and
/// j..=j+1 down (cut to the map). A PCF lookup reads texels spanning at
/// most `side` + 1 along each axis, which two blocks hold.
#[derive(Clone, Debug, Default)]
struct DepthBlocks {
    side: u32,
    /// Blocks along each axis.
    count: u32,
    near: Vec<f32>,
    far: Vec<f32>,
}

/// A shadowed light's maps for one frame.
#[derive(Default)]
pub struct LightShadow {
    pub settings: ShadowSettings,
    faces: Vec<Face>,
    /// How a point picks its face.
    pick: Pick,
    /// The frames' working buffers of each face's depth pass.
    passes: Vec<Option<Visibility>>,
}

/// How a shaded point picks one of a light's faces.
#[derive(Clone, Debug, Default)]
enum Pick {
    /// The only face.
    #[default]
    One,
    /// A point light's cube around this centre: the face of the largest
    /// coordinate of the point's offset from it.
    Cube(Vec3),
    /// A directional light's cascades: the point's view depth
    /// ((p − eye) · forward) against the split depths between them.
    Cascades {
        eye: Vec3,
        forward: Vec3,
        splits: Vec<f32>,
    },
}

/// Every shadowed light's maps for one frame, by light index.
#[derive(Default)]
pub struct ShadowMaps {
    lights: Vec<Option<LightShadow>>,
    /// The environment map's sun's, when the scene shadows it.
    sun: Option<LightShadow>,
    any: bool,
}

impl std::fmt::Debug for ShadowMaps {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShadowMaps")
            .field("passes", &self.passes())
            .finish()
    }
}

impl ShadowMaps {
    /// The maps when some light (or the sun) has shadows.
    pub fn active(&self) -> Option<&ShadowMaps> {
        self.any.then_some(self)
    }

    /// Light `k`'s maps, if it has shadows.
    pub fn light(&self, k: usize) -> Option<&LightShadow> {
        self.lights.get(k).and_then(Option::as_ref)
    }

    /// The environment map's sun's maps, if the scene shadows it
    /// ([`SceneData::sun_shadows`](crate::scene::SceneParts::sun_shadows)).
    pub fn sun(&self) -> Option<&LightShadow> {
        self.sun.as_ref()
    }

    /// Depth passes rendered this frame.
    pub fn passes(&self) -> u32 {
        self.lights
            .iter()
            .chain(std::iter::once(&self.sun))
            .flatten()
            .map(|l| l.faces.len() as u32)
            .sum()
    }

    /// Renders every shadowed light's maps of `scene` for the camera's
    /// `view`; `stats.times.shadow` gets their time.
    pub fn render(&mut self, scene: &SceneData, view: &View, stats: &mut FrameStats) {
        self.render_with(scene, view, DepthSetup::default(), stats);
    }

    /// [`ShadowMaps::render`] with the depth passes' `setup` chosen (the
    /// tests compare the two).
    pub fn render_with(
        &mut self,
        scene: &SceneData,
        view: &View,
        setup: DepthSetup,
        stats: &mut FrameStats,
    ) {
        self.lights.resize_with(scene.lights.len(), || None);
        self.any = false;
        let Some(bounds) = Bounds::of(scene) else {
            self.lights.iter_mut().for_each(|l| *l = None);
            self.sun = None;
            return;
        };
        for (k, light) in scene.lights.iter().enumerate() {
            let slot = &mut self.lights[k];
            match scene.shadows.get(k).copied().flatten() {
                Some(settings) => {
                    self.any |=
                        render_light(slot, settings, light, &bounds, view, scene, setup, stats)
                }
                None => *slot = None,
            }
        }
        // The environment's sun, as the directional light it is shaded as.
        let sun = scene.env_map.as_ref().and_then(|m| m.sun_world());
        match scene.sun_shadows.zip(sun) {
            Some((settings, sun)) => {
                let light = sun.directional();
                let slot = &mut self.sun;
                self.any |=
                    render_light(slot, settings, &light, &bounds, view, scene, setup, stats);
            }
            None => self.sun = None,
        }
    }
}

/// Renders the maps of `light` shadowed with `settings` into `slot`
/// (reusing the buffers it holds) when some map covers the scene;
/// otherwise empties `slot`. Whether `slot` holds maps.
#[allow(clippy::too_many_arguments)]
fn render_light(
    slot: &mut Option<LightShadow>,
    settings: ShadowSettings,
    light: &Light,
    bounds: &Bounds,
    view: &View,
    scene: &SceneData,
    setup: DepthSetup,
    stats: &mut FrameStats,
) -> bool {
    let Some((faces, pick)) = light_faces(&settings, light, bounds, view, scene.camera.near) else {
        *slot = None;
        return false;
    };
    let ls = slot.get_or_insert_with(LightShadow::default);
    ls.settings = settings;
    ls.pick = pick;
    // The previous frame's depth buffers are refilled, not reallocated.
    let mut faces = faces;
    for (new, old) in faces.iter_mut().zip(ls.faces.drain(..)) {
        new.depth = old.depth;
        new.blocks = old.blocks;
    }
    let block_side = settings.pcf_block_side();
    ls.faces = faces;
    ls.passes.resize_with(ls.faces.len(), || None);
    for (face, pass) in ls.faces.iter_mut().zip(&mut ls.passes) {
        render_face(scene, face, pass, block_side, setup, stats);
    }
    true
}

impl LightShadow {
    /// Maps this light renders (a cube's faces, cascades, or one).
    pub fn faces(&self) -> usize {
        self.faces.len()
    }

    /// Face `i`'s map: its side and its row-major linear depth (infinity
    /// where nothing was drawn).
    pub fn depth(&self, i: usize) -> (u32, &[f32]) {
        (self.faces[i].size, &self.faces[i].depth)
    }
}
