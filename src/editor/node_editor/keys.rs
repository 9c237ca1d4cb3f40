//! The node editor's keys, and the selection they act on.
//!
//! Snarl keeps its selection private: the app reads it ([`get_selected_nodes`]) but cannot
//! set it. Select all (A) is therefore a layer over it, [`SelectAll`]: the nodes A
//! selected, kept while snarl's own selection stays what it was when A was pressed (a
//! click or box select on the canvas then takes over, as in Blender), drawn as selected
//! by the editor and moved together when one of them is dragged. Deselect all (Alt+A)
//! gives the canvas a new egui id, so snarl starts from an empty selection; the editor
//! keeps the view.

use std::collections::BTreeSet;

use egui::{Key, Modifiers, Ui};
use egui_snarl::NodeId;
use egui_snarl::ui::get_selected_nodes;

use super::NodeEditor;
use crate::editor::graph_edit::{self, GROUP_OUTPUT, GraphEdit};
use crate::material::graph::{GROUP, GROUP_INPUT, GROUP_PARAM, REROUTE};
use crate::material::{Graph, Node, Param};

/// Nodes selected with A, over snarl's selection.
#[derive(Clone, Debug, Default)]
pub(super) struct SelectAll {
    pub(super) ids: BTreeSet<String>,
    /// Snarl's selection when A was pressed; once it differs, the layer is dropped.
    snarl_then: Vec<NodeId>,
}

impl NodeEditor {
    /// The canvas's egui id: fixed, so snarl's selection can be read back, until deselect
    /// all starts a new one.
    pub(super) fn canvas_id(&self) -> egui::Id {
        egui::Id::new("kiln node editor canvas").with(self.canvas_generation)
    }

    /// Deselects every node, keeping the view. (After the nodes are replaced, snarl's
    /// selection, by its node ids, would name other nodes.)
    fn deselect_all(&mut self) {
        self.select_all = None;
        self.canvas_generation += 1;
        self.keep_view = true;
    }

    /// Snarl's selection, by snarl node id.
    fn snarl_selection(&self, ctx: &egui::Context) -> Vec<NodeId> {
        get_selected_nodes(self.canvas_id(), ctx)
    }

    /// Drops the select-all layer once the user changed snarl's selection.
    pub(super) fn refresh_selection(&mut self, ctx: &egui::Context) {
        if self
            .select_all
            .as_ref()
            .is_some_and(|all| all.snarl_then != self.snarl_selection(ctx))
        {
            self.select_all = None;
        }
    }

    /// Node ids of the nodes selected on the canvas, sorted.
    pub(super) fn selected(&self, ctx: &egui::Context) -> Vec<String> {
        let mut ids: BTreeSet<String> = self
            .snarl_selection(ctx)
            .into_iter()
            .filter_map(|n| self.snarl.get_node(n).cloned())
            .collect();
        if let Some(all) = &self.select_all {
            let shown: BTreeSet<&String> = self.snarl.nodes().collect();
            ids.extend(all.ids.iter().filter(|id| shown.contains(id)).cloned());
        }
        ids.into_iter().collect()
    }

    /// Nodes the select-all layer selects that snarl does not (the editor draws them as
    /// selected).
    pub(super) fn selected_by_layer(&self, ctx: &egui::Context) -> BTreeSet<String> {
        let Some(all) = &self.select_all else {
            return BTreeSet::new();
        };
        let by_snarl: BTreeSet<String> = self
            .snarl_selection(ctx)
            .into_iter()
            .filter_map(|n| self.snarl.get_node(n).cloned())
            .collect();
        all.ids.difference(&by_snarl).cloned().collect()
    }

    /// Select all (A) and deselect all (Alt+A), delete (X, Delete), mute (M), duplicate
    /// (Shift+D), copy and paste (Ctrl+C, Ctrl+V), frame all (Home), the add menu
    /// (Shift+A), and structure: make a group (Ctrl+G), ungroup (Ctrl+Alt+G), enter a
    /// group or leave it (Tab; Ctrl+Tab leaves), join in a new frame (Ctrl+J) and take
    /// out of frames (Alt+P), while the pointer is over the canvas and no text field has
    /// the keyboard.
    pub(super) fn keyboard(&mut self, ui: &Ui, graph: &Graph, hovered: bool) -> Vec<GraphEdit> {
        let ctx = ui.ctx();
        if !hovered || ctx.egui_wants_keyboard_input() {
            return Vec::new();
        }
        let mut edits = Vec::new();
        // A pattern without Alt or Shift also matches a press with them: the keys with
        // modifiers are taken first.
        let pressed =
            |key: Key, modifiers: Modifiers| ctx.input_mut(|i| i.consume_key(modifiers, key));
        let copy_event = ctx.input(|i| i.events.iter().any(|e| matches!(e, egui::Event::Copy)));
        let paste_event =
            ctx.input(|i| i.events.iter().any(|e| matches!(e, egui::Event::Paste(_))));
        if pressed(Key::Home, Modifiers::NONE) {
            self.frame_all = true;
        }
        if pressed(Key::A, Modifiers::ALT) {
            self.deselect_all();
        }
        if pressed(Key::A, Modifiers::SHIFT) {
            self.add_menu = ctx.pointer_latest_pos();
            self.search.clear();
        }
        if pressed(Key::A, Modifiers::NONE) {
            self.select_all = Some(SelectAll {
                ids: graph.nodes.keys().cloned().collect(),
                snarl_then: self.snarl_selection(ctx),
            });
        }
        let selected = self.selected(ctx);
        edits.extend(self.structure_keys(ctx, graph, &selected));
        let delete = pressed(Key::X, Modifiers::NONE) || pressed(Key::Delete, Modifiers::NONE);
        // A group's output node stays while the group does.
        let removable: Vec<&String> = (selected.iter())
            .filter(|id| graph.nodes.get(*id).is_some_and(|n| n.kind != GROUP_OUTPUT))
            .collect();
        if delete && !removable.is_empty() {
            edits.push(GraphEdit::Batch(
                removable
                    .into_iter()
                    .map(|id| GraphEdit::RemoveNode { id: id.clone() })
                    .collect(),
            ));
            self.select_all = None;
        }
        if pressed(Key::M, Modifiers::NONE) {
            let toggles: Vec<GraphEdit> = selected
                .iter()
                .filter_map(|id| {
                    let node = graph.nodes.get(id)?;
                    // A node without outputs (the material output) has nothing to pass, a
                    // reroute passes its input anyway, a group's input node is its
                    // interface.
                    let outputs = graph_edit::sockets_of(graph, node).ok()?.outputs;
                    let passes = node.kind != REROUTE && node.kind != GROUP_INPUT;
                    (!outputs.is_empty() && passes).then(|| GraphEdit::SetMuted {
                        node: id.clone(),
                        muted: !node.muted,
                    })
                })
                .collect();
            if !toggles.is_empty() {
                edits.push(GraphEdit::Batch(toggles));
            }
        }
        let picked = |ids: &[String]| -> Vec<(String, Node)> {
            ids.iter()
                .filter_map(|id| graph.nodes.get(id).map(|n| (id.clone(), n.clone())))
                .collect()
        };
        if pressed(Key::D, Modifiers::SHIFT) && !selected.is_empty() {
            let (adds, _) = graph_edit::copies(graph, &picked(&selected), [40.0, 40.0]);
            edits.push(GraphEdit::Batch(adds));
        }
        if (copy_event || pressed(Key::C, Modifiers::COMMAND)) && !selected.is_empty() {
            self.clipboard = picked(&selected);
        }
        if (paste_event || pressed(Key::V, Modifiers::COMMAND)) && !self.clipboard.is_empty() {
            let (adds, _) = graph_edit::copies(graph, &self.clipboard, [60.0, 60.0]);
            edits.push(GraphEdit::Batch(adds));
        }
        edits
    }

    /// The structure keys (see [`NodeEditor::keyboard`]) on the nodes `selected`.
    fn structure_keys(
        &mut self,
        ctx: &egui::Context,
        graph: &Graph,
        selected: &[String],
    ) -> Vec<GraphEdit> {
        let pressed =
            |key: Key, modifiers: Modifiers| ctx.input_mut(|i| i.consume_key(modifiers, key));
        let mut edits = Vec::new();
        let any_tab = ctx.input(|i| i.key_pressed(Key::Tab));
        // The keys with more modifiers first: a pattern also matches a press with Alt.
        if pressed(Key::G, Modifiers::COMMAND | Modifiers::ALT) {
            let mut scratch = graph.clone();
            let mut ungroups = Vec::new();
            let groups = selected
                .iter()
                .filter(|id| graph.nodes.get(*id).is_some_and(|n| n.kind == GROUP));
            for id in groups {
                match graph_edit::ungroup(&scratch, id) {
                    // Applied to a copy, so that the next one gets fresh ids of its own.
                    Ok((edit, _)) => match edit.clone().apply(&mut scratch) {
                        Ok(_) => ungroups.push(edit),
                        Err(e) => self.message = Some(e),
                    },
                    Err(e) => self.message = Some(e),
                }
            }
            if !ungroups.is_empty() {
                edits.push(GraphEdit::Batch(ungroups));
                self.deselect_all();
            }
        }
        if pressed(Key::G, Modifiers::COMMAND) && !selected.is_empty() {
            match graph_edit::make_group(graph, selected) {
                Ok((edit, _)) => {
                    edits.push(edit);
                    self.deselect_all();
                }
                Err(e) => self.message = Some(e),
            }
        }
        let tab = pressed(Key::Tab, Modifiers::COMMAND);
        if tab {
            self.exit_group();
        } else if pressed(Key::Tab, Modifiers::NONE) {
            let group = selected.iter().find_map(|id| {
                let node = graph.nodes.get(id).filter(|n| n.kind == GROUP)?;
                match node.params.get(GROUP_PARAM) {
                    Some(Param::Text(name)) if graph.groups.contains_key(name) => {
                        Some(name.clone())
                    }
                    _ => None,
                }
            });
            match group {
                Some(name) => self.enter_group(name),
                None => self.exit_group(),
            }
        }
        if any_tab {
            // Tab is the editor's here: no widget keeps the focus it gave.
            ctx.memory_mut(|m| {
                if let Some(id) = m.focused() {
                    m.surrender_focus(id);
                }
                m.move_focus(egui::FocusDirection::None);
            });
        }
        if pressed(Key::J, Modifiers::COMMAND) {
            if let Some((edit, _)) = graph_edit::join_in_frame(graph, selected) {
                edits.push(edit);
            }
        }
        if pressed(Key::P, Modifiers::ALT) {
            edits.extend(graph_edit::remove_from_frames(graph, selected));
        }
        edits
    }
}
