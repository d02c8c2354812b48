//! `[environment]`: a uniform radiance or an environment map file, with
//! the map's settings checked.

use super::super::desc::{EnvironmentDesc, IblDesc};
use super::BuildError;
use crate::checks;
use std::path::Path;

/// What `[environment]` gives: a uniform radiance or a map.
pub(in crate::scene) enum Environment {
    Uniform([f32; 3]),
    Map(std::sync::Arc<specula_raster::envmap::EnvMap>),
}

/// `[environment]`: exactly one of `uniform` and `map`, the map's fields
/// checked and its file read through `read`.
pub(in crate::scene) fn build_environment(
    e: &EnvironmentDesc,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<Environment, BuildError> {
    match (&e.uniform, &e.map) {
        (Some(u), None) => {
            checks::radiometric("environment.uniform", *u)?;
            Ok(Environment::Uniform(*u))
        }
        (None, Some(path)) => {
            let settings = env_settings(e)?;
            let bytes = read(Path::new(path)).map_err(|source| BuildError::Read {
                field: "environment.map".into(),
                path: path.clone(),
                source,
            })?;
            let map =
                crate::envmap_file::load_env_map(path, &bytes, &settings).map_err(|source| {
                    BuildError::EnvMap {
                        field: "environment.map",
                        source,
                    }
                })?;
            Ok(Environment::Map(std::sync::Arc::new(map)))
        }
        (Some(_), Some(_)) => Err(BuildError::EnvironmentBoth),
        (None, None) => Err(BuildError::EnvironmentNeither),
    }
}

/// The map settings of `[environment]`, checked.
fn env_settings(e: &EnvironmentDesc) -> Result<crate::envmap_file::EnvSettings, BuildError> {
    use specula_raster::envmap::IblMethod;
    if !(e.intensity.is_finite() && e.intensity >= 0.0) {
        return Err(BuildError::EnvironmentIntensity(e.intensity));
    }
    if !e.rotate.is_finite() {
        return Err(BuildError::EnvironmentRotate(e.rotate));
    }
    if !(1..=1 << 20).contains(&e.ibl_samples) {
        return Err(BuildError::IblSamples(e.ibl_samples));
    }
    Ok(crate::envmap_file::EnvSettings {
        intensity: e.intensity,
        rotate_deg: e.rotate,
        visible: e.visible,
        method: match e.ibl {
            IblDesc::SplitSum => IblMethod::SplitSum,
            IblDesc::Reference => IblMethod::Reference {
                samples: e.ibl_samples,
            },
        },
    })
}
