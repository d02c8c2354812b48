//! The entry points of the fuzz targets (`fuzz/`, cargo-fuzz; see
//! docs/ROBUSTNESS.md), here in the library so that the stable test
//! `tests/fuzz_corpus.rs` replays the committed corpus through exactly the
//! code the fuzzer ran.
//!
//! Each function takes arbitrary bytes, runs them through a user-facing
//! path and checks the project's guarantees on the way out. It returns
//! `Ok` when the input was accepted and `Err(message)` when it was refused
//! with a message (both are fine), and panics, naming the broken
//! guarantee, when the input crashes the code or the output is wrong
//! (a NaN pixel, coverage outside the image, an answer that is not JSON).
//! A panic is what the fuzzer reports as a crash.

use crate::eval;
use crate::memory;
use crate::render::{render_scene, RenderSettings};
use crate::scene::{load_scene_str, LoadedScene};
use specula_raster::clip::GuardBand;
use specula_raster::fuzzing::LANES;
use specula_raster::fuzzing::{bin_chunk, BinnedChunk};
use specula_raster::fuzzing::{covered_groups, rasterize_tile};
use specula_raster::setup::{RasterTri, SetupContext, SetupCounts, TriPlanes};
use specula_raster::target::{Target, VisBuffer, MISS, TILE, TILE_PIXELS};
use specula_raster::{Cull, SceneData, ShadePath};
use std::path::Path;

/// Memory budget of one fuzz input (`memory::set_limit`): scenes that
/// would build more than this are refused, as `--max-memory 64M` would.
/// It keeps one input within the fuzzer's time and RSS limits.
pub(crate) const MEMORY_LIMIT: u64 = 64 << 20;

/// Side of the image a fuzzed scene is rendered at (after loading it the
/// way `specula render` does): enough to shade every object, fast enough
/// for thousands of inputs per second.
pub(crate) const RENDER_SIDE: u32 = 16;

/// Separates the OBJ from the MTL in an [`obj_mtl`] input.
pub(crate) const MTL_SEPARATOR: &[u8] = b"\n%%mtl%%\n";

/// The OBJ a scene under [`scene_toml`] reads for any `*.obj` name: one
/// quad with texture coordinates, normals and a material from its MTL.
const ASSET_OBJ: &str = "mtllib m.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nusemtl red\nf 1/1/1 2/2/1 3/3/1 4/4/1\n";
/// The MTL served for any `*.mtl` name.
const ASSET_MTL: &str = "newmtl red\nKd 0.8 0.1 0.1\nNs 40\n";

/// Starts the budget of one input afresh.
fn fresh_budget() {
    memory::reset_reserved();
    memory::set_limit(MEMORY_LIMIT);
}

/// Renders `scene` at [`RENDER_SIDE`]² on one thread, through the same
/// `render_scene` as the CLI, and checks that every pixel is finite.
fn render_checked(scene: &LoadedScene) -> Result<(), String> {
    let mut settings = RenderSettings::from_scene(scene);
    settings.width = RENDER_SIDE;
    settings.height = RENDER_SIDE;
    settings.ssaa = 1;
    settings.threads = Some(1);
    for path in [ShadePath::Simd, ShadePath::Scalar] {
        settings.path = path;
        let r = render_scene(scene, &settings, 0.0)?;
        let hdr = r.hdr();
        assert_eq!(hdr.len(), (RENDER_SIDE * RENDER_SIDE) as usize);
        if let Some(i) = hdr.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            panic!(
                "{path:?} pixel ({}, {}) is {:?}: no accepted scene may give a non-finite pixel",
                i as u32 % RENDER_SIDE,
                i as u32 / RENDER_SIDE,
                hdr[i]
            );
        }
    }
    Ok(())
}

/// Asset files for fuzzed scenes: any `*.obj` is [`ASSET_OBJ`], any
/// `*.mtl` is [`ASSET_MTL`], everything else is missing.
fn serve_assets(p: &Path) -> std::io::Result<Vec<u8>> {
    match p.extension().and_then(|e| e.to_str()) {
        Some("obj") => Ok(ASSET_OBJ.as_bytes().to_vec()),
        Some("mtl") => Ok(ASSET_MTL.as_bytes().to_vec()),
        _ => Err(std::io::ErrorKind::NotFound.into()),
    }
}

/// Target `scene_toml`: `data` as a scene file's text (not UTF-8 is
/// refused, as `specula render` refuses it), loaded and validated as
/// `specula render` does, then rendered at 16×16 in f32x8 and in f32.
pub fn scene_toml(data: &[u8]) -> Result<(), String> {
    let text = std::str::from_utf8(data).map_err(|e| format!("not UTF-8: {e}"))?;
    fresh_budget();
    let scene =
        load_scene_str(Path::new("fuzz.toml"), text, &serve_assets).map_err(|e| e.to_string())?;
    render_checked(&scene)
}

/// Target `gltf`: `data` as a glTF file (a GLB container when it starts
/// with the GLB magic, glTF JSON otherwise; any other file it names is
/// missing, data URIs are read), loaded as `specula render model.glb`
/// loads it (its camera and lights, or the defaults), then rendered as in
/// [`scene_toml`].
pub fn gltf(data: &[u8]) -> Result<(), String> {
    fresh_budget();
    let name = Path::new(if crate::gltf::is_glb(data) {
        "f.glb"
    } else {
        "f.gltf"
    });
    let read = |p: &Path| -> std::io::Result<Vec<u8>> {
        if p == name {
            Ok(data.to_vec())
        } else {
            Err(std::io::ErrorKind::NotFound.into())
        }
    };
    let opts = crate::scene::GltfOptions::default();
    let scene = crate::scene::load_gltf_str(name, &read, &opts)?;
    render_checked(&scene)
}

/// The scene an [`envmap`] input lights: a metallic sphere and a rough
/// dielectric one, the map seen around them.
const ENV_SCENE: &str = r#"
[camera]
eye = [0.0, 0.0, 4.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 50.0
near = 0.1
far = 100.0

[output]
width = 16
height = 16

[environment]
uniform = [1.0, 1.0, 1.0]

[materials.metal]
model = "metallic_roughness"
base_color = [0.9, 0.6, 0.3]
metallic = 1.0
roughness = 0.2

[materials.rough]
model = "metallic_roughness"
base_color = [0.5, 0.5, 0.5]
metallic = 0.0
roughness = 0.8

[[mesh]]
sphere = { radius = 0.8, segments = 12 }
material = "metal"
translate = [-0.9, 0.0, 0.0]

[[mesh]]
sphere = { radius = 0.8, segments = 12 }
material = "rough"
translate = [0.9, 0.0, 0.0]
"#;

/// Target `envmap`: `data` as an environment map file (Radiance HDR or
/// OpenEXR, sniffed from the bytes as `specula render` does), decoded and
/// checked by `envmap_file` (format, header size, memory budget), its
/// texels clamped, its derived data built (SH irradiance, the prefiltered
/// chain, the sampling distribution; the disk cache is not used), then
/// lighting `ENV_SCENE` rendered at 16×16 by the split sum and by the
/// Monte Carlo reference (4 samples a pixel), each in f32x8 and in f32.
/// Checks that every texel is finite and within the documented clamp,
/// that the derived data is finite, and that every pixel is finite.
pub fn envmap(data: &[u8]) -> Result<(), String> {
    use specula_raster::envmap::IblMethod;
    use specula_raster::equirect::MAX_TEXEL;
    fresh_budget();
    let settings = crate::envmap_file::EnvSettings {
        intensity: 1.0,
        rotate_deg: 30.0,
        visible: true,
        method: IblMethod::SplitSum,
    };
    let mut map = crate::envmap_file::new_env_map("fuzz.env", data, &settings)?;
    if let Some(t) = map
        .source
        .texels
        .iter()
        .flatten()
        .find(|c| !(0.0..=MAX_TEXEL).contains(*c))
    {
        panic!("texel {t} outside [0, {MAX_TEXEL}]: decoded texels must be clamped");
    }
    map.prepare(&|_, _| {});
    let (sh, levels, sun) = map.derived();
    if let Some(sun) = sun {
        let d = sun.direction;
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        assert!(
            (len - 1.0).abs() < 1e-3
                && sun.solid_angle.is_finite()
                && sun.solid_angle > 0.0
                && sun.irradiance().iter().all(|c| c.is_finite() && *c >= 0.0),
            "the extracted sun is not a finite light: {sun:?}"
        );
    }
    assert!(
        sh.iter().flatten().all(|c| c.is_finite()),
        "SH irradiance not finite: {sh:?}"
    );
    for (n, planes) in &levels {
        assert!(
            planes.iter().flatten().all(|c| c.is_finite() && *c >= 0.0),
            "a prefiltered level of side {n} has a texel that is negative or not finite"
        );
    }
    let mut scene = load_scene_str(Path::new("fuzz.toml"), ENV_SCENE, &serve_assets)
        .map_err(|e| e.to_string())?;
    let mut parts = scene.data.into_parts();
    parts.environment = None;
    // A sun found in the map casts PCF shadows: its direction, whatever
    // the map, reaches the shadow map's fit.
    parts.sun_shadows = map
        .sun_world()
        .map(|_| specula_raster::shadow::ShadowSettings {
            filter: specula_raster::shadow::ShadowFilter::Pcf,
            ..Default::default()
        });
    parts.env_map = Some(std::sync::Arc::new(map.clone()));
    scene.data = SceneData::new(parts).map_err(|e| e.to_string())?;
    render_checked(&scene)?;
    map.method = IblMethod::Reference { samples: 4 };
    let mut parts = scene.data.into_parts();
    parts.env_map = Some(std::sync::Arc::new(map));
    scene.data = SceneData::new(parts).map_err(|e| e.to_string())?;
    render_checked(&scene)
}

/// The scene an [`obj_mtl`] input is loaded into: the OBJ in view, its
/// own materials, a light and an environment so every material shades.
const OBJ_SCENE: &str = r#"
[camera]
eye = [0.0, 0.5, 3.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 60.0
near = 0.01
far = 100.0

[output]
width = 16
height = 16

[environment]
uniform = [0.2, 0.2, 0.2]

[[mesh]]
obj = "m.obj"

[[light]]
type = "point"
position = [2.0, 3.0, 3.0]
intensity = [10.0, 10.0, 10.0]
"#;

/// Target `obj_mtl`: the bytes before `MTL_SEPARATOR` are `m.obj`, the
/// bytes after it the MTL file that any `mtllib` name reads (no separator:
/// there is no MTL file). The OBJ is loaded by the project's loader
/// (`objcheck` line checks, then tobj, ear clipping, the MTL reading)
/// inside a small scene, which is then rendered as in [`scene_toml`].
pub fn obj_mtl(data: &[u8]) -> Result<(), String> {
    let (obj, mtl) = match find(data, MTL_SEPARATOR) {
        Some(i) => (&data[..i], Some(&data[i + MTL_SEPARATOR.len()..])),
        None => (data, None),
    };
    let read = |p: &Path| -> std::io::Result<Vec<u8>> {
        match p.extension().and_then(|e| e.to_str()) {
            _ if p == Path::new("m.obj") => Ok(obj.to_vec()),
            Some("mtl") => mtl
                .map(<[u8]>::to_vec)
                .ok_or_else(|| std::io::ErrorKind::NotFound.into()),
            _ => Err(std::io::ErrorKind::NotFound.into()),
        }
    };
    fresh_budget();
    let scene =
        load_scene_str(Path::new("fuzz.toml"), OBJ_SCENE, &read).map_err(|e| e.to_string())?;
    render_checked(&scene)
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// Target `eval_line`: `data` as `specula eval` input (any bytes; usually
/// one line). Every input line must get exactly one answer line, each a
/// JSON object with either `"error"` (a string naming the line) or the
/// answer's arrays of finite numbers.
pub fn eval_line(data: &[u8]) -> Result<(), String> {
    let mut out = Vec::new();
    eval::run(data, &mut out).expect("writing to memory");
    let text = String::from_utf8(out).expect("eval answers in UTF-8");
    // As `BufRead::split`: no line after a final newline.
    let lines = data.iter().filter(|&&b| b == b'\n').count()
        + usize::from(data.last().is_some_and(|&b| b != b'\n'));
    let answers: Vec<&str> = text.lines().collect();
    assert_eq!(answers.len(), lines, "one answer per input line");
    let mut errors = Vec::new();
    for (i, a) in answers.iter().enumerate() {
        let v: serde_json::Value = serde_json::from_str(a)
            .unwrap_or_else(|e| panic!("answer {} is not JSON ({e}): {a}", i + 1));
        let obj = v
            .as_object()
            .unwrap_or_else(|| panic!("answer {} is not an object: {a}", i + 1));
        if let Some(e) = obj.get("error").and_then(|e| e.as_str()) {
            assert!(
                e.starts_with(&format!("line {}: ", i + 1)),
                "the error names its line: {a}"
            );
            errors.push(e.to_string());
            continue;
        }
        let numbers = ["f", "emission", "radiance", "error"];
        assert!(
            obj.contains_key("f") || obj.contains_key("radiance"),
            "answer {} has neither \"f\", \"radiance\" nor \"error\": {a}",
            i + 1
        );
        for key in numbers {
            if let Some(x) = obj.get(key) {
                let ok = x
                    .as_array()
                    .is_some_and(|c| c.len() == 3 && c.iter().all(|c| c.as_f64().is_some()));
                assert!(ok, "answer {}: {key} is not 3 finite numbers: {a}", i + 1);
            }
        }
    }
    if errors.is_empty() {
        Ok(())
    } else {
        Err(errors.join("; "))
    }
}

/// Bytes per triangle of a [`raster`] input: three clip-space vertices of
/// four f32 (little-endian).
const TRI_BYTES: usize = 48;

/// Most triangles a [`raster`] input sets up.
const MAX_TRIANGLES: usize = 64;

/// The frame's 4-wide setup (groups of 4, the last 0–3 triangles one at
/// a time, as `frame` runs it) gives what `setup` per triangle gave:
/// the same screen triangles, planes (as bits) and counts.
fn same_as_setup_x4(
    ctx: &SetupContext,
    tris: &[[[f32; 4]; 3]],
    cull: Cull,
    raster_tris: &[RasterTri],
    planes: &[TriPlanes],
    counts: &SetupCounts,
) {
    let (mut out, mut counts4) = (Vec::new(), SetupCounts::default());
    let mut planes4 = vec![TriPlanes::default(); tris.len()];
    let quads = tris.len() / LANES * LANES;
    for (q, (v, p)) in tris[..quads]
        .chunks_exact(LANES)
        .zip(planes4.chunks_exact_mut(LANES))
        .enumerate()
    {
        let v = v.try_into().expect("chunks of LANES");
        let p = p.try_into().expect("chunks of LANES");
        ctx.setup_x4(
            (q * LANES) as u32,
            v,
            [cull; LANES],
            p,
            &mut out,
            &mut counts4,
        );
    }
    for (id, v) in tris.iter().enumerate().skip(quads) {
        if let Some(p) = ctx.setup(id as u32, *v, cull, &mut out, &mut counts4) {
            planes4[id] = p;
        }
    }
    assert_eq!(&counts4, counts, "setup_x4 counts");
    assert_eq!(out.len(), raster_tris.len(), "setup_x4 screen triangles");
    let rt_bits = |r: &RasterTri| {
        (
            r.edges,
            r.inv_step.map(f64::to_bits),
            r.small,
            r.bbox,
            r.tri,
        )
    };
    for (a, b) in out.iter().zip(raster_tris) {
        assert_eq!(
            rt_bits(a),
            rt_bits(b),
            "setup_x4: screen triangle of {}",
            b.tri
        );
    }
    let plane_bits = |p: &TriPlanes| {
        [&p.origin[..], &p.k1, &p.k2, &p.ks, &p.z, &[p.facing]]
            .concat()
            .iter()
            .map(|c| c.to_bits())
            .collect::<Vec<_>>()
    };
    for (id, (a, b)) in planes4.iter().zip(planes).enumerate() {
        assert_eq!(plane_bits(a), plane_bits(b), "setup_x4: planes of {id}");
    }
}

/// Target `raster`: arbitrary clip-space triangles through setup (cull,
/// clip, snap), binning and scan conversion into a visibility buffer of
/// a small image, checking that
/// - every screen triangle's pixel box lies inside the image,
/// - every pixel the scan reports covered is inside the image and inside
///   the triangle's exact fixed-point edges,
/// - the padding of the tiles past the image stays empty,
/// - every depth is finite and every id names a drawn triangle,
/// - the planes of drawn triangles are finite,
/// - the 4-wide setup the frame runs (`setup_x4`) gives the same screen
///   triangles, planes and counts, bit for bit.
///
/// Layout: byte 0 → width 1..=160, byte 1 → height 1..=160, byte 2 → cull
/// mode (0 back, 1 front, else none), then 48 bytes per triangle. The
/// vertices' f32 bits are taken as they are (NaN, inf, 1e38 and
/// denormals included), except that a triangle whose first byte is odd is
/// read as small integers (each coordinate an i32 / 2¹⁶), which reaches
/// the image far more often than random bit patterns do.
pub fn raster(data: &[u8]) -> Result<(), String> {
    let [w, h, cull, rest @ ..] = data else {
        return Err("too short".into());
    };
    let (width, height) = (1 + *w as u32 % 160, 1 + *h as u32 % 160);
    let cull = match cull {
        0 => Cull::Back,
        1 => Cull::Front,
        _ => Cull::None,
    };
    let target = Target::new(width, height).expect("a small image");
    let ctx = SetupContext {
        width,
        height,
        guard: GuardBand::for_image(width, height),
    };
    let mut raster_tris = Vec::new();
    let mut counts = SetupCounts::default();
    let mut planes: Vec<TriPlanes> = Vec::new();
    let mut drawn = Vec::new();
    let mut tris = Vec::new();
    for (id, t) in rest.chunks_exact(TRI_BYTES).take(MAX_TRIANGLES).enumerate() {
        let small = t[0] & 1 == 1;
        let c = |k: usize| -> f32 {
            let b = [t[4 * k], t[4 * k + 1], t[4 * k + 2], t[4 * k + 3]];
            if small {
                i32::from_le_bytes(b) as f32 / 65536.0
            } else {
                f32::from_le_bytes(b)
            }
        };
        let v = [0, 1, 2].map(|i| [0, 1, 2, 3].map(|j| c(4 * i + j)));
        tris.push(v);
        let before = raster_tris.len();
        let p = ctx.setup(id as u32, v, cull, &mut raster_tris, &mut counts);
        planes.push(p.unwrap_or_default());
        if let Some(p) = p {
            let finite = [p.k1, p.k2, p.ks, p.z]
                .iter()
                .flatten()
                .chain(&p.origin)
                .all(|x| x.is_finite());
            assert!(finite, "triangle {id} {v:?}: planes not finite: {p:?}");
            drawn.push(id as u32);
        } else {
            assert_eq!(
                raster_tris.len(),
                before,
                "triangle {id}: no planes but screen triangles"
            );
        }
    }
    same_as_setup_x4(&ctx, &tris, cull, &raster_tris, &planes, &counts);
    for rt in &raster_tris {
        let [x0, y0, x1, y1] = rt.bbox;
        assert!(
            0 <= x0 && x0 <= x1 && x1 <= width as i32 && 0 <= y0 && y0 <= y1 && y1 <= height as i32,
            "triangle {}: box {:?} outside the {width}×{height} image",
            rt.tri,
            rt.bbox
        );
        covered_groups(rt, [x0, x1, y0, y1], 0, |y, gx, mask| {
            for lane in 0..8 {
                if mask >> lane & 1 == 1 {
                    let x = gx + lane;
                    assert!(
                        (x0..x1).contains(&x) && (y0..y1).contains(&y),
                        "triangle {}: pixel ({x}, {y}) outside its box {:?}",
                        rt.tri,
                        rt.bbox
                    );
                    assert!(
                        rt.covers(x, y),
                        "triangle {}: pixel ({x}, {y}) reported covered, but outside its edges",
                        rt.tri
                    );
                }
            }
        });
    }
    let chunks: Vec<BinnedChunk> = vec![bin_chunk(&target, raster_tris)];
    let mut vis = VisBuffer::new(&target);
    for (t, (depth, ids)) in vis
        .depth
        .chunks_mut(TILE_PIXELS)
        .zip(vis.id.chunks_mut(TILE_PIXELS))
        .enumerate()
    {
        rasterize_tile(&target, t, &chunks, &planes, depth, ids);
    }
    for t in 0..target.tile_count() {
        let (tx, ty) = target.tile_origin(t);
        for i in 0..TILE_PIXELS {
            let (x, y) = (tx + (i % TILE) as u32, ty + (i / TILE) as u32);
            let (d, id) = (vis.depth[t * TILE_PIXELS + i], vis.id[t * TILE_PIXELS + i]);
            assert!(d.is_finite(), "pixel ({x}, {y}): depth {d}");
            if x >= width || y >= height {
                assert_eq!(id, MISS, "pixel ({x}, {y}) outside the image was drawn");
            } else if id != MISS {
                assert!(
                    drawn.binary_search(&id).is_ok(),
                    "pixel ({x}, {y}): id {id} was never set up"
                );
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_target_accepts_and_refuses() {
        assert!(scene_toml(b"[camera]").is_err());
        assert!(obj_mtl(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").is_ok());
        assert!(eval_line(b"{}").is_err());
        let mut tri = vec![64u8, 64, 2, 1];
        tri.resize(3 + TRI_BYTES, 0);
        assert!(raster(&tri).is_ok());
    }
}
