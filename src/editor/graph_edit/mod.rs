//! Edits of a material graph as invertible operations, and the graph facts the node editor
//! needs: each node's sockets with their types, which connections the compiler's type rules
//! accept, fresh node ids, and the automatic layout of nodes that have no position yet.
//!
//! A [`GraphEdit`] applied to a [`Graph`] returns the edit that reverts it, so the document
//! ([`super::document`]) wraps every graph edit in one command with undo/redo for free. An
//! edit that would leave the graph malformed (an unknown node type, a link to a missing
//! socket, a connection between types that do not convert, a cycle) is refused with a
//! message and leaves the graph untouched. Whether the whole graph compiles is the
//! compiler's to say; an edit may leave a graph that does not (a required input left
//! unconnected is still a graph the user is building).
//!
//! Structure has modules of its own: node groups (making, entering as a view, ungrouping,
//! their interface) in [`groups`], frames in [`frames`].
//!
//! Nothing here knows about egui.

mod frames;
mod groups;

use std::collections::{BTreeMap, BTreeSet};

pub use frames::{join_in_frame, remove_from_frames};
pub use groups::{
    GROUP_OUTPUT, GROUP_OUTPUT_ID, add_group_socket, group_view, instances_of, make_group,
    remove_group_socket, ungroup,
};

use crate::material::graph::{
    GROUP, GROUP_INPUT, GROUP_PARAM, REROUTE, REROUTE_INPUT, REROUTE_OUTPUT,
};
use crate::material::nodes::{self, ParamKind};
use crate::material::{Frame, Group, GroupSocket};
use crate::material::{Graph, Input, Link, Node, Param, SocketType};

/// One edit of a material graph.
#[derive(Clone, Debug, PartialEq)]
pub enum GraphEdit {
    /// Adds a node under a new id.
    AddNode { id: String, node: Node },
    /// Removes a node and every link to it.
    RemoveNode { id: String },
    /// Sets what feeds an input: a link (connect), a value, or `None` (the declared
    /// default; disconnect).
    SetInput {
        node: String,
        input: String,
        value: Option<Input>,
    },
    /// Sets a parameter (an enum's option, a flag, ramp stops, a file), or `None` for the
    /// declared default.
    SetParam {
        node: String,
        param: String,
        value: Option<Param>,
    },
    /// Mutes or unmutes a node (Blender's M: its outputs pass its inputs through).
    SetMuted { node: String, muted: bool },
    /// Shows or hides a node's preview image (a view setting saved with the graph, which
    /// renders nothing different).
    SetPreview { node: String, preview: bool },
    /// Sets where nodes are drawn.
    MoveNodes(Vec<(String, Option<[f32; 2]>)>),
    /// Sets which node is the material's output (`None`: the only `material_output`).
    SetOutput(Option<String>),
    /// Adds, replaces or (`None`) removes node group `name`. A group still used by a
    /// node is not removed.
    SetGroup { name: String, group: Option<Group> },
    /// Sets the interface of group `group`: its input and output sockets (names, types,
    /// defaults). What its instances and inner nodes link to it is not touched:
    /// [`remove_group_socket`] unlinks a socket before removing it.
    SetGroupSockets {
        group: String,
        inputs: Vec<GroupSocket>,
        outputs: Vec<GroupSocket>,
    },
    /// Renames an input (or, with `output`, an output) socket of group `group`, and with
    /// it every link and instance input that names it.
    RenameGroupSocket {
        group: String,
        output: bool,
        from: String,
        to: String,
    },
    /// An edit of the nodes inside group `group`, applied to its [`group_view`]: the
    /// group's nodes as a graph, with a `group_input` node giving the interface's inputs
    /// and the [`GROUP_OUTPUT`] node taking its outputs.
    InGroup { group: String, edit: Box<GraphEdit> },
    /// Adds, replaces or (`None`) removes frame `id`.
    SetFrame { id: String, frame: Option<Frame> },
    /// Several edits as one: all are applied or none.
    Batch(Vec<GraphEdit>),
}

impl GraphEdit {
    /// A wire from output `output` of node `from` to input `input` of node `to`.
    pub fn connect(from: &str, output: &str, to: &str, input: &str) -> Self {
        GraphEdit::SetInput {
            node: to.to_owned(),
            input: input.to_owned(),
            value: Some(Input::Link(Link::new(from, output))),
        }
    }

    /// Whether the edit only moves nodes (which changes nothing rendered).
    pub fn only_moves(&self) -> bool {
        match self {
            GraphEdit::MoveNodes(_) => true,
            GraphEdit::InGroup { edit, .. } => edit.only_moves(),
            GraphEdit::Batch(edits) => edits.iter().all(GraphEdit::only_moves),
            _ => false,
        }
    }

    /// Whether the edit changes what the material renders: moves and preview toggles
    /// do not.
    pub fn changes_image(&self) -> bool {
        match self {
            GraphEdit::MoveNodes(_) | GraphEdit::SetPreview { .. } => false,
            GraphEdit::Batch(edits) => edits.iter().any(GraphEdit::changes_image),
            _ => true,
        }
    }

    /// Applies the edit to `graph`; returns the edit that reverts it. A refused edit
    /// leaves `graph` unchanged.
    pub fn apply(self, graph: &mut Graph) -> Result<GraphEdit, String> {
        match self {
            GraphEdit::AddNode { id, node } => {
                if id.is_empty() || id.contains(char::is_whitespace) {
                    return Err(format!("\"{id}\" is not a node id (non-empty, no spaces)"));
                }
                if graph.nodes.contains_key(&id) {
                    return Err(format!("there is already a node \"{id}\""));
                }
                if node.kind == GROUP_OUTPUT {
                    return Err("a group has one output node, made with the group".into());
                }
                sockets_of(graph, &node)?;
                graph.nodes.insert(id.clone(), node);
                Ok(GraphEdit::RemoveNode { id })
            }
            GraphEdit::RemoveNode { id } => {
                if graph.nodes.get(&id).is_some_and(|n| n.kind == GROUP_OUTPUT) {
                    return Err("a group's output node stays while the group does".into());
                }
                let Some(node) = graph.nodes.remove(&id) else {
                    return Err(format!("no node \"{id}\""));
                };
                let mut inverse = vec![GraphEdit::AddNode {
                    id: id.clone(),
                    node,
                }];
                for (other, n) in &mut graph.nodes {
                    let linked: Vec<String> = n
                        .inputs
                        .iter()
                        .filter(|(_, i)| matches!(i, Input::Link(l) if l.node == id))
                        .map(|(name, _)| name.clone())
                        .collect();
                    for input in linked {
                        let value = n.inputs.remove(&input);
                        inverse.push(GraphEdit::SetInput {
                            node: other.clone(),
                            input,
                            value,
                        });
                    }
                }
                if graph.output.as_deref() == Some(id.as_str()) {
                    graph.output = None;
                    inverse.push(GraphEdit::SetOutput(Some(id.clone())));
                }
                // Frames lose the node (and a frame left empty goes).
                for (frame_id, frame) in &mut graph.frames {
                    if frame.nodes.contains(&id) {
                        inverse.push(GraphEdit::SetFrame {
                            id: frame_id.clone(),
                            frame: Some(frame.clone()),
                        });
                        frame.nodes.retain(|n| *n != id);
                    }
                }
                graph.frames.retain(|_, f| !f.nodes.is_empty());
                Ok(if inverse.len() == 1 {
                    inverse.pop().expect("one edit")
                } else {
                    GraphEdit::Batch(inverse)
                })
            }
            GraphEdit::SetInput { node, input, value } => {
                let Some(target) = graph.nodes.get(&node) else {
                    return Err(format!("no node \"{node}\""));
                };
                let sockets = sockets_of(graph, target)?;
                let Some(&(_, to_ty)) = sockets.inputs.iter().find(|(n, _)| *n == input) else {
                    return Err(format!("node \"{node}\" has no input \"{input}\""));
                };
                match &value {
                    Some(Input::Link(link)) => check_link(graph, link, &node, &input, to_ty)?,
                    Some(Input::Value(_)) if target.kind == REROUTE => {
                        return Err(format!(
                            "\"{node}\" is a reroute: it passes a wire on and holds no value"
                        ));
                    }
                    Some(Input::Value(_)) if target.kind == GROUP_OUTPUT => {
                        return Err(format!(
                            "the group's output \"{input}\" takes a wire, not a value"
                        ));
                    }
                    Some(Input::Value(v)) => {
                        let finite = match v {
                            crate::material::Value::Float(x) => x.is_finite(),
                            crate::material::Value::Vec2(a) => a.iter().all(|x| x.is_finite()),
                            crate::material::Value::Vec3(a) => a.iter().all(|x| x.is_finite()),
                        };
                        if !finite {
                            return Err(format!("input \"{input}\" of \"{node}\" must be finite"));
                        }
                        let range = nodes::find(&target.kind)
                            .and_then(|d| d.input(&input))
                            .and_then(|s| s.range);
                        if let (crate::material::Value::Float(x), Some(range)) = (v, range) {
                            if !range.contains(*x) {
                                return Err(format!(
                                    "input \"{input}\" of \"{node}\" takes {}, not {x}",
                                    range.describe()
                                ));
                            }
                        }
                        if to_ty.is_shader() {
                            return Err(format!(
                                "input \"{input}\" of \"{node}\" takes a shader, not a value"
                            ));
                        }
                    }
                    None => {}
                }
                let inputs = &mut graph.nodes.get_mut(&node).expect("checked").inputs;
                let old = match value {
                    Some(v) => inputs.insert(input.clone(), v),
                    None => inputs.remove(&input),
                };
                Ok(GraphEdit::SetInput {
                    node,
                    input,
                    value: old,
                })
            }
            GraphEdit::SetParam { node, param, value } => {
                let Some(target) = graph.nodes.get(&node) else {
                    return Err(format!("no node \"{node}\""));
                };
                check_param(target, &node, &param, value.as_ref())?;
                let params = &mut graph.nodes.get_mut(&node).expect("checked").params;
                let old = match value {
                    Some(v) => params.insert(param.clone(), v),
                    None => params.remove(&param),
                };
                Ok(GraphEdit::SetParam {
                    node,
                    param,
                    value: old,
                })
            }
            GraphEdit::SetMuted { node, muted } => {
                let Some(target) = graph.nodes.get_mut(&node) else {
                    return Err(format!("no node \"{node}\""));
                };
                if muted && matches!(target.kind.as_str(), GROUP_OUTPUT | GROUP_INPUT) {
                    return Err(format!(
                        "\"{node}\" is a group's interface: it cannot be muted"
                    ));
                }
                let old = std::mem::replace(&mut target.muted, muted);
                Ok(GraphEdit::SetMuted { node, muted: old })
            }
            GraphEdit::SetPreview { node, preview } => {
                let Some(target) = graph.nodes.get_mut(&node) else {
                    return Err(format!("no node \"{node}\""));
                };
                let old = std::mem::replace(&mut target.preview, preview);
                Ok(GraphEdit::SetPreview { node, preview: old })
            }
            GraphEdit::MoveNodes(moves) => {
                if let Some((id, _)) = moves.iter().find(|(id, _)| !graph.nodes.contains_key(id)) {
                    return Err(format!("no node \"{id}\""));
                }
                if let Some((id, _)) = moves
                    .iter()
                    .find(|(_, p)| p.is_some_and(|p| !p.iter().all(|x| x.is_finite())))
                {
                    return Err(format!("the position of \"{id}\" must be finite"));
                }
                let mut old = Vec::with_capacity(moves.len());
                for (id, pos) in moves {
                    let node = graph.nodes.get_mut(&id).expect("checked");
                    old.push((id, std::mem::replace(&mut node.position, pos)));
                }
                // Reverting in reverse order restores a node listed twice correctly.
                old.reverse();
                Ok(GraphEdit::MoveNodes(old))
            }
            GraphEdit::SetOutput(output) => {
                if let Some(id) = &output {
                    if !graph.nodes.contains_key(id) {
                        return Err(format!("no node \"{id}\""));
                    }
                }
                Ok(GraphEdit::SetOutput(std::mem::replace(
                    &mut graph.output,
                    output,
                )))
            }
            GraphEdit::SetGroup { name, group } => groups::set_group(graph, name, group),
            GraphEdit::SetGroupSockets {
                group,
                inputs,
                outputs,
            } => groups::set_group_sockets(graph, group, inputs, outputs),
            GraphEdit::RenameGroupSocket {
                group,
                output,
                from,
                to,
            } => groups::rename_group_socket(graph, group, output, from, to),
            GraphEdit::InGroup { group, edit } => {
                let mut view = group_view(graph, &group)?;
                let inverse = edit.apply(&mut view)?;
                groups::store_view(graph, &group, view);
                Ok(GraphEdit::InGroup {
                    group,
                    edit: Box::new(inverse),
                })
            }
            GraphEdit::SetFrame { id, frame } => frames::set_frame(graph, id, frame),
            GraphEdit::Batch(edits) => {
                let mut inverses = Vec::with_capacity(edits.len());
                for edit in edits {
                    match edit.apply(graph) {
                        Ok(inverse) => inverses.push(inverse),
                        Err(e) => {
                            // Undo what was applied, so a refused batch changes nothing.
                            for inverse in inverses.into_iter().rev() {
                                inverse
                                    .apply(graph)
                                    .expect("an inverse restores a state the graph was in");
                            }
                            return Err(e);
                        }
                    }
                }
                inverses.reverse();
                Ok(GraphEdit::Batch(inverses))
            }
        }
    }
}

/// A node's sockets by name and type, in declaration order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sockets {
    pub inputs: Vec<(String, SocketType)>,
    pub outputs: Vec<(String, SocketType)>,
}

/// The sockets of `node` in `graph`: its library declaration's, for a group node its
/// group's interface, for a reroute one input and one output of the type wired into it
/// ([`reroute_type`]; drawn as a float while nothing is). An unknown type or group is an
/// error naming it.
pub fn sockets_of(graph: &Graph, node: &Node) -> Result<Sockets, String> {
    if node.kind == REROUTE {
        let ty = reroute_type(graph, node).unwrap_or(SocketType::Float);
        return Ok(Sockets {
            inputs: vec![(REROUTE_INPUT.to_owned(), ty)],
            outputs: vec![(REROUTE_OUTPUT.to_owned(), ty)],
        });
    }
    if node.kind == GROUP_INPUT || node.kind == GROUP_OUTPUT {
        let Some(interface) = &graph.interface else {
            return Err(format!(
                "a {} node is only meaningful inside a group",
                node.kind
            ));
        };
        let sockets = |list: &[GroupSocket]| named(list.iter().map(|s| (s.name.as_str(), s.ty)));
        return Ok(if node.kind == GROUP_INPUT {
            Sockets {
                inputs: Vec::new(),
                outputs: sockets(&interface.inputs),
            }
        } else {
            Sockets {
                inputs: sockets(&interface.outputs),
                outputs: Vec::new(),
            }
        });
    }
    if node.kind == GROUP {
        let Some(Param::Text(name)) = node.params.get(GROUP_PARAM) else {
            return Err("a group node needs its \"group\" parameter".into());
        };
        let Some(group) = graph.groups.get(name) else {
            return Err(format!("no group \"{name}\""));
        };
        return Ok(Sockets {
            inputs: named(group.inputs.iter().map(|s| (s.name.as_str(), s.ty))),
            outputs: named(group.outputs.iter().map(|s| (s.name.as_str(), s.ty))),
        });
    }
    let Some(def) = nodes::find(&node.kind) else {
        return Err(format!("unknown node type \"{}\"", node.kind));
    };
    Ok(Sockets {
        inputs: named(def.inputs.iter().map(|s| (s.name, s.ty))),
        outputs: named(def.outputs.iter().map(|s| (s.name, s.ty))),
    })
}

fn named<'a>(sockets: impl Iterator<Item = (&'a str, SocketType)>) -> Vec<(String, SocketType)> {
    sockets.map(|(n, t)| (n.to_owned(), t)).collect()
}

/// The type of what is wired into a reroute (through chains of reroutes), or `None` when
/// nothing is: the type its output carries.
pub fn reroute_type(graph: &Graph, node: &Node) -> Option<SocketType> {
    let mut node = node;
    // A chain longer than the graph loops; its type is none.
    for _ in 0..=graph.nodes.len() {
        let Some(Input::Link(link)) = node.inputs.get(REROUTE_INPUT) else {
            return None;
        };
        let source = graph.nodes.get(&link.node)?;
        if source.kind != REROUTE {
            return sockets_of(graph, source)
                .ok()?
                .outputs
                .into_iter()
                .find(|(n, _)| *n == link.socket)
                .map(|(_, t)| t);
        }
        node = source;
    }
    None
}

/// The inputs (node, input, type) that read reroute `id`, through chains of reroutes.
fn reroute_consumers(graph: &Graph, id: &str) -> Vec<(String, String, SocketType)> {
    let mut found = Vec::new();
    let mut seen = BTreeSet::new();
    let mut stack = vec![id.to_owned()];
    while let Some(reroute) = stack.pop() {
        if !seen.insert(reroute.clone()) {
            continue;
        }
        for (other, n) in &graph.nodes {
            for (input, value) in &n.inputs {
                if !matches!(value, Input::Link(l) if l.node == reroute) {
                    continue;
                }
                if n.kind == REROUTE {
                    stack.push(other.clone());
                } else if let Some((_, ty)) = sockets_of(graph, n)
                    .ok()
                    .and_then(|s| s.inputs.into_iter().find(|(name, _)| name == input))
                {
                    found.push((other.clone(), input.clone(), ty));
                }
            }
        }
    }
    found
}

/// Why a wire from `link` into input `input` (of type `to_ty`) of node `node` is refused,
/// if it is: a missing node or socket, types the compiler does not convert, or a cycle.
/// Through reroutes the types checked are the real ones: what a reroute's source feeds
/// (an unconnected reroute feeds any input its default), and every input a reroute feeds.
fn check_link(
    graph: &Graph,
    link: &Link,
    node: &str,
    input: &str,
    to_ty: SocketType,
) -> Result<(), String> {
    let Some(source) = graph.nodes.get(&link.node) else {
        return Err(format!("no node \"{}\"", link.node));
    };
    let from_ty = sockets_of(graph, source)?
        .outputs
        .iter()
        .find(|(n, _)| *n == link.socket)
        .map(|&(_, t)| t)
        .ok_or_else(|| format!("node \"{}\" has no output \"{}\"", link.node, link.socket))?;
    let from_ty = if source.kind == REROUTE {
        reroute_type(graph, source)
    } else {
        Some(from_ty)
    };
    let targets = match graph.nodes.get(node) {
        Some(n) if n.kind == REROUTE => reroute_consumers(graph, node),
        _ => vec![(node.to_owned(), input.to_owned(), to_ty)],
    };
    for (node, input, to_ty) in targets {
        let Some(from_ty) = from_ty else { break };
        if from_ty.converts_to(to_ty).is_none() {
            return Err(format!(
                "cannot connect {} output \"{}\" of \"{}\" to {} input \"{input}\" of \"{node}\": a {} does not convert to a {}",
                from_ty.name(),
                link.socket,
                link.node,
                to_ty.name(),
                from_ty.name(),
                to_ty.name(),
            ));
        }
    }
    if link.node == node || depends_on(graph, &link.node, node) {
        return Err(format!(
            "connecting \"{}\" to \"{node}\" would make a cycle",
            link.node
        ));
    }
    Ok(())
}

/// Whether node `from` reads (through any chain of links) the output of node `on`.
pub fn depends_on(graph: &Graph, from: &str, on: &str) -> bool {
    let mut seen = BTreeSet::new();
    let mut stack = vec![from];
    while let Some(id) = stack.pop() {
        if id == on {
            return true;
        }
        if !seen.insert(id) {
            continue;
        }
        if let Some(node) = graph.nodes.get(id) {
            for input in node.inputs.values() {
                if let Input::Link(l) = input {
                    stack.push(l.node.as_str());
                }
            }
        }
    }
    false
}

/// Whether `value` fits parameter `param` of `node` (id `id`) as declared.
fn check_param(node: &Node, id: &str, param: &str, value: Option<&Param>) -> Result<(), String> {
    if node.kind == GROUP {
        return match value {
            Some(Param::Text(_)) | None if param == GROUP_PARAM => Ok(()),
            _ => Err(format!("group node \"{id}\" has no parameter \"{param}\"")),
        };
    }
    let Some(def) = nodes::find(&node.kind) else {
        return Err(format!("unknown node type \"{}\"", node.kind));
    };
    let Some(decl) = def.param(param) else {
        return Err(format!("node \"{id}\" has no parameter \"{param}\""));
    };
    let Some(value) = value else {
        return Ok(());
    };
    let fits = match (&decl.kind, value) {
        (ParamKind::Enum(options), Param::Text(t)) => options.contains(&t.as_str()),
        (ParamKind::Bool(_), Param::Bool(_)) => true,
        (ParamKind::Ramp, Param::Ramp(stops)) => !stops.is_empty(),
        (ParamKind::File, Param::Text(_)) => true,
        _ => false,
    };
    if fits {
        Ok(())
    } else {
        Err(format!(
            "parameter \"{param}\" of \"{id}\" cannot be {value:?}{}",
            match &decl.kind {
                ParamKind::Enum(options) => format!(" (one of {})", options.join(", ")),
                _ => String::new(),
            }
        ))
    }
}

/// An id for a new node of type `kind` not used in `graph`: the type's name, then with
/// `_2`, `_3`… (ids are what links name, so they stay plain words).
pub fn fresh_id(graph: &Graph, kind: &str) -> String {
    let base = kind.replace(|c: char| !c.is_ascii_alphanumeric() && c != '_', "_");
    if !graph.nodes.contains_key(&base) {
        return base;
    }
    (2..)
        .map(|n| format!("{base}_{n}"))
        .find(|id| !graph.nodes.contains_key(id))
        .expect("a free id exists")
}

/// The width the layout gives every node (snarl sizes nodes to their contents; the layout
/// only needs an upper bound of common nodes).
pub const NODE_WIDTH: f32 = 220.0;
/// The gap between layout columns and between nodes of a column.
pub const LAYOUT_GAP: f32 = 60.0;

/// The height the layout reserves for a node: its header, one row per socket and
/// parameter.
pub fn estimated_height(graph: &Graph, node: &Node) -> f32 {
    let sockets = sockets_of(graph, node).unwrap_or_default();
    let rows = sockets.inputs.len().max(sockets.outputs.len()) + node_param_rows(node);
    36.0 + 26.0 * rows as f32
}

/// The width the layout reserves for a node: the widest of its title and its rows (an
/// input's label and inline value, the parameters' column snarl draws between inputs and
/// outputs, an output's label). Snarl sizes nodes to their contents; this errs wide so
/// that laid-out columns never overlap.
pub fn estimated_width(graph: &Graph, node: &Node) -> f32 {
    const CHAR: f32 = 8.0;
    // An inline value (a number field, a colour swatch) and the pin's margins.
    const WIDGET: f32 = 90.0;
    let sockets = sockets_of(graph, node).unwrap_or_default();
    let label = |names: &[(String, SocketType)]| {
        names
            .iter()
            .map(|(n, _)| n.chars().count())
            .max()
            .unwrap_or(0) as f32
            * CHAR
    };
    let title = (node.kind.chars().count() + 12) as f32 * CHAR;
    // The parameters sit in a column between the inputs and the outputs.
    let body = nodes::find(&node.kind).map_or(0.0, |d| {
        d.params
            .iter()
            .map(|p| match &p.kind {
                // The name, and a dropdown as wide as its longest option.
                nodes::ParamKind::Enum(options) => {
                    let longest = options.iter().map(|o| o.chars().count()).max();
                    (p.name.chars().count() + longest.unwrap_or(0)) as f32 * CHAR + 50.0
                }
                nodes::ParamKind::Bool(_) => p.name.chars().count() as f32 * CHAR + 30.0,
                // The ramp editor's row of the selected stop.
                nodes::ParamKind::Ramp => 240.0,
                // A file name and the button to pick another.
                nodes::ParamKind::File => 260.0,
            })
            .fold(0.0, f32::max)
    });
    let rows = label(&sockets.inputs) + WIDGET + body + label(&sockets.outputs) + 40.0;
    title.max(rows).max(NODE_WIDTH)
}

/// The rows a node's parameters take (a ramp editor four: its name, its bar and markers,
/// its stop's fields).
fn node_param_rows(node: &Node) -> usize {
    nodes::find(&node.kind).map_or(node.params.len(), |d| {
        d.params
            .iter()
            .map(|p| match p.kind {
                nodes::ParamKind::Ramp => 4,
                _ => 1,
            })
            .sum()
    })
}

/// Where every node of `graph` is drawn: its saved position, or for nodes without one an
/// automatic layout that reads left to right (each node a column left of the nodes that
/// read it, the output rightmost), stacked without overlaps below any positioned nodes.
/// Deterministic: the same graph always gets the same layout.
pub fn layout(graph: &Graph) -> BTreeMap<String, [f32; 2]> {
    let mut out: BTreeMap<String, [f32; 2]> = graph
        .nodes
        .iter()
        .filter_map(|(id, n)| n.position.map(|p| (id.clone(), p)))
        .collect();
    let unplaced: Vec<&String> = graph
        .nodes
        .iter()
        .filter(|(_, n)| n.position.is_none())
        .map(|(id, _)| id)
        .collect();
    if unplaced.is_empty() {
        return out;
    }
    // Column of a node: the longest chain of links from it to a node nothing reads. At
    // most one pass per node, so a cycle (which the compiler reports) cannot loop.
    let mut readers: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for (id, node) in &graph.nodes {
        for input in node.inputs.values() {
            if let Input::Link(l) = input {
                if graph.nodes.contains_key(&l.node) {
                    readers.entry(l.node.as_str()).or_default().push(id);
                }
            }
        }
    }
    let mut column: BTreeMap<&str, usize> = graph.nodes.keys().map(|k| (k.as_str(), 0)).collect();
    for _ in 0..graph.nodes.len() {
        let mut changed = false;
        for (id, rs) in &readers {
            let depth = rs.iter().map(|r| column[r] + 1).max().unwrap_or(0);
            if depth > column[id] && depth < graph.nodes.len() {
                column.insert(*id, depth);
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    let top = out.values().map(|p| p[1]).fold(f32::NEG_INFINITY, f32::max);
    let bottom = graph
        .nodes
        .values()
        .filter_map(|n| n.position.map(|p| p[1] + estimated_height(graph, n)))
        .fold(f32::NEG_INFINITY, f32::max);
    let start_y = if top.is_finite() {
        bottom + LAYOUT_GAP
    } else {
        0.0
    };
    let columns = unplaced
        .iter()
        .map(|id| column[id.as_str()])
        .max()
        .unwrap_or(0);
    // Each column as wide as its widest node; column `columns` is the leftmost.
    let widths: Vec<f32> = (0..=columns)
        .map(|c| {
            unplaced
                .iter()
                .filter(|id| column[id.as_str()] == c)
                .map(|id| estimated_width(graph, &graph.nodes[id.as_str()]))
                .fold(NODE_WIDTH, f32::max)
        })
        .collect();
    let column_x = |c: usize| -> f32 { widths[c + 1..].iter().map(|w| w + LAYOUT_GAP).sum() };
    // Within a column, nodes follow the order of the first node that reads them, so wires
    // cross less; ties by id.
    let mut rank: BTreeMap<&str, usize> = BTreeMap::new();
    for c in 0..=columns {
        let mut ids: Vec<&str> = unplaced
            .iter()
            .map(|s| s.as_str())
            .filter(|id| column[id] == c)
            .collect();
        ids.sort_by_key(|id| {
            let reader = readers
                .get(id)
                .and_then(|rs| rs.iter().filter_map(|r| rank.get(r)).min().copied())
                .unwrap_or(usize::MAX);
            (reader, id.to_string())
        });
        let mut y = start_y;
        for (i, id) in ids.iter().enumerate() {
            rank.insert(*id, i);
            let x = column_x(c);
            out.insert(id.to_string(), [x, y]);
            y += estimated_height(graph, &graph.nodes[*id]) + LAYOUT_GAP / 2.0;
        }
    }
    out
}

/// The edit that gives every node without a position its [`layout`] position, so that a
/// graph once laid out keeps that layout when saved.
pub fn fix_layout(graph: &Graph) -> Vec<(String, Option<[f32; 2]>)> {
    let laid = layout(graph);
    graph
        .nodes
        .iter()
        .filter(|(_, n)| n.position.is_none())
        .map(|(id, _)| (id.clone(), laid.get(id).copied()))
        .collect()
}

/// The nodes `nodes` of `graph` (but a group's output node) copied under fresh ids, offset by `offset`, with the links
/// among them kept and links to nodes outside dropped. What paste and duplicate add.
pub fn copies(
    graph: &Graph,
    nodes: &[(String, Node)],
    offset: [f32; 2],
) -> (Vec<GraphEdit>, Vec<String>) {
    // A group's output node is one per group: it is not copied.
    let nodes: Vec<(String, Node)> = nodes
        .iter()
        .filter(|(_, n)| n.kind != GROUP_OUTPUT)
        .cloned()
        .collect();
    let nodes = nodes.as_slice();
    let mut scratch = graph.clone();
    let mut renamed = BTreeMap::new();
    for (id, node) in nodes {
        let new = fresh_id(&scratch, &node.kind);
        scratch.nodes.insert(new.clone(), node.clone());
        renamed.insert(id.clone(), new);
    }
    let laid = layout(graph);
    let mut edits = Vec::new();
    let mut ids = Vec::new();
    for (id, node) in nodes {
        let mut node = node.clone();
        node.inputs.retain(|_, input| match input {
            Input::Link(l) => renamed.contains_key(&l.node),
            Input::Value(_) => true,
        });
        for input in node.inputs.values_mut() {
            if let Input::Link(l) = input {
                l.node = renamed[&l.node].clone();
            }
        }
        let base = node
            .position
            .or_else(|| laid.get(id).copied())
            .unwrap_or([0.0, 0.0]);
        node.position = Some([base[0] + offset[0], base[1] + offset[1]]);
        ids.push(renamed[id].clone());
        edits.push(GraphEdit::AddNode {
            id: renamed[id].clone(),
            node,
        });
    }
    (edits, ids)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Value;

    fn marble() -> Graph {
        crate::material::parse_material(
            include_str!("../../../assets/materials/marble.kmat"),
            "marble.kmat",
        )
        .expect("the bundled marble parses")
        .1
    }

    #[test]
    fn every_edit_reverts_to_the_graph_it_started_from() {
        let start = marble();
        let mut g = start.clone();
        let edits = vec![
            GraphEdit::AddNode {
                id: "noise".into(),
                node: Node::new("noise_texture"),
            },
            GraphEdit::connect("noise", "color", "surface", "base_color"),
            GraphEdit::SetInput {
                node: "noise".into(),
                input: "scale".into(),
                value: Some(Input::Value(Value::Float(12.0))),
            },
            GraphEdit::SetParam {
                node: "veins".into(),
                param: "direction".into(),
                value: Some(Param::Text("x".into())),
            },
            GraphEdit::MoveNodes(vec![("noise".into(), Some([10.0, 20.0]))]),
            GraphEdit::RemoveNode { id: "ramp".into() },
        ];
        let mut inverses = Vec::new();
        for edit in edits {
            inverses.push(
                edit.clone()
                    .apply(&mut g)
                    .unwrap_or_else(|e| panic!("{edit:?}: {e}")),
            );
        }
        assert!(!g.nodes.contains_key("ramp"));
        assert!(
            !g.nodes["surface"].inputs.contains_key("base_color")
                || {
                    matches!(&g.nodes["surface"].inputs["base_color"], Input::Link(l) if l.node == "noise")
                }
        );
        for inverse in inverses.into_iter().rev() {
            inverse.apply(&mut g).unwrap();
        }
        assert_eq!(g, start);
    }

    #[test]
    fn a_colour_into_a_shader_input_is_refused_with_the_types_named() {
        let mut g = marble();
        let before = g.clone();
        let err = GraphEdit::connect("ramp", "color", "out", "surface")
            .apply(&mut g)
            .unwrap_err();
        assert!(err.contains("color") && err.contains("bsdf"), "{err}");
        assert_eq!(g, before);
    }

    #[test]
    fn implicit_conversions_are_accepted_and_cycles_refused() {
        let mut g = marble();
        // colour → float (luminance), as the compiler converts it.
        GraphEdit::connect("ramp", "color", "surface", "roughness")
            .apply(&mut g)
            .unwrap();
        let err = GraphEdit::connect("ramp", "alpha", "veins", "scale")
            .apply(&mut g)
            .unwrap_err();
        assert!(err.contains("cycle"), "{err}");
    }

    #[test]
    fn a_refused_batch_changes_nothing() {
        let mut g = marble();
        let before = g.clone();
        let err = GraphEdit::Batch(vec![
            GraphEdit::RemoveNode { id: "ramp".into() },
            GraphEdit::RemoveNode { id: "ramp".into() },
        ])
        .apply(&mut g)
        .unwrap_err();
        assert!(err.contains("ramp"), "{err}");
        assert_eq!(g, before);
    }

    #[test]
    fn a_value_outside_the_declared_range_is_refused() {
        let mut g = marble();
        g.add("noise", Node::new("noise_texture"));
        let before = g.clone();
        let set = |x: f32| GraphEdit::SetInput {
            node: "noise".into(),
            input: "scale".into(),
            value: Some(Input::Value(Value::Float(x))),
        };
        let e = set(-0.5).apply(&mut g).unwrap_err();
        assert!(e.contains("scale") && e.contains("[0, 1000]"), "{e}");
        assert_eq!(g, before);
        set(0.0).apply(&mut g).unwrap();
    }

    #[test]
    fn muting_is_one_edit_that_reverts() {
        let mut g = marble();
        let before = g.clone();
        let inverse = GraphEdit::SetMuted {
            node: "ramp".into(),
            muted: true,
        }
        .apply(&mut g)
        .unwrap();
        assert!(g.nodes["ramp"].muted);
        inverse.apply(&mut g).unwrap();
        assert_eq!(g, before);
    }

    #[test]
    fn a_preview_toggle_is_one_edit_that_reverts_and_changes_no_image() {
        let mut g = marble();
        let before = g.clone();
        let edit = GraphEdit::SetPreview {
            node: "ramp".into(),
            preview: true,
        };
        assert!(!edit.changes_image());
        let inverse = edit.apply(&mut g).unwrap();
        assert!(g.nodes["ramp"].preview);
        assert!(g.same_but_layout(&before), "a preview computes nothing");
        inverse.apply(&mut g).unwrap();
        assert_eq!(g, before);
        let missing = GraphEdit::SetPreview {
            node: "nowhere".into(),
            preview: true,
        };
        assert!(missing.apply(&mut g).unwrap_err().contains("nowhere"));
    }

    #[test]
    fn a_reroute_carries_the_type_wired_into_it() {
        let mut g = marble();
        g.add("reroute", Node::new(REROUTE));
        // Unconnected, it takes any wire and feeds any input (its consumers' defaults).
        GraphEdit::connect("reroute", REROUTE_OUTPUT, "surface", "roughness")
            .apply(&mut g)
            .unwrap();
        GraphEdit::connect("ramp", "alpha", "reroute", REROUTE_INPUT)
            .apply(&mut g)
            .unwrap();
        assert_eq!(
            sockets_of(&g, &g.nodes["reroute"]).unwrap().outputs,
            vec![(REROUTE_OUTPUT.to_owned(), SocketType::Float)]
        );
        // Its type is its source's: a float through it into a shader input is refused,
        // and so is a source that its consumers cannot take.
        let e = GraphEdit::connect("reroute", REROUTE_OUTPUT, "out", "surface")
            .apply(&mut g)
            .unwrap_err();
        assert!(e.contains("float") && e.contains("bsdf"), "{e}");
        GraphEdit::connect("reroute", REROUTE_OUTPUT, "surface", "roughness")
            .apply(&mut g)
            .unwrap();
        let e = GraphEdit::connect("surface", "bsdf", "reroute", REROUTE_INPUT)
            .apply(&mut g)
            .unwrap_err();
        assert!(e.contains("roughness"), "{e}");
        // It holds no value.
        let e = GraphEdit::SetInput {
            node: "reroute".into(),
            input: REROUTE_INPUT.into(),
            value: Some(Input::Value(Value::Float(1.0))),
        }
        .apply(&mut g)
        .unwrap_err();
        assert!(e.contains("reroute"), "{e}");
        assert!(crate::material::compile("m", &g, "material_0").is_ok());
    }

    #[test]
    fn bad_parameters_and_unknown_nodes_are_refused() {
        let mut g = marble();
        let e = GraphEdit::SetParam {
            node: "veins".into(),
            param: "direction".into(),
            value: Some(Param::Text("sideways".into())),
        }
        .apply(&mut g)
        .unwrap_err();
        assert!(e.contains("one of"), "{e}");
        let e = GraphEdit::AddNode {
            id: "x".into(),
            node: Node::new("no_such_node"),
        }
        .apply(&mut g)
        .unwrap_err();
        assert!(e.contains("no_such_node"), "{e}");
    }

    #[test]
    fn fresh_ids_do_not_collide() {
        let mut g = marble();
        assert_eq!(fresh_id(&g, "noise_texture"), "noise_texture");
        g.add("noise_texture", Node::new("noise_texture"));
        assert_eq!(fresh_id(&g, "noise_texture"), "noise_texture_2");
    }

    #[test]
    fn the_layout_reads_left_to_right_without_overlaps() {
        let g = marble();
        let laid = layout(&g);
        assert_eq!(laid.len(), g.nodes.len());
        assert!(laid["coords"][0] < laid["veins"][0]);
        assert!(laid["veins"][0] < laid["ramp"][0]);
        assert!(laid["surface"][0] < laid["out"][0]);
        assert!(overlaps(&g, &laid).is_none());
        assert_eq!(layout(&g), laid, "deterministic");
    }

    /// Two nodes whose layout boxes overlap, if any.
    pub(crate) fn overlaps(
        g: &Graph,
        laid: &BTreeMap<String, [f32; 2]>,
    ) -> Option<(String, String)> {
        let boxes: Vec<(&String, [f32; 4])> = laid
            .iter()
            .map(|(id, p)| {
                let h = estimated_height(g, &g.nodes[id]);
                let w = estimated_width(g, &g.nodes[id]);
                (id, [p[0], p[1], p[0] + w, p[1] + h])
            })
            .collect();
        for (i, (a, ra)) in boxes.iter().enumerate() {
            for (b, rb) in &boxes[i + 1..] {
                if ra[0] < rb[2] && rb[0] < ra[2] && ra[1] < rb[3] && rb[1] < ra[3] {
                    return Some(((*a).clone(), (*b).clone()));
                }
            }
        }
        None
    }

    #[test]
    fn every_bundled_material_lays_out_without_overlaps() {
        for entry in
            std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/materials")).unwrap()
        {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "kmat") {
                continue;
            }
            let (_, g) = crate::material::load_material(&path).unwrap();
            let laid = layout(&g);
            assert_eq!(laid.len(), g.nodes.len(), "{}", path.display());
            assert_eq!(overlaps(&g, &laid), None, "{}", path.display());
        }
    }

    #[test]
    fn copies_keep_links_among_themselves_only() {
        let g = marble();
        let picked: Vec<(String, Node)> = ["veins", "ramp"]
            .iter()
            .map(|id| (id.to_string(), g.nodes[*id].clone()))
            .collect();
        let (edits, ids) = copies(&g, &picked, [30.0, 30.0]);
        assert_eq!(ids, ["wave_texture", "color_ramp"]);
        let mut h = g.clone();
        GraphEdit::Batch(edits).apply(&mut h).unwrap();
        let ramp = &h.nodes["color_ramp"];
        assert_eq!(
            ramp.inputs["fac"],
            Input::Link(Link::new("wave_texture", "fac"))
        );
        assert!(!h.nodes["wave_texture"].inputs.contains_key("vector"));
    }

    #[test]
    fn every_bundled_material_saves_byte_identical_after_a_layout() {
        let dir = tempfile::tempdir().unwrap();
        for entry in
            std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/materials")).unwrap()
        {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "kmat") {
                continue;
            }
            let (name, mut g) = crate::material::load_material(&path).unwrap();
            // What the editor saves once the user moved a node: every position laid out.
            GraphEdit::MoveNodes(fix_layout(&g)).apply(&mut g).unwrap();
            let out = dir.path().join(path.file_name().unwrap());
            crate::material::save_material(&out, &name, &g).unwrap();
            let first = std::fs::read(&out).unwrap();
            let (name2, g2) = crate::material::load_material(&out).unwrap();
            assert_eq!((&name2, &g2), (&name, &g), "{}", path.display());
            crate::material::save_material(&out, &name2, &g2).unwrap();
            assert_eq!(std::fs::read(&out).unwrap(), first, "{}", path.display());
        }
    }

    mod random_edits {
        use super::*;
        use crate::editor::document::{Command, Document};
        use proptest::prelude::*;

        /// One user action, with numbers picking what it applies to in the graph of the
        /// moment.
        #[derive(Clone, Debug)]
        enum Action {
            Add(usize),
            Remove(usize),
            Connect(usize, usize, usize, usize),
            Disconnect(usize, usize),
            SetValue(usize, usize, f32),
            Move(usize, f32, f32),
            Mute(usize),
            /// Ctrl+G on two nodes.
            Group(usize, usize),
            /// Ctrl+Alt+G on a node (refused unless a group node).
            Ungroup(usize),
            /// A value set on a node inside a group.
            SetInGroup(usize, usize, usize, f32),
            /// Ctrl+J on two nodes.
            Frame(usize, usize),
            Undo,
            Redo,
        }

        fn action() -> impl Strategy<Value = Action> {
            let n = 0usize..64;
            prop_oneof![
                n.clone().prop_map(Action::Add),
                n.clone().prop_map(Action::Remove),
                (n.clone(), n.clone(), n.clone(), n.clone())
                    .prop_map(|(a, b, c, d)| Action::Connect(a, b, c, d)),
                (n.clone(), n.clone()).prop_map(|(a, b)| Action::Disconnect(a, b)),
                (n.clone(), n.clone(), -10.0f32..10.0)
                    .prop_map(|(a, b, v)| Action::SetValue(a, b, v)),
                (n.clone(), -500.0f32..500.0, -500.0f32..500.0)
                    .prop_map(|(a, x, y)| Action::Move(a, x, y)),
                n.clone().prop_map(Action::Mute),
                (n.clone(), n.clone()).prop_map(|(a, b)| Action::Group(a, b)),
                n.clone().prop_map(Action::Ungroup),
                (n.clone(), n.clone(), n.clone(), -10.0f32..10.0)
                    .prop_map(|(g, a, b, v)| Action::SetInGroup(g, a, b, v)),
                (n.clone(), n.clone()).prop_map(|(a, b)| Action::Frame(a, b)),
                Just(Action::Undo),
                Just(Action::Redo),
            ]
        }

        fn pick<T: Clone>(items: &[T], i: usize) -> Option<T> {
            (!items.is_empty()).then(|| items[i % items.len()].clone())
        }

        fn edit_for(g: &Graph, action: &Action) -> Option<GraphEdit> {
            let ids: Vec<String> = g.nodes.keys().cloned().collect();
            let sockets = |id: &str| sockets_of(g, &g.nodes[id]).unwrap_or_default();
            Some(match *action {
                Action::Add(k) => {
                    // The library's nodes and reroutes.
                    let kinds: Vec<&str> = nodes::library()
                        .iter()
                        .map(|d| d.kind)
                        .chain([REROUTE])
                        .collect();
                    let kind = pick(&kinds, k)?;
                    GraphEdit::AddNode {
                        id: fresh_id(g, kind),
                        node: Node::new(kind),
                    }
                }
                Action::Mute(a) => {
                    let node = pick(&ids, a)?;
                    GraphEdit::SetMuted {
                        muted: !g.nodes[&node].muted,
                        node,
                    }
                }
                Action::Remove(a) => GraphEdit::RemoveNode { id: pick(&ids, a)? },
                Action::Connect(a, b, c, d) => {
                    let from = pick(&ids, a)?;
                    let to = pick(&ids, c)?;
                    let (output, _) = pick(&sockets(&from).outputs, b)?;
                    let (input, _) = pick(&sockets(&to).inputs, d)?;
                    GraphEdit::connect(&from, &output, &to, &input)
                }
                Action::Disconnect(a, b) => {
                    let node = pick(&ids, a)?;
                    let (input, _) = pick(&sockets(&node).inputs, b)?;
                    GraphEdit::SetInput {
                        node,
                        input,
                        value: None,
                    }
                }
                Action::SetValue(a, b, v) => {
                    let node = pick(&ids, a)?;
                    let (input, _) = pick(&sockets(&node).inputs, b)?;
                    GraphEdit::SetInput {
                        node,
                        input,
                        value: Some(Input::Value(Value::Float(v))),
                    }
                }
                Action::Move(a, x, y) => GraphEdit::MoveNodes(vec![(pick(&ids, a)?, Some([x, y]))]),
                Action::Group(a, b) => make_group(g, &[pick(&ids, a)?, pick(&ids, b)?]).ok()?.0,
                Action::Ungroup(a) => ungroup(g, &pick(&ids, a)?).ok()?.0,
                Action::SetInGroup(k, a, b, v) => {
                    let names: Vec<String> = g.groups.keys().cloned().collect();
                    let group = pick(&names, k)?;
                    let view = group_view(g, &group).ok()?;
                    let inner: Vec<String> = view.nodes.keys().cloned().collect();
                    let node = pick(&inner, a)?;
                    let inputs = sockets_of(&view, &view.nodes[&node]).ok()?.inputs;
                    let (input, _) = pick(&inputs, b)?;
                    GraphEdit::InGroup {
                        group,
                        edit: Box::new(GraphEdit::SetInput {
                            node,
                            input,
                            value: Some(Input::Value(Value::Float(v))),
                        }),
                    }
                }
                Action::Frame(a, b) => join_in_frame(g, &[pick(&ids, a)?, pick(&ids, b)?])?.0,
                Action::Undo | Action::Redo => return None,
            })
        }

        proptest! {
            #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

            /// Random edits through the document never panic; a graph that does not
            /// compile always carries its error for the node editor to show; undoing
            /// everything returns the starting graph.
            #[test]
            fn random_graph_edits_keep_the_document_consistent(
                actions in proptest::collection::vec(action(), 1..24)
            ) {
                let scene = crate::scene::default_scene().expect("the bundled scene loads");
                let mut doc = Document::new(scene, None, Vec::new());
                let material = 0;
                let start = doc.material_graph(material).unwrap();
                for action in &actions {
                    match action {
                        Action::Undo => { doc.undo(); }
                        Action::Redo => { doc.redo(); }
                        _ => {
                            let g = doc.material_graph(material).unwrap();
                            if let Some(edit) = edit_for(&g, action) {
                                let _ = doc.apply(Command::EditGraph { material, edit }, None);
                            }
                        }
                    }
                    let g = doc.material_graph(material).unwrap();
                    let compiles = crate::material::compile("m", &g, "m").is_ok();
                    prop_assert!(compiles || doc.graph_error(material).is_some(),
                        "a graph that does not compile shows its error");
                }
                while doc.undo() {}
                prop_assert_eq!(doc.material_graph(material).unwrap(), start);
            }
        }
    }
}
