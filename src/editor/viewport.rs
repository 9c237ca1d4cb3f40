//! The live viewport: a progressive path-traced image that accumulates while nothing
//! changes and restarts on any change, rendered on a worker thread so the UI never waits
//! for the GPU.
//!
//! The UI thread posts the state it wants shown (the scene at a revision, the view's
//! camera, the image size, a sample limit) as a [`Target`]; the worker keeps a
//! [`Renderer`] for it, renders one whole sample pass at a time (the renderer cuts a pass
//! into dispatches of a few milliseconds, [`Pacing::Interactive`], and a new target
//! cancels the pass between two of them), and after each pass runs the display pass
//! ([`super::display`]) into a texture egui draws directly. The texture only ever receives
//! complete passes, so an edit never shows a half-cleared image.
//!
//! A new scene revision is applied as cheaply as it can be: the worker compares the scene
//! it renders with the new one ([`Renderer::update`]) and writes in place what changed
//! (a transform: the instance BVH and instances; a light or material parameter: those
//! buffers and the light distribution). Comparing scenes rather than listing the
//! document's commands keeps one rule for every way a scene can change (commands, undo,
//! a file reloaded, panels added later), and costs a comparison, far less than any
//! upload. What cannot be written in place (a mesh, a new material graph, an image size)
//! needs a new renderer, which is built on a thread of its own while the old renderer
//! keeps accumulating its image; the new one replaces it when ready, so the UI never
//! waits for a BVH build or a kernel compile. The editor renders with the unspecialised
//! kernel (every lobe and light type), so that a material parameter or a light rarely
//! changes the kernel. A camera move rebuilds nothing.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, mpsc};
use std::time::{Duration, Instant};

use crate::film::output::ViewSettings;
use crate::render::{
    GpuContext, KernelKind, Pacing, RenderControl, RenderSettings, Renderer, UpdateError, Updated,
};
use crate::scene::{Camera, Scene};

use super::display::{DisplayPipeline, FilmDisplay};

/// What the viewport should show.
#[derive(Clone)]
pub struct Target {
    /// The scene to render (hidden items already left out) and the document revision it
    /// was taken at: a new revision rebuilds the renderer.
    pub scene: Arc<Scene>,
    pub scene_revision: u64,
    pub camera: Camera,
    pub size: [u32; 2],
    /// Stop accumulating after this many samples per pixel.
    pub sample_limit: u32,
    /// Exposure and view transform of the display pass (no restart when they change).
    pub view: ViewSettings,
    /// How the viewport's kernels hold graph materials.
    pub graphs: GraphKernels,
}

/// How the viewport's kernels hold the scene's graph materials.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GraphKernels {
    /// Compiled, constants read from a buffer ([`KernelKind::General`]): a value edit is a
    /// write, a change of structure a compile (in the background).
    Compiled,
    /// Interpreted ([`KernelKind::Interpreted`]): any graph edit is a buffer write, at a
    /// cost in sampling speed.
    Interpreted,
    /// Interpreted (or [`KernelKind::General`] where the interpreter cannot run a
    /// graph), and once the scene has been still this long, renderers with the final
    /// render's kernel ([`KernelKind::Specialized`]: only the lobes and lights the scene
    /// uses, graphs compiled with their constants folded in) are built in the background
    /// and replace them (the editor): an edit shows at once and sampling is as fast as a
    /// final render's while nothing changes. The replaced renderers are kept: an edit the
    /// specialised kernel cannot take in place is written into them and they come back
    /// at once, without a build.
    InterpretedThenSpecialized(Duration),
}

impl Target {
    /// Whether going from `self` to `other` invalidates the film.
    fn restarts(&self, other: &Target) -> bool {
        self.scene_revision != other.scene_revision
            || self.camera != other.camera
            || self.size != other.size
    }
}

/// What the worker reports; read by the UI each frame.
#[derive(Clone, Default)]
pub struct ViewportStatus {
    /// Samples per pixel in the shown image.
    pub samples: u32,
    /// Sample passes completed over the viewport's life, of either film.
    pub passes: u64,
    /// Since the last restart.
    pub elapsed: Duration,
    /// The size of the shown image in pixels.
    pub size: [u32; 2],
    /// How many times accumulation started over (a new scene, camera or size).
    pub restarts: u64,
    /// Renderers built (a first image, a size, or an edit that could not be written in
    /// place); camera moves and in-place edits build none.
    pub renderer_builds: u64,
    /// Kernels compiled for those renderers (the rest came from the pipeline cache).
    pub kernel_builds: u64,
    /// Edits written into the renderer in place, by what they wrote.
    pub instance_uploads: u64,
    pub light_updates: u64,
    pub material_updates: u64,
    /// How long the last change took from being posted to its first image on screen
    /// (None until one has shown).
    pub last_edit_latency: Option<Duration>,
    /// Set when the last renderer build or pass failed; the previous image stays.
    pub error: Option<String>,
    /// The texture holding the shown image, and a counter that changes when it is
    /// replaced (a new size).
    pub texture: Option<(u64, wgpu::TextureView)>,
    /// The scene revision and camera of the shown image.
    pub shown_revision: Option<u64>,
    /// The value `restarts` had when the shown image was started: an image of the latest
    /// change is on screen when it equals `restarts`.
    pub shown_restart: u64,
    /// When the renderer being built in the background started building, while one is
    /// (the old image stays and keeps accumulating meanwhile).
    pub building: Option<Instant>,
    /// Side in pixels of the tiles the full image's passes are cut into at present
    /// (adapted so that one dispatch takes about [`DISPATCH_BUDGET_US`]).
    pub tile_size: u32,
    /// How the shown image's kernel holds the graph materials.
    pub kernel: Option<KernelKind>,
    /// True while specialised renderers are being built to replace the ones on screen
    /// ([`GraphKernels::InterpretedThenSpecialized`]), which keep accumulating meanwhile.
    pub compiling: bool,
    /// Renderers replaced by specialised ones; not counted in `renderer_builds`.
    pub compiled_swaps: u64,
    /// Edits the specialised renderers could not take in place, written instead into the
    /// renderers they had replaced, which came back without a build.
    pub standby_returns: u64,
}

impl ViewportStatus {
    /// Pixel samples per second since the last restart.
    pub fn samples_per_second(&self) -> f64 {
        let secs = self.elapsed.as_secs_f64();
        if secs <= 0.0 {
            return 0.0;
        }
        self.samples as f64 * self.size[0] as f64 * self.size[1] as f64 / secs
    }
}

struct Shared {
    /// The newest target not yet taken by the worker, and when it was posted.
    target: Mutex<Option<(Target, Instant)>>,
    wake: Condvar,
    /// Set with a new target: the pass in progress stops at its next dispatch.
    cancel: AtomicBool,
    shutdown: AtomicBool,
    /// Set (under the `target` lock) when a background build has finished.
    built: AtomicBool,
    status: Mutex<ViewportStatus>,
    /// When the UI last drew a frame, in milliseconds since `epoch`.
    ui_frame_ms: AtomicU64,
    epoch: Instant,
}

/// After each dispatch, while the UI is drawing frames (input within this long), the
/// worker pauses for [`UI_TURN`] so the UI's own GPU work gets into the queue: on a
/// software adapter the queue runs one submission at a time, and a worker that resubmits
/// at once can keep a frame waiting for several dispatches.
const UI_ACTIVE: Duration = Duration::from_millis(150);
const UI_TURN: Duration = Duration::from_millis(2);

/// What one viewport dispatch should take, in microseconds: short enough that a UI frame
/// queued behind it still makes 30 frames a second on a software adapter.
pub const DISPATCH_BUDGET_US: u32 = 4_000;

/// The worker thread and the channel to it.
pub struct ViewportRenderer {
    shared: Arc<Shared>,
    posted: Option<Target>,
    worker: Option<std::thread::JoinHandle<()>>,
}

impl ViewportRenderer {
    /// Starts the worker on `ctx`; `repaint` is called whenever a new image is ready.
    pub fn new(ctx: Arc<GpuContext>, repaint: impl Fn() + Send + 'static) -> Self {
        let shared = Arc::new(Shared {
            target: Mutex::new(None),
            wake: Condvar::new(),
            cancel: AtomicBool::new(false),
            shutdown: AtomicBool::new(false),
            built: AtomicBool::new(false),
            status: Mutex::new(ViewportStatus::default()),
            ui_frame_ms: AtomicU64::new(0),
            epoch: Instant::now(),
        });
        let worker_shared = Arc::clone(&shared);
        let worker = std::thread::Builder::new()
            .name("kiln viewport".into())
            .spawn(move || Worker::new(ctx, worker_shared, Box::new(repaint)).run())
            .ok();
        if worker.is_none() {
            lock(&shared.status).error =
                Some("could not start the viewport's render thread".into());
        }
        Self {
            shared,
            posted: None,
            worker,
        }
    }

    /// Asks for `target`; does nothing when it equals the last one posted.
    pub fn post(&mut self, target: Target) {
        if let Some(old) = &self.posted {
            if !old.restarts(&target)
                && old.sample_limit == target.sample_limit
                && old.view == target.view
            {
                return;
            }
            if old.restarts(&target) {
                self.shared.cancel.store(true, Ordering::Relaxed);
            }
        }
        *lock(&self.shared.target) = Some((target.clone(), Instant::now()));
        self.posted = Some(target);
        self.shared.wake.notify_all();
    }

    /// Tells the worker that the UI is drawing a frame (see [`UI_TURN`]).
    pub fn ui_frame(&self) {
        let ms = self.shared.epoch.elapsed().as_millis() as u64;
        self.shared.ui_frame_ms.store(ms, Ordering::Relaxed);
    }

    pub fn status(&self) -> ViewportStatus {
        lock(&self.shared.status).clone()
    }
}

impl Drop for ViewportRenderer {
    fn drop(&mut self) {
        self.shared.shutdown.store(true, Ordering::Relaxed);
        self.shared.cancel.store(true, Ordering::Relaxed);
        self.shared.wake.notify_all();
        if let Some(worker) = self.worker.take() {
            // The worker's last pass ends at its next dispatch.
            let _ = worker.join();
        }
    }
}

/// A poisoned lock only means a panic elsewhere; the data (a status, a target) is still
/// whole, so carry on with it.
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// A coarse film has at most this many pixels: one pass of it takes a few milliseconds
/// even on lavapipe, so the image follows a drag.
const COARSE_PIXELS: u32 = 160 * 120;
/// With interpreted graphs, which sample about 13 times slower on lavapipe
/// (docs/BENCHMARKS.md), the coarse film is a quarter of that, so that the first image of
/// a graph edit still comes within a second.
const COARSE_PIXELS_INTERPRETED: u32 = COARSE_PIXELS / 4;
/// The coarse film is shown until no change came for this long (Cycles' viewport
/// behaves the same: coarse while you move, refining when you stop).
const REFINE_AFTER: Duration = Duration::from_millis(300);
/// Coarse samples taken before refining anyway.
const COARSE_SAMPLES: u32 = 4;

/// A renderer with the texture its film is shown in.
struct Layer {
    renderer: Renderer,
    display: FilmDisplay,
    samples: u32,
    /// Changes when this layer's texture is replaced.
    texture_generation: u64,
}

/// The divisor of the image size that makes a film of at most `budget` pixels
/// ([`COARSE_PIXELS`], [`COARSE_PIXELS_INTERPRETED`]); 1 when the image is that small
/// already.
fn coarse_divisor(size: [u32; 2], budget: u32) -> u32 {
    let pixels = size[0] as f64 * size[1] as f64;
    (pixels / budget as f64).sqrt().ceil().max(1.0) as u32
}

/// The renderers a background build made for a target: the full image's and, for large
/// images, the coarse one's.
struct Built {
    full: Renderer,
    coarse: Option<Renderer>,
}

/// A renderer build running on a thread of its own.
struct Build {
    target: Target,
    /// When the target was posted.
    posted: Instant,
    result: mpsc::Receiver<Result<Built, String>>,
}

/// Specialised renderers being built to replace the ones on screen
/// ([`GraphKernels::InterpretedThenSpecialized`]).
struct Compile {
    build: Build,
}

/// The renderers specialised ones replaced, and the target they were last brought to:
/// an edit the specialised kernel cannot take is written into these instead.
struct Standby {
    full: Renderer,
    coarse: Option<Renderer>,
    target: Target,
}

/// Builds the renderers for `target` with kernels of kind `kernel` (on the build thread).
fn build_renderers(
    ctx: &Arc<GpuContext>,
    target: &Target,
    kernel: KernelKind,
) -> Result<Built, String> {
    let budget = match kernel {
        KernelKind::Interpreted => COARSE_PIXELS_INTERPRETED,
        KernelKind::Specialized | KernelKind::General => COARSE_PIXELS,
    };
    let divisor = coarse_divisor(target.size, budget);
    let coarse_size = target.size.map(|v| (v / divisor).max(1));
    let started = Instant::now();
    let full = build_renderer(ctx, target, target.size, kernel)?;
    let coarse = if divisor > 1 {
        Some(build_renderer(ctx, target, coarse_size, kernel)?)
    } else {
        None
    };
    tracing::debug!(
        "viewport renderers ({kernel:?}) built in {:.0} ms",
        started.elapsed().as_secs_f64() * 1e3
    );
    Ok(Built { full, coarse })
}

/// The kernel a new renderer for `target` starts with: the interpreting one when its
/// graphs are to be interpreted and the interpreter runs them (then no graph edit needs a
/// compile), else the general one (every lobe and light type, so that a parameter or
/// light edit rarely needs one).
fn first_kernel(target: &Target) -> KernelKind {
    let scene = &target.scene;
    let graphs = scene.materials.iter().any(|m| m.graph.is_some());
    if target.graphs != GraphKernels::Compiled
        && graphs
        && crate::render::materials::interprets(scene)
    {
        KernelKind::Interpreted
    } else {
        KernelKind::General
    }
}

fn build_renderer(
    ctx: &Arc<GpuContext>,
    target: &Target,
    size: [u32; 2],
    kernel: KernelKind,
) -> Result<Renderer, String> {
    let scene = &target.scene;
    // The scene's settings (bounces, seed) at the viewport's size and sample limit.
    let settings = RenderSettings {
        width: size[0],
        height: size[1],
        samples_per_pixel: target.sample_limit,
        kernel,
        // The viewport samples every pixel (its kernel takes edits without a compile).
        noise_threshold: 0.0,
        ..RenderSettings::from_scene(scene)
    };
    let mut renderer = Renderer::new(Arc::clone(ctx), scene, settings)
        .map_err(|e| format!("the viewport cannot render this scene: {e}"))?;
    if renderer.film_buffers().is_none() {
        return Err(format!(
            "the viewport's {}×{} film is larger than one buffer binding of this adapter",
            size[0], size[1]
        ));
    }
    renderer.set_camera(&target.camera);
    renderer.set_pacing(Pacing::Interactive {
        budget_us: DISPATCH_BUDGET_US,
    });
    Ok(renderer)
}

struct Worker {
    ctx: Arc<GpuContext>,
    shared: Arc<Shared>,
    repaint: Arc<dyn Fn() + Send + Sync>,
    display: DisplayPipeline,
    /// The image at full size, and (for large images) a coarse one shown while the
    /// user is changing things.
    full: Option<Layer>,
    coarse: Option<Layer>,
    /// What the layers render: their scene, camera and size.
    current: Option<Target>,
    /// The newest target, waiting while a build runs, and when it was posted.
    waiting: Option<(Target, Instant)>,
    build: Option<Build>,
    /// Specialised renderers for the current target, replacing the layers when ready;
    /// unlike `build`, it holds no target back.
    compile: Option<Compile>,
    /// The scene revision whose specialised build failed: not tried again.
    compile_failed: Option<u64>,
    /// The scene revision whose specialised renderers went in: a rebuild of that scene (a
    /// new viewport size) builds specialised renderers at once, their kernels cached.
    compiled_revision: Option<u64>,
    /// The renderers the specialised ones on screen replaced.
    standby: Option<Standby>,
    /// A target whose build failed: not tried again until the scene or size changes.
    failed: Option<(u64, [u32; 2])>,
    started: Instant,
    last_change: Instant,
    /// When the edit the layers are restarting for was posted, until its first pass shows.
    edit_posted: Option<Instant>,
    generations: u64,
}

impl Worker {
    fn new(ctx: Arc<GpuContext>, shared: Arc<Shared>, repaint: Box<dyn Fn() + Send>) -> Self {
        let display = DisplayPipeline::new(&ctx);
        // Shared with build threads, which wake the UI when they finish.
        let repaint = Mutex::new(repaint);
        let repaint: Arc<dyn Fn() + Send + Sync> = Arc::new(move || {
            let repaint = lock(&repaint);
            (*repaint)()
        });
        Self {
            ctx,
            shared,
            repaint,
            display,
            full: None,
            coarse: None,
            current: None,
            waiting: None,
            build: None,
            compile: None,
            compile_failed: None,
            compiled_revision: None,
            standby: None,
            failed: None,
            started: Instant::now(),
            last_change: Instant::now(),
            edit_posted: None,
            generations: 0,
        }
    }

    /// Whether the layers have all the samples asked for (or there are none to render).
    fn done(&self) -> bool {
        match (&self.full, &self.current) {
            (Some(full), Some(t)) => full.samples >= t.sample_limit,
            _ => true,
        }
    }

    fn run(mut self) {
        loop {
            let next = {
                let mut slot = lock(&self.shared.target);
                while slot.is_none()
                    && self.done()
                    && !self.compile_due()
                    && !self.shared.built.load(Ordering::Relaxed)
                    && !self.shared.shutdown.load(Ordering::Relaxed)
                {
                    // Woken by a target or a finished build; or, while compiled
                    // renderers are due, when the scene has been still long enough.
                    slot = match self.compile_wait() {
                        Some(wait) => {
                            (self.shared.wake.wait_timeout(slot, wait))
                                .unwrap_or_else(|e| e.into_inner())
                                .0
                        }
                        None => (self.shared.wake.wait(slot)).unwrap_or_else(|e| e.into_inner()),
                    };
                }
                let next = slot.take();
                // Consumed here, not where a result is taken: a build thread sets it after
                // sending, so a result taken early must not leave it set (the loop would
                // spin) — at worst it costs one more turn of the loop.
                if self.shared.built.swap(false, Ordering::Relaxed) {
                    // Its cancel has done its work (see `spawn_build`).
                    self.shared.cancel.store(false, Ordering::Relaxed);
                }
                next
            };
            if self.shared.shutdown.load(Ordering::Relaxed) {
                // A build in flight finishes on its own thread and is dropped there.
                return;
            }
            if let Some(next) = next {
                self.shared.cancel.store(false, Ordering::Relaxed);
                self.waiting = Some(next);
            }
            self.finish_build();
            if self.build.is_none() {
                if let Some((target, posted)) = self.waiting.take() {
                    self.retarget(target, posted);
                }
            }
            self.finish_compile();
            if self.compile_due() {
                self.start_compile();
            }
            if !self.done() {
                self.render_pass();
            }
        }
    }

    fn publish(&self, f: impl FnOnce(&mut ViewportStatus)) {
        f(&mut lock(&self.shared.status));
        (self.repaint)();
    }

    /// Starts building renderers for `target` on a thread of its own; the layers keep
    /// rendering what they render until it is done.
    fn start_build(&mut self, target: Target, posted: Instant) {
        let kernel = if self.compiled_revision == Some(target.scene_revision) {
            KernelKind::Specialized
        } else {
            first_kernel(&target)
        };
        if let Some(build) = self.spawn_build(target, posted, kernel) {
            self.build = Some(build);
            self.publish(|s| s.building = Some(Instant::now()));
        }
    }

    /// The kernel of the layers on screen.
    fn kernel(&self) -> Option<KernelKind> {
        self.full.as_ref().map(|l| l.renderer.settings().kernel)
    }

    /// How long until specialised renderers are due for the current target, if they will
    /// be.
    fn compile_wait(&self) -> Option<Duration> {
        let target = self.current.as_ref()?;
        let GraphKernels::InterpretedThenSpecialized(after) = target.graphs else {
            return None;
        };
        // Not before the first image is on screen: the compile would compete with it for
        // the device and the CPU.
        let wanted = self.kernel().is_some_and(|k| k != KernelKind::Specialized)
            && self.shown().is_some_and(|l| l.samples > 0)
            && self.build.is_none()
            && self.compile.is_none()
            && self.compile_failed != Some(target.scene_revision);
        wanted.then(|| after.saturating_sub(self.last_change.elapsed()))
    }

    /// Whether to start building specialised renderers now.
    fn compile_due(&self) -> bool {
        self.compile_wait().is_some_and(|w| w.is_zero())
    }

    fn start_compile(&mut self) {
        let Some(target) = self.current.clone() else {
            return;
        };
        if let Some(build) = self.spawn_build(target, Instant::now(), KernelKind::Specialized) {
            self.compile = Some(Compile { build });
            self.publish(|s| s.compiling = true);
        }
    }

    /// Swaps in specialised renderers that finished for the current target, keeping the
    /// replaced ones as the standby; drops them if the target moved on meanwhile (the
    /// next still moment starts another build).
    fn finish_compile(&mut self) {
        let Some(compile) = &self.compile else {
            return;
        };
        let result = match compile.build.result.try_recv() {
            Ok(result) => result,
            Err(mpsc::TryRecvError::Empty) => return,
            Err(mpsc::TryRecvError::Disconnected) => {
                Err("the viewport's build thread stopped without a renderer".into())
            }
        };
        let Some(Compile { build }) = self.compile.take() else {
            return;
        };
        self.publish(|s| s.compiling = false);
        let current = match &self.current {
            Some(c) if self.kernel().is_some_and(|k| k != KernelKind::Specialized) => c,
            _ => return,
        };
        let still = build.target.scene_revision == current.scene_revision
            && build.target.size == current.size;
        match result {
            Ok(built) if still => {
                let camera = current.camera;
                let replaced_target = current.clone();
                let kernels = [Some(&built.full), built.coarse.as_ref()]
                    .into_iter()
                    .flatten()
                    .filter(|r| r.build_info.kernel_compiled)
                    .count() as u64;
                let mut full = built.full;
                let mut coarse = built.coarse;
                for r in [Some(&mut full), coarse.as_mut()].into_iter().flatten() {
                    r.set_camera(&camera);
                }
                // Accumulation starts over with the faster kernel (from its coarse
                // film, as after any change).
                let full = self.layer(full);
                let coarse = coarse.map(|r| self.layer(r));
                let replaced_full = self.full.replace(full);
                let replaced_coarse = std::mem::replace(&mut self.coarse, coarse);
                self.standby = replaced_full.map(|full| Standby {
                    full: full.renderer,
                    coarse: replaced_coarse.map(|c| c.renderer),
                    target: replaced_target,
                });
                self.started = Instant::now();
                self.compiled_revision = Some(build.target.scene_revision);
                self.publish(|s| {
                    s.compiled_swaps += 1;
                    s.kernel_builds += kernels;
                    s.kernel = Some(KernelKind::Specialized);
                });
            }
            Ok(_) => {}
            Err(message) => {
                tracing::warn!(
                    "specialised viewport renderers failed, keeping the ones on screen: {message}"
                );
                self.compile_failed = Some(build.target.scene_revision);
            }
        }
    }

    /// Spawns a thread building renderers of kind `kernel` for `target`.
    fn spawn_build(
        &mut self,
        target: Target,
        posted: Instant,
        kernel: KernelKind,
    ) -> Option<Build> {
        let (tx, rx) = mpsc::channel();
        let ctx = Arc::clone(&self.ctx);
        let shared = Arc::clone(&self.shared);
        let repaint = Arc::clone(&self.repaint);
        let job = target.clone();
        let spawned = std::thread::Builder::new()
            .name("kiln viewport build".into())
            .spawn(move || {
                let built = build_renderers(&ctx, &job, kernel);
                // The worker may have gone (the window closed): then nobody wants it.
                let _ = tx.send(built);
                let _slot = lock(&shared.target);
                shared.built.store(true, Ordering::Relaxed);
                // The pass in progress stops, so the renderers go in without waiting
                // for it (a first full-size pass can take seconds).
                shared.cancel.store(true, Ordering::Relaxed);
                shared.wake.notify_all();
                drop(_slot);
                repaint();
            });
        match spawned {
            Ok(_) => Some(Build {
                target,
                posted,
                result: rx,
            }),
            Err(e) => {
                let message =
                    format!("could not start a thread to build the viewport's renderer: {e}");
                self.publish(|s| s.error = Some(message));
                None
            }
        }
    }

    /// Installs the renderers of a finished build, if one has finished.
    fn finish_build(&mut self) {
        let Some(build) = &self.build else {
            return;
        };
        let result = match build.result.try_recv() {
            Ok(result) => result,
            Err(mpsc::TryRecvError::Empty) => return,
            Err(mpsc::TryRecvError::Disconnected) => {
                Err("the viewport's build thread stopped without a renderer".into())
            }
        };
        let Some(Build { target, posted, .. }) = self.build.take() else {
            return;
        };
        match result {
            Ok(built) => {
                let kernels = [Some(&built.full), built.coarse.as_ref()]
                    .into_iter()
                    .flatten()
                    .filter(|r| r.build_info.kernel_compiled)
                    .count() as u64;
                let kernel = built.full.settings().kernel;
                self.full = Some(self.layer(built.full));
                self.coarse = built.coarse.map(|r| self.layer(r));
                self.standby = None;
                self.failed = None;
                self.publish(|s| {
                    s.renderer_builds += 1;
                    s.kernel_builds += kernels;
                    s.error = None;
                    s.building = None;
                    s.kernel = Some(kernel);
                });
                self.current = Some(target);
                self.restart(posted);
            }
            Err(message) => {
                // The old layers (if any) keep showing the scene they render.
                self.failed = Some((target.scene_revision, target.size));
                self.publish(|s| {
                    s.error = Some(message);
                    s.building = None;
                });
            }
        }
    }

    fn layer(&mut self, renderer: Renderer) -> Layer {
        let size = [renderer.settings().width, renderer.settings().height];
        let film = renderer
            .film_buffers()
            .expect("build_renderer refuses a film of several pieces");
        let display = self.display.bind(&self.ctx, film, size);
        self.generations += 1;
        Layer {
            renderer,
            display,
            samples: 0,
            texture_generation: self.generations,
        }
    }

    /// Zeroes the layers' films: accumulation starts over for the current target.
    fn restart(&mut self, posted: Instant) {
        for layer in [&mut self.full, &mut self.coarse].into_iter().flatten() {
            layer.renderer.clear_film();
            layer.samples = 0;
        }
        self.started = Instant::now();
        self.last_change = Instant::now();
        self.edit_posted = Some(posted);
        self.publish(|s| s.restarts += 1);
    }

    /// Moves the layers to `target` by the cheapest way there: nothing (a new sample
    /// limit or view transform), the camera, an update in place, or a new renderer built
    /// in the background.
    fn retarget(&mut self, target: Target, posted: Instant) {
        let Some(current) = self.current.clone().filter(|_| self.full.is_some()) else {
            self.rebuild(target, posted);
            return;
        };
        if current.size != target.size {
            self.rebuild(target, posted);
            return;
        }
        let mut updated = Updated::default();
        let mut returned = false;
        if current.scene_revision != target.scene_revision {
            let result = [&mut self.full, &mut self.coarse]
                .into_iter()
                .flatten()
                .try_for_each(|layer| {
                    updated = layer.renderer.update(&current.scene, &target.scene)?;
                    Ok::<_, UpdateError>(())
                });
            match result {
                Ok(()) => {}
                Err(UpdateError::NeedsRebuild { .. }) => {
                    returned = self.return_standby(&target);
                    if !returned {
                        self.rebuild(target, posted);
                        return;
                    }
                }
                Err(UpdateError::Render(e)) => {
                    let message = format!("the viewport cannot show this edit: {e}");
                    self.publish(|s| s.error = Some(message));
                    return;
                }
            }
        }
        let camera = current.camera != target.camera;
        if camera || updated.any() || returned {
            for layer in [&mut self.full, &mut self.coarse].into_iter().flatten() {
                layer.renderer.set_camera(&target.camera);
            }
            self.publish(|s| {
                s.instance_uploads += updated.instances as u64;
                s.light_updates += updated.lights as u64;
                s.material_updates += updated.materials as u64;
                s.error = None;
            });
            self.current = Some(target);
            self.restart(posted);
        } else {
            // Only the view transform or the limit changed: show the same film anew.
            if let Some(layer) = self.shown() {
                self.display.run(&self.ctx, &layer.display, target.view);
                (self.repaint)();
            }
            self.current = Some(target);
        }
    }

    /// Writes `target` into the standby renderers and puts them back on screen in place
    /// of the specialised ones, which could not take it; false (and no standby) when the
    /// standby cannot take it either.
    fn return_standby(&mut self, target: &Target) -> bool {
        let Some(mut standby) = self.standby.take() else {
            return false;
        };
        let taken = [Some(&mut standby.full), standby.coarse.as_mut()]
            .into_iter()
            .flatten()
            .try_for_each(|r| r.update(&standby.target.scene, &target.scene).map(|_| ()));
        if taken.is_err() {
            return false;
        }
        let kernel = standby.full.settings().kernel;
        self.full = Some(self.layer(standby.full));
        self.coarse = standby.coarse.map(|r| self.layer(r));
        self.publish(|s| {
            s.standby_returns += 1;
            s.kernel = Some(kernel);
        });
        true
    }

    fn rebuild(&mut self, target: Target, posted: Instant) {
        if self.failed == Some((target.scene_revision, target.size)) {
            return;
        }
        self.start_build(target, posted);
    }

    /// The layer whose image is on screen: the full one once it has a sample.
    fn shown(&self) -> Option<&Layer> {
        match (&self.full, &self.coarse) {
            (Some(full), _) if full.samples > 0 => Some(full),
            (_, Some(coarse)) => Some(coarse),
            (full, None) => full.as_ref(),
        }
    }

    fn render_pass(&mut self) {
        let Some(target) = &self.current else {
            return;
        };
        let refining = self.last_change.elapsed() >= REFINE_AFTER;
        let use_coarse = self
            .coarse
            .as_ref()
            .is_some_and(|c| c.samples == 0 || (!refining && c.samples < COARSE_SAMPLES));
        let layer = if use_coarse {
            self.coarse.as_mut()
        } else {
            self.full.as_mut()
        };
        let Some(layer) = layer else {
            return;
        };
        let shared = &self.shared;
        let mut give_ui_a_turn = |_: &crate::render::Progress| {
            let since_ui = shared.epoch.elapsed().saturating_sub(Duration::from_millis(
                shared.ui_frame_ms.load(Ordering::Relaxed),
            ));
            if since_ui < UI_ACTIVE {
                std::thread::sleep(UI_TURN);
            }
        };
        let control = RenderControl {
            cancel: Some(&self.shared.cancel),
            progress: Some(&mut give_ui_a_turn),
            // A film's first full-size pass can take seconds (a slow kernel, a large
            // viewport): an edit or a finished build must not wait for it.
            cancel_first_pass: true,
            ..Default::default()
        };
        match layer
            .renderer
            .render(layer.samples..layer.samples + 1, control)
        {
            Ok(stats) if stats.completed => {
                layer.samples += 1;
                let view = target.view;
                let revision = target.scene_revision;
                let shown = self.shown().map(|l| {
                    self.display.run(&self.ctx, &l.display, view);
                    (
                        l.texture_generation,
                        l.display.view.clone(),
                        l.display.size(),
                    )
                });
                let samples = self.full.as_ref().map_or(0, |f| f.samples);
                let tile_size = self.full.as_ref().map_or(0, |f| f.renderer.tile_size());
                let elapsed = self.started.elapsed();
                let latency = self.edit_posted.take().map(|t| t.elapsed());
                self.publish(|s| {
                    s.samples = samples;
                    s.passes += 1;
                    s.shown_restart = s.restarts;
                    s.elapsed = elapsed;
                    s.shown_revision = Some(revision);
                    s.tile_size = tile_size;
                    if latency.is_some() {
                        s.last_edit_latency = latency;
                    }
                    if let Some((generation, view, size)) = shown {
                        s.size = size;
                        s.texture = Some((generation, view));
                    }
                });
            }
            // Cancelled: a new target or a built renderer is waiting. The pass stopped
            // part-way: its film is thrown away, as a restart would.
            Ok(_) => {
                layer.renderer.clear_film();
                layer.samples = 0;
            }
            Err(e) => {
                let message = format!("rendering the viewport failed: {e}");
                self.full = None;
                self.coarse = None;
                self.current = None;
                self.publish(|s| s.error = Some(message));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_coarse_film_stays_within_its_pixel_budget() {
        for size in [[1, 1], [160, 120], [161, 120], [950, 754], [3840, 2160]] {
            for budget in [COARSE_PIXELS, COARSE_PIXELS_INTERPRETED] {
                let d = coarse_divisor(size, budget);
                let pixels = (size[0] / d).max(1) * (size[1] / d).max(1);
                assert!(pixels <= budget, "{size:?} / {d} = {pixels} pixels");
                assert!(
                    d == 1 || pixels * 4 > budget / 4,
                    "{size:?}: needlessly coarse"
                );
            }
        }
        assert_eq!(coarse_divisor([160, 120], COARSE_PIXELS), 1);
    }
}
