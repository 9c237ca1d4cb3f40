//! The node editor's structure: entering and leaving node groups (the breadcrumb above the
//! canvas, Tab), the entered group's interface panel, and frames — drawn behind the
//! nodes, moved by their label bar, relabelled and recoloured in a small window.
//!
//! Snarl knows neither groups nor frames. Inside a group the canvas shows the group's
//! view ([`graph_edit::group_view`]) and every edit made there is wrapped to reach the
//! group ([`scoped`]); frames are painted on the canvas under snarl's wires
//! and nodes ([`paint_frames`], from the viewer's background), around the rectangles the
//! nodes took in the last frame, and their label bars take the pointer on a layer above
//! the canvas.

use egui::{Color32, Pos2, RichText, Ui};

use super::{MOVE_GESTURE, NodeEditor, Viewer};
use crate::editor::document::GestureId;
use crate::editor::graph_edit::{self, GROUP_OUTPUT, GraphEdit};
use crate::material::graph::{GROUP, GROUP_INPUT, GROUP_PARAM};
use crate::material::{Graph, GroupSocket, Node, Param, SocketType, Value};

/// The room around a frame's nodes, and the height of its label bar, in canvas points.
const FRAME_MARGIN: f32 = 16.0;
const FRAME_BAR: f32 = 30.0;

/// A frame as drawn: its box and label bar in canvas coordinates.
#[derive(Clone, Debug)]
pub(super) struct FrameShape {
    id: String,
    label: String,
    color: Color32,
    nodes: Vec<String>,
    /// The whole frame, bar included.
    rect: egui::Rect,
    bar: egui::Rect,
}

/// `bounds` of nodes grown by the room frames around them take.
pub(super) fn with_frame_room(bounds: egui::Rect) -> egui::Rect {
    egui::Rect::from_min_max(
        bounds.min - egui::vec2(FRAME_MARGIN, FRAME_MARGIN + FRAME_BAR),
        bounds.max + egui::vec2(FRAME_MARGIN, FRAME_MARGIN),
    )
}

/// The label bar of frame `id` among `frames`, in canvas coordinates.
pub(super) fn bar_of(frames: &[FrameShape], id: &str) -> Option<egui::Rect> {
    frames.iter().find(|f| f.id == id).map(|f| f.bar)
}

/// Paints `frames` (in canvas coordinates, with the canvas's painter).
pub(super) fn paint_frames(frames: &[FrameShape], painter: &egui::Painter) {
    for frame in frames {
        painter.rect_filled(frame.rect, 6.0, frame.color.gamma_multiply(0.75));
        painter.rect_filled(
            frame.bar,
            egui::CornerRadius {
                nw: 6,
                ne: 6,
                sw: 0,
                se: 0,
            },
            frame.color,
        );
        painter.rect_stroke(
            frame.rect,
            6.0,
            egui::Stroke::new(1.0, frame.color.gamma_multiply(1.6)),
            egui::StrokeKind::Inside,
        );
        painter.text(
            frame.bar.left_center() + egui::vec2(10.0, 0.0),
            egui::Align2::LEFT_CENTER,
            &frame.label,
            egui::FontId::proportional(16.0),
            Color32::from_gray(230),
        );
    }
}

/// The default a group instance's input `input` takes while unconnected: the group's.
pub(super) fn group_default(graph: &Graph, node: &Node, input: &str) -> Option<Value> {
    if node.kind != GROUP {
        return None;
    }
    let Some(Param::Text(name)) = node.params.get(GROUP_PARAM) else {
        return None;
    };
    let socket = graph
        .groups
        .get(name)?
        .inputs
        .iter()
        .find(|s| s.name == input)?;
    socket.default.clone()
}

/// The socket types a group's interface offers, in the order of its "+" menus.
const SOCKET_TYPES: [SocketType; 6] = [
    SocketType::Float,
    SocketType::Vector,
    SocketType::Color,
    SocketType::Vec2,
    SocketType::Bsdf,
    SocketType::Volume,
];

/// `edit`, made on the canvas showing group `group` (`None`: the material's graph), as
/// an edit of the material: wrapped to reach the group.
pub(super) fn scoped(group: Option<&str>, edit: GraphEdit) -> GraphEdit {
    match group {
        Some(group) => GraphEdit::InGroup {
            group: group.to_owned(),
            edit: Box::new(edit),
        },
        None => edit,
    }
}

impl NodeEditor {
    /// The groups entered, as the material's graph `top` has them: another material
    /// starts outside, and a group that went (undone, ungrouped) takes the canvas out.
    pub(super) fn follow_path(&mut self, material: usize, top: &Graph) {
        if (self.shown.as_ref()).is_some_and(|(m, _, _)| *m != material) {
            self.path.clear();
        }
        if let Some(gone) = self.path.iter().position(|g| !top.groups.contains_key(g)) {
            self.path.truncate(gone);
        }
    }

    /// Shows the insides of group `name` (Tab on a group node).
    pub(super) fn enter_group(&mut self, name: String) {
        self.path.push(name);
        self.fresh_canvas();
    }

    /// Back to the graph around the group shown (Tab with no group node selected,
    /// Ctrl+Tab, "Exit group").
    pub(super) fn exit_group(&mut self) {
        if self.path.pop().is_some() {
            self.fresh_canvas();
        }
    }

    /// Another graph on the canvas: nothing selected, the view framing all of it.
    fn fresh_canvas(&mut self) {
        self.select_all = None;
        self.frame_edit = None;
        self.canvas_generation += 1;
        self.frame_all = true;
    }

    /// Tab moves egui's keyboard focus to the next widget: over the canvas it is the
    /// editor's key (enter or leave a group), so the focus stays where it was. Called
    /// before anything is drawn in a frame (the first widget drawn takes the focus).
    pub fn release_tab_focus(&self, ctx: &egui::Context) {
        let over_canvas = (self.rect)
            .zip(ctx.pointer_hover_pos())
            .is_some_and(|(r, p)| r.contains(p));
        if over_canvas
            && !ctx.egui_wants_keyboard_input()
            && ctx.input(|i| i.key_pressed(egui::Key::Tab))
        {
            ctx.memory_mut(|m| m.move_focus(egui::FocusDirection::None));
        }
    }

    /// Inside a group: the path ("Material › Group") with the button that leaves, and the
    /// group's interface. Returns the edits of the interface (edits of the material's
    /// graph `top`, not of the view), each with its gesture.
    pub(super) fn scope_bar(
        &mut self,
        ui: &mut Ui,
        material: &str,
        top: &Graph,
    ) -> Vec<(GraphEdit, Option<GestureId>)> {
        let Some(name) = self.path.last().cloned() else {
            return Vec::new();
        };
        let Some(group) = top.groups.get(&name) else {
            return Vec::new();
        };
        let mut edits = Vec::new();
        ui.horizontal(|ui| {
            if ui
                .button("Exit group")
                .on_hover_text("Back to the graph around it (Tab or Ctrl+Tab)")
                .clicked()
            {
                self.exit_group();
            }
            let path: Vec<&str> = std::iter::once(material)
                .chain(self.path.iter().map(String::as_str))
                .collect();
            ui.label(RichText::new(path.join(" › ")).strong());
        });
        egui::CollapsingHeader::new("Group interface")
            .id_salt(("kiln group interface", &name))
            .show(ui, |ui| {
                for output in [false, true] {
                    sockets_ui(ui, top, &name, group, output, &mut edits);
                }
            });
        if let Err(e) = edits
            .iter()
            .try_for_each(|(edit, _)| edit.clone().apply(&mut top.clone()).map(|_| ()))
        {
            self.message = Some(e);
            edits.clear();
        }
        edits
    }

    /// The frames of `graph` as drawn: around where their nodes were drawn in the last
    /// frame (or, for nodes not drawn yet, their laid-out boxes).
    pub(super) fn frame_shapes(&self, graph: &Graph) -> Vec<FrameShape> {
        let node_rect = |id: &String| -> Option<egui::Rect> {
            if let Some(rect) = self.node_rects.get(id) {
                return Some(*rect);
            }
            let (p, node) = (self.positions.get(id)?, graph.nodes.get(id)?);
            Some(egui::Rect::from_min_size(
                Pos2::new(p[0], p[1]),
                egui::vec2(
                    graph_edit::estimated_width(graph, node),
                    graph_edit::estimated_height(graph, node),
                ),
            ))
        };
        graph
            .frames
            .iter()
            .filter_map(|(id, frame)| {
                let bounds = (frame.nodes.iter())
                    .filter_map(node_rect)
                    .reduce(|a, b| a.union(b))?;
                let body = bounds.expand(FRAME_MARGIN);
                let bar = egui::Rect::from_min_max(
                    body.min - egui::vec2(0.0, FRAME_BAR),
                    Pos2::new(body.max.x, body.min.y),
                );
                let [r, g, b] = frame.color;
                let color: Color32 = egui::Rgba::from_rgb(r, g, b).into();
                Some(FrameShape {
                    id: id.clone(),
                    label: frame.label.clone(),
                    color,
                    nodes: frame.nodes.clone(),
                    rect: body.union(bar),
                    bar,
                })
            })
            .collect()
    }

    /// The frames' label bars, on a layer above the canvas (snarl's canvas takes every
    /// drag it is under): dragging one moves the frame's nodes (one undo step, as a node
    /// drag), double-clicking it or its context menu edits the frame. Returns the edits,
    /// with their gestures.
    pub(super) fn frame_bars(
        &mut self,
        ui: &Ui,
        graph: &Graph,
        frames: &[FrameShape],
        canvas: egui::Rect,
    ) -> Vec<(GraphEdit, Option<GestureId>)> {
        let ctx = ui.ctx().clone();
        let mut edits = Vec::new();
        for frame in frames {
            let bar = (self.to_global * frame.bar).intersect(canvas);
            if !bar.is_positive() {
                continue;
            }
            let response = egui::Area::new(self.canvas_id().with(("frame bar", &frame.id)))
                .order(egui::Order::Middle)
                .fixed_pos(bar.min)
                .constrain(false)
                .show(&ctx, |ui| {
                    let response = ui.allocate_response(bar.size(), egui::Sense::click_and_drag());
                    response.widget_info(|| {
                        egui::WidgetInfo::labeled(egui::WidgetType::Other, true, &frame.label)
                    });
                    response
                })
                .inner
                .on_hover_text("Drag to move the frame; double-click to edit its label and colour");
            if response.dragged() {
                let delta = response.drag_delta() / self.to_global.scaling;
                if delta != egui::Vec2::ZERO {
                    let moved = (frame.nodes.iter())
                        .filter_map(|id| {
                            let p = self.positions.get(id)?;
                            Some((id.clone(), Some([p[0] + delta.x, p[1] + delta.y])))
                        })
                        .collect();
                    if let Some(edit) = self.move_edit(graph, moved) {
                        edits.push((edit, Some(MOVE_GESTURE)));
                    }
                }
            }
            if response.double_clicked() {
                self.frame_edit = Some((frame.id.clone(), frame.label.clone()));
            }
            response.context_menu(|ui| {
                if ui.button("Edit label and colour…").clicked() {
                    self.frame_edit = Some((frame.id.clone(), frame.label.clone()));
                    ui.close();
                }
                if ui.button("Delete frame").clicked() {
                    edits.push((
                        GraphEdit::SetFrame {
                            id: frame.id.clone(),
                            frame: None,
                        },
                        None,
                    ));
                    ui.close();
                }
            });
        }
        edits.extend(self.frame_window(&ctx, graph));
        edits
    }

    /// The window editing a frame's label and colour.
    fn frame_window(
        &mut self,
        ctx: &egui::Context,
        graph: &Graph,
    ) -> Vec<(GraphEdit, Option<GestureId>)> {
        let Some((id, label)) = &mut self.frame_edit else {
            return Vec::new();
        };
        let Some(frame) = graph.frames.get(id.as_str()) else {
            self.frame_edit = None;
            return Vec::new();
        };
        let mut edits = Vec::new();
        let mut open = true;
        let set = |frame: crate::material::Frame| GraphEdit::SetFrame {
            id: id.clone(),
            frame: Some(frame),
        };
        egui::Window::new("Frame")
            .id(egui::Id::new("kiln frame editor"))
            .collapsible(false)
            .resizable(false)
            .open(&mut open)
            .show(ctx, |ui| {
                ui.horizontal(|ui| {
                    let name = ui.label("Label");
                    let field = ui
                        .add(egui::TextEdit::singleline(label))
                        .labelled_by(name.id);
                    if field.lost_focus() && *label != frame.label {
                        let mut changed = frame.clone();
                        changed.label = label.clone();
                        edits.push((set(changed), None));
                    }
                });
                ui.horizontal(|ui| {
                    let name = ui.label("Colour");
                    let mut color = frame.color;
                    let picker = ui
                        .color_edit_button_rgb(&mut color)
                        .labelled_by(name.id)
                        .on_hover_text("Linear RGB; the picker shows it as sRGB");
                    if picker.changed() {
                        let mut changed = frame.clone();
                        changed.color = color.map(|c| c.clamp(0.0, 1.0));
                        edits.push((set(changed), Some(picker.id.value())));
                    }
                });
                if ui.button("Delete frame").clicked() {
                    edits.push((
                        GraphEdit::SetFrame {
                            id: id.clone(),
                            frame: None,
                        },
                        None,
                    ));
                }
            });
        if !open {
            self.frame_edit = None;
        }
        edits
    }
}

/// One side of a group's interface (`output`: its outputs): each socket's name (renamed
/// when the field loses focus), type, default (inputs) and a button removing it, then a
/// menu adding one. Pushes the edits of `top` it makes.
fn sockets_ui(
    ui: &mut Ui,
    top: &Graph,
    name: &str,
    group: &crate::material::Group,
    output: bool,
    edits: &mut Vec<(GraphEdit, Option<GestureId>)>,
) {
    let list = if output {
        &group.outputs
    } else {
        &group.inputs
    };
    ui.label(RichText::new(if output { "Outputs" } else { "Inputs" }).strong());
    for (i, socket) in list.iter().enumerate() {
        ui.horizontal(|ui| {
            let id = ui.id().with(("group socket name", output, i));
            let mut text = ui
                .data(|d| d.get_temp::<String>(id))
                .unwrap_or_else(|| socket.name.clone());
            let field = ui.add(egui::TextEdit::singleline(&mut text).desired_width(110.0));
            if field.lost_focus() {
                if text != socket.name {
                    edits.push((
                        GraphEdit::RenameGroupSocket {
                            group: name.to_owned(),
                            output,
                            from: socket.name.clone(),
                            to: text,
                        },
                        None,
                    ));
                }
                ui.data_mut(|d| d.remove::<String>(id));
            } else if field.has_focus() {
                ui.data_mut(|d| d.insert_temp(id, text));
            }
            ui.weak(socket.ty.name());
            if !output {
                if let Some((default, gesture)) = default_ui(ui, socket) {
                    let mut inputs = group.inputs.clone();
                    inputs[i].default = Some(default);
                    edits.push((
                        GraphEdit::SetGroupSockets {
                            group: name.to_owned(),
                            inputs,
                            outputs: group.outputs.clone(),
                        },
                        gesture,
                    ));
                }
            }
            if ui
                .small_button("✖")
                .on_hover_text("Remove the socket (and its wires)")
                .clicked()
            {
                // It cannot fail: the group and the socket are the ones listed.
                if let Ok(edit) = graph_edit::remove_group_socket(top, name, output, &socket.name) {
                    edits.push((edit, None));
                }
            }
        });
    }
    let add = if output { "+ Output" } else { "+ Input" };
    ui.menu_button(add, |ui| {
        for ty in SOCKET_TYPES {
            if ui.button(ty.name()).clicked() {
                if let Ok(edit) = graph_edit::add_group_socket(top, name, output, ty) {
                    edits.push((with_input_node(group, name, output, edit), None));
                }
                ui.close();
            }
        }
    });
}

/// `edit` adding an input, with a group input node added inside when the group has none
/// (else the new input could not be wired to anything inside).
fn with_input_node(
    group: &crate::material::Group,
    name: &str,
    output: bool,
    edit: GraphEdit,
) -> GraphEdit {
    if output || group.nodes.values().any(|n| n.kind == GROUP_INPUT) {
        return edit;
    }
    let mut node = Node::new(GROUP_INPUT);
    let left = (group.nodes.values())
        .filter_map(|n| n.position)
        .fold(f32::INFINITY, |x, p| x.min(p[0]));
    let left = if left.is_finite() { left } else { 0.0 };
    node.position = Some([left - graph_edit::NODE_WIDTH - graph_edit::LAYOUT_GAP, 0.0]);
    let id = std::iter::once(GROUP_INPUT.to_owned())
        .chain((2..).map(|n| format!("{GROUP_INPUT}_{n}")))
        .find(|id| !group.nodes.contains_key(id))
        .expect("a free id exists");
    GraphEdit::Batch(vec![
        edit,
        GraphEdit::InGroup {
            group: name.to_owned(),
            edit: Box::new(GraphEdit::AddNode { id, node }),
        },
    ])
}

/// The widget of a group input's default; the new default when changed, with the drag's
/// gesture.
fn default_ui(ui: &mut Ui, socket: &GroupSocket) -> Option<(Value, Option<GestureId>)> {
    let current = socket.default.clone();
    match socket.ty {
        SocketType::Bsdf | SocketType::Volume => None,
        SocketType::Float => {
            let mut x = current.map_or(0.0, |v| v.as_f32());
            let r = ui.add(egui::DragValue::new(&mut x).speed(0.01).max_decimals(3));
            (r.changed() && x.is_finite())
                .then(|| (Value::Float(x), r.dragged().then(|| r.id.value())))
        }
        SocketType::Color => {
            let mut rgb = current.map_or([0.0; 3], |v| v.as_vec3());
            let r = ui
                .color_edit_button_rgb(&mut rgb)
                .on_hover_text("Linear RGB; the picker shows it as sRGB");
            r.changed().then(|| (Value::Vec3(rgb), Some(r.id.value())))
        }
        SocketType::Vector | SocketType::Vec2 => {
            let mut v = current.map_or([0.0; 3], |v| v.as_vec3());
            let n = if socket.ty == SocketType::Vec2 { 2 } else { 3 };
            let mut changed = None;
            for x in v.iter_mut().take(n) {
                let r = ui.add(egui::DragValue::new(x).speed(0.01).max_decimals(3));
                if r.changed() {
                    changed = Some(r.dragged().then(|| r.id.value()));
                }
            }
            let value = if n == 2 {
                Value::Vec2([v[0], v[1]])
            } else {
                Value::Vec3(v)
            };
            changed.map(|gesture| (value, gesture))
        }
    }
}

impl Viewer<'_> {
    /// The node menu's structure entries for node `id`: enter or ungroup a group node,
    /// put the node in a new frame or take it out of its frame.
    pub(super) fn structure_menu(&mut self, ui: &mut Ui, id: &str) {
        let Some(node) = self.node(id) else { return };
        if node.kind == GROUP {
            ui.separator();
            if ui.button("Enter group (Tab)").clicked() {
                if let Some(Param::Text(group)) = node.params.get(GROUP_PARAM) {
                    self.enter = Some(group.clone());
                }
                ui.close();
            }
            if ui.button("Ungroup (Ctrl+Alt+G)").clicked() {
                match graph_edit::ungroup(self.graph, id) {
                    Ok((edit, _)) => self.try_edit(edit, None),
                    Err(e) => self.message = Some(e),
                }
                ui.close();
            }
        }
        if node.kind == GROUP_OUTPUT {
            return;
        }
        ui.separator();
        let ids = [id.to_owned()];
        if ui.button("Join in new frame (Ctrl+J)").clicked() {
            if let Some((edit, _)) = graph_edit::join_in_frame(self.graph, &ids) {
                self.try_edit(edit, None);
            }
            ui.close();
        }
        if let Some(edit) = graph_edit::remove_from_frames(self.graph, &ids) {
            if ui.button("Remove from frame (Alt+P)").clicked() {
                self.try_edit(edit, None);
                ui.close();
            }
        }
    }
}
