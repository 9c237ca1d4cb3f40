//! The final render (Blender's Render Image, F12): the document's scene at its render
//! settings, with the kernel specialised to it, on a thread of its own that shares the
//! viewport's device. The UI shows its progress and can cancel it; a finished (or
//! cancelled, once every pixel has a sample) render is kept as an [`ExportFilm`] for the
//! render window and for Export, which writes it through the exporter plugins.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use crate::film::output::ExportFilm;
use crate::render::{GpuContext, RenderControl, RenderSettings, Renderer, export_film};
use crate::scene::Scene;

/// What a render produced.
pub struct RenderResult {
    pub film: ExportFilm,
    /// Mean samples per pixel (a cancelled render has fewer than asked for).
    pub samples_per_pixel: f64,
    pub elapsed: Duration,
    /// False when cancelled before the target sample count.
    pub completed: bool,
}

/// Where a render stands.
#[derive(Clone)]
pub enum RenderState {
    /// Building the renderer (BVHs, upload, kernel compile).
    Preparing,
    Rendering {
        /// Share of the pixel samples done, in [0, 1].
        fraction: f64,
        elapsed: Duration,
    },
    Finished(Arc<RenderResult>),
    Failed(String),
}

/// A final render running (or finished) in the background.
pub struct FinalRender {
    state: Arc<Mutex<RenderState>>,
    cancel: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl FinalRender {
    /// Starts rendering `scene` at its own settings (size, samples, bounces, seed); its
    /// view settings tonemap the display image. `repaint` is called as progress is made.
    pub fn start(
        ctx: Arc<GpuContext>,
        scene: Arc<Scene>,
        repaint: impl Fn() + Send + 'static,
    ) -> Self {
        let state = Arc::new(Mutex::new(RenderState::Preparing));
        let cancel = Arc::new(AtomicBool::new(false));
        let (thread_state, thread_cancel) = (Arc::clone(&state), Arc::clone(&cancel));
        let set = move |s: RenderState| {
            *thread_state.lock().unwrap_or_else(|e| e.into_inner()) = s;
            repaint();
        };
        let thread = std::thread::Builder::new()
            .name("kiln final render".into())
            .spawn(move || {
                let result = render(ctx, &scene, &thread_cancel, &set);
                set(match result {
                    Ok(r) => RenderState::Finished(Arc::new(r)),
                    Err(e) => RenderState::Failed(e),
                });
            });
        let thread = match thread {
            Ok(t) => Some(t),
            Err(e) => {
                *state.lock().unwrap_or_else(|e| e.into_inner()) =
                    RenderState::Failed(format!("could not start the render thread: {e}"));
                None
            }
        };
        Self {
            state,
            cancel,
            thread,
        }
    }

    pub fn state(&self) -> RenderState {
        self.state.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    /// Whether the render is still preparing or rendering.
    pub fn is_running(&self) -> bool {
        matches!(
            self.state(),
            RenderState::Preparing | RenderState::Rendering { .. }
        )
    }

    /// Asks the render to stop; it keeps what it has once every pixel has a sample.
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

impl Drop for FinalRender {
    fn drop(&mut self) {
        self.cancel();
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

fn render(
    ctx: Arc<GpuContext>,
    scene: &Scene,
    cancel: &AtomicBool,
    set: &impl Fn(RenderState),
) -> Result<RenderResult, String> {
    let denoiser = scene.settings.denoiser;
    if let Some(why) = denoiser.unavailable() {
        return Err(why.to_owned());
    }
    let settings = RenderSettings {
        // The denoiser's guides.
        aovs: denoiser != crate::scene::Denoiser::None,
        ..RenderSettings::from_scene(scene)
    };
    let view = scene.settings.view;
    let mut renderer = Renderer::new(ctx, scene, settings).map_err(|e| e.to_string())?;
    let spp = settings.samples_per_pixel;
    let mut report = |p: &crate::render::Progress| {
        set(RenderState::Rendering {
            fraction: p.pixel_samples_done as f64 / p.pixel_samples_total.max(1) as f64,
            elapsed: p.elapsed,
        })
    };
    let stats = renderer
        .render(
            0..spp,
            RenderControl {
                cancel: Some(cancel),
                deadline: None,
                progress: Some(&mut report),
                ..RenderControl::default()
            },
        )
        .map_err(|e| e.to_string())?;
    let film = export_film(&renderer, view, denoiser).map_err(|e| e.to_string())?;
    let pixels = settings.width as f64 * settings.height as f64;
    Ok(RenderResult {
        film,
        samples_per_pixel: stats.pixel_samples as f64 / pixels,
        elapsed: stats.elapsed,
        completed: stats.completed,
    })
}
