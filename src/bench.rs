//! `kiln bench`: samples/s and rays/s on the bundled Cornell box and on a generated
//! million-triangle scene, with BVH build and kernel build times reported apart. Prints
//! Markdown rows for `docs/BENCHMARKS.md`. Timings live here, never in tests.

use std::io::Write as _;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Result;
use glam::{Affine3A, Vec3};

mod soak;

pub use soak::bundled_materials;

use crate::accel::build_scene_accel;
use crate::render::gpu_scene::texel_table;
use crate::render::{Backend, GpuContext, KernelKind, RenderControl, RenderSettings, Renderer};
use crate::scene::{self, Camera, Material, Scene, UNLIMITED_BOUNCES, shapes};
use crate::shader::Ablation;
use crate::shader::bindings::{Space, TexelLayout, TexelReads, layout_entry};
use crate::shader::sampling::Sampler;

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Triangles in the generated large scene.
    #[arg(long, default_value_t = 1_000_000)]
    pub triangles: u32,
    /// Seconds of timed rendering per scene, after a warm-up.
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f64,
    /// Image size of the timed renders (square).
    #[arg(long, default_value_t = 512)]
    pub size: u32,
    /// Only the scenes whose name contains this text (any case); may be given several
    /// times. Every scene by default.
    #[arg(long = "scene", value_name = "TEXT")]
    pub scenes: Vec<String>,
    /// Instead of samples/s: each scene's error against a reference as its samples grow
    /// (RMSE against time, at the specialised kernel). Use a small --size.
    #[arg(long)]
    pub convergence: bool,
    /// Samples per pixel of the --convergence reference (two halves of different seeds);
    /// the measured renders go up to an eighth of it.
    #[arg(long, default_value_t = 1024, value_name = "SPP")]
    pub reference_spp: u32,
    /// Instead of samples/s: each scene's energy lost to a bounce limit, against unbounded
    /// depth (Russian roulette alone ending paths), and the time each limit takes, at
    /// --depth-spp. Use a small --size.
    #[arg(long)]
    pub depth: bool,
    /// Samples per pixel of each --depth render.
    #[arg(long, default_value_t = 256, value_name = "SPP")]
    pub depth_spp: u32,
    /// Instead of samples/s: what the firefly clamp does to each scene at --clamp-spp, a
    /// ladder of direct and indirect limits against a reference of --reference-spp without
    /// one: the light it takes away (its bias) and the error left (RMSE). Use a small
    /// --size.
    #[arg(long)]
    pub clamp: bool,
    /// Samples per pixel of each --clamp render.
    #[arg(long, default_value_t = 64, value_name = "SPP")]
    pub clamp_spp: u32,
    /// Instead of samples/s of each kernel kind: where the specialised kernel's time goes.
    /// Each scene is timed with the kernel cut down to camera rays, to primary hits, and to
    /// a walk of closest-hit and shadow rays with no shading, then whole; the table gives
    /// each part's time per sample and per ray.
    #[arg(long)]
    pub ablation: bool,
    /// Instead of samples/s: what a dependent load costs on this adapter, from a storage
    /// buffer and from a texel table read each way the adapter can (sampled, storage
    /// texture), with a working set that stays in the cache and one that does not (the
    /// loads of BVH traversal).
    #[arg(long)]
    pub fetch: bool,
    /// Instead of samples/s: the speed/accuracy trade at equal time. Each scene rendered
    /// for each of --budgets seconds plainly, with adaptive sampling (--tradeoff-threshold),
    /// denoised (à-trous, and Open Image Denoise in builds with it), both, with every lobe
    /// compiled in, at 2, 4, 8 and 16 bounces and with the presets' firefly clamp; the
    /// error against a reference of --reference-spp, cached in target/bench-references
    /// (RMSE, relMSE: squared error over the reference squared plus 0.01, and SSIM). Use a
    /// small --size.
    #[arg(long)]
    pub tradeoff: bool,
    /// Seconds of rendering per --tradeoff render (the denoiser's time is added).
    #[arg(long, value_delimiter = ',', default_values_t = [0.5, 1.0, 2.0, 4.0])]
    pub budgets: Vec<f64>,
    /// The noise threshold of --tradeoff's adaptive renders.
    #[arg(long, default_value_t = 0.02)]
    pub tradeoff_threshold: f32,
    /// Render each --tradeoff cell this many times, each with its own seed, and report the
    /// medians (of the seconds, samples, errors and SSIM, each on its own): one run's time
    /// on a busy machine, and its error at a few samples, swing widely.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub repeat: u32,
    /// Only the --tradeoff methods whose name contains this text (any case, "plain" is
    /// always measured: the ratios are to it); may be given several times. All by default.
    #[arg(long = "method", value_name = "TEXT")]
    pub methods: Vec<String>,
    /// Also write --tradeoff's rows as CSV to this file.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<std::path::PathBuf>,
    /// Also plot --tradeoff's relMSE against time (log-log) as a PNG to this file.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<std::path::PathBuf>,
    /// With --tradeoff --plot: plot the rows of an earlier run's --csv instead of
    /// measuring again.
    #[arg(long, value_name = "CSV", requires = "plot")]
    pub replot: Option<std::path::PathBuf>,
    /// Instead of samples/s: this many back-to-back small renders with varying material
    /// graphs in one process, printing resident memory and the pipeline cache every 100
    /// (what a long editor session would accumulate; docs/RELIABILITY.md).
    #[arg(long, value_name = "RENDERS")]
    pub soak: Option<u32>,
}

impl BenchArgs {
    /// A scene's render settings for a timed render: the bench's size, unlimited samples
    /// (the range rendered decides), the scene's own bounces and seed.
    fn settings(&self, scene: &Scene, kernel: KernelKind) -> RenderSettings {
        RenderSettings {
            width: self.size,
            height: self.size,
            samples_per_pixel: u32::MAX,
            kernel,
            ..RenderSettings::from_scene(scene)
        }
    }

    fn wants(&self, scene: &str) -> bool {
        matches_any(&self.scenes, scene)
    }

    fn wants_method(&self, method: &str) -> bool {
        method == "plain" || matches_any(&self.methods, method)
    }
}

/// Whether `name` contains any of `filters` (any case), or `filters` is empty.
fn matches_any(filters: &[String], name: &str) -> bool {
    let name = name.to_lowercase();
    filters.is_empty() || filters.iter().any(|f| name.contains(&f.to_lowercase()))
}

/// A displaced sphere on a floor, lit by a quad light and a dim sky.
pub fn large_scene(triangles: u32) -> Scene {
    let mut scene = Scene::empty(Camera::look_at(
        Vec3::new(0.0, 1.2, 3.2),
        Vec3::new(0.0, 0.8, 0.0),
        40.0,
    ));
    scene.environment = Vec3::splat(0.2);
    let grey = scene.add_material(Material::diffuse("grey", Vec3::splat(0.6)));
    let orange = scene.add_material(Material::diffuse("orange", Vec3::new(0.8, 0.4, 0.1)));
    let light = scene.add_material(Material::emitter("light", Vec3::splat(8.0)));
    let sphere = scene.add_mesh(shapes::displaced_sphere(triangles));
    let quad = scene.add_mesh(shapes::quad());
    scene.add_instance(
        sphere,
        orange,
        Affine3A::from_translation(Vec3::new(0.0, 0.8, 0.0))
            * Affine3A::from_scale(Vec3::splat(0.75)),
    );
    scene.add_instance(quad, grey, Affine3A::from_scale(Vec3::splat(10.0)));
    // Facing down from above.
    scene.add_instance(
        quad,
        light,
        Affine3A::from_translation(Vec3::new(0.0, 3.0, 0.0))
            * Affine3A::from_rotation_x(std::f32::consts::PI),
    );
    scene
}

struct Row {
    name: String,
    triangles: u64,
    bvh: Duration,
    kernel: Duration,
    /// The first dispatch of one sample per pixel, which includes the driver's compile.
    first_dispatch: Duration,
    /// Baking the heterogeneous volumes into grids (part of `kernel`), when there are any.
    volume_bake: Option<Duration>,
    samples_per_sec: f64,
    rays_per_sec: f64,
}

fn measure(
    ctx: &Arc<GpuContext>,
    name: &str,
    scene: &Scene,
    args: &BenchArgs,
    settings: RenderSettings,
) -> Result<Row> {
    // The BVH on its own, so its time is not mixed with upload.
    let t = Instant::now();
    build_scene_accel(scene)?;
    let bvh = t.elapsed();
    let mut renderer = Renderer::new(Arc::clone(ctx), scene, settings)?;
    let t = Instant::now();
    renderer.render(0..1, RenderControl::default())?;
    let first_dispatch = t.elapsed();
    // Warm-up: lets the batch size settle.
    renderer.render(1..4, RenderControl::default())?;
    let stats = render_for(&mut renderer, 4..u32::MAX, args.seconds)?;
    let secs = stats.elapsed.as_secs_f64();
    Ok(Row {
        name: name.to_owned(),
        triangles: scene.triangle_count(),
        bvh,
        kernel: renderer.build_info.kernel_build,
        first_dispatch,
        volume_bake: (renderer.build_info.volume_voxels > 0)
            .then_some(renderer.build_info.volume_bake),
        samples_per_sec: stats.pixel_samples as f64 / secs,
        rays_per_sec: stats.rays as f64 / secs,
    })
}

/// Runs the benchmarks and writes their report, a Markdown table as docs/BENCHMARKS.md
/// keeps it, to `out` row by row as each is measured (the library never prints: the CLI
/// passes standard output).
pub fn run(args: &BenchArgs, backend: Option<Backend>, out: &mut dyn std::io::Write) -> Result<()> {
    if args.convergence {
        let ctx = GpuContext::new(backend)?;
        return convergence(&ctx, &bench_scenes(args)?, args, out);
    }
    if args.depth {
        let ctx = GpuContext::new(backend)?;
        return depth(&ctx, &bench_scenes(args)?, args, out);
    }
    if args.clamp {
        let ctx = GpuContext::new(backend)?;
        return clamp(&ctx, &bench_scenes(args)?, args, out);
    }
    if args.ablation {
        let ctx = GpuContext::new(backend)?;
        return ablation(&ctx, &bench_scenes(args)?, args, out);
    }
    if args.fetch {
        return fetch(&*GpuContext::new(backend)?, out);
    }
    if let (Some(csv), Some(plot)) = (&args.replot, &args.plot) {
        return plot_tradeoff(plot, &read_tradeoff_csv(csv)?);
    }
    if args.tradeoff {
        let ctx = GpuContext::new(backend)?;
        return tradeoff(&ctx, &bench_scenes(args)?, args, out);
    }
    if let Some(renders) = args.soak {
        return soak::soak(&GpuContext::new(backend)?, renders, out);
    }
    // The import first, so the memory it measures is not hidden under the renders' peak.
    let import = measure_import(args.triangles);
    let ctx = GpuContext::new(backend)?;
    throughput(&ctx, &bench_scenes(args)?, import, args, out)
}

/// The scenes --scene asks for (every one by default).
fn bench_scenes(args: &BenchArgs) -> Result<Vec<(String, Scene)>> {
    let mut scenes = Vec::new();
    if args.wants("Cornell box") {
        scenes.push(("Cornell box".to_owned(), scene::default_scene()?));
    }
    let sphere = format!("displaced sphere ({} tris)", args.triangles);
    if args.wants(&sphere) {
        scenes.push((sphere, large_scene(args.triangles)));
    }
    // The bundled material scenes, when run from the source tree.
    for file in [
        "materials.kiln",
        "showcase.kiln",
        "subsurface.kiln",
        "volumes.kiln",
        "cloud.kiln",
    ] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/scenes")
            .join(file);
        if args.wants(file) && path.exists() {
            scenes.push((file.to_owned(), scene::load_scene(&path)?));
        }
    }
    if scenes.is_empty() {
        anyhow::bail!(
            "no benchmark scene matches --scene {}",
            args.scenes.join(", --scene ")
        );
    }
    Ok(scenes)
}

/// Mean over pixels and channels of the squared difference of two images.
fn mean_square_difference(a: &[Vec3], b: &[Vec3]) -> f64 {
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(a, b)| (*a - *b).as_dvec3().length_squared())
        .sum();
    sum / (3 * a.len().max(1)) as f64
}

/// A reference image of `half` samples per pixel rendered twice with different seeds
/// (`settings` of the seed): their mean, and its own noise as a mean square (each half's
/// variance is twice the mean's, and the halves differ by four times it).
fn reference_halves(
    ctx: &Arc<GpuContext>,
    scene: &Scene,
    settings: impl Fn(u32) -> RenderSettings,
    half: u32,
) -> Result<(Vec<Vec3>, f64)> {
    let mut halves = Vec::new();
    for seed in [0x5eed_0001, 0x5eed_0002] {
        let mut r = Renderer::new(Arc::clone(ctx), scene, settings(seed))?;
        r.render(0..half, RenderControl::default())?;
        halves.push(r.read_film()?.radiance());
    }
    let reference = halves[0]
        .iter()
        .zip(&halves[1])
        .map(|(a, b)| (*a + *b) * 0.5)
        .collect();
    Ok((
        reference,
        mean_square_difference(&halves[0], &halves[1]) / 4.0,
    ))
}

/// Each scene's error against a reference as samples grow: the RMSE of linear radiance
/// over every pixel and channel, with the reference's own noise (measured from its two
/// halves, rendered with different seeds) taken out. At the Monte Carlo rate the RMSE
/// falls as 1 / √spp and RMSE × √seconds stays constant: that product is the efficiency
/// to compare between renderers and settings (lower is better).
fn convergence(
    ctx: &Arc<GpuContext>,
    scenes: &[(String, Scene)],
    args: &BenchArgs,
    out: &mut dyn std::io::Write,
) -> Result<()> {
    let half = (args.reference_spp / 2).max(1);
    let max_spp = (args.reference_spp / 8).max(1);
    writeln!(
        out,
        "Adapter: {}; {}x{} px, specialised kernels, reference {} spp (two seeds), max bounces from each scene, NEE + MIS.",
        ctx.describe(),
        args.size,
        args.size,
        2 * half
    )?;
    writeln!(out)?;
    writeln!(
        out,
        "| scene | sampler | spp | seconds | RMSE | RMSE × √seconds |"
    )?;
    writeln!(out, "|---|---|---:|---:|---:|---:|")?;
    let mut slopes = Vec::new();
    let mut ratios_by_scene = Vec::new();
    for (name, scene) in scenes {
        let renderer = |seed: u32, sampler: Sampler| {
            let mut settings = RenderSettings {
                seed,
                ..args.settings(scene, KernelKind::Specialized)
            };
            settings.sampling.sampler = sampler;
            Renderer::new(Arc::clone(ctx), scene, settings)
        };
        let (reference, reference_noise) = reference_halves(
            ctx,
            scene,
            |seed| RenderSettings {
                seed,
                ..args.settings(scene, KernelKind::Specialized)
            },
            half,
        )?;
        // Each sampler against the same reference. The sampler is compiled into the kernel:
        // a pass rendered and cleared first has the driver compile it, so the timed
        // renders start warm.
        let mut errors = Vec::new();
        for sampler in Sampler::ALL {
            let mut measured = renderer(1, sampler)?;
            measured.render(0..1, RenderControl::default())?;
            measured.clear_film();
            let (mut done, mut seconds, mut fit) = (0, 0.0, Vec::new());
            let mut spp = 1;
            while spp <= max_spp {
                seconds += measured
                    .render(done..spp, RenderControl::default())?
                    .elapsed
                    .as_secs_f64();
                done = spp;
                let image = measured.read_film()?.radiance();
                let mse = (mean_square_difference(&image, &reference) - reference_noise).max(0.0);
                let rmse = mse.sqrt();
                if rmse > 0.0 {
                    fit.push(((spp as f64).ln(), rmse.ln()));
                }
                errors.push((sampler, spp, rmse));
                writeln!(
                    out,
                    "| {name} | {} | {spp} | {seconds:.3} | {rmse:.5} | {:.5} |",
                    sampler.key(),
                    rmse * seconds.sqrt()
                )?;
                spp *= 2;
            }
            slopes.push((name, sampler, slope(&fit)));
        }
        let ratios: Vec<String> = errors
            .iter()
            .filter(|(s, _, _)| *s == Sampler::Sobol)
            .filter_map(|&(_, spp, sobol)| {
                let (_, _, independent) = errors
                    .iter()
                    .find(|&&(s, n, _)| s == Sampler::Independent && n == spp)?;
                Some(format!("{spp}: {:.2}", sobol / independent))
            })
            .collect();
        ratios_by_scene.push((name, ratios.join(", ")));
    }
    writeln!(out)?;
    for (name, sampler, slope) in slopes {
        writeln!(
            out,
            "{name}, {}: RMSE ∝ spp^{slope:.2} (the Monte Carlo rate is -0.5)",
            sampler.key()
        )?;
    }
    for (name, ratios) in ratios_by_scene {
        writeln!(
            out,
            "{name}: RMSE of sobol / independent at equal spp: {ratios}"
        )?;
    }
    Ok(())
}

/// Mean over pixels and channels of the squared error relative to the reference's square
/// plus 0.01 (relMSE, as pbrt and Mitsuba's papers use it: dark pixels count too).
fn relative_mse(image: &[Vec3], reference: &[Vec3]) -> f64 {
    let sum: f64 = image
        .iter()
        .zip(reference)
        .flat_map(|(a, r)| (0..3).map(move |c| (a[c] as f64, r[c] as f64)))
        .map(|(a, r)| (a - r).powi(2) / (r * r + 0.01))
        .sum();
    sum / (3 * image.len().max(1)) as f64
}

/// One way of spending a `--tradeoff` budget: render settings and a denoiser.
struct Method {
    name: String,
    settings: RenderSettings,
    denoiser: scene::Denoiser,
}

/// The levers `kiln bench --tradeoff` compares at equal time, from a scene's own settings
/// (`base`, "plain"): adaptive sampling and each denoiser alone and together, every
/// lobe compiled in instead of the specialised kernel, lower bounce limits, and the
/// presets' firefly clamp.
fn tradeoff_methods(base: RenderSettings, threshold: f32) -> Vec<Method> {
    let method = |name: &str, settings: RenderSettings, denoiser| Method {
        name: name.to_owned(),
        settings: RenderSettings {
            aovs: denoiser != scene::Denoiser::None,
            ..settings
        },
        denoiser,
    };
    let adaptive = RenderSettings {
        noise_threshold: threshold,
        ..base
    };
    let mut methods = vec![
        method("plain", base, scene::Denoiser::None),
        method("adaptive", adaptive, scene::Denoiser::None),
    ];
    for denoiser in [scene::Denoiser::Atrous, scene::Denoiser::Oidn] {
        if denoiser.unavailable().is_none() {
            let key = denoiser.key();
            methods.push(method(key, base, denoiser));
            methods.push(method(&format!("adaptive + {key}"), adaptive, denoiser));
        }
    }
    let general = RenderSettings {
        kernel: KernelKind::General,
        ..base
    };
    methods.push(method("general kernel", general, scene::Denoiser::None));
    for max_bounces in [2, 4, 8, 16].into_iter().filter(|&b| b < base.max_bounces) {
        let settings = RenderSettings {
            max_bounces,
            ..base
        };
        let name = format!("{max_bounces} bounces");
        methods.push(method(&name, settings, scene::Denoiser::None));
    }
    let clamp = scene::Quality::Preview.settings().clamp;
    let clamped = RenderSettings { clamp, ..base };
    let name = format!("clamp {}", clamp.indirect);
    methods.push(method(&name, clamped, scene::Denoiser::None));
    methods
}

/// Where `kiln bench` keeps the references it renders, so that a second run reuses them:
/// `KILN_BENCH_CACHE`, or the build's `target/bench-references`.
fn reference_cache() -> std::path::PathBuf {
    std::env::var_os("KILN_BENCH_CACHE")
        .map(Into::into)
        .unwrap_or_else(|| {
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench-references")
        })
}

/// [`reference_halves`], read from [`reference_cache`] when the same binary rendered it
/// before for the same scene, settings and samples (the file is named by their hash).
fn cached_reference(
    ctx: &Arc<GpuContext>,
    scene: &Scene,
    base: RenderSettings,
    half: u32,
) -> Result<(Vec<Vec3>, f64)> {
    let key = crate::render::checkpoint::key(scene, &RenderSettings { seed: 0, ..base }, 0);
    let path = reference_cache().join(format!("{key:016x}-{half}.bin"));
    let pixels = (base.width * base.height) as usize;
    if let Ok(bytes) = std::fs::read(&path)
        && bytes.len() == 8 + 12 * pixels
    {
        let noise = f64::from_le_bytes(bytes[..8].try_into().expect("8 bytes"));
        let floats: &[f32] = bytemuck::cast_slice(&bytes[8..]);
        return Ok((
            floats.chunks_exact(3).map(Vec3::from_slice).collect(),
            noise,
        ));
    }
    let (reference, noise) =
        reference_halves(ctx, scene, |seed| RenderSettings { seed, ..base }, half)?;
    std::fs::create_dir_all(reference_cache())?;
    kiln_plugin_api::atomic::write_atomically(&path, |w| {
        let floats: Vec<f32> = reference.iter().flat_map(|c| c.to_array()).collect();
        w.write_all(&noise.to_le_bytes())
            .and_then(|()| w.write_all(bytemuck::cast_slice(&floats)))
            .map_err(|e| e.to_string())
    })
    .map_err(anyhow::Error::msg)?;
    Ok((reference, noise))
}

/// The mean structural similarity (SSIM; Wang et al. 2004: 11 × 11 Gaussian windows of
/// σ 1.5, K1 0.01, K2 0.03) of two images' luminance after the tone curve l / (1 + l),
/// which maps any radiance into [0, 1): 1 for equal images.
pub fn ssim(a: &[Vec3], b: &[Vec3], width: usize, height: usize) -> f64 {
    let tone = |c: &Vec3| {
        let l = c.dot(Vec3::new(0.2126, 0.7152, 0.0722)).max(0.0) as f64;
        l / (1.0 + l)
    };
    let x: Vec<f64> = a.iter().map(tone).collect();
    let y: Vec<f64> = b.iter().map(tone).collect();
    let weights: Vec<f64> = (-5..=5)
        .map(|i: i32| (-(i * i) as f64 / (2.0 * 1.5 * 1.5)).exp())
        .collect();
    // A separable Gaussian blur, the window renormalised where it leaves the image.
    let blur = |image: &[f64]| {
        let pass = |image: &[f64], horizontal: bool| {
            let mut out = vec![0.0; image.len()];
            for row in 0..height {
                for col in 0..width {
                    let (mut sum, mut total) = (0.0, 0.0);
                    for (k, w) in weights.iter().enumerate() {
                        let (r, c) = if horizontal {
                            (row as i64, col as i64 + k as i64 - 5)
                        } else {
                            (row as i64 + k as i64 - 5, col as i64)
                        };
                        if (0..height as i64).contains(&r) && (0..width as i64).contains(&c) {
                            sum += w * image[r as usize * width + c as usize];
                            total += w;
                        }
                    }
                    out[row * width + col] = sum / total;
                }
            }
            out
        };
        pass(&pass(image, true), false)
    };
    let product = |p: &[f64], q: &[f64]| p.iter().zip(q).map(|(p, q)| p * q).collect::<Vec<_>>();
    let (mx, my) = (blur(&x), blur(&y));
    let (xx, yy, xy) = (
        blur(&product(&x, &x)),
        blur(&product(&y, &y)),
        blur(&product(&x, &y)),
    );
    let (c1, c2) = (0.01f64.powi(2), 0.03f64.powi(2));
    let sum: f64 = (0..x.len())
        .map(|i| {
            let (vx, vy) = (xx[i] - mx[i] * mx[i], yy[i] - my[i] * my[i]);
            let cov = xy[i] - mx[i] * my[i];
            ((2.0 * mx[i] * my[i] + c1) * (2.0 * cov + c2))
                / ((mx[i] * mx[i] + my[i] * my[i] + c1) * (vx + vy + c2))
        })
        .sum();
    sum / x.len().max(1) as f64
}

/// One measured `--tradeoff` render.
struct TradeoffRow {
    scene: String,
    method: String,
    seconds: f64,
    rel_mse: f64,
}

/// The speed/accuracy trade at equal time: each scene rendered for each budget by each of
/// [`tradeoff_methods`], against a cached reference. Every render has its own renderer,
/// built (and its kernel compiled) before its clock starts; a denoiser's time counts.
fn tradeoff(
    ctx: &Arc<GpuContext>,
    scenes: &[(String, Scene)],
    args: &BenchArgs,
    out: &mut dyn std::io::Write,
) -> Result<()> {
    let half = (args.reference_spp / 2).max(1);
    let threshold = args.tradeoff_threshold;
    writeln!(
        out,
        "Adapter: {}; {}x{} px, specialised kernels but where named, each scene's settings, \
         reference {} spp (two seeds); adaptive: --noise-threshold {threshold}; relMSE: \
         squared error over the reference squared plus 0.01; SSIM of the tone-mapped \
         luminance; each cell the median of {} run(s), seeds 1 on.",
        ctx.describe(),
        args.size,
        args.size,
        2 * half,
        args.repeat,
    )?;
    writeln!(out)?;
    writeln!(
        out,
        "| scene | method | budget s | seconds | spp (mean) | Msamples/s | RMSE | relMSE | SSIM | relMSE ÷ plain's |"
    )?;
    writeln!(out, "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    let mut csv =
        String::from("scene,method,budget_s,seconds,spp,msamples_per_s,rmse,rel_mse,ssim,runs\n");
    let mut rows = Vec::new();
    let mut headlines = Vec::new();
    for (name, scene) in scenes {
        let base = RenderSettings {
            seed: 1,
            ..args.settings(scene, KernelKind::Specialized)
        };
        let (reference, reference_noise) = cached_reference(ctx, scene, base, half)?;
        let size = args.size as usize;
        let pixels = (size * size) as f64;
        for &budget in &args.budgets {
            let mut plain = None;
            let methods = tradeoff_methods(base, threshold);
            for method in methods.into_iter().filter(|m| args.wants_method(&m.name)) {
                let runs = (0..args.repeat)
                    .map(|k| {
                        let settings = RenderSettings {
                            seed: base.seed + k,
                            ..method.settings
                        };
                        measure_at_budget(ctx, scene, settings, method.denoiser, budget)
                    })
                    .collect::<Result<Vec<_>>>()?;
                let median = |f: &dyn Fn(&BudgetRun) -> f64| {
                    let mut values: Vec<f64> = runs.iter().map(f).collect();
                    values.sort_by(f64::total_cmp);
                    let n = values.len();
                    (values[(n - 1) / 2] + values[n / 2]) / 2.0
                };
                let seconds = median(&|r| r.seconds);
                let spp = median(&|r| r.pixel_samples / pixels);
                let rate = median(&|r| r.pixel_samples / r.render_seconds / 1e6);
                let rmse = median(&|r| {
                    (mean_square_difference(&r.image, &reference) - reference_noise)
                        .max(0.0)
                        .sqrt()
                });
                let rel = median(&|r| relative_mse(&r.image, &reference));
                let similarity = median(&|r| ssim(&r.image, &reference, size, size));
                let plain_rel = *plain.get_or_insert(rel);
                let method_name = &method.name;
                writeln!(
                    out,
                    "| {name} | {method_name} | {budget} | {seconds:.2} | {spp:.1} | {rate:.3} | {rmse:.5} | {rel:.5} | {similarity:.4} | {:.2} |",
                    rel / plain_rel
                )?;
                csv.push_str(&format!(
                    "{name},{method_name},{budget},{seconds:.3},{spp:.2},{rate:.4},{rmse:.6},{rel:.6},{similarity:.5},{}\n",
                    args.repeat
                ));
                if method_name.starts_with("adaptive + ") {
                    headlines.push(format!(
                        "{name}: at {budget} s, {method_name} has {:.1}× lower relMSE than plain",
                        plain_rel / rel.max(1e-30)
                    ));
                }
                rows.push(TradeoffRow {
                    scene: name.clone(),
                    method: method.name,
                    seconds,
                    rel_mse: rel,
                });
            }
        }
        // Written after each scene, so a long run stopped part way keeps what it measured.
        if let Some(path) = &args.csv {
            kiln_plugin_api::atomic::write_atomically(path, |w| {
                w.write_all(csv.as_bytes()).map_err(|e| e.to_string())
            })
            .map_err(anyhow::Error::msg)?;
        }
        if let Some(path) = &args.plot {
            plot_tradeoff(path, &rows)?;
        }
    }
    writeln!(out)?;
    for line in headlines {
        writeln!(out, "{line}")?;
    }
    Ok(())
}

/// Renders `samples` of every pixel, stopping at the end of the pass during which
/// `seconds` have passed.
fn render_for(
    renderer: &mut Renderer,
    samples: std::ops::Range<u32>,
    seconds: f64,
) -> Result<crate::render::RenderStats> {
    let deadline = Instant::now() + Duration::from_secs_f64(seconds);
    Ok(renderer.render(
        samples,
        RenderControl {
            deadline: Some(deadline),
            ..RenderControl::default()
        },
    )?)
}

/// One render of a `--tradeoff` cell: the image (denoised where asked) and its cost.
struct BudgetRun {
    image: Vec<Vec3>,
    /// Rendering and denoising.
    seconds: f64,
    render_seconds: f64,
    pixel_samples: f64,
}

/// Renders `scene` until `budget` seconds have passed, with its own renderer built (and
/// its kernel compiled and dispatched once) before the clock starts, and denoises the film
/// with `denoiser`, whose time counts.
fn measure_at_budget(
    ctx: &Arc<GpuContext>,
    scene: &Scene,
    settings: RenderSettings,
    denoiser: scene::Denoiser,
    budget: f64,
) -> Result<BudgetRun> {
    let mut r = Renderer::new(Arc::clone(ctx), scene, settings)?;
    // The driver compiles a kernel at its first dispatch: not the budget's.
    r.render(0..1, RenderControl::default())?;
    r.clear_film();
    let stats = render_for(&mut r, 0..u32::MAX, budget)?;
    let start = Instant::now();
    let film = r.read_film()?;
    let image = match (r.read_aovs()?, r.read_second_moments()?) {
        (Some(aovs), Some(moments)) if denoiser != scene::Denoiser::None => {
            crate::render::denoise::denoise_film(ctx, &film, &aovs, &moments, denoiser)?
        }
        _ => film,
    }
    .radiance();
    let denoise_seconds = if denoiser == scene::Denoiser::None {
        0.0
    } else {
        start.elapsed().as_secs_f64()
    };
    let render_seconds = stats.elapsed.as_secs_f64();
    Ok(BudgetRun {
        image,
        seconds: render_seconds + denoise_seconds,
        render_seconds,
        pixel_samples: stats.pixel_samples as f64,
    })
}

/// The rows of a `--tradeoff --csv` file, for `--replot`.
fn read_tradeoff_csv(path: &std::path::Path) -> Result<Vec<TradeoffRow>> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| anyhow::anyhow!("cannot read {}: {e}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or_else(|| anyhow::anyhow!("{}: no {name} column", path.display()))
    };
    let (scene, method, seconds, rel_mse) = (
        column("scene")?,
        column("method")?,
        column("seconds")?,
        column("rel_mse")?,
    );
    lines
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, line)| {
            let fields: Vec<&str> = line.split(',').collect();
            let field = |c: usize| {
                fields.get(c).copied().ok_or_else(|| {
                    anyhow::anyhow!("{} line {}: too few fields", path.display(), i + 2)
                })
            };
            let number = |c: usize| -> Result<f64> {
                field(c)?
                    .parse()
                    .map_err(|_| anyhow::anyhow!("{} line {}: not a number", path.display(), i + 2))
            };
            Ok(TradeoffRow {
                scene: field(scene)?.to_owned(),
                method: field(method)?.to_owned(),
                seconds: number(seconds)?,
                rel_mse: number(rel_mse)?,
            })
        })
        .collect()
}

/// `--tradeoff`'s relMSE against seconds, log-log, a panel per scene and a line per
/// method, as a PNG written atomically to `path`.
fn plot_tradeoff(path: &std::path::Path, rows: &[TradeoffRow]) -> Result<()> {
    use plotters::prelude::*;

    // Plotters draws text with a font it is given: egui's own, already in the binary.
    plotters::style::register_font(
        "sans-serif",
        FontStyle::Normal,
        epaint_default_fonts::UBUNTU_LIGHT,
    )
    .map_err(|_| anyhow::anyhow!("the plot's font does not load"))?;
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    let mut methods: Vec<&str> = Vec::new();
    for r in rows {
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    let (panel_w, panel_h) = (720u32, 520u32);
    let (width, height) = (panel_w, panel_h * scenes.len() as u32);
    let mut pixels = vec![0u8; (width * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (width, height)).into_drawing_area();
        root.fill(&WHITE)?;
        for (panel, scene) in root.split_evenly((scenes.len(), 1)).iter().zip(&scenes) {
            let of_scene: Vec<&TradeoffRow> = rows.iter().filter(|r| r.scene == *scene).collect();
            let range = |f: fn(&TradeoffRow) -> f64| {
                let values = of_scene.iter().map(|r| f(r)).filter(|v| *v > 0.0);
                let lo = values.clone().fold(f64::INFINITY, f64::min);
                let hi = values.fold(0.0, f64::max);
                (lo * 0.8)..(hi * 1.25)
            };
            let mut chart = ChartBuilder::on(panel)
                .caption(
                    format!("{scene}: relMSE against time (log-log)"),
                    ("sans-serif", 22),
                )
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(70)
                .build_cartesian_2d(
                    range(|r| r.seconds).log_scale(),
                    range(|r| r.rel_mse).log_scale(),
                )?;
            chart
                .configure_mesh()
                .x_desc("seconds")
                .y_desc("relMSE")
                .x_labels(8)
                .y_labels(8)
                .x_label_formatter(&|v| format!("{v:.2}"))
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .label_style(("sans-serif", 14))
                .draw()?;
            for (i, method) in methods.iter().enumerate() {
                let colour = Palette99::pick(i).to_rgba();
                let points: Vec<(f64, f64)> = of_scene
                    .iter()
                    .filter(|r| r.method == *method && r.rel_mse > 0.0)
                    .map(|r| (r.seconds, r.rel_mse))
                    .collect();
                if points.is_empty() {
                    continue;
                }
                chart
                    .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))?
                    .label(*method)
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                    });
                chart.draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 13))
                .draw()?;
        }
        root.present()?;
    }
    let image = image::RgbImage::from_raw(width, height, pixels)
        .ok_or_else(|| anyhow::anyhow!("the plot's buffer has the wrong size"))?;
    kiln_plugin_api::atomic::write_atomically(path, |w| {
        let mut png = Vec::new();
        image
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .map_err(|e| e.to_string())?;
        w.write_all(&png).map_err(|e| e.to_string())
    })
    .map_err(anyhow::Error::msg)
}

/// The (direct, indirect) limits `kiln bench --clamp` measures; the first is off.
const CLAMPS: [(f32, f32); 7] = [
    (0.0, 0.0),
    (0.0, 10.0),
    (0.0, 3.0),
    (0.0, 1.0),
    (0.0, 0.3),
    (10.0, 1.0),
    (3.0, 0.3),
];

/// What the firefly clamp trades: each scene's renders at the limits of [`CLAMPS`] against
/// a reference without one (two halves of different seeds, their own noise taken out of
/// the RMSE). The bias is the image mean's change against the reference; all clamped
/// renders share a seed, so their differences from one another are the clamp's alone.
fn clamp(
    ctx: &Arc<GpuContext>,
    scenes: &[(String, Scene)],
    args: &BenchArgs,
    out: &mut dyn std::io::Write,
) -> Result<()> {
    let half = (args.reference_spp / 2).max(1);
    writeln!(
        out,
        "Adapter: {}; {}x{} px, {} spp against an unclamped reference of {} spp (two seeds), \
         specialised kernels, each scene's bounces, NEE + MIS.",
        ctx.describe(),
        args.size,
        args.size,
        args.clamp_spp,
        2 * half
    )?;
    writeln!(out)?;
    writeln!(
        out,
        "| scene | clamp direct | clamp indirect | seconds | mean R | G | B against the reference | RMSE | RMSE ÷ unclamped's |"
    )?;
    writeln!(out, "|---|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    for (name, scene) in scenes {
        let settings = |seed: u32, direct: f32, indirect: f32| RenderSettings {
            seed,
            clamp: crate::scene::Clamp { direct, indirect },
            ..args.settings(scene, KernelKind::Specialized)
        };
        let (reference, reference_noise) =
            reference_halves(ctx, scene, |seed| settings(seed, 0.0, 0.0), half)?;
        let mean = |image: &[Vec3]| {
            image.iter().map(|c| c.as_dvec3()).sum::<glam::DVec3>() / image.len() as f64
        };
        let reference_mean = mean(&reference);
        let mut renderer = Renderer::new(Arc::clone(ctx), scene, settings(1, 0.0, 0.0))?;
        let mut unclamped_rmse = None;
        for (direct, indirect) in CLAMPS {
            renderer.set_clamp(crate::scene::Clamp { direct, indirect });
            renderer.clear_film();
            let seconds = renderer
                .render(0..args.clamp_spp, RenderControl::default())?
                .elapsed
                .as_secs_f64();
            let image = renderer.read_film()?.radiance();
            let rmse = (mean_square_difference(&image, &reference) - reference_noise)
                .max(0.0)
                .sqrt();
            let unclamped = *unclamped_rmse.get_or_insert(rmse);
            let change = (mean(&image) - reference_mean) / reference_mean * 100.0;
            let limit = |l: f32| {
                if l == 0.0 {
                    "off".to_owned()
                } else {
                    l.to_string()
                }
            };
            writeln!(
                out,
                "| {name} | {} | {} | {seconds:.2} | {:+.2}% | {:+.2}% | {:+.2}% | {rmse:.5} | {:.2} |",
                limit(direct),
                limit(indirect),
                change.x,
                change.y,
                change.z,
                rmse / unclamped
            )?;
        }
    }
    Ok(())
}

/// The bounce limits `kiln bench --depth` measures; the last is unbounded.
const DEPTHS: [u32; 11] = [1, 2, 3, 4, 6, 8, 12, 16, 32, 64, UNLIMITED_BOUNCES];

/// Each scene's energy lost to each bounce limit, against unbounded depth, and the time.
/// All renders share the seed, so up to a limit their paths are the same ones: the
/// difference from the unbounded image is the light of the longer paths alone, with
/// little noise of its own.
fn depth(
    ctx: &Arc<GpuContext>,
    scenes: &[(String, Scene)],
    args: &BenchArgs,
    out: &mut dyn std::io::Write,
) -> Result<()> {
    writeln!(
        out,
        "Adapter: {}; {}x{} px, {} spp, specialised kernels, NEE + MIS, Russian roulette; \
         energy: the image's mean per channel against unbounded depth.",
        ctx.describe(),
        args.size,
        args.size,
        args.depth_spp
    )?;
    writeln!(out)?;
    writeln!(
        out,
        "| scene | max bounces | seconds | time ÷ unbounded's | energy lost R | G | B |"
    )?;
    writeln!(out, "|---|---:|---:|---:|---:|---:|---:|")?;
    for (name, scene) in scenes {
        let mut renderer = Renderer::new(
            Arc::clone(ctx),
            scene,
            args.settings(scene, KernelKind::Specialized),
        )?;
        // A warm-up: the driver compiles the kernel at its first dispatch.
        renderer.render(0..1, RenderControl::default())?;
        let mut rows = Vec::new();
        for max_bounces in DEPTHS {
            renderer.set_max_bounces(max_bounces);
            renderer.clear_film();
            let seconds = renderer
                .render(0..args.depth_spp, RenderControl::default())?
                .elapsed
                .as_secs_f64();
            let image = renderer.read_film()?.radiance();
            let mean = image.iter().map(|c| c.as_dvec3()).sum::<glam::DVec3>() / image.len() as f64;
            rows.push((max_bounces, seconds, mean));
        }
        let &(_, unbounded_seconds, unbounded) = rows.last().expect("DEPTHS is not empty");
        for (max_bounces, seconds, mean) in rows {
            let lost = (unbounded - mean) / unbounded * 100.0;
            let limit = if max_bounces == UNLIMITED_BOUNCES {
                "unbounded".to_owned()
            } else {
                max_bounces.to_string()
            };
            writeln!(
                out,
                "| {name} | {limit} | {seconds:.2} | {:.2} | {:.2}% | {:.2}% | {:.2}% |",
                seconds / unbounded_seconds,
                lost.x,
                lost.y,
                lost.z
            )?;
        }
    }
    Ok(())
}

/// Where the specialised kernel's time goes: each scene timed with the kernel cut down to
/// each [`Ablation`] in turn. The walk of the traversal part gives the cost of an
/// incoherent ray without shading; the whole path's rays at that cost are its traversal
/// share, and the rest is shading (materials, BSDFs, lights, media).
fn ablation(
    ctx: &Arc<GpuContext>,
    scenes: &[(String, Scene)],
    args: &BenchArgs,
    out: &mut dyn std::io::Write,
) -> Result<()> {
    writeln!(
        out,
        "Adapter: {}; {}x{} px, specialised kernels, {} s per part after a warm-up; \
         ns/sample is per pixel sample, ns/ray per ray traced.",
        ctx.describe(),
        args.size,
        args.size,
        args.seconds
    )?;
    writeln!(out)?;
    writeln!(
        out,
        "| scene | part | Msamples/s | Mrays/s | rays/sample | ns/sample | ns/ray | share of the full path's time |"
    )?;
    writeln!(out, "|---|---|---:|---:|---:|---:|---:|---|")?;
    for (name, scene) in scenes {
        let mut rows = Vec::new();
        for part in Ablation::ALL {
            let settings = RenderSettings {
                ablation: part,
                ..args.settings(scene, KernelKind::Specialized)
            };
            rows.push((part, measure(ctx, name, scene, args, settings)?));
        }
        let ns_per_sample = |row: &Row| 1e9 / row.samples_per_sec;
        let rays_per_sample = |row: &Row| row.rays_per_sec / row.samples_per_sec;
        let camera = ns_per_sample(&rows[0].1);
        let (_, traversal) = &rows[2];
        // An incoherent ray's cost: the walk's time above the camera's, per ray.
        let per_ray = (ns_per_sample(traversal) - camera) / rays_per_sample(traversal);
        let (_, full) = &rows[3];
        let full_ns = ns_per_sample(full);
        for (part, row) in &rows {
            let share = match part {
                Ablation::Camera => format!("{:.0}% (camera, film)", camera / full_ns * 100.0),
                Ablation::Full => {
                    let tracing = per_ray * rays_per_sample(full);
                    format!(
                        "{:.0}% traversal ({:.2} rays at {per_ray:.0} ns), {:.0}% the rest",
                        tracing / full_ns * 100.0,
                        rays_per_sample(full),
                        (full_ns - camera - tracing) / full_ns * 100.0
                    )
                }
                _ => String::new(),
            };
            let rays = rays_per_sample(row);
            writeln!(
                out,
                "| {name} | {} | {:.3} | {:.2} | {rays:.2} | {:.0} | {} | {share} |",
                part.name(),
                row.samples_per_sec / 1e6,
                row.rays_per_sec / 1e6,
                ns_per_sample(row),
                if rays > 0.0 {
                    format!("{:.0}", (ns_per_sample(row) - camera) / rays)
                } else {
                    "–".to_owned()
                },
            )?;
        }
    }
    Ok(())
}

/// `kiln bench --fetch`: nanoseconds per dependent vec4 load, from a storage buffer and
/// from a texel table read each way the adapter can ([`TexelReads`];
/// shaders/bench/fetch.wgsl), at a 16 KiB and a 16 MiB working set.
fn fetch(ctx: &GpuContext, out: &mut dyn std::io::Write) -> Result<()> {
    use wgpu::util::DeviceExt;

    const SOURCE: &str = include_str!("../shaders/bench/fetch.wgsl");
    const ENTRIES: u32 = 1 << 20;
    const ROW: u32 = 1024;
    const STEPS: u32 = 64;
    const WIDTH: u32 = 512;
    let device = &ctx.device;
    let words: Vec<u32> = (0..ENTRIES * 4)
        .map(|i| i.wrapping_mul(2_654_435_761))
        .collect();
    let entries_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("fetch entries"),
        contents: bytemuck::cast_slice(&words),
        usage: wgpu::BufferUsages::STORAGE,
    });
    // One texel per entry, ROW to a row, as shaders/bench/fetch.wgsl reads them.
    let texels = texel_table(
        ctx,
        "fetch texels",
        TexelLayout {
            texels: 1,
            per_row: ROW,
        },
        bytemuck::cast_slice::<u32, [u32; 4]>(&words),
        &mut 0,
    )?;
    let view = texels.create_view(&Default::default());
    let sink = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("fetch sink"),
        size: u64::from(WIDTH * WIDTH) * 4,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    // How the table is read, or None for the storage buffer.
    let mut ways = vec![None, Some(TexelReads::Sampled)];
    if ctx.storage_texels {
        ways.push(Some(TexelReads::Storage));
    }
    writeln!(
        out,
        "Adapter: {}; {WIDTH}x{WIDTH} invocations, each a chain of {STEPS} dependent vec4 loads; \
         the best of 4 dispatches (the first compiles).",
        ctx.describe()
    )?;
    writeln!(out)?;
    writeln!(
        out,
        "| working set | storage buffer | sampled texture | storage texture |"
    )?;
    writeln!(out, "|---|---:|---:|---:|")?;
    for entries in [1u32 << 10, ENTRIES] {
        let mut ns = Vec::new();
        for way in &ways {
            let reads = way.unwrap_or_default();
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("fetch"),
                entries: &[
                    layout_entry(0, Space::ReadOnly, 0),
                    wgpu::BindGroupLayoutEntry {
                        ty: reads.binding_type(),
                        ..layout_entry(1, Space::Texels, 0)
                    },
                    layout_entry(2, Space::ReadWrite, 0),
                ],
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("fetch"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: entries_buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: sink.as_entire_binding(),
                    },
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("fetch"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let source = format!(
                "const FETCH_FROM_BUFFER: bool = {};\nconst FETCH_MASK: u32 = {}u;\n\
                 const FETCH_STEPS: u32 = {STEPS}u;\nconst FETCH_WIDTH: u32 = {WIDTH}u;\n{}{SOURCE}",
                way.is_none(),
                entries - 1,
                reads.wgsl(),
            );
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("fetch"),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            });
            let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("fetch"),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some("fetch_chain"),
                compilation_options: Default::default(),
                cache: None,
            });
            let mut best = f64::INFINITY;
            for _ in 0..4 {
                let t = Instant::now();
                let mut encoder = device.create_command_encoder(&Default::default());
                {
                    let mut pass = encoder.begin_compute_pass(&Default::default());
                    pass.set_pipeline(&pipeline);
                    pass.set_bind_group(0, &bind_group, &[]);
                    pass.dispatch_workgroups(WIDTH / 8, WIDTH / 8, 1);
                }
                ctx.queue.submit([encoder.finish()]);
                device
                    .poll(wgpu::PollType::wait_indefinitely())
                    .map_err(|e| anyhow::anyhow!("waiting for the fetch benchmark: {e}"))?;
                best = best.min(t.elapsed().as_secs_f64());
            }
            ns.push(format!(
                "{:.2} ns",
                best * 1e9 / f64::from(WIDTH * WIDTH * STEPS)
            ));
        }
        ns.resize(3, "–".to_owned());
        writeln!(
            out,
            "| {} KiB | {} |",
            u64::from(entries) * 16 / 1024,
            ns.join(" | ")
        )?;
    }
    Ok(())
}

/// The least-squares slope of y against x.
fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(x, y), p| (x + p.0 / n, y + p.1 / n));
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(sxy, sxx), (x, y)| {
        (sxy + (x - mx) * (y - my), sxx + (x - mx) * (x - mx))
    });
    if sxx > 0.0 { sxy / sxx } else { f64::NAN }
}

/// Samples/s and rays/s of each scene at each kernel kind, then the import's time.
fn throughput(
    ctx: &Arc<GpuContext>,
    scenes: &[(String, Scene)],
    import: Result<(Duration, Option<u64>, u64)>,
    args: &BenchArgs,
    out: &mut dyn std::io::Write,
) -> Result<()> {
    writeln!(
        out,
        "Adapter: {}; {}x{} px, max bounces from each scene, NEE + MIS.",
        ctx.describe(),
        args.size,
        args.size
    )?;
    writeln!(out)?;
    writeln!(
        out,
        "| scene | kernel | triangles | BVH build | kernel build (naga + pipeline + volume bake) | volume bake | first dispatch | Msamples/s | Mrays/s |"
    )?;
    writeln!(out, "|---|---|---:|---:|---:|---:|---:|---:|---:|")?;
    for (name, scene) in scenes {
        for kernel in [
            KernelKind::Specialized,
            KernelKind::General,
            KernelKind::Interpreted,
        ] {
            let row = measure(ctx, name, scene, args, args.settings(scene, kernel))?;
            writeln!(
                out,
                "| {} | {} | {} | {:.1} ms | {:.0} ms | {} | {:.0} ms | {:.3} | {:.2} |",
                row.name,
                match kernel {
                    KernelKind::Specialized => "specialised",
                    KernelKind::General => "everything",
                    KernelKind::Interpreted => "interpreted",
                },
                row.triangles,
                row.bvh.as_secs_f64() * 1e3,
                row.kernel.as_secs_f64() * 1e3,
                row.volume_bake.map_or("–".to_owned(), |d| format!(
                    "{:.0} ms",
                    d.as_secs_f64() * 1e3
                )),
                row.first_dispatch.as_secs_f64() * 1e3,
                row.samples_per_sec / 1e6,
                row.rays_per_sec / 1e6
            )?;
        }
    }
    writeln!(out)?;
    match import {
        Ok((time, extra, triangles)) => writeln!(
            out,
            "glTF import ({triangles} triangles, .glb through the plugin): {:.0} ms, peak memory +{}",
            time.as_secs_f64() * 1e3,
            extra.map_or("unknown".into(), |b| format!(
                "{:.0} MiB",
                b as f64 / (1u64 << 20) as f64
            ))
        )?,
        Err(e) => writeln!(out, "glTF import: not measured ({e:#})")?,
    }
    Ok(())
}

/// Writes `mesh` as a minimal binary glTF (one node, one primitive with positions and
/// normals when present, u32 indices): the input of the import benchmark and tests.
pub fn write_glb(mesh: &crate::scene::Mesh, path: &std::path::Path) -> std::io::Result<()> {
    let mut bin: Vec<u8> = Vec::new();
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for p in &mesh.positions {
        lo = lo.min(*p);
        hi = hi.max(*p);
        bin.extend(bytemuck::bytes_of(&p.to_array()));
    }
    let positions_len = bin.len();
    let has_normals = mesh.normals.len() == mesh.positions.len();
    if has_normals {
        for n in &mesh.normals {
            bin.extend(bytemuck::bytes_of(&n.to_array()));
        }
    }
    let indices_offset = bin.len();
    for t in &mesh.indices {
        bin.extend(bytemuck::bytes_of(t));
    }
    let count = mesh.positions.len();
    let normal_attr = if has_normals { r#","NORMAL":2"# } else { "" };
    let normal_view = if has_normals {
        format!(r#",{{"buffer":0,"byteOffset":{positions_len},"byteLength":{positions_len}}}"#)
    } else {
        String::new()
    };
    let normal_accessor = if has_normals {
        format!(r#",{{"bufferView":2,"componentType":5126,"count":{count},"type":"VEC3"}}"#)
    } else {
        String::new()
    };
    let json = format!(
        concat!(
            r#"{{"asset":{{"version":"2.0","generator":"kiln bench"}},"scene":0,"scenes":[{{"nodes":[0]}}],"#,
            r#""nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0{normal_attr}}},"indices":1}}]}}],"#,
            r#""buffers":[{{"byteLength":{total}}}],"#,
            r#""bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{plen}}},{{"buffer":0,"byteOffset":{ioff},"byteLength":{ilen}}}{normal_view}],"#,
            r#""accessors":[{{"bufferView":0,"componentType":5126,"count":{count},"type":"VEC3","min":[{lx},{ly},{lz}],"max":[{hx},{hy},{hz}]}},"#,
            r#"{{"bufferView":1,"componentType":5125,"count":{icount},"type":"SCALAR"}}{normal_accessor}]}}"#
        ),
        normal_attr = normal_attr,
        total = bin.len(),
        plen = positions_len,
        ioff = indices_offset,
        ilen = bin.len() - indices_offset,
        normal_view = normal_view,
        count = count,
        lx = lo.x,
        ly = lo.y,
        lz = lo.z,
        hx = hi.x,
        hy = hi.y,
        hz = hi.z,
        icount = mesh.indices.len() * 3,
        normal_accessor = normal_accessor,
    );
    let mut json = json.into_bytes();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    use std::io::Write;
    out.write_all(b"glTF")?;
    out.write_all(&2u32.to_le_bytes())?;
    out.write_all(&(total as u32).to_le_bytes())?;
    out.write_all(&(json.len() as u32).to_le_bytes())?;
    out.write_all(b"JSON")?;
    out.write_all(&json)?;
    out.write_all(&(bin.len() as u32).to_le_bytes())?;
    out.write_all(b"BIN\0")?;
    out.write_all(&bin)?;
    out.flush()
}

/// Resident memory of this process (Linux /proc/self/status): (now, peak so far), bytes.
pub fn memory() -> Option<(u64, u64)> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let field = |name: &str| -> Option<u64> {
        let line = status.lines().find(|l| l.starts_with(name))?;
        Some(line.split_whitespace().nth(1)?.parse::<u64>().ok()? * 1024)
    };
    Some((field("VmRSS:")?, field("VmHWM:")?))
}

/// Imports a `triangles`-triangle glTF through the plugin host: (time, extra peak memory
/// over the memory in use before, triangles imported). Run first in a process, before
/// rendering raises the peak.
pub fn measure_import(triangles: u32) -> Result<(Duration, Option<u64>, u64)> {
    let host = crate::plugin::PluginHost::discover(&[]);
    let dir = tempfile::tempdir()?;
    let path = dir.path().join("sphere.glb");
    {
        let mesh = shapes::displaced_sphere(triangles);
        write_glb(&mesh, &path)?;
    }
    let before = memory();
    let t = Instant::now();
    let imported = host.import(&path)?;
    let elapsed = t.elapsed();
    let after = memory();
    let extra = match (before, after) {
        (Some((rss, _)), Some((_, peak))) => Some(peak.saturating_sub(rss)),
        _ => None,
    };
    Ok((elapsed, extra, imported.scene.triangle_count()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth image with structure: a gradient and a bright disc.
    fn picture(width: usize, height: usize) -> Vec<Vec3> {
        (0..width * height)
            .map(|i| {
                let (x, y) = ((i % width) as f32, (i / width) as f32);
                let disc = if (x - 20.0).hypot(y - 12.0) < 6.0 {
                    4.0
                } else {
                    0.0
                };
                Vec3::new(x / width as f32 + disc, y / height as f32, 0.3)
            })
            .collect()
    }

    #[test]
    fn ssim_is_one_for_equal_images_and_falls_with_noise_and_lost_structure() {
        let (w, h) = (40, 24);
        let a = picture(w, h);
        assert!((ssim(&a, &a, w, h) - 1.0).abs() < 1e-9);
        // Deterministic noise of two amplitudes: more noise, lower similarity.
        let noisy = |amplitude: f32| -> Vec<Vec3> {
            a.iter()
                .enumerate()
                .map(|(i, c)| {
                    let n = ((i as u32).wrapping_mul(2_654_435_761) >> 8) as f32 / 16_777_216.0;
                    (*c + Vec3::splat(amplitude * (n - 0.5))).max(Vec3::ZERO)
                })
                .collect()
        };
        let (slight, strong) = (ssim(&noisy(0.05), &a, w, h), ssim(&noisy(0.5), &a, w, h));
        assert!(slight < 1.0 && strong < slight, "{slight} {strong}");
        assert!(strong > 0.0, "{strong}");
        // A uniform image of the same mean keeps the luminance term but loses structure.
        let mean = a.iter().copied().sum::<Vec3>() / a.len() as f32;
        let flat = vec![mean; a.len()];
        assert!(ssim(&flat, &a, w, h) < 0.5);
    }

    #[test]
    fn the_tradeoff_plot_is_a_png_of_a_panel_per_scene() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("plot.png");
        let row = |scene: &str, method: &str, seconds, rel_mse| TradeoffRow {
            scene: scene.into(),
            method: method.into(),
            seconds,
            rel_mse,
        };
        let rows = [
            row("a", "plain", 0.5, 0.02),
            row("a", "plain", 1.0, 0.01),
            row("a", "atrous", 0.5, 0.008),
            row("a", "atrous", 1.0, 0.005),
            row("b", "plain", 0.5, 0.3),
            row("b", "plain", 1.0, 0.1),
        ];
        plot_tradeoff(&path, &rows).unwrap();
        let image = image::open(&path).unwrap().to_rgb8();
        assert_eq!(image.dimensions(), (720, 2 * 520));
        // Something was drawn: not all white.
        assert!(image.pixels().any(|p| p.0 != [255, 255, 255]));
    }
}
