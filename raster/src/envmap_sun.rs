//! A compact, very bright source (a sun) taken out of an environment map,
//! so that the split sum lights the rest and the source is shaded as a
//! light through each model's own BRDF.
//!
//! Nine SH coefficients cannot hold a source a few degrees wide: its
//! irradiance rings by a few percent of the source's on normals facing
//! away from it, which under a sun is many times the sky's own
//! irradiance; the prefiltered chain smears it the same way. Engines
//! take such a source out as an analytic light.
//!
//! The rule ([`extract_sun`]), on the luminance Y of the texels, each
//! weighted by its exact solid angle Δφ (cos θ₀ − cos θ₁):
//!
//! 1. the map's typical level m is the solid-angle-weighted median of Y
//!    (a histogram of quarter stops);
//! 2. the source is the 8-connected region (wrapping in u) around the
//!    brightest texel of texels with Y > T, T = max(`MEDIAN_RATIO` · m,
//!    peak / `PEAK_RATIO`);
//! 3. it is taken out only if it is compact (its solid angle at most
//!    `MAX_SOLID_ANGLE`) and worth it (its luminance above the
//!    surrounding sky level carries at least `MIN_SHARE` of the map's
//!    ∫ Y dω);
//! 4. the surrounding sky level is the solid-angle-weighted mean radiance
//!    of the texels touching the region; the region's texels are replaced
//!    by it in the map the SH and the prefiltered chain are made of, and
//!    what they held above it becomes the [`Sun`]: its solid angle (the
//!    sum of the texels'), its mean radiance over it, its direction (the
//!    centroid of the texels' directions weighted by that luminance). The
//!    map and the sun add up to the original; the visible background and
//!    the Monte Carlo reference keep the original.

use crate::equirect::{luminance, uv_to_dir, Equirect};

/// T is at least this many times the median luminance.
pub(crate) const MEDIAN_RATIO: f32 = 64.0;
/// T is at least the peak luminance over this.
pub(crate) const PEAK_RATIO: f32 = 64.0;
/// Largest solid angle of a source (sr): a disk of about 7° radius.
pub(crate) const MAX_SOLID_ANGLE: f64 = 0.05;
/// Smallest share of the map's ∫ Y dω a source must carry.
pub(crate) const MIN_SHARE: f64 = 0.1;

/// A source taken out of a map (map frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    /// Unit direction toward its radiance-weighted centroid.
    pub direction: [f32; 3],
    /// The solid angle of its texels (sr).
    pub solid_angle: f32,
    /// Its mean radiance above the surrounding sky level.
    pub radiance: [f32; 3],
}

impl Sun {
    /// Irradiance on a surface facing it: L · Ω.
    pub fn irradiance(&self) -> [f32; 3] {
        self.radiance.map(|l| l * self.solid_angle)
    }

    /// The sun as 7 values (direction, solid angle, radiance), for the
    /// disk cache.
    pub fn to_values(&self) -> [f32; 7] {
        let (d, l) = (self.direction, self.radiance);
        [d[0], d[1], d[2], self.solid_angle, l[0], l[1], l[2]]
    }

    /// The inverse of [`Sun::to_values`]; `None` for values no sun has
    /// (not finite, negative, or a direction not of unit length).
    pub fn from_values(v: &[f32]) -> Option<Sun> {
        let [dx, dy, dz, omega, r, g, b] = <[f32; 7]>::try_from(v).ok()?;
        let len2 = dx * dx + dy * dy + dz * dz;
        let ok = v.iter().all(|x| x.is_finite())
            && (len2 - 1.0).abs() < 1e-4
            && omega > 0.0
            && [r, g, b].iter().all(|&c| c >= 0.0);
        ok.then_some(Sun {
            direction: [dx, dy, dz],
            solid_angle: omega,
            radiance: [r, g, b],
        })
    }
}

/// The solid angle of a texel of row `j` in a `w`×`h` map.
fn texel_solid_angle(j: usize, w: usize, h: usize) -> f64 {
    let pi = std::f64::consts::PI;
    let dphi = std::f64::consts::TAU / w as f64;
    dphi * ((j as f64 / h as f64 * pi).cos() - ((j + 1) as f64 / h as f64 * pi).cos())
}

/// The solid-angle-weighted median of `y` (per texel, row-major), to a
/// quarter stop.
fn weighted_median(y: &[f32], w: usize, h: usize) -> f32 {
    // Bins of a quarter stop over 2^-40 .. 2^40; below and above clamp.
    const BINS: usize = 320;
    let mut hist = [0.0f64; BINS];
    let mut total = 0.0;
    for j in 0..h {
        let d_omega = texel_solid_angle(j, w, h);
        for &x in &y[j * w..(j + 1) * w] {
            let b = if x > 0.0 {
                ((x.log2() + 40.0) * 4.0).clamp(0.0, (BINS - 1) as f32) as usize
            } else {
                0
            };
            hist[b] += d_omega;
            total += d_omega;
        }
    }
    let mut acc = 0.0;
    for (b, &v) in hist.iter().enumerate() {
        acc += v;
        if acc >= 0.5 * total {
            return ((b as f32 + 0.5) / 4.0 - 40.0).exp2();
        }
    }
    0.0
}

/// The 8 neighbours of texel (i, j): wrapped in i, rows outside the map
/// left out.
fn neighbours(i: usize, j: usize, w: usize, h: usize) -> impl Iterator<Item = (usize, usize)> {
    (-1isize..=1)
        .flat_map(|dj| (-1isize..=1).map(move |di| (di, dj)))
        .filter(|&d| d != (0, 0))
        .filter_map(move |(di, dj)| {
            let jj = j as isize + dj;
            (0..h as isize).contains(&jj).then(|| {
                let ii = (i as isize + di).rem_euclid(w as isize) as usize;
                (ii, jj as usize)
            })
        })
}

/// The source of `map` by the module's rule, and the map with its texels
/// replaced by the surrounding sky level; `None` when the map has none.
pub fn extract_sun(map: &Equirect) -> Option<(Sun, Equirect)> {
    let (w, h) = (map.width, map.height);
    let y: Vec<f32> = map.texels.iter().map(|&t| luminance(t)).collect();
    let (peak_at, peak) =
        y.iter()
            .copied()
            .enumerate()
            .fold((0, 0.0f32), |a, b| if b.1 > a.1 { b } else { a });
    let median = weighted_median(&y, w, h);
    let threshold = (MEDIAN_RATIO * median).max(peak / PEAK_RATIO);
    // Texels are never NaN (clamped where the map is made).
    if peak <= threshold {
        return None;
    }
    // The region: a flood fill from the peak, stopped once too large.
    let mut inside = vec![false; w * h];
    let mut region = vec![peak_at];
    inside[peak_at] = true;
    let mut solid_angle = 0.0;
    let mut next = 0;
    while next < region.len() {
        let k = region[next];
        next += 1;
        let (i, j) = (k % w, k / w);
        solid_angle += texel_solid_angle(j, w, h);
        if solid_angle > MAX_SOLID_ANGLE {
            return None;
        }
        for (ii, jj) in neighbours(i, j, w, h) {
            let n = jj * w + ii;
            if !inside[n] && y[n] > threshold {
                inside[n] = true;
                region.push(n);
            }
        }
    }
    // The surrounding sky level: the texels touching the region.
    let (mut ring, mut ring_omega) = ([0.0f64; 3], 0.0);
    let mut seen = vec![false; w * h];
    for &k in &region {
        for (ii, jj) in neighbours(k % w, k / w, w, h) {
            let n = jj * w + ii;
            if !inside[n] && !seen[n] {
                seen[n] = true;
                let d_omega = texel_solid_angle(jj, w, h);
                for (r, t) in ring.iter_mut().zip(map.texels[n]) {
                    *r += t as f64 * d_omega;
                }
                ring_omega += d_omega;
            }
        }
    }
    if ring_omega <= 0.0 {
        return None;
    }
    let fill = ring.map(|s| (s / ring_omega) as f32);
    // What the region holds above the fill, and its centroid.
    let (mut energy, mut centroid, mut sun_y) = ([0.0f64; 3], [0.0f64; 3], 0.0);
    for &k in &region {
        let (i, j) = (k % w, k / w);
        let d_omega = texel_solid_angle(j, w, h);
        let above: [f32; 3] = std::array::from_fn(|c| (map.texels[k][c] - fill[c]).max(0.0));
        for (e, a) in energy.iter_mut().zip(above) {
            *e += a as f64 * d_omega;
        }
        let wy = luminance(above) as f64 * d_omega;
        let d = uv_to_dir((i as f64 + 0.5) / w as f64, (j as f64 + 0.5) / h as f64);
        for (m, x) in centroid.iter_mut().zip(d) {
            *m += wy * x;
        }
        sun_y += wy;
    }
    let total_y: f64 = (0..h)
        .map(|j| {
            let d_omega = texel_solid_angle(j, w, h);
            y[j * w..(j + 1) * w].iter().map(|&x| x as f64).sum::<f64>() * d_omega
        })
        .sum();
    if sun_y < MIN_SHARE * total_y {
        return None;
    }
    let len = centroid.iter().map(|c| c * c).sum::<f64>().sqrt();
    if len <= 0.0 {
        return None;
    }
    let sun = Sun {
        direction: centroid.map(|c| (c / len) as f32),
        solid_angle: solid_angle as f32,
        radiance: energy.map(|e| (e / solid_angle) as f32),
    };
    let mut lit = map.clone();
    for &k in &region {
        lit.texels[k] = fill;
    }
    Some((sun, lit))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map_with(w: usize, h: usize, f: impl Fn(usize, usize) -> [f32; 3]) -> Equirect {
        Equirect {
            width: w,
            height: h,
            texels: (0..h)
                .flat_map(|j| (0..w).map(move |i| (i, j)))
                .map(|(i, j)| f(i, j))
                .collect(),
        }
    }

    /// A uniform map and a map of smooth gradients have no source.
    #[test]
    fn no_source_in_smooth_maps() {
        assert!(extract_sun(&map_with(64, 32, |_, _| [1.0; 3])).is_none());
        let grad = map_with(64, 32, |i, j| [(i + j) as f32 * 0.1 + 0.1; 3]);
        assert!(extract_sun(&grad).is_none());
    }

    /// A 2×2 block of texels at 1000 over a sky of 1: taken out, its
    /// solid angle the block's, its radiance 1000 − 1, the map filled
    /// with 1 (so the map and the sun add up to the original).
    #[test]
    fn a_block_is_taken_out_exactly() {
        let (w, h) = (64, 32);
        let hot = |i: usize, j: usize| (30..32).contains(&i) && (10..12).contains(&j);
        let map = map_with(w, h, |i, j| if hot(i, j) { [1000.0; 3] } else { [1.0; 3] });
        let (sun, lit) = extract_sun(&map).expect("a source");
        let omega = 2.0 * (texel_solid_angle(10, w, h) + texel_solid_angle(11, w, h));
        assert!((sun.solid_angle as f64 - omega).abs() < 1e-6 * omega);
        assert!(sun.radiance.iter().all(|&l| (l - 999.0).abs() < 1e-2));
        assert!(lit.texels.iter().all(|&t| t == [1.0; 3]));
        // The centroid: between the block's columns and rows (u = 0.5 − ...
        // its middle is the corner shared by the four texels).
        let d = uv_to_dir(31.0 / 64.0, 11.0 / 32.0);
        let cos = (0..3).map(|c| d[c] * sun.direction[c] as f64).sum::<f64>();
        assert!(
            cos > (0.2f64).to_radians().cos(),
            "{:?} vs {d:?}",
            sun.direction
        );
        assert_eq!(Sun::from_values(&sun.to_values()), Some(sun));
    }

    /// A bright region too large to be a sun is left in the map.
    #[test]
    fn a_large_bright_region_is_left() {
        let map = map_with(64, 32, |_, j| if j < 8 { [1000.0; 3] } else { [1.0; 3] });
        assert!(extract_sun(&map).is_none());
    }
}
