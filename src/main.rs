//! The `specula` command line. Besides `cpu_check`, the modules only the
//! command line needs live here rather than in the library: `furnace`
//! (`specula furnace`) and the LTC table fits `fit_ltc` and `fit_ltc_coat`
//! (`specula fit-ltc`, `specula fit-ltc-coat`); they reach the library
//! as `specula::…`.

mod cpu_check;
mod fit_ltc;
mod fit_ltc_coat;
mod furnace;

use clap::{Parser, Subcommand};
use image::ImageFormat;
use specula::render::{depth_aov, id_aov, normal_aov, render_scene, RenderSettings};
use specula::scene::{is_gltf_path, load_gltf_scene, load_scene, GltfOptions};
use specula::validate::truncate_lines;
use specula::{demo, image_file, memory, output_plan};
use specula_raster::frame::ShadePath;
use specula_raster::texture::Filter;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// Longest line of an error or warning printed: messages may quote input
/// (a TOML error shows the offending line), which may be megabytes long.
const MESSAGE_LINE_MAX: usize = 1000;

/// Large buffers on transparent huge pages: fewer page faults from process
/// start to image (src/huge_pages.rs).
#[global_allocator]
static ALLOC: specula::huge_pages::HugePageAlloc = specula::huge_pages::HugePageAlloc;

#[derive(Parser)]
#[command(
    name = "specula",
    version,
    about = "CPU software rasterizer with a packed-SIMD physically based shading core.\n\nWith no command, renders the built-in demo to specula-demo.png."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file to PNG (and optionally EXR and AOVs).
    Render(RenderArgs),
    /// Reference BRDF values: JSON Lines on stdin, one answer line per input
    /// line on stdout (see the README, "Reference values").
    Eval,
    /// Directional albedo E(μo) of a microfacet material at several
    /// roughnesses, without and with Kulla-Conty compensation.
    Furnace(FurnaceArgs),
    /// Generate a tonal art map (hatching textures, light to dark, with
    /// mip levels drawn at equal stroke width) into a directory.
    Tam(TamArgs),
    /// Fit the LTC table of the GGX lobe (core/data/ltc_ggx.bin; format in
    /// core/src/ltc/ggx.rs).
    FitLtc(FitLtcArgs),
    /// Fit the LTC table of the Disney clearcoat lobe (core/data/ltc_coat.bin;
    /// format in core/src/ltc/coat.rs).
    FitLtcCoat(FitLtcCoatArgs),
    /// Build the committed Kulla-Conty E tables (core/data/kc_tables.bin;
    /// format in core/src/kulla_conty/committed.rs).
    KcTables(KcTablesArgs),
    /// Compare a test image with a reference: PSNR, errors, FLIP, a heat map;
    /// exit status 0 pass, 1 a --fail-above/--fail-below bound crossed, 2 error.
    Diff(specula::diff::DiffArgs),
    /// Render scenes into a folder with a manifest (input and output hashes),
    /// resumably, optionally one shard of the set.
    Batch(specula::batch::BatchArgs),
    /// Write the generated HDR sky (a sky dome, ground and a sun disk of
    /// known size and radiance; src/sky.rs) as a Radiance .hdr file.
    Sky(SkyArgs),
}

#[derive(clap::Args)]
struct SkyArgs {
    /// Output .hdr file.
    #[arg(short, long)]
    output: PathBuf,
    /// Width in texels (the height is half of it).
    #[arg(long, default_value_t = 512)]
    width: usize,
}

#[derive(clap::Args)]
struct TamArgs {
    /// Output directory (created if missing): tam_t{tone}_l{level}.png and tam.json.
    #[arg(short, long)]
    output: PathBuf,
    /// Number of tones, light to dark.
    #[arg(long, default_value_t = 6)]
    tones: usize,
    /// Mip levels (default: down to 16×16).
    #[arg(long)]
    levels: Option<usize>,
    /// Width and height of level 0 (a power of two).
    #[arg(long, default_value_t = 256)]
    size: u32,
    /// Random seed: the same seed gives the same files.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

#[derive(clap::Args)]
struct FitLtcArgs {
    /// Where to write the table.
    #[arg(short, long, default_value = "core/data/ltc_ggx.bin")]
    output: PathBuf,
    /// Measure a table file (per-pixel error under a small light, the view
    /// sweep's kinks) instead of fitting.
    #[arg(long, value_name = "PATH")]
    check: Option<PathBuf>,
}

#[derive(clap::Args)]
struct FitLtcCoatArgs {
    /// Where to write the table.
    #[arg(short, long, default_value = "core/data/ltc_coat.bin")]
    output: PathBuf,
}

#[derive(clap::Args)]
struct KcTablesArgs {
    /// Where to write the tables.
    #[arg(short, long, default_value = "core/data/kc_tables.bin")]
    output: PathBuf,
}

#[derive(clap::Args)]
struct FurnaceArgs {
    /// The material, as a JSON object with the scene/eval field names (its
    /// alpha is replaced by each --alpha).
    #[arg(
        long,
        default_value = r#"{"model": "microfacet", "ndf": "ggx", "alpha": 0.5, "fresnel": {"type": "schlick", "f0": [1, 1, 1]}}"#
    )]
    material: String,
    /// Roughnesses (alpha) to tabulate, comma separated.
    #[arg(long, value_delimiter = ',', default_values_t = [0.1f32, 0.25, 0.5, 0.75, 1.0])]
    alpha: Vec<f32>,
    /// Also plot the curves to this PNG.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Scene file (TOML), or a glTF 2.0 file (.gltf, .glb) rendered with
    /// its own camera and lights.
    scene: PathBuf,
    /// Which of a glTF file's cameras to look through (in the order the
    /// default scene's nodes are met, from 0; default 0).
    #[arg(long, value_name = "N")]
    camera: Option<usize>,
    /// An environment map (Radiance .hdr or OpenEXR, equirectangular)
    /// lighting a glTF file rendered directly, seen behind it, in place of
    /// the default uniform environment.
    #[arg(long, value_name = "PATH")]
    env: Option<PathBuf>,
    /// Output image, its format from the extension: .png, .exr (linear HDR)
    /// or another format the image crate writes; `-` writes PNG to stdout.
    #[arg(short, long)]
    output: PathBuf,
    /// Image width in pixels (overrides the scene).
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels (overrides the scene).
    #[arg(long)]
    height: Option<u32>,
    /// Supersampling: N×N samples per pixel, box filtered (overrides the scene).
    #[arg(long)]
    ssaa: Option<u32>,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    /// Also write linear HDR colour to this OpenEXR file.
    #[arg(long, value_name = "PATH")]
    exr: Option<PathBuf>,
    /// Arbitrary output variables at the supersampled size: depth=PATH (EXR,
    /// view depth, +inf on miss), normal=PATH (EXR, world normal), id=PATH
    /// (raw u32 triangle ids, see README).
    #[arg(long, value_name = "NAME=PATH")]
    aov: Vec<String>,
    /// Also write the scene's stroke overlay (`[strokes]`) as SVG: one
    /// <path> per polyline, grouped by edge kind.
    #[arg(long, value_name = "PATH")]
    svg_lines: Option<PathBuf>,
    /// Print per-pass times and triangle counts.
    #[arg(long)]
    stats: bool,
    /// Write the statistics as JSON to this file.
    #[arg(long, value_name = "PATH")]
    stats_json: Option<PathBuf>,
    /// Shade one pixel at a time in f32 instead of 8 at a time in f32x8.
    #[arg(long)]
    scalar: bool,
    /// Shade 8 pixels at a time in f32x8 alone, without the AVX-512 packet
    /// pairs the processor may have (the same pixels; for timing).
    #[arg(long, conflicts_with = "scalar")]
    avx2_only: bool,
    /// Sample every texture map with this filter, whatever the scene says:
    /// nearest, bilinear, trilinear, anisotropic (16 taps) or
    /// anisotropic:N (N in 1..=16).
    #[arg(long, value_name = "FILTER", value_parser = parse_texture_filter)]
    texture_filter: Option<Filter>,
    /// Render the loaded scene N times, timing each frame (load and encode excluded).
    #[arg(long, default_value_t = 1)]
    repeat: u32,
    /// Refuse scenes and images estimated to need more memory than this
    /// (e.g. 4G, 512M; default: 3/4 of the machine's or cgroup's memory).
    #[arg(long, value_name = "SIZE", value_parser = specula::memory::parse_size)]
    max_memory: Option<u64>,
}

enum Aov {
    Depth(PathBuf),
    Normal(PathBuf),
    Id(PathBuf),
}

impl Aov {
    fn name(&self) -> &'static str {
        match self {
            Aov::Depth(_) => "depth",
            Aov::Normal(_) => "normal",
            Aov::Id(_) => "id",
        }
    }

    fn path(&self) -> &Path {
        match self {
            Aov::Depth(p) | Aov::Normal(p) | Aov::Id(p) => p,
        }
    }
}

fn parse_texture_filter(s: &str) -> Result<Filter, specula_raster::texture::FilterParseError> {
    s.parse()
}

fn parse_aov(s: &str) -> Result<Aov, String> {
    let (name, path) = s
        .split_once('=')
        .ok_or_else(|| format!("--aov {s}: expected NAME=PATH"))?;
    let path = PathBuf::from(path);
    match name {
        "depth" => Ok(Aov::Depth(path)),
        "normal" => Ok(Aov::Normal(path)),
        "id" => Ok(Aov::Id(path)),
        _ => Err(format!(
            "--aov {s}: unknown AOV {name:?} (depth, normal, id)"
        )),
    }
}

/// Whether the main output's name asks for an HDR format (for the memory
/// estimate; the format itself is checked with the other outputs).
fn is_hdr_name(p: &Path) -> bool {
    ImageFormat::from_path(p).is_ok_and(image_file::is_hdr)
}

fn run_render(a: RenderArgs) -> Result<(), String> {
    let aovs: Vec<Aov> = a
        .aov
        .iter()
        .map(|s| parse_aov(s))
        .collect::<Result<_, _>>()?;
    for (i, a) in aovs.iter().enumerate() {
        if let Some(b) = aovs[..i].iter().find(|b| b.name() == a.name()) {
            return Err(format!(
                "--aov {}: asked twice ({} and {}); one file per AOV",
                a.name(),
                b.path().display(),
                a.path().display()
            ));
        }
    }
    memory::set_limit(a.max_memory.unwrap_or_else(memory::default_limit));
    let t = Instant::now();
    let mut scene = if is_gltf_path(&a.scene) {
        let opts = GltfOptions {
            camera: a.camera,
            env: a.env.clone(),
        };
        load_gltf_scene(&a.scene, &opts)
    } else if a.env.is_some() {
        return Err(format!(
            "--env: {} is a TOML scene, whose environment is its [environment] (map = \"file.hdr\")",
            a.scene.display()
        ));
    } else if a.camera.is_some() {
        return Err(format!(
            "--camera: {} is a TOML scene, whose camera is its [camera]; --camera picks one of a glTF file's",
            a.scene.display()
        ));
    } else {
        load_scene(&a.scene)
    }
    .map_err(|e| e.to_string())?;
    if let Some(f) = a.texture_filter {
        scene.data.force_texture_filter(f);
    }
    let load_ms = t.elapsed().as_secs_f64() * 1e3;
    for w in &scene.warnings {
        eprintln!("warning: {}", truncate_lines(w, MESSAGE_LINE_MAX));
    }
    let mut settings = RenderSettings::from_scene(&scene);
    settings.width = a.width.unwrap_or(settings.width);
    settings.height = a.height.unwrap_or(settings.height);
    settings.ssaa = a.ssaa.unwrap_or(settings.ssaa);
    settings.threads = a.threads;
    settings.repeat = a.repeat;
    settings.path = if a.scalar {
        ShadePath::Scalar
    } else if a.avx2_only {
        ShadePath::SimdAvx2
    } else {
        ShadePath::Simd
    };
    for aov in &aovs {
        match aov {
            Aov::Depth(_) => settings.buffers.depth = true,
            Aov::Normal(_) => settings.buffers.normal = true,
            Aov::Id(_) => settings.buffers.id = true,
        }
    }
    settings.target().map_err(|e| {
        // The scene's own sizes were checked at load: name where each came from.
        let from = |flag: Option<u32>, name: &str| match flag {
            Some(v) => format!("--{name} {v}"),
            None => format!("{}: output.{name}", a.scene.display()),
        };
        format!(
            "{e} (width from {}, height from {}, ssaa from {})",
            from(a.width, "width"),
            from(a.height, "height"),
            from(a.ssaa, "ssaa")
        )
    })?;
    let (w, h, ss) = (
        settings.width as u64,
        settings.height as u64,
        settings.ssaa as u64,
    );
    let hdr_images = a.exr.is_some() as u64 + is_hdr_name(&a.output) as u64;
    // Only HDR outputs read the linear colour after the frame; without
    // them the shading pass may encode the 8-bit image itself.
    settings.keep_hdr = hdr_images > 0;
    memory::reserve(
        &format!("a {w}×{h} image with ssaa {ss}"),
        memory::image_bytes(w * h * ss * ss, w * h, aovs.len() as u64, hdr_images),
    )?;
    let mut outs: Vec<(&str, &Path)> = vec![("-o", &a.output)];
    outs.extend(a.exr.as_deref().map(|p| ("--exr", p)));
    outs.extend(aovs.iter().map(|v| match v {
        Aov::Depth(p) => ("--aov depth", p.as_path()),
        Aov::Normal(p) => ("--aov normal", p.as_path()),
        Aov::Id(p) => ("--aov id", p.as_path()),
    }));
    outs.extend(a.stats_json.as_deref().map(|p| ("--stats-json", p)));
    if a.svg_lines.is_some() && scene.lines.strokes.is_none() {
        return Err(format!(
            "--svg-lines: {} has no [strokes] table to draw",
            a.scene.display()
        ));
    }
    outs.extend(a.svg_lines.as_deref().map(|p| ("--svg-lines", p)));
    let plan = output_plan::plan(&outs, &scene.inputs, Some("-o"))?;
    let main_format = plan[0].image_format(ImageFormat::Png)?;
    for o in &plan[1..] {
        if o.flag != "--aov id"
            && o.flag != "--stats-json"
            && o.flag != "--svg-lines"
            && o.image_format(ImageFormat::OpenExr)? != ImageFormat::OpenExr
        {
            return Err(format!(
                "{} {}: this output is OpenEXR; give the name a .exr extension",
                o.flag,
                o.path.display()
            ));
        }
    }
    let by_flag = |f: &str| plan.iter().find(|o| o.flag == f).expect("planned");

    let mut r = render_scene(&scene, &settings, load_ms)?;
    let t = Instant::now();
    let main_bytes = if image_file::is_hdr(main_format) {
        image_file::encode_hdr(r.width, r.height, &r.hdr(), main_format)?
    } else {
        image_file::encode_ldr(r.width, r.height, std::mem::take(&mut r.ldr), main_format)?
    };
    // Every output is staged before any replaces its file: a failure in a
    // later one (a full disk, an unwritable --stats-json) leaves the
    // earlier files as they were.
    let mut staged = vec![plan[0].stage(&main_bytes)?];
    drop(main_bytes);
    if a.exr.is_some() {
        let bytes = image_file::encode_hdr(r.width, r.height, &r.hdr(), ImageFormat::OpenExr)?;
        staged.push(by_flag("--exr").stage(&bytes)?);
    }
    let (tw, th) = (r.frame.target.width, r.frame.target.height);
    let exr = |rgb: &[[f32; 3]]| image_file::encode_hdr(tw, th, rgb, ImageFormat::OpenExr);
    for aov in &aovs {
        let (flag, bytes) = match aov {
            Aov::Depth(_) => ("--aov depth", exr(&depth_aov(&r.frame)?)?),
            Aov::Normal(_) => ("--aov normal", exr(&normal_aov(&r.frame)?)?),
            Aov::Id(_) => (
                "--aov id",
                image_file::encode_ids(tw, th, id_aov(&r.frame)?),
            ),
        };
        staged.push(by_flag(flag).stage(&bytes)?);
    }
    if let (Some(_), Some(st)) = (&a.svg_lines, &scene.lines.strokes) {
        let lines = st.polylines(&r.frame.buffers, r.ssaa as usize);
        let doc = specula_npr::overlay::svg(&lines, &st.style, r.width, r.height);
        staged.push(by_flag("--svg-lines").stage(doc.as_bytes())?);
    }
    r.stats.encode_ms = t.elapsed().as_secs_f64() * 1e3;
    if a.stats_json.is_some() {
        let json = serde_json::to_string_pretty(&r.stats).map_err(|e| e.to_string())?;
        staged.push(by_flag("--stats-json").stage(json.as_bytes())?);
    }
    output_plan::commit_all(staged)?;
    if a.stats {
        // With the image on standard output, the report goes to stderr.
        if plan[0].sink == output_plan::Sink::Stdout {
            eprint!("{}", r.stats.report());
        } else {
            print!("{}", r.stats.report());
        }
    }
    Ok(())
}

fn run_furnace(a: FurnaceArgs) -> Result<(), String> {
    let curves = furnace::furnace(&a.material, &a.alpha)?;
    for n in curves.iter().flat_map(|c| &c.notes) {
        eprintln!("warning: --material.{n}");
    }
    print!("{}", furnace::table(&curves));
    if let Some(p) = &a.output {
        // Not `-`: the table already goes to standard output.
        let plan = output_plan::plan(&[("-o", p)], &[], None)?;
        if plan[0].image_format(ImageFormat::Png)? != ImageFormat::Png {
            return Err(format!(
                "-o {}: the plot is written as PNG; give the name a .png extension",
                p.display()
            ));
        }
        let png = furnace::plot_png(&curves)?;
        plan[0].write(&png)?;
        eprint!("{}", furnace::legend(&curves));
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}

fn run_tam(a: TamArgs) -> Result<(), String> {
    let mut p = specula_npr::tam::TamParams::new(a.tones, a.size, a.seed);
    if let Some(l) = a.levels {
        p.levels = l;
    }
    let out = &a.output;
    let shown = out.display();
    // The folder is checked, and a new one made beside it, before the map
    // is generated; the map is written there whole and then takes the
    // folder's place, so a failure never leaves a mix of two maps.
    let replacing = match std::fs::metadata(out) {
        Ok(m) if !m.is_dir() => return Err(format!("-o {shown}: exists and is not a folder")),
        Ok(_) => {
            let foreign = std::fs::read_dir(out)
                .map_err(|e| format!("-o {shown}: {e}"))?
                .filter_map(|e| e.ok())
                .any(|e| {
                    let name = e.file_name().to_string_lossy().into_owned();
                    !(name == "tam.json" || name.starts_with("tam_t") && name.ends_with(".png"))
                });
            if foreign {
                return Err(format!(
                    "-o {shown}: the folder holds files that are not a tonal art map's; refusing to replace it"
                ));
            }
            true
        }
        Err(_) => false,
    };
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let staging = tempfile::Builder::new()
        .prefix(".specula-tam-")
        .tempdir_in(parent)
        .map_err(|e| format!("-o {shown}: cannot write into {}: {e}", parent.display()))?;
    // Renamed into place below; until then an interrupt removes it.
    let _interrupted = output_plan::TemporaryDir::track(staging.path());
    let tam = specula_npr::tam::generate(p).map_err(|e| format!("tam: {e}"))?;
    tam.write_dir(staging.path()).map_err(|e| e.to_string())?;
    if replacing {
        let old = tempfile::Builder::new()
            .prefix(".specula-tam-old-")
            .tempdir_in(parent)
            .map_err(|e| format!("-o {shown}: {e}"))?;
        let old_path = old.path().join("map");
        std::fs::rename(out, &old_path).map_err(|e| format!("-o {shown}: {e}"))?;
        if let Err(e) = std::fs::rename(staging.path(), out) {
            let _ = std::fs::rename(&old_path, out);
            return Err(format!("-o {shown}: {e}"));
        }
    } else {
        std::fs::rename(staging.path(), out).map_err(|e| format!("-o {shown}: {e}"))?;
    }
    // The staging folder was private (0700); a map folder is an ordinary one.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(out, std::fs::Permissions::from_mode(0o755))
            .map_err(|e| format!("-o {shown}: {e}"))?;
    }
    let m = tam.manifest();
    for (t, d) in m.darkness.iter().enumerate() {
        let levels: Vec<String> = m.measured[t].iter().map(|v| format!("{v:.3}")).collect();
        println!("tone {t}: darkness {d:.3}, measured {}", levels.join(" "));
    }
    println!("wrote {}", a.output.display());
    Ok(())
}

fn run_demo() -> Result<(), String> {
    let t = Instant::now();
    let scene = demo::demo_scene().map_err(|e| e.to_string())?;
    let load_ms = t.elapsed().as_secs_f64() * 1e3;
    let settings = RenderSettings::from_scene(&scene);
    let out = PathBuf::from("specula-demo.png");
    let plan = output_plan::plan(&[("demo", &out)], &[], None)?;
    let mut r = render_scene(&scene, &settings, load_ms)?;
    let t = Instant::now();
    plan[0].write(&image_file::encode_ldr(
        r.width,
        r.height,
        std::mem::take(&mut r.ldr),
        ImageFormat::Png,
    )?)?;
    r.stats.encode_ms = t.elapsed().as_secs_f64() * 1e3;
    print!("{}", r.stats.report());
    let shown = std::fs::canonicalize(&out).unwrap_or(out);
    println!("wrote {}", shown.display());
    Ok(())
}

fn run_batch(a: specula::batch::BatchArgs) -> Result<(), String> {
    let o = specula::batch::run(&a, true)?;
    println!(
        "{} rendered, {} up to date, {} failed; manifest {}",
        o.rendered.len(),
        o.skipped.len(),
        o.failed.len(),
        o.manifest.display()
    );
    for (scene, e) in &o.failed {
        eprintln!(
            "error: {scene}: {}",
            truncate_lines(&e.to_string(), MESSAGE_LINE_MAX)
        );
    }
    if o.failed.is_empty() {
        Ok(())
    } else {
        Err(format!("{} scene(s) failed", o.failed.len()))
    }
}

/// On SIGINT, SIGTERM or SIGHUP, removes the temporary files of outputs
/// being written (no destructor runs when a signal ends the process) and
/// exits with 128 + the signal number the shell reports for SIGINT.
fn remove_temporaries_on_interrupt() {
    let installed = ctrlc::set_handler(|| {
        output_plan::remove_temporaries();
        std::process::exit(130);
    });
    if let Err(e) = installed {
        eprintln!("warning: no signal handler ({e}): an interrupted run may leave temporary files");
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    specula::table_cache::install();
    remove_temporaries_on_interrupt();
    let result = match cli.command {
        Some(Command::Diff(a)) => {
            return match specula::diff::run(&a) {
                Ok(specula::diff::Verdict::Pass) => ExitCode::SUCCESS,
                Ok(specula::diff::Verdict::Fail) => ExitCode::from(1),
                Err(e) => {
                    eprintln!(
                        "error: {}",
                        truncate_lines(&e.to_string(), MESSAGE_LINE_MAX)
                    );
                    ExitCode::from(2)
                }
            }
        }
        Some(Command::Batch(a)) => run_batch(a),
        Some(Command::Sky(a)) => {
            specula::sky::write_sky(&a.output, a.width).map_err(|e| e.to_string())
        }
        None => run_demo(),
        Some(Command::Render(a)) => run_render(a),
        Some(Command::Furnace(a)) => run_furnace(a),
        Some(Command::Tam(a)) => run_tam(a),
        Some(Command::FitLtc(a)) => fit_ltc::run(&a.output, &fit_ltc::Options { check: a.check }),
        Some(Command::FitLtcCoat(a)) => fit_ltc_coat::run(&a.output),
        Some(Command::KcTables(a)) => {
            specula::table_cache::write_committed(&a.output).map_err(|e| e.to_string())
        }
        Some(Command::Eval) => {
            let stdin = std::io::stdin().lock();
            let stdout = std::io::BufWriter::new(std::io::stdout().lock());
            specula::eval::run(stdin, stdout).map_err(|e| format!("eval: {e}"))
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", truncate_lines(&e, MESSAGE_LINE_MAX));
            ExitCode::FAILURE
        }
    }
}
