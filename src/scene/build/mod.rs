//! Each table of a parsed scene checked and turned into the renderer's
//! values, one file per concern: `[camera]` (`camera.rs`), `[output]`
//! (`output.rs`), `[environment]` (`environment.rs`), `[materials]` and
//! MTL materials (`materials.rs`), `[[mesh]]` (`meshes.rs`, with the
//! procedural shapes in `shapes.rs` and `translate`/`rotate`/`scale` in
//! `placement.rs`), `[[light]]` (`lights.rs`, their shadow fields in
//! `shadows.rs`), and `[posterize]` and `[[outline]]` (`post.rs`). What
//! the tables add up to while they are read in order is the
//! [`SceneBuilder`] here.

mod camera;
mod environment;
mod error;
mod lights;
mod materials;
mod meshes;
mod output;
mod placement;
mod post;
mod shadows;
mod shapes;

pub(super) use camera::build_camera;
pub(super) use environment::{build_environment, sun_light_size, Environment};
pub(super) use error::BuildError;
use materials::Materials;
pub(super) use output::check_output;
pub(super) use placement::place_mesh;
pub(super) use post::{build_posterize, check_outlines};

use specula_core::light::Light;
use specula_core::Model;
use specula_raster::{Camera, SceneParts};
use specula_raster::{Lit, Material};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

/// What the tables add up to while they are read in order.
pub(super) struct SceneBuilder<'a> {
    pub(super) path: &'a Path,
    pub(super) read: &'a dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    /// The folder `read` reads files from, when they are files on disk.
    pub(super) dir: Option<&'a Path>,
    pub(super) data: SceneParts,
    pub(super) materials: Materials,
    /// Whether some mesh brought texture coordinates.
    pub(super) any_uvs: bool,
    pub(super) inputs: Vec<PathBuf>,
    pub(super) warnings: Vec<String>,
    /// Tangents meshes brought or were given (tangents.rs), by their
    /// first vertex in `data`.
    pub(super) given_tangents: Vec<(usize, Vec<glam::Vec4>)>,
}

impl<'a> SceneBuilder<'a> {
    pub(super) fn new(
        path: &'a Path,
        read: &'a dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
        camera: Camera,
        background: [f32; 3],
    ) -> Self {
        SceneBuilder {
            path,
            read,
            dir: None,
            data: SceneParts::empty(camera, background),
            materials: Materials {
                list: Vec::new(),
                by_name: HashMap::new(),
                textured: HashSet::new(),
                normal_mapped: HashSet::new(),
                default_id: None,
            },
            any_uvs: false,
            inputs: vec![path.to_path_buf()],
            warnings: Vec::new(),
            given_tangents: Vec::new(),
        }
    }

    /// Tables built once per process on first use: made here, so that
    /// their cost (the split-sum tables above all) counts as
    /// loading and not as the first frame's shading pass.
    pub(super) fn warm_tables(&self) {
        let polygon_lights = self
            .data
            .lights
            .iter()
            .any(|l| matches!(l, Light::Polygon { .. }));
        if polygon_lights {
            specula_core::ltc::ggx::lookup();
        }
        if (polygon_lights || self.data.environment.is_some() || self.data.env_map.is_some())
            && self.materials.list.iter().any(is_split_sum_model)
        {
            specula_core::albedo_tables::AlbedoTables::get();
        }
        if self.materials.list.iter().any(has_sheen) {
            specula_core::sheen::SheenTable::get();
        }
    }
}

/// Whether a material is `metallic_roughness` or `gltf`, whose
/// polygon-light and environment terms read the process-wide split-sum
/// tables.
fn is_split_sum_model(m: &Material) -> bool {
    m.shader
        .as_any()
        .downcast_ref::<Lit>()
        .is_some_and(|l| matches!(l.model(), Model::MetallicRoughness(_) | Model::Gltf(_)))
}

/// Whether a material is `gltf` with sheen, whose every light reads the
/// sheen albedo table.
fn has_sheen(m: &Material) -> bool {
    m.shader
        .as_any()
        .downcast_ref::<Lit>()
        .is_some_and(|l| matches!(l.model(), Model::Gltf(g) if g.has_sheen()))
}
