//! The scene loader's error messages, whole: each case breaks one rule of
//! one table and expects the exact text the loader has always printed
//! (written out here from the rule, not printed by the code under test).
//! Users and scripts read these messages; typed errors must keep them.

use std::path::Path;

const BASE_CAMERA: &str = r#"
[camera]
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
fov_y = 45.0
near = 0.1
far = 10.0
"#;

const BASE_OUTPUT: &str = "[output]\nwidth = 32\nheight = 24\n";

const POINT_LIGHT: &str =
    "[[light]]\ntype = \"point\"\nposition = [2.0, 2.0, 2.0]\nintensity = [10.0, 10.0, 10.0]\n";

const SPHERE: &str = "[[mesh]]\nsphere = { radius = 1.0, segments = 16, rings = 8 }\n";

/// The scene of the given tables, any of them replaced.
fn scene(camera: &str, output: &str, rest: &str) -> String {
    format!("{camera}\n{output}\n{rest}\n")
}

/// The loader's message for `toml`, read as `s.toml` with no other files.
fn error(toml: &str) -> String {
    let read = |_: &Path| -> std::io::Result<Vec<u8>> { Err(std::io::ErrorKind::NotFound.into()) };
    match specula::scene::load_scene_str(Path::new("s.toml"), toml, &read) {
        Ok(_) => panic!("loaded, expected an error:\n{toml}"),
        Err(e) => e.to_string(),
    }
}

fn expect(toml: &str, want: &str) {
    assert_eq!(error(toml), format!("s.toml: {want}"), "\n{toml}");
}

#[test]
fn camera_errors_name_their_field() {
    let camera = |from: &str, to: &str| BASE_CAMERA.replace(from, to);
    let rest = format!("{POINT_LIGHT}{SPHERE}");
    expect(
        &scene(&camera("fov_y = 45.0", "fov_y = 200.0"), BASE_OUTPUT, &rest),
        "camera.fov_y: must be in [0.001, 179] degrees, got 200",
    );
    expect(
        &scene(
            &camera("near = 0.1\nfar = 10.0", "near = 2.0\nfar = 1.0"),
            BASE_OUTPUT,
            &rest,
        ),
        "camera.near / camera.far: need 0 < near < far (far may be inf), got 2 and 1",
    );
    expect(
        &scene(
            &camera("target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, 3.0]"),
            BASE_OUTPUT,
            &rest,
        ),
        "camera: eye, target and up must span a frame (target ≠ eye, up not parallel to the view)",
    );
    expect(
        &scene(
            &camera("eye = [0.0, 0.0, 3.0]", "eye = [nan, 0.0, 3.0]"),
            BASE_OUTPUT,
            &rest,
        ),
        "camera.eye: every component must be finite, got [NaN, 0.0, 3.0]",
    );
}

#[test]
fn output_errors_name_their_field() {
    let rest = format!("{POINT_LIGHT}{SPHERE}");
    expect(
        &scene(BASE_CAMERA, &format!("{BASE_OUTPUT}ssaa = 17\n"), &rest),
        "output.ssaa: must be in 1..=16, got 17",
    );
    expect(
        &scene(
            BASE_CAMERA,
            "[output]\nwidth = 20000\nheight = 24\nssaa = 2\n",
            &rest,
        ),
        "output.width: must be in 1..=8192 (at most 16384 after ssaa 2), got 20000",
    );
    expect(
        &scene(
            BASE_CAMERA,
            &format!("{BASE_OUTPUT}exposure = inf\n"),
            &rest,
        ),
        "output.exposure: must be finite",
    );
}

#[test]
fn environment_errors_name_their_field() {
    let with = |env: &str| {
        scene(
            BASE_CAMERA,
            BASE_OUTPUT,
            &format!("{SPHERE}[environment]\n{env}\n"),
        )
    };
    expect(
        &with("uniform = [1.0, 1.0, 1.0]\nmap = \"sky.hdr\""),
        "environment: give either uniform or map, not both",
    );
    expect(
        &with("intensity = 2.0"),
        "environment: give uniform = [r, g, b] or map = \"file.hdr\"",
    );
    expect(
        &with("map = \"sky.hdr\"\nintensity = -1.0"),
        "environment.intensity must be finite and ≥ 0, got -1",
    );
    expect(
        &with("map = \"sky.hdr\"\nrotate = nan"),
        "environment.rotate must be finite, got NaN",
    );
    let not_found = std::io::Error::from(std::io::ErrorKind::NotFound);
    expect(
        &with("map = \"sky.hdr\""),
        &format!("environment.map: cannot read sky.hdr: {not_found}"),
    );
}

#[test]
fn mesh_errors_name_their_field() {
    let with = |mesh: &str| scene(BASE_CAMERA, BASE_OUTPUT, &format!("{POINT_LIGHT}{mesh}"));
    expect(
        &with("[[mesh]]\nsphere = { radius = 1.0 }\nplane = { size = [1.0, 1.0] }\n"),
        "mesh[0]: give exactly one of obj, gltf, sphere, plane, cube",
    );
    expect(
        &with("[[mesh]]\nsphere = { radius = 1.0, segments = 2, rings = 8 }\n"),
        "mesh[0].sphere.segments: must be in 3..=4096, got 2",
    );
    expect(
        &with(&format!("{SPHERE}scale = 0.0\n")),
        "mesh[0].scale: every component must be a number with 1e-12 ≤ |s| ≤ 1e12, got [0, 0, 0]",
    );
    expect(
        &with(&format!("{SPHERE}material = \"nope\"\n")),
        "mesh[0].material: no material named \"nope\" in [materials] or the mesh's MTL",
    );
    let not_found = std::io::Error::from(std::io::ErrorKind::NotFound);
    expect(
        &with("[[mesh]]\nobj = \"m.obj\"\n"),
        &format!("mesh[0].obj: cannot read m.obj: {not_found}"),
    );
}

#[test]
fn light_errors_name_their_field() {
    let with = |light: &str| scene(BASE_CAMERA, BASE_OUTPUT, &format!("{SPHERE}{light}"));
    expect(
        &with(&POINT_LIGHT.replace("[2.0, 2.0, 2.0]", "[nan, 0.0, 0.0]")),
        "light[0].position: every coordinate must be finite and within ±1e9, got [NaN, 0.0, 0.0]",
    );
    expect(
        &with(&format!("{POINT_LIGHT}range = 0.0\n")),
        "light[0].range: must be a distance > 0 (or inf for no cutoff), got 0",
    );
    expect(
        &with(&format!(
            "{POINT_LIGHT}shadows = \"hard\"\nshadow_map_size = 0\n"
        )),
        "light[0].shadow_map_size: must be 1..=8192 texels, got 0",
    );
    // Edge 1 (x + y = 1) crosses edge 3 (from (1.3, 1.4) back to the
    // origin); edges 0 and 2 lie at y = 0 and y ≥ 1.
    expect(
        &with(
            "[[light]]\ntype = \"polygon\"\nvertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.3, 1.4, 0.0]]\nradiance = [1.0, 1.0, 1.0]\n",
        ),
        "light[0].vertices: the polygon is not simple (edges 1 and 3 cross)",
    );
}

#[test]
fn material_errors_name_the_material_and_field() {
    let with = |material: &str| {
        scene(
            BASE_CAMERA,
            BASE_OUTPUT,
            &format!("{POINT_LIGHT}{SPHERE}material = \"m\"\n[materials.m]\n{material}\n"),
        )
    };
    expect(
        &with("model = \"metallic_roughness\"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 2.0"),
        "materials.m.roughness: must be in [0, 1], got 2",
    );
    expect(
        &with("model = \"lambert\"\nbase_color = [1.0, 1.0, 1.0]\ntexture_wrap = \"bogus\""),
        "materials.m.texture_wrap: expected \"repeat\", \"clamp_to_edge\" or \"mirrored_repeat\", got \"bogus\"",
    );
    expect(
        &with("model = \"lambert\"\nbase_color = [1.0, 1.0, 1.0]\nnormal_scale = nan"),
        "materials.m.normal_scale: must be a finite number, got NaN",
    );
    expect(
        &with("model = \"unlit\"\ncolor = [1.0, 1.0, 1.0]\nintensity = -1.0"),
        "materials.m.intensity: must be finite and in [0, 1e20], got -1",
    );
    expect(
        &with("model = \"microfacet\"\nndf = \"ggx\"\nalpha = -1.0\nfresnel = { type = \"schlick\", f0 = [0.5, 0.5, 0.5] }"),
        "materials.m.alpha: must be a finite number ≥ 0 (values outside [1e-3, 1] are clamped into it), got -1",
    );
    expect(
        &with("model = \"microfacet\"\nndf = \"ggx\"\nalpha = 0.5\nfresnel = { type = \"schlick\", f0 = [1.5, 0.5, 0.5] }"),
        "materials.m.fresnel.f0: components must be ≤ 1, got [1.5, 0.5, 0.5]",
    );
    expect(
        &with("model = \"toon\"\nbase_color = [1.0, 1.0, 1.0]\nbands = 3\nramp = [[0.0, [1.0, 1.0, 1.0]]]"),
        "materials.m.bands / ramp: give one of them, not both",
    );
    expect(
        &with("model = \"toon\"\nbase_color = [1.0, 1.0, 1.0]\nspecular_threshold = 2.0"),
        "materials.m.specular_threshold: must be in [-1, 1], got 2",
    );
    expect(
        &with("model = \"hatching\"\nscale = 0.0"),
        "materials.m.scale: must be finite and > 0, got 0",
    );
}
