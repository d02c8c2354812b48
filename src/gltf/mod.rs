//! glTF 2.0 input (`.gltf` JSON with its buffers and images, or `.glb`):
//! the default scene's meshes with their node transforms, materials,
//! cameras and KHR_lights_punctual lights, read through the `gltf` crate's
//! JSON types and checked here, so that bad input is an error naming the
//! JSON path (`meshes[0].primitives[1].attributes.POSITION`), never a panic.
//!
//! What comes out ([`GltfScene`]) is still glTF's: positions in the
//! scene's space (node transforms applied, +Y up, metres), uvs with
//! (0, 0) at the top-left of the image, materials as the file describes
//! them (`material::GltfMaterial`). `scene/gltf_file.rs` places it in a
//! specula scene; `scene_material::scene_material` makes its materials.

mod buffers;
mod error;
mod glb;
pub(crate) mod images;
pub(crate) mod material;
mod nodes;
pub(crate) mod scene_material;

use crate::checks;
use buffers::Buffers;
pub use error::{DataUriError, GltfError};
use glam::{Mat4, Vec2, Vec3, Vec4};
use gltf::json;
use json::validation::Validate;
use material::GltfMaterial;
use specula_core::light::Light;
use std::path::{Path, PathBuf};

/// Extensions this loader reads (the others in `extensionsRequired` are an
/// error, in `extensionsUsed` a warning). KHR_texture_transform and the
/// material extensions are read into the material description, which
/// says which of them are rendered.
pub(crate) const KNOWN_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_pbrSpecularGlossiness",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
    "KHR_materials_volume",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_iridescence",
    "KHR_materials_anisotropy",
    "KHR_materials_dispersion",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_variants",
    "KHR_mesh_quantization",
];

/// One triangle primitive of one mesh instance, in the scene's space.
#[derive(Clone, Debug, Default)]
pub struct GltfPrimitive {
    /// `meshes[m].primitives[p]` (under `nodes[n]`).
    pub at: String,
    pub positions: Vec<Vec3>,
    /// Unit normals: the file's, or flat ones (each triangle its own three
    /// vertices) where it has none, as the spec requires.
    pub normals: Vec<Vec3>,
    /// TANGENT (xyz unit, w = ±1 handedness), when given with normals.
    pub(crate) tangents: Option<Vec<Vec4>>,
    /// TEXCOORD_0 and TEXCOORD_1 in glTF's convention: (0, 0) is the
    /// top-left corner of the image.
    pub uv0: Option<Vec<Vec2>>,
    pub(crate) uv1: Option<Vec<Vec2>>,
    /// COLOR_0 as RGBA (alpha 1 where the file gives RGB).
    pub(crate) color0: Option<Vec<Vec4>>,
    /// Counter-clockwise seen from the front (after the node transform:
    /// mirroring ones are flipped back).
    pub triangles: Vec<[u32; 3]>,
    /// `materials[i]`, or `None` for the default material.
    pub(crate) material: Option<usize>,
}

/// A camera's projection as the file gives it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Projection {
    /// `yfov` in radians; `zfar` `None` is infinite.
    Perspective {
        yfov: f32,
        aspect_ratio: Option<f32>,
        znear: f32,
        zfar: Option<f32>,
    },
    Orthographic {
        xmag: f32,
        ymag: f32,
        znear: f32,
        zfar: f32,
    },
}

/// A camera placed by its node: it looks down its local −Z, +Y up.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfCamera {
    /// `cameras[c]` (at `nodes[n]`).
    pub(crate) at: String,
    pub eye: Vec3,
    /// Unit view direction and up.
    pub forward: Vec3,
    pub up: Vec3,
    pub(crate) projection: Projection,
}

/// The default scene of a glTF file, read and checked.
pub struct GltfScene {
    pub primitives: Vec<GltfPrimitive>,
    /// `materials[i]`, in order.
    pub(crate) materials: Vec<GltfMaterial>,
    /// Cameras in the order their nodes are met (depth first, children in
    /// order), which `--camera N` counts.
    pub cameras: Vec<GltfCamera>,
    /// KHR_lights_punctual lights placed by their nodes (glTF's candela
    /// and lux taken as W/sr and W/m²).
    pub lights: Vec<Light>,
    pub warnings: Vec<String>,
    /// Files read besides the glTF itself (buffers, images read so far).
    pub(crate) inputs: Vec<PathBuf>,
    root: json::Root,
    buffers: Buffers,
    dir: PathBuf,
}

impl GltfScene {
    /// The images of the file, decoded on demand (`read` supplies files
    /// relative to the glTF's folder).
    pub(crate) fn images<'a>(
        &'a self,
        read: &'a dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    ) -> images::Images<'a> {
        images::Images::new(&self.root, &self.buffers, self.dir.clone(), read)
    }
}

/// What the loader carries while it reads a file.
pub(crate) struct Ctx<'a> {
    pub(crate) root: json::Root,
    /// The glTF's folder, which its relative URIs are resolved against.
    pub(crate) dir: PathBuf,
    pub(crate) read: &'a dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    pub(crate) inputs: Vec<PathBuf>,
    pub(crate) warnings: Vec<String>,
}

/// Whether `bytes` are a GLB container (by its magic).
pub(crate) fn is_glb(bytes: &[u8]) -> bool {
    bytes.starts_with(glb::MAGIC)
}

/// Reads a glTF file from its bytes. `path` names it (a `.glb` name must
/// hold a GLB container) and locates its relative URIs, which `read`
/// supplies. Errors name the JSON path, not the file (the caller adds it).
pub fn load(
    path: &Path,
    bytes: &[u8],
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<GltfScene, GltfError> {
    let glb_name = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let (json_bytes, bin) = if is_glb(bytes) || glb_name {
        let g = glb::split(bytes)?;
        (g.json, g.bin)
    } else {
        (bytes, None)
    };
    let root = parse_json(json_bytes)?;
    let mut ctx = Ctx {
        root,
        dir: path.parent().unwrap_or(Path::new("")).to_path_buf(),
        read,
        inputs: Vec::new(),
        warnings: Vec::new(),
    };
    check_extensions(&mut ctx)?;
    validate(&ctx.root)?;
    let buffers = Buffers::load(&mut ctx, bin)?;
    let materials = (0..ctx.root.materials.len())
        .map(|i| material::read_material(&ctx.root, i))
        .collect::<Result<Vec<_>, _>>()?;
    let placed = nodes::walk(&mut ctx, &buffers)?;
    Ok(GltfScene {
        primitives: placed.primitives,
        materials,
        cameras: placed.cameras,
        lights: placed.lights,
        warnings: ctx.warnings,
        inputs: ctx.inputs,
        root: ctx.root,
        buffers,
        dir: ctx.dir,
    })
}

/// The JSON as the `gltf` crate's types; a syntax or type error says the
/// JSON path and the line.
fn parse_json(bytes: &[u8]) -> Result<json::Root, GltfError> {
    let mut de = serde_json::Deserializer::from_slice(bytes);
    serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let at = e.path().to_string();
        let inner = e.into_inner();
        if at.is_empty() || at == "." {
            GltfError::Syntax(inner)
        } else {
            GltfError::Json { at, source: inner }
        }
    })
}

/// `extensionsRequired` must name only extensions this loader reads;
/// unknown ones in `extensionsUsed` are worth a warning.
fn check_extensions(ctx: &mut Ctx) -> Result<(), GltfError> {
    for (i, e) in ctx.root.extensions_required.iter().enumerate() {
        if !KNOWN_EXTENSIONS.contains(&e.as_str()) {
            return Err(GltfError::Extension {
                index: i,
                name: e.clone(),
            });
        }
    }
    for e in &ctx.root.extensions_used {
        if !KNOWN_EXTENSIONS.contains(&e.as_str()) {
            ctx.warnings.push(format!(
                "extensionsUsed: {e:?} is not supported and is ignored"
            ));
        }
    }
    Ok(())
}

/// The `gltf` crate's validation (indices in range, required fields,
/// enum values), its first error reported with its JSON path. Its
/// `extensionsRequired` check is ours ([`check_extensions`]).
///
/// Two deviations: POSITION accessors need no `min` / `max` here (the
/// bounds are computed from the data), and POSITION indices are checked
/// before the crate's validation, which indexes with them unchecked.
fn validate(root: &json::Root) -> Result<(), GltfError> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let pos = json::mesh::Semantic::Positions;
            if let Some(a) = prim.attributes.get(&json::validation::Checked::Valid(pos)) {
                if a.value() >= root.accessors.len() {
                    return Err(GltfError::at(
                        &format!("meshes[{m}].primitives[{p}].attributes.POSITION"),
                        format!(
                            "index out of range (accessor {a} of {})",
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    let mut first: Option<GltfError> = None;
    root.validate(root, json::Path::new, &mut |path, err| {
        let p = path().to_string();
        let bounds = p.ends_with("[\"POSITION\"].min") || p.ends_with("[\"POSITION\"].max");
        if first.is_none() && !p.starts_with("extensionsRequired") && !bounds {
            let what = match err {
                json::validation::Error::IndexOutOfBounds => "index out of range",
                json::validation::Error::Invalid => "invalid value",
                json::validation::Error::Missing => "missing",
                json::validation::Error::Oversize => "size too large",
                json::validation::Error::Unsupported => "not supported",
            };
            first = Some(GltfError::Invalid { at: p, what });
        }
    });
    match first {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// A punctual light of the file at a node's world transform (`at` is
/// `extensions.KHR_lights_punctual.lights[i]`).
pub(crate) fn punctual_light(
    at: &str,
    l: &json::extensions::scene::khr_lights_punctual::Light,
    world: &Mat4,
) -> Result<Light, GltfError> {
    use json::extensions::scene::khr_lights_punctual::Type;
    use json::validation::Checked;
    let position = world.transform_point3(Vec3::ZERO);
    let direction = world
        .transform_vector3(Vec3::NEG_Z)
        .try_normalize()
        .ok_or_else(|| GltfError::at(at, "its node's transform has no direction (zero scale)"))?;
    let rgb = l.color.map(|c| c * l.intensity);
    checks::radiometric(&format!("{at}.color × intensity"), rgb)?;
    if !l.color.iter().all(|c| (0.0..=1.0).contains(c)) {
        return Err(GltfError::at(
            &format!("{at}.color"),
            format!("every component must be in [0, 1], got {:?}", l.color),
        ));
    }
    let range = l.range.unwrap_or(f32::INFINITY);
    checks::light_range(&format!("{at}.range"), range)?;
    crate::validate::check_point(&format!("{at} (position)"), position.to_array())?;
    Ok(match l.type_ {
        Checked::Valid(Type::Directional) => Light::Directional {
            to_light: (-direction).to_array(),
            irradiance: rgb,
        },
        Checked::Valid(Type::Point) => Light::Point {
            position: position.to_array(),
            intensity: rgb,
            range,
        },
        Checked::Valid(Type::Spot) => {
            let (inner, outer) = l
                .spot
                .as_ref()
                .map_or((0.0, std::f32::consts::FRAC_PI_4), |s| {
                    (s.inner_cone_angle, s.outer_cone_angle)
                });
            checks::cone_angles(
                (&format!("{at}.spot.innerConeAngle"), inner),
                (&format!("{at}.spot.outerConeAngle"), outer),
                &|r| format!("{r} rad"),
            )?;
            Light::Spot {
                position: position.to_array(),
                direction: direction.to_array(),
                intensity: rgb,
                cos_inner: inner.cos(),
                cos_outer: outer.cos(),
                range,
            }
        }
        Checked::Invalid => return Err(GltfError::at(&format!("{at}.type"), "invalid")),
    })
}
