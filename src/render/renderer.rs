//! The progressive renderer: uploads a scene once, then renders any range of sample
//! indices into its film in whole-image passes. A pass adds the same number of samples
//! to every pixel, in dispatches short enough that none runs long ([`Pacing`]: tiles of
//! 256×256 pixels with the samples per pass adapted to a time target for a final render,
//! or small tiles sized to a budget of a few milliseconds for the editor); the film lives
//! on the device in pieces that each fit a binding (`film_pieces.rs`). An edit of the
//! scene can be written into a built renderer (`update.rs`).
//!
//! A render stops (cancel, deadline) only between dispatches and never before the film
//! holds one whole pass, so a stopped render has a sample in every pixel and sample
//! counts that differ across pixels by at most one pass's batch; each pixel is normalised
//! by its own count.
//!
//! Samples are pure functions of (pixel, sample index, seed), and each pixel adds its
//! samples in index order, so the film after `render(0..n)` is the same bits however the
//! work was cut into passes and dispatches, and `render(0..k)` then `render(k..n)` equals
//! `render(0..n)`.

use std::ops::Range;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use thiserror::Error;

use super::context::{GpuContext, GpuError};
use super::film_pieces::{
    AOV_BYTES, DeviceFilm, FilmPiece, SUM_BYTES, SharedBuffers, allocate_pieces, memory_check,
    piece_rows, read_aov_rows, read_exact_film_rows, read_film_rows, read_noise_rows,
};
use super::gpu_scene::{GpuScene, UploadError, scene_bind_group_layout};
use super::kernel::{KernelError, path_tracing_kernel};
use super::readback::map_and_read;
use crate::accel::query::Enclosures;
use crate::accel::{AccelError, build_scene_accel};
use crate::film::{ExactFilm, Film};
use crate::scene::Scene;
use crate::shader::bindings::TexelReads;
use crate::shader::gpu_types::{
    FLAG_ENVIRONMENT_MAP, FLAG_LIGHT_SAMPLING, FLAG_SHADOW_CATCHER, GpuParams, GpuStats,
};
use crate::shader::sampling::Sampling;
use crate::shader::{Ablation, KernelFeatures};

const TILE_SIZE: u32 = 256;
const GIB: f64 = (1u64 << 30) as f64;
const MIB: f64 = (1u64 << 20) as f64;
const WORKGROUP_SIZE: u32 = 8;
/// How long a tile's batch of samples (one submission) should take.
const TARGET_BATCH: Duration = Duration::from_millis(60);
/// The most samples in a tile's batch: a dispatch per sample, each reading its own slot
/// of the params buffer, which holds this many. 64 already amortises a submission's
/// overhead.
const MAX_BATCH: u32 = 64;
/// Adaptive sampling checks the film first after this many samples per pixel: fewer
/// make the variance estimate too noisy to stop on.
pub const ADAPTIVE_MIN_SAMPLES: u32 = 16;

/// Whether adaptive sampling checks the film once a pixel has `samples` samples: after
/// [`ADAPTIVE_MIN_SAMPLES`], then every 16 samples up to 256, then in steps of about an
/// eighth of the count (multiples of 16), so that a check's cost stays small next to the
/// samples between checks. A function of the count alone, so the same render stops the
/// same pixels however it is timed.
pub fn is_adaptive_check(samples: u32) -> bool {
    next_adaptive_check(samples.saturating_sub(1)) == samples
}

/// The first sample count after `samples` at which adaptive sampling checks the film.
pub fn next_adaptive_check(samples: u32) -> u32 {
    let mut check = ADAPTIVE_MIN_SAMPLES;
    while check <= samples {
        check = check.saturating_add((check / 8 / 16 * 16).max(16));
    }
    check
}

/// `bake_volume_grid`'s workgroup size, and the grid points one bake dispatch evaluates:
/// short dispatches, as the render's.
const BAKE_WORKGROUP_SIZE: u32 = 64;
const BAKE_VOXELS_PER_DISPATCH: u32 = 1 << 16;

/// The first tile side of [`Pacing::Interactive`], and the range it adapts in: 16² pixels
/// keep a dispatch's fixed cost small next to its work, 256² is the final render's tile.
const INTERACTIVE_FIRST_TILE: u32 = 64;
const INTERACTIVE_MIN_TILE: u32 = 16;

/// The next tile side for a dispatch budget of `budget_us`, given that tiles of side
/// `tile` took `mean` each: grows or shrinks the area by about 2× a step, in multiples of
/// the workgroup size.
fn adapt_tile(tile: u32, mean: Duration, budget_us: u32) -> u32 {
    let budget = Duration::from_micros(budget_us as u64);
    let next = if mean < budget / 2 {
        tile * 3 / 2
    } else if mean > budget * 3 / 2 {
        tile * 2 / 3
    } else {
        tile
    };
    (next / WORKGROUP_SIZE * WORKGROUP_SIZE).clamp(INTERACTIVE_MIN_TILE, TILE_SIZE)
}

#[derive(Debug, Error)]
pub enum RenderError {
    #[error("invalid scene: {0}")]
    Scene(String),
    #[error(transparent)]
    Accel(#[from] AccelError),
    #[error(transparent)]
    Upload(#[from] UploadError),
    #[error(transparent)]
    Kernel(#[from] KernelError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Material(#[from] crate::material::GraphError),
    #[error(
        "a {width}x{height} film needs {:.1} GiB of memory, but {:.1} GiB are available: at this aspect ratio the largest film that fits is about {max_width}x{max_height}",
        *.needed as f64 / GIB,
        *.available as f64 / GIB
    )]
    FilmTooLarge {
        width: u32,
        height: u32,
        needed: u64,
        available: u64,
        max_width: u32,
        max_height: u32,
    },
    #[error(
        "the device ran out of memory for a {width}x{height} film ({:.1} GiB): render a smaller image ({message})",
        *.bytes as f64 / GIB
    )]
    FilmOutOfMemory {
        width: u32,
        height: u32,
        bytes: u64,
        message: String,
    },
    #[error(
        "{lost}. On the device: {triangles} triangles and {:.1} MiB of scene and film for a {width}x{height} image; the adapter allows {:.0} MiB in one buffer. A driver crash, a dispatch the system stopped for running too long, or the device running out of memory loses it; a checkpoint already written stays valid (kiln render --resume)",
        *.bytes as f64 / MIB,
        *.max_buffer as f64 / MIB
    )]
    DeviceLost {
        lost: GpuError,
        triangles: u64,
        bytes: u64,
        width: u32,
        height: u32,
        max_buffer: u64,
    },
    #[error(
        "the device ran out of memory uploading the scene ({triangles} triangles in {meshes} meshes; the adapter allows {:.0} MiB in one buffer): make the scene smaller or use a device with more memory ({message})",
        *.max_buffer as f64 / MIB
    )]
    SceneOutOfMemory {
        triangles: u64,
        meshes: usize,
        max_buffer: u64,
        message: String,
    },
    #[error("cannot denoise: {0}")]
    Denoise(String),
    #[error(
        "one film row of {width} pixels needs {row_bytes} bytes, more than the {limit}-byte limit of a film buffer"
    )]
    FilmRowTooLarge {
        width: u32,
        row_bytes: u64,
        limit: u64,
    },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub samples_per_pixel: u32,
    /// Scattering events per path; 0 shows only what the camera sees directly.
    pub max_bounces: u32,
    /// Scattering events in volumes per path; past them media only absorb
    /// ([`crate::scene::SceneSettings::max_volume_bounces`]).
    pub max_volume_bounces: u32,
    pub seed: u32,
    /// The sampler and the pixel filter: parameters, not kernel changes.
    pub sampling: Sampling,
    /// Grid points along the longest side of a heterogeneous volume's bounds
    /// ([`crate::scene::SceneSettings::volume_resolution`]).
    pub volume_resolution: u32,
    /// The firefly clamp ([`crate::scene::Clamp`]); a parameter, not a kernel change.
    pub clamp: crate::scene::Clamp,
    /// Adaptive sampling: a pixel whose estimated noise (`shaders/integrator/adaptive.wgsl`)
    /// falls below this takes no more samples; 0 for off. The samples per pixel and the
    /// time limit still bound the render.
    pub noise_threshold: f32,
    /// Next-event estimation with multiple importance sampling; off means BSDF sampling
    /// alone (useful as a reference: both must converge to the same image).
    pub light_sampling: bool,
    /// Page size in bytes of the paged scene arrays (BVH nodes, triangles); default: the
    /// largest binding the adapter allows. Tests lower it to exercise paging.
    pub page_bytes: Option<u64>,
    /// What the kernel is specialised to: final renders compile only what the scene uses,
    /// the editor a kernel that takes edits without a compile.
    pub kernel: KernelKind,
    /// Also render the albedo, normal and depth AOVs ([`Renderer::read_aovs`]), and
    /// estimate the noise ([`Renderer::read_noise`]).
    pub aovs: bool,
    /// Largest film buffer in bytes; default: the largest binding the adapter allows. A
    /// film beyond it is split into pieces of whole rows; tests lower it to split small
    /// films.
    pub film_piece_bytes: Option<u64>,
    /// The kernel cut down to a part of its work, for `kiln bench --ablation`; renders
    /// use [`Ablation::Full`].
    pub ablation: Ablation,
    /// How the kernel reads its texel tables; default: the context's choice
    /// ([`GpuContext::texel_reads`]). Tests set it to check that both read the same.
    pub texel_reads: Option<TexelReads>,
}

/// What a kernel is specialised to, from the fastest to build on to the fastest to edit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelKind {
    /// Only the lobes and light types the scene uses, each graph material compiled with
    /// its constants folded in: final renders (the default).
    Specialized,
    /// Every lobe and light type, graph materials compiled with their constants read from
    /// a buffer: a value edit is a buffer write, other edits of a graph a compile.
    General,
    /// Every lobe and light type, graph materials run by an interpreter from a buffer
    /// ([`crate::material::compile::compile_program`]): any edit of a graph is a buffer
    /// write (the editor). Graphs the interpreter cannot run are compiled as in
    /// [`KernelKind::General`].
    Interpreted,
}

impl RenderSettings {
    pub fn from_scene(scene: &Scene) -> Self {
        Self {
            width: scene.settings.width,
            height: scene.settings.height,
            samples_per_pixel: scene.settings.samples_per_pixel,
            max_bounces: scene.settings.max_bounces,
            max_volume_bounces: scene.settings.max_volume_bounces,
            clamp: scene.settings.clamp,
            noise_threshold: scene.settings.noise_threshold,
            seed: scene.settings.seed,
            sampling: scene.settings.sampling,
            volume_resolution: scene.settings.volume_resolution,
            light_sampling: true,
            page_bytes: None,
            kernel: KernelKind::Specialized,
            aovs: false,
            film_piece_bytes: None,
            ablation: Ablation::Full,
            texel_reads: None,
        }
    }
}

/// Auxiliary images of the first surface each camera path meets (see
/// [`Renderer::read_aovs`]): 3, 3, 1 and 3 floats per pixel.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Aovs {
    pub albedo: Vec<f32>,
    pub normal: Vec<f32>,
    pub depth: Vec<f32>,
    /// The light the camera sees emitted directly, by surfaces and the sky (Cycles' Emit
    /// and Background passes together): part of the image, kept out of the denoiser.
    pub emission: Vec<f32>,
    /// Coverage: 1 where the camera sees a surface, 0 where it sees the sky, and on a
    /// shadow catcher the share of the light that objects block (its shadow's opacity).
    pub alpha: Vec<f32>,
}

/// Reported after every dispatch.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    pub pixel_samples_done: u64,
    pub pixel_samples_total: u64,
    pub rays: u64,
    pub elapsed: Duration,
    /// Whole passes over the image finished in this call.
    pub passes_done: u32,
    /// Samples every pixel has received in this call (those of the whole passes).
    pub whole_pass_samples: u32,
    /// Samples per pixel the pass under way adds.
    pub pass_samples: u32,
    /// Share of the image the pass under way has covered, in [0, 1).
    pub pass_fraction: f64,
    /// Time since the pass under way began.
    pub pass_elapsed: Duration,
    /// Pixels adaptive sampling has not found converged (see [`RenderStats`]).
    pub active_pixels: Option<u64>,
}

/// How a caller steers a render: stop it, bound it in time, watch it.
#[derive(Default)]
pub struct RenderControl<'a> {
    pub cancel: Option<&'a AtomicBool>,
    pub deadline: Option<Instant>,
    pub progress: Option<&'a mut dyn FnMut(&Progress)>,
    /// Lets a cancel stop the film's first pass too. The film is then partial (some
    /// pixels have no sample): the caller throws it away ([`Renderer::clear_film`]), as
    /// the editor's viewport does when a new scene or a built renderer replaces a pass.
    pub cancel_first_pass: bool,
    /// Stops at the end of the first whole pass that ends after this instant, with
    /// `checkpoint` set in the stats: every pixel then has the same samples (those below
    /// [`RenderStats::next_sample`]), a state a checkpoint can keep and a later
    /// `render(next_sample..)` continue bit for bit.
    pub pass_deadline: Option<Instant>,
}

impl RenderStats {
    /// Adds a later call's stats to these: one render made of several calls.
    pub fn merge(&mut self, later: &RenderStats) {
        self.pixel_samples += later.pixel_samples;
        self.rays += later.rays;
        self.non_finite += later.non_finite;
        self.dispatches += later.dispatches;
        self.elapsed += later.elapsed;
        self.completed = later.completed;
        self.passes += later.passes;
        self.active_pixels = later.active_pixels.or(self.active_pixels);
        self.next_sample = later.next_sample;
        self.checkpoint = later.checkpoint;
        self.first_pass = self.first_pass.or(later.first_pass);
    }

    /// Adds what a dispatch (or a pass's dispatches) reported.
    fn add(&mut self, s: &GpuStats) {
        self.rays += s.rays as u64;
        self.non_finite += s.non_finite as u64;
        self.pixel_samples -= self.pixel_samples.min(s.skipped_samples as u64);
    }
}

#[derive(Clone, Copy, Debug, Default)]
pub struct RenderStats {
    pub pixel_samples: u64,
    pub rays: u64,
    /// Samples whose radiance was NaN or infinite; the kernel counts them as black.
    pub non_finite: u64,
    pub dispatches: u32,
    pub elapsed: Duration,
    /// False when cancelled or out of time before the range was done.
    pub completed: bool,
    /// Whole passes over the image finished.
    pub passes: u32,
    /// Pixels adaptive sampling has not found converged, after its last check in this
    /// call; None without adaptive sampling or before its first check.
    pub active_pixels: Option<u64>,
    /// The first sample index not yet in every pixel: the end of the last whole pass.
    pub next_sample: u32,
    /// Stopped at the end of a pass for [`RenderControl::pass_deadline`].
    pub checkpoint: bool,
    /// How long the film's first whole pass took, when this call rendered it: a cancel or
    /// deadline waits for it, so it can run past a time limit.
    pub first_pass: Option<Duration>,
}

/// What building the renderer cost, for `kiln bench` and the CLI's summary.
#[derive(Clone, Copy, Debug, Default)]
pub struct BuildInfo {
    pub triangles: u64,
    pub instances: u32,
    pub emissive_triangles: u32,
    pub accel_build: Duration,
    pub upload: Duration,
    pub upload_bytes: u64,
    /// naga validation, pipeline creation and the driver's compile at first dispatch.
    pub kernel_build: Duration,
    /// Whether the kernel was compiled for this renderer (false: the device's pipeline
    /// cache had it).
    pub kernel_compiled: bool,
    /// Evaluating the heterogeneous volumes into their grids (part of `kernel_build`,
    /// after the bake kernel's compile).
    pub volume_bake: Duration,
    /// Grid points baked.
    pub volume_voxels: u64,
    /// Baking the world graph into its map (compile and evaluation; zero when the bake of
    /// an identical world was remembered, or the scene has no world), and the map's texels.
    pub world_bake: Duration,
    pub world_texels: u64,
}

pub struct Renderer {
    pub(super) ctx: Arc<GpuContext>,
    pipeline: wgpu::ComputePipeline,
    /// `bake_volume_grid`, for a scene with heterogeneous volumes.
    bake_pipeline: Option<wgpu::ComputePipeline>,
    /// `adaptive_error` and `adaptive_converge`, when the noise is estimated.
    noise_pipelines: Option<[wgpu::ComputePipeline; 2]>,
    /// Whether adaptive sampling found every pixel converged.
    all_converged: bool,
    /// [`MAX_BATCH`] slots of `Params`, one per dispatch of a batch (`Space::UniformSlots`).
    params_buffer: wgpu::Buffer,
    /// Bytes from one slot to the next: `Params` rounded up to the device's alignment of
    /// uniform offsets.
    params_stride: u64,
    /// The scene's buffers, which edits write into (`update.rs`).
    pub(super) gpu_scene: GpuScene,
    /// The meshes' BVHs, kept so a transform edit rebuilds only the top level.
    pub(super) blas: Vec<Option<crate::accel::Bvh>>,
    /// The objects holding media, to find those around the camera.
    pub(super) enclosures: Enclosures,
    /// What the kernel was built with: an edit that needs other features or other
    /// material code needs a new renderer.
    pub(super) features: KernelFeatures,
    pub(super) materials_wgsl: Vec<(String, String)>,
    /// How the passes are cut (see [`Pacing`]).
    pacing: Pacing,
    /// Side of the square tiles the interactive pacing dispatches; adapted to its budget.
    tile_size: u32,
    /// The film, in bands of rows that each fit a binding.
    pieces: Vec<FilmPiece>,
    /// Whether every pixel of the film holds at least one whole pass: until it does,
    /// only an error stops a render.
    film_has_whole_pass: bool,
    stats_buffer: wgpu::Buffer,
    stats_staging: wgpu::Buffer,
    pub(super) base_params: GpuParams,
    pub(super) settings: RenderSettings,
    /// Samples per pixel a tile's submission adds, adapted to [`TARGET_BATCH`].
    samples_per_batch: u32,
    pub build_info: BuildInfo,
}

/// The features of the kernel a renderer with `settings` builds for a scene needing
/// `scene_features`.
pub(super) fn kernel_features(
    scene_features: KernelFeatures,
    settings: &RenderSettings,
) -> KernelFeatures {
    let features = KernelFeatures {
        aovs: settings.aovs,
        noise: settings.aovs || settings.noise_threshold > 0.0,
        ablation: settings.ablation,
        texel_reads: settings.texel_reads.unwrap_or(scene_features.texel_reads),
        sampler: Some(settings.sampling.sampler),
        ..scene_features
    };
    // `everything` keeps the bindings, so one layout serves both kernels.
    match settings.kernel {
        KernelKind::Specialized => features,
        KernelKind::General | KernelKind::Interpreted => features.everything(),
    }
}

/// How a renderer cuts its passes into dispatches. Either way the film is the same bits
/// (samples are functions of pixel and index alone); what differs is how long the device's
/// queue is held at a time and what a render reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pacing {
    /// Tiles of 256×256 pixels with the samples per dispatch adapted to about 60 ms, the
    /// statistics read back after each dispatch: throughput first (`kiln render`).
    Final,
    /// Square tiles adapted so that one dispatch takes about `budget_us` microseconds, and
    /// statistics read once a pass, not after each dispatch: the queue is free between
    /// dispatches for others (the editor's UI, on a software adapter that runs one
    /// submission at a time). Progress reports come per dispatch but count rays only at
    /// the end of a pass.
    Interactive { budget_us: u32 },
}

/// The parts of `Params` fixed for a scene and settings.
pub fn base_params(scene: &Scene, gpu: &GpuScene, settings: &RenderSettings) -> GpuParams {
    let cam = &scene.camera;
    let (right, up, forward) = cam.frame();
    GpuParams {
        film_size: [settings.width, settings.height],
        seed: settings.seed,
        max_bounces: settings.max_bounces,
        max_volume_bounces: settings.max_volume_bounces,
        clamp_direct: settings.clamp.direct,
        clamp_indirect: settings.clamp.indirect,
        noise_threshold: settings.noise_threshold,
        sampler: settings.sampling.sampler.gpu_id(),
        filter_quantiles: settings.sampling.filter.quantiles(),
        flags: if settings.light_sampling {
            FLAG_LIGHT_SAMPLING
        } else {
            0
        } | if gpu.has_environment_map {
            FLAG_ENVIRONMENT_MAP
        } else {
            0
        } | if gpu.has_shadow_catcher {
            FLAG_SHADOW_CATCHER
        } else {
            0
        },
        light_count: gpu.light_count,
        instance_count: gpu.instance_count,
        opaque_one: 1.0,
        triangle_page_shift: gpu.triangle_page_shift,
        node_page_shift: gpu.node_page_shift,
        cam_position: cam.position.extend(1.0).into(),
        cam_right: right.extend(0.0).into(),
        cam_up: up.extend(0.0).into(),
        cam_forward: forward.extend(0.0).into(),
        cam_lens: [
            (cam.fov_y_degrees.to_radians() * 0.5).tan(),
            settings.width as f32 / settings.height as f32,
            cam.aperture_radius,
            cam.focus_distance,
        ],
        environment: scene.environment.extend(gpu.environment_pick).into(),
        light_power: gpu.light_power,
        triangle_pick: gpu.triangle_pick,
        light_split: gpu.light_split,
        local_lights: gpu.local_lights,
        analytic_light_count: gpu.analytic_light_count,
        // Set per dispatch, for the piece it renders into.
        film_piece_start: 0,
        ..GpuParams::default()
    }
}

/// Builds a small renderer of `scene` with `settings` on `ctx` and drops it, so that the
/// driver has compiled its kernel there (see [`GpuContext::rehearse_compiles_on`]). The
/// film's size is not part of what the driver compiles for: 8 × 8 pixels serve.
fn rehearse(ctx: &Arc<GpuContext>, scene: &Scene, settings: &RenderSettings) {
    let small = RenderSettings {
        width: settings.width.min(8),
        height: settings.height.min(8),
        ..*settings
    };
    let started = Instant::now();
    match Renderer::new(Arc::clone(ctx), scene, small) {
        Ok(_) => tracing::debug!(
            "kernel rehearsed on the second device in {:.0} ms",
            started.elapsed().as_secs_f64() * 1e3
        ),
        // The real build reports what went wrong.
        Err(e) => tracing::debug!("the kernel's rehearsal failed: {e}"),
    }
}

impl Renderer {
    pub fn new(
        ctx: Arc<GpuContext>,
        scene: &Scene,
        settings: RenderSettings,
    ) -> Result<Self, RenderError> {
        scene.validate().map_err(RenderError::Scene)?;
        let original = scene;
        // A world graph renders as the environment map and sun lights it bakes into.
        let world_texels = scene
            .world
            .as_ref()
            .map_or(0, |w| u64::from(w.resolution) * u64::from(w.resolution / 2));
        let world_start = Instant::now();
        let resolved = super::world_bake::resolve_world(&ctx, scene)?;
        let world_bake = world_start.elapsed();
        let scene: &Scene = &resolved;
        // Hidden objects stay in the scene (and its file) but are not rendered.
        let shown;
        let scene = if scene.instances.iter().all(|i| i.visible) {
            scene
        } else {
            shown = scene.without_hidden();
            &shown
        };
        crate::scene::validate_image_size(settings.width, settings.height)
            .map_err(RenderError::Scene)?;
        crate::scene::validate_volume_resolution(settings.volume_resolution)
            .map_err(RenderError::Scene)?;

        let accel = build_scene_accel(scene)?;
        let upload_start = Instant::now();
        let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let gpu_scene = GpuScene::upload(
            &ctx,
            scene,
            &accel,
            settings.page_bytes,
            settings.volume_resolution,
        );
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::SceneOutOfMemory {
                triangles: scene.triangle_count(),
                meshes: scene.meshes.len(),
                max_buffer: ctx.device.limits().max_buffer_size,
                message: e.to_string(),
            });
        }
        ctx.check_lost("uploading the scene")?;
        let gpu_scene = gpu_scene?;
        let upload = upload_start.elapsed();

        let kernel_start = Instant::now();
        let device = &ctx.device;
        let features = kernel_features(gpu_scene.features(), &settings);
        let layout = scene_bind_group_layout(device, &features);
        // The unspecialised kernel (the editor's) reads the graphs' constants from a
        // buffer, so that a value edit is a write, not a kernel.
        let materials = super::materials::scene_materials(scene, settings.kernel)?;
        if !materials.parameters.is_empty() {
            ctx.queue.write_buffer(
                &gpu_scene.material_params,
                0,
                bytemuck::cast_slice(&materials.parameters),
            );
        }
        let kernel = path_tracing_kernel(&features, &materials.wgsl);
        let kernel_compiled = !kernel.is_cached(&ctx, 1, "render");
        if kernel_compiled && let Some(rehearsal) = ctx.rehearsal() {
            rehearse(rehearsal, original, &settings);
            // The driver's cache keeps the machine code; the rehearsal's device would hold
            // a second copy of every viewport kernel for nothing.
            kernel.forget(rehearsal, 1);
        }
        let pipeline = kernel.create_pipeline(&ctx, &[&layout], "render")?;
        let bake_pipeline = if gpu_scene.volume_grids.grids.is_empty() {
            None
        } else {
            Some(kernel.create_pipeline(&ctx, &[&layout], "bake_volume_grid")?)
        };
        let noise_pipelines = if features.noise {
            Some([
                kernel.create_pipeline(&ctx, &[&layout], "adaptive_error")?,
                kernel.create_pipeline(&ctx, &[&layout], "adaptive_converge")?,
            ])
        } else {
            None
        };
        crate::scene::validate_noise_threshold(settings.noise_threshold)
            .map_err(RenderError::Scene)?;
        let film = DeviceFilm {
            aovs: settings.aovs,
            noise: features.noise,
        };

        let (width, height) = (settings.width, settings.height);
        let limits = ctx.limits();
        let binding_limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let piece_limit = settings
            .film_piece_bytes
            .map_or(binding_limit, |b| b.min(binding_limit));
        let widest = if settings.aovs { AOV_BYTES } else { SUM_BYTES };
        let rows = piece_rows(width, height, widest, piece_limit)?;
        // The device film alone; callers check it with what they hold (`memory_check`).
        memory_check(&ctx, width, height, film, 0)?;
        let stats_size = std::mem::size_of::<GpuStats>() as u64;
        let stats_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("stats"),
            size: stats_size,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let stats_staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("stats staging"),
            size: stats_size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let params_stride = (std::mem::size_of::<GpuParams>() as u64)
            .next_multiple_of(device.limits().min_uniform_buffer_offset_alignment as u64);
        let params_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("params"),
            size: params_stride * MAX_BATCH as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let pieces = allocate_pieces(
            &ctx,
            &gpu_scene,
            &layout,
            &rows,
            width,
            film,
            SharedBuffers {
                params: &params_buffer,
                stats: &stats_buffer,
            },
        )?;
        let base_params = base_params(scene, &gpu_scene, &settings);
        let gpu_order = accel.tlas.as_ref().map_or(&[][..], |t| &t.primitive_order);
        let enclosures = Enclosures::new(scene, &accel.blas, gpu_order);
        let mut renderer = Self {
            build_info: BuildInfo {
                triangles: scene.triangle_count(),
                instances: gpu_scene.instance_count,
                emissive_triangles: gpu_scene.light_count,
                accel_build: accel.build_time,
                upload,
                upload_bytes: gpu_scene.bytes + width as u64 * height as u64 * film.pixel_bytes(),
                kernel_build: Duration::ZERO,
                kernel_compiled,
                volume_bake: Duration::ZERO,
                volume_voxels: 0,
                world_bake,
                world_texels,
            },
            ctx,
            pipeline,
            bake_pipeline,
            noise_pipelines,
            all_converged: false,
            params_buffer,
            params_stride,
            gpu_scene,
            blas: accel.blas,
            enclosures,
            features,
            materials_wgsl: materials.wgsl,
            pacing: Pacing::Final,
            tile_size: TILE_SIZE,
            pieces,
            film_has_whole_pass: false,
            stats_buffer,
            stats_staging,
            base_params,
            settings,
            samples_per_batch: 1,
        };
        renderer.set_camera(&scene.camera);
        renderer.clear_film();
        // An empty dispatch makes drivers that compile lazily (lavapipe) do it now, so the
        // compile is counted here and not in the first samples.
        renderer.dispatch(0, [0, 0], [0, 0], 0..1, true)?;
        renderer.bake_volume_grids()?;
        renderer.build_info.kernel_build = kernel_start.elapsed();
        Ok(renderer)
    }

    /// Evaluates the heterogeneous volumes into their grids (`bake_volume_grid`), in
    /// dispatches of [`BAKE_VOXELS_PER_DISPATCH`] points, each waited for.
    pub(super) fn bake_volume_grids(&mut self) -> Result<(), RenderError> {
        let Some(pipeline) = &self.bake_pipeline else {
            return Ok(());
        };
        let start = Instant::now();
        let mut voxels = 0u64;
        let queue = &self.ctx.queue;
        for grid in &self.gpu_scene.volume_grids.grids {
            let count = grid.voxels();
            for first in (0..count).step_by(BAKE_VOXELS_PER_DISPATCH as usize) {
                let params = GpuParams {
                    bake_grid: grid.offset,
                    bake_first: first,
                    ..self.base_params
                };
                queue.write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&params));
                let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
                {
                    let mut pass = encoder.begin_compute_pass(&Default::default());
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(
                        crate::shader::bindings::SCENE_GROUP,
                        &self.pieces[0].bind_group,
                        &[0],
                    );
                    let n = (count - first).min(BAKE_VOXELS_PER_DISPATCH);
                    pass.dispatch_workgroups(n.div_ceil(BAKE_WORKGROUP_SIZE), 1, 1);
                }
                self.submit_and_wait(encoder, "baking a volume grid")?;
            }
            voxels += count as u64;
        }
        self.build_info.volume_bake = start.elapsed();
        self.build_info.volume_voxels = voxels;
        Ok(())
    }

    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    pub fn adapter(&self) -> String {
        self.ctx.describe()
    }

    /// How many pieces the film is split into on the device (1 unless it exceeds a
    /// binding, or `RenderSettings::film_piece_bytes`).
    pub fn film_pieces(&self) -> usize {
        self.pieces.len()
    }

    /// Whether every pixel of the film holds at least one whole pass of samples (what a
    /// stopped or failed render can still write).
    pub fn has_whole_pass(&self) -> bool {
        self.film_has_whole_pass
    }

    /// Zeroes the film: the next render starts from no samples.
    pub fn clear_film(&mut self) {
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        for piece in &self.pieces {
            encoder.clear_buffer(&piece.sum, 0, None);
            encoder.clear_buffer(&piece.high, 0, None);
            for buffer in [&piece.aov, &piece.noise].into_iter().flatten() {
                encoder.clear_buffer(buffer, 0, None);
            }
        }
        self.ctx.queue.submit([encoder.finish()]);
        self.film_has_whole_pass = false;
        self.all_converged = false;
    }

    /// How passes are cut into dispatches from now on (see [`Pacing`]); the film is the
    /// same either way.
    pub fn set_pacing(&mut self, pacing: Pacing) {
        self.pacing = pacing;
        self.tile_size = match pacing {
            Pacing::Final => TILE_SIZE,
            Pacing::Interactive { .. } => INTERACTIVE_FIRST_TILE,
        };
    }

    /// The side of the square tiles a pass is cut into at present.
    pub fn tile_size(&self) -> u32 {
        self.tile_size
    }

    /// The tiles of a pass: (piece, origin, size), none straddling two pieces.
    fn tiles(&self) -> Vec<(usize, [u32; 2], [u32; 2])> {
        let width = self.settings.width;
        let tile = self.tile_size;
        let mut tiles = Vec::new();
        for (i, piece) in self.pieces.iter().enumerate() {
            for y in piece.rows.clone().step_by(tile as usize) {
                for x in (0..width).step_by(tile as usize) {
                    let size = [tile.min(width - x), tile.min(piece.rows.end - y)];
                    tiles.push((i, [x, y], size));
                }
            }
        }
        tiles
    }

    /// Adds the samples with indices in `samples` to a tile of piece `piece`: one
    /// submission, a dispatch per sample, each reading its own slot of the params buffer.
    /// With `read_stats` it zeroes the statistics first and returns what the submission
    /// produced, waiting for it; without, the statistics keep adding up on the device
    /// (read by [`Renderer::take_stats`]) and the call still waits for the submission to
    /// finish, so the caller's next one never queues behind more than one.
    fn dispatch(
        &mut self,
        piece: usize,
        origin: [u32; 2],
        size: [u32; 2],
        samples: Range<u32>,
        read_stats: bool,
    ) -> Result<Option<GpuStats>, RenderError> {
        debug_assert!(samples.len() as u32 <= MAX_BATCH);
        let tile = GpuParams {
            tile_origin: origin,
            tile_size: size,
            film_piece_start: self.pieces[piece].rows.start * self.settings.width,
            ..self.base_params
        };
        let stride = self.params_stride as usize;
        let mut slots = vec![0u8; stride * samples.len()];
        for (slot, sample_index) in slots.chunks_exact_mut(stride).zip(samples) {
            let params = GpuParams {
                sample_index,
                ..tile
            };
            slot[..size_of::<GpuParams>()].copy_from_slice(bytemuck::bytes_of(&params));
        }
        let queue = &self.ctx.queue;
        queue.write_buffer(&self.params_buffer, 0, &slots);
        if read_stats {
            self.zero_stats();
        }
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            for offset in (0..slots.len()).step_by(stride) {
                pass.set_bind_group(
                    crate::shader::bindings::SCENE_GROUP,
                    &self.pieces[piece].bind_group,
                    &[offset as u32],
                );
                pass.dispatch_workgroups(
                    size[0].div_ceil(WORKGROUP_SIZE).max(1),
                    size[1].div_ceil(WORKGROUP_SIZE).max(1),
                    1,
                );
            }
        }
        if !read_stats {
            self.submit_and_wait(encoder, "a render dispatch")?;
            return Ok(None);
        }
        queue.submit([encoder.finish()]);
        self.take_stats().map(Some)
    }

    /// Submits `encoder` and waits for it to finish; `during` names the work in an error.
    fn submit_and_wait(
        &self,
        encoder: wgpu::CommandEncoder,
        during: &str,
    ) -> Result<(), RenderError> {
        let index = self.ctx.queue.submit([encoder.finish()]);
        self.ctx
            .device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map_err(|e| {
                self.ctx
                    .check_lost(during)
                    .err()
                    .unwrap_or(GpuError::Runtime {
                        during: during.into(),
                        message: e.to_string(),
                    })
            })?;
        self.ctx.check_lost(during)?;
        Ok(())
    }

    fn zero_stats(&self) {
        self.ctx.queue.write_buffer(
            &self.stats_buffer,
            0,
            bytemuck::bytes_of(&GpuStats::default()),
        );
    }

    /// Reads the statistics the dispatches since they were last zeroed added up.
    fn take_stats(&self) -> Result<GpuStats, RenderError> {
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(
            &self.stats_buffer,
            0,
            &self.stats_staging,
            0,
            self.stats_staging.size(),
        );
        self.ctx.queue.submit([encoder.finish()]);
        let bytes = map_and_read(&self.ctx, &self.stats_staging)?;
        Ok(*bytemuck::from_bytes::<GpuStats>(&bytes))
    }

    /// Adds the samples with indices in `samples` to every pixel of the film, in
    /// whole-image passes. Stops early (with `completed: false`) when cancelled or past
    /// the deadline, but never before the film holds one whole pass: a stopped film has a
    /// sample in every pixel, and its pixels' counts differ by at most one pass's batch
    /// (each pixel knows its own count).
    pub fn render(
        &mut self,
        samples: Range<u32>,
        control: RenderControl,
    ) -> Result<RenderStats, RenderError> {
        self.render_passes(samples, control)
            .map_err(|e| self.explain_loss(e))
    }

    /// A lost device's error with what this renderer put on it, against the adapter's
    /// limits: what a user needs to tell a crash from a scene too large for the device.
    fn explain_loss(&self, error: RenderError) -> RenderError {
        match error {
            RenderError::Gpu(lost @ GpuError::DeviceLost { .. }) => RenderError::DeviceLost {
                lost,
                triangles: self.build_info.triangles,
                bytes: self.build_info.upload_bytes,
                width: self.settings.width,
                height: self.settings.height,
                max_buffer: self.ctx.device.limits().max_buffer_size,
            },
            other => other,
        }
    }

    fn render_passes(
        &mut self,
        samples: Range<u32>,
        mut control: RenderControl,
    ) -> Result<RenderStats, RenderError> {
        let start = Instant::now();
        let tiles = self.tiles();
        let pixels = self.settings.width as u64 * self.settings.height as u64;
        let mut stats = RenderStats {
            completed: true,
            ..RenderStats::default()
        };
        let total = pixels * samples.len() as u64;
        let adaptive = self.settings.noise_threshold > 0.0 && self.noise_pipelines.is_some();
        let mut next = samples.start;
        stats.next_sample = next;
        'passes: while next < samples.end {
            if adaptive && self.all_converged {
                break;
            }
            // The first pass, which nothing but an error stops, is as short as it can be:
            // one sample per pixel, whatever batch an earlier render settled on.
            let batch = if self.film_has_whole_pass {
                self.samples_per_batch
            } else {
                1
            };
            let mut count = batch.min(samples.end - next);
            if adaptive {
                // Passes end at the checks, so that they fall on the same counts however
                // the passes are batched.
                count = count.min(next_adaptive_check(next) - next);
            }
            let pass_start = Instant::now();
            let mut pass_pixels = 0u64;
            let mut slowest = Duration::ZERO;
            let mut pass_dispatch_time = Duration::ZERO;
            let read_each = self.pacing == Pacing::Final;
            if !read_each {
                self.zero_stats();
            }
            for &(piece, origin, size) in &tiles {
                let cancelled = control.cancel.is_some_and(|c| c.load(Ordering::Relaxed));
                let stop = cancelled || control.deadline.is_some_and(|d| Instant::now() >= d);
                if stop && (self.film_has_whole_pass || cancelled && control.cancel_first_pass) {
                    stats.completed = false;
                    break 'passes;
                }
                let t = Instant::now();
                let s = self.dispatch(piece, origin, size, next..next + count, read_each)?;
                slowest = slowest.max(t.elapsed());
                pass_dispatch_time += t.elapsed();
                let tile_pixels = size[0] as u64 * size[1] as u64;
                pass_pixels += tile_pixels;
                stats.dispatches += 1;
                stats.pixel_samples += tile_pixels * count as u64;
                if let Some(s) = s {
                    stats.add(&s);
                }
                let pass_done = pass_pixels == pixels;
                if pass_done && !read_each {
                    // One read-back a pass, not one per dispatch.
                    let s = self.take_stats()?;
                    stats.add(&s);
                }
                if pass_done {
                    if !self.film_has_whole_pass {
                        stats.first_pass = Some(pass_start.elapsed());
                        self.film_has_whole_pass = true;
                    }
                    stats.passes += 1;
                }
                if let Some(progress) = control.progress.as_mut() {
                    progress(&Progress {
                        pixel_samples_done: stats.pixel_samples,
                        pixel_samples_total: total,
                        rays: stats.rays,
                        elapsed: start.elapsed(),
                        passes_done: stats.passes,
                        whole_pass_samples: next - samples.start
                            + if pass_done { count } else { 0 },
                        pass_samples: count,
                        pass_fraction: if pass_done {
                            0.0
                        } else {
                            pass_pixels as f64 / pixels as f64
                        },
                        pass_elapsed: if pass_done {
                            Duration::ZERO
                        } else {
                            pass_start.elapsed()
                        },
                        active_pixels: stats.active_pixels,
                    });
                }
            }
            next += count;
            stats.next_sample = next;
            if adaptive && is_adaptive_check(next) {
                let active = self.adaptive_check(true)?;
                stats.active_pixels = Some(active as u64);
                self.all_converged = active == 0;
            }
            if next < samples.end && control.pass_deadline.is_some_and(|d| Instant::now() >= d) {
                stats.completed = false;
                stats.checkpoint = true;
                break;
            }
            // Batching and tiling change only how work is cut, never the result.
            if let Pacing::Interactive { budget_us } = self.pacing {
                let mean = pass_dispatch_time / tiles.len().max(1) as u32;
                self.tile_size = adapt_tile(self.tile_size, mean, budget_us);
            }
            if slowest < TARGET_BATCH / 2 {
                self.samples_per_batch = (self.samples_per_batch * 2).min(MAX_BATCH);
            } else if slowest > TARGET_BATCH * 2 {
                self.samples_per_batch = (self.samples_per_batch / 2).max(1);
            }
        }
        stats.elapsed = start.elapsed();
        Ok(stats)
    }

    /// Runs adaptive sampling's check over the whole film: estimates every pixel's noise,
    /// then with `converge` marks converged the pixels below the threshold and returns how
    /// many are not.
    fn adaptive_check(&self, converge: bool) -> Result<u32, RenderError> {
        let Some(pipelines) = &self.noise_pipelines else {
            return Ok(0);
        };
        let passes = if converge {
            &pipelines[..]
        } else {
            &pipelines[..1]
        };
        self.zero_stats();
        let width = self.settings.width;
        for piece in &self.pieces {
            let params = GpuParams {
                tile_origin: [0, piece.rows.start],
                tile_size: [width, piece.rows.len() as u32],
                film_piece_start: piece.rows.start * width,
                ..self.base_params
            };
            self.ctx
                .queue
                .write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&params));
            let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
            // One compute pass each: the second reads what the first wrote.
            for pipeline in passes {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(pipeline);
                pass.set_bind_group(
                    crate::shader::bindings::SCENE_GROUP,
                    &piece.bind_group,
                    &[0],
                );
                pass.dispatch_workgroups(
                    width.div_ceil(WORKGROUP_SIZE),
                    (piece.rows.len() as u32).div_ceil(WORKGROUP_SIZE),
                    1,
                );
            }
            self.submit_and_wait(encoder, "adaptive sampling's check")?;
        }
        Ok(self.take_stats()?.active_pixels)
    }

    /// The film's state on the device, bit for bit: per piece its sums' low words and
    /// counts, their high words, and the AOV and noise films it has (a checkpoint's content).
    pub fn film_state(&self) -> Result<Vec<Vec<u8>>, RenderError> {
        let mut state = Vec::new();
        for piece in &self.pieces {
            for buffer in piece.buffers() {
                state.push(
                    super::readback::read_buffer(&self.ctx, buffer, buffer.size())
                        .map_err(|e| self.explain_loss(e.into()))?,
                );
            }
        }
        Ok(state)
    }

    /// Puts back a state [`Renderer::film_state`] read from a renderer of the same scene
    /// and settings; the film then holds whole passes (a state is taken between them).
    pub fn restore_film_state(&mut self, state: &[Vec<u8>]) -> Result<(), RenderError> {
        let buffers: Vec<&wgpu::Buffer> = self.pieces.iter().flat_map(|p| p.buffers()).collect();
        let fits = buffers.len() == state.len()
            && buffers
                .iter()
                .zip(state)
                .all(|(b, s)| b.size() == s.len() as u64);
        if !fits {
            return Err(RenderError::Scene(
                "the saved film does not fit this render's film (another size or other layers)"
                    .into(),
            ));
        }
        for (buffer, bytes) in buffers.into_iter().zip(state) {
            self.ctx.queue.write_buffer(buffer, 0, bytes);
        }
        self.ctx.queue.submit([]);
        self.film_has_whole_pass = true;
        self.all_converged = false;
        Ok(())
    }

    /// Each pixel's noise estimate, from the top-left (see
    /// `shaders/integrator/adaptive.wgsl`): the half-width of the 90 % confidence interval
    /// of its mean's r + g + b over the square root of that mean; 3·10³⁸ where a pixel has
    /// fewer than two samples. None unless the renderer estimates the noise (AOVs or
    /// adaptive sampling).
    pub fn read_noise(&self) -> Result<Option<Vec<f32>>, RenderError> {
        if self.noise_pipelines.is_none() {
            return Ok(None);
        }
        self.adaptive_check(false)?;
        read_noise_rows(
            &self.ctx,
            &self.pieces,
            self.settings.width,
            0..self.settings.height,
            |m| m[2],
        )
    }

    /// Per pixel from the top-left, the sum over its samples of (r + g + b)²: with the
    /// film's sums, the samples' variance. None unless the noise is estimated.
    pub fn read_second_moments(&self) -> Result<Option<Vec<f64>>, RenderError> {
        // Kahan: the running sum minus its compensation.
        read_noise_rows(
            &self.ctx,
            &self.pieces,
            self.settings.width,
            0..self.settings.height,
            |m| m[0] as f64 - m[1] as f64,
        )
    }

    /// The AOVs averaged over the samples taken, per pixel from the top-left: albedo
    /// (RGB), shading normal (world space, unit length where a surface was hit), depth
    /// (distance from the camera to the first hit; 0 where the camera saw nothing), the
    /// emission seen directly (RGB). None
    /// unless the settings asked for them.
    pub fn read_aovs(&self) -> Result<Option<Aovs>, RenderError> {
        self.read_aov_rows(0..self.settings.height)
    }

    /// Rows `rows` of the AOVs (see [`Renderer::read_aovs`]).
    pub fn read_aov_rows(&self, rows: Range<u32>) -> Result<Option<Aovs>, RenderError> {
        if !self.settings.aovs {
            return Ok(None);
        }
        read_aov_rows(
            &self.ctx,
            &self.pieces,
            self.settings.width,
            self.clamp(rows),
        )
    }

    /// The film on the device, when it is one piece: per pixel (row-major from the
    /// top-left) a `vec4<u32>` of the low words of the fixed-point radiance sums (rgb) and
    /// the sample count (w), and one of their high words ([`crate::film::ExactFilm`]).
    /// For passes that show the film without reading it back (the
    /// editor's viewport); `None` for a film split into pieces (larger than one binding).
    pub fn film_buffers(&self) -> Option<(&wgpu::Buffer, &wgpu::Buffer)> {
        match self.pieces.as_slice() {
            [piece] => Some((&piece.sum, &piece.high)),
            _ => None,
        }
    }

    /// Whether the camera sees a transparent background: the scene has a shadow catcher,
    /// and exports take their alpha from the coverage AOV ([`Aovs::alpha`]).
    pub fn transparent(&self) -> bool {
        self.base_params.flags & FLAG_SHADOW_CATCHER != 0
    }

    /// Moves the camera without rebuilding anything: later samples see `camera`. Clear
    /// the film ([`Renderer::clear_film`]) before rendering again, or the film mixes the
    /// two views.
    pub fn set_camera(&mut self, camera: &crate::scene::Camera) {
        let (right, up, forward) = camera.frame();
        let p = &mut self.base_params;
        p.cam_position = camera.position.extend(1.0).into();
        p.cam_right = right.extend(0.0).into();
        p.cam_up = up.extend(0.0).into();
        p.cam_forward = forward.extend(0.0).into();
        p.cam_lens = [
            (camera.fov_y_degrees.to_radians() * 0.5).tan(),
            self.settings.width as f32 / self.settings.height as f32,
            camera.aperture_radius,
            camera.focus_distance,
        ];
        self.set_camera_media();
    }

    /// Finds the media around the camera for paths to start in (objects nested deeper
    /// than the kernel's media stack are left out, as it leaves them out).
    pub(super) fn set_camera_media(&mut self) {
        let [x, y, z, _] = self.base_params.cam_position;
        let around = self.enclosures.around(&self.blas, glam::Vec3::new(x, y, z));
        let p = &mut self.base_params;
        p.camera_media = [0; 4];
        for (slot, &i) in p.camera_media.iter_mut().zip(&around) {
            *slot = i;
        }
        p.camera_media_count = around.len().min(4) as u32;
    }

    /// Copies the film back from the device.
    pub fn read_film(&self) -> Result<Film, RenderError> {
        self.read_film_rows(0..self.settings.height)
    }

    /// Copies rows `rows` of the film back from the device, as a film of their own (as
    /// wide as the image, `rows.len()` high): a large image is read and written a band at
    /// a time, never held whole twice.
    pub fn read_film_rows(&self, rows: Range<u32>) -> Result<Film, RenderError> {
        read_film_rows(
            &self.ctx,
            &self.pieces,
            self.settings.width,
            self.clamp(rows),
        )
        .map_err(|e| self.explain_loss(e))
    }

    /// The whole film exactly as the device holds it: fixed-point sums and counts (what
    /// the part of a split render keeps, so that parts merge bit for bit).
    pub fn read_exact_film(&self) -> Result<ExactFilm, RenderError> {
        read_exact_film_rows(
            &self.ctx,
            &self.pieces,
            self.settings.width,
            0..self.settings.height,
        )
        .map_err(|e| self.explain_loss(e))
    }

    fn clamp(&self, rows: Range<u32>) -> Range<u32> {
        let h = self.settings.height;
        rows.start.min(h)..rows.end.min(h)
    }
}
