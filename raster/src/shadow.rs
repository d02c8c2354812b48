//! Shadow maps: per shadowed light, depth-only passes of the scene through
//! the light's view (the same setup, binning and scan as the camera's
//! passes, `frame::depth_pass`), and the per-lane lookups the light loop
//! multiplies a light's contribution by.
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

use crate::camera::{Camera, View};
use crate::frame::{depth_pass, FrameStats, Visibility};
use crate::scene::SceneData;
use crate::target::Target;
use glam::{Mat4, Vec3, Vec4};
use rayon::prelude::*;
use specula_core::light::Light;
use specula_core::{Real, V3};

/// How a light's shadow is filtered.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShadowFilter {
    /// One depth comparison at the nearest texel.
    #[default]
    Hard,
    /// Percentage-closer filtering: the mean of bilinear depth comparisons
    /// over a square of `filter_radius` texels.
    Pcf,
    /// Percentage-closer soft shadows: a blocker search, the penumbra
    /// width from the light's size, then PCF over that width.
    Pcss,
}

/// One light's shadow settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowSettings {
    pub filter: ShadowFilter,
    /// Map side in texels (each cube face's for point lights).
    pub map_size: u32,
    /// Depth offset toward the light, in texels at the shaded point.
    pub bias: f32,
    /// Offset of the shaded point along its normal, in texels at the
    /// point (times 1 + the filter radius).
    pub normal_bias: f32,
    /// PCF half-width in texels.
    pub filter_radius: f32,
    /// PCSS: the light's diameter in world units (directional lights: the
    /// tangent of its angular diameter).
    pub light_size: f32,
    /// Directional lights: maps along the view's depth (1..=4), each
    /// `map_size` a side ([`cascade_splits`]); 1 for other lights.
    pub cascades: u32,
}

/// Largest number of cascades of a directional light.
pub const MAX_CASCADES: u32 = 4;

/// The practical split scheme's blend between logarithmic (1) and uniform
/// (0) split depths.
pub const CASCADE_LAMBDA: f32 = 0.75;

/// Largest accepted map side.
pub const MAX_MAP_SIZE: u32 = 8192;

impl Default for ShadowSettings {
    fn default() -> Self {
        ShadowSettings {
            filter: ShadowFilter::Hard,
            map_size: 1024,
            bias: 1.0,
            normal_bias: 1.0,
            filter_radius: 1.5,
            light_size: 0.1,
            cascades: 1,
        }
    }
}

impl ShadowSettings {
    /// Checks every field; the error names the field.
    pub fn check(&self) -> Result<(), String> {
        if !(1..=MAX_MAP_SIZE).contains(&self.map_size) {
            return Err(format!(
                "shadow_map_size: must be 1..={MAX_MAP_SIZE} texels, got {}",
                self.map_size
            ));
        }
        if !(1..=MAX_CASCADES).contains(&self.cascades) {
            return Err(format!(
                "cascades: must be 1..={MAX_CASCADES}, got {}",
                self.cascades
            ));
        }
        let fields = [
            ("bias", self.bias, 1e3),
            ("normal_bias", self.normal_bias, 1e3),
            ("filter_radius", self.filter_radius, 64.0),
            ("light_size", self.light_size, 1e9),
        ];
        for (name, v, max) in fields {
            if !(0.0..=max).contains(&v) {
                return Err(format!(
                    "{name}: must be a finite number in [0, {max}], got {v}"
                ));
            }
        }
        Ok(())
    }

    /// Faces of a light's map: 6 for a point light, 1 otherwise.
    pub fn faces(&self, light: &Light) -> u32 {
        match light {
            Light::Point { .. } | Light::Polygon { .. } => 6,
            Light::Directional { .. } => self.cascades,
            _ => 1,
        }
    }

    /// Bytes of a light's maps (a frame's depth and id per texel, and the
    /// linear depth kept for lookups).
    pub fn bytes(&self, light: &Light) -> u64 {
        let side = (self.map_size as u64).div_ceil(64) * 64;
        side * side * 12 * self.faces(light) as u64
    }

    /// Texels a lookup may read away from its centre texel.
    fn reach(&self) -> f32 {
        match self.filter {
            ShadowFilter::Hard => 1.0,
            ShadowFilter::Pcf => self.filter_radius + 2.0,
            ShadowFilter::Pcss => self.filter_radius.max(PCSS_MAX_RADIUS) + 2.0,
        }
    }
}

/// Largest PCSS filter half-width in texels.
const PCSS_MAX_RADIUS: f32 = 24.0;

/// One shadow map: a light's view and the depth it saw.
#[derive(Clone, Debug, Default)]
struct Face {
    /// World → the light's clip space.
    clip: Mat4,
    size: u32,
    /// Row-major linear depth (along `axis` from `origin`); infinity where
    /// nothing was drawn.
    depth: Vec<f32>,
    origin: Vec3,
    axis: Vec3,
    /// World size of a texel (perspective maps: at unit depth).
    texel: f32,
    perspective: bool,
    /// Perspective maps: the near distance (NDC depth = near / depth).
    /// Orthographic: NDC depth = 1 − (depth − near) / span.
    near: f32,
    span: f32,
}

/// A shadowed light's maps for one frame.
#[derive(Default)]
pub struct LightShadow {
    pub settings: ShadowSettings,
    faces: Vec<Face>,
    /// How a point picks its face.
    pick: Pick,
    /// The frames' working buffers of each face's depth pass.
    passes: Vec<Option<Visibility>>,
}

/// How a shaded point picks one of a light's faces.
#[derive(Clone, Debug, Default)]
enum Pick {
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
    lights: Vec<Option<LightShadow>>,
    any: bool,
}

impl std::fmt::Debug for ShadowMaps {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShadowMaps")
            .field("passes", &self.passes())
            .finish()
    }
}

impl ShadowMaps {
    /// The maps when some light has shadows.
    pub fn active(&self) -> Option<&ShadowMaps> {
        self.any.then_some(self)
    }

    /// Light `k`'s maps, if it has shadows.
    pub fn light(&self, k: usize) -> Option<&LightShadow> {
        self.lights.get(k).and_then(Option::as_ref)
    }

    /// Depth passes rendered this frame.
    pub fn passes(&self) -> u32 {
        self.lights
            .iter()
            .flatten()
            .map(|l| l.faces.len() as u32)
            .sum()
    }

    /// Renders every shadowed light's maps of `scene` for the camera's
    /// `view`; `stats.times.shadow` gets their time.
    pub fn render(&mut self, scene: &SceneData, view: &View, stats: &mut FrameStats) {
        self.lights.resize_with(scene.lights.len(), || None);
        self.any = false;
        let Some(bounds) = Bounds::of(scene) else {
            self.lights.iter_mut().for_each(|l| *l = None);
            return;
        };
        for (k, light) in scene.lights.iter().enumerate() {
            let Some(settings) = scene.shadows.get(k).copied().flatten() else {
                self.lights[k] = None;
                continue;
            };
            let Some((faces, pick)) =
                light_faces(&settings, light, &bounds, view, scene.camera.near)
            else {
                self.lights[k] = None;
                continue;
            };
            let ls = self.lights[k].get_or_insert_with(LightShadow::default);
            ls.settings = settings;
            ls.pick = pick;
            // The previous frame's depth buffers are refilled, not reallocated.
            let mut faces = faces;
            for (new, old) in faces.iter_mut().zip(ls.faces.drain(..)) {
                new.depth = old.depth;
            }
            ls.faces = faces;
            ls.passes.resize_with(ls.faces.len(), || None);
            for (face, pass) in ls.faces.iter_mut().zip(&mut ls.passes) {
                render_face(scene, face, pass, stats);
            }
            self.any = true;
        }
    }
}

/// The maps of `light` and how a point picks one, or `None` for a light
/// without shadow maps. `near` is the camera's near distance.
fn light_faces(
    settings: &ShadowSettings,
    light: &Light,
    bounds: &Bounds,
    view: &View,
    near: f32,
) -> Option<(Vec<Face>, Pick)> {
    Some(match light {
        Light::Directional { to_light, .. } => {
            let to_light = Vec3::from(*to_light);
            // The view frustum out to the farthest scene corner.
            let far = bounds
                .corners()
                .iter()
                .map(|c| (*c - view.eye).dot(view.forward))
                .fold(0.0f32, f32::max);
            let first = far * 1e-4;
            if settings.cascades <= 1 || far <= 0.0 {
                let face = directional_face(settings, to_light, bounds, view, (first, far));
                return Some((vec![face], Pick::One));
            }
            let splits = cascade_splits(settings.cascades, near.max(first), far);
            let faces = (0..splits.len() + 1)
                .map(|i| {
                    let d0 = if i == 0 { first } else { splits[i - 1] };
                    let d1 = splits.get(i).copied().unwrap_or(far);
                    directional_face(settings, to_light, bounds, view, (d0, d1))
                })
                .collect();
            let pick = Pick::Cascades {
                eye: view.eye,
                forward: view.forward,
                splits,
            };
            (faces, pick)
        }
        Light::Spot {
            position,
            direction,
            cos_outer,
            ..
        } => {
            let half = cos_outer.clamp(-1.0, 1.0).acos();
            let tan_half = half.min(MAX_SPOT_HALF_ANGLE.to_radians()).tan();
            let face = perspective_face(
                settings,
                Vec3::from(*position),
                Vec3::from(*direction),
                tan_half,
                bounds,
            );
            (vec![face], Pick::One)
        }
        Light::Point { position, .. } => {
            let pos = Vec3::from(*position);
            let n = settings.map_size as f32;
            let margin = settings.reach().ceil().min(n / 4.0);
            let tan_half = n / (n - 2.0 * margin);
            let faces = CUBE_AXES
                .iter()
                .map(|a| perspective_face(settings, pos, *a, tan_half, bounds))
                .collect();
            (faces, Pick::Cube(pos))
        }
        Light::Polygon {
            vertices,
            two_sided,
            ..
        } => {
            let (centre, normal, _) = polygon_shape(vertices)?;
            // A one-sided polygon's cube sits a hair in front of it, so its
            // own triangles lie behind the centre instead of through it.
            let pos = if *two_sided {
                centre
            } else {
                centre + normal * (bounds.diagonal() * 1e-4)
            };
            let n = settings.map_size as f32;
            let margin = settings.reach().ceil().min(n / 4.0);
            let tan_half = n / (n - 2.0 * margin);
            let faces = CUBE_AXES
                .iter()
                .map(|a| perspective_face(settings, pos, *a, tan_half, bounds))
                .collect();
            (faces, Pick::Cube(pos))
        }
    })
}

/// A polygon's vertex mean, unit normal (Newell's, toward the side a
/// counter-clockwise polygon faces) and area, or `None` when it has no
/// area.
fn polygon_shape(vertices: &[[f32; 3]]) -> Option<(Vec3, Vec3, f32)> {
    let v: Vec<Vec3> = vertices.iter().map(|p| Vec3::from(*p)).collect();
    if v.len() < 3 {
        return None;
    }
    let centre = v.iter().copied().sum::<Vec3>() / v.len() as f32;
    let twice = (0..v.len())
        .map(|i| (v[i] - centre).cross(v[(i + 1) % v.len()] - centre))
        .sum::<Vec3>();
    let area = 0.5 * twice.length();
    (area > 0.0 && area.is_finite()).then(|| (centre, twice.normalize(), area))
}

/// The PCSS light size of a polygon light: the diameter of the disk of
/// the polygon's area (0 for a polygon without area).
pub fn polygon_light_size(vertices: &[[f32; 3]]) -> f32 {
    polygon_shape(vertices).map_or(0.0, |(_, _, a)| 2.0 * (a / std::f32::consts::PI).sqrt())
}

/// The `count − 1` view depths between `count` cascades over the view
/// depths `near..far`: the practical split scheme, a blend by
/// [`CASCADE_LAMBDA`] of the logarithmic split near·(far/near)^(i/count)
/// and the uniform one near + (far − near)·i/count.
pub fn cascade_splits(count: u32, near: f32, far: f32) -> Vec<f32> {
    if !(far > 0.0 && far.is_finite()) {
        return vec![0.0; count.saturating_sub(1) as usize];
    }
    // At most 1e6 between near and far, so the powers stay finite.
    let near = near.max(far * 1e-6).min(far);
    (1..count)
        .map(|i| {
            let t = i as f32 / count as f32;
            let log = near * (far / near).powf(t);
            let uniform = near + (far - near) * t;
            CASCADE_LAMBDA * log + (1.0 - CASCADE_LAMBDA) * uniform
        })
        .collect()
}

/// Widest half-angle a spot light's map covers (degrees); points outside
/// it are lit.
const MAX_SPOT_HALF_ANGLE: f32 = 80.0;

/// The cube map's face axes: +x, −x, +y, −y, +z, −z.
const CUBE_AXES: [Vec3; 6] = [
    Vec3::X,
    Vec3::NEG_X,
    Vec3::Y,
    Vec3::NEG_Y,
    Vec3::Z,
    Vec3::NEG_Z,
];

/// The scene's world bounds.
struct Bounds {
    min: Vec3,
    max: Vec3,
}

impl Bounds {
    fn of(scene: &SceneData) -> Option<Bounds> {
        let (min, max) = scene
            .positions
            .iter()
            .filter(|p| p.is_finite())
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        (min.cmple(max).all()).then_some(Bounds { min, max })
    }

    fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }

    fn diagonal(&self) -> f32 {
        (self.max - self.min).length().max(1e-6)
    }
}

/// A unit vector orthogonal to `axis` (a fixed choice per axis).
fn up_for(axis: Vec3) -> Vec3 {
    if axis.y.abs() < 0.9 {
        Vec3::Y
    } else {
        Vec3::Z
    }
}

/// The orthographic map of a directional light toward `to_light`: across
/// the light, the scene's bounds cut to the camera frustum's slice between
/// view depths `slice.0` and `slice.1`; along it, the whole scene.
fn directional_face(
    s: &ShadowSettings,
    to_light: Vec3,
    b: &Bounds,
    view: &View,
    slice: (f32, f32),
) -> Face {
    let axis = -to_light.normalize();
    let right = axis.cross(up_for(axis)).normalize();
    let up = right.cross(axis);
    let lx = |p: Vec3| Vec3::new(p.dot(right), p.dot(up), p.dot(axis));
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for c in b.corners() {
        (lo, hi) = (lo.min(lx(c)), hi.max(lx(c)));
    }
    if slice.1 > 0.0 {
        let (mut flo, mut fhi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for d in [slice.0, slice.1] {
            for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
                let p = view.eye
                    + (view.forward + view.right * (sx * view.tan_x) + view.up * (sy * view.tan_y))
                        * d;
                (flo, fhi) = (flo.min(lx(p)), fhi.max(lx(p)));
            }
        }
        let (x0, x1) = (lo.x.max(flo.x), hi.x.min(fhi.x));
        let (y0, y1) = (lo.y.max(flo.y), hi.y.min(fhi.y));
        if x0 < x1 && y0 < y1 {
            (lo.x, hi.x, lo.y, hi.y) = (x0, x1, y0, y1);
        }
    }
    let n = s.map_size as f32;
    // Square texels: the larger extent on both axes.
    let extent = (hi.x - lo.x).max(hi.y - lo.y).max(b.diagonal() * 1e-6);
    let margin = s.reach().ceil() + 1.0;
    let texel = extent / (n - 2.0 * margin).max(1.0);
    let half = 0.5 * texel * n;
    let centre = Vec3::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), 0.0);
    let pad = 0.01 * (hi.z - lo.z) + b.diagonal() * 1e-4;
    let (near, span) = (lo.z - pad, (hi.z - lo.z) + 2.0 * pad);
    // Rows of the world → clip matrix: x, y across; z = 1 − (d − near)/span.
    let row_x = (right / half).extend(-centre.x / half);
    let row_y = (up / half).extend(-centre.y / half);
    let row_z = (-axis / span).extend(1.0 + near / span);
    let clip = Mat4::from_cols(row_x, row_y, row_z, Vec4::W).transpose();
    Face {
        clip,
        size: s.map_size,
        depth: Vec::new(),
        origin: Vec3::ZERO,
        axis,
        texel,
        perspective: false,
        near,
        span,
    }
}

/// A perspective map from `pos` along `axis` with a square field of view
/// of half-width tan = `tan_half`.
fn perspective_face(s: &ShadowSettings, pos: Vec3, axis: Vec3, tan_half: f32, b: &Bounds) -> Face {
    let axis = axis.normalize();
    let near = b.diagonal() * 1e-4;
    let camera = Camera {
        eye: pos,
        target: pos + axis,
        up: up_for(axis),
        fov_y_deg: (2.0 * tan_half.atan()).to_degrees(),
        near,
        far: f32::INFINITY,
    };
    let view = camera.view(s.map_size, s.map_size);
    Face {
        clip: view.view_proj,
        size: s.map_size,
        depth: Vec::new(),
        origin: pos,
        axis,
        texel: 2.0 * tan_half / s.map_size as f32,
        perspective: true,
        near,
        span: 0.0,
    }
}

/// Draws `face`'s depth pass and keeps its linear depth, row-major.
fn render_face(
    scene: &SceneData,
    face: &mut Face,
    pass: &mut Option<Visibility>,
    stats: &mut FrameStats,
) {
    let target = Target::new(face.size, face.size).expect("map size checked at load");
    let v = depth_pass(scene, &target, face.clip, pass, stats);
    let n = face.size as usize;
    face.depth.resize(n * n, 0.0);
    let (perspective, near, span) = (face.perspective, face.near, face.span);
    face.depth
        .par_chunks_mut(n)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, d) in row.iter_mut().enumerate() {
                let z = v.vis.depth[target.index(x as u32, y as u32)];
                *d = if z <= 0.0 {
                    f32::INFINITY
                } else if perspective {
                    near / z
                } else {
                    near + (1.0 - z) * span
                };
            }
        });
}

impl Face {
    /// Linear depth of `p`.
    fn depth_of(&self, p: Vec3) -> f32 {
        (p - self.origin).dot(self.axis)
    }

    /// The map's depth at integer texel (x, y), clamped to the map.
    fn at(&self, x: i32, y: i32) -> f32 {
        let n = self.size as i32;
        self.depth[(y.clamp(0, n - 1) * n + x.clamp(0, n - 1)) as usize]
    }

    /// Bilinear mean of the comparisons `d <= depth` at continuous texel
    /// coordinates (u, v) (texel centres at integers).
    fn compare_bilinear(&self, u: f32, v: f32, d: f32) -> f32 {
        let (x0, y0) = (u.floor(), v.floor());
        let (fx, fy) = (u - x0, v - y0);
        let (x0, y0) = (x0 as i32, y0 as i32);
        let lit = |x, y| (d <= self.at(x, y)) as u32 as f32;
        let top = lit(x0, y0) * (1.0 - fx) + lit(x0 + 1, y0) * fx;
        let bottom = lit(x0, y0 + 1) * (1.0 - fx) + lit(x0 + 1, y0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// Mean of bilinear comparisons over a 3 × 3 grid of half-width
    /// `radius` texels around (u, v).
    fn pcf(&self, u: f32, v: f32, d: f32, radius: f32) -> f32 {
        if radius <= 0.0 {
            return self.compare_bilinear(u, v, d);
        }
        let mut sum = 0.0;
        for j in -1..=1 {
            for i in -1..=1 {
                sum += self.compare_bilinear(u + i as f32 * radius, v + j as f32 * radius, d);
            }
        }
        sum / 9.0
    }

    /// Mean of bilinear comparisons over the taps of a 7 × 7 grid that
    /// lie in a disk of radius `radius` texels around (u, v): the shape of
    /// a round light's footprint, for PCSS.
    fn pcf_disk(&self, u: f32, v: f32, d: f32, radius: f32) -> f32 {
        let step = radius / 3.0;
        let (mut sum, mut n) = (0.0, 0u32);
        for j in -3i32..=3 {
            for i in -3i32..=3 {
                if i * i + j * j <= 9 {
                    sum += self.compare_bilinear(u + i as f32 * step, v + j as f32 * step, d);
                    n += 1;
                }
            }
        }
        sum / n as f32
    }

    /// The mean depth of the texels nearer than `d` in a square of
    /// half-width `radius` texels around (u, v), if any.
    fn blockers(&self, u: f32, v: f32, d: f32, radius: f32) -> Option<f32> {
        let step = radius / 3.0;
        let (mut sum, mut count) = (0.0, 0u32);
        for j in -3..=3 {
            for i in -3..=3 {
                let z = self.at(
                    (u + i as f32 * step).round() as i32,
                    (v + j as f32 * step).round() as i32,
                );
                if z < d {
                    sum += z;
                    count += 1;
                }
            }
        }
        (count > 0).then(|| sum / count as f32)
    }
}

impl LightShadow {
    /// The index of the face that sees `p`.
    fn face_index(&self, p: Vec3) -> usize {
        match &self.pick {
            Pick::One => 0,
            Pick::Cube(c) => {
                let d = p - *c;
                let a = d.abs();
                if a.x >= a.y && a.x >= a.z {
                    (d.x < 0.0) as usize
                } else if a.y >= a.z {
                    2 + (d.y < 0.0) as usize
                } else {
                    4 + (d.z < 0.0) as usize
                }
            }
            Pick::Cascades {
                eye,
                forward,
                splits,
            } => {
                let depth = (p - *eye).dot(*forward);
                splits.iter().filter(|s| **s <= depth).count()
            }
        }
    }

    /// The face that sees `p`.
    fn face_for(&self, p: Vec3) -> &Face {
        &self.faces[self.face_index(p)]
    }

    /// Maps this light renders (a cube's faces, cascades, or one).
    pub fn faces(&self) -> usize {
        self.faces.len()
    }

    /// The fraction of the light reaching world point `p` with unit
    /// normal `n`: 0 in shadow, 1 lit (between: filtered).
    pub fn visibility(&self, p: Vec3, n: Vec3) -> f32 {
        if !(p.is_finite() && n.is_finite()) {
            return 1.0;
        }
        let face = self.face_for(p);
        let s = &self.settings;
        let scale = if face.perspective {
            face.depth_of(p).max(face.near)
        } else {
            1.0
        };
        let texel = face.texel * scale;
        let radius = match s.filter {
            ShadowFilter::Hard => 0.0,
            _ => s.filter_radius,
        };
        let p = p + n * (s.normal_bias * texel * (1.0 + radius));
        let c = face.clip * p.extend(1.0);
        if c.w <= 0.0 {
            return 1.0;
        }
        let (x, y) = (c.x / c.w, c.y / c.w);
        if !(x.abs() <= 1.0 && y.abs() <= 1.0) {
            return 1.0;
        }
        let size = face.size as f32;
        let u = (x + 1.0) * 0.5 * size - 0.5;
        let v = (1.0 - y) * 0.5 * size - 0.5;
        let d = face.depth_of(p) - s.bias * texel;
        match s.filter {
            ShadowFilter::Hard => (d <= face.at(u.round() as i32, v.round() as i32)) as u32 as f32,
            ShadowFilter::Pcf => face.pcf(u, v, d, s.filter_radius),
            ShadowFilter::Pcss => self.pcss(face, u, v, d, texel),
        }
    }

    /// Blocker search over the light's footprint, penumbra width
    /// w = (d_receiver − d_blocker) · size / d_blocker (perspective; the
    /// size itself for directional lights, as an angle), then PCF over w.
    fn pcss(&self, face: &Face, u: f32, v: f32, d: f32, texel: f32) -> f32 {
        let s = &self.settings;
        let size = s.light_size;
        // Search half-width: the cone from the receiver to the light, at
        // blockers half way to the light (perspective) or anywhere up to
        // the map's near side (directional), in texels at the receiver.
        let search = if face.perspective {
            0.5 * size / texel
        } else {
            0.5 * size * (d - face.near).max(0.0) / texel
        };
        let search = search.clamp(1.0, PCSS_MAX_RADIUS);
        let Some(blocker) = face.blockers(u, v, d, search) else {
            return 1.0;
        };
        let width = if face.perspective {
            (d - blocker) * size / blocker.max(1e-12)
        } else {
            (d - blocker) * size
        };
        // Half the penumbra in texels at the receiver.
        let radius = (0.5 * width / texel).clamp(0.0, PCSS_MAX_RADIUS);
        face.pcf_disk(u, v, d, radius.max(s.filter_radius.min(1.0)))
    }

    /// [`LightShadow::visibility`] of each lane of `p`, `n` in `lanes`
    /// (1 elsewhere), bit for bit. Hard and PCF lookups on maps small
    /// enough for exact f32 gather indices run on all lanes at once
    /// ([`LightShadow::visibility_packet`]): each lane picks its face (cube
    /// face or cascade) as the scalar lookup does, and each face present
    /// runs once under its lanes' mask. PCSS (whose search and filter
    /// widths differ per lane) and larger maps go lane by lane.
    pub fn visibility_lanes<R: Real>(&self, p: &V3<R>, n: &V3<R>, lanes: u32) -> R {
        if self.settings.filter != ShadowFilter::Pcss && self.faces[0].size <= MAX_PACKET_MAP {
            if self.faces.len() == 1 {
                return self.visibility_packet(&self.faces[0], p, n, lanes);
            }
            let masks = self.face_masks(p, lanes);
            let mut out = R::ONE;
            for (face, m) in self.faces.iter().zip(masks) {
                if m != 0 {
                    let f = self.visibility_packet(face, p, n, m);
                    out = R::select(R::mask_from_bits(m), f, out);
                }
            }
            return out;
        }
        let mut c = [[0.0f32; 8]; 6];
        for (out, v) in c.iter_mut().zip([p.x, p.y, p.z, n.x, n.y, n.z]) {
            v.store(out);
        }
        let mut f = [1.0f32; 8];
        for (i, f) in f.iter_mut().enumerate().take(R::LANES) {
            if lanes & (1 << i) != 0 {
                *f = self.visibility(
                    Vec3::new(c[0][i], c[1][i], c[2][i]),
                    Vec3::new(c[3][i], c[4][i], c[5][i]),
                );
            }
        }
        R::load(&f)
    }

    /// Per face, the mask of the `lanes` whose point it sees (a lane with
    /// a non-finite point goes to face 0, whose lookup gives it 1).
    fn face_masks<R: Real>(&self, p: &V3<R>, lanes: u32) -> [u32; 6] {
        let mut masks = [0u32; 6];
        for i in (0..R::LANES).filter(|i| lanes & (1 << i) != 0) {
            let q = Vec3::new(p.x.lane(i) as f32, p.y.lane(i) as f32, p.z.lane(i) as f32);
            let f = if q.is_finite() { self.face_index(q) } else { 0 };
            masks[f] |= 1 << i;
        }
        masks
    }

    /// [`LightShadow::visibility`] on every lane at once, for a hard or
    /// PCF light whose lanes all use `face`: the same operations in the
    /// same order (no fused multiply-adds), so the same bits.
    #[inline(always)]
    fn visibility_packet<R: Real>(&self, face: &Face, p: &V3<R>, n: &V3<R>, lanes: u32) -> R {
        let s = &self.settings;
        let k = |x: f32| R::splat(x as f64);
        let finite = p.x.is_finite()
            & p.y.is_finite()
            & p.z.is_finite()
            & n.x.is_finite()
            & n.y.is_finite()
            & n.z.is_finite();
        let texel = if face.perspective {
            k(face.texel) * face.depth_of_lanes(p).max(k(face.near))
        } else {
            k(face.texel)
        };
        let radius = match s.filter {
            ShadowFilter::Hard => 0.0,
            _ => s.filter_radius,
        };
        let push = k(s.normal_bias) * texel * k(1.0 + radius);
        let p = V3::new(p.x + n.x * push, p.y + n.y * push, p.z + n.z * push);
        // face.clip × (p, 1), column by column as glam's Mat4 × Vec4 adds.
        let [c0, c1, c2, c3] = [
            face.clip.x_axis,
            face.clip.y_axis,
            face.clip.z_axis,
            face.clip.w_axis,
        ];
        let row = |a: f32, b: f32, c: f32, d: f32| k(a) * p.x + k(b) * p.y + k(c) * p.z + k(d);
        let cx = row(c0.x, c1.x, c2.x, c3.x);
        let cy = row(c0.y, c1.y, c2.y, c3.y);
        let cw = row(c0.w, c1.w, c2.w, c3.w);
        let (x, y) = (cx / cw, cy / cw);
        let inside = cw.gt(R::ZERO) & x.abs().le(R::ONE) & y.abs().le(R::ONE);
        let use_map = finite & inside & R::mask_from_bits(lanes);
        let size = k(face.size as f32);
        let half = R::HALF;
        let u = R::select(use_map, (x + R::ONE) * half * size - half, R::ZERO);
        let v = R::select(use_map, (R::ONE - y) * half * size - half, R::ZERO);
        let d = R::select(
            use_map,
            face.depth_of_lanes(&p) - k(s.bias) * texel,
            R::ZERO,
        );
        let f = match s.filter {
            ShadowFilter::Hard => face.lit_lanes(round_lanes(u), round_lanes(v), d),
            _ => face.pcf_lanes(u, v, d, s.filter_radius),
        };
        R::select(use_map, f, R::ONE)
    }
}

/// Largest map side whose texel indices (up to side² − 1) are exact in
/// f32, the index type of the lanes' gathers.
const MAX_PACKET_MAP: u32 = 4096;

/// f32's `round` (half away from zero) for values that are then clamped
/// to texels ≥ 0: below 0 it may differ, but only among values that
/// clamp to texel 0 alike. (The fraction u − ⌊u⌋ is exact.)
#[inline(always)]
fn round_lanes<R: Real>(u: R) -> R {
    let t = u.floor();
    R::select((u - t).ge(R::HALF), t + R::ONE, t)
}

impl Face {
    /// [`Face::depth_of`] per lane, with its operations in its order.
    #[inline(always)]
    fn depth_of_lanes<R: Real>(&self, p: &V3<R>) -> R {
        let k = |x: f32| R::splat(x as f64);
        let (o, a) = (self.origin, self.axis);
        (p.x - k(o.x)) * k(a.x) + (p.y - k(o.y)) * k(a.y) + (p.z - k(o.z)) * k(a.z)
    }

    /// 1 where `d` ≤ the map's depth at integer texel (x, y) (clamped to
    /// the map), 0 elsewhere: [`Face::at`]'s comparison per lane.
    #[inline(always)]
    fn lit_lanes<R: Real>(&self, x: R, y: R, d: R) -> R {
        let last = R::splat((self.size - 1) as f64);
        let (x, y) = (x.clamp(R::ZERO, last), y.clamp(R::ZERO, last));
        let depth = R::gather(&self.depth, y * R::splat(self.size as f64) + x);
        R::select(d.le(depth), R::ONE, R::ZERO)
    }

    /// [`Face::compare_bilinear`] per lane.
    #[inline(always)]
    fn compare_bilinear_lanes<R: Real>(&self, u: R, v: R, d: R) -> R {
        let (x0, y0) = (u.floor(), v.floor());
        let (fx, fy) = (u - x0, v - y0);
        let (x1, y1) = (x0 + R::ONE, y0 + R::ONE);
        let top = self.lit_lanes(x0, y0, d) * (R::ONE - fx) + self.lit_lanes(x1, y0, d) * fx;
        let bottom = self.lit_lanes(x0, y1, d) * (R::ONE - fx) + self.lit_lanes(x1, y1, d) * fx;
        top * (R::ONE - fy) + bottom * fy
    }

    /// [`Face::pcf`] per lane.
    #[inline(always)]
    fn pcf_lanes<R: Real>(&self, u: R, v: R, d: R, radius: f32) -> R {
        if radius <= 0.0 {
            return self.compare_bilinear_lanes(u, v, d);
        }
        let mut sum = R::ZERO;
        for j in -1..=1 {
            for i in -1..=1 {
                let (du, dv) = (i as f32 * radius, j as f32 * radius);
                sum += self.compare_bilinear_lanes(
                    u + R::splat(du as f64),
                    v + R::splat(dv as f64),
                    d,
                );
            }
        }
        sum / R::splat(9.0)
    }
}

/// A drawn pixel's surface and one light's shadow factor there
/// ([`pixel_shadows`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelShadow {
    /// World position and unit shading normal at the pixel centre.
    pub p: Vec3,
    pub n: Vec3,
    /// Light k's shadow factor (what the light loop multiplies by).
    pub factor: f32,
}

/// Every pixel of `target` (row-major) as the shading pass sees it for
/// light `k`: its surface point and normal, and the light's shadow factor
/// there; `None` where no triangle is drawn. Empty when light `k` has no
/// shadow map in `v`. For tests and tools that compare the maps with
/// exact visibility.
pub fn pixel_shadows(
    scene: &SceneData,
    target: &Target,
    v: &Visibility,
    k: usize,
) -> Vec<Option<PixelShadow>> {
    let Some(light) = v.shadows.light(k) else {
        return Vec::new();
    };
    let ctx = crate::resolve::ResolveContext::new(scene, &v.planes, &v.view);
    let mut out = Vec::with_capacity(target.pixel_count());
    for y in 0..target.height {
        for x in 0..target.width {
            let id = v.vis.id[target.index(x, y)];
            if id == crate::target::MISS {
                out.push(None);
                continue;
            }
            let tris = crate::resolve::PacketTris::new(&[id], 1, &ctx);
            let f = ctx.resolve::<f32>(x, y, &tris);
            let (p, n) = (
                Vec3::new(f.p.x, f.p.y, f.p.z),
                Vec3::new(f.n.x, f.n.y, f.n.z),
            );
            out.push(Some(PixelShadow {
                p,
                n,
                factor: light.visibility(p, n),
            }));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The split depths of 4 cascades over 1..10000: the logarithmic ones
    /// are 10, 100 and 1000, the uniform ones 2500.75, 5000.5 and
    /// 7500.25, blended 3 : 1.
    #[test]
    fn cascade_splits_blend_log_and_uniform() {
        let s = cascade_splits(4, 1.0, 10000.0);
        let want = [
            0.75 * 10.0 + 0.25 * 2500.75,
            0.75 * 100.0 + 0.25 * 5000.5,
            0.75 * 1000.0 + 0.25 * 7500.25,
        ];
        assert_eq!(s.len(), 3);
        for (g, w) in s.iter().zip(want) {
            assert!((g - w).abs() <= 1e-3 * w, "{s:?} vs {want:?}");
        }
        assert!(cascade_splits(1, 0.1, 50.0).is_empty());
        // Increasing and inside the range for any near/far.
        for (n, f) in [
            (0.1, 50.0),
            (1e-6, 1e6),
            (3.0, 3.0),
            (0.0, 10.0),
            (1.0, 0.0),
        ] {
            let s = cascade_splits(4, n, f);
            assert!(s.windows(2).all(|w| w[0] <= w[1]), "{s:?}");
            assert!(s.iter().all(|z| z.is_finite() && *z <= f), "{s:?}");
        }
    }

    /// A polygon's size for PCSS is the diameter of the disk of its area.
    #[test]
    fn polygon_light_size_is_the_equal_area_disk() {
        let square = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 0.0, 2.0],
            [0.0, 0.0, 2.0],
        ];
        let d = polygon_light_size(&square);
        assert!(
            (d - 2.0 * (4.0 / std::f32::consts::PI).sqrt()).abs() < 1e-5,
            "{d}"
        );
        assert_eq!(polygon_light_size(&[[0.0; 3]; 3]), 0.0);
    }
}
