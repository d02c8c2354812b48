//! The frame as a list of passes: two geometry passes into one visibility
//! buffer, each with its own vertex stage, cull mode, id range and
//! material; the `unlit` shader end to end; polygon lights checked against
//! the materials that must integrate them.

mod common;

use common::scene;
use specula::render::{render_scene, RenderSettings};
use specula_raster::frame::{render, visibility, FrameStats, ShadePath};
use specula_raster::{
    Cull, FrameContext, GeometryPass, Material, SceneData, SceneDataError, SceneMesh, Target,
    Unlit, VertexStage, MISS,
};
use std::sync::Arc;

const SPHERES: &str = r#"
[camera]
eye = [0.0, 1.0, 6.0]
target = [0.0, 0.0, 0.0]
fov_y = 45.0
near = 0.1
far = 50.0
[[mesh]]
sphere = { radius = 1.0, segments = 48, rings = 24 }
material = "a"
[[mesh]]
sphere = { radius = 0.7, segments = 32, rings = 16 }
translate = [0.9, 0.3, 1.0]
material = "b"
[[mesh]]
plane = { size = [20.0, 20.0], segments = [4, 4] }
translate = [0.0, -1.0, 0.0]
material = "a"
[materials.a]
model = "metallic_roughness"
base_color = [0.8, 0.5, 0.3]
roughness = 0.4
[materials.b]
model = "lambert"
base_color = [0.2, 0.6, 0.9]
[[light]]
type = "point"
position = [3.0, 4.0, 5.0]
intensity = [40.0, 40.0, 40.0]
"#;

#[test]
fn a_scene_split_into_two_passes_gives_the_same_visibility_buffer() {
    let s = scene(SPHERES, &[]);
    let t = Target::new(200, 150).unwrap();
    let one = visibility(&s.data, &t, &mut FrameStats::default());
    let n = s.data.triangles.len() as u32;
    // Split inside the first sphere, so both passes hold part of a mesh.
    for split in [1, n / 3, n - 1] {
        let mut two = s.data.clone().into_parts();
        let mut a = GeometryPass::main(n as usize);
        a.triangles = 0..split;
        let mut b = GeometryPass::main(n as usize);
        b.triangles = split..n;
        b.name = "second".into();
        two.geometry = vec![a, b];
        let two = SceneData::new(two).unwrap();
        let v = visibility(&two, &t, &mut FrameStats::default());
        assert_eq!(v.vis.id, one.vis.id, "split at {split}");
        assert_eq!(v.vis.depth, one.vis.depth, "split at {split}");
    }
}

/// Pushes every vertex out along its normal, then projects: a shell
/// around the mesh.
#[derive(Debug)]
struct Inflate(f32);

impl VertexStage for Inflate {
    fn instance(&self) -> Box<dyn VertexStage> {
        Box::new(Inflate(self.0))
    }

    fn clip_positions(&mut self, frame: &FrameContext, scene: &SceneMesh, out: &mut Vec<[f32; 4]>) {
        let view = frame.view;
        out.extend(
            scene
                .positions
                .iter()
                .zip(scene.normals)
                .map(|(p, n)| (view.view_proj * (*p + *n * self.0).extend(1.0)).to_array()),
        );
    }
}

#[test]
fn a_second_pass_of_inflated_back_faces_draws_a_rim_in_its_own_ids_and_material() {
    let base = scene(
        r#"
[camera]
eye = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 50.0
[[mesh]]
sphere = { radius = 1.0, segments = 64, rings = 32 }
material = "m"
[materials.m]
model = "lambert"
base_color = [0.5, 0.5, 0.5]
[[light]]
type = "directional"
direction = [0.0, 0.0, -1.0]
irradiance = [1.0, 1.0, 1.0]
"#,
        &[],
    );
    let t = Target::new(160, 120).unwrap();
    let alone = render(&base.data, t, ShadePath::Simd);

    let mut s = base.data.clone().into_parts();
    let n = s.triangles.len() as u32;
    let ink = [0.1, 0.9, 0.2];
    s.materials.push(Material::new(
        "rim",
        Unlit {
            color: ink,
            intensity: 1.0,
        },
        false,
    ));
    s.geometry.push(GeometryPass {
        name: "rim".into(),
        vertex: Arc::new(Inflate(0.08)),
        cull: Cull::Front,
        triangles: 0..n,
        id_base: n,
        material: Some(s.materials.len() as u32 - 1),
    });
    let s = SceneData::new(s).unwrap();
    let both = render(&s, t, ShadePath::Simd);

    let (ids_alone, ids_both) = (
        t.to_row_major(&alone.visibility.vis.id),
        t.to_row_major(&both.visibility.vis.id),
    );
    let mut rim = 0;
    for (i, (&a, &b)) in ids_alone.iter().zip(&ids_both).enumerate() {
        if a != MISS {
            // Inside the silhouette the sphere's front faces are nearer
            // than the shell's back faces.
            assert_eq!(a, b, "pixel {i}");
            assert_eq!(
                both.buffers.color.get(i),
                alone.buffers.color.get(i),
                "pixel {i}"
            );
        } else if b != MISS {
            assert!((n..2 * n).contains(&b), "pixel {i}: id {b}");
            assert_eq!(both.buffers.color.get(i), ink, "pixel {i}");
            rim += 1;
        }
    }
    // The shell's silhouette is 8% wider: a ring of roughly
    // 2π r · 0.08 r pixels (r ≈ 37 px here).
    assert!(rim > 400, "{rim} rim pixels");
    assert_eq!(both.stats.counts.triangles, 2 * n as u64);
}

#[test]
fn overlapping_id_ranges_are_refused() {
    let mut s = scene(SPHERES, &[]).data.into_parts();
    let n = s.triangles.len();
    s.geometry.push(GeometryPass::main(n));
    let e = SceneData::new(s).unwrap_err();
    assert!(matches!(e, SceneDataError::Passes(_)), "{e}");
    assert!(e.to_string().contains("overlapping ids"), "{e}");
}

#[test]
fn unlit_renders_its_radiance_exactly_whatever_the_lights() {
    let s = scene(
        &SPHERES.replace(
            "[materials.b]\nmodel = \"lambert\"\nbase_color = [0.2, 0.6, 0.9]",
            "[materials.b]\nmodel = \"unlit\"\ncolor = [0.2, 0.6, 0.9]\nintensity = 0.5",
        ),
        &[],
    );
    let mut set = RenderSettings::from_scene(&s);
    set.width = 200;
    set.height = 150;
    set.ssaa = 1;
    set.buffers.id = true;
    let want = [0.2f32 * 0.5, 0.6 * 0.5, 0.9 * 0.5];
    for path in [ShadePath::Simd, ShadePath::Scalar] {
        set.path = path;
        let r = render_scene(&s, &set, 0.0).unwrap();
        let b = &r.frame.buffers;
        let mut seen = 0;
        for (i, &id) in b.id.iter().enumerate() {
            if id != MISS && s.data.tri_material[id as usize] == 1 {
                assert_eq!(b.color.get(i), want, "pixel {i} ({path:?})");
                seen += 1;
            }
        }
        assert!(seen > 1000, "{seen} unlit pixels");
    }
}

const POLY_LIGHT: &str = "[[light]]\ntype = \"polygon\"\nvertices = [[-1.0, 3.0, -1.0], [1.0, 3.0, -1.0], [1.0, 3.0, 1.0], [-1.0, 3.0, 1.0]]\nradiance = [5.0, 5.0, 5.0]\n";

#[test]
fn polygon_lights_are_validated_where_scenes_load() {
    let read = |_: &std::path::Path| -> std::io::Result<Vec<u8>> {
        Err(std::io::ErrorKind::NotFound.into())
    };
    // Every model here integrates polygons (lambert exactly, the others by
    // LTC); a model without `Brdf::polygon_local` is refused by
    // `Lit::check_lights`, naming the light and the model.
    let text = format!("{SPHERES}{POLY_LIGHT}");
    specula::scene::load_scene_str(std::path::Path::new("s.toml"), &text, &read).unwrap();

    // Unlit ignores lights, so the same light is fine there.
    let unlit_only = format!(
        "[camera]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 40.0\nnear = 0.1\nfar = 50.0\n\
         [[mesh]]\nsphere = {{ radius = 1.0 }}\nmaterial = \"u\"\n\
         [materials.u]\nmodel = \"unlit\"\ncolor = [1.0, 1.0, 1.0]\n{POLY_LIGHT}"
    );
    specula::scene::load_scene_str(std::path::Path::new("s.toml"), &unlit_only, &read).unwrap();

    for (bad, needle) in [
        ("[[-1.0, 3.0, -1.0], [1.0, 3.0, -1.0]]", "3 to 16 vertices"),
        (
            "[[0.0, 3.0, 0.0], [1.0, 3.0, 0.0], [2.0, 3.0, 0.0]]",
            "no area",
        ),
        (
            "[[-1.0, 3.0, -1.0], [1.0, 3.0, -1.0], [-1.0, 3.0, 1.0], [1.6, 3.0, 1.8]]",
            "not simple",
        ),
        (
            "[[-1.0, 3.0, -1.0], [1.0, 3.0, -1.0], [1.0, 4.0, 1.0], [-1.0, 3.0, 1.0]]",
            "not planar",
        ),
    ] {
        let t = unlit_only.replace(
            "[[-1.0, 3.0, -1.0], [1.0, 3.0, -1.0], [1.0, 3.0, 1.0], [-1.0, 3.0, 1.0]]",
            bad,
        );
        let e = specula::scene::load_scene_str(std::path::Path::new("s.toml"), &t, &read)
            .err()
            .unwrap_or_else(|| panic!("{bad} must fail"))
            .to_string();
        assert!(
            e.contains("light[0].vertices") && e.contains(needle),
            "{bad}: {e}"
        );
    }
}
