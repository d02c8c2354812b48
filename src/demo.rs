//! The built-in demo scene: a roughness × metallic sphere grid and the
//! Stanford bunny, compiled into the binary so `specula` with no arguments
//! works from any folder.

use crate::scene::{load_scene_str, LoadedScene, SceneError};
use std::path::Path;

/// fixtures/scenes/demo.toml
pub const DEMO_TOML: &str = include_str!("../fixtures/scenes/demo.toml");
/// fixtures/models/bunny.obj (npm package `bunny`, normalized; see its header).
pub const BUNNY_OBJ: &[u8] = include_bytes!("../fixtures/models/bunny.obj");

/// Loads the demo from the embedded files.
pub fn demo_scene() -> Result<LoadedScene, SceneError> {
    let read = |p: &Path| -> std::io::Result<Vec<u8>> {
        if p == Path::new("../models/bunny.obj") {
            Ok(BUNNY_OBJ.to_vec())
        } else {
            Err(std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "not part of the built-in demo",
            ))
        }
    };
    let mut s = load_scene_str(Path::new("<built-in demo>"), DEMO_TOML, &read)?;
    s.inputs.clear();
    Ok(s)
}
