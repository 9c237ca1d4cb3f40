//! The editor's window: menu bar, outliner and inspector on the right, the live viewport in
//! the middle, a status line at the bottom, as Blender arranges them. The app owns the
//! [`Document`] and applies the commands its panels return; it owns the viewport's view
//! (not part of the document, as in Blender) and turns mouse and keys into navigation.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use egui::{Color32, Key, KeyboardShortcut, Modifiers, PointerButton, RichText, Sense, Ui};
use glam::Vec3;

use crate::film::tonemap::Tonemap;
use crate::plugin::PluginHost;
use crate::render::GpuContext;
use crate::scene::{Camera, Scene};

use super::document::{Command, Document, GestureId, Selection};
use super::files::{FileDialogs, open_document, save_document};
use super::inspector::{InspectorAction, inspector_ui};
use super::navigation;
use super::outliner::{Outliner, OutlinerAction};
use super::pick::{Picker, camera_ray};
use super::viewport::{Target, ViewportRenderer, ViewportStatus};

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
    /// for repaints): tests set a small number.
    pub sample_limit: u32,
}

/// Something the user asked for that waits on the unsaved-changes prompt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pending {
    Open,
    Close,
}

const UNDO: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Z);
const REDO: KeyboardShortcut =
    KeyboardShortcut::new(Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::Z);
const REDO_Y: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Y);
const SAVE: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::S);
const SAVE_AS: KeyboardShortcut =
    KeyboardShortcut::new(Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::S);
const OPEN: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::O);

/// The editor application (an [`eframe::App`]).
pub struct EditorApp {
    document: Document,
    /// Bumped whenever the document is replaced, so the viewport tells documents apart.
    document_serial: u64,
    view: Camera,
    gpu: Option<Arc<GpuContext>>,
    render_state: Option<egui_wgpu::RenderState>,
    viewport: Option<ViewportRenderer>,
    texture: Option<(u64, egui::TextureId)>,
    dialogs: Box<dyn FileDialogs>,
    plugins: PluginHost,
    outliner: Outliner,
    picker: Option<((u64, u64), Picker)>,
    render_scene: Option<((u64, u64), Arc<Scene>)>,
    sample_limit: u32,
    exposure_ev: f32,
    tonemap: Tonemap,
    error: Option<String>,
    pending: Option<Pending>,
    allow_close: bool,
    title: String,
    /// Frames drawn since `log_start`, for the debug log of the frame rate.
    frames_logged: u32,
    log_start: Instant,
    viewport_rect: Option<egui::Rect>,
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
        let viewport = gpu.as_ref().map(|ctx| {
            let egui_ctx = cc.egui_ctx.clone();
            ViewportRenderer::new(Arc::clone(ctx), move || egui_ctx.request_repaint())
        });
        let view = document.scene().camera;
        Self {
            document,
            document_serial: 0,
            view,
            gpu,
            render_state: cc.wgpu_render_state.clone(),
            viewport,
            texture: None,
            dialogs: options.dialogs,
            plugins: options.plugins,
            outliner: Outliner::default(),
            picker: None,
            render_scene: None,
            sample_limit: options.sample_limit.max(1),
            exposure_ev: 0.0,
            tonemap: Tonemap::Agx,
            error,
            pending: None,
            allow_close: false,
            title: String::new(),
            frames_logged: 0,
            log_start: Instant::now(),
            viewport_rect: None,
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

    /// Where the viewport was laid out in the last frame (points).
    pub fn viewport_rect(&self) -> Option<egui::Rect> {
        self.viewport_rect
    }

    /// The node editor's state (the material it shows, where it drew its pins).
    pub fn node_editor(&self) -> &super::node_editor::NodeEditor {
        &self.node_editor
    }

    /// The error shown to the user, if any.
    pub fn error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// Whether the unsaved-changes prompt is showing.
    pub fn is_prompting(&self) -> bool {
        self.pending.is_some()
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

    fn replace_document(&mut self, document: Document) {
        self.document = document;
        self.document_serial += 1;
        self.view = self.document.scene().camera;
        self.picker = None;
        self.render_scene = None;
    }

    // ---- files ----

    fn request(&mut self, action: Pending, ctx: &egui::Context) {
        if self.document.is_dirty() {
            self.pending = Some(action);
        } else {
            self.proceed(action, ctx);
        }
    }

    fn proceed(&mut self, action: Pending, ctx: &egui::Context) {
        match action {
            Pending::Open => {
                if let Some(path) = self.dialogs.open_path() {
                    self.open(path);
                }
            }
            Pending::Close => {
                self.allow_close = true;
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
        }
    }

    /// Opens `path` in place of the document; on failure the document stays and the
    /// error is shown.
    pub fn open(&mut self, path: PathBuf) {
        match open_document(&path, &self.plugins) {
            Ok(document) => self.replace_document(document),
            Err(e) => self.error = Some(e),
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
            Ok(()) => true,
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
            self.request(Pending::Open, ctx);
        }
        if ctx.input(|i| i.key_pressed(Key::Home)) {
            self.view = navigation::frame_all(&self.view, self.document.scene());
        }
        if ctx.input(|i| i.key_pressed(Key::F)) {
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
                    .add(egui::Button::new("Open…").shortcut_text(ui.ctx().format_shortcut(&OPEN)))
                    .clicked()
                {
                    self.request(Pending::Open, ui.ctx());
                }
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
                if ui.button("Quit").clicked() {
                    ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
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
                ui.label("View transform");
                ui.radio_value(&mut self.tonemap, Tonemap::Agx, "AgX");
                ui.radio_value(&mut self.tonemap, Tonemap::None, "Standard");
                ui.horizontal(|ui| {
                    ui.label("Exposure");
                    ui.add(
                        egui::DragValue::new(&mut self.exposure_ev)
                            .speed(0.05)
                            .range(-10.0..=10.0),
                    );
                });
                ui.horizontal(|ui| {
                    ui.label("Samples");
                    ui.add(egui::DragValue::new(&mut self.sample_limit).range(1..=65536));
                });
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
                ui.label(RichText::new("Properties").heading());
                ui.separator();
                for action in inspector_ui(ui, &self.document, &self.view) {
                    match action {
                        InspectorAction::Edit(edit) => self.apply(edit.command, edit.gesture),
                        InspectorAction::LookThroughCamera => {
                            self.view = self.document.scene().camera
                        }
                        InspectorAction::CameraFromView => {
                            let mut camera = self.view;
                            let old = self.document.scene().camera;
                            camera.aperture_radius = old.aperture_radius;
                            camera.focus_distance = (camera.look_at - camera.position).length();
                            self.apply(Command::SetCamera(camera), None);
                        }
                    }
                }
            });
    }

    fn status_bar(&mut self, ui: &mut Ui) {
        egui::Panel::bottom("status").show(ui, |ui| {
            ui.horizontal(|ui| {
                if let Some(status) = self.viewport_status() {
                    let rate = status.samples_per_second();
                    let rate = if rate >= 1e6 {
                        format!("{:.2} M", rate / 1e6)
                    } else {
                        format!("{:.0} k", rate / 1e3)
                    };
                    let t = status.elapsed.as_secs_f32();
                    ui.label(format!(
                        "Samples {}/{}  ·  {rate} samples/s  ·  {:02}:{:05.2}  ·  {}×{}",
                        status.samples,
                        self.sample_limit,
                        (t / 60.0) as u32,
                        t % 60.0,
                        status.size[0],
                        status.size[1],
                    ));
                    if status.building {
                        ui.label(RichText::new("· preparing…").weak());
                    }
                }
                if let Some(gpu) = &self.gpu {
                    ui.separator();
                    ui.label(RichText::new(gpu.describe()).weak());
                }
            });
        });
    }

    fn viewport_ui(&mut self, ui: &mut Ui) {
        let rect = ui.available_rect_before_wrap();
        self.viewport_rect = Some(rect);
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let ppp = ui.ctx().pixels_per_point();
        let size = [
            ((rect.width() * ppp).round() as u32).max(1),
            ((rect.height() * ppp).round() as u32).max(1),
        ];
        self.navigate(ui, &response, rect);

        let scene = self.render_scene();
        let key = self.scene_key();
        let target = Target {
            scene,
            // One number for both parts of the key: documents never reach 2^40 edits.
            scene_revision: (key.0 << 40) | key.1,
            camera: self.view,
            size,
            sample_limit: self.sample_limit,
            exposure_ev: self.exposure_ev,
            tonemap: self.tonemap,
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
        if response.hovered() && scroll != 0.0 {
            self.view = navigation::zoom(&self.view, scroll / 50.0);
        }
        if response.clicked_by(PointerButton::Primary) && !modifiers.alt {
            if let Some(pos) = response.interact_pointer_pos() {
                self.pick(pos, rect);
            }
        }
    }

    /// Selects the object under `pos` (or nothing).
    pub fn pick(&mut self, pos: egui::Pos2, rect: egui::Rect) {
        let key = self.scene_key();
        let scene = self.render_scene();
        if self.picker.as_ref().is_none_or(|(k, _)| *k != key) {
            match Picker::new(&scene) {
                Ok(p) => self.picker = Some((key, p)),
                Err(e) => {
                    self.error = Some(format!("cannot select: {e}"));
                    return;
                }
            }
        }
        let Some((_, picker)) = &self.picker else {
            return;
        };
        let u = (pos.x - rect.left()) / rect.width();
        let v = (pos.y - rect.top()) / rect.height();
        let (origin, dir) = camera_ray(&self.view, u, v, rect.width() / rect.height());
        self.document.selection = picker
            .pick(&scene, origin, dir)
            .and_then(|(rendered, _)| self.document.object_of_rendered_instance(rendered))
            .map(Selection::Object);
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
        let (right, up, forward) = self.view.frame();
        let tan_half = (self.view.fov_y_degrees.to_radians() * 0.5).tan();
        let aspect = rect.width() / rect.height();
        let project = |p: Vec3| -> Option<egui::Pos2> {
            let rel = instance.transform.transform_point3(p) - self.view.position;
            let z = rel.dot(forward);
            if z <= 1e-6 {
                return None;
            }
            let x = rel.dot(right) / z / (tan_half * aspect);
            let y = rel.dot(up) / z / tan_half;
            Some(egui::pos2(
                rect.left() + (x + 1.0) * 0.5 * rect.width(),
                rect.top() + (1.0 - y) * 0.5 * rect.height(),
            ))
        };
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
        if let Some(action) = self.pending {
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
                        Pending::Open => "opening another file",
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
        }
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
        let ctx = ui.ctx().clone();
        let now = Instant::now();
        self.frames_logged += 1;
        if now.duration_since(self.log_start).as_secs_f32() >= 2.0 {
            // For measuring (KILN_LOG=kiln=debug): frames drawn and the viewport's rate.
            let seconds = now.duration_since(self.log_start).as_secs_f32();
            let status = self.viewport_status().unwrap_or_default();
            tracing::debug!(
                fps = self.frames_logged as f32 / seconds,
                samples = status.samples,
                samples_per_second = status.samples_per_second(),
                width = status.size[0],
                height = status.size[1],
                "editor frames"
            );
            self.frames_logged = 0;
            self.log_start = now;
        }

        if ctx.input(|i| i.viewport().close_requested())
            && self.document.is_dirty()
            && !self.allow_close
        {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.pending = Some(Pending::Close);
        }
        // A gesture lasts while a button is held.
        if !ctx.input(|i| i.pointer.any_down()) {
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
                for (command, gesture) in self.node_editor.ui(ui, &self.document) {
                    self.apply(command, gesture);
                }
            });
        egui::CentralPanel::no_frame().show(ui, |ui| self.viewport_ui(ui));
        self.dialogs_ui(&ctx);
        self.update_title(&ctx);
    }
}
