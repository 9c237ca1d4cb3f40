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

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
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
    /// When the UI last drew a frame, in milliseconds since `epoch`.
    ui_frame_ms: AtomicU64,
    epoch: Instant,
}

/// After each dispatch, while the UI is drawing frames (input within this long), the
/// worker pauses for [`UI_TURN`] so the UI's own GPU work gets into the queue: on a
/// software adapter the queue runs one submission at a time, and a worker that resubmits
/// at once can keep a frame waiting for several dispatches.
const UI_ACTIVE: Duration = Duration::from_millis(150);
const UI_TURN: Duration = Duration::from_millis(12);

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

/// A coarse film has at most this many pixels: one dispatch (a tile of the renderer) of
/// it takes tens of milliseconds even on lavapipe, so the image follows a drag.
const COARSE_PIXELS: u32 = 160 * 120;
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

/// The divisor of the image size that makes a film of at most [`COARSE_PIXELS`]; 1 when
/// the image is that small already.
fn coarse_divisor(size: [u32; 2]) -> u32 {
    let pixels = size[0] as f64 * size[1] as f64;
    (pixels / COARSE_PIXELS as f64).sqrt().ceil().max(1.0) as u32
}

struct Worker {
    ctx: Arc<GpuContext>,
    shared: Arc<Shared>,
    repaint: Box<dyn Fn() + Send>,
    display: DisplayPipeline,
    /// The image at full size, and (for large images) a coarse one shown while the
    /// user is changing things.
    full: Option<Layer>,
    coarse: Option<Layer>,
    current: Option<Target>,
    started: Instant,
    last_change: Instant,
    generations: u64,
}

impl Worker {
    fn new(ctx: Arc<GpuContext>, shared: Arc<Shared>, repaint: Box<dyn Fn() + Send>) -> Self {
        let display = DisplayPipeline::new(&ctx);
        Self {
            ctx,
            shared,
            repaint,
            display,
            full: None,
            coarse: None,
            current: None,
            started: Instant::now(),
            last_change: Instant::now(),
            generations: 0,
        }
    }

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

    fn build_layer(
        &mut self,
        scene: &Scene,
        target: &Target,
        size: [u32; 2],
    ) -> Result<Layer, String> {
        let settings = RenderSettings {
            width: size[0],
            height: size[1],
            samples_per_pixel: target.sample_limit,
            max_bounces: scene.settings.max_bounces,
            seed: 0,
            light_sampling: true,
            page_bytes: None,
            specialize: false,
            aovs: false,
            film_piece_bytes: None,
        };
        let renderer = Renderer::new(Arc::clone(&self.ctx), scene, settings)
            .map_err(|e| format!("the viewport cannot render this scene: {e}"))?;
        let film = renderer.film_buffers().ok_or_else(|| {
            format!(
                "the viewport's {}×{} film is larger than one buffer binding of this adapter",
                size[0], size[1]
            )
        })?;
        let display = self.display.bind(&self.ctx, film, size);
        self.generations += 1;
        Ok(Layer {
            renderer,
            display,
            samples: 0,
            texture_generation: self.generations,
        })
    }

    fn retarget(&mut self, target: Target) {
        let rebuild = match &self.current {
            Some(old) => {
                old.scene_revision != target.scene_revision
                    || old.size != target.size
                    || self.full.is_none()
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
            let mut scene = (*target.scene).clone();
            scene.camera = target.camera;
            let divisor = coarse_divisor(target.size);
            let coarse_size = target.size.map(|v| (v / divisor).max(1));
            let built = self
                .build_layer(&scene, &target, target.size)
                .and_then(|full| {
                    let coarse = if divisor > 1 {
                        Some(self.build_layer(&scene, &target, coarse_size)?)
                    } else {
                        None
                    };
                    Ok((full, coarse))
                });
            match built {
                Ok((full, coarse)) => {
                    self.full = Some(full);
                    self.coarse = coarse;
                    self.publish(|s| {
                        s.renderer_builds += 1;
                        s.error = None;
                        s.building = false;
                    });
                }
                Err(message) => {
                    self.full = None;
                    self.coarse = None;
                    self.current = Some(target);
                    self.publish(|s| {
                        s.error = Some(message);
                        s.building = false;
                    });
                    return;
                }
            }
        }
        if restart {
            for layer in [&mut self.full, &mut self.coarse].into_iter().flatten() {
                layer.renderer.set_camera(&target.camera);
                layer.renderer.clear_film();
                layer.samples = 0;
            }
            self.started = Instant::now();
            self.last_change = Instant::now();
            self.publish(|s| s.restarts += 1);
        } else if let Some(layer) = self.shown() {
            // Only the view transform or the limit changed: show the same film anew.
            self.display.run(
                &self.ctx,
                &layer.display,
                target.exposure_ev,
                target.tonemap,
            );
            (self.repaint)();
        }
        self.current = Some(target);
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
            ..Default::default()
        };
        match layer
            .renderer
            .render(layer.samples..layer.samples + 1, control)
        {
            Ok(stats) if stats.completed => {
                layer.samples += 1;
                let (exposure, tonemap) = (target.exposure_ev, target.tonemap);
                let revision = target.scene_revision;
                let shown = self.shown().map(|l| {
                    self.display.run(&self.ctx, &l.display, exposure, tonemap);
                    (
                        l.texture_generation,
                        l.display.view.clone(),
                        l.display.size(),
                    )
                });
                let samples = self.full.as_ref().map_or(0, |f| f.samples);
                let elapsed = self.started.elapsed();
                self.publish(|s| {
                    s.samples = samples;
                    s.elapsed = elapsed;
                    s.shown_revision = Some(revision);
                    if let Some((generation, view, size)) = shown {
                        s.size = size;
                        s.texture = Some((generation, view));
                    }
                });
            }
            // Cancelled: a new target is waiting and will clear the film.
            Ok(_) => {}
            Err(e) => {
                let message = format!("rendering the viewport failed: {e}");
                self.full = None;
                self.coarse = None;
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
            let d = coarse_divisor(size);
            let pixels = (size[0] / d).max(1) * (size[1] / d).max(1);
            assert!(pixels <= COARSE_PIXELS, "{size:?} / {d} = {pixels} pixels");
            assert!(
                d == 1 || pixels * 4 > COARSE_PIXELS / 4,
                "{size:?}: needlessly coarse"
            );
        }
        assert_eq!(coarse_divisor([160, 120]), 1);
    }
}
