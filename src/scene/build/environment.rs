//! `[environment]`: a uniform radiance or an environment map file, with
//! the map's settings checked, and `[environment.sun]`, the shadow of the
//! sun taken out of the map.

use super::super::desc::{EnvironmentDesc, IblDesc, ShadowsDesc, SunDesc};
use super::BuildError;
use crate::checks;
use specula_raster::envmap::EnvMap;
use specula_raster::shadow::{ShadowFilter, ShadowSettings};
use std::path::Path;

/// What `[environment]` gives: a uniform radiance or a map, with its
/// sun's shadow settings (`None`: unshadowed).
pub(in crate::scene) enum Environment {
    Uniform([f32; 3]),
    Map {
        map: std::sync::Arc<EnvMap>,
        sun_shadows: Option<ShadowSettings>,
    },
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
            if e.sun.is_some() {
                return Err(BuildError::SunWithoutMap);
            }
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
            let sun_shadows = match &e.sun {
                Some(sun) => build_sun_shadows(sun, path, &map)?,
                None => None,
            };
            Ok(Environment::Map {
                map: std::sync::Arc::new(map),
                sun_shadows,
            })
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

/// `[environment.sun]`'s shadow settings for `map` (read from `path`),
/// checked whether or not shadows are on; `None` with shadows "none".
fn build_sun_shadows(
    d: &SunDesc,
    path: &str,
    map: &EnvMap,
) -> Result<Option<ShadowSettings>, BuildError> {
    let filter = match d.shadows {
        ShadowsDesc::None | ShadowsDesc::Hard => ShadowFilter::Hard,
        ShadowsDesc::Pcf => ShadowFilter::Pcf,
        ShadowsDesc::Pcss => ShadowFilter::Pcss,
    };
    let sun = map.sun_world();
    // The sun's own size unless given (any in range where there is none).
    let own_size = sun.map_or(0.0, |s| sun_light_size(s.sin2_radius));
    let s = ShadowSettings {
        filter,
        map_size: d.shadow_map_size,
        bias: d.bias,
        normal_bias: d.normal_bias,
        filter_radius: d.filter_radius,
        light_size: d.light_size.unwrap_or(own_size),
        cascades: d.cascades,
    };
    s.check().map_err(|source| BuildError::Shadows {
        table: "environment.sun".into(),
        source,
    })?;
    if d.shadows == ShadowsDesc::None {
        return Ok(None);
    }
    let Some(sun) = sun else {
        return Err(BuildError::NoSun {
            path: path.to_string(),
        });
    };
    crate::memory::reserve("the sun's shadow maps", s.bytes(&sun.directional()))
        .map_err(BuildError::Memory)?;
    Ok(Some(s))
}

/// A directional light's PCSS `light_size` for a disk of angular radius
/// ρ (given sin² ρ): the tangent of its angular diameter, tan 2ρ.
pub(in crate::scene) fn sun_light_size(sin2_radius: f32) -> f32 {
    let rho = (sin2_radius.clamp(0.0, 1.0) as f64).sqrt().asin();
    (2.0 * rho).tan() as f32
}
