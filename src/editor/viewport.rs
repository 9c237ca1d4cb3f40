//! The live viewport: a progressive path-traced image that accumulates while nothing
//! changes and restarts on any change, rendered on a worker thread so the UI never waits
//! for the GPU.
//!
//! The UI thread posts the state it wants shown (the scene at a revision, the view's
//! camera, the image size, a sample limit) as a [`Target`]; the worker keeps a
//! [`Renderer`] for it, renders one whole sample pass at a time (the renderer cuts a pass
//! into short dispatches, and a new target cancels the pass between two of them), and
//! after each pass runs the display pass ([`super::display`]) into a texture egui draws
//! directly. The texture only ever receives complete passes, so an edit never shows a
//! half-cleared image.
//!
//! A change of scene or size builds a new renderer on the worker; its kernel comes from the
//! device's pipeline cache unless the kernel's contents changed. The editor renders with
//! the unspecialised kernel (every lobe and light type), so that editing a material
//! parameter or a light never changes the kernel. A camera move rebuilds nothing.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use crate::film::tonemap::Tonemap;
use crate::render::{GpuContext, RenderControl, RenderSettings, Renderer};
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
    pub exposure_ev: f32,
    pub tonemap: Tonemap,
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
    /// Since the last restart.
    pub elapsed: Duration,
    /// The size of the shown image in pixels.
    pub size: [u32; 2],
    /// How many times accumulation started over (a new scene, camera or size).
    pub restarts: u64,
    /// Renderers built (scene or size changes); camera moves build none.
    pub renderer_builds: u64,
    /// Set when the last renderer build or pass failed; the previous image stays.
    pub error: Option<String>,
    /// The texture holding the shown image, and a counter that changes when it is
    /// replaced (a new size).
    pub texture: Option<(u64, wgpu::TextureView)>,
    /// The scene revision and camera of the shown image.
    pub shown_revision: Option<u64>,
    /// True while the worker is building a renderer (the old image stays meanwhile).
    pub building: bool,
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
    target: Mutex<Option<Target>>,
    wake: Condvar,
    /// Set with a new target: the pass in progress stops at its next dispatch.
    cancel: AtomicBool,
    shutdown: AtomicBool,
    status: Mutex<ViewportStatus>,
}

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
            status: Mutex::new(ViewportStatus::default()),
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
            let same_view = old.exposure_ev == target.exposure_ev && old.tonemap == target.tonemap;
            if !old.restarts(&target) && old.sample_limit == target.sample_limit && same_view {
                return;
            }
            if old.restarts(&target) {
                self.shared.cancel.store(true, Ordering::Relaxed);
            }
        }
        *lock(&self.shared.target) = Some(target.clone());
        self.posted = Some(target);
        self.shared.wake.notify_all();
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

struct Worker {
    ctx: Arc<GpuContext>,
    shared: Arc<Shared>,
    repaint: Box<dyn Fn() + Send>,
    display: DisplayPipeline,
    renderer: Option<(Renderer, FilmDisplay)>,
    current: Option<Target>,
    samples: u32,
    started: Instant,
    texture_generation: u64,
}

impl Worker {
    fn new(ctx: Arc<GpuContext>, shared: Arc<Shared>, repaint: Box<dyn Fn() + Send>) -> Self {
        let display = DisplayPipeline::new(&ctx);
        Self {
            ctx,
            shared,
            repaint,
            display,
            renderer: None,
            current: None,
            samples: 0,
            started: Instant::now(),
            texture_generation: 0,
        }
    }

    fn done(&self) -> bool {
        match (&self.renderer, &self.current) {
            (Some(_), Some(t)) => self.samples >= t.sample_limit,
            _ => true,
        }
    }

    fn run(mut self) {
        loop {
            let next = {
                let mut slot = lock(&self.shared.target);
                while slot.is_none() && self.done() && !self.shared.shutdown.load(Ordering::Relaxed)
                {
                    slot = self
                        .shared
                        .wake
                        .wait(slot)
                        .unwrap_or_else(|e| e.into_inner());
                }
                slot.take()
            };
            if self.shared.shutdown.load(Ordering::Relaxed) {
                return;
            }
            if let Some(target) = next {
                self.shared.cancel.store(false, Ordering::Relaxed);
                self.retarget(target);
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

    fn retarget(&mut self, target: Target) {
        let rebuild = match &self.current {
            Some(old) => {
                old.scene_revision != target.scene_revision
                    || old.size != target.size
                    || self.renderer.is_none()
            }
            None => true,
        };
        let restart = rebuild
            || self
                .current
                .as_ref()
                .is_none_or(|old| old.restarts(&target));
        if rebuild {
            self.publish(|s| s.building = true);
            let settings = RenderSettings {
                width: target.size[0],
                height: target.size[1],
                samples_per_pixel: target.sample_limit,
                max_bounces: target.scene.settings.max_bounces,
                seed: 0,
                light_sampling: true,
                page_bytes: None,
                specialize: false,
                aovs: false,
            };
            let mut scene = (*target.scene).clone();
            scene.camera = target.camera;
            match Renderer::new(Arc::clone(&self.ctx), &scene, settings) {
                Ok(renderer) => {
                    // Same size: bind the new film to the texture egui already has.
                    let reuse = self
                        .renderer
                        .as_ref()
                        .map(|(_, d)| d)
                        .filter(|d| d.size() == target.size);
                    let new_texture = reuse.is_none();
                    let display = match reuse {
                        Some(old) => self.display.rebind(&self.ctx, old, renderer.film_buffers()),
                        None => self
                            .display
                            .bind(&self.ctx, renderer.film_buffers(), target.size),
                    };
                    self.renderer = Some((renderer, display));
                    if new_texture {
                        self.texture_generation += 1;
                    }
                    let view = self.renderer.as_ref().map(|(_, d)| d.view.clone());
                    let generation = self.texture_generation;
                    self.publish(|s| {
                        s.renderer_builds += 1;
                        s.error = None;
                        s.building = false;
                        if let Some(view) = view {
                            s.texture = Some((generation, view));
                        }
                    });
                }
                Err(e) => {
                    let message = format!("the viewport cannot render this scene: {e}");
                    self.renderer = None;
                    self.current = Some(target);
                    self.publish(|s| {
                        s.error = Some(message);
                        s.building = false;
                    });
                    return;
                }
            }
        } else if restart {
            if let Some((renderer, _)) = &mut self.renderer {
                renderer.set_camera(&target.camera);
            }
        }
        if let Some((renderer, _)) = self.renderer.as_mut().filter(|_| restart) {
            renderer.clear_film();
            self.samples = 0;
            self.started = Instant::now();
            self.publish(|s| s.restarts += 1);
        } else if let Some((_, display)) = &self.renderer {
            // Only the view transform or the limit changed: show the same film anew.
            self.display
                .run(&self.ctx, display, target.exposure_ev, target.tonemap);
            (self.repaint)();
        }
        self.current = Some(target);
    }

    fn render_pass(&mut self) {
        let (Some((renderer, display)), Some(target)) = (&mut self.renderer, &self.current) else {
            return;
        };
        let control = RenderControl {
            cancel: Some(&self.shared.cancel),
            ..Default::default()
        };
        match renderer.render(self.samples..self.samples + 1, control) {
            Ok(stats) if stats.completed => {
                self.samples += 1;
                self.display
                    .run(&self.ctx, display, target.exposure_ev, target.tonemap);
                let (samples, elapsed, size) = (self.samples, self.started.elapsed(), target.size);
                let revision = target.scene_revision;
                self.publish(|s| {
                    s.samples = samples;
                    s.elapsed = elapsed;
                    s.size = size;
                    s.shown_revision = Some(revision);
                });
            }
            // Cancelled: a new target is waiting and will clear the film.
            Ok(_) => {}
            Err(e) => {
                let message = format!("rendering the viewport failed: {e}");
                self.renderer = None;
                self.publish(|s| s.error = Some(message));
            }
        }
    }
}
