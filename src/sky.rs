//! A generated high-dynamic-range sky (`specula sky`): a smooth sky dome,
//! a dark ground and a sun disk of known angular radius and radiance, so
//! that image-based lighting is tested with a bright, small source whose
//! contribution is known in closed form.
//!
//! - Sky (θ < 90°): L = horizon + (zenith − horizon) cos θ.
//! - Ground (θ > 90°): a constant.
//! - Sun: every texel whose centre direction is within `SUN_RADIUS_DEG` of
//!   the sun direction has radiance `SUN_RADIANCE` (replacing the sky).
//!   The disk's analytic solid angle is 2π(1 − cos r); the texels that
//!   draw it cover [`sun_solid_angle`] (their exact sum), which is what the
//!   map holds.
//!
//! Every radiance is a power of two times a value RGBE stores exactly
//! (8-bit mantissas), so the written `.hdr` file holds these values to
//! the bit.

use specula_raster::equirect::{uv_to_dir, Equirect};

/// Angular radius of the sun disk.
pub const SUN_RADIUS_DEG: f64 = 2.0;
/// The sun's radiance (W/m²/sr per channel).
pub const SUN_RADIANCE: [f32; 3] = [16384.0, 14336.0, 12288.0];
/// Elevation above the horizon and azimuth (from −Z toward +X) of the sun.
pub const SUN_ELEVATION_DEG: f64 = 35.0;
pub(crate) const SUN_AZIMUTH_DEG: f64 = 40.0;
const ZENITH: [f32; 3] = [0.25, 0.5, 1.0];
const HORIZON: [f32; 3] = [1.0, 1.0, 1.0];
const GROUND: [f32; 3] = [0.125, 0.125, 0.125];

/// The unit direction toward the sun (map frame: +Y up, −Z at the centre).
pub fn sun_direction() -> [f64; 3] {
    let (e, a) = (SUN_ELEVATION_DEG.to_radians(), SUN_AZIMUTH_DEG.to_radians());
    [e.cos() * a.sin(), e.sin(), -e.cos() * a.cos()]
}

/// Whether texel (i, j) of a `w`×`h` map is the sun's.
fn is_sun(i: usize, j: usize, w: usize, h: usize) -> bool {
    let d = uv_to_dir((i as f64 + 0.5) / w as f64, (j as f64 + 0.5) / h as f64);
    let s = sun_direction();
    d[0] * s[0] + d[1] * s[1] + d[2] * s[2] >= SUN_RADIUS_DEG.to_radians().cos()
}

/// The sky as a `w`×`h` equirectangular map.
pub fn sky(w: usize, h: usize) -> Equirect {
    let mut texels = Vec::with_capacity(w * h);
    for j in 0..h {
        for i in 0..w {
            let d = uv_to_dir((i as f64 + 0.5) / w as f64, (j as f64 + 0.5) / h as f64);
            let t = if is_sun(i, j, w, h) {
                SUN_RADIANCE
            } else if d[1] > 0.0 {
                let c = d[1] as f32;
                std::array::from_fn(|k| HORIZON[k] + (ZENITH[k] - HORIZON[k]) * c)
            } else {
                GROUND
            };
            texels.push(t);
        }
    }
    Equirect {
        width: w,
        height: h,
        texels,
    }
}

/// The solid angle the sun's texels cover in a `w`×`h` map: Σ over them
/// of Δφ (cos θ₀ − cos θ₁).
pub fn sun_solid_angle(w: usize, h: usize) -> f64 {
    let dphi = std::f64::consts::TAU / w as f64;
    let mut sum = 0.0;
    for j in 0..h {
        let (t0, t1) = (
            j as f64 / h as f64 * std::f64::consts::PI,
            (j + 1) as f64 / h as f64 * std::f64::consts::PI,
        );
        let band = dphi * (t0.cos() - t1.cos());
        sum += band * (0..w).filter(|&i| is_sun(i, j, w, h)).count() as f64;
    }
    sum
}

/// Why `specula sky` wrote nothing.
#[derive(Debug, thiserror::Error)]
pub enum SkyError {
    /// A width the map cannot have.
    #[error("--width must be even, in 4..=16384, got {0}")]
    Width(usize),
    /// The Radiance encoder refused the texels.
    #[error("{}: {source}", .path.display())]
    Encode {
        path: std::path::PathBuf,
        source: image::ImageError,
    },
    /// The output cannot be written (`--output` at fault).
    #[error(transparent)]
    Output(#[from] crate::output_plan::OutputError),
}

/// `specula sky`: writes the sky, `width` × `width / 2` texels, as a
/// Radiance `.hdr` file to `path` (through the output plan: a file is
/// replaced whole or not at all).
pub fn write_sky(path: &std::path::Path, width: usize) -> Result<(), SkyError> {
    if !(4..=16384).contains(&width) || !width.is_multiple_of(2) {
        return Err(SkyError::Width(width));
    }
    crate::output_plan::check_early("--output", path)?;
    let (w, h) = (width, width / 2);
    let map = sky(w, h);
    let px: Vec<image::Rgb<f32>> = map.texels.iter().map(|t| image::Rgb(*t)).collect();
    let mut bytes = Vec::new();
    image::codecs::hdr::HdrEncoder::new(&mut bytes)
        .encode(&px, w, h)
        .map_err(|source| SkyError::Encode {
            path: path.to_path_buf(),
            source,
        })?;
    crate::output_plan::Output::new("--output", path)?.write(&bytes)?;
    Ok(())
}
