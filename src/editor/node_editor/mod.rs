//! The node editor: a view of one material's graph on an egui-snarl canvas, and the
//! material list above it.
//!
//! The document stays the single source of truth. Each frame the editor compares the
//! document's graph of the shown material with the graph it last drew and, when they
//! differ, rebuilds its [`Snarl`] from it (nodes in id order, so snarl's node ids and
//! with them its selection stay stable while nothing is added or removed). The
//! [`SnarlViewer`] never changes the snarl: a wire drawn, a value dragged or a node added
//! becomes a [`GraphEdit`], which [`NodeEditor::ui`] returns as a document [`Command`];
//! the app applies it, the document's graph changes, and the next frame shows it. Snarl
//! reports no node moves, so after drawing, node positions are compared with the
//! document's and a difference becomes a move command under one gesture (a drag is one
//! undo step).
//!
//! Connections are checked as they are dropped ([`GraphEdit::apply`] on a copy, which
//! applies the compiler's type rules and refuses cycles) and a refused one leaves its
//! reason in the editor's message line.
//!
//! Float fields keep to their input's declared range ([`FloatRange`]); a muted node is
//! drawn dimmed under a red header, a reroute as a small node with no labels. The keys
//! and the selection they act on are in [`keys`]; node groups (entering one shows its
//! view, and edits there are wrapped to reach it) and frames in [`structure`].
//!
//! Each node with outputs has a preview toggle (the eye in its header, or the node menu;
//! a [`GraphEdit::SetPreview`], so it undoes and is saved) that shows its first output as
//! an image under its body, made in the background by [`NodePreviews`]. Ctrl+Shift+click
//! on a node previews it in the viewport instead (Node Wrangler's; again on the same node,
//! its next output): a view state ([`ViewportPreview`]) that the app applies to the scene
//! it hands the viewport, cleared by Ctrl+Shift+click on empty canvas, Esc or the banner
//! over the viewport.

mod keys;
mod ramp;
mod structure;

use std::cell::RefCell;
use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;
use std::rc::Rc;

use egui::emath::TSTransform;
use egui::{Color32, Key, Pos2, RichText, Stroke, Ui};
use egui_snarl::ui::{
    AnyPins, PinInfo, PinPlacement, PinShape, PinWireInfo, SnarlPin, SnarlStyle, SnarlViewer,
    SnarlWidget,
};
use egui_snarl::{InPin, InPinId, NodeId, OutPin, OutPinId, Snarl};

use super::document::{Command, Document, GestureId, Selection};
use super::files::{self, FileDialogs};
use super::graph_edit::{self, GraphEdit, Sockets, sockets_of};
use super::node_previews::NodePreviews;
use super::thumbnails::Thumbnails;
use super::viewport_preview::ViewportPreview;
use crate::material::graph::{
    GROUP, GROUP_INPUT, GROUP_PARAM, REROUTE, REROUTE_INPUT, REROUTE_OUTPUT,
};
use crate::material::nodes::{self, FloatRange, ParamKind};
use crate::material::{Graph, GraphError, Input, Node, Param, SocketType, Value};
use crate::scene::{Material, World};
use graph_edit::GROUP_OUTPUT;

/// The node type a dropped image becomes, and its parameter naming the file.
const IMAGE_TEXTURE: &str = "image_texture";
/// The key the editor's per-graph state (the snarl built, the groups entered) takes for the
/// world's graph, which no material index reaches.
const WORLD_KEY: usize = usize::MAX;
const IMAGE_FILE_PARAM: &str = "file";

/// The preview toggle in a node's header (an eye, as Blender's).
const PREVIEW_ICON: &str = "👁";
/// Side of a node's preview image in points.
const PREVIEW_POINTS: f32 = 96.0;

/// The gesture node drags merge under (one drag, one undo step).
const MOVE_GESTURE: GestureId = 0x6e6f_6465_6d6f_7665;

/// A socket's colour, as Blender draws it: grey floats, purple vectors, yellow colours,
/// green shaders (and a blue for Kiln's two-component vectors).
pub fn socket_color(ty: SocketType) -> Color32 {
    match ty {
        SocketType::Float => Color32::from_rgb(0xa1, 0xa1, 0xa1),
        SocketType::Vec2 => Color32::from_rgb(0x63, 0xa1, 0xc7),
        SocketType::Vector => Color32::from_rgb(0x63, 0x63, 0xc7),
        SocketType::Color => Color32::from_rgb(0xc7, 0xc7, 0x29),
        SocketType::Bsdf | SocketType::Volume => Color32::from_rgb(0x63, 0xc7, 0x63),
    }
}

/// A socket's shape: circles as Blender's, a square for the two-component vector (no
/// Blender type to follow) and a diamond-like triangle nowhere — shaders are circles too.
pub fn socket_shape(ty: SocketType) -> PinShape {
    match ty {
        SocketType::Vec2 => PinShape::Square,
        _ => PinShape::Circle,
    }
}

/// Which side of a node a pin is on.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Side {
    Input,
    Output,
}

/// Where pins were drawn in the last frame, in canvas coordinates, by node, side and
/// socket name.
type PinRects = Rc<RefCell<BTreeMap<(String, Side, String), egui::Rect>>>;

/// A pin that draws as [`PinInfo`] and records where it was drawn.
struct RecordedPin {
    info: PinInfo,
    key: (String, Side, String),
    rects: PinRects,
}

impl SnarlPin for RecordedPin {
    fn draw(
        self,
        snarl_style: &SnarlStyle,
        style: &egui::Style,
        rect: egui::Rect,
        painter: &egui::Painter,
    ) -> PinWireInfo {
        self.rects.borrow_mut().insert(self.key, rect);
        self.info.draw(snarl_style, style, rect, painter)
    }
}

/// The node editor's state: which material it shows, the snarl it draws, and the
/// transient state of its menus.
pub struct NodeEditor {
    material: Option<usize>,
    /// Whether the canvas shows the world's graph instead of a material's (the Shader
    /// Editor's Object / World switch in Blender).
    world: bool,
    /// The selection the material was last taken from.
    followed: Option<Selection>,
    snarl: Snarl<String>,
    /// The groups entered (Tab), outermost first: the canvas shows the last one's
    /// insides ([`graph_edit::group_view`]), the material's graph when empty.
    path: Vec<String>,
    /// The frame whose label and colour are being edited, and the label as typed.
    frame_edit: Option<(String, String)>,
    /// The frames drawn in the last frame.
    frame_shapes: Vec<structure::FrameShape>,
    /// The graph the snarl was built from (of the material, in the group entered, if
    /// any), and where each node was drawn.
    shown: Option<(usize, Option<String>, Graph)>,
    positions: BTreeMap<String, [f32; 2]>,
    search: String,
    /// The Shift+A menu, open at this screen position.
    add_menu: Option<Pos2>,
    message: Option<String>,
    clipboard: Vec<(String, Node)>,
    rename: String,
    to_global: TSTransform,
    pins: PinRects,
    /// Where each node was drawn in the last frame, in canvas coordinates.
    node_rects: BTreeMap<String, egui::Rect>,
    rect: Option<egui::Rect>,
    /// Set when the view should frame all nodes in the next frame (another material
    /// shown, or Home).
    frame_all: bool,
    /// Set by a framing: the next frame frames again, with the sizes the nodes were
    /// drawn at where the first used the layout's estimates (which err wide).
    reframe: bool,
    /// Nodes selected with A, over snarl's own selection ([`keys`]).
    select_all: Option<keys::SelectAll>,
    /// Part of the canvas's egui id; deselect all (Alt+A) moves to the next.
    canvas_generation: u64,
    /// Set when the canvas's id changed: the next frame keeps the view.
    keep_view: bool,
    /// The shown graph's compile: its WGSL size and time, or the error.
    stats: Option<Result<CompileStats, String>>,
    /// The node the viewport shows instead of its material (Ctrl+Shift+click).
    viewport_preview: Option<ViewportPreview>,
    /// The material list's Import Materials… or Export Material…, for the app to answer.
    file_request: Option<MaterialFileRequest>,
}

/// What the material list asks the app to do with material files.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialFileRequest {
    /// Add the materials of a file a material-format plugin reads.
    Import,
    /// Write material `.0` through a material-format plugin.
    Export(usize),
}

/// What compiling a material's graph gave (the material list's statistics).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompileStats {
    /// Bytes of the material's WGSL (its function and helpers).
    pub wgsl_bytes: usize,
    /// The graph → WGSL compile, naga-checked code included in the kernel later.
    pub compile: std::time::Duration,
}

/// Compiles `graph` for the material list's statistics (its error when it does not).
fn compile_stats(graph: &Graph) -> Result<CompileStats, String> {
    let start = std::time::Instant::now();
    crate::material::compile("material", graph, "material")
        .map(|compiled| CompileStats {
            wgsl_bytes: compiled.code.len(),
            compile: start.elapsed(),
        })
        .map_err(|e| e.message)
}

/// The payload of a material dragged from the material list onto an object (the
/// viewport or the outliner assigns it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaterialDrag(pub usize);

impl Default for NodeEditor {
    fn default() -> Self {
        Self {
            material: None,
            world: false,
            followed: None,
            snarl: Snarl::new(),
            path: Vec::new(),
            frame_edit: None,
            frame_shapes: Vec::new(),
            shown: None,
            positions: BTreeMap::new(),
            search: String::new(),
            add_menu: None,
            message: None,
            clipboard: Vec::new(),
            rename: String::new(),
            to_global: TSTransform::IDENTITY,
            pins: PinRects::default(),
            node_rects: BTreeMap::new(),
            rect: None,
            frame_all: true,
            reframe: false,
            select_all: None,
            canvas_generation: 0,
            keep_view: false,
            stats: None,
            viewport_preview: None,
            file_request: None,
        }
    }
}

/// What the viewer collects while the canvas is drawn.
struct Viewer<'a> {
    graph: &'a Graph,
    error: Option<&'a GraphError>,
    edits: Vec<(GraphEdit, Option<GestureId>)>,
    message: Option<String>,
    search: &'a mut String,
    to_global: TSTransform,
    pins: PinRects,
    /// The view to set this frame: the nodes' bounds in canvas coordinates and the
    /// screen rectangle to fit them in.
    frame: Option<(egui::Rect, egui::Rect)>,
    /// The view to keep this frame (the canvas has a new id, and snarl a new view).
    view: Option<TSTransform>,
    /// Nodes selected by the select-all layer and not by snarl: drawn as selected here.
    layer_selected: BTreeSet<String>,
    selection_stroke: Stroke,
    /// The file parameter (node, parameter) whose "Open…" was clicked: the editor asks
    /// its dialogs for a file after drawing.
    pick_file: Option<(String, String)>,
    /// Where each node was drawn, in canvas coordinates.
    node_rects: BTreeMap<String, egui::Rect>,
    /// The node previews (none without a device, or inside a group), and the shown
    /// material's index.
    previews: Option<&'a NodePreviews>,
    material: usize,
    /// The frames to draw behind the nodes.
    frames: Vec<structure::FrameShape>,
    /// A group node whose "Enter group" was clicked.
    enter: Option<String>,
}

impl NodeEditor {
    /// The material shown, by index into the scene's materials.
    pub fn material(&self) -> Option<usize> {
        self.material
    }

    /// Whether the canvas shows the world's graph.
    pub fn showing_world(&self) -> bool {
        self.world
    }

    /// The last refused edit's reason, shown above the canvas.
    /// The shown graph's compile statistics, or its compile error.
    pub fn stats(&self) -> Option<&Result<CompileStats, String>> {
        self.stats.as_ref()
    }

    pub fn message(&self) -> Option<&str> {
        self.message.as_deref()
    }

    /// The node the viewport previews instead of its material, if any (Ctrl+Shift+click).
    pub fn viewport_preview(&self) -> Option<&ViewportPreview> {
        self.viewport_preview.as_ref()
    }

    /// Shows the material in the viewport again.
    pub fn clear_viewport_preview(&mut self) {
        self.viewport_preview = None;
    }

    /// Where the pin of `socket` on node `node` (an input when `input`) was drawn in the
    /// last frame, in screen points.
    pub fn pin_position(&self, node: &str, socket: &str, input: bool) -> Option<Pos2> {
        Some(self.pin_rect(node, socket, input)?.center())
    }

    /// The rectangle the pin of `socket` on node `node` (an input when `input`) took in
    /// the last frame, in screen points.
    pub fn pin_rect(&self, node: &str, socket: &str, input: bool) -> Option<egui::Rect> {
        let side = if input { Side::Input } else { Side::Output };
        let rects = self.pins.borrow();
        let rect = rects.get(&(node.to_owned(), side, socket.to_owned()))?;
        Some(self.to_global * *rect)
    }

    /// The rectangle node `node` took in the last frame (its frame), in screen points.
    pub fn node_rect(&self, node: &str) -> Option<egui::Rect> {
        Some(self.to_global * *self.node_rects.get(node)?)
    }

    /// Where node `node` is drawn, in screen points (its top-left corner).
    pub fn node_position(&self, node: &str) -> Option<Pos2> {
        let p = self.positions.get(node)?;
        Some(self.to_global * Pos2::new(p[0], p[1]))
    }

    /// A point of the canvas in screen points, as the last frame drew it. (Widgets on the
    /// canvas report their places to accessibility in canvas coordinates.)
    pub fn canvas_to_screen(&self, canvas: Pos2) -> Pos2 {
        self.to_global * canvas
    }

    /// The groups entered, outermost first (empty: the material's graph is shown).
    pub fn group_path(&self) -> &[String] {
        &self.path
    }

    /// The label bar of frame `id` in the last frame, in screen points.
    pub fn frame_bar(&self, id: &str) -> Option<egui::Rect> {
        Some(self.to_global * structure::bar_of(&self.frame_shapes, id)?)
    }

    /// The rectangle the canvas took in the last frame.
    pub fn canvas_rect(&self) -> Option<egui::Rect> {
        self.rect
    }

    /// What the material list's Import Materials… or Export Material… asked for since the last call: the
    /// app answers it, with its dialogs and plugins.
    pub fn take_file_request(&mut self) -> Option<MaterialFileRequest> {
        self.file_request.take()
    }

    /// Shows material `material`'s graph (what picking it in the list does).
    pub fn show_material(&mut self, material: usize) {
        self.world = false;
        self.material = Some(material);
    }

    /// Draws the material list (with `thumbnails`, when the app renders them) and the
    /// shown material's graph (with its nodes' `previews`, when the app makes them);
    /// returns the commands the user's edits make, each with its gesture. `dialogs`
    /// answers an image parameter's "Open…".
    pub fn ui(
        &mut self,
        ui: &mut Ui,
        document: &Document,
        thumbnails: Option<&Thumbnails>,
        previews: Option<&mut NodePreviews>,
        dialogs: &mut dyn FileDialogs,
    ) -> Vec<(Command, Option<GestureId>)> {
        let mut commands = Vec::new();
        self.follow_selection(document);
        self.material_bar(ui, document, thumbnails, &mut commands);
        let world = self.world;
        let (material, top) = if world {
            let Some(top) = document.world_graph() else {
                ui.horizontal(|ui| {
                    ui.label("The scene has no world graph.");
                    if ui
                        .button("New World")
                        .on_hover_text("A world of the environment's colour, as a graph")
                        .clicked()
                    {
                        let world = World::constant(document.scene().environment);
                        commands.push((Command::SetWorld(Some(Box::new(world))), None));
                    }
                });
                // Keep the panel's height for the canvas that follows.
                ui.allocate_space(ui.available_size());
                return commands;
            };
            (WORLD_KEY, top)
        } else {
            let Some(material) = self.material else {
                ui.label("No material.");
                ui.allocate_space(ui.available_size());
                return commands;
            };
            // None for the one frame between picking a new material and the document
            // holding it. A frame that leaves the panel empty would shrink it for good.
            let Some(top) = document.material_graph(material) else {
                ui.allocate_space(ui.available_size());
                return commands;
            };
            (material, top)
        };
        let command = |edit: GraphEdit| match world {
            true => Command::EditWorldGraph(edit),
            false => Command::EditGraph { material, edit },
        };
        // Inside a group, the canvas shows and edits its view; edits are wrapped to reach
        // the group ([`structure::scoped`]), the one shown this frame even when a key
        // enters or leaves one after drawing.
        self.follow_path(material, &top);
        let name = match world {
            true => "World",
            false => document.scene().materials[material].name.as_str(),
        };
        for (edit, gesture) in self.scope_bar(ui, name, &top) {
            commands.push((command(edit), gesture));
        }
        let scope = self.path.last().cloned();
        let view = (scope.as_ref()).and_then(|g| graph_edit::group_view(&top, g).ok());
        let graph = view.as_ref().unwrap_or(&top);
        let error = match world {
            true => document.world_error(),
            false => document.graph_error(material),
        };
        if let Some(e) = error {
            ui.label(
                RichText::new(format!(
                    "⚠ {} (the viewport shows the last valid {})",
                    e.message,
                    if world { "world" } else { "material" }
                ))
                .color(Color32::LIGHT_RED),
            );
        }
        if let Some(m) = &self.message {
            ui.label(RichText::new(m).color(Color32::from_rgb(255, 170, 60)));
        }
        self.sync(material, graph, &top);
        // Previews are of the material's own nodes (a group's nodes compute per
        // instance): none inside a group.
        // The world's nodes have no previews: a preview shades a sphere with a material.
        let previews = previews.filter(|_| scope.is_none() && !world).map(|p| {
            if let Some(source) = document.scene().materials.get(material) {
                p.want(material, &top, source);
            }
            &*p
        });
        // A previewed node that is gone (deleted, undone) is previewed no more.
        if self
            .viewport_preview
            .as_ref()
            .is_some_and(|p| p.material == material && !top.nodes.contains_key(&p.node))
        {
            self.viewport_preview = None;
        }
        self.refresh_selection(ui.ctx());
        let layer_selected = self.selected_by_layer(ui.ctx());
        let view = std::mem::take(&mut self.keep_view).then_some(self.to_global);
        let canvas_id = self.canvas_id();

        let frames = self.frame_shapes(graph);
        let mut viewer = Viewer {
            graph,
            error,
            edits: Vec::new(),
            message: None,
            search: &mut self.search,
            to_global: self.to_global,
            pins: Rc::clone(&self.pins),
            frame: None,
            view,
            layer_selected,
            selection_stroke: Stroke::new(2.0, ui.visuals().selection.stroke.color),
            pick_file: None,
            node_rects: BTreeMap::new(),
            previews,
            material,
            frames,
            enter: None,
        };
        self.pins.borrow_mut().clear();
        // The canvas fills what is left of the panel (snarl's response covers the whole
        // plane it pans over, so it cannot tell where the canvas is).
        let canvas = ui.available_rect_before_wrap();
        // Home on the graph drawn last frame frames it at once; another graph's nodes are
        // not drawn yet, so it is framed from their estimated sizes, then again.
        let reframe = std::mem::take(&mut self.reframe);
        let frame_all = std::mem::take(&mut self.frame_all);
        if frame_all || reframe {
            viewer.frame = Some((bounds(graph, &self.positions, &self.node_rects), canvas));
            self.reframe = frame_all;
        }
        SnarlWidget::new()
            .id(canvas_id)
            .style(style())
            .show(&mut self.snarl, &mut viewer, ui);
        self.rect = Some(canvas);
        self.to_global = viewer.to_global;
        self.node_rects = std::mem::take(&mut viewer.node_rects);
        let frames = std::mem::take(&mut viewer.frames);
        let enter = viewer.enter.take();
        let mut edits = std::mem::take(&mut viewer.edits);
        if let Some(m) = viewer.message.take() {
            self.message = Some(m);
        } else if !edits.is_empty() {
            self.message = None;
        }

        if let Some((node, param)) = viewer.pick_file.take() {
            if let Some(path) = dialogs.image_path() {
                edits.push((
                    GraphEdit::SetParam {
                        node,
                        param,
                        value: Some(Param::Text(path.to_string_lossy().into_owned())),
                    },
                    None,
                ));
            }
        }
        if let Some(moves) = self.moves(graph) {
            edits.push((moves, Some(MOVE_GESTURE)));
        }
        if scope.is_none() && !world {
            self.viewport_preview_keys(ui, material, graph, canvas);
        }
        edits.extend(self.frame_bars(ui, graph, &frames, canvas));
        self.frame_shapes = frames;
        if let Some(group) = enter {
            self.enter_group(group);
        }
        // The pointer over the canvas, whichever of snarl's layers it is over (its nodes
        // sit on a layer of their own).
        let hovered = ui
            .ctx()
            .pointer_hover_pos()
            .is_some_and(|p| canvas.contains(p));
        edits.extend(
            self.keyboard(ui, graph, hovered)
                .into_iter()
                .map(|e| (e, None)),
        );
        edits.extend(
            self.add_menu_popup(ui, graph)
                .into_iter()
                .map(|e| (e, None)),
        );
        // Images dropped over the canvas become image-texture nodes there. Some platforms
        // report no pointer while a file is dragged in from outside: a drop with no
        // pointer known lands in the canvas's middle.
        let drop_at = match ui.ctx().pointer_hover_pos() {
            Some(p) => canvas.contains(p).then_some(p),
            None => Some(canvas.center()),
        };
        if let Some(at) = drop_at {
            let dropped: Vec<PathBuf> = ui.ctx().input(|i| {
                i.raw
                    .dropped_files
                    .iter()
                    .map(|f| f.path().to_owned())
                    .collect()
            });
            if let Some(edit) = self.dropped_images(graph, &dropped, at) {
                edits.push((edit, None));
            }
        }
        // A graph laid out automatically (a material of fixed parameters, a file without
        // positions) is laid out again when its nodes or links change, which would move
        // every node the user sees: its first edit also saves where they are drawn (a
        // move saves them itself, `move_edit`).
        if let Some((edit, _)) = edits.iter_mut().find(|(e, _)| !e.only_moves()) {
            let drawn = graph_edit::fix_layout(graph);
            if !drawn.is_empty() {
                let add = std::mem::replace(edit, GraphEdit::Batch(Vec::new()));
                *edit = GraphEdit::Batch(vec![GraphEdit::MoveNodes(drawn), add]);
            }
        }
        commands.extend(
            edits.into_iter().map(|(edit, gesture)| {
                (command(structure::scoped(scope.as_deref(), edit)), gesture)
            }),
        );
        commands
    }

    /// Ctrl+Shift+click on a node previews it in the viewport (again on the same node: its
    /// next output), on empty canvas clears the preview, as does Esc while no text field
    /// takes keys.
    fn viewport_preview_keys(
        &mut self,
        ui: &Ui,
        material: usize,
        graph: &Graph,
        canvas: egui::Rect,
    ) {
        let (clicked, escape) = ui.input(|i| {
            let clicked = i.pointer.primary_clicked()
                && i.modifiers.command
                && i.modifiers.shift
                && !i.modifiers.alt;
            let at = i.pointer.interact_pos().filter(|p| canvas.contains(*p));
            (
                clicked.then_some(at).flatten(),
                i.key_pressed(Key::Escape) && i.modifiers.is_none(),
            )
        });
        if escape && self.viewport_preview.is_some() && !ui.ctx().egui_wants_keyboard_input() {
            self.viewport_preview = None;
        }
        let Some(at) = clicked else { return };
        let hit = self
            .node_rects
            .iter()
            .find(|(_, rect)| (self.to_global * **rect).contains(at))
            .map(|(id, _)| id.clone());
        let Some(node) = hit else {
            self.viewport_preview = None;
            return;
        };
        let outputs = graph
            .nodes
            .get(&node)
            .filter(|n| n.kind != REROUTE)
            .and_then(|n| sockets_of(graph, n).ok())
            .map_or(0, |s| s.outputs.len());
        if outputs == 0 {
            return;
        }
        let output = match &self.viewport_preview {
            Some(p) if p.material == material && p.node == node => (p.output + 1) % outputs,
            _ => 0,
        };
        self.viewport_preview = Some(ViewportPreview {
            material,
            node,
            output,
        });
    }

    /// Shows the selected object's material when the selection changes to an object.
    fn follow_selection(&mut self, document: &Document) {
        let materials = document.scene().materials.len();
        if document.selection != self.followed {
            self.followed = document.selection;
            if let Some(Selection::Object(i)) = document.selection {
                if let Some(instance) = document.scene().instances.get(i) {
                    self.material = Some(instance.material);
                }
            }
        }
        if self.material.is_none_or(|m| m >= materials) {
            self.material = (materials > 0).then_some(0);
        }
    }

    /// The material list: pick the material shown, create, duplicate, rename, delete, and
    /// assign it to the selected object.
    fn material_bar(
        &mut self,
        ui: &mut Ui,
        document: &Document,
        thumbnails: Option<&Thumbnails>,
        commands: &mut Vec<(Command, Option<GestureId>)>,
    ) {
        let materials = &document.scene().materials;
        let thumbnail = |i: usize, side: f32| {
            thumbnails
                .and_then(|t| t.texture(i))
                .map(|texture| egui::Image::new((texture.id(), egui::vec2(side, side))))
        };
        // Wrapped: in a narrow window the bar takes a second row rather than running under
        // the side panel.
        ui.horizontal_wrapped(|ui| {
            ui.selectable_value(&mut self.world, false, "Object")
                .on_hover_text("The node graph of the selected object's material");
            ui.selectable_value(&mut self.world, true, "World")
                .on_hover_text(
                    "The world's node graph: the light from every direction no object covers",
                );
            if self.world {
                return;
            }
            ui.separator();
            let label = ui.label("Material");
            let current = self
                .material
                .and_then(|m| materials.get(m))
                .map_or("—".to_owned(), |m| m.name.clone());
            egui::ComboBox::from_id_salt("node editor material")
                .selected_text(current)
                .show_ui(ui, |ui| {
                    for (i, m) in materials.iter().enumerate() {
                        let clicked = ui
                            .horizontal(|ui| {
                                if let Some(image) = thumbnail(i, 20.0) {
                                    ui.add(image);
                                }
                                ui.selectable_label(self.material == Some(i), m.name.as_str())
                                    .clicked()
                            })
                            .inner;
                        if clicked {
                            self.material = Some(i);
                        }
                    }
                })
                .response
                .labelled_by(label.id);
            if ui
                .button("Import Materials…")
                .on_hover_text("Add the materials of a material file (MaterialX .mtlx, …)")
                .clicked()
            {
                self.file_request = Some(MaterialFileRequest::Import);
            }
            if ui.button("New").clicked() {
                let name = document.unique_material_name("Material");
                commands.push((
                    Command::AddMaterial {
                        index: materials.len(),
                        material: Box::new(Material::with(&name, Default::default())),
                        pending: None,
                    },
                    None,
                ));
                self.material = Some(materials.len());
            }
            let Some(m) = self.material.filter(|&m| m < materials.len()) else {
                return;
            };
            ui.dnd_drag_source(egui::Id::new("material drag"), MaterialDrag(m), |ui| {
                // The material's thumbnail is its handle, as in Blender's asset lists.
                if let Some(image) = thumbnail(m, 22.0) {
                    ui.add(image.sense(egui::Sense::hover()));
                }
                ui.add(egui::Label::new("✚ Drag").selectable(false))
            })
            .response
            .on_hover_text("Drag onto an object in the viewport or the outliner to assign");
            if ui.button("Duplicate").clicked() {
                let mut copy = materials[m].clone();
                copy.name = document.unique_material_name(&copy.name);
                commands.push((
                    Command::AddMaterial {
                        index: materials.len(),
                        material: Box::new(copy),
                        pending: None,
                    },
                    None,
                ));
                self.material = Some(materials.len());
            }
            if ui.button("Delete").clicked() {
                commands.push((Command::RemoveMaterial { index: m }, None));
            }
            if ui
                .button("Export Material…")
                .on_hover_text("Write this material as a material file (MaterialX .mtlx, …)")
                .clicked()
            {
                self.file_request = Some(MaterialFileRequest::Export(m));
            }
            if let Some(Selection::Object(object)) = document.selection {
                let assigned = document
                    .scene()
                    .instances
                    .get(object)
                    .is_some_and(|i| i.material == m);
                if ui
                    .add_enabled(!assigned, egui::Button::new("Assign"))
                    .on_hover_text(format!(
                        "Give \"{}\" this material",
                        document.name(Selection::Object(object))
                    ))
                    .clicked()
                {
                    commands.push((
                        Command::AssignMaterial {
                            object,
                            material: m,
                        },
                        None,
                    ));
                }
            }
            // The label and its field wrap together.
            let edit = ui
                .horizontal(|ui| {
                    let label = ui.label("Name");
                    ui.add(egui::TextEdit::singleline(&mut self.rename).desired_width(140.0))
                        .labelled_by(label.id)
                })
                .inner;
            if !edit.has_focus() && !edit.lost_focus() {
                self.rename = materials[m].name.clone();
            }
            if edit.lost_focus() && self.rename != materials[m].name {
                commands.push((
                    Command::RenameMaterial {
                        material: m,
                        name: self.rename.clone(),
                    },
                    None,
                ));
            }
            match &self.stats {
                // A material of fixed parameters runs no generated code (until edited).
                _ if materials[m].graph.is_none() => {
                    ui.weak("fixed parameters")
                        .on_hover_text("No generated code: its first graph edit makes one");
                }
                Some(Ok(stats)) => {
                    // The time in the tooltip: a number that changes each frame would
                    // make the bar flicker (and snapshots differ).
                    ui.weak(format!("WGSL {:.1} KiB", stats.wgsl_bytes as f64 / 1024.0))
                        .on_hover_text(format!(
                            "The material's generated code; the graph compiled in {:.1} ms (the \
                         kernel it joins compiles in the background)",
                            stats.compile.as_secs_f64() * 1e3
                        ));
                }
                Some(Err(_)) => {
                    ui.weak("does not compile");
                }
                None => {}
            }
        });
    }

    /// Rebuilds the snarl when the document's graph (`graph`, the view of the group
    /// entered if any, of the material's graph `top`) differs from the one drawn.
    fn sync(&mut self, material: usize, graph: &Graph, top: &Graph) {
        let scope = self.path.last().cloned();
        let same_place = |m: &usize, s: &Option<String>| *m == material && *s == scope;
        if (self.shown.as_ref()).is_some_and(|(m, s, g)| same_place(m, s) && g == graph) {
            return;
        }
        let moved_only = (self.shown.as_ref())
            .is_some_and(|(m, s, g)| same_place(m, s) && g.same_but_layout(graph));
        if !moved_only {
            self.stats = Some(compile_stats(top));
        }
        let laid = graph_edit::layout(graph);
        let mut snarl = Snarl::new();
        let mut ids = BTreeMap::new();
        for id in graph.nodes.keys() {
            let p = laid.get(id).copied().unwrap_or([0.0, 0.0]);
            ids.insert(
                id.clone(),
                snarl.insert_node(Pos2::new(p[0], p[1]), id.clone()),
            );
        }
        for (id, node) in &graph.nodes {
            let Ok(to) = sockets_of(graph, node) else {
                continue;
            };
            for (name, input) in &node.inputs {
                let Input::Link(link) = input else { continue };
                let (Some(&from_node), Some(input)) = (
                    ids.get(&link.node),
                    to.inputs.iter().position(|(n, _)| n == name),
                ) else {
                    continue;
                };
                let Some(output) = graph
                    .nodes
                    .get(&link.node)
                    .and_then(|n| sockets_of(graph, n).ok())
                    .and_then(|s| s.outputs.iter().position(|(n, _)| *n == link.socket))
                else {
                    continue;
                };
                snarl.connect(
                    OutPinId {
                        node: from_node,
                        output,
                    },
                    InPinId {
                        node: ids[id],
                        input,
                    },
                );
            }
        }
        if (self.shown.as_ref()).is_none_or(|(m, s, _)| !same_place(m, s)) {
            self.frame_all = true;
            // Rectangles of the nodes of another graph, some of the same ids.
            self.node_rects.clear();
        }
        self.snarl = snarl;
        self.positions = laid;
        self.shown = Some((material, scope, graph.clone()));
    }

    /// The move command for nodes the user dragged this frame, if any. The first move of
    /// a graph without saved positions also saves the layout of every other node, so the
    /// file keeps what the user saw.
    fn moves(&mut self, graph: &Graph) -> Option<GraphEdit> {
        self.move_with_layer();
        let mut moved = Vec::new();
        for (_, pos, id) in self.snarl.nodes_pos_ids() {
            let now = [pos.x, pos.y];
            if self.positions.get(id).is_some_and(|p| *p != now) {
                moved.push((id.clone(), Some(now)));
            }
        }
        self.move_edit(graph, moved)
    }

    /// The edit moving nodes as `moved` says (with the layout of all others saved, as
    /// [`NodeEditor::moves`] does), or none when nothing moves.
    fn move_edit(
        &mut self,
        graph: &Graph,
        moved: Vec<(String, Option<[f32; 2]>)>,
    ) -> Option<GraphEdit> {
        if moved.is_empty() {
            return None;
        }
        for (id, p) in moved.iter().filter_map(|(id, p)| p.map(|p| (id, p))) {
            self.positions.insert(id.clone(), p);
        }
        let mut all = graph_edit::fix_layout(graph);
        all.retain(|(id, _)| !moved.iter().any(|(m, _)| m == id));
        all.extend(moved);
        Some(GraphEdit::MoveNodes(all))
    }

    /// Snarl moves the nodes it has selected together; a node dragged while select all
    /// holds it takes the other nodes that holds along.
    fn move_with_layer(&mut self) {
        let Some(all) = &self.select_all else { return };
        let dragged = self.snarl.nodes_pos_ids().find_map(|(_, pos, id)| {
            let was = self.positions.get(id)?;
            let delta = pos - Pos2::new(was[0], was[1]);
            (all.ids.contains(id) && delta != egui::Vec2::ZERO).then_some(delta)
        });
        let Some(delta) = dragged else { return };
        for node in self.snarl.nodes_info_mut() {
            let Some(was) = self.positions.get(node.value.as_str()) else {
                continue;
            };
            if all.ids.contains(node.value.as_str()) && node.pos == Pos2::new(was[0], was[1]) {
                node.pos += delta;
            }
        }
    }

    /// The edit that adds an image-texture node reading each image of `files` (dropped on
    /// the canvas at screen point `at`; the others are not the node editor's), one below
    /// the other, as one undo step. An image that does not load shows its error on its
    /// node, as a missing image does.
    pub fn dropped_images(&self, graph: &Graph, files: &[PathBuf], at: Pos2) -> Option<GraphEdit> {
        let mut scratch = graph.clone();
        let mut adds = Vec::new();
        let mut pos = self.to_global.inverse() * at;
        for file in files.iter().filter(|f| files::is_image(f)) {
            let GraphEdit::AddNode { id, mut node } = new_node(&scratch, IMAGE_TEXTURE, pos) else {
                continue;
            };
            node.params.insert(
                IMAGE_FILE_PARAM.to_owned(),
                Param::Text(file.to_string_lossy().into_owned()),
            );
            pos.y += graph_edit::estimated_height(&scratch, &node) + 20.0;
            let add = GraphEdit::AddNode { id, node };
            // Applied to a copy so that the next node gets a fresh id of its own.
            if add.clone().apply(&mut scratch).is_ok() {
                adds.push(add);
            }
        }
        (!adds.is_empty()).then_some(GraphEdit::Batch(adds))
    }

    /// The add menu opened with Shift+A, as a popup at the pointer.
    fn add_menu_popup(&mut self, ui: &Ui, graph: &Graph) -> Vec<GraphEdit> {
        let Some(at) = self.add_menu else {
            return Vec::new();
        };
        let ctx = ui.ctx().clone();
        let graph_pos = self.to_global.inverse() * at;
        let mut chosen = None;
        let area = egui::Area::new(egui::Id::new("kiln add node menu"))
            .fixed_pos(at)
            .order(egui::Order::Foreground)
            .show(&ctx, |ui| {
                egui::Frame::popup(ui.style()).show(ui, |ui| {
                    chosen = add_menu(ui, &mut self.search, None);
                })
            });
        let clicked_outside = ctx.input(|i| i.pointer.any_pressed())
            && !ctx
                .pointer_interact_pos()
                .is_some_and(|p| area.response.rect.contains(p));
        if chosen.is_some() || clicked_outside || ctx.input(|i| i.key_pressed(Key::Escape)) {
            self.add_menu = None;
        }
        chosen
            .map(|kind| vec![new_node(graph, kind, graph_pos)])
            .unwrap_or_default()
    }
}

/// The bounds of the nodes at `positions` in canvas coordinates: each node as large as it
/// was `drawn`, else as the layout estimates it.
fn bounds(
    graph: &Graph,
    positions: &BTreeMap<String, [f32; 2]>,
    drawn: &BTreeMap<String, egui::Rect>,
) -> egui::Rect {
    let mut bounds = egui::Rect::NOTHING;
    for (id, p) in positions {
        let Some(node) = graph.nodes.get(id) else {
            continue;
        };
        let min = Pos2::new(p[0], p[1]);
        let size = drawn.get(id).map_or_else(
            || {
                egui::vec2(
                    graph_edit::estimated_width(graph, node),
                    graph_edit::estimated_height(graph, node),
                )
            },
            |r| r.size(),
        );
        bounds = bounds.union(egui::Rect::from_min_size(min, size));
    }
    if bounds.is_finite() {
        // Room for the frames around nodes, and their label bars above.
        if graph.frames.is_empty() {
            bounds
        } else {
            structure::with_frame_room(bounds)
        }
    } else {
        egui::Rect::from_min_size(Pos2::ZERO, egui::vec2(400.0, 200.0))
    }
}

/// The view that shows `bounds` in `canvas`, at most at scale 1: whole when it fits at a
/// readable scale, else from its top, centred across. A graph reads from left to right,
/// inputs to the output, so its whole width is shown down to scale 0.4 (Blender's Home
/// zooms out without a limit); its height only down to 0.8, where text stays legible, and
/// a taller graph is scrolled.
fn framing(bounds: egui::Rect, canvas: egui::Rect) -> TSTransform {
    let margin = 24.0;
    let room = (canvas.size() - egui::vec2(2.0 * margin, 2.0 * margin)).max(egui::vec2(1.0, 1.0));
    let fit_width = room.x / bounds.width();
    let fit_height = room.y / bounds.height();
    let scale = fit_width.min(fit_height.max(0.8)).clamp(0.4, 1.0);
    let x = canvas.center().x - bounds.center().x * scale;
    let y = if bounds.height() * scale <= room.y {
        canvas.center().y - bounds.center().y * scale
    } else {
        canvas.top() + margin - bounds.top() * scale
    };
    TSTransform::new(egui::vec2(x, y), scale)
}

/// Snarl's style for the canvas. Pins sit on the node's edge, as Blender's: snarl 0.12
/// reserves the room of a pin drawn inside the node wrongly on the output side (its
/// right-to-left row grows past the node's edge, and each output row starts further right
/// than the last, so that output labels run under their pins and out of the node, clipped
/// away). A pin on the edge needs no room reserved inside.
fn style() -> SnarlStyle {
    SnarlStyle {
        collapsible: Some(true),
        pin_placement: Some(PinPlacement::Edge),
        ..SnarlStyle::new()
    }
}

/// The width an error message on a node wraps at.
const ERROR_WIDTH: f32 = 240.0;

/// The edit adding a node of type `kind` at canvas position `pos`.
fn new_node(graph: &Graph, kind: &str, pos: Pos2) -> GraphEdit {
    let mut node = Node::new(kind);
    node.position = Some([pos.x, pos.y]);
    GraphEdit::AddNode {
        id: graph_edit::fresh_id(graph, kind),
        node,
    }
}

/// The add menu's "Layout" entries (type, label, doc): nodes the compiler resolves away
/// rather than library nodes.
const LAYOUT_NODES: &[(&str, &str, &str)] = &[(
    REROUTE,
    "Reroute",
    "Passes one wire on, to route wires; it carries the type of what is wired into it",
)];

/// The add-node menu: a search field, then the node library grouped by category (or,
/// while searching, the matching nodes, the first highlighted: Enter picks it, as in
/// Blender's search). With `only`, lists only node types that have a socket that can take
/// the given socket type (an input when the flag is true). Returns the chosen node type.
fn add_menu(
    ui: &mut Ui,
    search: &mut String,
    only: Option<(SocketType, bool)>,
) -> Option<&'static str> {
    let label = ui.label("Search");
    let field = ui
        .add(egui::TextEdit::singleline(search).hint_text("node name…"))
        .labelled_by(label.id);
    if !field.has_focus() && search.is_empty() {
        field.request_focus();
    }
    ui.separator();
    let fits = |def: &nodes::NodeDef| match only {
        None => true,
        Some((ty, true)) => def.inputs.iter().any(|s| ty.converts_to(s.ty).is_some()),
        Some((ty, false)) => def.outputs.iter().any(|s| s.ty.converts_to(ty).is_some()),
    };
    let query = search.trim().to_lowercase();
    let mut chosen = None;
    if query.is_empty() {
        let mut categories: Vec<&str> = Vec::new();
        for def in nodes::library() {
            if !categories.contains(&def.category) {
                categories.push(def.category);
            }
        }
        for category in categories {
            let defs: Vec<_> = nodes::library()
                .iter()
                .filter(|d| d.category == category && fits(d))
                .collect();
            if defs.is_empty() {
                continue;
            }
            ui.menu_button(category, |ui| {
                for def in defs {
                    if ui.button(def.label).on_hover_text(def.doc).clicked() {
                        chosen = Some(def.kind);
                    }
                }
            });
        }
        // Structural nodes, not in the library: they fit any wire.
        ui.menu_button("Layout", |ui| {
            for &(kind, label, doc) in LAYOUT_NODES {
                if ui.button(label).on_hover_text(doc).clicked() {
                    chosen = Some(kind);
                }
            }
        });
    } else {
        let found = |kind: &str, label: &str| {
            label.to_lowercase().contains(&query) || kind.contains(&query)
        };
        // (type, label, tooltip) of every match, library nodes first.
        let matches: Vec<(&'static str, &'static str, String)> = nodes::library()
            .iter()
            .filter(|d| fits(d) && found(d.kind, d.label))
            .map(|d| (d.kind, d.label, format!("{} — {}", d.category, d.doc)))
            .chain(
                LAYOUT_NODES
                    .iter()
                    .filter(|(kind, label, _)| found(kind, label))
                    .map(|&(kind, label, doc)| (kind, label, format!("Layout — {doc}"))),
            )
            .collect();
        if field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
            chosen = matches.first().map(|m| m.0);
        }
        egui::ScrollArea::vertical()
            .max_height(300.0)
            .show(ui, |ui| {
                for (i, (kind, label, tooltip)) in matches.iter().enumerate() {
                    let button = egui::Button::new(*label).selected(i == 0);
                    if ui.add(button).on_hover_text(tooltip).clicked() {
                        chosen = Some(*kind);
                    }
                }
            });
        if matches.is_empty() {
            ui.weak("No node matches.");
        }
    }
    if chosen.is_some() {
        search.clear();
        ui.close();
    }
    chosen
}

impl<'a> Viewer<'a> {
    fn node(&self, id: &str) -> Option<&'a Node> {
        self.graph.nodes.get(id)
    }

    fn sockets(&self, id: &str) -> Sockets {
        self.node(id)
            .and_then(|n| sockets_of(self.graph, n).ok())
            .unwrap_or_default()
    }

    /// The name and type of socket `index` on `side` of node `id` (a placeholder for a
    /// socket the graph no longer has, drawn for the one frame before the view rebuilds).
    fn socket(&self, id: &str, side: Side, index: usize) -> (String, SocketType) {
        let sockets = self.sockets(id);
        let list = match side {
            Side::Input => sockets.inputs,
            Side::Output => sockets.outputs,
        };
        list.get(index)
            .cloned()
            .unwrap_or(("?".into(), SocketType::Float))
    }

    fn is_reroute(&self, id: &str) -> bool {
        self.node(id).is_some_and(|n| n.kind == REROUTE)
    }

    /// Whether node `id` has an output to preview (a reroute has no preview).
    fn has_outputs(&self, id: &str) -> bool {
        !self.is_reroute(id) && !self.sockets(id).outputs.is_empty()
    }

    fn previewing(&self, id: &str) -> bool {
        self.has_outputs(id) && self.node(id).is_some_and(|n| n.preview)
    }

    fn toggle_preview(&mut self, id: &str) {
        if let Some(n) = self.node(id) {
            self.try_edit(
                GraphEdit::SetPreview {
                    node: id.to_owned(),
                    preview: !n.preview,
                },
                None,
            );
        }
    }

    /// The preview image under a node: the latest made (the previous one, with a
    /// spinner, while a new one renders), or why there is none.
    fn preview_ui(&self, ui: &mut Ui, id: &str) {
        let size = egui::Vec2::splat(PREVIEW_POINTS);
        let Some(previews) = self.previews else {
            ui.label(RichText::new("no preview here (inside a group, or no GPU device)").weak());
            return;
        };
        let view = previews.view(self.material, id, self.graph);
        let (rect, _) = ui.allocate_exact_size(size, egui::Sense::hover());
        if let Some(texture) = view.texture {
            egui::Image::new((texture.id(), size)).paint_at(ui, rect);
        }
        if !view.current {
            let spinner = if view.texture.is_some() {
                // Small, in the corner of the previous image.
                egui::Rect::from_min_size(
                    rect.left_top() + egui::vec2(4.0, 4.0),
                    egui::vec2(14.0, 14.0),
                )
            } else {
                egui::Rect::from_center_size(rect.center(), egui::vec2(24.0, 24.0))
            };
            ui.put(spinner, egui::Spinner::new());
        } else if let Some(e) = view.error {
            // The first line (a kernel error's full text is long), all of it on hover.
            let galley = ui.painter().layout(
                format!("no preview: {}", e.lines().next().unwrap_or_default()),
                egui::TextStyle::Small.resolve(ui.style()),
                Color32::LIGHT_RED,
                PREVIEW_POINTS,
            );
            ui.painter()
                .galley(rect.left_top(), galley, Color32::LIGHT_RED);
            ui.interact(
                rect,
                ui.id().with(("preview error", id)),
                egui::Sense::hover(),
            )
            .on_hover_text(e);
        }
    }

    /// The compile error at node `id`, if any. The compiler names a node inside a group
    /// by its path of instances (`group/veins`): outside, the error is on the instance;
    /// inside a group, on the node of that id (any instance of the group shows it).
    fn error_on(&self, id: &str) -> Option<&'a GraphError> {
        self.error.filter(|e| {
            let Some(path) = e.node.as_deref() else {
                return false;
            };
            if self.graph.interface.is_some() {
                path.rsplit('/').next() == Some(id) && path.contains('/')
            } else {
                path.split('/').next() == Some(id)
            }
        })
    }

    /// Records `edit` if the graph accepts it, else its reason.
    fn try_edit(&mut self, edit: GraphEdit, gesture: Option<GestureId>) {
        let mut scratch = self.graph.clone();
        match edit.clone().apply(&mut scratch) {
            Ok(_) => self.edits.push((edit, gesture)),
            Err(e) => self.message = Some(e),
        }
    }

    fn pin(&self, node: &str, side: Side, socket: &str, ty: SocketType) -> RecordedPin {
        let mut info = PinInfo::default()
            .with_shape(socket_shape(ty))
            .with_fill(socket_color(ty))
            .with_wire_color(socket_color(ty));
        let at_fault = self
            .error_on(node)
            .is_some_and(|e| e.socket.as_deref() == Some(socket));
        if at_fault {
            info = info.with_stroke(Stroke::new(2.0, Color32::RED));
        }
        RecordedPin {
            info,
            key: (node.to_owned(), side, socket.to_owned()),
            rects: Rc::clone(&self.pins),
        }
    }

    /// The widget of an unconnected input's value.
    fn value_ui(&mut self, ui: &mut Ui, id: &str, name: &str, ty: SocketType, label: egui::Id) {
        let Some(node) = self.node(id) else { return };
        let def = nodes::find(&node.kind);
        let given = match node.inputs.get(name) {
            Some(Input::Value(v)) => Some(v.clone()),
            _ => None,
        };
        let declared = def.and_then(|d| d.input(name)).map(|s| &s.default);
        let value = match (given, declared) {
            (Some(v), _) => v,
            (None, Some(nodes::Default::Value(v))) => v.clone(),
            (None, Some(nodes::Default::Implicit(_, what))) => {
                ui.label(RichText::new(format!("({what})")).weak());
                return;
            }
            // A group's input: the group's default for it.
            (None, None) => match structure::group_default(self.graph, node, name) {
                Some(v) => v,
                None => match ty {
                    SocketType::Float => Value::Float(0.0),
                    SocketType::Vec2 => Value::Vec2([0.0; 2]),
                    _ => Value::Vec3([0.0; 3]),
                },
            },
        };
        let range = def.and_then(|d| d.input(name)).and_then(|s| s.range);
        let mut changed = None;
        let mut gesture = None;
        match ty {
            SocketType::Float => {
                let old = value.as_f32();
                let mut x = old;
                let mut r = ui.add(float_field(&mut x, range)).labelled_by(label);
                if let Some(range) = range {
                    r = r.on_hover_text(range.describe());
                }
                if r.changed() {
                    if let (Some(range), true) = (range, r.dragged()) {
                        x = keep_to_soft_range(x, old, &range);
                    }
                    if x != old {
                        changed = Some(Value::Float(x));
                        gesture = r.dragged().then(|| r.id.value());
                    }
                }
            }
            SocketType::Color => {
                let mut rgb = value.as_vec3();
                let r = ui
                    .color_edit_button_rgb(&mut rgb)
                    .labelled_by(label)
                    .on_hover_text("Linear RGB (scene-referred); the picker shows it as sRGB");
                if r.changed() {
                    changed = Some(Value::Vec3(rgb));
                    gesture = Some(r.id.value());
                }
            }
            SocketType::Vector | SocketType::Vec2 => {
                let mut v = value.as_vec3();
                let n = if ty == SocketType::Vec2 { 2 } else { 3 };
                let mut any = false;
                for x in v.iter_mut().take(n) {
                    let r = ui
                        .add(egui::DragValue::new(x).speed(0.01).max_decimals(3))
                        .labelled_by(label);
                    if r.changed() {
                        any = true;
                        gesture = r.dragged().then(|| r.id.value());
                    }
                }
                if any {
                    changed = Some(if n == 2 {
                        Value::Vec2([v[0], v[1]])
                    } else {
                        Value::Vec3(v)
                    });
                }
            }
            SocketType::Bsdf | SocketType::Volume => {}
        }
        if let Some(v) = changed {
            self.try_edit(
                GraphEdit::SetInput {
                    node: id.to_owned(),
                    input: name.to_owned(),
                    value: Some(Input::Value(v)),
                },
                gesture,
            );
        }
    }

    /// A node's parameters: dropdowns for enums, checkboxes for flags, the colour-ramp
    /// editor ([`ramp`]), and a file's name with a button to pick another.
    fn params_ui(&mut self, ui: &mut Ui, id: &str) {
        let Some(node) = self.node(id) else { return };
        let Some(def) = nodes::find(&node.kind) else {
            if let Some(Param::Text(group)) = node.params.get(crate::material::graph::GROUP_PARAM) {
                ui.label(format!("Group \"{group}\""));
            }
            return;
        };
        let mut edit = None;
        let mut gesture = None;
        for p in &def.params {
            let current = node.params.get(p.name);
            match &p.kind {
                ParamKind::Enum(options) => {
                    let chosen = match current {
                        Some(Param::Text(t)) => t.as_str(),
                        _ => options[0],
                    };
                    ui.horizontal(|ui| {
                        let label = ui.label(p.name);
                        egui::ComboBox::from_id_salt((id, p.name))
                            .selected_text(chosen)
                            .show_ui(ui, |ui| {
                                for option in *options {
                                    if ui.selectable_label(*option == chosen, *option).clicked()
                                        && *option != chosen
                                    {
                                        edit = Some((p.name, Param::Text((*option).to_owned())));
                                    }
                                }
                            })
                            .response
                            .labelled_by(label.id)
                            .on_hover_text(p.doc);
                    });
                }
                ParamKind::Bool(default) => {
                    let mut b = match current {
                        Some(Param::Bool(b)) => *b,
                        _ => *default,
                    };
                    if ui.checkbox(&mut b, p.name).on_hover_text(p.doc).changed() {
                        edit = Some((p.name, Param::Bool(b)));
                    }
                }
                ParamKind::Ramp => {
                    let stops = match current {
                        Some(Param::Ramp(stops)) => stops.clone(),
                        _ => nodes::default_ramp_stops(),
                    };
                    let mode = match node.params.get("interpolation") {
                        Some(Param::Text(choice)) => ramp::Interpolation::from_choice(choice),
                        _ => ramp::Interpolation::Linear,
                    };
                    let ramp_id = egui::Id::new(("kiln color ramp", id, p.name));
                    ui.vertical(|ui| {
                        ui.label(p.name).on_hover_text(p.doc);
                        if let Some((new, g)) = ramp::ramp_ui(ui, ramp_id, &stops, mode) {
                            edit = Some((p.name, Param::Ramp(new)));
                            gesture = g;
                        }
                    });
                }
                ParamKind::File => {
                    let file = match current {
                        Some(Param::Text(t)) => std::path::Path::new(t)
                            .file_name()
                            .map_or(t.clone(), |f| f.to_string_lossy().into_owned()),
                        _ => "(no image)".to_owned(),
                    };
                    ui.horizontal(|ui| {
                        let label = ui.label(format!("{}: {file}", p.name));
                        if let Some(Param::Text(t)) = current {
                            label.on_hover_text(t.as_str());
                        }
                        if ui.button("Open…").on_hover_text(p.doc).clicked() {
                            self.pick_file = Some((id.to_owned(), p.name.to_owned()));
                        }
                    });
                }
            }
        }
        if let Some((param, value)) = edit {
            self.try_edit(
                GraphEdit::SetParam {
                    node: id.to_owned(),
                    param: param.to_owned(),
                    value: Some(value),
                },
                gesture,
            );
        }
    }
}

/// The field of a float input: clamped to the declared hard range (typed values too) and
/// dragged at the speed the soft range sets.
fn float_field(x: &mut f32, range: Option<FloatRange>) -> egui::DragValue<'_> {
    let field = egui::DragValue::new(x)
        .max_decimals(3)
        // A value loaded from a file is shown as it is (the compiler reports it), not
        // changed by being shown.
        .clamp_existing_to_range(false);
    match range {
        Some(r) => field.speed(r.drag_speed()).range(r.min..=r.max),
        None => field.speed(0.01),
    }
}

/// A dragged value kept to the soft range, as Blender's fields: a drag stops at the soft
/// bounds (widened to hold the value the drag started from), typing reaches the hard ones.
fn keep_to_soft_range(x: f32, old: f32, range: &FloatRange) -> f32 {
    x.clamp(range.soft_min.min(old), range.soft_max.max(old))
}

impl SnarlViewer<String> for Viewer<'_> {
    fn title(&mut self, node: &String) -> String {
        let kind = self.node(node).map_or("", |n| n.kind.as_str());
        match kind {
            REROUTE => return String::new(),
            GROUP_INPUT => return "Group Input".into(),
            GROUP_OUTPUT => return "Group Output".into(),
            GROUP => {
                if let Some(Param::Text(group)) =
                    self.node(node).and_then(|n| n.params.get(GROUP_PARAM))
                {
                    return format!("{group}  ·  {node}");
                }
            }
            _ => {}
        }
        let label = nodes::find(kind).map_or(kind, |d| d.label);
        format!("{label}  ·  {node}")
    }

    fn show_header(
        &mut self,
        node: NodeId,
        _inputs: &[InPin],
        _outputs: &[OutPin],
        ui: &mut Ui,
        snarl: &mut Snarl<String>,
    ) {
        let id = snarl[node].clone();
        // Node text is not selectable, so a click anywhere on a node reaches the node
        // (to select or drag it), as in Blender.
        ui.style_mut().interaction.selectable_labels = false;
        if self.is_reroute(&id) {
            // A reroute is a dot: a header just wide enough to grab it by.
            ui.add_space(4.0);
            return;
        }
        ui.label(self.title(&id));
        if self.node(&id).is_some_and(|n| n.muted) {
            ui.label(RichText::new("muted").small().color(Color32::LIGHT_RED))
                .on_hover_text("M: its outputs pass its first input of their type through");
        }
        if self.error_on(&id).is_some() {
            ui.label(RichText::new("⚠").color(Color32::LIGHT_RED));
        }
        if self.has_outputs(&id) {
            let on = self.node(&id).is_some_and(|n| n.preview);
            let toggle = ui
                .add(egui::Button::selectable(on, PREVIEW_ICON).small())
                .on_hover_text(if on {
                    "Hide the preview"
                } else {
                    "Show a preview of the node's output (Ctrl+Shift+click: in the viewport)"
                });
            if toggle.clicked() {
                self.toggle_preview(&id);
            }
        }
    }

    fn inputs(&mut self, node: &String) -> usize {
        self.sockets(node).inputs.len()
    }

    fn outputs(&mut self, node: &String) -> usize {
        self.sockets(node).outputs.len()
    }

    fn show_input(
        &mut self,
        pin: &InPin,
        ui: &mut Ui,
        snarl: &mut Snarl<String>,
    ) -> impl SnarlPin + 'static {
        let id = snarl[pin.id.node].clone();
        let (name, ty) = self.socket(&id, Side::Input, pin.id.input);
        ui.style_mut().interaction.selectable_labels = false;
        if self.is_reroute(&id) {
            return self.pin(&id, Side::Input, &name, ty);
        }
        let label = ui.label(&name);
        let takes_values = self.node(&id).is_some_and(|n| n.kind != GROUP_OUTPUT);
        if pin.remotes.is_empty() && !ty.is_shader() && takes_values {
            self.value_ui(ui, &id, &name, ty, label.id);
        }
        self.pin(&id, Side::Input, &name, ty)
    }

    fn show_output(
        &mut self,
        pin: &OutPin,
        ui: &mut Ui,
        snarl: &mut Snarl<String>,
    ) -> impl SnarlPin + 'static {
        let id = snarl[pin.id.node].clone();
        let (name, ty) = self.socket(&id, Side::Output, pin.id.output);
        ui.style_mut().interaction.selectable_labels = false;
        if !self.is_reroute(&id) {
            ui.label(&name);
        }
        self.pin(&id, Side::Output, &name, ty)
    }

    fn has_body(&mut self, node: &String) -> bool {
        self.error_on(node).is_some()
            || self.node(node).is_some_and(|n| {
                nodes::find(&n.kind).map_or(!n.params.is_empty(), |d| !d.params.is_empty())
            })
    }

    fn show_body(
        &mut self,
        node: NodeId,
        _inputs: &[InPin],
        _outputs: &[OutPin],
        ui: &mut Ui,
        snarl: &mut Snarl<String>,
    ) {
        let id = snarl[node].clone();
        // The body takes the width its content needs: snarl gives it the room the last
        // frame measured, so text wrapped to that room would never widen the node.
        ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Extend);
        ui.vertical(|ui| {
            if let Some(e) = self.error_on(&id) {
                // An error wraps at a width of its own instead.
                let galley = ui.painter().layout(
                    e.message.clone(),
                    egui::TextStyle::Body.resolve(ui.style()),
                    Color32::LIGHT_RED,
                    ERROR_WIDTH,
                );
                ui.label(galley);
            }
            self.params_ui(ui, &id);
        });
    }

    fn has_footer(&mut self, node: &String) -> bool {
        self.previewing(node)
    }

    /// The preview, under the node's pins and body (as Blender draws it, full width).
    fn show_footer(
        &mut self,
        node: NodeId,
        _inputs: &[InPin],
        _outputs: &[OutPin],
        ui: &mut Ui,
        snarl: &mut Snarl<String>,
    ) {
        let id = snarl[node].clone();
        ui.vertical_centered(|ui| self.preview_ui(ui, &id));
    }

    fn node_frame(
        &mut self,
        default: egui::Frame,
        node: NodeId,
        _inputs: &[InPin],
        _outputs: &[OutPin],
        snarl: &Snarl<String>,
    ) -> egui::Frame {
        let id = &snarl[node];
        let mut frame = default;
        if self.is_reroute(id) {
            frame = frame.inner_margin(2.0).corner_radius(8.0);
        }
        if self.node(id).is_some_and(|n| n.muted) {
            // Dimmed, as Blender draws a muted node.
            frame.fill = frame.fill.lerp_to_gamma(Color32::BLACK, 0.45);
        }
        if self.error_on(id).is_some() {
            frame.stroke(Stroke::new(2.0, Color32::RED))
        } else if self.layer_selected.contains(id) {
            frame.stroke(self.selection_stroke)
        } else {
            frame
        }
    }

    fn header_frame(
        &mut self,
        default: egui::Frame,
        node: NodeId,
        _inputs: &[InPin],
        _outputs: &[OutPin],
        snarl: &Snarl<String>,
    ) -> egui::Frame {
        let id = &snarl[node];
        if self.is_reroute(id) {
            default.inner_margin(0.0)
        } else if self.node(id).is_some_and(|n| n.muted) {
            // A red header, as Blender marks a muted node.
            default.fill(Color32::from_rgb(0x6e, 0x22, 0x22))
        } else {
            default
        }
    }

    fn connect(&mut self, from: &OutPin, to: &InPin, snarl: &mut Snarl<String>) {
        let from_id = snarl[from.id.node].clone();
        let to_id = snarl[to.id.node].clone();
        let (Some((output, _)), Some((input, _))) = (
            self.sockets(&from_id).outputs.get(from.id.output).cloned(),
            self.sockets(&to_id).inputs.get(to.id.input).cloned(),
        ) else {
            return;
        };
        // An input takes one wire: setting the link replaces the one it had.
        self.try_edit(GraphEdit::connect(&from_id, &output, &to_id, &input), None);
    }

    fn disconnect(&mut self, _from: &OutPin, to: &InPin, snarl: &mut Snarl<String>) {
        self.drop_inputs(to, snarl);
    }

    fn drop_inputs(&mut self, pin: &InPin, snarl: &mut Snarl<String>) {
        let id = snarl[pin.id.node].clone();
        if let Some((input, _)) = self.sockets(&id).inputs.get(pin.id.input).cloned() {
            self.try_edit(
                GraphEdit::SetInput {
                    node: id,
                    input,
                    value: None,
                },
                None,
            );
        }
    }

    fn drop_outputs(&mut self, pin: &OutPin, snarl: &mut Snarl<String>) {
        let edits: Vec<GraphEdit> = pin
            .remotes
            .iter()
            .filter_map(|remote| {
                let id = snarl[remote.node].clone();
                let (input, _) = self.sockets(&id).inputs.get(remote.input).cloned()?;
                Some(GraphEdit::SetInput {
                    node: id,
                    input,
                    value: None,
                })
            })
            .collect();
        if !edits.is_empty() {
            self.try_edit(GraphEdit::Batch(edits), None);
        }
    }

    fn has_graph_menu(&mut self, _pos: Pos2, _snarl: &mut Snarl<String>) -> bool {
        true
    }

    fn show_graph_menu(&mut self, pos: Pos2, ui: &mut Ui, _snarl: &mut Snarl<String>) {
        if let Some(kind) = add_menu(ui, self.search, None) {
            let edit = new_node(self.graph, kind, pos);
            self.try_edit(edit, None);
        }
    }

    fn has_dropped_wire_menu(&mut self, _src: AnyPins, _snarl: &mut Snarl<String>) -> bool {
        true
    }

    fn show_dropped_wire_menu(
        &mut self,
        pos: Pos2,
        ui: &mut Ui,
        src: AnyPins,
        snarl: &mut Snarl<String>,
    ) {
        // The first pin the wire came from decides what fits.
        let source = match src {
            AnyPins::Out(pins) => pins.first().and_then(|p| {
                let id = snarl[p.node].clone();
                let (name, ty) = self.sockets(&id).outputs.get(p.output).cloned()?;
                Some((id, name, ty, true))
            }),
            AnyPins::In(pins) => pins.first().and_then(|p| {
                let id = snarl[p.node].clone();
                let (name, ty) = self.sockets(&id).inputs.get(p.input).cloned()?;
                Some((id, name, ty, false))
            }),
        };
        let Some((source, socket, ty, from_output)) = source else {
            ui.close();
            return;
        };
        let Some(kind) = add_menu(ui, self.search, Some((ty, from_output))) else {
            return;
        };
        let GraphEdit::AddNode { id, node } = new_node(self.graph, kind, pos) else {
            return;
        };
        if kind == REROUTE {
            let wire = if from_output {
                GraphEdit::connect(&source, &socket, &id, REROUTE_INPUT)
            } else {
                GraphEdit::connect(&id, REROUTE_OUTPUT, &source, &socket)
            };
            self.try_edit(
                GraphEdit::Batch(vec![GraphEdit::AddNode { id, node }, wire]),
                None,
            );
            return;
        }
        let Some(def) = nodes::find(kind) else { return };
        let wire = if from_output {
            def.inputs
                .iter()
                .find(|s| ty.converts_to(s.ty).is_some())
                .map(|s| GraphEdit::connect(&source, &socket, &id, s.name))
        } else {
            def.outputs
                .iter()
                .find(|s| s.ty.converts_to(ty).is_some())
                .map(|s| GraphEdit::connect(&id, s.name, &source, &socket))
        };
        let mut edits = vec![GraphEdit::AddNode { id, node }];
        edits.extend(wire);
        self.try_edit(GraphEdit::Batch(edits), None);
    }

    fn has_node_menu(&mut self, _node: &String) -> bool {
        true
    }

    fn show_node_menu(
        &mut self,
        node: NodeId,
        _inputs: &[InPin],
        _outputs: &[OutPin],
        ui: &mut Ui,
        snarl: &mut Snarl<String>,
    ) {
        let id = snarl[node].clone();
        if self.has_outputs(&id) {
            let label = if self.previewing(&id) {
                "Hide preview"
            } else {
                "Show preview"
            };
            if ui.button(label).clicked() {
                self.toggle_preview(&id);
                ui.close();
            }
        }
        if ui.button("Duplicate").clicked() {
            if let Some(n) = self.node(&id) {
                let (adds, _) =
                    graph_edit::copies(self.graph, &[(id.clone(), n.clone())], [40.0, 40.0]);
                self.try_edit(GraphEdit::Batch(adds), None);
            }
            ui.close();
        }
        if ui.button("Delete").clicked() {
            self.try_edit(GraphEdit::RemoveNode { id: id.clone() }, None);
            ui.close();
        }
        self.structure_menu(ui, &id);
    }

    fn draw_background(
        &mut self,
        background: Option<&egui_snarl::ui::BackgroundPattern>,
        viewport: &egui::Rect,
        snarl_style: &SnarlStyle,
        style: &egui::Style,
        painter: &egui::Painter,
        _snarl: &Snarl<String>,
    ) {
        if let Some(background) = background {
            background.draw(viewport, snarl_style, style, painter);
        }
        // Frames lie on the canvas, under the wires and the nodes.
        structure::paint_frames(&self.frames, painter);
    }

    fn final_node_rect(
        &mut self,
        node: NodeId,
        rect: egui::Rect,
        _ui: &mut Ui,
        snarl: &mut Snarl<String>,
    ) {
        self.node_rects.insert(snarl[node].clone(), rect);
    }

    fn current_transform(&mut self, to_global: &mut TSTransform, _snarl: &mut Snarl<String>) {
        if let Some(view) = self.view.take() {
            *to_global = view;
        }
        if let Some((bounds, canvas)) = self.frame.take() {
            *to_global = framing(bounds, canvas);
        }
        self.to_global = *to_global;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `bounds` in screen points under `view`.
    fn shown(view: TSTransform, bounds: egui::Rect) -> egui::Rect {
        egui::Rect::from_min_max(view * bounds.min, view * bounds.max)
    }

    #[test]
    fn home_shows_a_graph_s_whole_width_and_a_tall_one_from_its_top() {
        let canvas = egui::Rect::from_min_size(egui::pos2(0.0, 400.0), egui::vec2(940.0, 300.0));
        // Small: whole and centred, at scale 1.
        let small = egui::Rect::from_min_size(egui::pos2(-50.0, 20.0), egui::vec2(400.0, 150.0));
        let view = framing(small, canvas);
        assert_eq!(view.scaling, 1.0);
        assert!((shown(view, small).center() - canvas.center()).length() < 1e-3);
        // Wide and short: zoomed out until its whole width shows.
        let wide = egui::Rect::from_min_size(egui::pos2(-300.0, 0.0), egui::vec2(1400.0, 200.0));
        let view = framing(wide, canvas);
        assert!(
            view.scaling < 0.8 && view.scaling >= 0.4,
            "{}",
            view.scaling
        );
        assert!(
            canvas.contains_rect(shown(view, wide)),
            "{:?}",
            shown(view, wide)
        );
        // Wide and tall (a Principled BSDF among other nodes): the whole width, from the top.
        let tall = egui::Rect::from_min_size(egui::pos2(0.0, 0.0), egui::vec2(1100.0, 800.0));
        let view = framing(tall, canvas);
        let r = shown(view, tall);
        assert!(
            r.left() >= canvas.left() && r.right() <= canvas.right(),
            "{r:?}"
        );
        assert!((r.top() - (canvas.top() + 24.0)).abs() < 1e-3, "{r:?}");
        // Narrow and tall: legible (0.8), from the top.
        let column = egui::Rect::from_min_size(egui::pos2(0.0, 0.0), egui::vec2(300.0, 900.0));
        let view = framing(column, canvas);
        assert_eq!(view.scaling, 0.8);
        assert!((shown(view, column).top() - (canvas.top() + 24.0)).abs() < 1e-3);
        // Wider than scale 0.4 can show: 0.4, centred across.
        let huge = egui::Rect::from_min_size(egui::pos2(0.0, 0.0), egui::vec2(5000.0, 100.0));
        let view = framing(huge, canvas);
        assert_eq!(view.scaling, 0.4);
        assert!((shown(view, huge).center().x - canvas.center().x).abs() < 1e-3);
    }

    #[test]
    fn a_drag_stops_at_the_soft_range_unless_it_started_beyond() {
        let range = FloatRange::new(0.0, 1000.0).soft(0.0, 100.0);
        assert_eq!(keep_to_soft_range(130.0, 99.0, &range), 100.0);
        assert_eq!(keep_to_soft_range(-3.0, 1.0, &range), 0.0);
        // Typed to 500 (beyond the soft range), a drag from there comes back freely and
        // goes no further out.
        assert_eq!(keep_to_soft_range(480.0, 500.0, &range), 480.0);
        assert_eq!(keep_to_soft_range(510.0, 500.0, &range), 500.0);
        // The drag speed follows the soft range, in small steps for wide ones.
        assert_eq!(nodes::UNIT.drag_speed(), 1.0 / 400.0);
        assert_eq!(nodes::ANY.drag_speed(), 0.05);
    }
}
