//! When the copy of a flat open piece cannot show: the proof and its
//! margins, checked per view.

use super::topology::FlatPiece;
use super::OPEN_DEPTH_PUSH;
use glam::Vec4;
use specula_raster::clip::GuardBand;
use specula_raster::setup::{orientation, MAX_CLIP_COORD};
use specula_raster::SceneMesh;

/// Whether the copy of flat open piece `p` (clip positions `clip`, the
/// copy's `copy`, a `w` × `h` image) writes no pixel after the main pass,
/// which drew `p` itself earlier in the frame. Shown, or `false`:
///
/// 1. Every vertex of `p` is valid for setup, in front of the eye (w > 0)
///    and needs no clipping (guard band, near plane), and every triangle
///    of `p` faces the eye as setup decides it (`orientation` > 0): the
///    main pass draws each of them whole, snapped, with no culling.
/// 2. `p` is flat and in front of the eye, so its projection is one to
///    one and the boundary of its image is the image of its boundary
///    edges. Every boundary edge lies beyond one side of the image grown
///    by 2 pixels (both ends beyond the same side, as its image is the
///    segment between them), and the image's centre is in a triangle of
///    `p`: so the grown image, connected and meeting no boundary, lies
///    inside the image of `p`, and the main pass (watertight) covers every
///    pixel centre of the image with a triangle of `p` (the snapped
///    vertices move 1/512 px, far less than the 2 px).
/// 3. So after the main pass every pixel's depth is at least that
///    triangle's plane there. The triangles of `p` and of its copy lie on
///    S, the plane of `p`'s first triangle as z/w over pixel coordinates,
///    and (1 − OPEN_DEPTH_PUSH)·S respectively, up to δ (largest
///    |z/w − S| of `p`'s vertices) and δ′ (largest z/w − (1 −
///    push)·S of the copy's vertices; affine over each triangle, so the
///    vertices bound it). Setup keeps each plane in f32 and evaluates it
///    relative to a corner of the image (`occlusion::hides`' margins): an
///    error below e = 1e-6·(max S + |g_x|·(w + 1) + |g_y|·(h + 1)) +
///    (|g_x| + |g_y|)/256 with g the largest gradient of the triangles'
///    planes. The copy loses the depth test at every pixel when
///    push · min S > 2·(δ + max(δ′, 0) + 2e), min S over the image's
///    corners (S is affine): the factor 2 is slack.
pub(super) fn copy_hidden(
    scene: &SceneMesh,
    p: &FlatPiece,
    clip: &[Vec4],
    copy: &[[f32; 4]],
    w: f64,
    h: f64,
) -> bool {
    let guard = GuardBand::for_image(w as u32, h as u32);
    let f64s = |c: [f32; 4]| c.map(|x| x as f64);
    let vertex_ok = |v: &u32| {
        let (Some(c), Some(k)) = (clip.get(*v as usize), copy.get(*v as usize)) else {
            return false;
        };
        let c = f64s(c.to_array());
        c.iter().all(|x| x.abs() <= MAX_CLIP_COORD)
            && c[3] > 0.0
            && !guard.needs_clip(&[c; 3])
            && k[3] > 0.0
            && k.iter().all(|x| x.is_finite())
    };
    if p.tris.is_empty() || !p.vertices.iter().all(vertex_ok) {
        return false;
    }
    // Pixel coordinates and z/w, as setup projects.
    let screen = |c: [f32; 4]| {
        let [x, y, z, cw] = f64s(c);
        [(x / cw + 1.0) * 0.5 * w, (1.0 - y / cw) * 0.5 * h, z / cw]
    };
    let corners = |f: u32, of: &dyn Fn(u32) -> [f32; 4]| scene.triangles[f as usize].map(of);
    let main = |v: u32| clip[v as usize].to_array();
    let copied = |v: u32| copy[v as usize];
    if !p
        .tris
        .iter()
        .all(|&f| orientation(&corners(f, &main)) > 0.0)
    {
        return false;
    }
    let beyond = |a: [f64; 3], b: [f64; 3]| {
        let m = 2.0;
        (a[0] < -m && b[0] < -m)
            || (a[0] > w + m && b[0] > w + m)
            || (a[1] < -m && b[1] < -m)
            || (a[1] > h + m && b[1] > h + m)
    };
    if !p.boundary.iter().all(|&[a, b]| {
        beyond(
            screen(clip[a as usize].to_array()),
            screen(clip[b as usize].to_array()),
        )
    }) {
        return false;
    }
    // A triangle's z/w as an affine function of pixel coordinates:
    // [g_x, g_y, z at (0, 0)].
    let plane = |t: [[f64; 3]; 3]| {
        let [a, b, c] = t;
        let (ux, uy, uz) = (b[0] - a[0], b[1] - a[1], b[2] - a[2]);
        let (vx, vy, vz) = (c[0] - a[0], c[1] - a[1], c[2] - a[2]);
        let d = ux * vy - vx * uy;
        let gx = (uz * vy - vz * uy) / d;
        let gy = (ux * vz - vx * uz) / d;
        [gx, gy, a[2] - gx * a[0] - gy * a[1]]
    };
    let at = |s: [f64; 3], x: f64, y: f64| s[0] * x + s[1] * y + s[2];
    let centre = |t: [[f64; 3]; 3]| {
        let side = |a: [f64; 3], b: [f64; 3]| {
            (b[0] - a[0]) * (h * 0.5 - a[1]) - (b[1] - a[1]) * (w * 0.5 - a[0])
        };
        let s = [side(t[0], t[1]), side(t[1], t[2]), side(t[2], t[0])];
        s.iter().all(|&x| x >= 0.0) || s.iter().all(|&x| x <= 0.0)
    };
    let mains: Vec<[[f64; 3]; 3]> = p
        .tris
        .iter()
        .map(|&f| corners(f, &main).map(screen))
        .collect();
    if !mains.iter().any(|&t| centre(t)) {
        return false;
    }
    let s = plane(mains[0]);
    let push = OPEN_DEPTH_PUSH as f64;
    let off = |q: [f64; 3], scale: f64| q[2] - scale * at(s, q[0], q[1]);
    let delta = (p.vertices.iter())
        .map(|&v| off(screen(main(v)), 1.0).abs())
        .fold(0.0, f64::max);
    let delta_copy = (p.vertices.iter())
        .map(|&v| off(screen(copied(v)), 1.0 - push))
        .fold(0.0, f64::max);
    let (mut gx, mut gy) = (0.0f64, 0.0f64);
    for t in mains
        .iter()
        .copied()
        .chain(p.tris.iter().map(|&f| corners(f, &copied).map(screen)))
    {
        let q = plane(t);
        gx = gx.max(q[0].abs());
        gy = gy.max(q[1].abs());
    }
    let on_image = [at(s, 0.0, 0.0), at(s, w, 0.0), at(s, 0.0, h), at(s, w, h)];
    let s_min = on_image.iter().copied().fold(f64::INFINITY, f64::min);
    let s_max = on_image.iter().copied().fold(0.0, f64::max) + delta;
    let e = 1e-6 * (s_max + gx * (w + 1.0) + gy * (h + 1.0)) + (gx + gy) / 256.0;
    let margin = push * s_min;
    let need = 2.0 * (delta + delta_copy + 2.0 * e);
    // NaN anywhere (a degenerate first triangle) fails the comparison.
    margin > need && s_min > 0.0
}
