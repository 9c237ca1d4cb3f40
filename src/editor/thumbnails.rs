//! Material thumbnails: each material on a preview sphere, as Blender's material list
//! shows them, rendered on a worker thread that shares the viewport's device.
//!
//! The preview scene holds every material of the document (so its material code is the
//! viewport's, and its kernel usually comes from the pipeline cache) on one sphere under
//! a sky and a sun; a thumbnail is the sphere with one of them, and going from one
//! material to the next is an in-place renderer update (`Renderer::update`: the instance's
//! material index). The worker renders a material again only when it changed, and waits
//! while the viewport builds a kernel, so thumbnails never compete with the image the user
//! is looking at for the single queue of a software adapter.

use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

use glam::{Affine3A, Vec3};

use crate::film::output::{ViewSettings, to_srgb_image};
use crate::render::{GpuContext, KernelKind, Pacing, RenderControl, RenderSettings, Renderer};
use crate::scene::{Camera, Light, Material, Scene, shapes};

/// Side of a thumbnail in pixels.
pub const THUMBNAIL_SIZE: u32 = 64;
/// Samples per pixel of a thumbnail.
const SAMPLES: u32 = 16;

/// A rendered thumbnail: which material (as it was) and its sRGB pixels.
struct Rendered {
    index: usize,
    material: Material,
    image: egui::ColorImage,
}

#[derive(Default)]
struct State {
    /// The materials wanted (the document's), or None while the worker should wait.
    wanted: Option<Vec<Material>>,
    done: Vec<Rendered>,
    error: Option<String>,
    quit: bool,
}

struct Shared {
    state: Mutex<State>,
    wake: Condvar,
}

fn lock(shared: &Shared) -> MutexGuard<'_, State> {
    shared.state.lock().unwrap_or_else(|e| e.into_inner())
}

struct Shown {
    material: Material,
    texture: egui::TextureHandle,
    image: egui::ColorImage,
}

/// The thumbnails of a document's materials, kept up to date in the background.
pub struct Thumbnails {
    shared: Arc<Shared>,
    worker: Option<JoinHandle<()>>,
    /// By material index: the material as its texture shows it, the texture and its
    /// pixels.
    textures: Vec<Option<Shown>>,
}

impl Thumbnails {
    /// Starts the worker on `ctx`; `repaint` is called when a thumbnail is ready.
    pub fn new(ctx: Arc<GpuContext>, repaint: impl Fn() + Send + 'static) -> Self {
        let shared = Arc::new(Shared {
            state: Mutex::new(State::default()),
            wake: Condvar::new(),
        });
        let worker_shared = Arc::clone(&shared);
        let worker = std::thread::Builder::new()
            .name("kiln thumbnails".into())
            .spawn(move || work(&ctx, &worker_shared, &repaint))
            .ok();
        Self {
            shared,
            worker,
            textures: Vec::new(),
        }
    }

    /// Asks for thumbnails of `materials` (the document's, in its order); those already
    /// shown as they are cost nothing. `None` pauses the worker (the viewport is building
    /// a kernel).
    pub fn request(&self, materials: Option<&[Material]>) {
        let mut state = lock(&self.shared);
        let wanted = materials.map(<[Material]>::to_vec);
        if state.wanted != wanted {
            state.wanted = wanted;
            self.shared.wake.notify_all();
        }
    }

    /// Takes finished thumbnails into textures of `ctx`.
    pub fn poll(&mut self, ctx: &egui::Context) {
        let done = std::mem::take(&mut lock(&self.shared).done);
        for rendered in done {
            if self.textures.len() <= rendered.index {
                self.textures.resize_with(rendered.index + 1, || None);
            }
            let name = format!("material thumbnail {}", rendered.index);
            let texture =
                ctx.load_texture(name, rendered.image.clone(), egui::TextureOptions::LINEAR);
            self.textures[rendered.index] = Some(Shown {
                material: rendered.material,
                texture,
                image: rendered.image,
            });
        }
    }

    /// The latest thumbnail of material `index`: while an edited material renders again,
    /// its previous look, as Blender's previews do.
    pub fn texture(&self, index: usize) -> Option<&egui::TextureHandle> {
        Some(&self.textures.get(index)?.as_ref()?.texture)
    }

    /// The pixels of the thumbnail of material `index` if it was rendered of `material`
    /// as it is now.
    pub fn image(&self, index: usize, material: &Material) -> Option<&egui::ColorImage> {
        self.shown(index, material).map(|s| &s.image)
    }

    fn shown(&self, index: usize, material: &Material) -> Option<&Shown> {
        self.textures
            .get(index)?
            .as_ref()
            .filter(|s| s.material == *material)
    }

    /// Why the last thumbnail failed, if it did.
    pub fn error(&self) -> Option<String> {
        lock(&self.shared).error.clone()
    }
}

impl Drop for Thumbnails {
    fn drop(&mut self) {
        lock(&self.shared).quit = true;
        self.shared.wake.notify_all();
        if let Some(worker) = self.worker.take() {
            let _ = worker.join();
        }
    }
}

/// The preview scene: a sphere with material `shown` of `materials` under a soft sky and
/// a warm sun from the upper left, framed to fill most of the thumbnail.
pub fn preview_scene(materials: &[Material], shown: usize) -> Scene {
    let camera = Camera::look_at(Vec3::new(0.0, 0.0, 4.2), Vec3::ZERO, 30.0);
    let mut scene = Scene::empty(camera);
    scene.environment = Vec3::new(0.45, 0.5, 0.6);
    scene.materials = materials.to_vec();
    let sphere = scene.add_mesh(shapes::uv_sphere(48, 24, true));
    scene.add_instance(sphere, shown, Affine3A::IDENTITY);
    scene.add_light(Light::Distant {
        direction: Vec3::new(1.0, -1.0, -1.2).normalize(),
        irradiance: Vec3::new(2.6, 2.4, 2.1),
        angular_diameter: 3.0,
    });
    scene.settings.width = THUMBNAIL_SIZE;
    scene.settings.height = THUMBNAIL_SIZE;
    scene.settings.samples_per_pixel = SAMPLES;
    scene.settings.max_bounces = 6;
    scene
}

/// The worker: renders the first wanted material whose thumbnail is missing or stale,
/// until told to quit.
fn work(ctx: &Arc<GpuContext>, shared: &Shared, repaint: &dyn Fn()) {
    let mut renderer: Option<(Renderer, Scene)> = None;
    // The materials as their thumbnails were last rendered, by index.
    let mut rendered: Vec<Option<Material>> = Vec::new();
    loop {
        let (materials, index) = {
            let mut state = lock(shared);
            loop {
                if state.quit {
                    return;
                }
                let next = state.wanted.as_ref().and_then(|wanted| {
                    let stale = (0..wanted.len())
                        .find(|&i| rendered.get(i).and_then(Option::as_ref) != Some(&wanted[i]));
                    stale.map(|i| (wanted.clone(), i))
                });
                if let Some(next) = next {
                    break next;
                }
                state = shared
                    .wake
                    .wait_timeout(state, Duration::from_secs(1))
                    .map(|(s, _)| s)
                    .unwrap_or_else(|e| e.into_inner().0);
            }
        };
        let scene = preview_scene(&materials, index);
        let result = render(ctx, &mut renderer, scene);
        // Marked done either way: a failed thumbnail is not retried until its material
        // changes.
        if rendered.len() <= index {
            rendered.resize(index + 1, None);
        }
        let material = materials[index].clone();
        rendered[index] = Some(material.clone());
        let mut state = lock(shared);
        match result {
            Ok(image) => {
                state.error = None;
                state.done.push(Rendered {
                    index,
                    material,
                    image,
                });
            }
            Err(e) => state.error = Some(format!("thumbnail of \"{}\": {e}", material.name)),
        }
        drop(state);
        repaint();
    }
}

/// Renders `scene` with the kept renderer when an in-place update takes it, otherwise
/// with a new one (kept for the next thumbnail).
fn render(
    ctx: &Arc<GpuContext>,
    kept: &mut Option<(Renderer, Scene)>,
    scene: Scene,
) -> Result<egui::ColorImage, String> {
    let updated = match kept.as_mut() {
        Some((renderer, old)) => renderer.update(old, &scene).is_ok(),
        None => false,
    };
    if !updated {
        let settings = RenderSettings {
            // The editor's kernel: interpreted graphs, every lobe; usually already
            // compiled for the viewport.
            kernel: KernelKind::Interpreted,
            noise_threshold: 0.0,
            ..RenderSettings::from_scene(&scene)
        };
        let mut renderer =
            Renderer::new(Arc::clone(ctx), &scene, settings).map_err(|e| e.to_string())?;
        renderer.set_pacing(Pacing::Interactive { budget_us: 4000 });
        *kept = Some((renderer, scene.clone()));
    }
    let (renderer, kept_scene) = kept.as_mut().expect("a renderer was kept");
    *kept_scene = scene;
    renderer.clear_film();
    renderer
        .render(0..SAMPLES, RenderControl::default())
        .map_err(|e| e.to_string())?;
    let film = renderer.read_film().map_err(|e| e.to_string())?;
    let image = to_srgb_image(&film, ViewSettings::default());
    Ok(egui::ColorImage::from_rgb(
        [THUMBNAIL_SIZE as usize; 2],
        image.as_raw(),
    ))
}
