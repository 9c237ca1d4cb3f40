//! Node groups in the editor: making one from selected nodes (Blender's Ctrl+G),
//! ungrouping an instance (Ctrl+Alt+G), editing a group's insides, and its interface.
//!
//! Inside, a group is edited as a graph of its own, its [`group_view`]: the group's nodes
//! plus an output node of type [`GROUP_OUTPUT`] standing for `Group::links` (Blender's
//! Group Output; files have no such node), with the group's interface set on the view so
//! that `group_input` nodes have their outputs and the output node its inputs. Every
//! [`GraphEdit`] works on a view as on a material, wrapped in [`GraphEdit::InGroup`], which
//! writes the view back ([`store_view`]).
//!
//! Making a group and ungrouping keep what the material computes: the compiler flattens
//! groups, and these edits move the same nodes and links across the group's boundary
//! (an exposed socket takes the type of the output it passes on, so every conversion
//! happens where it did).

use std::collections::{BTreeMap, BTreeSet};

use super::{
    GraphEdit, LAYOUT_GAP, NODE_WIDTH, estimated_height, estimated_width, fix_layout, fresh_id,
    layout, reroute_type, sockets_of,
};
use crate::material::graph::{GROUP, GROUP_INPUT, GROUP_PARAM, REROUTE};
use crate::material::nodes::MATERIAL_OUTPUT;
use crate::material::{
    Graph, Group, GroupInterface, GroupSocket, Input, Link, Node, Param, SocketType,
};

/// The node type of a group view's output node: one input per exposed output, wired to
/// what computes it.
pub const GROUP_OUTPUT: &str = "group_output";
/// The id of a group view's output node. It has a space, which the ids of added nodes
/// never have ([`GraphEdit::AddNode`] refuses them), so it names no node of the group.
pub const GROUP_OUTPUT_ID: &str = "Group Output";

/// The nodes of group `name` as a graph to edit: its nodes, the output node standing for
/// its links, its frames, and its interface (see the module's documentation).
pub fn group_view(graph: &Graph, name: &str) -> Result<Graph, String> {
    let group = graph
        .groups
        .get(name)
        .ok_or_else(|| format!("no group \"{name}\""))?;
    let mut nodes = group.nodes.clone();
    let mut output = Node::new(GROUP_OUTPUT);
    output.inputs = (group.links.iter())
        .map(|(socket, link)| (socket.clone(), Input::Link(link.clone())))
        .collect();
    output.position = group.output_position;
    nodes.insert(GROUP_OUTPUT_ID.to_owned(), output);
    Ok(Graph {
        nodes,
        groups: graph.groups.clone(),
        output: None,
        frames: group.frames.clone(),
        interface: Some(GroupInterface {
            inputs: group.inputs.clone(),
            outputs: group.outputs.clone(),
        }),
    })
}

/// Writes `view`, a [`group_view`] of group `name` after edits, back into `graph`.
pub(super) fn store_view(graph: &mut Graph, name: &str, mut view: Graph) {
    let output = (view.nodes.remove(GROUP_OUTPUT_ID)).unwrap_or_else(|| Node::new(GROUP_OUTPUT));
    // Groups the edit added (a group made inside this one) live beside it.
    graph.groups = std::mem::take(&mut view.groups);
    let group = graph.groups.entry(name.to_owned()).or_default();
    group.nodes = view.nodes;
    group.frames = view.frames;
    group.output_position = output.position;
    group.links = (output.inputs.into_iter())
        .filter_map(|(socket, input)| match input {
            Input::Link(link) => Some((socket, link)),
            Input::Value(_) => None,
        })
        .collect();
}

/// Whether `node` is an instance of group `name`.
fn is_instance(node: &Node, name: &str) -> bool {
    node.kind == GROUP && matches!(node.params.get(GROUP_PARAM), Some(Param::Text(n)) if n == name)
}

/// Every node using group `name`: the group it sits in (`None`: the material) and its id.
pub fn instances_of(graph: &Graph, name: &str) -> Vec<(Option<String>, String)> {
    let scopes = std::iter::once((None, &graph.nodes))
        .chain((graph.groups.iter()).map(|(group, g)| (Some(group.clone()), &g.nodes)));
    scopes
        .flat_map(|(scope, nodes)| {
            (nodes.iter())
                .filter(|(_, n)| is_instance(n, name))
                .map(move |(id, _)| (scope.clone(), id.clone()))
        })
        .collect()
}

/// `edit` of the nodes of `scope`: the material's, or a group's.
fn in_scope(scope: &Option<String>, edit: GraphEdit) -> GraphEdit {
    match scope {
        None => edit,
        Some(group) => GraphEdit::InGroup {
            group: group.clone(),
            edit: Box::new(edit),
        },
    }
}

/// Applies [`GraphEdit::SetGroup`].
pub(super) fn set_group(
    graph: &mut Graph,
    name: String,
    group: Option<Group>,
) -> Result<GraphEdit, String> {
    if name.trim().is_empty() {
        return Err("a group needs a name".into());
    }
    let old = match group {
        Some(group) => {
            check_sockets(&name, &group.inputs, "input")?;
            check_sockets(&name, &group.outputs, "output")?;
            graph.groups.insert(name.clone(), group)
        }
        None => {
            if let Some((scope, id)) = instances_of(graph, &name).into_iter().next() {
                let inside = scope.map_or(String::new(), |g| format!(" in group \"{g}\""));
                return Err(format!("group \"{name}\" is used by node \"{id}\"{inside}"));
            }
            match graph.groups.remove(&name) {
                Some(old) => Some(old),
                None => return Err(format!("no group \"{name}\"")),
            }
        }
    };
    Ok(GraphEdit::SetGroup { name, group: old })
}

/// Why a socket name cannot be one, if it cannot: links are written `"node.socket"` and
/// split at the last dot, so a socket's name has none.
fn check_socket_name(group: &str, name: &str) -> Result<(), String> {
    if name.trim().is_empty() || name.contains('.') {
        return Err(format!(
            "group \"{group}\": \"{name}\" is not a socket name (not empty, no dots)"
        ));
    }
    Ok(())
}

/// Why a group's list of sockets (`side`: "input" or "output") is refused, if it is.
fn check_sockets(group: &str, sockets: &[GroupSocket], side: &str) -> Result<(), String> {
    let mut names = BTreeSet::new();
    for socket in sockets {
        check_socket_name(group, &socket.name)?;
        if !names.insert(socket.name.as_str()) {
            return Err(format!(
                "group \"{group}\" has two {side}s \"{}\"",
                socket.name
            ));
        }
        match &socket.default {
            Some(_) if socket.ty.is_shader() => {
                return Err(format!(
                    "group \"{group}\": shader {side} \"{}\" takes no default",
                    socket.name
                ));
            }
            Some(v) if !v.as_vec3().iter().all(|x| x.is_finite()) => {
                return Err(format!(
                    "group \"{group}\": the default of {side} \"{}\" must be finite",
                    socket.name
                ));
            }
            _ => {}
        }
    }
    Ok(())
}

/// Applies [`GraphEdit::SetGroupSockets`].
pub(super) fn set_group_sockets(
    graph: &mut Graph,
    name: String,
    inputs: Vec<GroupSocket>,
    outputs: Vec<GroupSocket>,
) -> Result<GraphEdit, String> {
    check_sockets(&name, &inputs, "input")?;
    check_sockets(&name, &outputs, "output")?;
    let Some(group) = graph.groups.get_mut(&name) else {
        return Err(format!("no group \"{name}\""));
    };
    let inputs = std::mem::replace(&mut group.inputs, inputs);
    let outputs = std::mem::replace(&mut group.outputs, outputs);
    Ok(GraphEdit::SetGroupSockets {
        group: name,
        inputs,
        outputs,
    })
}

/// Applies [`GraphEdit::RenameGroupSocket`].
pub(super) fn rename_group_socket(
    graph: &mut Graph,
    name: String,
    output: bool,
    from: String,
    to: String,
) -> Result<GraphEdit, String> {
    check_socket_name(&name, &to)?;
    let side = if output { "output" } else { "input" };
    let Some(group) = graph.groups.get_mut(&name) else {
        return Err(format!("no group \"{name}\""));
    };
    let list = if output {
        &mut group.outputs
    } else {
        &mut group.inputs
    };
    if from != to && list.iter().any(|s| s.name == to) {
        return Err(format!("group \"{name}\" already has an {side} \"{to}\""));
    }
    let Some(socket) = list.iter_mut().find(|s| s.name == from) else {
        return Err(format!("group \"{name}\" has no {side} \"{from}\""));
    };
    socket.name = to.clone();
    if output {
        if let Some(link) = group.links.remove(&from) {
            group.links.insert(to.clone(), link);
        }
    } else {
        // Inside, what reads the group's input node.
        let inputs: BTreeSet<String> = (group.nodes.iter())
            .filter(|(_, n)| n.kind == GROUP_INPUT)
            .map(|(id, _)| id.clone())
            .collect();
        let links = (group.nodes.values_mut())
            .flat_map(|n| n.inputs.values_mut())
            .filter_map(|i| match i {
                Input::Link(l) => Some(l),
                Input::Value(_) => None,
            })
            .chain(group.links.values_mut());
        for link in links {
            if inputs.contains(&link.node) && link.socket == from {
                link.socket = to.clone();
            }
        }
    }
    // Where the group is used: its instances' inputs, or the links to their outputs.
    let scopes = std::iter::once((&mut graph.nodes, None))
        .chain((graph.groups.values_mut()).map(|g| (&mut g.nodes, Some(&mut g.links))));
    for (nodes, group_links) in scopes {
        let ids: BTreeSet<String> = (nodes.iter())
            .filter(|(_, n)| is_instance(n, &name))
            .map(|(id, _)| id.clone())
            .collect();
        if output {
            let links = (nodes.values_mut())
                .flat_map(|n| n.inputs.values_mut())
                .filter_map(|i| match i {
                    Input::Link(l) => Some(l),
                    Input::Value(_) => None,
                })
                .chain(group_links.into_iter().flat_map(|l| l.values_mut()));
            for link in links {
                if ids.contains(&link.node) && link.socket == from {
                    link.socket = to.clone();
                }
            }
        } else {
            for id in &ids {
                let node = nodes.get_mut(id).expect("an id of these nodes");
                if let Some(value) = node.inputs.remove(&from) {
                    node.inputs.insert(to.clone(), value);
                }
            }
        }
    }
    Ok(GraphEdit::RenameGroupSocket {
        group: name,
        output,
        from: to,
        to: from,
    })
}

/// `base`, or with `_2`, `_3`… the first not the name of one of `sockets`.
fn fresh_socket_name(sockets: &[GroupSocket], base: &str) -> String {
    let base = if base.is_empty() { "socket" } else { base };
    std::iter::once(base.to_owned())
        .chain((2..).map(|n| format!("{base}_{n}")))
        .find(|name| sockets.iter().all(|s| s.name != *name))
        .expect("a free name exists")
}

/// The edit that adds an input (or, with `output`, an output) of type `ty` to group
/// `name`, named after its type as Blender names new sockets.
pub fn add_group_socket(
    graph: &Graph,
    name: &str,
    output: bool,
    ty: SocketType,
) -> Result<GraphEdit, String> {
    let group = graph
        .groups
        .get(name)
        .ok_or_else(|| format!("no group \"{name}\""))?;
    let base = match ty {
        SocketType::Float => "Value",
        SocketType::Vec2 => "Vector2",
        SocketType::Vector => "Vector",
        SocketType::Color => "Color",
        SocketType::Bsdf => "Shader",
        SocketType::Volume => "Volume",
    };
    let (mut inputs, mut outputs) = (group.inputs.clone(), group.outputs.clone());
    let list = if output { &mut outputs } else { &mut inputs };
    list.push(GroupSocket {
        name: fresh_socket_name(list, base),
        ty,
        default: None,
    });
    Ok(GraphEdit::SetGroupSockets {
        group: name.to_owned(),
        inputs,
        outputs,
    })
}

/// The edit that removes input (or, with `output`, output) `socket` of group `name`, and
/// first every link through it: its instances' wires into it or out of it, and inside,
/// the wires from the group's input node or into its output node.
pub fn remove_group_socket(
    graph: &Graph,
    name: &str,
    output: bool,
    socket: &str,
) -> Result<GraphEdit, String> {
    let group = graph
        .groups
        .get(name)
        .ok_or_else(|| format!("no group \"{name}\""))?;
    let (mut inputs, mut outputs) = (group.inputs.clone(), group.outputs.clone());
    let list = if output { &mut outputs } else { &mut inputs };
    let before = list.len();
    list.retain(|s| s.name != socket);
    if list.len() == before {
        let side = if output { "output" } else { "input" };
        return Err(format!("group \"{name}\" has no {side} \"{socket}\""));
    }
    let unset = |node: &str, input: &str| GraphEdit::SetInput {
        node: node.to_owned(),
        input: input.to_owned(),
        value: None,
    };
    let mut edits = Vec::new();
    for (scope, id) in instances_of(graph, name) {
        let (nodes, links) = match &scope {
            None => (&graph.nodes, None),
            Some(g) => (&graph.groups[g].nodes, Some(&graph.groups[g].links)),
        };
        if !output {
            if nodes[&id].inputs.contains_key(socket) {
                edits.push(in_scope(&scope, unset(&id, socket)));
            }
            continue;
        }
        let reads = |l: &Link| l.node == id && l.socket == socket;
        for (consumer, node) in nodes {
            for (input, value) in &node.inputs {
                if matches!(value, Input::Link(l) if reads(l)) {
                    edits.push(in_scope(&scope, unset(consumer, input)));
                }
            }
        }
        for (exposed, link) in links.into_iter().flatten() {
            if reads(link) {
                edits.push(in_scope(&scope, unset(GROUP_OUTPUT_ID, exposed)));
            }
        }
    }
    let inside = |edit| GraphEdit::InGroup {
        group: name.to_owned(),
        edit: Box::new(edit),
    };
    if output {
        if group.links.contains_key(socket) {
            edits.push(inside(unset(GROUP_OUTPUT_ID, socket)));
        }
    } else {
        let reads = |l: &Link| {
            l.socket == socket
                && group
                    .nodes
                    .get(&l.node)
                    .is_some_and(|n| n.kind == GROUP_INPUT)
        };
        for (consumer, node) in &group.nodes {
            for (input, value) in &node.inputs {
                if matches!(value, Input::Link(l) if reads(l)) {
                    edits.push(inside(unset(consumer, input)));
                }
            }
        }
        for (exposed, link) in &group.links {
            if reads(link) {
                edits.push(inside(unset(GROUP_OUTPUT_ID, exposed)));
            }
        }
    }
    edits.push(GraphEdit::SetGroupSockets {
        group: name.to_owned(),
        inputs,
        outputs,
    });
    Ok(GraphEdit::Batch(edits))
}

/// A name for a new group not used in `graph`: "NodeGroup", then "NodeGroup.001"… as
/// Blender names them.
fn fresh_group_name(graph: &Graph) -> String {
    std::iter::once("NodeGroup".to_owned())
        .chain((1..).map(|n| format!("NodeGroup.{n:03}")))
        .find(|name| !graph.groups.contains_key(name))
        .expect("a free name exists")
}

/// The type output `link` carries in `graph` (through reroutes, the type wired into them;
/// a float for what carries none).
fn output_type(graph: &Graph, link: &Link) -> SocketType {
    graph
        .nodes
        .get(&link.node)
        .and_then(|n| {
            if n.kind == REROUTE {
                reroute_type(graph, n)
            } else {
                let outputs = sockets_of(graph, n).ok()?.outputs;
                outputs
                    .into_iter()
                    .find(|(s, _)| *s == link.socket)
                    .map(|(_, t)| t)
            }
        })
        .unwrap_or(SocketType::Float)
}

/// The box nodes `ids` take in the layout of `graph`: min and max corners.
fn bounds<'a>(graph: &Graph, ids: impl Iterator<Item = &'a String>) -> ([f32; 2], [f32; 2]) {
    let laid = layout(graph);
    let (mut min, mut max) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    for id in ids {
        let (Some(p), Some(node)) = (laid.get(id), graph.nodes.get(id)) else {
            continue;
        };
        let size = [estimated_width(graph, node), estimated_height(graph, node)];
        for k in 0..2 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k] + size[k]);
        }
    }
    if min[0].is_finite() {
        (min, max)
    } else {
        ([0.0; 2], [0.0; 2])
    }
}

/// Ctrl+G: the edit that moves nodes `ids` of `graph` into a new group and puts an
/// instance of it where they were, and the instance's id. Every wire entering the
/// selection becomes a group input (one per source output, of its type) wired to the
/// instance; every wire leaving it a group output the consumers now read from the
/// instance. Nodes elsewhere keep where they are drawn. Refused (with why) for nothing
/// to group, for the material's output, and where the instance would make a cycle (a
/// wire that leaves the selection and comes back).
pub fn make_group(graph: &Graph, ids: &[String]) -> Result<(GraphEdit, String), String> {
    let picked: BTreeSet<&String> = ids
        .iter()
        .filter(|id| {
            (graph.nodes.get(*id)).is_some_and(|n| n.kind != GROUP_OUTPUT && n.kind != GROUP_INPUT)
        })
        .collect();
    if picked.is_empty() {
        return Err(
            "select the nodes to group (a group's input and output nodes stay in it)".into(),
        );
    }
    if let Some(id) = picked
        .iter()
        .find(|id| graph.nodes[**id].kind == MATERIAL_OUTPUT || graph.output.as_ref() == Some(**id))
    {
        return Err(format!(
            "\"{id}\" is the material's output: it cannot go into a group"
        ));
    }
    let name = fresh_group_name(graph);
    let laid = layout(graph);
    let (min, max) = bounds(graph, picked.iter().copied());
    let mut group = Group::default();
    // The group's input node has an id none of the grouped nodes has.
    let input_id = std::iter::once(GROUP_INPUT.to_owned())
        .chain((2..).map(|n| format!("{GROUP_INPUT}_{n}")))
        .find(|id| !picked.contains(id))
        .expect("a free id exists");
    let mut exposed_inputs: BTreeMap<Link, String> = BTreeMap::new();
    let mut instance_inputs = BTreeMap::new();
    for id in &picked {
        let mut node = graph.nodes[*id].clone();
        node.position = laid.get(*id).copied();
        for input in node.inputs.values_mut() {
            let Input::Link(link) = input else { continue };
            if picked.contains(&link.node) {
                continue;
            }
            let socket = exposed_inputs.entry(link.clone()).or_insert_with(|| {
                let socket = fresh_socket_name(&group.inputs, &link.socket);
                group.inputs.push(GroupSocket {
                    name: socket.clone(),
                    ty: output_type(graph, link),
                    default: None,
                });
                instance_inputs.insert(socket.clone(), Input::Link(link.clone()));
                socket
            });
            *input = Input::Link(Link::new(&input_id, socket));
        }
        group.nodes.insert((*id).clone(), node);
    }
    if !group.inputs.is_empty() {
        let mut node = Node::new(GROUP_INPUT);
        node.position = Some([min[0] - NODE_WIDTH - LAYOUT_GAP, min[1]]);
        group.nodes.insert(input_id, node);
    }
    let mut exposed_outputs: BTreeMap<Link, String> = BTreeMap::new();
    let mut rewires = Vec::new();
    for (consumer, node) in &graph.nodes {
        if picked.contains(consumer) {
            continue;
        }
        for (input, value) in &node.inputs {
            let Input::Link(link) = value else { continue };
            if !picked.contains(&link.node) {
                continue;
            }
            let socket = exposed_outputs.entry(link.clone()).or_insert_with(|| {
                let socket = fresh_socket_name(&group.outputs, &link.socket);
                group.outputs.push(GroupSocket {
                    name: socket.clone(),
                    ty: output_type(graph, link),
                    default: None,
                });
                group.links.insert(socket.clone(), link.clone());
                socket
            });
            rewires.push((consumer.clone(), input.clone(), socket.clone()));
        }
    }
    group.output_position = Some([max[0] + LAYOUT_GAP, min[1]]);

    let instance_id = fresh_id(graph, GROUP);
    let mut instance = Node::new(GROUP).param(GROUP_PARAM, Param::Text(name.clone()));
    instance.inputs = instance_inputs;
    instance.position = Some([
        (min[0] + max[0]) / 2.0 - NODE_WIDTH / 2.0,
        (min[1] + max[1]) / 2.0 - 40.0,
    ]);
    let mut edits = keep_layout(graph, |id| !picked.contains(&id.to_owned()));
    edits.push(GraphEdit::SetGroup {
        name,
        group: Some(group),
    });
    edits.extend(
        picked
            .iter()
            .map(|id| GraphEdit::RemoveNode { id: (*id).clone() }),
    );
    edits.push(GraphEdit::AddNode {
        id: instance_id.clone(),
        node: instance,
    });
    edits.extend(rewires.into_iter().map(|(consumer, input, socket)| {
        GraphEdit::connect(&instance_id, &socket, &consumer, &input)
    }));
    Ok((GraphEdit::Batch(edits), instance_id))
}

/// The move that fixes where the nodes `keep` selects are drawn (as laid out now), so that
/// adding or removing other nodes does not lay them out anew; none when all have places.
fn keep_layout(graph: &Graph, keep: impl Fn(&str) -> bool) -> Vec<GraphEdit> {
    let moves: Vec<(String, Option<[f32; 2]>)> = fix_layout(graph)
        .into_iter()
        .filter(|(id, _)| keep(id))
        .collect();
    if moves.is_empty() {
        Vec::new()
    } else {
        vec![GraphEdit::MoveNodes(moves)]
    }
}

/// Ctrl+Alt+G: the edit that replaces group instance `id` of `graph` with the group's
/// nodes (under fresh ids where its ids are taken), centred where it was, wired as it
/// was: what fed an input of the instance now feeds what read it inside (its default
/// where nothing did), and what read an output reads what computed it. The group itself
/// goes when nothing else uses it. Returns the edit and the ids of the nodes it adds.
pub fn ungroup(graph: &Graph, id: &str) -> Result<(GraphEdit, Vec<String>), String> {
    let Some(instance) = graph.nodes.get(id) else {
        return Err(format!("no node \"{id}\""));
    };
    if instance.kind != GROUP {
        return Err(format!("\"{id}\" is not a group node"));
    }
    if instance.muted {
        return Err(format!(
            "\"{id}\" is muted: unmute it (M) before ungrouping, or its nodes would compute what it does not"
        ));
    }
    let Some(Param::Text(name)) = instance.params.get(GROUP_PARAM) else {
        return Err(format!("group node \"{id}\" names no group"));
    };
    let view = group_view(graph, name)?;
    let group = &graph.groups[name];
    // What a group input resolves to outside: the instance's input, else the group's
    // default, else nothing (the reader's own default), as the compiler resolves it.
    let outer = |socket: &str| -> Option<Input> {
        instance.inputs.get(socket).cloned().or_else(|| {
            let declared = group.inputs.iter().find(|s| s.name == socket)?;
            declared.default.clone().map(Input::Value)
        })
    };
    let mut scratch = graph.clone();
    let mut renamed = BTreeMap::new();
    for (inner, node) in &group.nodes {
        if node.kind == GROUP_INPUT {
            continue;
        }
        let new = if scratch.nodes.contains_key(inner) {
            fresh_id(&scratch, inner)
        } else {
            inner.clone()
        };
        scratch.nodes.insert(new.clone(), node.clone());
        renamed.insert(inner.clone(), new);
    }
    let resolve = |link: &Link| -> Option<Input> {
        match group.nodes.get(&link.node) {
            Some(n) if n.kind == GROUP_INPUT => outer(&link.socket),
            _ => Some(Input::Link(Link::new(
                renamed.get(&link.node)?,
                &link.socket,
            ))),
        }
    };
    // The inner nodes, centred on the instance.
    let inner_ids: Vec<&String> = renamed.keys().collect();
    let (min, max) = bounds(&view, inner_ids.iter().copied());
    let laid = layout(&view);
    let at = graph_position(graph, id);
    let centre = [at[0] + NODE_WIDTH / 2.0, at[1] + 40.0];
    let shift = [
        centre[0] - (min[0] + max[0]) / 2.0,
        centre[1] - (min[1] + max[1]) / 2.0,
    ];
    let mut edits = keep_layout(graph, |other| other != id);
    let mut added = Vec::new();
    for (inner, new) in &renamed {
        let mut node = group.nodes[inner].clone();
        node.inputs = (node.inputs.iter())
            .filter_map(|(input, value)| match value {
                Input::Link(link) => resolve(link).map(|v| (input.clone(), v)),
                Input::Value(_) => Some((input.clone(), value.clone())),
            })
            .collect();
        let p = laid.get(inner).copied().unwrap_or(min);
        node.position = Some([p[0] + shift[0], p[1] + shift[1]]);
        added.push(new.clone());
        edits.push(GraphEdit::AddNode {
            id: new.clone(),
            node,
        });
    }
    // Frames inside come out with their nodes.
    let mut frames = graph.clone();
    for frame in group.frames.values() {
        let mut frame = frame.clone();
        frame.nodes = (frame.nodes.iter())
            .filter_map(|n| renamed.get(n).cloned())
            .collect();
        if frame.nodes.is_empty() {
            continue;
        }
        let frame_id = super::frames::fresh_frame_id(&frames);
        frames.frames.insert(frame_id.clone(), frame.clone());
        edits.push(GraphEdit::SetFrame {
            id: frame_id,
            frame: Some(frame),
        });
    }
    // Removing the instance unlinks what read it; each reader then reads what computed
    // the output (a reroute or an output node takes no value: left unconnected).
    edits.push(GraphEdit::RemoveNode { id: id.to_owned() });
    for (consumer, node) in &graph.nodes {
        for (input, value) in &node.inputs {
            let Input::Link(link) = value else { continue };
            if link.node != id {
                continue;
            }
            let source = group.links.get(&link.socket).and_then(&resolve);
            let takes_values = node.kind != REROUTE && node.kind != GROUP_OUTPUT;
            let source = source.filter(|s| takes_values || matches!(s, Input::Link(_)));
            if let Some(value) = source {
                edits.push(GraphEdit::SetInput {
                    node: consumer.clone(),
                    input: input.clone(),
                    value: Some(value),
                });
            }
        }
    }
    if instances_of(graph, name).len() == 1 {
        edits.push(GraphEdit::SetGroup {
            name: name.clone(),
            group: None,
        });
    }
    Ok((GraphEdit::Batch(edits), added))
}

/// Where node `id` is drawn in `graph` (its position, else its layout's).
fn graph_position(graph: &Graph, id: &str) -> [f32; 2] {
    (graph.nodes.get(id))
        .and_then(|n| n.position)
        .or_else(|| layout(graph).get(id).copied())
        .unwrap_or([0.0, 0.0])
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

    /// The material's WGSL, up to names: what it computes. The compiler numbers values
    /// (`n3`) and helper functions (`m_ramp1`) in the order of the flattened node ids
    /// and comments each with its node's path, which grouping changes; each such name is
    /// renamed by its first appearance and the comments dropped.
    fn wgsl(g: &Graph) -> String {
        let code = crate::material::compile("m", g, "m")
            .unwrap_or_else(|e| panic!("{}", e.message))
            .code;
        let numbered = |word: &str| {
            let stem = word.trim_end_matches(|c: char| c.is_ascii_digit());
            stem.len() < word.len() && (stem == "n" || stem.starts_with("m_"))
        };
        let mut names: BTreeMap<String, String> = BTreeMap::new();
        let mut out = String::new();
        for line in code.lines().filter(|l| !l.trim_start().starts_with("//")) {
            let mut word = String::new();
            for c in line.chars().chain(std::iter::once('\n')) {
                if c.is_ascii_alphanumeric() || c == '_' {
                    word.push(c);
                    continue;
                }
                if numbered(&word) {
                    let next = format!("v{}", names.len());
                    word = names.entry(word).or_insert(next).clone();
                }
                out.push_str(&word);
                out.push(c);
                word.clear();
            }
        }
        out
    }

    #[test]
    fn grouping_and_ungrouping_keep_the_compiled_material_and_revert() {
        let start = marble();
        let before = wgsl(&start);
        let mut g = start.clone();
        let (edit, instance) = make_group(&g, &["veins".into(), "ramp".into()]).unwrap();
        let undo_group = edit.apply(&mut g).unwrap();
        let group = &g.groups["NodeGroup"];
        assert_eq!(
            group.nodes.keys().collect::<Vec<_>>(),
            ["group_input", "ramp", "veins"]
        );
        // One input per source outside (the coordinates), one output per source read
        // outside (the ramp's colour).
        assert_eq!(group.inputs.len(), 1);
        assert_eq!(group.inputs[0].ty, SocketType::Vector);
        assert_eq!(group.outputs.len(), 1);
        assert_eq!(group.outputs[0].ty, SocketType::Color);
        assert_eq!(
            g.nodes[&instance].inputs[&group.inputs[0].name],
            Input::Link(Link::new("coords", "object"))
        );
        assert_eq!(
            g.nodes["surface"].inputs["base_color"],
            Input::Link(Link::new(&instance, &group.outputs[0].name))
        );
        assert!(!g.nodes.contains_key("veins") && !g.nodes.contains_key("ramp"));
        assert_eq!(
            wgsl(&g),
            before,
            "grouping changes what the material computes"
        );

        // An edit inside the group reaches it and reverts.
        let grouped = g.clone();
        let undo_inside = GraphEdit::InGroup {
            group: "NodeGroup".into(),
            edit: Box::new(GraphEdit::SetInput {
                node: "veins".into(),
                input: "scale".into(),
                value: Some(Input::Value(Value::Float(3.0))),
            }),
        }
        .apply(&mut g)
        .unwrap();
        assert_eq!(
            g.groups["NodeGroup"].nodes["veins"].inputs["scale"],
            Input::Value(Value::Float(3.0))
        );
        assert_ne!(wgsl(&g), before);
        undo_inside.apply(&mut g).unwrap();
        assert_eq!(g, grouped);

        let (edit, added) = ungroup(&g, &instance).unwrap();
        let undo_ungroup = edit.apply(&mut g).unwrap();
        assert_eq!(added, ["ramp", "veins"]);
        assert!(g.groups.is_empty(), "the group nothing uses goes");
        assert_eq!(
            wgsl(&g),
            before,
            "ungrouping changes what the material computes"
        );
        assert!(
            g.same_but_layout(&start),
            "ungrouping gives the graph grouped"
        );
        undo_ungroup.apply(&mut g).unwrap();
        assert_eq!(g, grouped);
        undo_group.apply(&mut g).unwrap();
        assert_eq!(g, start);
    }

    #[test]
    fn grouping_refuses_the_output_and_a_wire_that_leaves_and_comes_back() {
        let g = marble();
        let e = make_group(&g, &["out".into()]).unwrap_err();
        assert!(e.contains("out") && e.contains("output"), "{e}");
        // veins → ramp → surface: grouping veins and surface leaves the ramp outside,
        // read by the group and reading it.
        let (edit, _) = make_group(&g, &["veins".into(), "surface".into()]).unwrap();
        let e = edit.apply(&mut g.clone()).unwrap_err();
        assert!(e.contains("cycle"), "{e}");
        assert!(make_group(&g, &[]).is_err());
    }

    #[test]
    fn ungrouping_takes_fresh_ids_and_the_group_defaults() {
        let mut g = marble();
        let (edit, instance) = make_group(&g, &["ramp".into()]).unwrap();
        edit.apply(&mut g).unwrap();
        // A node outside now has the id of the node inside.
        g.add("ramp", Node::new("color_ramp"));
        // The instance's input left unconnected: the group's default feeds the ramp.
        let input = g.groups["NodeGroup"].inputs[0].name.clone();
        g.groups.get_mut("NodeGroup").unwrap().inputs[0].default = Some(Value::Float(0.25));
        g.nodes.get_mut(&instance).unwrap().inputs.remove(&input);
        let before = wgsl(&g);
        let (edit, added) = ungroup(&g, &instance).unwrap();
        edit.apply(&mut g).unwrap();
        assert_eq!(added, ["ramp_2"]);
        assert_eq!(
            g.nodes["ramp_2"].inputs["fac"],
            Input::Value(Value::Float(0.25))
        );
        assert_eq!(
            g.nodes["surface"].inputs["base_color"],
            Input::Link(Link::new("ramp_2", "color"))
        );
        assert_eq!(wgsl(&g), before);
    }

    #[test]
    fn interface_sockets_are_added_renamed_and_removed_with_their_wires() {
        let start = {
            let mut g = marble();
            let (edit, _) = make_group(&g, &["veins".into(), "ramp".into()]).unwrap();
            edit.apply(&mut g).unwrap();
            g
        };
        let mut g = start.clone();
        let before = wgsl(&g);
        let (input, output) = {
            let group = &g.groups["NodeGroup"];
            (group.inputs[0].name.clone(), group.outputs[0].name.clone())
        };
        let mut undo = Vec::new();
        let mut apply = |edit: GraphEdit, g: &mut Graph| undo.push(edit.apply(g).unwrap());
        apply(
            GraphEdit::RenameGroupSocket {
                group: "NodeGroup".into(),
                output: false,
                from: input.clone(),
                to: "Coordinates".into(),
            },
            &mut g,
        );
        apply(
            GraphEdit::RenameGroupSocket {
                group: "NodeGroup".into(),
                output: true,
                from: output.clone(),
                to: "Marble".into(),
            },
            &mut g,
        );
        assert_eq!(wgsl(&g), before, "renaming changes no wire");
        assert_eq!(
            g.nodes["surface"].inputs["base_color"],
            Input::Link(Link::new("group", "Marble"))
        );
        apply(
            add_group_socket(&g, "NodeGroup", false, SocketType::Float).unwrap(),
            &mut g,
        );
        assert_eq!(g.groups["NodeGroup"].inputs[1].name, "Value");
        apply(
            remove_group_socket(&g, "NodeGroup", false, "Coordinates").unwrap(),
            &mut g,
        );
        apply(
            remove_group_socket(&g, "NodeGroup", true, "Marble").unwrap(),
            &mut g,
        );
        let group = &g.groups["NodeGroup"];
        assert!(group.links.is_empty());
        assert!(!g.nodes["group"].inputs.contains_key("Coordinates"));
        assert!(!g.nodes["surface"].inputs.contains_key("base_color"));
        assert!(!group.nodes["veins"].inputs.contains_key("vector"));
        // A name with a dot could not be written in a link.
        let e = GraphEdit::RenameGroupSocket {
            group: "NodeGroup".into(),
            output: false,
            from: "Value".into(),
            to: "a.b".into(),
        }
        .apply(&mut g)
        .unwrap_err();
        assert!(e.contains("a.b"), "{e}");
        for edit in undo.into_iter().rev() {
            edit.apply(&mut g).unwrap();
        }
        assert_eq!(g, start);
    }

    #[test]
    fn the_view_of_a_group_shows_its_output_node_and_keeps_it() {
        let mut g = marble();
        let (edit, _) = make_group(&g, &["veins".into(), "ramp".into()]).unwrap();
        edit.apply(&mut g).unwrap();
        let view = group_view(&g, "NodeGroup").unwrap();
        let output = &view.nodes[GROUP_OUTPUT_ID];
        assert_eq!(sockets_of(&view, output).unwrap().inputs.len(), 1);
        let input = &view.nodes[GROUP_INPUT];
        assert_eq!(sockets_of(&view, input).unwrap().outputs.len(), 1);
        let inside = |edit: GraphEdit| GraphEdit::InGroup {
            group: "NodeGroup".into(),
            edit: Box::new(edit),
        };
        for refused in [
            GraphEdit::RemoveNode {
                id: GROUP_OUTPUT_ID.into(),
            },
            GraphEdit::SetInput {
                node: GROUP_OUTPUT_ID.into(),
                input: "color".into(),
                value: Some(Input::Value(Value::Float(1.0))),
            },
        ] {
            assert!(inside(refused).apply(&mut g).is_err());
        }
        // Rewiring the group's output to the veins' factor (float → colour converts).
        inside(GraphEdit::connect("veins", "fac", GROUP_OUTPUT_ID, "color"))
            .apply(&mut g)
            .unwrap();
        assert_eq!(
            g.groups["NodeGroup"].links["color"],
            Link::new("veins", "fac")
        );
        // A group input node outside a group has no sockets.
        assert!(sockets_of(&g, &Node::new(GROUP_INPUT)).is_err());

        // Frames inside a group are the group's, and its output node may be in one.
        let before = g.clone();
        let view = group_view(&g, "NodeGroup").unwrap();
        let (join, frame) =
            super::super::join_in_frame(&view, &["veins".into(), GROUP_OUTPUT_ID.into()]).unwrap();
        let undo = inside(join).apply(&mut g).unwrap();
        assert_eq!(
            g.groups["NodeGroup"].frames[&frame].nodes,
            [GROUP_OUTPUT_ID, "veins"]
        );
        assert!(g.frames.is_empty());
        undo.apply(&mut g).unwrap();
        assert_eq!(g, before);
    }
}
