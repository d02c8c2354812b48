//! The rasterizer end to end on small analytic scenes: clipping, the camera
//! inside a mesh, geometry behind the camera, non-finite and huge vertices,
//! and perspective-correct interpolation against ray-plane intersection.

mod common;

use common::scene;
use specula_raster::frame::{render, FrameStats, ShadePath};
use specula_raster::resolve::ResolveContext;
use specula_raster::{visibility, Target, MISS};

const CAMERA: &str = r#"
[camera]
eye = [0.0, 1.0, 0.0]
target = [0.0, 1.0, -1.0]
up = [0.0, 1.0, 0.0]
fov_y = 60.0
near = 0.1
far = 1000.0
"#;

fn ids_row_major(s: &specula::scene::LoadedScene, w: u32, h: u32) -> (Vec<u32>, FrameStats) {
    let t = Target::new(w, h).unwrap();
    let mut st = FrameStats::default();
    let v = visibility(&s.data, &t, &mut st);
    (t.to_row_major(&v.vis.id), st)
}

/// Horizontal ray/plane test in f64 through the pixel centre, the camera
/// convention of the README.
fn ray_dir(px: u32, py: u32, w: u32, h: u32, fov_deg: f64) -> [f64; 3] {
    let t = (fov_deg.to_radians() / 2.0).tan();
    let sx = 2.0 * (px as f64 + 0.5) / w as f64 - 1.0;
    let sy = 1.0 - 2.0 * (py as f64 + 0.5) / h as f64;
    // Camera looks down −z, right +x, up +y.
    [sx * t * w as f64 / h as f64, sy * t, -1.0]
}

#[test]
fn ground_plane_through_the_near_plane_is_clipped_and_covers_exactly_below_the_horizon() {
    let s = scene(
        &format!(
            "{CAMERA}\n[[mesh]]\nplane = {{ size = [4000.0, 4000.0] }}\nmaterial = \"m\"\n[materials.m]\nmodel = \"lambert\"\nbase_color = [0.5, 0.5, 0.5]\n"
        ),
        &[],
    );
    let (w, h) = (160, 90);
    let (ids, st) = ids_row_major(&s, w, h);
    assert!(
        st.counts.clipped >= 1,
        "the plane crosses the near plane: {:?}",
        st.counts
    );
    for py in 0..h {
        for px in 0..w {
            let d = ray_dir(px, py, w, h, 60.0);
            // Hits y = 0 from height 1 when d.y < 0, at t = 1/−d.y, within the
            // plane's ±2000 extent.
            let hit = d[1] < 0.0 && {
                let t = 1.0 / -d[1];
                (d[0] * t).abs() < 2000.0 && (d[2] * t).abs() < 2000.0
            };
            // The horizon row is ambiguous within a pixel.
            let near_horizon = (py as f64 + 0.5 - h as f64 / 2.0).abs() < 1.0;
            if !near_horizon {
                assert_eq!(
                    ids[(py * w + px) as usize] != MISS,
                    hit,
                    "pixel ({px}, {py})"
                );
            }
        }
    }
}

#[test]
fn camera_inside_a_closed_mesh() {
    let base = format!("{CAMERA}\n[[mesh]]\ncube = {{ size = 10.0, segments = 3 }}\nmaterial = \"m\"\ntranslate = [0.0, 1.0, 0.0]\n");
    // Seen from inside, every face is a back face.
    let single = scene(
        &format!("{base}[materials.m]\nmodel = \"lambert\"\nbase_color = [0.5, 0.5, 0.5]\n"),
        &[],
    );
    let (ids, st) = ids_row_major(&single, 64, 48);
    assert!(ids.iter().all(|&i| i == MISS));
    assert_eq!(st.counts.drawn, 0);
    assert!(st.counts.culled_backface > 0);
    // Double-sided: every pixel sees a wall, and shading stays finite.
    let double = scene(
        &format!("{base}[materials.m]\nmodel = \"metallic_roughness\"\nbase_color = [0.5, 0.5, 0.5]\nroughness = 0.4\ndouble_sided = true\n[[light]]\ntype = \"point\"\nposition = [1.0, 2.0, -1.0]\nintensity = [5.0, 5.0, 5.0]\n"),
        &[],
    );
    let (ids, _) = ids_row_major(&double, 64, 48);
    assert!(
        ids.iter().all(|&i| i != MISS),
        "a pixel sees no wall from inside the cube"
    );
    let f = render(&double.data, Target::new(64, 48).unwrap(), ShadePath::Simd);
    let lit = f.buffers.color.r.iter().filter(|v| **v > 0.0).count();
    assert!(f
        .buffers
        .color
        .r
        .iter()
        .chain(&f.buffers.color.g)
        .chain(&f.buffers.color.b)
        .all(|v| v.is_finite()));
    assert!(
        lit > 64 * 48 / 2,
        "inner walls must be lit (normals flipped toward the viewer): {lit} lit"
    );
}

#[test]
fn mesh_entirely_behind_the_camera_draws_nothing() {
    let s = scene(
        &format!("{CAMERA}\n[[mesh]]\nsphere = {{ radius = 1.0 }}\nmaterial = \"m\"\ntranslate = [0.0, 1.0, 5.0]\n[materials.m]\nmodel = \"lambert\"\nbase_color = [1.0, 1.0, 1.0]\n"),
        &[],
    );
    let (ids, st) = ids_row_major(&s, 64, 48);
    assert!(ids.iter().all(|&i| i == MISS));
    assert_eq!(st.counts.drawn, 0);
    assert_eq!(
        st.counts.culled_outside + st.counts.culled_backface,
        st.counts.triangles
    );
}

#[test]
fn nan_and_huge_vertices_are_skipped_and_counted_and_leave_no_nan_pixel() {
    let obj = "v 0 0 -5\nv 1 0 -5\nv 0 1 -5\nv nan 0 -5\nv 1e30 1 -5\nv 0 -1e30 -5\nv -1 0 -5\n\
               f 1 2 3\nf 1 4 2\nf 1 2 5\nf 7 6 1\nf 5 4 6\n";
    let s = scene(
        &format!("{CAMERA}\n[[mesh]]\nobj = \"bad.obj\"\nmaterial = \"m\"\n[materials.m]\nmodel = \"metallic_roughness\"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 0.5\n[[light]]\ntype = \"point\"\nposition = [0.0, 2.0, 0.0]\nintensity = [3.0, 3.0, 3.0]\n"),
        &[("bad.obj", obj)],
    );
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("bad.obj") && w.contains("not finite")),
        "{:?}",
        s.warnings
    );
    let f = render(&s.data, Target::new(80, 60).unwrap(), ShadePath::Simd);
    let c = f.stats.counts;
    assert_eq!(c.skipped_invalid, 4, "{c:?}");
    assert_eq!(c.drawn, 1, "{c:?}");
    assert!(f
        .buffers
        .color
        .r
        .iter()
        .chain(&f.buffers.color.g)
        .chain(&f.buffers.color.b)
        .all(|v| v.is_finite()));
    assert!(f.visibility.vis.id.contains(&0));
}

#[test]
fn perspective_correct_uv_on_a_grazing_checker_plane() {
    // Eye 0.3 above a 200 × 200 plane, looking almost along it.
    let s = scene(
        r#"
[camera]
eye = [0.0, 0.3, 40.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 50.0
near = 0.05
far = 500.0
[[mesh]]
plane = { size = [200.0, 200.0], segments = [3, 5] }
material = "m"
[materials.m]
model = "lambert"
base_color = [1.0, 1.0, 1.0]
"#,
        &[],
    );
    let (w, h) = (320, 200);
    let t = Target::new(w, h).unwrap();
    let vis = visibility(&s.data, &t, &mut FrameStats::default());
    let ctx = ResolveContext::new(&s.data, &vis.planes, &vis.view);
    let ids = t.to_row_major(&vis.vis.id);
    let cam = &s.data.camera;
    let (eye, target) = (cam.eye.as_dvec3(), cam.target.as_dvec3());
    let f = (target - eye).normalize();
    let r = f.cross(glam::DVec3::Y).normalize();
    let u = r.cross(f);
    let tan = (50f64.to_radians() / 2.0).tan();
    let mut checked = 0;
    let mut worst = 0.0f64;
    let mut worst_d = 0.0f64;
    for py in 0..h {
        for px in 0..w {
            let id = ids[(py * w + px) as usize];
            if id == MISS {
                continue;
            }
            let sx = 2.0 * (px as f64 + 0.5) / w as f64 - 1.0;
            let sy = 1.0 - 2.0 * (py as f64 + 0.5) / h as f64;
            let d = f + r * (sx * tan * w as f64 / h as f64) + u * (sy * tan);
            let p = eye + d * (-eye.y / d.y);
            // mesh::plane: s along +z, t along +x, both from −100.
            let want = [(p.z + 100.0) / 200.0, (p.x + 100.0) / 200.0];
            let tris = specula_raster::resolve::PacketTris::new(&[id], 1, &ctx);
            let frag = ctx.resolve::<f32>(px, py, &tris);
            let surf = ctx.surface::<f32>(&tris, &frag);
            let got = glam::DVec2::new(surf.uv[0] as f64, surf.uv[1] as f64);
            // Analytic derivatives against central differences of the
            // analytic uv (a thousandth of a pixel each way, in f64).
            let uv_at = |x: f64, y: f64| {
                let sx = 2.0 * x / w as f64 - 1.0;
                let sy = 1.0 - 2.0 * y / h as f64;
                let d = f + r * (sx * tan * w as f64 / h as f64) + u * (sy * tan);
                let p = eye + d * (-eye.y / d.y);
                glam::DVec2::new((p.z + 100.0) / 200.0, (p.x + 100.0) / 200.0)
            };
            let (cx, cy) = (px as f64 + 0.5, py as f64 + 0.5);
            let ddx = (uv_at(cx + 1e-3, cy) - uv_at(cx - 1e-3, cy)) * 500.0;
            let ddy = (uv_at(cx, cy + 1e-3) - uv_at(cx, cy - 1e-3)) * 500.0;
            for (g, want) in [(surf.duv_dx, ddx), (surf.duv_dy, ddy)] {
                let scale = want.length().max(1e-6);
                let e = ((g[0] as f64 - want.x).abs() + (g[1] as f64 - want.y).abs()) / scale;
                worst_d = worst_d.max(e);
                assert!(
                    e < 1e-3,
                    "pixel ({px}, {py}): duv {g:?}, finite differences {want:?}"
                );
            }
            // The plane's tangent is +z (u grows along z), orthogonal to the
            // shading normal, which at grazing pixels is bent toward the eye.
            assert!(
                surf.tangent.z > 0.999 && surf.tangent.dot(frag.n).abs() < 1e-5,
                "tangent {:?}",
                surf.tangent
            );
            let err = (got.x - want[0]).abs().max((got.y - want[1]).abs());
            worst = worst.max(err);
            assert!(
                err < 1e-4,
                "pixel ({px}, {py}): uv {got:?}, analytic {want:?}"
            );
            checked += 1;
        }
    }
    assert!(
        checked > (w * h / 3) as usize,
        "only {checked} pixels on the plane"
    );
    eprintln!("worst uv error {worst:.2e}, worst relative derivative error {worst_d:.2e}, over {checked} pixels");
}
