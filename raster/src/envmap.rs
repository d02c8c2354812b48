//! Environment maps: an equirectangular radiance image lighting the scene
//! and seen behind it, and what image-based lighting derives from it once
//! per map.
//!
//! Directions are the source image's ([`crate::equirect`]); `rotate`
//! turns the map about +Y: a world direction is turned by −rotate before
//! the lookup.
//!
//! Derived data ([`EnvMap::prepare`]):
//! - the source's mip chain (2×2 box), read by the prefiltering;
//! - the prefiltered radiance chain, one level per perceptual roughness
//!   0, 1/5, …, 1 (α = roughness²), each the GGX lobe's weighted mean of
//!   the radiance around the mirror direction with n = v = r \[Karis13\]
//!   (weighted by the lobe's masking G1(l), not by n·l),
//!   importance sampled (512 samples a texel at roughness 1/5 and 2/5,
//!   doubled at each coarser level; level 1 a quarter of level 0's side, then
//!   halving), each sample read from the source mip whose texel matches
//!   the sample's solid angle \[Colbert07\]; stored as octahedral maps
//!   (RGB texels) so a packet reads a footprint's channels at once; a
//!   lobe is read between the two levels around [`level_position`];
//! - a compact, very bright source (a sun) taken out of the map
//!   ([`crate::envmap_sun`]): the prefiltered chain and the SH are made
//!   of the map without it, and it is shaded as a light
//!   ([`EnvMap::sun`]); the background and the reference keep it;
//! - the irradiance in nine spherical harmonics \[Ramamoorthi01\], as
//!   E(n)/π: the radiance a white Lambertian surface reflects;
//! - the luminance distribution for sampling the map in the reference
//!   (`crate::envmap_sample`; the Monte Carlo reference that uses it is
//!   [`crate::envmap_reference`]).

use crate::envmap_sun::Sun;
use crate::equirect::{clamp_texel, dir_to_uv, dir_to_uv_lanes, uv_to_dir, Equirect, MAX_TEXEL};
use specula_core::{f32x8, Constant, Mask, Real, Rgb, V3};

/// How a map lights surfaces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IblMethod {
    /// Prefiltered radiance and SH irradiance with the model's albedo
    /// split ([`specula_core::Brdf::env_lobes`]).
    SplitSum,
    /// Per-pixel Monte Carlo with multiple importance sampling, this many
    /// samples per pixel.
    Reference { samples: u32 },
}

/// Perceptual roughness of the prefiltered levels: level k is at k / 5.
pub const PREFILTER_LEVELS: usize = 6;

/// GGX samples per texel of prefiltered levels 1 and 2; each coarser
/// level doubles them. From level 2 on a level has a quarter of the
/// texels of the one before, so each costs half as much, and the
/// broadest lobes, whose estimates converge slowest, get the most
/// samples. Level 1 takes as many as level 2: its lobe's far tails,
/// which G1 weighs fully, are read from coarse source mips, and half as
/// many samples leave its estimate the chain's largest error
/// (docs/accuracy.md, "Samples a prefiltered texel").
const PREFILTER_SAMPLES: u32 = 512;

/// GGX samples per texel of prefiltered level `k` ≥ 1.
fn level_samples(k: usize) -> u32 {
    PREFILTER_SAMPLES << k.saturating_sub(2)
}

/// Octahedral map of a unit direction (y folds): (x, z) / (|x|+|y|+|z|),
/// the lower half folded over the diagonals, to [0, 1]².
#[inline(always)]
fn oct_encode<R: Real>(d: V3<R>) -> (R, R) {
    let inv = (d.x.abs() + d.y.abs() + d.z.abs())
        .max(R::splat(1e-30))
        .rcp();
    let (px, pz) = (d.x * inv, d.z * inv);
    let below = d.y.lt(R::ZERO);
    let sign = |a: R| R::select(a.ge(R::ZERO), R::ONE, -R::ONE);
    let fx = (R::ONE - pz.abs()) * sign(px);
    let fz = (R::ONE - px.abs()) * sign(pz);
    let (x, z) = (R::select(below, fx, px), R::select(below, fz, pz));
    (x.mul_add(R::HALF, R::HALF), z.mul_add(R::HALF, R::HALF))
}

/// The inverse of [`oct_encode`] at (s, t) ∈ [0, 1]², unit length.
fn oct_decode(s: f64, t: f64) -> [f64; 3] {
    let (x, z) = (2.0 * s - 1.0, 2.0 * t - 1.0);
    let y = 1.0 - x.abs() - z.abs();
    let (x, z) = if y < 0.0 {
        ((1.0 - z.abs()) * x.signum(), (1.0 - x.abs()) * z.signum())
    } else {
        (x, z)
    };
    let l = (x * x + y * y + z * z).sqrt();
    [x / l, y / l, z / l]
}

/// One prefiltered level: a square octahedral map of RGB texels.
#[derive(Clone, Debug)]
struct OctLevel {
    size: usize,
    /// size, size − 1 and the row stride size + 1, as lanes broadcast them.
    side: Constant,
    last: Constant,
    stride: Constant,
    /// The texels, three floats each, in size + 1 rows of size + 1: each
    /// row's last texel repeated after it, the last row repeated below,
    /// and one float more at the end ([`Real::gather_rgb_block`]). A
    /// lookup reads a bilinear footprint, every channel at once, from one
    /// index; at the last column or row the neighbour is the texel
    /// itself, as the clamp to the edge gives.
    texels: Vec<f32>,
}

impl OctLevel {
    /// The level of `size`² texels from its planes (rows of `size`).
    fn new(size: usize, rgb: [Vec<f32>; 3]) -> OctLevel {
        let stride = size + 1;
        let mut texels = Vec::with_capacity(3 * stride * stride + 1);
        for y in 0..size {
            for x in (0..size).chain([size - 1]) {
                let i = y * size + x;
                texels.extend([rgb[0][i], rgb[1][i], rgb[2][i]]);
            }
        }
        texels.extend_from_within(texels.len() - 3 * stride..);
        texels.push(0.0);
        OctLevel {
            size,
            side: Constant::new(size as f64),
            last: Constant::new((size - 1) as f64),
            stride: Constant::new(stride as f64),
            texels,
        }
    }

    /// The planes as [`OctLevel::new`] took them (rows of `size`).
    fn planes(&self) -> [Vec<f32>; 3] {
        core::array::from_fn(|c| {
            self.texels
                .chunks_exact(3 * (self.size + 1))
                .take(self.size)
                .flat_map(|row| row[..3 * self.size].chunks_exact(3))
                .map(|t| t[c])
                .collect()
        })
    }

    /// Bilinear radiance at octahedral (s, t), clamped at the edges.
    #[inline(always)]
    fn bilinear<R: Real>(&self, s: R, t: R) -> Rgb<R> {
        let (n, hi) = (R::constant(self.side), R::constant(self.last));
        let x = (s * n - R::HALF).clamp(R::ZERO, hi);
        let y = (t * n - R::HALF).clamp(R::ZERO, hi);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        // Texels x0 and x0 + 1 of rows y0 and y0 + 1, the padding standing
        // in for x0 + 1 and y0 + 1 at the last column and row.
        let stride = self.size + 1;
        let [[a, b], [c, d]] = R::gather_rgb_block(
            &self.texels,
            y0.mul_add(R::constant(self.stride), x0),
            stride,
        );
        let ch = |k: usize| {
            let top = (b[k] - a[k]).mul_add(fx, a[k]);
            let bot = (d[k] - c[k]).mul_add(fx, c[k]);
            (bot - top).mul_add(fy, top)
        };
        Rgb::new(ch(0), ch(1), ch(2))
    }
}

/// The derived data of a map as plain values (the disk cache's form):
/// the SH coefficients, each prefiltered level's side and planes, and the
/// source taken out of the map, if any.
pub type Derived = ([[f32; 3]; 9], Vec<(usize, [Vec<f32>; 3])>, Option<Sun>);

/// The sun taken out of a map, as a distant light in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunLight {
    /// Unit direction from the scene toward it.
    pub to_light: [f32; 3],
    /// Irradiance on a surface facing it: L · Ω.
    pub(crate) irradiance: [f32; 3],
    /// Its mean radiance L.
    pub(crate) radiance: [f32; 3],
    /// sin² of its angular radius ρ, from Ω = 2π(1 − cos ρ).
    pub sin2_radius: f32,
}

impl SunLight {
    /// The directional light toward the sun's centroid, of its
    /// irradiance: what its shadow maps are fitted to.
    pub fn directional(&self) -> specula_core::light::Light {
        specula_core::light::Light::Directional {
            to_light: self.to_light,
            irradiance: self.irradiance,
        }
    }
}

/// The clamped cosine of a uniform disk of angular radius ρ whose centre
/// is at cos θ from the normal, as a factor of its irradiance when it
/// faces the surface: ∫disk max(0, cos) dω / (π sin²ρ). It is max(0, cos θ)
/// while the disk is wholly above or below the horizon (cos² θ > sin² ρ);
/// across it, with x = √(1/sin²ρ − 1), y = −x cos θ / sin θ \[Lagarde14\]:
/// ((cos θ acos y − x sin θ √(1 − y²)) sin²ρ + atan(sin θ √(1 − y²) / x)) / (π sin²ρ).
#[inline(always)]
pub(crate) fn disk_cos_factor<R: Real>(cos_theta: R, sin2_radius: f32) -> R {
    let s2 = R::splat(sin2_radius as f64);
    let whole = cos_theta.max(R::ZERO);
    let sin_theta = (R::ONE - cos_theta * cos_theta)
        .max(R::ZERO)
        .sqrt()
        .max(R::splat(1e-7));
    let x = (R::splat(1.0 / sin2_radius as f64 - 1.0))
        .max(R::ZERO)
        .sqrt();
    // |y| ≤ 1 where the partial form is selected; clamped for the others.
    let y = (-x * cos_theta / sin_theta).clamp(-R::ONE, R::ONE);
    let root = (R::ONE - y * y).max(R::ZERO).sqrt();
    let sq = sin_theta * root;
    let acos_y = root.atan2(y);
    let partial =
        ((cos_theta * acos_y - x * sq) * s2 + sq.atan2(x)) / (R::splat(std::f64::consts::PI) * s2);
    R::select((cos_theta * cos_theta).gt(s2), whole, partial.max(R::ZERO))
}

/// A loaded environment map and its derived data.
#[derive(Clone, Debug)]
pub struct EnvMap {
    /// The source, times the intensity, texels clamped.
    pub source: Equirect,
    /// cos and sin of the rotation about +Y.
    rot: [f32; 2],
    /// Whether the map is seen where no surface is.
    pub(crate) visible: bool,
    pub method: IblMethod,
    /// E(n)/π in nine SH coefficients per channel (map frame), without
    /// the sun.
    sh: [[f32; 3]; 9],
    /// The prefiltered chain, without the sun.
    levels: Vec<OctLevel>,
    /// The source taken out of the map for the SH and the chain.
    sun: Option<Sun>,
    /// `sun` in the world (rotated, its radius from its solid angle),
    /// made once where `sun` is set, read per packet.
    sun_light: Option<SunLight>,
    /// The luminance distribution for the reference (empty until
    /// prepared, or for an all-black map).
    pub(crate) sampler: crate::envmap_sample::EnvSampler,
}

/// Why [`EnvMap::new`] refused a source image.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum EnvMapError {
    #[error("the map is {width}×{height}: an environment map needs at least 2×2 texels")]
    TooSmall { width: usize, height: usize },
    #[error("texel count does not match the size")]
    TexelCount,
}

impl EnvMap {
    /// The map from `source` (texels as decoded: they are clamped here,
    /// then multiplied by `intensity`); nothing derived yet.
    pub fn new(
        mut source: Equirect,
        intensity: f32,
        rotate_deg: f32,
        visible: bool,
        method: IblMethod,
    ) -> Result<EnvMap, EnvMapError> {
        let (width, height) = (source.width, source.height);
        if width < 2 || height < 2 {
            return Err(EnvMapError::TooSmall { width, height });
        }
        if source.texels.len() != width * height {
            return Err(EnvMapError::TexelCount);
        }
        for t in &mut source.texels {
            *t = t.map(|c| (clamp_texel(c) * intensity).min(MAX_TEXEL));
        }
        let r = rotate_deg.to_radians();
        Ok(EnvMap {
            source,
            rot: [r.cos(), r.sin()],
            visible,
            method,
            sh: [[0.0; 3]; 9],
            levels: Vec::new(),
            sun: None,
            sun_light: None,
            sampler: Default::default(),
        })
    }

    /// A map of one radiance everywhere (tests, furnaces).
    pub fn uniform(radiance: [f32; 3], method: IblMethod) -> EnvMap {
        let source = Equirect {
            width: 64,
            height: 32,
            texels: vec![radiance; 64 * 32],
        };
        let mut m = EnvMap::new(source, 1.0, 0.0, true, method).expect("64×32 map");
        m.prepare(&|_, _| {});
        m
    }

    /// Builds the derived data; `progress(done, total)` is called as the
    /// prefiltered levels are made (rows of work).
    pub fn prepare(&mut self, progress: &(dyn Fn(u64, u64) + Sync)) {
        let (sun, lit) = match crate::envmap_sun::extract_sun(&self.source) {
            Some((sun, lit)) => (Some(sun), lit),
            None => (None, self.source.clone()),
        };
        self.set_sun(sun);
        self.sh = sh9_irradiance(&lit);
        self.levels = prefilter(lit, progress);
        self.sampler = crate::envmap_sample::EnvSampler::new(&self.source);
    }

    /// The prefiltered levels as (size, rgb planes), for the disk cache.
    pub fn derived(&self) -> Derived {
        let levels = self.levels.iter().map(|l| (l.size, l.planes())).collect();
        (self.sh, levels, self.sun)
    }

    /// Installs derived data read back from the cache (as
    /// [`EnvMap::derived`] gave it); false if its shape is wrong.
    pub fn set_derived(&mut self, (sh, levels, sun): Derived) -> bool {
        if levels.len() != PREFILTER_LEVELS
            || levels
                .iter()
                .any(|(n, p)| p.iter().any(|c| c.len() != n * n) || *n == 0)
        {
            return false;
        }
        self.sh = sh;
        self.set_sun(sun);
        self.levels = levels
            .into_iter()
            .map(|(size, rgb)| OctLevel::new(size, rgb))
            .collect();
        self.sampler = crate::envmap_sample::EnvSampler::new(&self.source);
        true
    }

    /// A world direction in the map's frame (turned by −rotate about +Y).
    #[inline(always)]
    pub(crate) fn to_map<R: Real>(&self, d: V3<R>) -> V3<R> {
        let (c, s) = (R::splat(self.rot[0] as f64), R::splat(self.rot[1] as f64));
        V3::new(c.mul_add(d.x, -(s * d.z)), d.y, s.mul_add(d.x, c * d.z))
    }

    /// A map direction in the world.
    #[inline]
    pub(crate) fn to_world(&self, d: [f64; 3]) -> [f64; 3] {
        let (c, s) = (self.rot[0] as f64, self.rot[1] as f64);
        [c * d[0] + s * d[2], d[1], -s * d[0] + c * d[2]]
    }

    /// The source's (u, v) toward world directions `d` (any nonzero
    /// length), per lane: where [`EnvMap::radiance_at`] reads the
    /// background.
    #[inline(always)]
    pub(crate) fn uv_toward<R: Real>(&self, d: V3<R>) -> (R, R) {
        dir_to_uv_lanes(self.to_map(d))
    }

    /// The source's bilinear radiance at (u, v) ∈ [0, 1]².
    #[inline]
    pub(crate) fn radiance_at(&self, u: f32, v: f32) -> [f32; 3] {
        self.source.bilinear(u, v)
    }

    /// The source taken out of the map, if any (map frame).
    pub fn sun(&self) -> Option<&Sun> {
        self.sun.as_ref()
    }

    /// Sets the source taken out of the map and its light in the world.
    fn set_sun(&mut self, sun: Option<Sun>) {
        self.sun = sun;
        self.sun_light = sun.map(|s| {
            let cos_r = 1.0 - s.solid_angle as f64 / std::f64::consts::TAU;
            SunLight {
                to_light: self.to_world(s.direction.map(f64::from)).map(|x| x as f32),
                irradiance: s.irradiance(),
                radiance: s.radiance,
                sin2_radius: (1.0 - cos_r * cos_r) as f32,
            }
        });
    }

    /// The sun as a light in the world, if the map has one.
    #[inline(always)]
    pub fn sun_world(&self) -> Option<SunLight> {
        self.sun_light
    }

    /// E(n)/π at world unit normal `n`: the radiance a white Lambertian
    /// surface reflects, the sun's part (E_sun times the disk's
    /// `disk_cos_factor`, over π) included.
    #[inline(always)]
    pub fn irradiance_over_pi<R: Real>(&self, n: V3<R>) -> Rgb<R> {
        self.irradiance_over_pi_shadowed(n, |_| R::ONE)
    }

    /// [`EnvMap::irradiance_over_pi`] with the sun's part times
    /// `sun_visibility` of that part (its shadow factor).
    #[inline(always)]
    pub(crate) fn irradiance_over_pi_shadowed<R: Real>(
        &self,
        n: V3<R>,
        sun_visibility: impl FnOnce(&Rgb<R>) -> R,
    ) -> Rgb<R> {
        let sky = self.sky_irradiance_over_pi(n);
        match self.sun_world() {
            Some(sun) => {
                let cos = n.dot(V3::from_f32(sun.to_light));
                let k =
                    disk_cos_factor(cos, sun.sin2_radius) * R::splat(std::f64::consts::FRAC_1_PI);
                let e = V3::from_f32(sun.irradiance);
                // k × 1 is k: unshadowed, the same bits as without a factor.
                let k = k * sun_visibility(&(e * k));
                e.mul_elem_add(V3::splat(k), sky)
            }
            None => sky,
        }
    }

    /// [`EnvMap::irradiance_over_pi`] without the sun: the SH alone. SH
    /// ringing below zero is clamped.
    #[inline(always)]
    pub fn sky_irradiance_over_pi<R: Real>(&self, n: V3<R>) -> Rgb<R> {
        let d = self.to_map(n);
        let y = sh9_basis(d);
        // A loop, not a closure per channel: a closure is compiled without
        // the AVX-512 features of the packet pairs' function.
        let mut e = [R::ZERO; 3];
        for (c, e) in e.iter_mut().enumerate() {
            let mut s = R::ZERO;
            for (k, yk) in y.iter().enumerate() {
                s = yk.mul_add(R::splat(self.sh[k][c] as f64), s);
            }
            *e = s.max(R::ZERO);
        }
        Rgb::new(e[0], e[1], e[2])
    }

    /// The prefiltered radiance around world direction `r` (of any
    /// nonzero length) at perceptual `roughness`: a blend of the two
    /// levels around [`level_position`]`(roughness)`.
    #[inline(always)]
    pub fn prefiltered<R: Real>(&self, r: V3<R>, roughness: R) -> Rgb<R> {
        self.read_levels(r, level_position(roughness))
    }

    /// The prefiltered radiance around world direction `r` at level
    /// position `f` (see [`level_position`]), held to 0..=5.
    #[inline(always)]
    pub fn prefiltered_at<R: Real>(&self, r: V3<R>, f: R) -> Rgb<R> {
        let top = (PREFILTER_LEVELS - 1) as f64;
        self.read_levels(r, f.clamp(R::ZERO, R::splat(top)))
    }

    /// [`EnvMap::prefiltered_at`] of an `f` already in 0..=5.
    #[inline(always)]
    fn read_levels<R: Real>(&self, r: V3<R>, f: R) -> Rgb<R> {
        let (s, t) = oct_encode(self.to_map(r));
        // Each lane's two nearest levels weigh 1 − |f − k|; a level is read
        // when some lane weighs it (one or two levels per packet, usually).
        let mut acc = Rgb::zero();
        // k counts in lanes: no integer conversion per level.
        let mut k = R::ZERO;
        for level in &self.levels {
            let wk = (R::ONE - (f - k).abs()).max(R::ZERO);
            if wk.gt(R::ZERO).any() {
                acc = level.bilinear(s, t).mul_add(wk, acc);
            }
            k += R::ONE;
        }
        acc
    }
}

/// Where perceptual `roughness` falls in the prefiltered chain, in
/// levels (0 = the mirror level, 5 = roughness 1): level k + w reads
/// level k with weight 1 − w and level k + 1 with weight w.
///
/// From level 1 up the levels are 1/5 of roughness apart and the position
/// is 5 × roughness. Below level 1 the blend is of the mirror image and a
/// lobe of roughness 1/5, so the position is the mix whose spread matches
/// the lobe's: the blend's resultant length (the mean cosine of its
/// kernel about r) is linear in w, and the w at which it equals the
/// roughness's own kernel's is within 0.01 of x³ (0.7 + 0.3 x), x = 5 ×
/// roughness (`level_position_matches_the_kernels_spread` checks it
/// against quadrature of the kernel; the split sum's error with it:
/// docs/accuracy.md, "Near-mirror lobes").
#[inline(always)]
pub fn level_position<R: Real>(roughness: R) -> R {
    let top = (PREFILTER_LEVELS - 1) as f64;
    let f = (roughness * R::splat(top)).clamp(R::ZERO, R::splat(top));
    let low = f * f * f * f.mul_add(R::splat(0.3), R::splat(0.7));
    R::select(f.lt(R::ONE), low, f)
}

/// The resultant length of a prefiltered level's kernel at GGX `alpha`:
/// its mean cosine about r, the kernel being D(h) G1(l) over l with
/// n = v = r (the prefiltering's weights), integrated over θh by the
/// midpoint rule (dω_l = 4 cos θh dω_h; l is above the horizon for
/// θh < 45°). What [`level_position`] matches; for checks and the
/// accuracy tests, not the renderer.
#[doc(hidden)]
pub fn kernel_resultant(alpha: f64) -> f64 {
    let steps = 200_000;
    let dh = std::f64::consts::FRAC_PI_4 / steps as f64;
    let (mut m0, mut m1) = (0.0, 0.0);
    for i in 0..steps {
        let th = (i as f64 + 0.5) * dh;
        let (sin, c) = th.sin_cos();
        let d = specula_core::ndf::d_ggx(alpha, c * c, sin * sin);
        let nl = (2.0 * th).cos();
        let w = d * g1_normal_view(alpha, nl) * 4.0 * c * sin;
        m0 += w;
        m1 += w * nl;
    }
    m1 / m0
}

/// The prefiltering's weight of a light direction at cosine `nl` from
/// n = v: the masking G1(l) = 1 / (1 + Λ(n·l)) of GGX `alpha`, the lobe
/// f cos θl = D G2 / (4 cos θv) with Λ(v) = 0 over D(h) / 4.
fn g1_normal_view(alpha: f64, nl: f64) -> f64 {
    1.0 / (1.0 + specula_core::masking::lambda_ggx(alpha, nl))
}

/// The nine real SH basis functions at unit `d`.
#[inline(always)]
fn sh9_basis<R: Real>(d: V3<R>) -> [R; 9] {
    let (x, y, z) = (d.x, d.y, d.z);
    let c1 = R::splat(0.488_602_5);
    let c2 = R::splat(1.092_548_4);
    [
        R::splat(0.282_094_8),
        c1 * y,
        c1 * z,
        c1 * x,
        c2 * x * y,
        c2 * y * z,
        R::splat(0.315_391_57) * (R::splat(3.0) * z * z - R::ONE),
        c2 * x * z,
        R::splat(0.546_274_2) * (x * x - y * y),
    ]
}

/// E(n)/π of `map` in SH9: the radiance projected texel by texel (each
/// texel's exact solid angle, the basis at its centre), each band times the clamped cosine's factor
/// Â = π, 2π/3, π/4 \[Ramamoorthi01\], over π.
fn sh9_irradiance(map: &Equirect) -> [[f32; 3]; 9] {
    let mut acc = [[0.0f64; 3]; 9];
    let (w, h) = (map.width, map.height);
    let dphi = std::f64::consts::TAU / w as f64;
    let pi = std::f64::consts::PI;
    for j in 0..h {
        let v = (j as f64 + 0.5) / h as f64;
        // A texel's exact solid angle: Δφ (cos θ₀ − cos θ₁).
        let d_omega =
            dphi * ((j as f64 / h as f64 * pi).cos() - ((j + 1) as f64 / h as f64 * pi).cos());
        for i in 0..w {
            let d = uv_to_dir((i as f64 + 0.5) / w as f64, v);
            let y = sh9_basis(V3::new(d[0], d[1], d[2]));
            let t = map.texels[j * w + i];
            for (k, yk) in y.iter().enumerate() {
                for c in 0..3 {
                    acc[k][c] += t[c] as f64 * yk * d_omega;
                }
            }
        }
    }
    let band = [
        1.0,
        2.0 / 3.0,
        2.0 / 3.0,
        2.0 / 3.0,
        0.25,
        0.25,
        0.25,
        0.25,
        0.25,
    ];
    std::array::from_fn(|k| acc[k].map(|a| (a * band[k]) as f32))
}

/// Side of the sharpest prefiltered level: the source's angular
/// resolution, half its width or its height, whichever is smaller (they
/// agree for a 2:1 map; a map of another shape has no more detail than
/// its coarser axis), as a power of two in 16..=1024.
fn level0_size(width: usize, height: usize) -> usize {
    (width / 2).min(height).next_power_of_two().clamp(16, 1024)
}

/// Side of prefiltered level `k` after a sharpest level of `level0`:
/// level 1 a quarter of it (its lobe, α = 0.04, is still several of its
/// texels wide), then halving, down to 16.
fn level_size(level0: usize, k: usize) -> usize {
    match k {
        0 => level0,
        k => (level0 >> (k + 1)).max(16),
    }
}

/// The prefiltered chain of `map` (module docs).
fn prefilter(map: Equirect, progress: &(dyn Fn(u64, u64) + Sync)) -> Vec<OctLevel> {
    use rayon::prelude::*;
    let mut mips = vec![map];
    while mips.last().is_some_and(|m| m.width > 1 || m.height > 1) {
        let next = mips.last().map(Equirect::half).unwrap_or_default();
        mips.push(next);
    }
    let map = &mips[0];
    let sizes: Vec<usize> = (0..PREFILTER_LEVELS)
        .map(|k| level_size(level0_size(map.width, map.height), k))
        .collect();
    let total: u64 = sizes.iter().map(|&n| n as u64).sum();
    let done = std::sync::atomic::AtomicU64::new(0);
    // Solid angle of a source texel (its mean over the sphere).
    let omega_p = 4.0 * std::f64::consts::PI / (map.width * map.height) as f64;
    sizes
        .iter()
        .enumerate()
        .map(|(k, &n)| {
            let roughness = k as f64 / (PREFILTER_LEVELS - 1) as f64;
            // 1e-3: the models' α floor (ALPHA_MIN).
            let alpha = (roughness * roughness).max(1e-3);
            let top = (mips.len() - 1) as f64;
            let samples = if k > 0 {
                ggx_samples(alpha, level_samples(k), omega_p, top)
            } else {
                Vec::new()
            };
            let rows: Vec<Vec<[f32; 3]>> = (0..n)
                .into_par_iter()
                .map(|j| {
                    let row = (0..n)
                        .map(|i| {
                            let r = oct_decode(
                                (i as f64 + 0.5) / n as f64,
                                (j as f64 + 0.5) / n as f64,
                            );
                            if k == 0 {
                                let (u, v) = dir_to_uv(r.map(|x| x as f32));
                                map.bilinear(u, v)
                            } else {
                                ggx_filtered(&mips, r, &samples)
                            }
                        })
                        .collect();
                    let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    progress(d + 1, total);
                    row
                })
                .collect();
            let mut rgb = [vec![0.0; n * n], vec![0.0; n * n], vec![0.0; n * n]];
            for (j, row) in rows.iter().enumerate() {
                for (i, t) in row.iter().enumerate() {
                    for c in 0..3 {
                        rgb[c][j * n + i] = t[c];
                    }
                }
            }
            OctLevel::new(n, rgb)
        })
        .collect()
}

/// Radical inverse in base 2 (Hammersley's second coordinate).
fn radical_inverse(i: u32) -> f64 {
    i.reverse_bits() as f64 * (1.0 / 4_294_967_296.0)
}

/// One sample of a level's GGX lobe about the local z axis (n = v = z):
/// the light direction l = 2 (v·h) h − v for h drawn from D(h) cos θh,
/// its weight, and the source mip to read it from.
struct LobeSample {
    l: [f64; 3],
    /// [`g1_normal_view`] of l.
    weight: f64,
    lod: f64,
}

/// The `count` samples of the GGX lobe of `alpha` (Hammersley points,
/// the same for every texel of a level) that reach above the surface,
/// each read from the source mip whose texel solid angle matches the
/// sample's Ωs = 1/(N p(l)), p(l) = D(h)/4, where a source texel
/// averages `omega_p` and the coarsest mip is `top`.
fn ggx_samples(alpha: f64, count: u32, omega_p: f64, top: f64) -> Vec<LobeSample> {
    let a2 = alpha * alpha;
    (0..count)
        .filter_map(|i| {
            let (x1, x2) = ((i as f64 + 0.5) / count as f64, radical_inverse(i));
            let cos_h = ((1.0 - x1) / (1.0 + (a2 - 1.0) * x1)).sqrt();
            let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
            let phi = std::f64::consts::TAU * x2;
            let nl = 2.0 * cos_h * cos_h - 1.0;
            if nl <= 0.0 {
                return None;
            }
            let dd = cos_h * cos_h * (a2 - 1.0) + 1.0;
            let d = a2 / (std::f64::consts::PI * dd * dd);
            let omega_s = 1.0 / (count as f64 * d * 0.25);
            Some(LobeSample {
                l: [
                    2.0 * cos_h * (sin_h * phi.cos()),
                    2.0 * cos_h * (sin_h * phi.sin()),
                    nl,
                ],
                weight: g1_normal_view(alpha, nl),
                lod: (0.5 * (omega_s / omega_p).log2() + 1.0).clamp(0.0, top),
            })
        })
        .collect()
}

/// The GGX lobe's mean radiance around unit `r` with n = v = r: the
/// level's `samples` turned to r's frame, each read trilinearly from its
/// mip, weighted by its masking G1(l) (the lobe's own weight with the
/// view along the normal; \[Karis13\] weights by n·l instead, a
/// narrower kernel than the lobe's, which left rough metals' split sum
/// further from the reference: docs/accuracy.md).
fn ggx_filtered(mips: &[Equirect], r: [f64; 3], samples: &[LobeSample]) -> [f32; 3] {
    let n = V3::new(r[0], r[1], r[2]);
    let up = if n.y.abs() < 0.999 {
        V3::new(0.0, 1.0, 0.0)
    } else {
        V3::new(1.0, 0.0, 0.0)
    };
    let t = up.cross(n).normalize();
    let b = n.cross(t);
    let mut sum = [0.0f64; 3];
    let mut wsum = 0.0;
    // Eight samples' map coordinates at a time (two atan2s each, a large
    // part of the prefiltering one by one), then each sample's trilinear
    // read.
    for chunk in samples.chunks(8) {
        let mut d = [[0.0f32; 8]; 3];
        for (i, s) in chunk.iter().enumerate() {
            let l = t * s.l[0] + b * s.l[1] + n * s.l[2];
            (d[0][i], d[1][i], d[2][i]) = (l.x as f32, l.y as f32, l.z as f32);
        }
        let (u, v) = dir_to_uv_lanes(V3::new(
            f32x8::from(d[0]),
            f32x8::from(d[1]),
            f32x8::from(d[2]),
        ));
        let (u, v) = (u.to_array(), v.to_array());
        for (i, s) in chunk.iter().enumerate() {
            let c = trilinear(mips, u[i], v[i], s.lod);
            for k in 0..3 {
                sum[k] += c[k] as f64 * s.weight;
            }
            wsum += s.weight;
        }
    }
    if wsum <= 0.0 {
        return mips[0].nearest(0.5, 0.5);
    }
    sum.map(|s| (s / wsum) as f32)
}

/// Radiance at map coordinates (u, v) between mips ⌊lod⌋ and ⌈lod⌉.
fn trilinear(mips: &[Equirect], u: f32, v: f32, lod: f64) -> [f32; 3] {
    let k0 = lod.floor() as usize;
    let k1 = (k0 + 1).min(mips.len() - 1);
    let w = (lod - k0 as f64) as f32;
    let a = mips[k0].bilinear(u, v);
    let b = mips[k1].bilinear(u, v);
    std::array::from_fn(|c| a[c] + (b[c] - a[c]) * w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn octahedral_round_trip() {
        for &(s, t) in &[(0.1, 0.2), (0.9, 0.3), (0.5, 0.5), (0.05, 0.95), (0.7, 0.8)] {
            let d = oct_decode(s, t);
            let (s2, t2) = oct_encode(V3::new(d[0], d[1], d[2]));
            assert!(
                (s - s2).abs() < 1e-9 && (t - t2).abs() < 1e-9,
                "{s} {t} -> {s2} {t2}"
            );
        }
    }

    /// Below level 1, `level_position` mixes the mirror level and level 1
    /// in the proportion whose kernel has the roughness's own kernel's
    /// resultant length (within 0.01 of a level); from level 1 up it is
    /// linear in roughness, continuous at level 1.
    #[test]
    fn level_position_matches_the_kernels_spread() {
        let alpha = |r: f64| (r * r).max(1e-3);
        let r1 = kernel_resultant(alpha(0.2));
        for i in 0..=40 {
            let r = 0.2 * i as f64 / 40.0;
            let exact = (1.0 - kernel_resultant(alpha(r))) / (1.0 - r1);
            let got = level_position(r);
            assert!(
                (got - exact).abs() < 0.01,
                "roughness {r}: level {got}, matching mix {exact}"
            );
        }
        for i in 0..=40 {
            let r = 0.2 + 0.8 * i as f64 / 40.0;
            assert!((level_position(r) - 5.0 * r).abs() < 1e-12, "roughness {r}");
        }
        assert_eq!(level_position(-1.0), 0.0);
        assert_eq!(level_position(2.0), 5.0);
    }

    #[test]
    fn equirect_round_trip() {
        for &(u, v) in &[(0.1, 0.2), (0.9, 0.3), (0.5, 0.5), (0.3, 0.95)] {
            let d = uv_to_dir(u, v);
            let (u2, v2) = dir_to_uv(d.map(|x| x as f32));
            assert!((u - u2 as f64).abs() < 1e-5 && (v - v2 as f64).abs() < 1e-5);
        }
        // The centre column looks down −Z, the top row up +Y.
        let d = uv_to_dir(0.5, 0.5);
        assert!((d[2] + 1.0).abs() < 1e-12);
        assert!((uv_to_dir(0.3, 0.0)[1] - 1.0).abs() < 1e-12);
    }

    /// Level 0 follows the source's coarser axis: a wide, short map (a
    /// shape the EXR display window allows) gets the chain its eight rows
    /// support, not one sized by its width, and still prefilters a uniform
    /// radiance to itself.
    #[test]
    fn level_zero_follows_the_coarser_axis() {
        let sides = |w: usize, h: usize| {
            let source = Equirect {
                width: w,
                height: h,
                texels: vec![[0.25, 0.5, 1.0]; w * h],
            };
            let mut m = EnvMap::new(source, 1.0, 0.0, true, IblMethod::SplitSum).unwrap();
            m.prepare(&|_, _| {});
            let (_, levels, _) = m.derived();
            for (n, planes) in &levels {
                for (c, want) in [0.25f32, 0.5, 1.0].into_iter().enumerate() {
                    assert!(
                        planes[c].iter().all(|t| (t - want).abs() <= 1e-5 * want),
                        "{w}×{h}, level of side {n}, channel {c}"
                    );
                }
            }
            levels.iter().map(|(n, _)| *n).collect::<Vec<_>>()
        };
        assert_eq!(sides(8976, 8), [16; PREFILTER_LEVELS]);
        assert_eq!(sides(256, 128), [128, 32, 16, 16, 16, 16]);
        assert_eq!(sides(128, 256), [64, 16, 16, 16, 16, 16]);
        assert_eq!(level_size(1024, 1), 256);
        assert_eq!(level_size(1024, 5), 16);
    }

    /// The disk's clamped cosine against midpoint quadrature over the
    /// disk (polar grid about its centre), from wholly above to wholly
    /// below the horizon.
    #[test]
    fn disk_cos_factor_matches_quadrature() {
        let rho = 0.2f64;
        let s2 = rho.sin().powi(2);
        for k in 0..=40 {
            let theta = (90.0 - 15.0 + 30.0 * k as f64 / 40.0).to_radians();
            let c = V3::new(theta.sin(), 0.0, theta.cos());
            let (u, v) = (
                V3::new(theta.cos(), 0.0, -theta.sin()),
                V3::new(0.0, 1.0, 0.0),
            );
            let (nr, np) = (400, 400);
            let mut sum = 0.0;
            for i in 0..nr {
                let a = (i as f64 + 0.5) / nr as f64 * rho;
                for j in 0..np {
                    let p = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
                    let d = c * a.cos() + u * (a.sin() * p.cos()) + v * (a.sin() * p.sin());
                    sum += d.z.max(0.0)
                        * a.sin()
                        * (rho / nr as f64)
                        * (std::f64::consts::TAU / np as f64);
                }
            }
            let want = sum / (std::f64::consts::PI * s2);
            let got = disk_cos_factor(theta.cos(), s2 as f32);
            assert!(
                (got - want).abs() < 2e-3 * (1.0 - rho.cos()).max(want),
                "θ {theta}: {got} vs {want}"
            );
        }
    }

    /// A uniform map: every level and the irradiance give its radiance.
    #[test]
    fn uniform_map_prefilters_to_itself() {
        let m = EnvMap::uniform([0.5, 1.0, 2.0], IblMethod::SplitSum);
        for &r in &[0.0, 0.1, 0.5, 0.77, 1.0] {
            for d in [
                V3::new(0.0, 1.0, 0.0),
                V3::new(0.6, -0.8, 0.0),
                V3::new(0.0, 0.0, -1.0),
            ] {
                let p = m.prefiltered(d, r);
                let e = m.irradiance_over_pi(d);
                for (got, want) in [(p.x, 0.5), (p.y, 1.0), (p.z, 2.0), (e.x, 0.5), (e.z, 2.0)] {
                    assert!((got - want).abs() < 2e-3 * want, "{got} vs {want} at r {r}");
                }
            }
        }
    }
}
