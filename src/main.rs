//! `kiln`: the command line. Renders scene files, lists adapters, runs benchmarks.
//! Errors reach the user as one message with its causes and a non-zero exit code
//! (2 for usage errors, 1 for everything else), never as a panic.

use std::cell::Cell;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use clap::builder::TypedValueParser as _;
use clap::{Parser, Subcommand, ValueEnum};
use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use kiln::plugin::{ExportFilm, Isolation, PluginHost, PluginKind};

use kiln::farm::part::PartHeader;
use kiln::film::output::{ViewSettings, write_image};
use kiln::film::tonemap::Tonemap;
use kiln::limits::Limits;
use kiln::render::checkpoint::{self, Checkpoint};
use kiln::render::{
    Backend, GpuContext, RenderControl, RenderSettings, RenderStats, Renderer, context,
};
use kiln::scene::{self, Denoiser, Quality, Scene, lookdev};
use kiln::shader::sampling::{FilterKind, PixelFilter, Sampler};

#[derive(Parser)]
#[command(name = "kiln", version, about = "A physically based GPU path tracer")]
struct Cli {
    /// Graphics API to run on (default: the best the system offers).
    #[arg(long, global = true, value_enum)]
    backend: Option<BackendArg>,
    /// Also load plugins from this folder (searched before $KILN_PLUGIN_PATH and the
    /// folder of the executable); may be given several times.
    #[arg(long = "plugin-dir", global = true, value_name = "DIR")]
    plugin_dirs: Vec<PathBuf>,
    /// Run importer plugins in a separate process, so that one that crashes or hangs fails
    /// its import instead of taking Kiln down (the editor always does).
    #[arg(long, global = true)]
    isolate_importers: bool,
    /// Seconds an isolated import may take before it is stopped.
    #[arg(long, global = true, default_value_t = 600.0, value_name = "SECS")]
    import_timeout: f64,
    /// The largest width or height of an image texture read (an environment map may be
    /// this wide and half as high); larger files are refused before decoding.
    #[arg(long, global = true, value_name = "TEXELS", default_value_t = Limits::DEFAULT.texture_size,
          value_parser = clap::value_parser!(u32).range(1..))]
    max_texture_size: u32,
    /// The most vertices, and triangles, one import may hand over (importer plugins refuse
    /// larger counts before reading them) or a scene file's meshes may hold together.
    #[arg(long, global = true, value_name = "N", default_value_t = Limits::DEFAULT.triangles,
          value_parser = clap::value_parser!(u64).range(1..))]
    max_triangles: u64,
    /// The most nodes a material graph may expand to, every use of a group counted with
    /// its nodes.
    #[arg(long, global = true, value_name = "N", default_value_t = Limits::DEFAULT.graph_nodes)]
    max_graph_nodes: usize,
    /// How deep node groups may nest.
    #[arg(long, global = true, value_name = "N", default_value_t = Limits::DEFAULT.group_depth)]
    max_group_depth: usize,
    #[command(subcommand)]
    command: Command,
}

/// What an imported model without lights stands on (the look-dev default).
#[derive(Clone, Copy, ValueEnum)]
enum GroundArg {
    /// Nothing: the model floats in the sky.
    None,
    /// A matte grey plane under the model's bounds, which its shadow falls on.
    Plane,
    /// The plane as a shadow catcher: the image holds the model and its shadow as alpha
    /// over a transparent background (write an EXR to keep the alpha).
    Catcher,
}

impl From<GroundArg> for lookdev::Ground {
    fn from(g: GroundArg) -> Self {
        match g {
            GroundArg::None => lookdev::Ground::None,
            GroundArg::Plane => lookdev::Ground::Plane,
            GroundArg::Catcher => lookdev::Ground::Catcher,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum BackendArg {
    Vulkan,
    Gl,
    Metal,
    Dx12,
}

impl From<BackendArg> for Backend {
    fn from(b: BackendArg) -> Self {
        match b {
            BackendArg::Vulkan => Backend::Vulkan,
            BackendArg::Gl => Backend::Gl,
            BackendArg::Metal => Backend::Metal,
            BackendArg::Dx12 => Backend::Dx12,
        }
    }
}

/// The values of a flag choosing one of `all` by its key (as scene files spell it):
/// `--tonemap`, `--sampler`, `--filter`.
fn key_parser<T: Copy + Send + Sync + 'static>(
    all: &'static [T],
    key: fn(T) -> &'static str,
) -> impl clap::builder::TypedValueParser<Value = T> {
    clap::builder::PossibleValuesParser::new(all.iter().map(|&t| key(t))).map(move |k| {
        *all.iter()
            .find(|&&t| key(t) == k)
            .expect("clap accepts only the listed keys")
    })
}

/// `--filter-width`: pixels in (0, MAX_FILTER_WIDTH].
fn parse_filter_width(s: &str) -> Result<f32, String> {
    let width: f32 = s
        .trim()
        .parse()
        .map_err(|_| format!("\"{s}\" is not a number of pixels"))?;
    PixelFilter {
        kind: FilterKind::Box,
        width,
    }
    .validate()?;
    Ok(width)
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to an image (the bundled Cornell box when no scene is given).
    Render(RenderArgs),
    /// Open the editor: a live path-traced viewport, outliner and inspector, on a .kiln
    /// scene, a file an importer plugin reads, or the bundled Cornell box.
    Edit {
        /// A .kiln scene or a file an importer reads (.gltf, .glb, .obj, …).
        file: Option<PathBuf>,
        /// Samples per pixel the viewport accumulates before it rests.
        /// [default: the last one chosen in the Render tab, else 1024]
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
        samples: Option<u32>,
        /// Close the window once the viewport holds --samples samples and print what it
        /// rendered (smoke tests, scripted screenshots); fails if the viewport failed.
        #[arg(long)]
        quit_when_done: bool,
        /// Screen pixels per viewport pixel along each axis (1, 2, 4 or 8): 2 renders a
        /// quarter of the pixels, for slow adapters; also in the Render tab. [default: the
        /// last one chosen there, else 1]
        #[arg(long, value_parser = parse_pixel_size)]
        pixel_size: Option<u32>,
    },
    /// List the GPU adapters and the one Kiln would use.
    Info,
    /// Measure samples/s, rays/s and BVH build time; prints a Markdown table.
    Bench(kiln::bench::BenchArgs),
    /// List the importer and exporter plugins found, and the libraries refused.
    Plugins,
    /// Convert a file an importer plugin reads (glTF, OBJ, …) into a Kiln scene.
    Import {
        file: PathBuf,
        /// The scene file to write; meshes and images go to `<stem>.assets/` beside it.
        #[arg(short, long)]
        output: PathBuf,
        /// What a model that brings no lights stands on under the look-dev sky.
        #[arg(long, value_enum, default_value_t = GroundArg::Plane)]
        ground: GroundArg,
    },
    /// The worker of an isolated import: imports FILE in this process and writes the
    /// calls the importer made to standard output, for the Kiln that started it.
    #[command(hide = true)]
    ImportWorker { file: PathBuf },
    /// Check material graphs (.kmat) and show the WGSL they compile to.
    #[command(subcommand)]
    Material(MaterialCommand),
    /// Merge the parts of a split render (`kiln render --samples A..B -o part.exr`) into
    /// one image, bit for bit the image one process rendering every sample writes.
    Merge {
        /// The parts: OpenEXR files `kiln render --samples` wrote.
        #[arg(required = true)]
        parts: Vec<PathBuf>,
        /// The merged image (any format a writer has: .exr, .png, …).
        #[arg(short, long)]
        output: PathBuf,
        /// Merge the parts there are when sample ranges are missing (and say which).
        #[arg(long)]
        allow_partial: bool,
        /// Options for the image writer, as for `kiln render`.
        #[arg(long, default_value = "")]
        export_options: String,
    },
    /// Render on a cluster: Slurm job arrays of parts and frames, merged exactly
    /// (docs/SCALE_OUT.md).
    #[command(subcommand)]
    Farm(FarmCommand),
}

#[derive(Subcommand)]
enum FarmCommand {
    /// Write a Slurm job array that renders SCENE in parts (and frames), and a merge job
    /// that depends on it, into a farm folder; --submit submits both.
    Slurm {
        /// A .kiln scene (the bundled Cornell box when none is given).
        scene: Option<PathBuf>,
        /// Parts each frame's samples are split into: one array task each.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100_000))]
        parts: u32,
        /// Samples per pixel (default: the scene's).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
        spp: Option<u32>,
        // A turntable: one task per frame and part.
        #[command(flatten)]
        animation: AnimationArgs,
        /// The merged image; with frames, `#`s in its name become the frame number.
        #[arg(short, long)]
        output: PathBuf,
        /// The farm folder, on storage every node sees [default: beside the output, named
        /// after it: shot_####.png → shot.farm].
        #[arg(long)]
        dir: Option<PathBuf>,
        /// An #SBATCH option of both jobs (`--partition=gpu`, `--time=2:00:00`); may be
        /// given several times.
        #[arg(long = "sbatch-arg", value_name = "OPTION", allow_hyphen_values = true)]
        sbatch_args: Vec<String>,
        /// Submit the jobs with sbatch (else print the commands that do).
        #[arg(long)]
        submit: bool,
        /// `kiln render` flags every task passes, after `--` (`-- --size 1920x1080`).
        #[arg(last = true)]
        render_args: Vec<String>,
    },
    /// Show which parts are rendered, queued, or missing (failed or cancelled tasks, with
    /// their sample ranges); fails while parts are missing.
    Status {
        /// The farm folder `kiln farm slurm` wrote.
        dir: PathBuf,
    },
    /// Submit again only the tasks whose parts are missing, and a new merge job.
    Resubmit {
        /// The farm folder `kiln farm slurm` wrote.
        dir: PathBuf,
    },
}

#[derive(Subcommand)]
enum MaterialCommand {
    /// Compile a material and validate the kernel it makes; prints OK or the error.
    Check { file: PathBuf },
    /// Print the complete path-tracing kernel with the material spliced in.
    Wgsl {
        file: PathBuf,
        /// Print only the material's own function(s).
        #[arg(long)]
        snippet: bool,
    },
    /// Print the node reference (docs/NODES.md) generated from the node library.
    Nodes,
    /// Read the materials of a material file (MaterialX `.mtlx`, through a material-format
    /// plugin) and write each as a `.kmat` file in a folder; warnings name what could not
    /// be represented.
    Import {
        file: PathBuf,
        /// The folder the `.kmat` files are written to (made if missing).
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Write a `.kmat` material in another format (MaterialX `.mtlx`), through a
    /// material-format plugin.
    Export {
        file: PathBuf,
        /// The file to write; its extension picks the format.
        #[arg(short, long)]
        output: PathBuf,
    },
}

/// A turntable's frames, as `kiln render` and `kiln farm slurm` take them.
#[derive(clap::Args)]
struct AnimationArgs {
    /// The frames A..B (B excluded) of a turntable.
    #[arg(long, value_name = "A..B", value_parser = kiln::farm::part::parse_range, requires = "turntable")]
    frames: Option<std::ops::Range<u32>>,
    /// Degrees the camera orbits its target (about its up axis) over --frames.
    #[arg(
        long,
        value_name = "DEGREES",
        allow_hyphen_values = true,
        requires = "frames"
    )]
    turntable: Option<f32>,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// A .kiln scene file.
    scene: Option<PathBuf>,
    /// Output image: .png, .jpg or .exr (linear float).
    #[arg(short, long, default_value = "out.png")]
    output: PathBuf,
    /// Samples per pixel (default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    spp: Option<u32>,
    /// Maximum number of bounces (default: the scene's).
    #[arg(long)]
    max_bounces: Option<u32>,
    /// Scattering events in volumes per path, past which media only absorb (default: the
    /// scene's, or as many as the bounces allow).
    #[arg(long, value_name = "N")]
    max_volume_bounces: Option<u32>,
    /// Grid points along the longest side of a heterogeneous volume (a graph-driven
    /// density), which is baked into a grid of this resolution before rendering: finer
    /// keeps more detail and costs memory and bake time (default: the scene's, or 128).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(8..=1024))]
    volume_resolution: Option<u32>,
    /// Image size as WIDTHxHEIGHT (default: the scene's).
    #[arg(long, value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// Firefly clamp of direct light: the most one sample's light that scattered at most
    /// once may add, its colour kept; cuts noise from small bright lights at the cost of
    /// darker highlights (default: the scene's, or 0: off).
    #[arg(long, value_name = "RADIANCE", value_parser = parse_clamp)]
    clamp_direct: Option<f32>,
    /// Firefly clamp of indirect light (scattered twice or more): cuts fireflies from
    /// caustics and glossy bounces at the cost of darker ones (default: the scene's, or 0:
    /// off).
    #[arg(long, value_name = "RADIANCE", value_parser = parse_clamp)]
    clamp_indirect: Option<f32>,
    /// Adaptive sampling: a pixel stops taking samples once its estimated noise is below
    /// this (checked from 16 spp on; 0.01 is fine, 0.05 a preview), so the samples go
    /// where noise remains; --spp and --time-limit still bound the render. The noise is
    /// the 90 % confidence half-width of the pixel's r+g+b over the square root of its
    /// value; an EXR output gets it as the `noise` layer (default: the scene's, or 0:
    /// off).
    #[arg(long, value_name = "T", allow_hyphen_values = true, value_parser = parse_noise_threshold)]
    noise_threshold: Option<f32>,
    /// Denoise the image before writing it: atrous is an edge-avoiding filter guided by
    /// the albedo, normal and depth and by each pixel's noise; an EXR keeps the image as
    /// rendered as its `noisy` layer (default: the scene's, or none).
    #[arg(long, value_parser = key_parser(&Denoiser::ALL, Denoiser::key))]
    denoise: Option<Denoiser>,
    /// A preset of the samples, bounces, clamp, noise threshold and denoiser, chosen from
    /// measurements (docs/BENCHMARKS.md); flags given beside it win.
    #[arg(long, value_parser = key_parser(&Quality::ALL, Quality::key), long_help = quality_help())]
    quality: Option<Quality>,
    /// Render only the sample indices A..B (B excluded) of every pixel, as the part of a
    /// split render: the output must be .exr and keeps the exact sums and a header for
    /// `kiln merge`. --spp is the whole render's samples per pixel.
    #[arg(long, value_name = "A..B", value_parser = kiln::farm::part::parse_range)]
    samples: Option<std::ops::Range<u32>>,
    // A turntable, its frames each written to OUTPUT with its frame number (`#`s in the
    // name, else `_NNNN` before the extension).
    #[command(flatten)]
    animation: AnimationArgs,
    /// Render only this frame of --frames.
    #[arg(long, requires = "frames")]
    frame: Option<u32>,
    /// Seed of the random sequence; the same seed gives the same image (default: the
    /// scene's, or 0).
    #[arg(long)]
    seed: Option<u32>,
    /// Where each path's random numbers come from: Owen-scrambled Sobol' points, stratified
    /// over a pixel's samples, or independent ones (default: the scene's, or sobol).
    #[arg(long, value_parser = key_parser(&Sampler::ALL, Sampler::key))]
    sampler: Option<Sampler>,
    /// The pixel filter samples are drawn from (default: the scene's, or blackman-harris).
    #[arg(long, value_parser = key_parser(&FilterKind::ALL, FilterKind::key))]
    filter: Option<FilterKind>,
    /// The pixel filter's width in pixels (default: the scene's, or 1.5).
    #[arg(long, value_name = "PIXELS", value_parser = parse_filter_width)]
    filter_width: Option<f32>,
    /// Exposure in stops (EV) applied before tonemapping (default: the scene's, or 0).
    #[arg(long, allow_hyphen_values = true)]
    exposure: Option<f32>,
    /// View transform from scene radiance to display (default: the scene's, or agx).
    #[arg(long, value_parser = key_parser(&Tonemap::ALL, Tonemap::key))]
    tonemap: Option<Tonemap>,
    /// What an imported model that brings no lights stands on, under the look-dev sky
    /// and sun it gets: a matte grey plane under its bounds, nothing, or the plane as a
    /// shadow catcher (the model and its shadow as alpha over a transparent background).
    #[arg(long, value_enum, default_value_t = GroundArg::Plane)]
    ground: GroundArg,
    /// Stop after this many seconds and write what has accumulated.
    #[arg(long)]
    time_limit: Option<f64>,
    /// Write a checkpoint of the film so far next to the output (OUT.kiln-checkpoint)
    /// every this many seconds, at the end of a pass, for --resume; 0: never. It is
    /// removed once the whole render is written.
    #[arg(long, value_name = "SECS", default_value_t = 60.0)]
    checkpoint_every: f64,
    /// Continue from the checkpoint next to the output: the same scene and settings (--spp
    /// may be higher), and the image is bit for bit the one an uninterrupted render makes.
    #[arg(long)]
    resume: bool,
    /// Environment: a uniform radiance R,G,B or an equirectangular .hdr/.exr map
    /// (overrides the scene's).
    #[arg(long, value_parser = parse_environment)]
    environment: Option<EnvironmentArg>,
    /// Sample BSDFs only, without next-event estimation (a reference for MIS).
    #[arg(long)]
    no_light_sampling: bool,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
    /// Options for the image writer (an exporter plugin, or the host's own for PNG, JPEG
    /// and EXR), `key=value;…` (PNG: `bits=16`; JPEG: `quality=90`; EXR:
    /// `compression=zip|piz|none`).
    #[arg(long, default_value = "")]
    export_options: String,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, e.g. 800x600, got \"{s}\""))?;
    let parse = |v: &str| -> Result<u32, String> {
        match v.trim().parse::<u32>() {
            Ok(n) if (1..=16384).contains(&n) => Ok(n),
            _ => Err(format!("\"{v}\" is not a size between 1 and 16384")),
        }
    };
    Ok((parse(w)?, parse(h)?))
}

fn parse_clamp(s: &str) -> Result<f32, String> {
    let limit: f32 = s
        .trim()
        .parse()
        .map_err(|_| format!("\"{s}\" is not a number"))?;
    if !(limit.is_finite() && limit >= 0.0) {
        return Err(format!(
            "a clamp is 0 (off) or a finite radiance above 0, got {s}"
        ));
    }
    Ok(limit)
}

/// `--quality`'s long help: what each preset sets, from the presets themselves.
fn quality_help() -> String {
    let mut help = String::from(
        "A preset of the samples, bounces, clamp, noise threshold and denoiser, chosen from \
         measurements (docs/BENCHMARKS.md); flags given beside it win.\n",
    );
    for q in Quality::ALL {
        help.push_str(&format!("\n  {}", q.describe()));
    }
    help
}

fn parse_noise_threshold(s: &str) -> Result<f32, String> {
    let t: f32 = s
        .trim()
        .parse()
        .map_err(|_| format!("\"{s}\" is not a number"))?;
    kiln::scene::validate_noise_threshold(t)?;
    Ok(t)
}

#[derive(Clone, Debug)]
enum EnvironmentArg {
    Uniform(Vec3),
    Map(PathBuf),
}

fn parse_environment(s: &str) -> Result<EnvironmentArg, String> {
    let lower = s.to_ascii_lowercase();
    if lower.ends_with(".hdr") || lower.ends_with(".exr") {
        return Ok(EnvironmentArg::Map(PathBuf::from(s)));
    }
    parse_rgb(s)
        .map(EnvironmentArg::Uniform)
        .map_err(|e| format!("{e}, or a .hdr / .exr file"))
}

fn parse_rgb(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("expected R,G,B, e.g. 0.5,0.5,0.5, got \"{s}\""));
    }
    let mut rgb = [0.0f32; 3];
    for (c, p) in rgb.iter_mut().zip(parts) {
        *c = p
            .trim()
            .parse()
            .ok()
            .filter(|v: &f32| v.is_finite() && *v >= 0.0)
            .ok_or_else(|| format!("\"{p}\" is not a finite non-negative number"))?;
    }
    Ok(Vec3::from(rgb))
}

/// Gives the process a private runtime directory when the session has none (a headless
/// machine, a CI job, a farm node). Mesa's window-system code looks for one on every device
/// creation and otherwise prints "Error: XDG_RUNTIME_DIR is invalid or not set", the first
/// line a newcomer would read, although compute needs no window system. Only an unset or
/// missing directory is replaced; one per user, private (0700), reused across runs.
#[cfg(unix)]
fn ensure_runtime_dir() {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
    if std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| Path::new(&d).is_dir()) {
        return;
    }
    let Ok(uid) = std::fs::metadata("/proc/self").map(|m| m.uid()) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("kiln-runtime-{uid}"));
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    // Use it only if it is ours and private (not one another user planted).
    let usable = std::fs::symlink_metadata(&dir)
        .is_ok_and(|m| m.is_dir() && m.uid() == uid && m.permissions().mode() & 0o077 == 0);
    if usable {
        // SAFETY: called first thing in main, before any other thread exists.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
    }
}

/// One of [`kiln::editor::PIXEL_SIZES`].
fn parse_pixel_size(s: &str) -> std::result::Result<u32, String> {
    s.parse()
        .ok()
        .filter(|n| kiln::editor::PIXEL_SIZES.contains(n))
        .ok_or_else(|| format!("the pixel size is one of {:?}", kiln::editor::PIXEL_SIZES))
}

/// Opens the editor's window; returns when it is closed. The editor picks its adapter as
/// wgpu does for a window (`WGPU_BACKEND` chooses the API).
fn edit(
    file: Option<PathBuf>,
    samples: Option<u32>,
    pixel_size: Option<u32>,
    quit_when_done: bool,
    plugins: PluginHost,
) -> Result<()> {
    report_editor_panics();
    let import_extensions = plugins
        .plugins()
        .filter(|p| p.kind == PluginKind::Importer)
        .flat_map(|p| p.extensions.clone())
        .collect();
    let report = kiln::editor::run(kiln::editor::EditorOptions {
        file,
        dialogs: Box::new(kiln::editor::NativeDialogs { import_extensions }),
        plugins,
        sample_limit: samples,
        state_dir: kiln::editor::session::SessionStore::default_dir(),
        autosave_every: kiln::editor::AUTOSAVE_EVERY,
        quit_when_done,
        thumbnails: true,
        graph_kernels: kiln::editor::GRAPH_KERNELS,
        pixel_size,
        on_device_lost: Box::new(restart_after_device_loss),
        restarted_after_device_loss: restarted_after_device_loss(),
        rehearse_compiles: true,
    })
    .map_err(|e| anyhow::anyhow!("the editor's window failed: {e}"))?;
    if let Some(error) = report.error {
        bail!("the viewport failed: {error}");
    }
    if quit_when_done {
        eprintln!(
            "viewport: {} spp at {}x{}, {:.0} k samples/s on {}",
            report.samples,
            report.size[0],
            report.size[1],
            report.samples_per_second / 1e3,
            report.adapter
        );
    }
    Ok(())
}

/// `kiln edit`'s panic report: one `error:` line naming where the editor failed, since the
/// editor, dropped as the panic unwinds, then says what it kept (the recovery autosave)
/// and, when the GPU device was lost under egui's renderer (whose panic eframe cannot
/// catch), starts again. `RUST_BACKTRACE` set keeps Rust's own report, backtrace and all.
fn report_editor_panics() {
    if std::env::var_os("RUST_BACKTRACE").is_some() {
        return;
    }
    std::panic::set_hook(Box::new(|info| {
        let message = info
            .payload()
            .downcast_ref::<&str>()
            .copied()
            .or_else(|| info.payload().downcast_ref::<String>().map(String::as_str))
            .unwrap_or("no message");
        eprintln!("{}", panic_line(message, info.location()));
    }));
}

/// The line [`report_editor_panics`] prints.
fn panic_line(message: &str, location: Option<&std::panic::Location<'_>>) -> String {
    let at = location.map_or(String::new(), |l| {
        format!(" at {}:{}", source_file(l.file()), l.line())
    });
    format!("error: the editor failed{at}: {message}")
}

/// A dependency's source file by its crate and path, without the registry's folders.
fn source_file(file: &str) -> String {
    match file.rsplit_once("/src/") {
        Some((krate, path)) => {
            let krate = krate.rsplit('/').next().unwrap_or(krate);
            format!("{krate}/src/{path}")
        }
        None => file.to_owned(),
    }
}

/// Set in the environment of an editor started again after a lost device: the reason,
/// and the process id of the editor it replaces.
const DEVICE_LOST_ENV: &str = "KILN_DEVICE_LOST";
const DEVICE_LOST_PID_ENV: &str = "KILN_DEVICE_LOST_PID";

/// `kiln edit`'s answer to a lost GPU device (`EditorOptions::on_device_lost`): the
/// window cannot draw again on that device, so this process starts a new editor on the
/// same file (with a new device; its unsaved changes offered from the recovery autosave
/// just written) and ends. An editor that was itself started after a loss does not start
/// another: it ends, saying where the document is.
fn restart_after_device_loss(lost: kiln::editor::DeviceLost) {
    let kept = if lost.autosaved {
        "unsaved changes are in the recovery autosave"
    } else {
        "no unsaved changes"
    };
    eprintln!("error: the GPU device was lost ({}); {kept}", lost.reason);
    if std::env::var_os(DEVICE_LOST_ENV).is_some() {
        eprintln!(
            "the editor had already been started again after a lost device: run kiln edit to recover"
        );
        std::process::exit(1);
    }
    let restart = std::env::current_exe().and_then(|exe| {
        let mut command = std::process::Command::new(exe);
        command.arg("edit").args(lost.file.as_ref());
        command
            .env(DEVICE_LOST_ENV, &lost.reason)
            .env(DEVICE_LOST_PID_ENV, std::process::id().to_string())
            .spawn()
    });
    match restart {
        Ok(_) => {
            eprintln!("starting the editor again");
            std::process::exit(0);
        }
        Err(e) => {
            eprintln!("cannot start the editor again ({e}): run kiln edit to recover");
            std::process::exit(1);
        }
    }
}

/// In an editor started by [`restart_after_device_loss`]: why the last one lost its
/// device, once that editor has ended (so that its autosave counts as left behind and is
/// offered). None in any other editor.
fn restarted_after_device_loss() -> Option<String> {
    let reason = std::env::var(DEVICE_LOST_ENV).ok()?;
    if let Some(pid) = std::env::var(DEVICE_LOST_PID_ENV)
        .ok()
        .and_then(|p| p.parse().ok())
    {
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(5);
        while kiln::editor::session::process_is_running(pid) && std::time::Instant::now() < deadline
        {
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
    }
    Some(reason)
}

fn main() -> ExitCode {
    #[cfg(unix)]
    ensure_runtime_dir();
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_env("KILN_LOG")
                // wgpu-hal's EGL loader logs an error for each display platform it tries
                // before the one that works (DRI2 on a machine without a GPU); a GL backend
                // that fails altogether is Kiln's own error ("no usable GPU adapter").
                // KILN_LOG=debug shows them.
                .unwrap_or_else(|_| {
                    tracing_subscriber::EnvFilter::new("warn,wgpu_hal::gles::egl=off")
                }),
        )
        .with_writer(std::io::stderr)
        .init();
    let cli = Cli::parse();
    kiln::limits::set(Limits {
        texture_size: cli.max_texture_size,
        triangles: cli.max_triangles,
        graph_nodes: cli.max_graph_nodes,
        group_depth: cli.max_group_depth,
    });
    // SAFETY: no other thread runs yet. Importer plugins, here or in an isolated worker
    // (which inherits it), read the limit from the environment.
    unsafe {
        std::env::set_var(
            kiln_plugin_api::MAX_TRIANGLES_ENV,
            cli.max_triangles.to_string(),
        )
    };
    let backend = cli.backend.map(Backend::from);
    if !(cli.import_timeout.is_finite() && cli.import_timeout > 0.0) {
        eprintln!(
            "error: --import-timeout must be a positive number of seconds, got {}",
            cli.import_timeout
        );
        return ExitCode::FAILURE;
    }
    let isolated_plugins = || {
        let mut host = PluginHost::discover(&cli.plugin_dirs);
        match std::env::current_exe() {
            Ok(exe) => host.isolate_importers(Isolation {
                exe,
                plugin_dirs: cli.plugin_dirs.clone(),
                timeout: Duration::from_secs_f64(cli.import_timeout),
            }),
            Err(e) => eprintln!("warning: importers run in this process: {e}"),
        }
        host
    };
    let plugins = || {
        if cli.isolate_importers {
            isolated_plugins()
        } else {
            PluginHost::discover(&cli.plugin_dirs)
        }
    };
    let result = match cli.command {
        Command::Render(args) => render(args, backend, &plugins()),
        Command::Edit {
            file,
            samples,
            quit_when_done,
            pixel_size,
        } => edit(
            file,
            samples,
            pixel_size,
            quit_when_done,
            isolated_plugins(),
        ),
        Command::Plugins => list_plugins(&plugins()),
        Command::Import {
            file,
            output,
            ground,
        } => import(&plugins(), &file, &output, ground.into()),
        Command::ImportWorker { file } => {
            let stream = PluginHost::discover(&cli.plugin_dirs).import_recorded(&file);
            std::io::stdout()
                .lock()
                .write_all(&stream)
                .context("cannot send the import to Kiln")
        }
        Command::Info => info(backend),
        Command::Bench(args) => kiln::bench::run(&args, backend, &mut std::io::stdout()),
        Command::Material(command) => material(command, &plugins()),
        Command::Merge {
            parts,
            output,
            allow_partial,
            export_options,
        } => merge(&parts, &output, allow_partial, &export_options, &plugins()),
        Command::Farm(command) => farm(command, &plugins()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// A material file compiled as material 0 of a scene, and the kernel it makes.
fn compile_material_file(
    file: &std::path::Path,
) -> Result<(String, kiln::material::CompiledMaterial, String)> {
    use kiln::material::{compile, load_material, materials_wgsl};
    use kiln::render::kernel::path_tracing_kernel;
    use kiln::shader::KernelFeatures;
    let (name, graph) = load_material(file)?;
    let compiled = compile(&name, &graph, "material_0")?;
    let kernel = path_tracing_kernel(
        &KernelFeatures::default(),
        &materials_wgsl(&[(0, &compiled)]),
    );
    kernel.validate()?;
    Ok((name, compiled, kernel.text))
}

fn material(command: MaterialCommand, plugins: &PluginHost) -> Result<()> {
    use kiln::material::relative_files;
    match command {
        MaterialCommand::Import { file, output } => {
            let imported = plugins.import_materials(&file)?;
            for warning in &imported.warnings {
                eprintln!("warning: {warning}");
            }
            if imported.materials.is_empty() {
                anyhow::bail!("{} holds no material Kiln can read", file.display());
            }
            std::fs::create_dir_all(&output)
                .with_context(|| format!("cannot make the folder {}", output.display()))?;
            let mut written = Vec::new();
            for (name, mut graph) in imported.materials {
                relative_files(&mut graph, &output);
                let stem: String = name
                    .chars()
                    .map(|c| {
                        if c.is_alphanumeric() || c == '-' {
                            c
                        } else {
                            '_'
                        }
                    })
                    .collect();
                let mut path = output.join(format!("{stem}.kmat"));
                for n in 2.. {
                    if !written.contains(&path) {
                        break;
                    }
                    path = output.join(format!("{stem}_{n}.kmat"));
                }
                kiln::material::save_material(&path, &name, &graph)?;
                println!("{}", path.display());
                written.push(path);
            }
        }
        MaterialCommand::Export { file, output } => {
            let (name, mut graph) = kiln::material::load_material(&file)?;
            // Compiled first: a graph Kiln cannot render is not handed to other tools.
            kiln::material::compile(&name, &graph, "material_0")
                .with_context(|| format!("{} does not compile", file.display()))?;
            let folder = match output.parent() {
                Some(p) if !p.as_os_str().is_empty() => p,
                _ => std::path::Path::new("."),
            };
            relative_files(&mut graph, folder);
            plugins.export_material(&output, &name, &graph)?;
            println!("{}", output.display());
        }
        MaterialCommand::Check { file } => {
            let (name, compiled, kernel) = compile_material_file(&file)?;
            println!(
                "OK: material \"{name}\" ({} lines of WGSL; kernel {} lines, validated by naga)",
                compiled.code.lines().count(),
                kernel.lines().count()
            );
        }
        MaterialCommand::Wgsl { file, snippet } => {
            let (_, compiled, kernel) = compile_material_file(&file)?;
            print!("{}", if snippet { &compiled.code } else { &kernel });
        }
        MaterialCommand::Nodes => print!("{}", kiln::material::docs::nodes_markdown()),
    }
    Ok(())
}

fn info(backend: Option<Backend>) -> Result<()> {
    let adapters = context::list_adapters(backend);
    if adapters.is_empty() {
        println!("no adapters found");
    }
    for a in &adapters {
        println!("adapter: {}", context::describe_adapter(a));
    }
    let ctx = GpuContext::new(backend)?;
    println!("would use: {}", ctx.describe());
    let l = ctx.limits();
    println!(
        "limits: storage binding {} MiB, buffer {} MiB, {} storage buffers per stage",
        l.max_storage_buffer_binding_size >> 20,
        l.max_buffer_size >> 20,
        l.max_storage_buffers_per_shader_stage
    );
    Ok(())
}

/// The scene `path` names (an import is staged on `ground` when it brings no lights), or
/// the bundled default, with the name to report it by.
fn load(
    path: Option<&Path>,
    plugins: &PluginHost,
    ground: lookdev::Ground,
) -> Result<(Scene, String)> {
    match path {
        Some(p) if plugins.handles(PluginKind::Importer, p) => {
            let imported = import_file(plugins, p)?;
            let mut scene = imported.scene;
            if !imported.has_lights {
                lookdev::add_ground(&mut scene, ground);
            }
            Ok((scene, p.display().to_string()))
        }
        Some(p) => Ok((scene::load_scene(p)?, p.display().to_string())),
        None => Ok((
            scene::default_scene()?,
            scene::DEFAULT_SCENE_PATH.to_owned(),
        )),
    }
}

fn import_file(plugins: &PluginHost, file: &Path) -> Result<kiln::plugin::Imported> {
    let imported = plugins.import(file)?;
    for w in &imported.warnings {
        eprintln!("warning: {}: {w}", file.display());
    }
    Ok(imported)
}

fn import(plugins: &PluginHost, file: &Path, output: &Path, ground: lookdev::Ground) -> Result<()> {
    let imported = import_file(plugins, file)?;
    let mut scene = imported.scene;
    if !imported.has_lights {
        lookdev::add_ground(&mut scene, ground);
    }
    scene::save_scene(&scene, output, &imported.images)?;
    eprintln!(
        "wrote {}: {} meshes, {} materials, {} instances, {} lights",
        output.display(),
        scene.meshes.len(),
        scene.materials.len(),
        scene.instances.len(),
        scene.lights.len()
    );
    Ok(())
}

fn list_plugins(plugins: &PluginHost) -> Result<()> {
    let mut any = false;
    for p in plugins.plugins() {
        any = true;
        println!(
            "{} {} ({}; .{}): {}",
            p.name,
            p.version,
            p.kind,
            p.extensions.join(", ."),
            p.path.display()
        );
    }
    if !any {
        println!(
            "no plugins found (looked in --plugin-dir, $KILN_PLUGIN_PATH and next to the executable)"
        );
    }
    for r in &plugins.rejected {
        println!("refused {}: {}", r.path.display(), r.reason);
    }
    Ok(())
}

fn render(args: RenderArgs, backend: Option<Backend>, plugins: &PluginHost) -> Result<()> {
    // Which frames, and where each goes.
    let turntable = args
        .animation
        .frames
        .clone()
        .map(|frames| kiln::farm::Turntable {
            degrees: args.animation.turntable.unwrap_or(0.0),
            frames,
        });
    let frames: Vec<Option<u32>> = match (&turntable, args.frame) {
        (Some(t), Some(f)) if !t.frames.contains(&f) => bail!(
            "--frame {f} is not one of --frames {}..{}",
            t.frames.start,
            t.frames.end
        ),
        (Some(_), Some(f)) => vec![Some(f)],
        (Some(t), None) => t.frames.clone().map(Some).collect(),
        (None, _) => vec![None],
    };
    let output_of = |frame: Option<u32>| match frame {
        Some(f) => kiln::farm::frame_path(&args.output, f),
        None => args.output.clone(),
    };
    if args.samples.is_some()
        && !args
            .output
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
    {
        bail!(
            "--samples writes the part of a split render, an OpenEXR file: name the output .exr, not {}",
            args.output.display()
        );
    }
    // Refuse an output that cannot be written before spending minutes on the render.
    check_output(&output_of(frames[0]), plugins, &args.export_options)?;
    if let Some(t) = args.time_limit
        && !(t.is_finite() && t > 0.0)
    {
        bail!("--time-limit must be a positive number of seconds, got {t}");
    }
    if args.exposure.is_some_and(|ev| !ev.is_finite()) {
        bail!("--exposure must be a finite number of stops");
    }
    let (mut scene, name) = load(args.scene.as_deref(), plugins, args.ground.into())?;
    match &args.environment {
        Some(EnvironmentArg::Uniform(colour)) => {
            scene.environment = *colour;
            scene.environment_map = None;
            scene.world = None;
        }
        Some(EnvironmentArg::Map(path)) => {
            let map = kiln::scene::EnvironmentMap::load(path).map_err(|e| {
                anyhow::anyhow!("cannot load environment map {}: {e}", path.display())
            })?;
            scene.environment_map = Some(map);
            scene.world = None;
        }
        None => {}
    }
    if let Some(quality) = args.quality {
        quality.apply(&mut scene.settings);
    }
    let mut settings = RenderSettings::from_scene(&scene);
    if let Some((w, h)) = args.size {
        settings.width = w;
        settings.height = h;
    }
    if let Some(spp) = args.spp {
        settings.samples_per_pixel = spp;
    }
    if let Some(b) = args.max_bounces {
        settings.max_bounces = b;
    }
    if let Some(b) = args.max_volume_bounces {
        settings.max_volume_bounces = b;
    }
    if let Some(r) = args.volume_resolution {
        settings.volume_resolution = r;
    }
    if let Some(seed) = args.seed {
        settings.seed = seed;
    }
    if let Some(limit) = args.clamp_direct {
        settings.clamp.direct = limit;
    }
    if let Some(limit) = args.clamp_indirect {
        settings.clamp.indirect = limit;
    }
    if let Some(t) = args.noise_threshold {
        settings.noise_threshold = t;
    }
    if let Some(sampler) = args.sampler {
        settings.sampling.sampler = sampler;
    }
    if let Some(kind) = args.filter {
        settings.sampling.filter.kind = kind;
    }
    if let Some(width) = args.filter_width {
        settings.sampling.filter.width = width;
    }
    settings.light_sampling = !args.no_light_sampling;
    if let Some(range) = &args.samples {
        part_settings_check(&args, &settings, &scene, range)?;
    }
    // An EXR gets the AOV layers too (whichever writes it: a plugin or the host's writer,
    // which is the plugin's code).
    let denoiser = args.denoise.unwrap_or(scene.settings.denoiser);
    if let Some(why) = denoiser.unavailable() {
        bail!("cannot denoise with {}: {why}", denoiser.key());
    }
    // A shadow catcher's alpha is an AOV too.
    // A part keeps the film alone: only its sums merge exactly.
    settings.aovs = args.samples.is_none()
        && (denoiser != Denoiser::None
            || scene.instances.iter().any(|i| i.shadow_catcher)
            || args
                .output
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("exr")));

    if !(args.checkpoint_every.is_finite() && args.checkpoint_every >= 0.0) {
        bail!(
            "--checkpoint-every must be 0 (never) or a number of seconds, got {}",
            args.checkpoint_every
        );
    }
    let ctx = GpuContext::new(backend)?;
    eprintln!("adapter: {}", ctx.describe());
    let cancel = Arc::new(AtomicBool::new(false));
    {
        let cancel = Arc::clone(&cancel);
        let out_dir = match args.output.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
            _ => PathBuf::from("."),
        };
        // A second Ctrl-C while the partial image is written exits at once, leaving the
        // previous file (if any) as it was and no temporary file behind.
        ctrlc::set_handler(move || {
            if cancel.swap(true, Ordering::SeqCst) {
                kiln_plugin_api::atomic::remove_partial_files(&out_dir);
                std::process::exit(130);
            }
            // The first whole pass may still take a while on a large image.
            eprintln!(
                "\ninterrupted: the image is written once every pixel has a sample (Ctrl-C again quits without writing)"
            );
        })
        .context("cannot install the Ctrl-C handler")?;
    }
    let view = ViewSettings {
        exposure_ev: args.exposure.unwrap_or(scene.settings.view.exposure_ev),
        tonemap: args.tonemap.unwrap_or(scene.settings.view.tonemap),
    };
    let job = RenderJob {
        args: &args,
        ctx: &ctx,
        name: &name,
        settings,
        denoiser,
        view,
        cancel: &cancel,
        plugins,
    };
    for frame in frames {
        let mut scene = scene.clone();
        if let (Some(t), Some(f)) = (&turntable, frame) {
            scene.camera = t.camera(&scene.camera, f);
            eprintln!("frame {f}");
        }
        let part = args.samples.clone().map(|samples| PartHeader {
            samples,
            total_samples: settings.samples_per_pixel,
            seed: settings.seed,
            sampler: settings.sampling.sampler.key().to_owned(),
            scene_hash: kiln::farm::part::scene_hash(&scene),
            settings_hash: kiln::farm::part::settings_hash(&settings),
            frame,
            view,
        });
        job.render_frame(&scene, &output_of(frame), part)?;
        if cancel.load(Ordering::SeqCst) {
            break;
        }
    }
    Ok(())
}

/// What every frame of a `kiln render` shares.
struct RenderJob<'a> {
    args: &'a RenderArgs,
    ctx: &'a Arc<GpuContext>,
    name: &'a str,
    settings: RenderSettings,
    denoiser: Denoiser,
    view: ViewSettings,
    cancel: &'a Arc<AtomicBool>,
    plugins: &'a PluginHost,
}

impl RenderJob<'_> {
    /// Renders `scene` (one frame) to `output`; with `part`, only its samples, written as a
    /// part for `kiln merge`.
    fn render_frame(&self, scene: &Scene, output: &Path, part: Option<PartHeader>) -> Result<()> {
        let RenderJob {
            args,
            ctx,
            name,
            settings,
            denoiser,
            view,
            cancel,
            plugins,
        } = *self;
        let range = part
            .as_ref()
            .map_or(0..settings.samples_per_pixel, |p| p.samples.clone());
        let checkpoint_path = checkpoint::path_for(output);
        let key = checkpoint::key(scene, &settings, range.start);
        // Refused before anything is built: a checkpoint of another scene or other settings.
        let resumed = if args.resume {
            let c = Checkpoint::read(&checkpoint_path).map_err(anyhow::Error::msg)?;
            c.check(&checkpoint_path, key, settings.width, settings.height)
                .map_err(anyhow::Error::msg)?;
            Some(c)
        } else {
            None
        };

        // What `write_output` holds whole on the host, per pixel, for a plugin and the host's
        // writer alike: radiance and display RGBA f32, the sample counts, the AOVs. Refused
        // before the kernel is built when it cannot fit; docs/BENCHMARKS.md has the peaks.
        let noise = settings.aovs || settings.noise_threshold > 0.0;
        // Denoising holds the whole film (32 bytes a pixel), its guides and the filtered image
        // (72), and the noisy image as a layer (12).
        let output_bytes = 36
            + if settings.aovs { 40 } else { 0 }
            + if noise { 4 } else { 0 }
            + if denoiser != Denoiser::None { 116 } else { 0 };
        kiln::render::memory_check(
            ctx,
            settings.width,
            settings.height,
            kiln::render::DeviceFilm {
                aovs: settings.aovs,
                noise,
            },
            output_bytes,
        )?;
        let mut renderer = Renderer::new(Arc::clone(ctx), scene, settings)
            .with_context(|| format!("cannot prepare {name} for rendering"))?;
        let first = Cell::new(range.start);
        if let Some(c) = resumed {
            renderer.restore_film_state(&c.film)?;
            first.set(c.next_sample);
            eprintln!(
                "resuming from {} at {} spp",
                checkpoint_path.display(),
                c.next_sample
            );
        }

        // Printed once Ctrl-C is handled: from this line on, an interrupt writes the image.
        let info = renderer.build_info;
        eprintln!(
            "scene: {name}: {} triangles, {} instances, {} emissive triangles; BVH {:.0} ms, kernel {:.0} ms",
            info.triangles,
            info.instances,
            info.emissive_triangles,
            info.accel_build.as_secs_f64() * 1e3,
            info.kernel_build.as_secs_f64() * 1e3
        );
        if info.volume_voxels > 0 {
            eprintln!(
                "volumes: {} grid points baked in {:.0} ms (--volume-resolution {})",
                info.volume_voxels,
                info.volume_bake.as_secs_f64() * 1e3,
                settings.volume_resolution
            );
        }
        if info.world_texels > 0 {
            eprintln!(
                "world: baked into {} texels in {:.0} ms",
                info.world_texels,
                info.world_bake.as_secs_f64() * 1e3
            );
        }
        let pixels = settings.width as u64 * settings.height as u64;
        let bar = if args.quiet {
            ProgressBar::hidden()
        } else {
            ProgressBar::new(range.len() as u64)
        };
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} spp  {msg}",
            )
            .expect("the template is valid"),
        );
        let mut on_progress = |p: &kiln::render::Progress| {
            // The bar counts the samples every pixel has: those of the whole passes.
            bar.set_position((first.get() - range.start + p.whole_pass_samples) as u64);
            let secs = p.elapsed.as_secs_f64().max(1e-9);
            let next = if p.pass_fraction > 0.0 {
                let left = p.pass_elapsed.as_secs_f64() * (1.0 - p.pass_fraction) / p.pass_fraction;
                format!("{left:.1} s")
            } else {
                "-".to_owned()
            };
            let converged = match p.active_pixels {
                Some(active) => format!(
                    "  {:.0}% converged",
                    100.0 * (pixels - active.min(pixels)) as f64 / pixels as f64
                ),
                None => String::new(),
            };
            bar.set_message(format!(
            "pass {} (+{} spp) {:.0}%, next whole image in {next}  {:.2} Msamples/s  {:.1} Mrays/s{converged}",
            p.passes_done + 1,
            p.pass_samples,
            p.pass_fraction * 100.0,
            p.pixel_samples_done as f64 / secs / 1e6,
            p.rays as f64 / secs / 1e6
        ));
        };
        let deadline = args
            .time_limit
            .map(|t| Instant::now() + Duration::from_secs_f64(t));
        let every =
            (args.checkpoint_every > 0.0).then(|| Duration::from_secs_f64(args.checkpoint_every));
        let mut total = RenderStats {
            completed: true,
            next_sample: first.get(),
            ..RenderStats::default()
        };
        // One call per checkpoint: each stops at the end of a pass once `every` has passed.
        let result = loop {
            let call = renderer.render(
                first.get()..range.end,
                RenderControl {
                    cancel: Some(cancel),
                    deadline,
                    progress: Some(&mut on_progress),
                    pass_deadline: every.map(|e| Instant::now() + e),
                    ..RenderControl::default()
                },
            );
            let stats = match call {
                Ok(stats) => stats,
                Err(e) => break Err(e),
            };
            total.merge(&stats);
            if !stats.checkpoint {
                break Ok(total);
            }
            let saved = renderer
                .film_state()
                .map_err(|e| e.to_string())
                .and_then(|film| {
                    Checkpoint {
                        key,
                        width: settings.width,
                        height: settings.height,
                        next_sample: stats.next_sample,
                        film,
                    }
                    .write(&checkpoint_path)
                });
            // A checkpoint that cannot be written does not stop the render it protects.
            if let Err(e) = saved {
                bar.suspend(|| eprintln!("warning: no checkpoint: {e}"));
            }
            first.set(stats.next_sample);
        };
        bar.finish_and_clear();
        if let Some(header) = part {
            return write_part_output(renderer, result, output, &header, &checkpoint_path);
        }
        let write = |renderer| {
            write_output(
                renderer,
                output,
                plugins,
                view,
                denoiser,
                &args.export_options,
            )
        };
        let stats = match result {
            Ok(stats) => stats,
            // Whole passes rendered before an error still make an image with a sample in
            // every pixel: write it, then report the error.
            Err(e) if renderer.has_whole_pass() => {
                let written = write(renderer);
                return Err(match written {
                    Ok(()) => anyhow::anyhow!(
                        "the render stopped with an error: {e}; {} holds the whole passes rendered before it",
                        output.display()
                    ),
                    Err(w) => anyhow::anyhow!(
                        "the render stopped with an error: {e}; writing what it had rendered failed too: {w:#}"
                    ),
                });
            }
            Err(e) => return Err(e.into()),
        };
        write(renderer)?;
        if stats.completed {
            // The render is whole and written: its checkpoint has served.
            let _ = std::fs::remove_file(&checkpoint_path);
        } else if checkpoint_path.exists() {
            eprintln!(
                "{} holds the last whole pass: --resume continues from it",
                checkpoint_path.display()
            );
        }
        let secs = stats.elapsed.as_secs_f64().max(1e-9);
        let reason = if stats.completed {
            ""
        } else if cancel.load(Ordering::SeqCst) {
            " (interrupted)"
        } else {
            " (time limit reached)"
        };
        // A stop waits for the first whole pass; say so when it ran past the time limit.
        let overrun = match (args.time_limit, stats.first_pass) {
            (Some(limit), Some(first)) if first.as_secs_f64() > limit => format!(
                "; the first whole pass took {:.2} s, longer than the {limit} s time limit (it always completes, so that every pixel has a sample)",
                first.as_secs_f64()
            ),
            _ => String::new(),
        };
        let adaptive = match stats.active_pixels {
            Some(active) => format!(
                "; adaptive sampling: {:.1} % of pixels converged",
                100.0 * (pixels - active.min(pixels)) as f64 / pixels as f64
            ),
            None => String::new(),
        };
        eprintln!(
            "wrote {}: {:.1} spp average in {:.2} s{reason}, {} whole passes, {:.2} Msamples/s, {:.1} Mrays/s{}{overrun}{adaptive}",
            output.display(),
            stats.pixel_samples as f64 / pixels as f64,
            secs,
            stats.passes,
            stats.pixel_samples as f64 / secs / 1e6,
            stats.rays as f64 / secs / 1e6,
            if stats.non_finite > 0 {
                format!(", {} non-finite samples dropped", stats.non_finite)
            } else {
                String::new()
            }
        );
        Ok(())
    }
}

/// Refuses what a part of a split render cannot hold: anything that makes a pixel's
/// samples depend on more than their indices, or layers that would not merge exactly.
fn part_settings_check(
    args: &RenderArgs,
    settings: &RenderSettings,
    scene: &Scene,
    range: &std::ops::Range<u32>,
) -> Result<()> {
    if range.end > settings.samples_per_pixel {
        bail!(
            "--samples {}..{} goes past the render's {} samples per pixel (--spp is the whole render's)",
            range.start,
            range.end,
            settings.samples_per_pixel
        );
    }
    if settings.noise_threshold > 0.0 {
        bail!(
            "--samples cannot split a render with adaptive sampling (--noise-threshold): where a pixel stops depends on the samples before A; set --noise-threshold 0"
        );
    }
    if args.time_limit.is_some() {
        bail!("--samples and --time-limit: a part must hold every sample of its range");
    }
    let denoise = args.denoise.unwrap_or(scene.settings.denoiser);
    if denoise != Denoiser::None {
        bail!(
            "--samples cannot denoise a part (--denoise {}): denoising goes after the merge; set --denoise none",
            denoise.key()
        );
    }
    if scene.instances.iter().any(|i| i.shadow_catcher) {
        bail!(
            "--samples cannot split a scene with a shadow catcher: its alpha is an AOV, which does not merge exactly"
        );
    }
    Ok(())
}

/// Writes the part of a split render: every pixel holds exactly the part's samples, or
/// nothing is written (an interrupted part keeps its checkpoint for --resume).
fn write_part_output(
    renderer: Renderer,
    result: Result<RenderStats, kiln::render::RenderError>,
    output: &Path,
    header: &PartHeader,
    checkpoint_path: &Path,
) -> Result<()> {
    let stats = result?;
    if !stats.completed {
        let resume = if checkpoint_path.exists() {
            format!("; --resume continues from {}", checkpoint_path.display())
        } else {
            String::new()
        };
        bail!(
            "interrupted: the part {} is not written, since it must hold every sample of {}..{}{resume}",
            output.display(),
            header.samples.start,
            header.samples.end
        );
    }
    let film = renderer.read_exact_film()?;
    drop(renderer);
    kiln::farm::part::write_part(output, header, &film).map_err(anyhow::Error::msg)?;
    let _ = std::fs::remove_file(checkpoint_path);
    eprintln!(
        "wrote {}: samples {}..{} of {} in {:.2} s",
        output.display(),
        header.samples.start,
        header.samples.end,
        header.total_samples,
        stats.elapsed.as_secs_f64()
    );
    Ok(())
}

/// `kiln merge`: the parts' exact films added and written as one image.
fn merge(
    parts: &[PathBuf],
    output: &Path,
    allow_partial: bool,
    export_options: &str,
    plugins: &PluginHost,
) -> Result<()> {
    check_output(output, plugins, export_options)?;
    let (header, film, coverage) =
        kiln::farm::part::merge_parts(parts, allow_partial).map_err(anyhow::Error::msg)?;
    if !coverage.missing.is_empty() {
        eprintln!(
            "warning: samples {} of {} per pixel are missing: the image holds the others",
            kiln::farm::part::describe_ranges(&coverage.missing),
            header.total_samples
        );
    }
    let film = film.to_film();
    let samples = film.sums.iter().map(|s| s[3] as f32).collect();
    let export = ExportFilm::from_film(
        &film,
        header.view,
        vec![kiln::film::output::ExportLayer {
            name: "samples".into(),
            channels: 1,
            data: samples,
        }],
    );
    plugins
        .write_image(output, &export, export_options)
        .map_err(anyhow::Error::msg)?;
    eprintln!(
        "wrote {}: {} parts, {} samples per pixel",
        output.display(),
        parts.len(),
        film.sums.first().map_or(0, |s| s[3] as u64)
    );
    Ok(())
}

/// `kiln farm`: Slurm job arrays of parts and frames.
fn farm(command: FarmCommand, plugins: &PluginHost) -> Result<()> {
    use kiln::farm::slurm::{self, FarmJob, TaskState};
    let absolute = |p: &Path| {
        std::path::absolute(p).with_context(|| format!("cannot resolve {}", p.display()))
    };
    match command {
        FarmCommand::Slurm {
            scene,
            parts,
            spp,
            animation: AnimationArgs { frames, turntable },
            output,
            dir,
            sbatch_args,
            submit,
            render_args,
        } => {
            // The scene is read here once, so that a broken one fails now, not on the
            // cluster, and its samples per pixel are known.
            let (loaded, _) = load(scene.as_deref(), plugins, lookdev::Ground::Plane)?;
            let spp = spp.unwrap_or(loaded.settings.samples_per_pixel);
            if parts > spp {
                bail!(
                    "--parts {parts} is more than the {spp} samples per pixel: a part needs at least one"
                );
            }
            let first_output = frames
                .clone()
                .map_or(output.clone(), |f| kiln::farm::frame_path(&output, f.start));
            check_output(&first_output, plugins, "")?;
            let output = absolute(&output)?;
            let dir = match dir {
                Some(d) => absolute(&d)?,
                None => slurm::default_dir(&output),
            };
            let mut job = FarmJob {
                kiln: std::env::current_exe().context("cannot find the kiln executable")?,
                scene: scene.as_deref().map(absolute).transpose()?,
                output,
                spp,
                parts,
                frames,
                turntable,
                render_args,
                sbatch_args,
                submissions: Vec::new(),
            };
            slurm::write_farm(&dir, &job).map_err(anyhow::Error::msg)?;
            eprintln!(
                "wrote {}: {} tasks ({} frame(s) × {parts} part(s) of {spp} spp)",
                dir.display(),
                job.task_count(),
                job.frame_count()
            );
            if submit {
                let s = slurm::submit(&dir, &mut job, None).map_err(anyhow::Error::msg)?;
                eprintln!(
                    "submitted job array {} and merge job {}",
                    s.render_job, s.merge_job
                );
            } else {
                eprintln!(
                    "submit with: kiln farm slurm … --submit, or\n  id=$(sbatch --parsable {0}/{1}) && sbatch --dependency=afterok:$id {0}/{2}",
                    dir.display(),
                    slurm::RENDER_SCRIPT,
                    slurm::MERGE_SCRIPT
                );
            }
            Ok(())
        }
        FarmCommand::Status { dir } => {
            let job = slurm::read_farm(&dir).map_err(anyhow::Error::msg)?;
            let state = slurm::status(&dir, &job).map_err(anyhow::Error::msg)?;
            let count = |f: fn(&TaskState) -> bool| state.tasks.iter().filter(|t| f(t)).count();
            let done = count(|t| *t == TaskState::Done);
            println!(
                "{}: {done} of {} parts rendered",
                dir.display(),
                job.task_count()
            );
            let mut missing = Vec::new();
            for (t, task_state) in state.tasks.iter().enumerate() {
                let task = job.task(t as u32);
                let what = match task.frame {
                    Some(f) => format!(
                        "frame {f} samples {}..{}",
                        task.samples.start, task.samples.end
                    ),
                    None => format!("samples {}..{}", task.samples.start, task.samples.end),
                };
                match task_state {
                    TaskState::Done => {}
                    TaskState::Queued(q) => println!("  task {t} ({what}): {}", q.to_lowercase()),
                    TaskState::NotSubmitted => println!("  task {t} ({what}): not submitted"),
                    TaskState::Missing(log) => {
                        println!(
                            "  task {t} ({what}): missing, failed or cancelled{}",
                            log.as_ref()
                                .map_or(String::new(), |l| format!(" (its log ends: {l})"))
                        );
                        missing.push(what);
                    }
                }
            }
            match &state.merge_queued {
                Some(q) => println!("  merge: {}", q.to_lowercase()),
                None => println!(
                    "  merged: {} of {} image(s)",
                    state.merged.len(),
                    job.frame_count()
                ),
            }
            if !missing.is_empty() {
                bail!(
                    "{} part(s) missing ({}): kiln farm resubmit {} renders them again",
                    missing.len(),
                    missing.join("; "),
                    dir.display()
                );
            }
            Ok(())
        }
        FarmCommand::Resubmit { dir } => {
            let mut job = slurm::read_farm(&dir).map_err(anyhow::Error::msg)?;
            match slurm::resubmit(&dir, &mut job).map_err(anyhow::Error::msg)? {
                Some(s) => eprintln!(
                    "resubmitted task(s) {:?} as job array {} with merge job {}",
                    s.tasks, s.render_job, s.merge_job
                ),
                None => eprintln!("nothing to resubmit: every part is rendered or queued"),
            }
            Ok(())
        }
    }
}

/// Refuses an output that could not be written: a missing or read-only folder, a format
/// no writer has, options the writer refuses. The writer the render will use writes a 1×1
/// image with the same options into a temporary folder beside the output, which is then
/// removed: what passes here fails at the end only if the disk changes meanwhile.
fn check_output(output: &Path, plugins: &PluginHost, options: &str) -> Result<()> {
    let folder = match output.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !folder.is_dir() {
        bail!(
            "cannot write {}: the folder {} does not exist",
            output.display(),
            folder.display()
        );
    }
    let scratch = tempfile::Builder::new()
        .prefix(".kiln-check-")
        .tempdir_in(folder)
        .with_context(|| {
            format!(
                "cannot write {}: the folder {} is not writable",
                output.display(),
                folder.display()
            )
        })?;
    let name = output.file_name().unwrap_or(output.as_os_str());
    let probe = scratch.path().join(name);
    let film = ExportFilm::from_film(
        &kiln::film::Film::new(1, 1),
        ViewSettings::default(),
        Vec::new(),
    );
    let written = plugins
        .write_image(&probe, &film, options)
        .map_err(anyhow::Error::msg);
    // The writer's message names the scratch file; the user knows the output's path.
    written.map_err(|e| {
        let message =
            format!("{e:#}").replace(&probe.display().to_string(), &output.display().to_string());
        anyhow::anyhow!("cannot write {}: {message}", output.display())
    })
}

/// Where an image goes when its own path cannot be written at the end of a render (the
/// disk filled up, the folder was removed): an EXR in the temporary folder, which keeps
/// the linear film, its AOV layers and its sample counts.
fn fallback_path(output: &Path) -> PathBuf {
    let stem = output
        .file_stem()
        .map_or("render".into(), |s| s.to_string_lossy().into_owned());
    std::env::temp_dir().join(format!("kiln-{stem}-{}.exr", std::process::id()))
}

/// Writes the renderer's film to `output`, with the exporter plugin for its extension or
/// the host's own writer. The renderer (and its film on the device) is dropped before
/// the file is encoded, so the two are never in memory together.
fn write_output(
    renderer: Renderer,
    output: &Path,
    plugins: &PluginHost,
    view: ViewSettings,
    denoiser: Denoiser,
    export_options: &str,
) -> Result<()> {
    // A denoiser that fails does not cost the render: the image is written as rendered,
    // and the error says so.
    let (film, denoise_error) = match kiln::render::export_film(&renderer, view, denoiser) {
        Ok(film) => (film, None),
        Err(e) if denoiser != Denoiser::None => (
            kiln::render::export_film(&renderer, view, Denoiser::None)?,
            Some(e),
        ),
        Err(e) => return Err(e.into()),
    };
    // The device's film is freed before the file is encoded.
    drop(renderer);
    let written = plugins
        .write_image(output, &film, export_options)
        .map_err(anyhow::Error::msg);
    if let Err(e) = written {
        // Hours of rendering are not dropped for want of one path: the film goes to a
        // fallback file, whose path the error names.
        let fallback = fallback_path(output);
        return Err(match write_image(&fallback, &film, "") {
            Ok(()) => e.context(format!(
                "the render was saved to {} instead",
                fallback.display()
            )),
            Err(f) => e.context(format!(
                "saving the render to {} instead failed too: {f}",
                fallback.display()
            )),
        });
    }
    match denoise_error {
        Some(e) => Err(anyhow::Error::new(e).context(format!(
            "{} was written without denoising",
            output.display()
        ))),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_editor_panic_is_one_line_naming_the_crate_and_file() {
        assert_eq!(
            source_file(
                "/root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/egui-wgpu-0.36.2/src/renderer.rs"
            ),
            "egui-wgpu-0.36.2/src/renderer.rs"
        );
        assert_eq!(source_file("src/main.rs"), "src/main.rs");
        let line = panic_line("Failed to create staging buffer", None);
        assert_eq!(
            line,
            "error: the editor failed: Failed to create staging buffer"
        );
        let here = std::panic::Location::caller();
        let line = panic_line("boom", Some(here));
        assert!(
            line.starts_with("error: the editor failed at src/main.rs:")
                && line.ends_with(": boom"),
            "{line}"
        );
    }
}
