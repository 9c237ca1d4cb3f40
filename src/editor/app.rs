//! The editor's window: menu bar, outliner and inspector on the right, the live viewport in
//! the middle, a status line at the bottom, as Blender arranges them. The app owns the
//! [`Document`] and applies the commands its panels return; it owns the viewport's view
//! (not part of the document, as in Blender) and turns mouse and keys into navigation.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use egui::{Color32, Key, KeyboardShortcut, Modifiers, PointerButton, RichText, Sense, Ui};
use glam::Vec3;

use crate::plugin::PluginHost;
use crate::render::{GpuContext, KernelKind};
use crate::scene::{Camera, Material, Scene, lookdev};

use super::document::{Command, Document, GestureId, Selection};
use super::files::{FileDialogs, open_document, save_document};
use super::final_render::{FinalRender, RenderState};
use super::gizmo::{self, Constraint, Mode, Orientation, ViewProjection};
use super::inspector::{InspectorAction, inspector_ui};
use super::navigation;
use super::node_editor::{MaterialDrag, MaterialFileRequest};
use super::node_previews::NodePreviews;
use super::outliner::{Outliner, OutlinerAction};
use super::pick::{Picker, camera_ray};
use super::session::{Recovery, SessionStore, ViewportPreferences};
use super::settings_panel::{RenderAction, ViewOptions, WorldAction, render_tab_ui, world_tab_ui};
use super::thumbnails::Thumbnails;
use super::viewport::{GraphKernels, Target, ViewportRenderer, ViewportStatus};
use super::viewport_preview::{ViewportPreview, preview_scene};

/// Samples per pixel the viewport accumulates before it stops (Blender's viewport default
/// is 1024).
pub const DEFAULT_SAMPLE_LIMIT: u32 = 1024;

/// How the editor starts.
pub struct EditorOptions {
    /// The file to open; None opens the bundled Cornell box.
    pub file: Option<PathBuf>,
    pub dialogs: Box<dyn FileDialogs>,
    pub plugins: PluginHost,
    /// Samples per pixel after which the viewport stops accumulating (and stops asking
    /// for repaints): tests set a small number. None: the user's last choice (the state
    /// folder's viewport preferences), else [`DEFAULT_SAMPLE_LIMIT`].
    pub sample_limit: Option<u32>,
    /// The folder for recent files and autosaves ([`SessionStore::default_dir`]); None
    /// keeps neither (tests that do not test them).
    pub state_dir: Option<PathBuf>,
    /// How often a changed document is autosaved for crash recovery.
    pub autosave_every: Duration,
    /// Close the window once the viewport holds `sample_limit` samples (smoke tests,
    /// scripted screenshots); [`RunReport`] says what it rendered.
    pub quit_when_done: bool,
    /// Render material thumbnails for the material list (tests that do not look at them
    /// leave the device to the viewport).
    pub thumbnails: bool,
    /// How the viewport's kernels hold graph materials: the editor interprets them (a
    /// graph edit shows at once) and switches to the final render's specialised kernel once
    /// the scene is still ([`GRAPH_KERNELS`]); tests that count builds keep them interpreted.
    pub graph_kernels: GraphKernels,
    /// Screen pixels per viewport pixel along each axis ([`PIXEL_SIZES`]): 2 renders a
    /// quarter of the pixels (Blender's Preferences ▸ Viewport ▸ Pixel Size). None: the
    /// user's last choice, else 1.
    pub pixel_size: Option<u32>,
    /// What the editor does once its GPU device is lost, after writing the document to
    /// its recovery autosave: `kiln edit` starts a new editor on the same file
    /// (`restart_after_device_loss` in main.rs) and ends this one, whose window cannot draw
    /// on a lost device; tests record the call.
    pub on_device_lost: Box<dyn FnMut(DeviceLost)>,
    /// Why the editor this one replaces lost its device, if it did: said at start,
    /// beside the recovery of its unsaved changes.
    pub restarted_after_device_loss: Option<String>,
    /// On a software driver, compile the viewport's kernels on the background device
    /// first ([`GpuContext::rehearse_compiles_on`]), so that the window never waits for
    /// one (it froze for a minute on a cold shader cache): `kiln edit` does; tests, which
    /// have no window to keep responsive, leave it off unless they test it.
    pub rehearse_compiles: bool,
}

/// A GPU device lost under the editor, and what of its document was kept.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeviceLost {
    /// The driver's reason.
    pub reason: String,
    /// The document's file, if it has one.
    pub file: Option<PathBuf>,
    /// Whether unsaved changes were written to the recovery autosave just now.
    pub autosaved: bool,
}

/// The viewport's pixel sizes the Render tab offers.
pub const PIXEL_SIZES: [u32; 4] = [1, 2, 4, 8];

/// The editor's viewport: graphs interpreted, the final render's specialised kernel once
/// the scene has been still for 1.5 s.
pub const GRAPH_KERNELS: GraphKernels =
    GraphKernels::InterpretedThenSpecialized(Duration::from_millis(1500));

/// What an editor session rendered, for the caller of [`super::run`].
#[derive(Clone, Debug, Default)]
pub struct RunReport {
    /// Samples per pixel in the viewport when the window closed.
    pub samples: u32,
    pub samples_per_second: f64,
    pub size: [u32; 2],
    pub adapter: String,
    /// The viewport's error, if it had one when the window closed.
    pub error: Option<String>,
}

/// Blender autosaves every two minutes; the issue asks for one.
pub const AUTOSAVE_EVERY: Duration = Duration::from_secs(60);

/// How often the editor gives the C heap's free pages back to the system
/// ([`crate::render::release_free_host_memory`]): on a CPU adapter each rebuilt renderer
/// and compiled kernel frees hundreds of MiB that glibc otherwise keeps.
const HEAP_RELEASE_EVERY: Duration = Duration::from_secs(10);

/// Something the user asked for that waits on the unsaved-changes prompt.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Pending {
    New,
    /// Open a file: the one given (a recent file), or one the dialog asks for.
    Open(Option<PathBuf>),
    Close,
}

/// The tabs of the properties editor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Tab {
    Object,
    Render,
    World,
}

/// A modal transform under way (G, R, S, or a drag of a gizmo arrow).
#[derive(Clone, Copy, Debug)]
struct TransformTool {
    mode: Mode,
    object: usize,
    start: glam::Affine3A,
    /// Where the pointer was when the tool started.
    from: egui::Pos2,
    constraint: Option<Constraint>,
    gesture: GestureId,
    /// Whether a command was applied (a cancel then undoes it).
    applied: bool,
    /// Started by dragging a gizmo arrow: releasing the button confirms.
    dragging: bool,
}

/// Gesture ids of transform tools, apart from the widget ids the panels use.
const TOOL_GESTURES: GestureId = 1 << 63;

/// Metres (scene units) per second of fly navigation, as a share of the scene's size.
const FLY_SPEED: f32 = 0.25;

const UNDO: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Z);
const REDO: KeyboardShortcut =
    KeyboardShortcut::new(Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::Z);
const REDO_Y: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Y);
const SAVE: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::S);
const SAVE_AS: KeyboardShortcut =
    KeyboardShortcut::new(Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::S);
const OPEN: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::O);
const NEW: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::N);
const QUIT: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Q);
const DUPLICATE: KeyboardShortcut = KeyboardShortcut::new(Modifiers::SHIFT, Key::D);

/// What the viewport's scene is made of: the document (serial, image revision) and the
/// node previewed in it.
#[derive(Clone, Debug, PartialEq)]
struct ViewportSceneKey {
    document: (u64, u64),
    preview: Option<ViewportPreview>,
}

/// The editor application (an [`eframe::App`]).
pub struct EditorApp {
    document: Document,
    /// Bumped whenever the document is replaced, so the viewport tells documents apart.
    document_serial: u64,
    view: Camera,
    gpu: Option<Arc<GpuContext>>,
    /// A second device on the same adapter for the renders whose images come back to the
    /// host (thumbnails, node previews, the final render), so that their submissions never
    /// hold up the window's (see [`GpuContext::sibling`]); `gpu` when none could be opened.
    background_gpu: Option<Arc<GpuContext>>,
    render_state: Option<egui_wgpu::RenderState>,
    viewport: Option<ViewportRenderer>,
    /// The material list's thumbnails, and the document state they were last asked for
    /// (document serial, image revision, whether the viewport was building a kernel).
    thumbnails: Option<Thumbnails>,
    thumbnails_key: Option<(u64, u64, bool)>,
    texture: Option<(u64, egui::TextureId)>,
    dialogs: Box<dyn FileDialogs>,
    plugins: PluginHost,
    outliner: Outliner,
    picker: Option<((u64, u64), Picker)>,
    render_scene: Option<((u64, u64), Arc<Scene>)>,
    /// The scene the viewport shows (the document's, or with a node previewed: see
    /// [`super::viewport_preview`]), the state it was made of and its revision, which
    /// counts every change of it.
    viewport_scene: Option<(ViewportSceneKey, u64, Arc<Scene>)>,
    viewport_revision: u64,
    /// Why the previewed node cannot be shown, if it cannot.
    viewport_preview_error: Option<String>,
    /// The node editor's per-node previews.
    node_previews: Option<NodePreviews>,
    options: ViewOptions,
    tab: Tab,
    final_render: Option<FinalRender>,
    /// Whether the render window is open, and the texture of the result it shows.
    render_window: bool,
    render_texture: Option<(usize, egui::TextureHandle)>,
    session: Option<SessionStore>,
    /// The viewport's preferences as the state folder has them (or as they started).
    saved_viewport: ViewportPreferences,
    recent: Vec<PathBuf>,
    autosave_every: Duration,
    last_autosave: Instant,
    /// When the C heap's free pages were last given back ([`HEAP_RELEASE_EVERY`]).
    last_heap_release: Instant,
    /// The document revision the last autosave holds, and the autosave under way.
    autosaved_revision: Option<(u64, u64)>,
    autosave_job: Option<JoinHandle<Result<(), String>>>,
    /// An autosave from a crashed session, offered at start.
    recovery: Option<Recovery>,
    on_device_lost: Box<dyn FnMut(DeviceLost)>,
    /// Why the device was lost, once it was: the editor then draws only that.
    device_lost: Option<String>,
    /// eframe closed the window normally ([`eframe::App::on_exit`]).
    exited: bool,
    quit_when_done: bool,
    report: Option<Arc<std::sync::Mutex<RunReport>>>,
    tool: Option<TransformTool>,
    orientation: Orientation,
    tools_started: u64,
    /// Where Shift+A opened the Add menu over the viewport.
    add_menu_at: Option<egui::Pos2>,
    /// The active tool, whose gizmo the selection shows (the viewport's toolbar).
    gizmo_mode: Mode,
    error: Option<String>,
    /// A message that is not an error (what an import could not represent): its title
    /// and text.
    notice: Option<(String, String)>,
    pending: Option<Pending>,
    allow_close: bool,
    title: String,
    /// Frames drawn since `log_start`, for the debug log of the frame rate.
    frames_logged: u32,
    /// Time spent in the app's code over those frames.
    app_time: Duration,
    log_start: Instant,
    viewport_rect: Option<egui::Rect>,
    status_rect: Option<egui::Rect>,
    node_editor: super::node_editor::NodeEditor,
}

impl EditorApp {
    /// Opens the editor on the options' file (or the Cornell box) with eframe's wgpu
    /// device, which the viewport's renderer shares. A file that fails to open is
    /// reported in the window over the Cornell box; without a wgpu device the viewport
    /// shows why and the rest of the editor works.
    pub fn new(cc: &eframe::CreationContext<'_>, options: EditorOptions) -> Self {
        let mut error = None;
        let document = match &options.file {
            Some(path) => match open_document(path, &options.plugins) {
                Ok(d) => Some(d),
                Err(e) => {
                    error = Some(e);
                    None
                }
            },
            None => None,
        };
        let document = document.unwrap_or_else(|| match crate::scene::default_scene() {
            Ok(scene) => Document::new(scene, None, Vec::new()),
            Err(e) => {
                error = Some(format!("the bundled scene failed to load: {e}"));
                Document::new(
                    Scene::empty(Camera::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, 40.0)),
                    None,
                    Vec::new(),
                )
            }
        });
        let gpu = match cc.wgpu_render_state.as_ref() {
            Some(rs) => match GpuContext::from_device(
                rs.adapter.clone(),
                rs.device.clone(),
                rs.queue.clone(),
            ) {
                Ok(ctx) => Some(ctx),
                Err(e) => {
                    error = Some(format!("the viewport cannot render: {e}"));
                    None
                }
            },
            None => {
                error = Some("the viewport needs eframe's wgpu renderer".into());
                None
            }
        };
        let background_gpu = gpu.as_ref().map(|ctx| {
            let background = ctx.sibling().unwrap_or_else(|e| {
                tracing::warn!(
                    "no second device for background renders, sharing the window's: {e}"
                );
                Arc::clone(ctx)
            });
            if options.rehearse_compiles {
                ctx.rehearse_compiles_on(Arc::clone(&background));
            }
            background
        });
        // Ctrl+Q is the editor's own shortcut (`QUIT`, shown in the File menu), taken the
        // way File ▸ Quit is; egui's built-in copy of it goes, so that there is one.
        cc.egui_ctx.options_mut(|o| o.quit_shortcuts.clear());
        let viewport = gpu.as_ref().map(|ctx| {
            let egui_ctx = cc.egui_ctx.clone();
            ViewportRenderer::new(Arc::clone(ctx), move || egui_ctx.request_repaint())
        });
        let thumbnails = background_gpu
            .as_ref()
            .filter(|_| options.thumbnails)
            .map(|ctx| {
                let egui_ctx = cc.egui_ctx.clone();
                Thumbnails::new(Arc::clone(ctx), move || egui_ctx.request_repaint())
            });
        let node_previews = background_gpu.as_ref().map(|ctx| {
            let egui_ctx = cc.egui_ctx.clone();
            NodePreviews::new(Arc::clone(ctx), move || egui_ctx.request_repaint())
        });
        let view = document.scene().camera;
        let session = options.state_dir.clone().map(SessionStore::new);
        if let Some(reason) = &options.restarted_after_device_loss {
            let notice = format!(
                "The GPU device was lost ({reason}), so Kiln started the editor again; \
                 unsaved changes, if there were any, are offered for recovery."
            );
            error = Some(match error {
                Some(e) => format!("{notice}\n\n{e}"),
                None => notice,
            });
        }
        let remembered = session.as_ref().map_or_else(
            ViewportPreferences::default,
            SessionStore::viewport_preferences,
        );
        let viewport_preferences = ViewportPreferences {
            pixel_size: options.pixel_size.unwrap_or(remembered.pixel_size).max(1),
            max_samples: options
                .sample_limit
                .unwrap_or(remembered.max_samples)
                .max(1),
        };
        if let (Some(store), Some(path)) = (&session, document.path()) {
            if let Err(e) = store.add_recent(path) {
                tracing::warn!("cannot record the recent file: {e}");
            }
        }
        Self {
            document,
            document_serial: 0,
            view,
            gpu,
            background_gpu,
            render_state: cc.wgpu_render_state.clone(),
            viewport,
            thumbnails,
            thumbnails_key: None,
            texture: None,
            dialogs: options.dialogs,
            plugins: options.plugins,
            outliner: Outliner::default(),
            picker: None,
            render_scene: None,
            viewport_scene: None,
            viewport_revision: 0,
            viewport_preview_error: None,
            node_previews,
            options: ViewOptions {
                viewport: viewport_preferences,
                export_options: String::new(),
                graph_kernels: options.graph_kernels,
            },
            tab: Tab::Object,
            final_render: None,
            render_window: false,
            render_texture: None,
            recent: session
                .as_ref()
                .map(SessionStore::recent)
                .unwrap_or_default(),
            recovery: session.as_ref().and_then(SessionStore::recovery),
            on_device_lost: options.on_device_lost,
            device_lost: None,
            exited: false,
            saved_viewport: viewport_preferences,
            session,
            autosave_every: options.autosave_every,
            last_autosave: Instant::now(),
            last_heap_release: Instant::now(),
            autosaved_revision: None,
            autosave_job: None,
            quit_when_done: options.quit_when_done,
            report: None,
            tool: None,
            orientation: Orientation::Global,
            tools_started: 0,
            add_menu_at: None,
            gizmo_mode: Mode::Move,
            error,
            notice: None,
            pending: None,
            allow_close: false,
            title: String::new(),
            frames_logged: 0,
            app_time: Duration::ZERO,
            log_start: Instant::now(),
            viewport_rect: None,
            status_rect: None,
            node_editor: Default::default(),
        }
    }

    pub fn document(&self) -> &Document {
        &self.document
    }

    /// The viewport's current view.
    pub fn view(&self) -> &Camera {
        &self.view
    }

    /// What the viewport's worker last reported (None without a GPU).
    pub fn viewport_status(&self) -> Option<ViewportStatus> {
        self.viewport.as_ref().map(ViewportRenderer::status)
    }

    /// The device the viewport renders on.
    pub fn gpu(&self) -> Option<&Arc<GpuContext>> {
        self.gpu.as_ref()
    }

    /// The device of the thumbnails, node previews and final renders (see
    /// [`GpuContext::sibling`]).
    pub fn background_gpu(&self) -> Option<&Arc<GpuContext>> {
        self.background_gpu.as_ref()
    }

    /// Where the viewport was laid out in the last frame (points).
    pub fn viewport_rect(&self) -> Option<egui::Rect> {
        self.viewport_rect
    }

    /// The node editor's state (the material it shows, where it drew its pins).
    /// The material thumbnails, when the app renders them.
    pub fn thumbnails(&self) -> Option<&Thumbnails> {
        self.thumbnails.as_ref()
    }

    /// The node editor's per-node previews, when there is a device to make them.
    pub fn node_previews(&self) -> Option<&NodePreviews> {
        self.node_previews.as_ref()
    }

    pub fn node_editor(&self) -> &super::node_editor::NodeEditor {
        &self.node_editor
    }

    /// The error shown to the user, if any.
    pub fn error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// Where the status line was laid out in the last frame (points).
    pub fn status_rect(&self) -> Option<egui::Rect> {
        self.status_rect
    }

    /// Whether the unsaved-changes prompt is showing.
    pub fn is_prompting(&self) -> bool {
        self.pending.is_some()
    }

    /// Where the session's [`RunReport`] is written when the window closes.
    pub fn report_to(&mut self, report: Arc<std::sync::Mutex<RunReport>>) {
        self.report = Some(report);
    }

    /// The state of the last final render, if one was started.
    pub fn render_state(&self) -> Option<RenderState> {
        self.final_render.as_ref().map(FinalRender::state)
    }

    /// The crashed session's autosave the editor is offering, if any.
    pub fn offered_recovery(&self) -> Option<&Recovery> {
        self.recovery.as_ref()
    }

    /// The files File ▸ Open Recent lists.
    pub fn recent_files(&self) -> &[PathBuf] {
        &self.recent
    }

    /// Applies `command` to the document as a panel would (one undo step; a refused one
    /// is reported in the window): scripted edits, tests and benchmarks.
    pub fn apply_command(&mut self, command: Command) {
        self.apply(command, None);
    }

    /// Applies a command, reporting a refused one in the window.
    fn apply(&mut self, command: Command, gesture: Option<GestureId>) {
        if let Err(e) = self.document.apply(command, gesture) {
            self.error = Some(e.to_string());
        }
    }

    fn scene_key(&self) -> (u64, u64) {
        (self.document_serial, self.document.image_revision())
    }

    fn render_scene(&mut self) -> Arc<Scene> {
        let key = self.scene_key();
        match &self.render_scene {
            Some((k, scene)) if *k == key => Arc::clone(scene),
            _ => {
                let scene = Arc::new(self.document.render_scene());
                self.render_scene = Some((key, Arc::clone(&scene)));
                scene
            }
        }
    }

    /// The scene the viewport renders, and its revision: the document's, with the
    /// node the node editor previews in the viewport (Ctrl+Shift+click) shown on its
    /// material instead of the material. Only the viewport takes it: final renders take
    /// [`Self::render_scene`].
    fn viewport_scene(&mut self) -> (Arc<Scene>, u64) {
        let key = ViewportSceneKey {
            document: self.scene_key(),
            preview: self.node_editor.viewport_preview().cloned(),
        };
        if let Some((k, revision, scene)) = &self.viewport_scene
            && *k == key
        {
            return (Arc::clone(scene), *revision);
        }
        let mut scene = self.render_scene();
        self.viewport_preview_error = None;
        if let Some(preview) = &key.preview {
            let mut previewed = (*scene).clone();
            let shown = self
                .document
                .material_graph(preview.material)
                .ok_or_else(|| format!("no material {}", preview.material))
                .and_then(|graph| preview_scene(&mut previewed, &graph, preview));
            match shown {
                Ok(_) => scene = Arc::new(previewed),
                Err(e) => self.viewport_preview_error = Some(e),
            }
        }
        self.viewport_revision += 1;
        self.viewport_scene = Some((key, self.viewport_revision, Arc::clone(&scene)));
        (scene, self.viewport_revision)
    }

    fn replace_document(&mut self, document: Document) {
        self.document = document;
        self.document_serial += 1;
        self.view = self.document.scene().camera;
        self.picker = None;
        self.render_scene = None;
        // The previewed node was another document's.
        self.node_editor.clear_viewport_preview();
    }

    // ---- files ----

    fn request(&mut self, action: Pending, ctx: &egui::Context) {
        if self.pending.is_some() {
            return;
        }
        if self.document.is_dirty() {
            self.pending = Some(action);
        } else {
            self.proceed(action, ctx);
        }
    }

    fn proceed(&mut self, action: Pending, ctx: &egui::Context) {
        match action {
            Pending::New => self.new_document(),
            Pending::Open(Some(path)) => self.open(path),
            Pending::Open(None) => {
                if let Some(path) = self.dialogs.open_path() {
                    self.open(path);
                }
            }
            Pending::Close => {
                if let Some(store) = &self.session {
                    store.clear_autosave();
                }
                self.allow_close = true;
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
        }
    }

    /// Opens `path` in place of the document; on failure the document stays and the
    /// error is shown.
    pub fn open(&mut self, path: PathBuf) {
        match open_document(&path, &self.plugins) {
            Ok(document) => {
                self.replace_document(document);
                self.remember(&path);
            }
            Err(e) => self.error = Some(e),
        }
    }

    /// Puts `path` first in the recent files.
    fn remember(&mut self, path: &std::path::Path) {
        if let Some(store) = &self.session {
            if let Err(e) = store.add_recent(path) {
                tracing::warn!("cannot record the recent file: {e}");
            }
            self.recent = store.recent();
        }
    }

    /// Replaces the document with a new, empty scene: a camera and a grey world.
    fn new_document(&mut self) {
        let camera = Camera::look_at(Vec3::new(7.0, 5.0, 7.0), Vec3::ZERO, 40.0);
        let mut scene = Scene::empty(camera);
        scene.environment = Vec3::splat(super::document::NEW_SCENE_GREY);
        self.replace_document(Document::new(scene, None, Vec::new()));
    }

    /// Adds what an importer plugin reads from a file the dialog asks for to the scene,
    /// as one undo step.
    fn import(&mut self) {
        let extensions = self.plugins.import_extensions();
        if extensions.is_empty() {
            self.error = Some("no importer plugin is loaded (see `kiln plugins`)".into());
            return;
        }
        let Some(path) = self.dialogs.import_path(&extensions) else {
            return;
        };
        let imported = match self.plugins.import(&path) {
            Ok(imported) => imported,
            Err(e) => {
                self.error = Some(format!("cannot import {}: {e}", path.display()));
                return;
            }
        };
        // A model without lights imported into a scene that nothing lights is staged as
        // `kiln edit model.obj` opens one (the look-dev default), in the same undo step.
        let stage = !imported.has_lights && self.document.unlit();
        let mut scene = imported.scene;
        if !stage {
            let command = self.document.append(scene, imported.images);
            self.apply(command, None);
            return;
        }
        lookdev::add_ground(&mut scene, lookdev::Ground::Plane);
        let world = scene.world.take().unwrap_or_else(lookdev::world);
        let mut view = self.document.scene().settings.view;
        view.exposure_ev = lookdev::EXPOSURE_EV;
        let append = self.document.append(scene, imported.images);
        let commands = vec![
            append,
            Command::SetWorld(Some(Box::new(world))),
            Command::SetView(view),
        ];
        if let Err(e) = self.document.apply_all(commands) {
            self.error = Some(e.to_string());
        }
    }

    /// The material list's Import Materials…: the materials of a file a material-format plugin
    /// reads, added as one undo step (one whose graph does not compile, for a missing
    /// image, is added with its graph kept and the error shown, as an edit that does not
    /// compile is); the first is shown. Warnings are shown after.
    fn import_materials(&mut self) {
        let extensions = self.plugins.material_extensions(false);
        if extensions.is_empty() {
            self.error = Some("no material-format plugin is loaded (see `kiln plugins`)".into());
            return;
        }
        let Some(path) = self.dialogs.material_import_path(&extensions) else {
            return;
        };
        let imported = match self.plugins.import_materials(&path) {
            Ok(imported) => imported,
            Err(e) => {
                self.error = Some(format!("cannot import {}: {e}", path.display()));
                return;
            }
        };
        let first = self.document.scene().materials.len();
        let mut commands = Vec::new();
        let mut names: Vec<String> = Vec::new();
        for (name, graph) in imported.materials {
            let mut unique = self.document.unique_material_name(&name);
            for n in 2.. {
                if !names.contains(&unique) {
                    break;
                }
                unique = self.document.unique_material_name(&format!("{name} {n}"));
            }
            names.push(unique.clone());
            let (material, pending) = match Material::from_graph(&unique, graph.clone()) {
                Ok(m) => (m, None),
                Err(e) => (
                    Material::with(&unique, Default::default()),
                    Some(Box::new((graph, e))),
                ),
            };
            commands.push(Command::AddMaterial {
                index: first + commands.len(),
                material: Box::new(material),
                pending,
            });
        }
        if let Err(e) = self.document.apply_all(commands) {
            self.error = Some(e.to_string());
            return;
        }
        self.node_editor.show_material(first);
        if !imported.warnings.is_empty() {
            self.notice = Some((
                "Imported with warnings".into(),
                format!(
                    "{} imported from {}:\n\n{}",
                    names.join(", "),
                    path.display(),
                    imported.warnings.join("\n")
                ),
            ));
        }
    }

    /// The material list's Export Material…: material `material`'s graph (as edited) written
    /// through a material-format plugin, its images named relative to the file.
    fn export_material(&mut self, material: usize) {
        let extensions = self.plugins.material_extensions(true);
        if extensions.is_empty() {
            self.error =
                Some("no material-format plugin writes materials (see `kiln plugins`)".into());
            return;
        }
        let Some(mut graph) = self.document.material_graph(material) else {
            return;
        };
        let name = self.document.scene().materials[material].name.clone();
        // As `kiln material export`: a graph that does not compile is not written (another
        // program would read a material Kiln cannot render).
        if let Some(e) = self.document.graph_error(material) {
            self.error = Some(format!(
                "cannot export {name}: its graph does not compile ({e}); fix it first"
            ));
            return;
        }
        let Some(path) = self.dialogs.material_export_path(&name, &extensions) else {
            return;
        };
        let folder = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
            _ => std::path::PathBuf::from("."),
        };
        crate::material::relative_files(&mut graph, &folder);
        if let Err(e) = self.plugins.export_material(&path, &name, &graph) {
            self.error = Some(format!("cannot export {name}: {e}"));
        }
    }

    /// Recovers the offered autosave as an unsaved document (Save asks where, starting
    /// from the file it came from).
    fn recover(&mut self) {
        let Some(recovery) = self.recovery.take() else {
            return;
        };
        match crate::scene::load_scene(&recovery.scene) {
            Ok(scene) => {
                let mut document = Document::new(scene, None, Vec::new());
                document.mark_unsaved();
                self.replace_document(document);
                if let Some(store) = &self.session {
                    store.discard(&recovery);
                }
            }
            Err(e) => self.error = Some(format!("the autosave cannot be recovered: {e}")),
        }
    }

    /// Checks whether the GPU device was lost (a driver crash, a reset, running out of
    /// memory); once it is, writes unsaved changes to the recovery autosave at once (the
    /// last may be a minute old) and hands over to [`EditorOptions::on_device_lost`].
    /// True from then on: nothing else is drawn, since the window draws with the same
    /// device.
    fn handle_device_loss(&mut self, ui: &mut Ui) -> bool {
        if let Some(reason) = &self.device_lost {
            ui.label(format!(
                "The GPU device was lost ({reason}); the document is in the recovery autosave."
            ));
            return true;
        }
        let Some(gpu) = &self.gpu else {
            return false;
        };
        // Runs the device's callbacks, the one that says it is lost among them. The
        // background device is not polled here (a poll waits while a kernel compiles in
        // a submission): its workers' polls report its loss (a driver reset loses both).
        let _ = gpu.device.poll(wgpu::PollType::Poll);
        let background = self.background_gpu.as_ref().and_then(|b| b.lost());
        let Some(reason) = gpu.lost().or(background) else {
            return false;
        };
        self.report_device_loss(reason);
        // The notice shows from this frame on.
        self.handle_device_loss(ui)
    }

    /// Writes unsaved changes to the recovery autosave at once and hands over to
    /// [`EditorOptions::on_device_lost`] (once).
    fn report_device_loss(&mut self, reason: String) {
        tracing::error!("the editor's GPU device was lost: {reason}");
        let autosaved = match &self.session {
            Some(store) if self.document.is_dirty() => {
                // A background autosave under way would finish after this one.
                if let Some(job) = self.autosave_job.take() {
                    let _ = job.join();
                }
                let source = self.document.path();
                let written = store.autosave(self.document.scene(), self.document.images(), source);
                if let Err(e) = &written {
                    tracing::error!("the autosave after the device loss failed: {e}");
                }
                written.is_ok()
            }
            _ => false,
        };
        let lost = DeviceLost {
            reason: reason.clone(),
            file: self.document.path().map(Path::to_owned),
            autosaved,
        };
        self.device_lost = Some(reason);
        (self.on_device_lost)(lost);
    }

    /// Writes a changed document to the recovery autosave every [`AUTOSAVE_EVERY`], on a
    /// thread of its own (a large scene takes a while to write).
    fn autosave(&mut self) {
        let Some(store) = &self.session else {
            return;
        };
        if let Some(job) = self.autosave_job.take_if(|j| j.is_finished()) {
            match job.join() {
                Ok(Err(e)) => tracing::warn!("autosave failed: {e}"),
                Err(_) => tracing::warn!("autosave panicked"),
                Ok(Ok(())) => {}
            }
        }
        let key = (self.document_serial, self.document.revision());
        if self.autosave_job.is_some()
            || !self.document.is_dirty()
            || self.autosaved_revision == Some(key)
            || self.last_autosave.elapsed() < self.autosave_every
        {
            return;
        }
        self.last_autosave = Instant::now();
        self.autosaved_revision = Some(key);
        let (store, scene) = (store.clone(), self.document.scene().clone());
        let images = self.document.images().to_vec();
        let source = self.document.path().map(|p| p.to_owned());
        self.autosave_job = std::thread::Builder::new()
            .name("kiln autosave".into())
            .spawn(move || store.autosave(&scene, &images, source.as_deref()))
            .ok();
    }

    /// Starts the final render of the document (hidden items left out) with the kernel
    /// specialised to it.
    fn start_render(&mut self, ctx: &egui::Context) {
        let Some(gpu) = &self.background_gpu else {
            self.error = Some("rendering needs a GPU device, and none was found".into());
            return;
        };
        if self
            .final_render
            .as_ref()
            .is_some_and(FinalRender::is_running)
        {
            return;
        }
        let repaint = ctx.clone();
        self.final_render = Some(FinalRender::start(
            Arc::clone(gpu),
            self.render_scene(),
            move || repaint.request_repaint(),
        ));
        self.render_window = true;
    }

    /// Writes the last render through the exporter plugins (or the host's writers).
    fn export_render(&mut self) {
        let Some(RenderState::Finished(result)) = self.render_state() else {
            self.error = Some("render an image first (Render ▸ Render Image, F12)".into());
            return;
        };
        let extensions = self.plugins.export_extensions();
        let Some(path) = self.dialogs.export_path(&extensions) else {
            return;
        };
        if let Err(e) = self
            .plugins
            .write_image(&path, &result.film, &self.options.export_options)
        {
            self.error = Some(e);
        }
    }

    /// Saves to the document's file, or asks where when it has none (or was imported).
    /// Returns whether it was saved.
    fn save(&mut self) -> bool {
        match self.document.path().map(|p| p.to_owned()) {
            Some(path) => self.save_to(path),
            None => self.save_as(),
        }
    }

    fn save_as(&mut self) -> bool {
        match self.dialogs.save_path(self.document.path()) {
            Some(path) => self.save_to(path),
            None => false,
        }
    }

    fn save_to(&mut self, path: PathBuf) -> bool {
        match save_document(&mut self.document, &path) {
            Ok(()) => {
                self.remember(&path);
                // Nothing is lost silently: an edited graph that does not compile stays
                // in the document, but the file keeps the material's last valid graph.
                let uncompiled: Vec<String> = self
                    .document
                    .uncompiled_graphs()
                    .map(|(m, e)| {
                        let name = &self.document.scene().materials[m].name;
                        format!("\"{name}\" ({})", e.message)
                    })
                    .collect();
                if !uncompiled.is_empty() {
                    self.error = Some(format!(
                        "Saved {}, with the last graph that compiled for {}: fix the graph and save again to keep the edit",
                        path.display(),
                        uncompiled.join(", ")
                    ));
                }
                true
            }
            Err(e) => {
                self.error = Some(e);
                false
            }
        }
    }

    // ---- panels ----

    fn shortcuts(&mut self, ctx: &egui::Context) {
        if ctx.egui_wants_keyboard_input() {
            return;
        }
        // Longer shortcuts first: Ctrl+Shift+Z would also match Ctrl+Z.
        if ctx.input_mut(|i| i.consume_shortcut(&REDO) || i.consume_shortcut(&REDO_Y)) {
            self.document.redo();
        }
        if ctx.input_mut(|i| i.consume_shortcut(&UNDO)) {
            self.document.undo();
        }
        if ctx.input_mut(|i| i.consume_shortcut(&SAVE_AS)) {
            self.save_as();
        }
        if ctx.input_mut(|i| i.consume_shortcut(&SAVE)) {
            self.save();
        }
        if ctx.input_mut(|i| i.consume_shortcut(&OPEN)) {
            self.request(Pending::Open(None), ctx);
        }
        if ctx.input_mut(|i| i.consume_shortcut(&NEW)) {
            self.request(Pending::New, ctx);
        }
        if ctx.input_mut(|i| i.consume_shortcut(&QUIT)) {
            self.request(Pending::Close, ctx);
        }
        let add = KeyboardShortcut::new(Modifiers::SHIFT, Key::A);
        let over_viewport = ctx
            .pointer_hover_pos()
            .zip(self.viewport_rect)
            .filter(|(p, rect)| rect.contains(*p));
        if let Some((pos, _)) = over_viewport {
            if ctx.input_mut(|i| i.consume_shortcut(&add)) {
                self.add_menu_at = Some(pos);
            }
        }
        if ctx.input(|i| i.key_pressed(Key::F12)) {
            self.start_render(ctx);
        }
        // Over the node editor, these keys are the node editor's (its nodes, not objects).
        let over_nodes = ctx
            .pointer_hover_pos()
            .zip(self.node_editor.canvas_rect())
            .is_some_and(|(p, rect)| rect.contains(p));
        if !over_nodes && ctx.input_mut(|i| i.consume_shortcut(&DUPLICATE)) {
            if let Some(command) = self
                .document
                .selection
                .and_then(|s| self.document.duplicate(s))
            {
                self.apply(command, None);
            }
        }
        let delete = ctx.input(|i| {
            i.key_pressed(Key::Delete) || (i.key_pressed(Key::X) && i.modifiers.is_none())
        });
        if delete && self.tool.is_none() && !over_nodes {
            if let Some(command) = self
                .document
                .selection
                .and_then(|s| self.document.delete(s))
            {
                self.apply(command, None);
            }
        }
        if !over_nodes && ctx.input(|i| i.key_pressed(Key::Home)) {
            self.view = navigation::frame_all(&self.view, self.document.scene());
        }
        if !over_nodes && ctx.input(|i| i.key_pressed(Key::F)) {
            self.frame_selected();
        }
    }

    fn frame_selected(&mut self) {
        let Some(Selection::Object(i)) = self.document.selection else {
            return;
        };
        let scene = self.document.scene();
        let mut only = Scene::empty(scene.camera);
        only.meshes = scene.meshes.clone();
        only.instances = vec![scene.instances[i].clone()];
        self.view = navigation::frame_all(&self.view, &only);
    }

    fn menu_bar(&mut self, ui: &mut Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui
                    .add(egui::Button::new("New").shortcut_text(ui.ctx().format_shortcut(&NEW)))
                    .clicked()
                {
                    self.request(Pending::New, ui.ctx());
                }
                if ui
                    .add(egui::Button::new("Open…").shortcut_text(ui.ctx().format_shortcut(&OPEN)))
                    .clicked()
                {
                    self.request(Pending::Open(None), ui.ctx());
                }
                ui.menu_button("Open Recent", |ui| {
                    if self.recent.is_empty() {
                        ui.weak("No recent files");
                    }
                    for path in self.recent.clone() {
                        let name = path
                            .file_name()
                            .map_or(path.display().to_string(), |n| n.to_string_lossy().into());
                        if ui
                            .button(name)
                            .on_hover_text(path.display().to_string())
                            .clicked()
                        {
                            self.request(Pending::Open(Some(path)), ui.ctx());
                        }
                    }
                });
                if ui
                    .add(egui::Button::new("Save").shortcut_text(ui.ctx().format_shortcut(&SAVE)))
                    .clicked()
                {
                    self.save();
                }
                if ui
                    .add(
                        egui::Button::new("Save As…")
                            .shortcut_text(ui.ctx().format_shortcut(&SAVE_AS)),
                    )
                    .clicked()
                {
                    self.save_as();
                }
                ui.separator();
                if ui.button("Import…").clicked() {
                    self.import();
                }
                let rendered = matches!(self.render_state(), Some(RenderState::Finished(_)));
                if ui
                    .add_enabled(rendered, egui::Button::new("Export Render…"))
                    .clicked()
                {
                    self.export_render();
                }
                ui.separator();
                if ui
                    .add(egui::Button::new("Quit").shortcut_text(ui.ctx().format_shortcut(&QUIT)))
                    .clicked()
                {
                    self.request(Pending::Close, ui.ctx());
                }
            });
            ui.menu_button("Edit", |ui| {
                if ui
                    .add_enabled(
                        self.document.can_undo(),
                        egui::Button::new("Undo").shortcut_text(ui.ctx().format_shortcut(&UNDO)),
                    )
                    .clicked()
                {
                    self.document.undo();
                }
                if ui
                    .add_enabled(
                        self.document.can_redo(),
                        egui::Button::new("Redo").shortcut_text(ui.ctx().format_shortcut(&REDO)),
                    )
                    .clicked()
                {
                    self.document.redo();
                }
                ui.separator();
                let selection = self.document.selection;
                let duplicate = selection.and_then(|s| self.document.duplicate(s));
                if ui
                    .add_enabled(
                        duplicate.is_some(),
                        egui::Button::new("Duplicate")
                            .shortcut_text(ui.ctx().format_shortcut(&DUPLICATE)),
                    )
                    .clicked()
                {
                    if let Some(command) = duplicate {
                        self.apply(command, None);
                    }
                }
                let delete = selection.and_then(|s| self.document.delete(s));
                if ui
                    .add_enabled(
                        delete.is_some(),
                        egui::Button::new("Delete").shortcut_text("X"),
                    )
                    .clicked()
                {
                    if let Some(command) = delete {
                        self.apply(command, None);
                    }
                }
            });
            ui.menu_button("Add", |ui| {
                if self.add_menu_items(ui) {
                    ui.close();
                }
            });
            ui.menu_button("Render", |ui| {
                let running = self
                    .final_render
                    .as_ref()
                    .is_some_and(FinalRender::is_running);
                if ui
                    .add_enabled(
                        !running,
                        egui::Button::new("Render Image").shortcut_text("F12"),
                    )
                    .clicked()
                {
                    self.start_render(ui.ctx());
                }
                if ui
                    .add_enabled(
                        self.final_render.is_some(),
                        egui::Button::new("View Render"),
                    )
                    .clicked()
                {
                    self.render_window = true;
                }
            });
            ui.menu_button("View", |ui| {
                if ui
                    .add(egui::Button::new("Frame All").shortcut_text("Home"))
                    .clicked()
                {
                    self.view = navigation::frame_all(&self.view, self.document.scene());
                }
                if ui
                    .add(egui::Button::new("Frame Selected").shortcut_text("F"))
                    .clicked()
                {
                    self.frame_selected();
                }
                if ui.button("Look Through Camera").clicked() {
                    self.view = self.document.scene().camera;
                }
                ui.separator();
                ui.label("Transform orientation");
                ui.radio_value(&mut self.orientation, Orientation::Global, "Global");
                ui.radio_value(&mut self.orientation, Orientation::Local, "Local");
                ui.separator();
                ui.weak("G / R / S: move, rotate, scale the selection (X Y Z: axis)");
                ui.weak("Fly: hold the right mouse button, move with W A S D, Q E");
            });
        });
    }

    fn side_panels(&mut self, ui: &mut Ui) {
        egui::Panel::right("properties")
            .resizable(true)
            .default_size(330.0)
            .show(ui, |ui| {
                let height = ui.available_height();
                ui.allocate_ui(egui::vec2(ui.available_width(), height * 0.35), |ui| {
                    ui.label(RichText::new("Outliner").heading());
                    ui.separator();
                    let actions = self.outliner.ui(ui, &self.document);
                    for action in actions {
                        match action {
                            OutlinerAction::Select(target) => {
                                self.document.selection = Some(target)
                            }
                            OutlinerAction::Apply(command) => self.apply(command, None),
                        }
                    }
                });
                ui.separator();
                ui.horizontal(|ui| {
                    for (tab, name) in [
                        (Tab::Object, "▣ Object"),
                        (Tab::Render, "📷 Render"),
                        (Tab::World, "🌐 World"),
                    ] {
                        ui.selectable_value(&mut self.tab, tab, RichText::new(name).strong());
                    }
                });
                ui.separator();
                match self.tab {
                    Tab::Object => self.object_tab(ui),
                    Tab::Render => self.render_tab(ui),
                    Tab::World => self.world_tab(ui),
                }
            });
    }

    fn render_tab(&mut self, ui: &mut Ui) {
        let state = self.render_state();
        let actions = egui::ScrollArea::vertical()
            .auto_shrink([false, false])
            .show(ui, |ui| {
                render_tab_ui(ui, &self.document, &mut self.options, state)
            })
            .inner;
        // Written once a change is done, not on every frame of a drag of Max Samples.
        let chosen = self.options.viewport;
        if chosen != self.saved_viewport && !ui.input(|i| i.pointer.any_down()) {
            self.saved_viewport = chosen;
            if let Some(store) = &self.session
                && let Err(e) = store.save_viewport_preferences(chosen)
            {
                tracing::warn!("cannot keep the viewport's preferences: {e}");
            }
        }
        for action in actions {
            match action {
                RenderAction::Edit(edit) => self.apply(edit.command, edit.gesture),
                RenderAction::StartRender => self.start_render(ui.ctx()),
                RenderAction::CancelRender => {
                    if let Some(render) = &self.final_render {
                        render.cancel();
                    }
                }
                RenderAction::ShowResult => self.render_window = true,
                RenderAction::Export => self.export_render(),
            }
        }
    }

    fn world_tab(&mut self, ui: &mut Ui) {
        let actions = egui::ScrollArea::vertical()
            .auto_shrink([false, false])
            .show(ui, |ui| world_tab_ui(ui, &self.document))
            .inner;
        for action in actions {
            match action {
                WorldAction::Edit(edit) => self.apply(edit.command, edit.gesture),
                WorldAction::LoadMap => {
                    let Some(path) = self.dialogs.environment_path() else {
                        continue;
                    };
                    match crate::scene::EnvironmentMap::load(&path) {
                        Ok(map) => {
                            self.apply(Command::SetEnvironmentMap(Some(Box::new(map))), None)
                        }
                        Err(e) => self.error = Some(format!("cannot load {}: {e}", path.display())),
                    }
                }
            }
        }
    }

    fn object_tab(&mut self, ui: &mut Ui) {
        for action in inspector_ui(ui, &self.document, &self.view) {
            match action {
                InspectorAction::Edit(edit) => self.apply(edit.command, edit.gesture),
                InspectorAction::LookThroughCamera => self.view = self.document.scene().camera,
                InspectorAction::CameraFromView => {
                    let mut camera = self.view;
                    let old = self.document.scene().camera;
                    camera.aperture_radius = old.aperture_radius;
                    camera.focus_distance = (camera.look_at - camera.position).length();
                    self.apply(Command::SetCamera(camera), None);
                }
            }
        }
    }

    fn status_bar(&mut self, ui: &mut Ui) {
        let panel = egui::Panel::bottom("status").show(ui, |ui| {
            ui.horizontal(|ui| {
                if let Some(status) = self.viewport_status() {
                    let rate = status.samples_per_second();
                    let rate = if rate >= 1e6 {
                        format!("{:.2} M", rate / 1e6)
                    } else {
                        format!("{:.0} k", rate / 1e3)
                    };
                    let t = status.elapsed.as_secs_f32();
                    let pixel_size = match self.options.viewport.pixel_size {
                        1 => String::new(),
                        n => format!(" at {n}× pixels"),
                    };
                    ui.label(format!(
                        "Samples {}/{}  ·  {rate} samples/s  ·  {:02}:{:05.2}  ·  {}×{}{pixel_size}",
                        status.samples,
                        self.options.viewport.max_samples,
                        (t / 60.0) as u32,
                        t % 60.0,
                        status.size[0],
                        status.size[1],
                    ));
                    if let Some(since) = status.building {
                        ui.label(RichText::new(preparing_label(since.elapsed())).weak())
                            .on_hover_text(
                                "Building the viewport's renderers: the scene's BVHs, their \
                                 upload and, the first time a kernel is used, its compile, which \
                                 a software driver (lavapipe) can take minutes over. Mesa keeps \
                                 compiled kernels on disk, so the next time is quick.",
                            );
                        // The clock ticks while nothing else repaints.
                        ui.ctx().request_repaint_after(Duration::from_millis(500));
                    }
                    let interpreted = status.kernel == Some(KernelKind::Interpreted);
                    let text = match (interpreted, status.compiling) {
                        (true, true) => Some("· graphs interpreted, compiling…"),
                        (true, false) => Some("· graphs interpreted"),
                        (false, true) => Some("· compiling…"),
                        (false, false) => None,
                    };
                    if let Some(text) = text {
                        ui.label(RichText::new(text).weak()).on_hover_text(
                            "While you edit, the viewport's kernel holds every lobe and runs \
                             material graphs through the interpreter, so that an edit shows at \
                             once; once the scene is still, the final render's kernel (only \
                             what the scene uses, graphs compiled) is built in the background \
                             and samples faster.",
                        );
                    }
                }
                if let Some(gpu) = &self.gpu {
                    ui.separator();
                    ui.label(RichText::new(gpu.describe()).weak());
                }
            });
        });
        self.status_rect = Some(panel.response.rect);
    }

    fn viewport_ui(&mut self, ui: &mut Ui) {
        let rect = ui.available_rect_before_wrap();
        self.viewport_rect = Some(rect);
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let scale = ui.ctx().pixels_per_point() / self.options.viewport.pixel_size as f32;
        let size = [
            ((rect.width() * scale).round() as u32).max(1),
            ((rect.height() * scale).round() as u32).max(1),
        ];
        // A material dropped from the node editor's material list onto an object.
        if let (Some(dragged), Some(pos)) = (
            response.dnd_release_payload::<MaterialDrag>(),
            response.hover_pos(),
        ) && let Some(object) = self.object_at(pos, rect)
        {
            let MaterialDrag(material) = *dragged;
            self.apply(Command::AssignMaterial { object, material }, None);
        }
        let tool_was_active = self.tool.is_some();
        self.transform_tool(ui, &response, rect);
        if !tool_was_active && self.tool.is_none() {
            self.navigate(ui, &response, rect);
        }

        let (scene, scene_revision) = self.viewport_scene();
        let target = Target {
            scene,
            scene_revision,
            camera: self.view,
            size,
            sample_limit: self.options.viewport.max_samples,
            view: self.document.scene().settings.view,
            graphs: self.options.graph_kernels,
        };
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, Color32::from_gray(30));
        let Some(viewport) = self.viewport.as_mut() else {
            painter.text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                "No GPU device: the viewport cannot render.",
                egui::FontId::proportional(16.0),
                Color32::LIGHT_RED,
            );
            return;
        };
        viewport.ui_frame();
        viewport.post(target);
        let status = viewport.status();
        if let Some((generation, view)) = &status.texture {
            let stale = self.texture.is_none_or(|(g, _)| g != *generation);
            if stale {
                if let Some(id) = self.register_texture(view) {
                    self.texture = Some((*generation, id));
                }
            }
        }
        if let Some((_, id)) = self.texture {
            painter.image(
                id,
                rect,
                egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                Color32::WHITE,
            );
        }
        self.selection_outline(&painter, rect);
        self.draw_gizmo(&painter, rect);
        self.toolbar(ui, rect);
        self.viewport_preview_banner(ui, rect);
        if let Some(error) = &status.error {
            painter.text(
                rect.left_top() + egui::vec2(12.0, 12.0),
                egui::Align2::LEFT_TOP,
                error,
                egui::FontId::proportional(14.0),
                Color32::LIGHT_RED,
            );
        }
    }

    /// The banner over the viewport while it previews a node: which, why it cannot if it
    /// cannot, and the button that clears it (as do Esc and Ctrl+Shift+click on empty
    /// canvas in the node editor).
    fn viewport_preview_banner(&mut self, ui: &mut Ui, rect: egui::Rect) {
        let Some(preview) = self.node_editor.viewport_preview().cloned() else {
            return;
        };
        let material = self
            .document
            .scene()
            .materials
            .get(preview.material)
            .map_or("?", |m| m.name.as_str());
        let at = egui::pos2(rect.center().x, rect.top() + 8.0);
        let mut clear = false;
        egui::Area::new(egui::Id::new("viewport preview banner"))
            .fixed_pos(at)
            .pivot(egui::Align2::CENTER_TOP)
            .order(egui::Order::Foreground)
            .show(ui.ctx(), |ui| {
                egui::Frame::popup(ui.style()).show(ui, |ui| {
                    ui.horizontal(|ui| {
                        ui.label(
                            RichText::new(format!(
                                "Previewing node {} of \"{material}\"",
                                preview.node
                            ))
                            .strong(),
                        );
                        if let Some(e) = &self.viewport_preview_error {
                            ui.label(RichText::new(format!("⚠ {e}")).color(Color32::LIGHT_RED));
                        }
                        clear = ui
                            .button("🗙 Clear preview")
                            .on_hover_text("Show the material again (Esc)")
                            .clicked();
                    });
                });
            });
        if clear {
            self.node_editor.clear_viewport_preview();
        }
    }

    /// Hands the viewport's texture to egui's renderer (the first time) or points the
    /// egui texture at it (after a resize replaced it).
    fn register_texture(&self, view: &wgpu::TextureView) -> Option<egui::TextureId> {
        let rs = self.render_state.as_ref()?;
        let mut renderer = rs.renderer.write();
        Some(match self.texture {
            Some((_, id)) => {
                renderer.update_egui_texture_from_wgpu_texture(
                    &rs.device,
                    view,
                    wgpu::FilterMode::Linear,
                    id,
                );
                id
            }
            None => renderer.register_native_texture(&rs.device, view, wgpu::FilterMode::Linear),
        })
    }

    /// Orbit, pan and zoom (Blender's middle-mouse conventions, and Alt+left drag for
    /// trackpads), and click to select.
    fn navigate(&mut self, ui: &Ui, response: &egui::Response, rect: egui::Rect) {
        let (delta, modifiers, scroll) =
            ui.input(|i| (i.pointer.delta(), i.modifiers, i.smooth_scroll_delta.y));
        let middle = response.dragged_by(PointerButton::Middle);
        let alt_left = response.dragged_by(PointerButton::Primary) && modifiers.alt;
        if (middle || alt_left) && delta != egui::Vec2::ZERO {
            if modifiers.shift {
                self.view = navigation::pan(&self.view, delta.x, delta.y, rect.height());
            } else if modifiers.ctrl && middle {
                self.view = navigation::zoom(&self.view, -delta.y / 20.0);
            } else {
                self.view = navigation::orbit(&self.view, delta.x, delta.y);
            }
        }
        if response.dragged_by(PointerButton::Secondary) {
            self.fly(ui, delta);
        }
        if response.hovered() && scroll != 0.0 {
            self.view = navigation::zoom(&self.view, scroll / 50.0);
        }
        if response.clicked_by(PointerButton::Primary) && !modifiers.alt {
            if let Some(pos) = response.interact_pointer_pos() {
                self.pick(pos, rect);
            }
        }
    }

    /// The Add menu's entries (the menu bar's and Shift+A's); true when one was chosen.
    fn add_menu_items(&mut self, ui: &mut Ui) -> bool {
        use crate::scene::{Light, shapes};
        // New things go to the view's pivot, sized to what the view shows.
        let pivot = self.view.look_at;
        let distance = (self.view.look_at - self.view.position).length().max(1e-3);
        let size = distance * 0.2;
        let mut command = None;
        ui.label(RichText::new("Mesh").weak());
        for (label, mesh) in [
            ("Plane", shapes::quad as fn() -> crate::scene::Mesh),
            ("Cube", shapes::cube),
            ("UV Sphere", || shapes::uv_sphere(32, 16, true)),
        ] {
            if ui.button(label).clicked() {
                let mut mesh = mesh();
                mesh.name = label.to_owned();
                let transform = glam::Affine3A::from_scale_rotation_translation(
                    Vec3::splat(size),
                    glam::Quat::IDENTITY,
                    pivot,
                );
                command = Some(self.document.add_object(mesh, transform));
            }
        }
        ui.separator();
        ui.label(RichText::new("Light").weak());
        // Bright enough to light what is around the pivot: about unit irradiance at half
        // the view's distance.
        let intensity = Vec3::splat((0.5 * distance).powi(2));
        let above = pivot + self.view.up.normalize_or(Vec3::Y) * size * 2.0;
        let lights = [
            (
                "Point",
                Light::Point {
                    position: above,
                    intensity,
                    radius: size * 0.1,
                },
            ),
            (
                "Spot",
                Light::Spot {
                    position: above,
                    direction: Vec3::NEG_Y,
                    intensity,
                    cone_angle: 30.0,
                    blend: 0.15,
                    radius: 0.0,
                },
            ),
            (
                "Sun",
                Light::Distant {
                    direction: Vec3::new(-0.3, -1.0, -0.2).normalize(),
                    irradiance: Vec3::splat(3.0),
                    angular_diameter: 0.53,
                },
            ),
        ];
        for (label, light) in lights {
            if ui.button(label).clicked() {
                command = Some(self.document.add_light(light));
            }
        }
        match command {
            Some(command) => {
                self.apply(command, None);
                true
            }
            None => false,
        }
    }

    /// The Add menu at the pointer (Shift+A over the viewport).
    fn add_menu_popup(&mut self, ctx: &egui::Context) {
        let Some(at) = self.add_menu_at else {
            return;
        };
        let mut chosen = false;
        let area = egui::Area::new(egui::Id::new("add menu"))
            .order(egui::Order::Foreground)
            .fixed_pos(at)
            .show(ctx, |ui| {
                egui::Frame::menu(ui.style()).show(ui, |ui| {
                    ui.label(RichText::new("Add").strong());
                    ui.separator();
                    chosen = self.add_menu_items(ui);
                });
            });
        let clicked_elsewhere = ctx.input(|i| i.pointer.any_pressed())
            && !ctx
                .pointer_interact_pos()
                .is_some_and(|p| area.response.rect.contains(p));
        if chosen || clicked_elsewhere || ctx.input(|i| i.key_pressed(Key::Escape)) {
            self.add_menu_at = None;
        }
    }

    fn projection(&self, rect: egui::Rect) -> ViewProjection {
        ViewProjection {
            camera: self.view,
            rect,
        }
    }

    /// The selected object, if it is a visible object.
    fn selected_object(&self) -> Option<usize> {
        match self.document.selection {
            Some(Selection::Object(i)) if self.document.objects().get(i)?.visible => Some(i),
            _ => None,
        }
    }

    /// Starts, steers, confirms and cancels the modal transform tools (G, R, S with X, Y,
    /// Z constraints; a drag of a gizmo arrow).
    fn transform_tool(&mut self, ui: &Ui, response: &egui::Response, rect: egui::Rect) {
        let pointer = ui.input(|i| i.pointer.hover_pos());
        let typing = ui.ctx().egui_wants_keyboard_input();
        if self.tool.is_none() {
            let Some(object) = self.selected_object() else {
                return;
            };
            let start = self.document.scene().instances[object].transform;
            let mut started = None;
            // A drag that begins on a gizmo handle moves, turns or scales along its axis.
            if response.drag_started_by(PointerButton::Primary) {
                if let Some(press) = ui.input(|i| i.pointer.press_origin()) {
                    let view = self.projection(rect);
                    let axis = match self.gizmo_mode {
                        Mode::Rotate => gizmo::rings(&view, &start, self.orientation)
                            .and_then(|r| gizmo::ring_at(&r, press, 8.0)),
                        _ => gizmo::arrows(&view, &start, self.orientation)
                            .and_then(|a| gizmo::arrow_at(&a, press, 8.0)),
                    };
                    if let Some(axis) = axis {
                        started = Some((self.gizmo_mode, Some(axis), press, true));
                    }
                }
            }
            let over_viewport = pointer.is_some_and(|p| rect.contains(p));
            let idle = !ui.input(|i| i.pointer.any_down() || i.modifiers.any());
            if started.is_none() && over_viewport && idle && !typing {
                let key = ui.input(|i| {
                    [
                        (Key::G, Mode::Move),
                        (Key::R, Mode::Rotate),
                        (Key::S, Mode::Scale),
                    ]
                    .into_iter()
                    .find(|(k, _)| i.key_pressed(*k))
                    .map(|(_, mode)| mode)
                });
                if let (Some(mode), Some(p)) = (key, pointer) {
                    started = Some((mode, None, p, false));
                }
            }
            if let Some((mode, axis, from, dragging)) = started {
                self.tools_started += 1;
                self.tool = Some(TransformTool {
                    mode,
                    object,
                    start,
                    from,
                    constraint: axis.map(|axis| Constraint {
                        axis,
                        orientation: self.orientation,
                    }),
                    gesture: TOOL_GESTURES + self.tools_started,
                    applied: false,
                    dragging,
                });
            }
            return;
        }
        let Some(mut tool) = self.tool else {
            return;
        };
        // X, Y, Z: constrain to the global axis, again for the local one, again for none.
        if !tool.dragging && !typing {
            for (axis, key) in [Key::X, Key::Y, Key::Z].into_iter().enumerate() {
                if ui.input(|i| i.key_pressed(key)) {
                    tool.constraint = match tool.constraint {
                        Some(c) if c.axis == axis && c.orientation == Orientation::Global => {
                            Some(Constraint {
                                axis,
                                orientation: Orientation::Local,
                            })
                        }
                        Some(c) if c.axis == axis => None,
                        _ => Some(Constraint {
                            axis,
                            orientation: Orientation::Global,
                        }),
                    };
                }
            }
        }
        if let Some(to) = pointer {
            let transform = gizmo::modal_transform(
                tool.mode,
                &tool.start,
                tool.constraint,
                &self.projection(rect),
                tool.from,
                to,
            );
            let current = self
                .document
                .scene()
                .instances
                .get(tool.object)
                .map(|i| i.transform);
            if current.is_some_and(|c| c != transform) {
                let command = Command::SetTransform {
                    object: tool.object,
                    transform,
                };
                match self.document.apply(command, Some(tool.gesture)) {
                    Ok(()) => tool.applied = true,
                    // A degenerate transform (zero scale) is skipped, not reported: the
                    // next mouse position will do.
                    Err(e) => tracing::debug!("transform tool: {e}"),
                }
            }
        }
        let (confirm, cancel) = ui.input(|i| {
            let confirm = if tool.dragging {
                !i.pointer.primary_down()
            } else {
                // On release: the click that confirms is over when the tool ends, so it
                // does not also select.
                i.pointer.primary_released() || i.key_pressed(Key::Enter)
            };
            let cancel = i.key_pressed(Key::Escape) || i.pointer.secondary_pressed();
            (confirm, cancel)
        });
        if cancel {
            if tool.applied {
                self.document.undo();
                // The undone drag is not something to redo.
                self.document.forget_redo();
            }
            self.tool = None;
        } else if confirm {
            self.document.end_gesture();
            self.tool = None;
        } else {
            self.tool = Some(tool);
            ui.ctx().request_repaint();
        }
    }

    /// The tool buttons at the viewport's top left (Blender's toolbar): which gizmo the
    /// selection shows.
    fn toolbar(&mut self, ui: &Ui, rect: egui::Rect) {
        egui::Area::new(egui::Id::new("viewport toolbar"))
            .order(egui::Order::Foreground)
            .fixed_pos(rect.left_top() + egui::vec2(8.0, 8.0))
            .show(ui.ctx(), |ui| {
                egui::Frame::menu(ui.style()).show(ui, |ui| {
                    ui.horizontal(|ui| {
                        for (mode, label, tip) in [
                            (Mode::Move, "✚ Move", "Move gizmo (G moves by the mouse)"),
                            (
                                Mode::Rotate,
                                "⟳ Rotate",
                                "Rotate gizmo (R turns by the mouse)",
                            ),
                            (
                                Mode::Scale,
                                "⛶ Scale",
                                "Scale gizmo (S scales by the mouse)",
                            ),
                        ] {
                            ui.selectable_value(&mut self.gizmo_mode, mode, label)
                                .on_hover_text(tip);
                        }
                    });
                });
            });
    }

    /// The active tool's gizmo on the selected object, and a modal tool's axis.
    fn draw_gizmo(&self, painter: &egui::Painter, rect: egui::Rect) {
        let Some(object) = self.selected_object() else {
            return;
        };
        let transform = self.document.scene().instances[object].transform;
        let view = self.projection(rect);
        if let Some(tool) = self.tool {
            if let Some(c) = tool.constraint {
                // The constraint axis through the object, as Blender draws it.
                let origin: Vec3 = transform.translation.into();
                let direction = gizmo::axis_direction(&tool.start, c);
                let far = 1e3 * view.world_per_point(origin);
                if let (Some(a), Some(b)) = (
                    view.project(origin - direction * far),
                    view.project(origin + direction * far),
                ) {
                    painter
                        .line_segment([a, b], egui::Stroke::new(1.0, gizmo::AXIS_COLORS[c.axis]));
                }
            }
            let label = format!(
                "{:?}{}   (X Y Z: axis · click/Enter: confirm · Esc/right click: cancel)",
                tool.mode,
                tool.constraint.map_or(String::new(), |c| format!(
                    " along {} {}",
                    match c.orientation {
                        Orientation::Global => "global",
                        Orientation::Local => "local",
                    },
                    ["X", "Y", "Z"][c.axis]
                ))
            );
            painter.text(
                rect.left_bottom() + egui::vec2(12.0, -12.0),
                egui::Align2::LEFT_BOTTOM,
                label,
                egui::FontId::proportional(14.0),
                Color32::WHITE,
            );
            return;
        }
        if self.gizmo_mode == Mode::Rotate {
            if let Some(rings) = gizmo::rings(&view, &transform, self.orientation) {
                for (axis, ring) in rings.into_iter().enumerate() {
                    let stroke = egui::Stroke::new(2.0, gizmo::AXIS_COLORS[axis]);
                    painter.add(egui::Shape::line(ring, stroke));
                }
            }
            return;
        }
        let Some(arrows) = gizmo::arrows(&view, &transform, self.orientation) else {
            return;
        };
        for (axis, (a, b)) in arrows.iter().enumerate() {
            if (*b - *a).length() < 4.0 {
                continue;
            }
            let color = gizmo::AXIS_COLORS[axis];
            if self.gizmo_mode == Mode::Scale {
                // Scale handles: a line ending in a square, as Blender draws them.
                painter.line_segment([*a, *b], egui::Stroke::new(2.5, color));
                painter.rect_filled(
                    egui::Rect::from_center_size(*b, egui::vec2(9.0, 9.0)),
                    1.0,
                    color,
                );
            } else {
                painter.arrow(*a, *b - *a, egui::Stroke::new(2.5, color));
            }
        }
        painter.circle_filled(arrows[0].0, 3.0, Color32::WHITE);
    }

    /// Fly navigation while the right mouse button is held: the mouse turns the view, W A
    /// S D move it forward, left, back and right, Q and E down and up, Shift is faster.
    fn fly(&mut self, ui: &Ui, delta: egui::Vec2) {
        let (keys, fast, dt) = ui.input(|i| {
            let axis =
                |plus: Key, minus: Key| (i.key_down(plus) as i32 - i.key_down(minus) as i32) as f32;
            (
                Vec3::new(
                    axis(Key::D, Key::A),
                    axis(Key::E, Key::Q),
                    axis(Key::W, Key::S),
                ),
                i.modifiers.shift,
                i.stable_dt.min(0.1),
            )
        });
        let size = navigation::scene_size(self.document.scene()).max(1e-3);
        let speed = size * FLY_SPEED * if fast { 4.0 } else { 1.0 };
        self.view = navigation::fly(&self.view, delta.x, delta.y, keys * speed * dt);
        if keys != Vec3::ZERO {
            ui.ctx().request_repaint();
        }
    }

    /// Selects the object under `pos` (or nothing).
    /// Asks for thumbnails of the document's materials when they may have changed, and
    /// pauses them while the viewport builds a kernel (one device, one queue).
    fn update_thumbnails(&mut self, ctx: &egui::Context) {
        let building = self.viewport_status().is_some_and(|s| s.building.is_some());
        let Some(thumbnails) = self.thumbnails.as_mut() else {
            return;
        };
        thumbnails.poll(ctx);
        // The image revision: moving nodes or renaming changes no thumbnail.
        let key = (
            self.document_serial,
            self.document.image_revision(),
            building,
        );
        if self.thumbnails_key != Some(key) {
            self.thumbnails_key = Some(key);
            let materials = &self.document.scene().materials;
            thumbnails.request((!building).then_some(materials.as_slice()));
        }
    }

    pub fn pick(&mut self, pos: egui::Pos2, rect: egui::Rect) {
        self.document.selection = self.object_at(pos, rect).map(Selection::Object);
    }

    /// The object whose surface is under `pos` in the viewport `rect` (a ray cast through
    /// the picking BVH), if any.
    fn object_at(&mut self, pos: egui::Pos2, rect: egui::Rect) -> Option<usize> {
        let key = self.scene_key();
        let scene = self.render_scene();
        if self.picker.as_ref().is_none_or(|(k, _)| *k != key) {
            match Picker::new(&scene) {
                Ok(p) => self.picker = Some((key, p)),
                Err(e) => {
                    self.error = Some(format!("cannot select: {e}"));
                    return None;
                }
            }
        }
        let (_, picker) = self.picker.as_ref()?;
        let u = (pos.x - rect.left()) / rect.width();
        let v = (pos.y - rect.top()) / rect.height();
        let (origin, dir) = camera_ray(&self.view, u, v, rect.width() / rect.height());
        picker
            .pick(&scene, origin, dir)
            .and_then(|(rendered, _)| self.document.object_of_rendered_instance(rendered))
    }

    /// The selected object's box, drawn over the image in Blender's selection orange.
    fn selection_outline(&self, painter: &egui::Painter, rect: egui::Rect) {
        let Some(Selection::Object(i)) = self.document.selection else {
            return;
        };
        let scene = self.document.scene();
        let Some(instance) = scene.instances.get(i) else {
            return;
        };
        if !self.document.objects()[i].visible {
            return;
        }
        let mesh = &scene.meshes[instance.mesh];
        let (lo, hi) = mesh.positions.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        if lo.x > hi.x {
            return;
        }
        let view = self.projection(rect);
        let project = |p: Vec3| view.project(instance.transform.transform_point3(p));
        let corner = |c: usize| {
            Vec3::new(
                if c & 1 == 0 { lo.x } else { hi.x },
                if c & 2 == 0 { lo.y } else { hi.y },
                if c & 4 == 0 { lo.z } else { hi.z },
            )
        };
        let stroke = egui::Stroke::new(1.5, Color32::from_rgb(255, 160, 40));
        for a in 0..8usize {
            for bit in [1, 2, 4] {
                let b = a | bit;
                if b == a {
                    continue;
                }
                if let (Some(p), Some(q)) = (project(corner(a)), project(corner(b))) {
                    painter.line_segment([p, q], stroke);
                }
            }
        }
    }

    fn dialogs_ui(&mut self, ctx: &egui::Context) {
        if let Some(action) = self.pending.clone() {
            let name = self
                .document
                .path()
                .and_then(|p| p.file_name())
                .map_or("Untitled".to_owned(), |n| n.to_string_lossy().into_owned());
            let mut choice = None;
            egui::Modal::new(egui::Id::new("unsaved changes")).show(ctx, |ui| {
                ui.heading("Unsaved changes");
                ui.label(format!(
                    "Save changes to {name} before {}?",
                    match action {
                        Pending::New => "starting a new scene",
                        Pending::Open(_) => "opening another file",
                        Pending::Close => "closing",
                    }
                ));
                ui.add_space(8.0);
                ui.horizontal(|ui| {
                    if ui.button("Save").clicked() {
                        choice = Some(0);
                    }
                    if ui.button("Don't Save").clicked() {
                        choice = Some(1);
                    }
                    if ui.button("Cancel").clicked() {
                        choice = Some(2);
                    }
                });
            });
            match choice {
                Some(0) => {
                    self.pending = None;
                    if self.save() {
                        self.proceed(action, ctx);
                    }
                }
                Some(1) => {
                    self.pending = None;
                    self.proceed(action, ctx);
                }
                Some(_) => self.pending = None,
                None => {}
            }
        }
        self.recovery_ui(ctx);
        self.render_window_ui(ctx);
        self.add_menu_popup(ctx);
        if let Some(message) = self.error.clone() {
            let mut close = false;
            egui::Modal::new(egui::Id::new("error")).show(ctx, |ui| {
                ui.set_max_width(480.0);
                ui.heading("Error");
                ui.label(message);
                ui.add_space(8.0);
                close = ui.button("OK").clicked();
            });
            if close {
                self.error = None;
            }
        } else if let Some((title, message)) = self.notice.clone() {
            let mut close = false;
            egui::Modal::new(egui::Id::new("notice")).show(ctx, |ui| {
                ui.set_max_width(560.0);
                ui.heading(title);
                egui::ScrollArea::vertical()
                    .max_height(320.0)
                    .show(ui, |ui| ui.label(message));
                ui.add_space(8.0);
                close = ui.button("OK").clicked();
            });
            if close {
                self.notice = None;
            }
        }
    }

    /// The notice shown to the user (title and text), if any.
    pub fn notice(&self) -> Option<(&str, &str)> {
        self.notice.as_ref().map(|(t, m)| (t.as_str(), m.as_str()))
    }

    /// Offers the autosave a crashed session left.
    fn recovery_ui(&mut self, ctx: &egui::Context) {
        let Some(recovery) = &self.recovery else {
            return;
        };
        let age = recovery
            .saved_at
            .elapsed()
            .map_or("a while".to_owned(), |d| {
                format!("{} min", d.as_secs() / 60)
            });
        let from = recovery
            .source
            .as_ref()
            .map_or("an unsaved scene".to_owned(), |p| p.display().to_string());
        let mut choice = None;
        egui::Modal::new(egui::Id::new("recover autosave")).show(ctx, |ui| {
            ui.set_max_width(480.0);
            ui.heading("Recover unsaved work?");
            ui.label(format!(
                "Kiln did not close normally. An autosave of {from} from {age} ago is available."
            ));
            ui.add_space(8.0);
            ui.horizontal(|ui| {
                if ui.button("Recover").clicked() {
                    choice = Some(true);
                }
                if ui.button("Discard").clicked() {
                    choice = Some(false);
                }
            });
        });
        match choice {
            Some(true) => self.recover(),
            Some(false) => {
                if let (Some(store), Some(recovery)) = (&self.session, self.recovery.take()) {
                    store.discard(&recovery);
                }
            }
            None => {}
        }
    }

    /// The render window: the final render's progress or result.
    fn render_window_ui(&mut self, ctx: &egui::Context) {
        if !self.render_window {
            return;
        }
        let Some(state) = self.render_state() else {
            return;
        };
        let mut open = true;
        let mut export = false;
        let mut cancel = false;
        egui::Window::new("Render")
            .open(&mut open)
            .default_size([640.0, 480.0])
            .resizable(true)
            .show(ctx, |ui| match &state {
                RenderState::Preparing => {
                    ui.add(egui::ProgressBar::new(0.0).text("Preparing the kernel…"));
                    cancel = ui.button("Cancel").clicked();
                }
                RenderState::Rendering { fraction, elapsed } => {
                    ui.add(egui::ProgressBar::new(*fraction as f32).text(format!(
                        "{:.0} %  ·  {:.1} s",
                        fraction * 100.0,
                        elapsed.as_secs_f64()
                    )));
                    cancel = ui.button("Cancel").clicked();
                }
                RenderState::Failed(message) => {
                    ui.colored_label(ui.visuals().error_fg_color, message);
                }
                RenderState::Finished(result) => {
                    ui.horizontal(|ui| {
                        ui.label(format!(
                            "{}×{}  ·  {:.1} spp  ·  {:.2} s{}",
                            result.film.width,
                            result.film.height,
                            result.samples_per_pixel,
                            result.elapsed.as_secs_f64(),
                            if result.completed {
                                ""
                            } else {
                                "  ·  cancelled"
                            }
                        ));
                        export = ui.button("Export…").clicked();
                    });
                    let key = Arc::as_ptr(result) as usize;
                    if self.render_texture.as_ref().is_none_or(|(k, _)| *k != key) {
                        let film = &result.film;
                        let pixels: Vec<u8> = film
                            .display
                            .iter()
                            .map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
                            .collect();
                        let image = egui::ColorImage::from_rgba_unmultiplied(
                            [film.width as usize, film.height as usize],
                            &pixels,
                        );
                        let texture =
                            ctx.load_texture("final render", image, egui::TextureOptions::LINEAR);
                        self.render_texture = Some((key, texture));
                    }
                    if let Some((_, texture)) = &self.render_texture {
                        ui.add(egui::Image::new(texture).shrink_to_fit());
                    }
                }
            });
        if cancel {
            if let Some(render) = &self.final_render {
                render.cancel();
            }
        }
        if export {
            self.export_render();
        }
        self.render_window = open;
    }

    fn update_title(&mut self, ctx: &egui::Context) {
        let name = self
            .document
            .path()
            .and_then(|p| p.file_name())
            .map_or("Untitled".to_owned(), |n| n.to_string_lossy().into_owned());
        let dirty = if self.document.is_dirty() { "*" } else { "" };
        let title = format!("Kiln — {name}{dirty}");
        if title != self.title {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.title = title;
        }
    }
}

impl eframe::App for EditorApp {
    fn ui(&mut self, ui: &mut Ui, _frame: &mut eframe::Frame) {
        let now = Instant::now();
        self.frames_logged += 1;
        if now.duration_since(self.log_start).as_secs_f32() >= 2.0 {
            // For measuring (KILN_LOG=kiln=debug): frames drawn, the time the app's own
            // code took per frame (the rest is egui's tessellation and painting), and
            // the viewport's rate.
            let seconds = now.duration_since(self.log_start).as_secs_f32();
            let status = self.viewport_status().unwrap_or_default();
            tracing::debug!(
                fps = self.frames_logged as f32 / seconds,
                app_ms = self.app_time.as_secs_f64() * 1e3 / self.frames_logged as f64,
                samples = status.samples,
                samples_per_second = status.samples_per_second(),
                width = status.size[0],
                height = status.size[1],
                "editor frames"
            );
            self.frames_logged = 0;
            self.app_time = Duration::ZERO;
            self.log_start = now;
        }
        if self.handle_device_loss(ui) {
            return;
        }
        // Before any panel is drawn: the first widget drawn would take Tab's focus.
        self.node_editor.release_tab_focus(ui.ctx());
        self.frame(ui);
        self.app_time += now.elapsed();
    }

    fn on_exit(&mut self) {
        self.exited = true;
        if let Some(report) = &self.report {
            let status = self.viewport_status().unwrap_or_default();
            *report.lock().unwrap_or_else(|e| e.into_inner()) = RunReport {
                samples: status.samples,
                samples_per_second: status.samples_per_second(),
                size: status.size,
                adapter: self.gpu.as_ref().map(|g| g.describe()).unwrap_or_default(),
                error: status.error.or_else(|| {
                    self.gpu
                        .is_none()
                        .then(|| "no GPU device for the viewport".to_owned())
                }),
            };
        }
        // A normal close: the autosave is not needed for recovery.
        if let Some(job) = self.autosave_job.take() {
            let _ = job.join();
        }
        if let Some(store) = &self.session {
            store.clear_autosave();
        }
    }
}

/// A device lost while egui draws a frame (after [`EditorApp::handle_device_loss`]'s check
/// at the frame's start) makes egui's renderer panic: the editor is dropped as that panic
/// unwinds, and writes the document to the recovery autosave and hands over then, as it
/// would have at the next frame. Any other panic also leaves the unsaved document in the
/// recovery autosave, offered at the next start.
impl Drop for EditorApp {
    fn drop(&mut self) {
        if self.device_lost.is_some() || self.exited {
            return;
        }
        if let Some(gpu) = &self.gpu {
            // The workers poll the device too, and the one whose poll finds the lost device
            // reports it: stop them first, so that no report is still on its way.
            drop(self.viewport.take());
            drop(self.thumbnails.take());
            drop(self.node_previews.take());
            drop(self.final_render.take());
            // A destroyed device says so once the work submitted before finishes: wait
            // for it (a lost device's queue does not run forever; under load a viewport
            // dispatch on a software driver can take seconds, so wait up to thirty).
            let deadline = Instant::now() + Duration::from_secs(30);
            while gpu.lost().is_none() && Instant::now() < deadline {
                let idle = gpu.device.poll(wgpu::PollType::Wait {
                    submission_index: None,
                    timeout: Some(Duration::from_millis(500)),
                });
                if !matches!(idle, Err(wgpu::PollError::Timeout)) {
                    break;
                }
            }
            if let Some(reason) = gpu.lost() {
                self.report_device_loss(reason);
                return;
            }
        }
        if !std::thread::panicking() || !self.document.is_dirty() {
            return;
        }
        if let Some(job) = self.autosave_job.take() {
            let _ = job.join();
        }
        if let Some(store) = &self.session
            && let Err(e) = store.autosave(
                self.document.scene(),
                self.document.images(),
                self.document.path(),
            )
        {
            tracing::error!("the autosave after a panic failed: {e}");
        }
    }
}

impl EditorApp {
    /// One frame of the window.
    fn frame(&mut self, ui: &mut Ui) {
        let ctx = ui.ctx().clone();

        if ctx.input(|i| i.viewport().close_requested())
            && self.document.is_dirty()
            && !self.allow_close
        {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.pending = Some(Pending::Close);
        }
        // A gesture lasts while a button is held (a modal tool's, until it ends).
        if !ctx.input(|i| i.pointer.any_down()) && self.tool.is_none() {
            self.document.end_gesture();
        }
        self.shortcuts(&ctx);
        egui::Panel::top("menu").show(ui, |ui| self.menu_bar(ui));
        self.status_bar(ui);
        self.side_panels(ui);
        egui::Panel::bottom("node editor")
            .resizable(true)
            .default_size(340.0)
            .show(ui, |ui| {
                self.update_thumbnails(ui.ctx());
                let thumbnails = self.thumbnails.as_ref();
                let dialogs = self.dialogs.as_mut();
                if let Some(previews) = self.node_previews.as_mut() {
                    previews.poll(ui.ctx());
                }
                let previews = self.node_previews.as_mut();
                for (command, gesture) in
                    self.node_editor
                        .ui(ui, &self.document, thumbnails, previews, dialogs)
                {
                    self.apply(command, gesture);
                }
                match self.node_editor.take_file_request() {
                    Some(MaterialFileRequest::Import) => self.import_materials(),
                    Some(MaterialFileRequest::Export(m)) => self.export_material(m),
                    None => {}
                }
            });
        egui::CentralPanel::no_frame().show(ui, |ui| self.viewport_ui(ui));
        self.dialogs_ui(&ctx);
        self.update_title(&ctx);
        self.autosave();
        if self.last_heap_release.elapsed() >= HEAP_RELEASE_EVERY {
            self.last_heap_release = Instant::now();
            crate::render::release_free_host_memory();
        }
        if self.quit_when_done {
            let status = self.viewport_status();
            let done = status.is_none_or(|s| {
                s.error.is_some() || s.samples >= self.options.viewport.max_samples
            });
            if done && !self.document.is_dirty() {
                self.allow_close = true;
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
        }
        if self.autosave_job.is_some() || self.document.is_dirty() {
            // Come back for the autosave even when nothing else asks for a frame.
            ctx.request_repaint_after(self.autosave_every.min(Duration::from_secs(5)));
        }
    }
}

/// The status bar's note while the viewport's renderers are built, with how long that has
/// taken (a first compile on a software driver can take minutes).
fn preparing_label(taken: Duration) -> String {
    let secs = taken.as_secs();
    format!("· preparing… {}:{:02}", secs / 60, secs % 60)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_preparing_note_counts_minutes_and_seconds() {
        assert_eq!(
            preparing_label(Duration::from_millis(4_900)),
            "· preparing… 0:04"
        );
        assert_eq!(
            preparing_label(Duration::from_secs(545)),
            "· preparing… 9:05"
        );
    }
}
