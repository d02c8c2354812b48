//! The scene file's tables as serde reads them (`*Desc`): fields as the
//! user writes them, defaults, and unknown fields refused. Checked and
//! built in build.rs.

use crate::material_desc::MaterialDesc;
use serde::Deserialize;
use specula_raster::post::Tonemap;
use std::collections::BTreeMap;
use std::path::PathBuf;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub(super) camera: CameraDesc,
    #[serde(default)]
    pub(super) output: OutputDesc,
    pub(super) environment: Option<EnvironmentDesc>,
    #[serde(default, rename = "mesh")]
    pub(super) meshes: Vec<MeshDesc>,
    #[serde(default)]
    pub(super) materials: BTreeMap<String, MaterialDesc>,
    #[serde(default, rename = "light")]
    pub(super) lights: Vec<LightDesc>,
    pub(super) posterize: Option<PosterizeDesc>,
    #[serde(default)]
    pub(super) render: RenderDesc,
    /// `[[outline]]` and `[strokes]` (lines.rs).
    #[serde(default, rename = "outline")]
    pub(super) outlines: Vec<crate::lines::OutlineDesc>,
    pub(super) strokes: Option<crate::lines::StrokesDesc>,
}

/// `[posterize]`: quantize the tone-mapped image (npr/src/posterize.rs).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PosterizeDesc {
    pub(super) levels: u32,
    #[serde(default)]
    pub(super) mode: PosterizeModeDesc,
}

#[derive(Debug, Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "snake_case")]
pub(super) enum PosterizeModeDesc {
    #[default]
    Rgb,
    Luminance,
}

/// How the frame is lit (the `[render]` table).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RenderDesc {
    /// How polygon lights are integrated: "ltc" (closed form) or
    /// "reference" (converged quadrature per pixel, slow).
    #[serde(default)]
    pub(super) area_lights: AreaLightsDesc,
}

#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(super) enum AreaLightsDesc {
    #[default]
    Ltc,
    Reference,
}

pub(super) fn infinite() -> f32 {
    f32::INFINITY
}

pub(super) fn yes() -> bool {
    true
}

pub(super) fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraDesc {
    pub(super) eye: [f32; 3],
    pub(super) target: [f32; 3],
    #[serde(default = "default_up")]
    pub(super) up: [f32; 3],
    /// Vertical field of view, degrees.
    pub(super) fov_y: f32,
    pub(super) near: f32,
    pub(super) far: f32,
}

/// How the image is produced; CLI flags override the size and supersampling.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct OutputDesc {
    pub width: u32,
    pub height: u32,
    pub(crate) ssaa: u32,
    pub(crate) tonemap: TonemapDesc,
    /// Exposure in stops: radiance is scaled by 2^exposure before tone mapping.
    pub(crate) exposure: f32,
    /// Radiance of uncovered pixels when there is no environment.
    pub(crate) background: [f32; 3],
    /// Text written on the image (`[[output.label]]`, label.rs).
    #[serde(rename = "label")]
    pub labels: Vec<crate::label::LabelDesc>,
}

impl Default for OutputDesc {
    fn default() -> Self {
        OutputDesc {
            width: 960,
            height: 540,
            ssaa: 1,
            tonemap: TonemapDesc::Clamp,
            exposure: 0.0,
            background: [0.0; 3],
            labels: Vec::new(),
        }
    }
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub(crate) enum TonemapDesc {
    #[default]
    Clamp,
    Reinhard,
    Aces,
}

impl From<TonemapDesc> for Tonemap {
    fn from(t: TonemapDesc) -> Tonemap {
        match t {
            TonemapDesc::Clamp => Tonemap::Clamp,
            TonemapDesc::Reinhard => Tonemap::Reinhard,
            TonemapDesc::Aces => Tonemap::Aces,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct EnvironmentDesc {
    /// Radiance arriving equally from every direction.
    pub(super) uniform: Option<[f32; 3]>,
    /// An equirectangular radiance map (Radiance HDR or OpenEXR),
    /// relative to the scene file.
    pub(super) map: Option<String>,
    /// The map's radiance scale.
    #[serde(default = "one")]
    pub(super) intensity: f32,
    /// Degrees about +Y the map is turned by.
    #[serde(default)]
    pub(super) rotate: f32,
    /// The map seen where no surface is.
    #[serde(default = "yes")]
    pub(super) visible: bool,
    #[serde(default)]
    pub(super) ibl: IblDesc,
    /// Samples per pixel of `ibl = "reference"`.
    #[serde(default = "ibl_samples")]
    pub(super) ibl_samples: u32,
    /// `[environment.sun]`: the shadow of the sun taken out of the map.
    pub(super) sun: Option<SunDesc>,
}

/// `[environment.sun]`: the sun taken out of the map (envmap_sun.rs)
/// casts a shadow, with a directional light's shadow fields.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SunDesc {
    /// Shadows: "none", "hard", "pcf" or "pcss" (shadow.rs).
    #[serde(default)]
    pub(super) shadows: ShadowsDesc,
    /// Shadow map side in texels (each cascade's).
    #[serde(default = "shadow_map_size")]
    pub(super) shadow_map_size: u32,
    /// Depth offset toward the sun, in texels.
    #[serde(default = "one")]
    pub(super) bias: f32,
    /// Offset along the surface normal, in texels.
    #[serde(default = "one")]
    pub(super) normal_bias: f32,
    /// PCF half-width in texels.
    #[serde(default = "filter_radius")]
    pub(super) filter_radius: f32,
    /// PCSS: the tangent of the sun's angular diameter; by default the
    /// sun's own, from the solid angle taken out of the map.
    pub(super) light_size: Option<f32>,
    /// Shadow maps along the view's depth, 1 to 4 (shadow.rs).
    #[serde(default = "cascades")]
    pub(super) cascades: u32,
}

/// How an environment map lights surfaces.
#[derive(Debug, Deserialize, Default, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(super) enum IblDesc {
    #[default]
    SplitSum,
    Reference,
}

fn ibl_samples() -> u32 {
    256
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SphereDesc {
    #[serde(default = "one")]
    pub(super) radius: f32,
    #[serde(default = "sphere_segments")]
    pub(super) segments: u32,
    #[serde(default = "sphere_rings")]
    pub(super) rings: u32,
}

pub(super) fn one() -> f32 {
    1.0
}
pub(super) fn sphere_segments() -> u32 {
    64
}
pub(super) fn sphere_rings() -> u32 {
    32
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PlaneDesc {
    #[serde(default = "unit2")]
    pub(super) size: [f32; 2],
    #[serde(default = "one2")]
    pub(super) segments: [u32; 2],
}

pub(super) fn unit2() -> [f32; 2] {
    [1.0, 1.0]
}
pub(super) fn one2() -> [u32; 2] {
    [1, 1]
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CubeDesc {
    #[serde(default = "one")]
    pub(super) size: f32,
    #[serde(default = "one_u")]
    pub(super) segments: u32,
}

pub(super) fn one_u() -> u32 {
    1
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub(super) enum Scale {
    Uniform(f32),
    Axes([f32; 3]),
}

impl Default for Scale {
    fn default() -> Self {
        Scale::Uniform(1.0)
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MeshDesc {
    pub(super) obj: Option<PathBuf>,
    /// A glTF 2.0 file (.gltf or .glb): its default scene's meshes with
    /// their materials (scene/gltf_file.rs).
    pub(super) gltf: Option<PathBuf>,
    pub(super) sphere: Option<SphereDesc>,
    pub(super) plane: Option<PlaneDesc>,
    pub(super) cube: Option<CubeDesc>,
    /// Material for every triangle of the mesh (overrides the MTL's).
    pub(super) material: Option<String>,
    #[serde(default)]
    pub(super) translate: [f32; 3],
    /// Euler angles in degrees, applied about X, then Y, then Z.
    #[serde(default)]
    pub(super) rotate: [f32; 3],
    #[serde(default)]
    pub(super) scale: Scale,
}

// The six shadow fields repeat in the point, spot and directional
// variants: serde's `flatten` would share them, but it cannot be combined
// with `deny_unknown_fields`, which the scene files rely on.
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub(super) enum LightDesc {
    Point {
        position: [f32; 3],
        /// Radiant intensity (W/sr), RGB.
        intensity: [f32; 3],
        /// Distance at which the light's smooth cutoff reaches zero.
        #[serde(default = "infinite")]
        range: f32,
        /// Shadows: "none", "hard", "pcf" or "pcss" (shadow.rs).
        #[serde(default)]
        shadows: ShadowsDesc,
        /// Shadow map side in texels (each cube face's for point lights).
        #[serde(default = "shadow_map_size")]
        shadow_map_size: u32,
        /// Depth offset toward the light, in texels.
        #[serde(default = "one")]
        bias: f32,
        /// Offset along the surface normal, in texels.
        #[serde(default = "one")]
        normal_bias: f32,
        /// PCF half-width in texels.
        #[serde(default = "filter_radius")]
        filter_radius: f32,
        /// PCSS light diameter in world units (directional: tangent of
        /// its angular diameter).
        #[serde(default = "light_size")]
        light_size: f32,
    },
    Spot {
        position: [f32; 3],
        /// Direction the cone points (from the light toward the scene).
        direction: [f32; 3],
        /// Radiant intensity (W/sr) inside the inner cone, RGB.
        intensity: [f32; 3],
        /// Half-angle (degrees) of the cone of full intensity.
        #[serde(default)]
        inner_cone: f32,
        /// Half-angle (degrees) where the falloff reaches zero.
        outer_cone: f32,
        /// Distance at which the light's smooth cutoff reaches zero.
        #[serde(default = "infinite")]
        range: f32,
        /// Shadows: "none", "hard", "pcf" or "pcss" (shadow.rs).
        #[serde(default)]
        shadows: ShadowsDesc,
        /// Shadow map side in texels (each cube face's for point lights).
        #[serde(default = "shadow_map_size")]
        shadow_map_size: u32,
        /// Depth offset toward the light, in texels.
        #[serde(default = "one")]
        bias: f32,
        /// Offset along the surface normal, in texels.
        #[serde(default = "one")]
        normal_bias: f32,
        /// PCF half-width in texels.
        #[serde(default = "filter_radius")]
        filter_radius: f32,
        /// PCSS light diameter in world units (directional: tangent of
        /// its angular diameter).
        #[serde(default = "light_size")]
        light_size: f32,
    },
    Directional {
        /// Direction the light travels (from the light toward the scene).
        direction: [f32; 3],
        /// Irradiance on a surface facing the light, RGB.
        irradiance: [f32; 3],
        /// Shadows: "none", "hard", "pcf" or "pcss" (shadow.rs).
        #[serde(default)]
        shadows: ShadowsDesc,
        /// Shadow map side in texels (each cube face's for point lights).
        #[serde(default = "shadow_map_size")]
        shadow_map_size: u32,
        /// Depth offset toward the light, in texels.
        #[serde(default = "one")]
        bias: f32,
        /// Offset along the surface normal, in texels.
        #[serde(default = "one")]
        normal_bias: f32,
        /// PCF half-width in texels.
        #[serde(default = "filter_radius")]
        filter_radius: f32,
        /// PCSS light diameter in world units (directional: tangent of
        /// its angular diameter).
        #[serde(default = "light_size")]
        light_size: f32,
        /// Shadow maps along the view's depth, 1 to 4 (shadow.rs).
        #[serde(default = "cascades")]
        cascades: u32,
    },
    Polygon {
        /// A planar simple polygon (convex or not), 3 to 16 vertices,
        /// counter-clockwise seen from the side it lights.
        vertices: Vec<[f32; 3]>,
        /// Radiance (W/m²/sr), RGB.
        radiance: [f32; 3],
        /// Emits from both sides.
        #[serde(default)]
        two_sided: bool,
        /// Drawn as unlit geometry of its radiance.
        #[serde(default = "yes")]
        visible: bool,
        /// Shadows: "none", "hard", "pcf" or "pcss" (shadow.rs): a cube
        /// map from the polygon's centre; PCSS with the polygon's size
        /// gives the soft shadow.
        #[serde(default)]
        shadows: ShadowsDesc,
        /// Shadow map side in texels (each cube face's).
        #[serde(default = "shadow_map_size")]
        shadow_map_size: u32,
        /// Depth offset toward the light, in texels.
        #[serde(default = "one")]
        bias: f32,
        /// Offset along the surface normal, in texels.
        #[serde(default = "one")]
        normal_bias: f32,
        /// PCF half-width in texels.
        #[serde(default = "filter_radius")]
        filter_radius: f32,
    },
}

/// A light's `shadows` field.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(super) enum ShadowsDesc {
    #[default]
    None,
    Hard,
    Pcf,
    Pcss,
}

fn shadow_map_size() -> u32 {
    specula_raster::shadow::ShadowSettings::default().map_size
}

fn filter_radius() -> f32 {
    specula_raster::shadow::ShadowSettings::default().filter_radius
}

fn cascades() -> u32 {
    specula_raster::shadow::ShadowSettings::default().cascades
}

fn light_size() -> f32 {
    specula_raster::shadow::ShadowSettings::default().light_size
}
