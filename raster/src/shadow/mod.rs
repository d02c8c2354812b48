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
//! This module holds the maps and reads them; `shadow_pass` draws them.
//! The pieces: [`ShadowSettings`] and their checks (`settings.rs`); the
//! cascades' split depths (`cascades.rs`); a map's depth bounds over
//! its filter windows (`windows.rs`); the scalar lookups with their filters, hard, PCF and
//! PCSS (`lookup.rs`); and the same lookups on a packet's lanes
//! (`lanes.rs`).

mod cascades;
mod lanes;
mod lookup;
mod settings;
mod windows;

pub(crate) use cascades::cascade_splits;
pub(crate) use settings::polygon_shape;
pub use settings::{
    polygon_light_size, ShadowFilter, ShadowSettings, ShadowSettingsError, MAX_MAP_SIZE,
};

use glam::{Mat4, Vec3};

/// One shadow map: a light's view and the depth it saw.
#[derive(Clone, Debug, Default)]
pub(crate) struct Face {
    /// World → the light's clip space.
    pub(crate) clip: Mat4,
    pub(crate) size: u32,
    /// Row-major linear depth (along `axis` from `origin`); infinity where
    /// nothing was drawn.
    pub(crate) depth: Vec<f32>,
    pub(crate) origin: Vec3,
    pub(crate) axis: Vec3,
    /// World size of a texel (perspective maps: at unit depth).
    pub(crate) texel: f32,
    pub(crate) perspective: bool,
    /// Perspective maps: the near distance (NDC depth = near / depth).
    /// Orthographic: NDC depth = 1 − (depth − near) / span.
    pub(crate) near: f32,
    pub(crate) span: f32,
    /// PCF lights: the depth bounds that decide wholly lit and wholly
    /// shadowed lookups without their taps (`lanes.rs`).
    pub(crate) bounds: Option<DepthWindows>,
    /// Nothing of the scene lies in front of the face (a point light's
    /// face toward open sky): its depth pass would draw nothing.
    pub(crate) sees_nothing: bool,
    /// The size and PCF window of the map with nothing drawn (every depth
    /// and bound infinity) that `depth` and `bounds` hold, if they hold
    /// one: a face that sees nothing frame after frame fills it once.
    pub(crate) blank: Option<(u32, Option<u32>)>,
}

/// A face's nearest and farthest depth over every window of `window` ×
/// `window` texels, row-major by the window's first texel: `near[y·size
/// + x]` is the least depth of texels x..x + window across and y..y +
/// window down (cut to the map). A PCF lookup reads texels spanning at
/// most `window` along each axis, so one window holds them.
#[derive(Clone, Debug, Default)]
pub(crate) struct DepthWindows {
    window: u32,
    near: Vec<f32>,
    far: Vec<f32>,
}

/// A shadowed light's maps for one frame.
#[derive(Default)]
pub struct LightShadow {
    pub(crate) settings: ShadowSettings,
    pub(crate) faces: Vec<Face>,
    /// How a point picks its face.
    pub(crate) pick: Pick,
}

/// How a shaded point picks one of a light's faces.
#[derive(Clone, Debug, Default)]
pub(crate) enum Pick {
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
    pub(crate) lights: Vec<Option<LightShadow>>,
    /// The environment map's sun's, when the scene shadows it.
    pub(crate) sun: Option<LightShadow>,
    pub(crate) any: bool,
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
    pub(crate) fn active(&self) -> Option<&ShadowMaps> {
        self.any.then_some(self)
    }

    /// Light `k`'s maps, if it has shadows.
    pub fn light(&self, k: usize) -> Option<&LightShadow> {
        self.lights.get(k).and_then(Option::as_ref)
    }

    /// The environment map's sun's maps, if the scene shadows it
    /// ([`SceneData::sun_shadows`](crate::scene::SceneParts::sun_shadows)).
    pub(crate) fn sun(&self) -> Option<&LightShadow> {
        self.sun.as_ref()
    }

    /// Depth passes rendered this frame.
    pub(crate) fn passes(&self) -> u32 {
        self.lights
            .iter()
            .chain(std::iter::once(&self.sun))
            .flatten()
            .map(|l| l.faces.len() as u32)
            .sum()
    }
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
