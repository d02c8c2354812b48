//! Each light kind's maps, fitted to the scene and the view: one
//! orthographic map (or one per cascade) for a directional light, fitted
//! to the scene's bounds cut to the camera's view; one perspective map
//! for a spot light; a cube of six for a point light and for a polygon
//! light (from its centre).

use crate::camera::{Camera, View};
use crate::scene::SceneData;
use crate::shadow::{cascade_splits, polygon_shape, Face, Pick, ShadowSettings};
use glam::{Mat4, Vec3, Vec4};
use specula_core::light::Light;

/// The maps of `light` and how a point picks one, or `None` for a light
/// without shadow maps. `near` is the camera's near distance.
pub(super) fn light_faces(
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
        Light::Point { position, .. } => cube_faces(settings, Vec3::from(*position), bounds),
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
            cube_faces(settings, pos, bounds)
        }
    })
}

/// A cube of six maps around `pos`, each a little over 90° so that a
/// filter near a face's edge stays inside that face.
fn cube_faces(settings: &ShadowSettings, pos: Vec3, bounds: &Bounds) -> (Vec<Face>, Pick) {
    let n = settings.map_size as f32;
    let margin = settings.reach().ceil().min(n / 4.0);
    let tan_half = n / (n - 2.0 * margin);
    let faces = CUBE_AXES
        .iter()
        .map(|a| perspective_face(settings, pos, *a, tan_half, bounds))
        .collect();
    (faces, Pick::Cube(pos))
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
pub(super) struct Bounds {
    min: Vec3,
    max: Vec3,
}

impl Bounds {
    pub(super) fn of(scene: &SceneData) -> Option<Bounds> {
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
        bounds: None,
        sees_nothing: false,
        blank: None,
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
    // Every corner of the scene's bounds on or behind the plane through
    // the light across the axis: each triangle lies behind the near plane
    // (a positive distance ahead), beyond which setup rejects it whole.
    let sees_nothing = b.corners().iter().all(|c| axis.dot(*c - pos) <= 0.0);
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
        bounds: None,
        sees_nothing,
        blank: None,
    }
}
