//! The progressive renderer: uploads a scene once, then renders any range of sample
//! indices into its film, in dispatches short enough that none runs long (tiles of at
//! most 256×256 pixels, with the samples per dispatch adapted to a time target).
//!
//! Samples are pure functions of (pixel, sample index, seed), and each pixel adds its
//! samples in index order, so the film after `render(0..n)` is the same bits however the
//! work was cut into dispatches, and `render(0..k)` then `render(k..n)` equals
//! `render(0..n)`.

use std::ops::Range;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use thiserror::Error;

use super::context::{GpuContext, GpuError};
use super::gpu_scene::{FrameBuffers, GpuScene, UploadError, scene_bind_group_layout};
use super::kernel::{KernelError, path_tracing_kernel};
use super::readback::{map_and_read, read_buffer};
use crate::accel::{AccelError, build_scene_accel};
use crate::film::Film;
use crate::scene::Scene;
use crate::shader::KernelFeatures;
use crate::shader::gpu_types::{FLAG_ENVIRONMENT_MAP, FLAG_LIGHT_SAMPLING, GpuParams, GpuStats};

const TILE_SIZE: u32 = 256;
const WORKGROUP_SIZE: u32 = 8;
/// Dispatch duration the sample batching aims for.
const TARGET_DISPATCH: Duration = Duration::from_millis(60);
/// Lavapipe (Mesa 22.3) loses samples when one dispatch carries a few hundred samples per
/// pixel of long paths (tests/determinism.rs checks every pixel's count); 64 is safe and
/// already amortises the per-dispatch overhead.
const MAX_SAMPLES_PER_DISPATCH: u32 = 64;

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
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub samples_per_pixel: u32,
    /// Scattering events per path; 0 shows only what the camera sees directly.
    pub max_bounces: u32,
    pub seed: u32,
    /// Next-event estimation with multiple importance sampling; off means BSDF sampling
    /// alone (useful as a reference: both must converge to the same image).
    pub light_sampling: bool,
    /// Page size in bytes of the paged scene arrays (BVH nodes, triangles); default: the
    /// largest binding the adapter allows. Tests lower it to exercise paging.
    pub page_bytes: Option<u64>,
    /// Compile only the lobes and light types the scene uses (the default); off builds
    /// the kernel with everything, for comparison.
    pub specialize: bool,
    /// Also render the albedo, normal and depth AOVs ([`Renderer::read_aovs`]).
    pub aovs: bool,
}

impl RenderSettings {
    pub fn from_scene(scene: &Scene) -> Self {
        Self {
            width: scene.settings.width,
            height: scene.settings.height,
            samples_per_pixel: scene.settings.samples_per_pixel,
            max_bounces: scene.settings.max_bounces,
            seed: 0,
            light_sampling: true,
            page_bytes: None,
            specialize: true,
            aovs: false,
        }
    }
}

/// Auxiliary images of the first surface each camera path meets (see
/// [`Renderer::read_aovs`]): 3, 3 and 1 floats per pixel.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Aovs {
    pub albedo: Vec<f32>,
    pub normal: Vec<f32>,
    pub depth: Vec<f32>,
}

/// Reported after every dispatch.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    pub pixel_samples_done: u64,
    pub pixel_samples_total: u64,
    pub rays: u64,
    pub elapsed: Duration,
}

/// How a caller steers a render: stop it, bound it in time, watch it.
#[derive(Default)]
pub struct RenderControl<'a> {
    pub cancel: Option<&'a AtomicBool>,
    pub deadline: Option<Instant>,
    pub progress: Option<&'a mut dyn FnMut(&Progress)>,
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
}

pub struct Renderer {
    ctx: Arc<GpuContext>,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    params_buffer: wgpu::Buffer,
    film_sum: wgpu::Buffer,
    film_compensation: wgpu::Buffer,
    film_aov: Option<wgpu::Buffer>,
    stats_buffer: wgpu::Buffer,
    stats_staging: wgpu::Buffer,
    base_params: GpuParams,
    settings: RenderSettings,
    samples_per_dispatch: u32,
    pub build_info: BuildInfo,
}

/// The parts of `Params` fixed for a scene and settings.
pub fn base_params(scene: &Scene, gpu: &GpuScene, settings: &RenderSettings) -> GpuParams {
    let cam = &scene.camera;
    let (right, up, forward) = cam.frame();
    GpuParams {
        film_size: [settings.width, settings.height],
        seed: settings.seed,
        max_bounces: settings.max_bounces,
        flags: if settings.light_sampling {
            FLAG_LIGHT_SAMPLING
        } else {
            0
        } | if gpu.has_environment_map {
            FLAG_ENVIRONMENT_MAP
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
        analytic_light_count: gpu.analytic_light_count,
        ..GpuParams::default()
    }
}

impl Renderer {
    pub fn new(
        ctx: Arc<GpuContext>,
        scene: &Scene,
        settings: RenderSettings,
    ) -> Result<Self, RenderError> {
        scene.validate().map_err(RenderError::Scene)?;
        crate::scene::validate_image_size(settings.width, settings.height)
            .map_err(RenderError::Scene)?;

        let accel = build_scene_accel(scene)?;
        let upload_start = Instant::now();
        let gpu_scene = GpuScene::upload(&ctx, scene, &accel, settings.page_bytes)?;
        let upload = upload_start.elapsed();

        let kernel_start = Instant::now();
        let device = &ctx.device;
        let scene_features = KernelFeatures {
            aovs: settings.aovs,
            ..gpu_scene.features()
        };
        // `everything` keeps the bindings, so one layout serves both kernels.
        let features = if settings.specialize {
            scene_features
        } else {
            scene_features.everything()
        };
        let layout = scene_bind_group_layout(device, &features);
        let materials = super::materials::scene_materials_wgsl(scene)?;
        let pipeline = path_tracing_kernel(&features, &materials).create_pipeline(
            &ctx,
            &[&layout],
            "render",
        )?;

        let pixels = settings.width as u64 * settings.height as u64;
        let film_bytes = pixels * 16;
        let storage = |label: &str, size: u64, extra: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST
                    | extra,
                mapped_at_creation: false,
            })
        };
        let limits = ctx.limits();
        if film_bytes > limits.max_storage_buffer_binding_size {
            return Err(RenderError::Upload(UploadError::TooLarge {
                buffer: "film",
                bytes: film_bytes,
                limit: limits.max_storage_buffer_binding_size,
            }));
        }
        let film_sum = storage("film sum", film_bytes, wgpu::BufferUsages::empty());
        let film_compensation =
            storage("film compensation", film_bytes, wgpu::BufferUsages::empty());
        let film_aov = settings
            .aovs
            .then(|| storage("film AOVs", 2 * film_bytes, wgpu::BufferUsages::empty()));
        let stats_size = std::mem::size_of::<GpuStats>() as u64;
        let stats_buffer = storage("stats", stats_size, wgpu::BufferUsages::empty());
        let stats_staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("stats staging"),
            size: stats_size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let params_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("params"),
            size: std::mem::size_of::<GpuParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = gpu_scene.bind_group(
            device,
            &layout,
            &FrameBuffers {
                params: &params_buffer,
                film_sum: &film_sum,
                film_compensation: &film_compensation,
                stats: &stats_buffer,
                film_aov: film_aov.as_ref(),
            },
        );
        let base_params = base_params(scene, &gpu_scene, &settings);
        let mut renderer = Self {
            build_info: BuildInfo {
                triangles: scene.triangle_count(),
                instances: gpu_scene.instance_count,
                emissive_triangles: gpu_scene.light_count,
                accel_build: accel.build_time,
                upload,
                upload_bytes: gpu_scene.bytes + 2 * film_bytes,
                kernel_build: Duration::ZERO,
            },
            ctx,
            pipeline,
            bind_group,
            params_buffer,
            film_sum,
            film_compensation,
            film_aov,
            stats_buffer,
            stats_staging,
            base_params,
            settings,
            samples_per_dispatch: 1,
        };
        renderer.clear_film();
        // An empty dispatch makes drivers that compile lazily (lavapipe) do it now, so the
        // compile is counted here and not in the first samples.
        renderer.dispatch([0, 0], [0, 0], 0, 0)?;
        renderer.build_info.kernel_build = kernel_start.elapsed();
        Ok(renderer)
    }

    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    pub fn adapter(&self) -> String {
        self.ctx.describe()
    }

    /// Zeroes the film: the next render starts from no samples.
    pub fn clear_film(&mut self) {
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&self.film_sum, 0, None);
        encoder.clear_buffer(&self.film_compensation, 0, None);
        if let Some(aov) = &self.film_aov {
            encoder.clear_buffer(aov, 0, None);
        }
        self.ctx.queue.submit([encoder.finish()]);
    }

    /// One dispatch over a tile; returns the stats it produced.
    fn dispatch(
        &mut self,
        origin: [u32; 2],
        size: [u32; 2],
        sample_start: u32,
        sample_count: u32,
    ) -> Result<GpuStats, RenderError> {
        let params = GpuParams {
            tile_origin: origin,
            tile_size: size,
            sample_start,
            sample_count,
            ..self.base_params
        };
        let queue = &self.ctx.queue;
        queue.write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&params));
        queue.write_buffer(
            &self.stats_buffer,
            0,
            bytemuck::bytes_of(&GpuStats::default()),
        );
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(crate::shader::bindings::SCENE_GROUP, &self.bind_group, &[]);
            pass.dispatch_workgroups(
                size[0].div_ceil(WORKGROUP_SIZE).max(1),
                size[1].div_ceil(WORKGROUP_SIZE).max(1),
                1,
            );
        }
        encoder.copy_buffer_to_buffer(
            &self.stats_buffer,
            0,
            &self.stats_staging,
            0,
            self.stats_staging.size(),
        );
        queue.submit([encoder.finish()]);
        let bytes = map_and_read(&self.ctx, &self.stats_staging)?;
        Ok(*bytemuck::from_bytes::<GpuStats>(&bytes))
    }

    /// Adds the samples with indices in `samples` to every pixel of the film. Stops early
    /// (with `completed: false`) when cancelled or past the deadline; the film then holds
    /// whole dispatches only, and each pixel knows its own sample count.
    pub fn render(
        &mut self,
        samples: Range<u32>,
        mut control: RenderControl,
    ) -> Result<RenderStats, RenderError> {
        let start = Instant::now();
        let (width, height) = (self.settings.width, self.settings.height);
        let tiles: Vec<([u32; 2], [u32; 2])> = (0..height)
            .step_by(TILE_SIZE as usize)
            .flat_map(|y| {
                (0..width).step_by(TILE_SIZE as usize).map(move |x| {
                    (
                        [x, y],
                        [TILE_SIZE.min(width - x), TILE_SIZE.min(height - y)],
                    )
                })
            })
            .collect();
        let pixels = width as u64 * height as u64;
        let mut stats = RenderStats {
            completed: true,
            ..RenderStats::default()
        };
        let total = pixels * samples.len() as u64;
        let mut next = samples.start;
        'batches: while next < samples.end {
            let count = self.samples_per_dispatch.min(samples.end - next);
            let mut slowest = Duration::ZERO;
            for &(origin, size) in &tiles {
                let stop = control.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
                    || control.deadline.is_some_and(|d| Instant::now() >= d);
                if stop {
                    stats.completed = false;
                    break 'batches;
                }
                let t = Instant::now();
                let s = self.dispatch(origin, size, next, count)?;
                slowest = slowest.max(t.elapsed());
                stats.dispatches += 1;
                stats.rays += s.rays as u64;
                stats.non_finite += s.non_finite as u64;
                stats.pixel_samples += size[0] as u64 * size[1] as u64 * count as u64;
                if let Some(progress) = control.progress.as_mut() {
                    progress(&Progress {
                        pixel_samples_done: stats.pixel_samples,
                        pixel_samples_total: total,
                        rays: stats.rays,
                        elapsed: start.elapsed(),
                    });
                }
            }
            next += count;
            // Batching changes only how work is cut, never the result.
            if slowest < TARGET_DISPATCH / 2 {
                self.samples_per_dispatch =
                    (self.samples_per_dispatch * 2).min(MAX_SAMPLES_PER_DISPATCH);
            } else if slowest > TARGET_DISPATCH * 2 {
                self.samples_per_dispatch = (self.samples_per_dispatch / 2).max(1);
            }
        }
        stats.elapsed = start.elapsed();
        Ok(stats)
    }

    /// The AOVs averaged over the samples taken, per pixel from the top-left: albedo
    /// (RGB), shading normal (world space, unit length where a surface was hit), depth
    /// (distance from the camera to the first hit; 0 where the camera saw nothing). None
    /// unless the settings asked for them.
    pub fn read_aovs(&self) -> Result<Option<Aovs>, RenderError> {
        let Some(buffer) = &self.film_aov else {
            return Ok(None);
        };
        let raw = read_buffer(&self.ctx, buffer, buffer.size())?;
        let raw: &[[f32; 4]] = bytemuck::cast_slice(&raw);
        let mut aovs = Aovs::default();
        for px in raw.chunks_exact(2) {
            let [a, n] = [px[0], px[1]];
            // The AOV film counts its own samples.
            let samples = n[3].max(1.0);
            aovs.albedo.extend([a[0], a[1], a[2]].map(|v| v / samples));
            aovs.depth.push(a[3] / samples);
            let normal = glam::Vec3::new(n[0], n[1], n[2]);
            let unit = normal.try_normalize().unwrap_or(glam::Vec3::ZERO);
            aovs.normal.extend(unit.to_array());
        }
        Ok(Some(aovs))
    }

    /// The film on the device: per pixel (row-major from the top-left) a `vec4<f32>` of
    /// the radiance sum (rgb) and sample count (w), and its Kahan compensation. For
    /// passes that show the film without reading it back (the editor's viewport).
    pub fn film_buffers(&self) -> (&wgpu::Buffer, &wgpu::Buffer) {
        (&self.film_sum, &self.film_compensation)
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
    }

    /// Copies the film back from the device.
    pub fn read_film(&self) -> Result<Film, RenderError> {
        let size = self.film_sum.size();
        let sums = read_buffer(&self.ctx, &self.film_sum, size)?;
        let compensation = read_buffer(&self.ctx, &self.film_compensation, size)?;
        let sums: &[[f32; 4]] = bytemuck::cast_slice(&sums);
        let compensation: &[[f32; 4]] = bytemuck::cast_slice(&compensation);
        let mut film = Film::new(self.settings.width, self.settings.height);
        for ((out, s), c) in film.sums.iter_mut().zip(sums).zip(compensation) {
            // Kahan: the running sum minus the compensation is the better estimate.
            *out = std::array::from_fn(|i| s[i] as f64 - c[i] as f64);
        }
        Ok(film)
    }
}
