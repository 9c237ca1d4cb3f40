//! The material graph as a user edits and saves it: nodes by id, each with a type from the
//! node library ([`super::nodes`]), parameter values, and inputs that are either values or
//! links to another node's output. Node groups are graphs used as nodes.
//!
//! This is plain data: nothing here checks types or cycles; [`super::compile`] does, and
//! names the node and socket of every error.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// The types a socket carries. `Vector` and `Color` are both three floats but convert
/// into each other only where Blender does (implicitly, channel for channel).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SocketType {
    Float,
    Vec2,
    Vector,
    Color,
    Bsdf,
    /// A volume shader: what fills a closed mesh (`VolumeEval`).
    Volume,
}

impl SocketType {
    pub fn name(self) -> &'static str {
        match self {
            SocketType::Float => "float",
            SocketType::Vec2 => "vec2",
            SocketType::Vector => "vector",
            SocketType::Color => "color",
            SocketType::Bsdf => "bsdf",
            SocketType::Volume => "volume",
        }
    }

    pub fn wgsl(self) -> &'static str {
        match self {
            SocketType::Float => "f32",
            SocketType::Vec2 => "vec2<f32>",
            SocketType::Vector | SocketType::Color => "vec3<f32>",
            SocketType::Bsdf => "MaterialEval",
            SocketType::Volume => "VolumeEval",
        }
    }

    /// A shader (surface or volume): a closure, not a value; it has no constant and is
    /// never held in an interpreter register.
    pub fn is_shader(self) -> bool {
        matches!(self, SocketType::Bsdf | SocketType::Volume)
    }

    /// Whether a value of `self` may feed an input of type `to`, and how: the implicit
    /// conversions Blender makes between float, vector and colour.
    pub fn converts_to(self, to: SocketType) -> Option<Conversion> {
        use SocketType::*;
        match (self, to) {
            (a, b) if a == b => Some(Conversion::None),
            (Vector, Color) | (Color, Vector) => Some(Conversion::None),
            (Float, Vector) | (Float, Color) => Some(Conversion::Splat),
            (Color, Float) => Some(Conversion::Luminance),
            (Vector, Float) => Some(Conversion::Average),
            _ => None,
        }
    }
}

/// An implicit conversion between socket types.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Conversion {
    None,
    /// float → vector/colour: the value in every channel.
    Splat,
    /// colour → float: Rec. 709 luminance, as Blender's colour-to-float conversion.
    Luminance,
    /// vector → float: the mean of the components, as Blender.
    Average,
}

/// A constant: a float, or two or three floats.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Value {
    Float(f32),
    Vec2([f32; 2]),
    Vec3([f32; 3]),
}

impl Value {
    /// As a float: a vector's mean.
    pub fn as_f32(&self) -> f32 {
        match self {
            Value::Float(x) => *x,
            Value::Vec2(a) => (a[0] + a[1]) / 2.0,
            Value::Vec3(a) => (a[0] + a[1] + a[2]) / 3.0,
        }
    }

    /// As three floats: a float in every component, a vec2 with z = 0.
    pub fn as_vec3(&self) -> [f32; 3] {
        match self {
            Value::Float(x) => [*x; 3],
            Value::Vec2(a) => [a[0], a[1], 0.0],
            Value::Vec3(a) => *a,
        }
    }
}

/// What feeds an input: a constant, or a link written `"node.output"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Input {
    Link(Link),
    Value(Value),
}

/// A link to output `socket` of node `node`; in files, the string `"node.socket"`.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Link {
    pub node: String,
    pub socket: String,
}

impl Link {
    pub fn new(node: &str, socket: &str) -> Self {
        Self {
            node: node.to_owned(),
            socket: socket.to_owned(),
        }
    }
}

impl std::fmt::Display for Link {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}.{}", self.node, self.socket)
    }
}

impl Serialize for Link {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

impl<'de> Deserialize<'de> for Link {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let text = String::deserialize(d)?;
        // Node ids may contain dots; the socket is after the last one.
        match text.rsplit_once('.') {
            Some((node, socket)) if !node.is_empty() && !socket.is_empty() => {
                Ok(Link::new(node, socket))
            }
            _ => Err(serde::de::Error::custom(format!(
                "link \"{text}\" must be written \"node.socket\""
            ))),
        }
    }
}

/// One stop of a colour ramp.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RampStop {
    pub position: f32,
    pub color: [f32; 4],
}

/// A node parameter: a choice (`"multiply"`), a flag, a number, a file, or ramp stops.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Param {
    Bool(bool),
    Number(f32),
    Text(String),
    Ramp(Vec<RampStop>),
}

/// One node: its type, parameters and connected or set inputs. Unset inputs take the
/// node type's defaults.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Node {
    #[serde(rename = "type")]
    pub kind: String,
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub params: BTreeMap<String, Param>,
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub inputs: BTreeMap<String, Input>,
    /// Where a graph editor draws the node (kept through load and save); no meaning to
    /// the compiler.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<[f32; 2]>,
    /// A muted node computes nothing (Blender's M): each of its outputs passes the node's
    /// first input of the output's type, or the type's zero (black, 0; for a shader, what
    /// the consumer reads unconnected) when it has none. Saved only when set.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub muted: bool,
    /// Whether a graph editor shows the node's output as a small image under it
    /// (Blender's node preview); no meaning to the compiler. Saved only when set.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub preview: bool,
}

impl Node {
    pub fn new(kind: &str) -> Self {
        Self {
            kind: kind.to_owned(),
            ..Self::default()
        }
    }

    pub fn input(mut self, name: &str, input: impl Into<Input>) -> Self {
        self.inputs.insert(name.to_owned(), input.into());
        self
    }

    pub fn param(mut self, name: &str, param: Param) -> Self {
        self.params.insert(name.to_owned(), param);
        self
    }
}

impl From<f32> for Input {
    fn from(v: f32) -> Self {
        Input::Value(Value::Float(v))
    }
}

impl From<[f32; 3]> for Input {
    fn from(v: [f32; 3]) -> Self {
        Input::Value(Value::Vec3(v))
    }
}

impl From<Link> for Input {
    fn from(l: Link) -> Self {
        Input::Link(l)
    }
}

/// A socket a group exposes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroupSocket {
    pub name: String,
    #[serde(rename = "type")]
    pub ty: SocketType,
    /// The value of an input left unconnected where the group is used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub default: Option<Value>,
}

/// The node type that instantiates a [`Group`], named by its parameter [`GROUP_PARAM`].
pub const GROUP: &str = "group";
/// The parameter of a [`GROUP`] node naming the group.
pub const GROUP_PARAM: &str = "group";
/// The node type that, inside a group, has one output per exposed input.
pub const GROUP_INPUT: &str = "group_input";

/// The node type that passes one wire on unchanged, to route wires (Blender's reroute): it
/// has input [`REROUTE_INPUT`] and output [`REROUTE_OUTPUT`], of the type of what is wired
/// into it, and compiles to nothing (a link through it is a link to its source; an
/// unconnected one gives its consumers their defaults). It holds no value.
pub const REROUTE: &str = "reroute";
/// A reroute's input.
pub const REROUTE_INPUT: &str = "input";
/// A reroute's output.
pub const REROUTE_OUTPUT: &str = "output";

/// A graph used as a node (`type: "group", params: { "group": "name" }`). Inside, node
/// type `group_input` has one output per exposed input; `outputs` says which inner
/// socket feeds each exposed output.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Group {
    #[serde(default)]
    pub inputs: Vec<GroupSocket>,
    pub outputs: Vec<GroupSocket>,
    pub nodes: BTreeMap<String, Node>,
    /// Exposed output name → the inner `"node.socket"` that computes it.
    pub links: BTreeMap<String, Link>,
    /// Where a graph editor draws the group's output node (the node it shows for
    /// `links`); no meaning to the compiler.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output_position: Option<[f32; 2]>,
    /// The editor's frames inside the group, as [`Graph::frames`].
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub frames: BTreeMap<String, Frame>,
}

/// A frame, as Blender's Frame node: a labelled, coloured box a graph editor draws behind
/// a set of nodes (around their bounds). Layout only: no meaning to the compiler.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Frame {
    pub label: String,
    /// Linear RGB, each in [0, 1].
    pub color: [f32; 3],
    /// The ids of the nodes it holds, sorted.
    pub nodes: Vec<String>,
}

/// The sockets a group exposes: what its instances show, what its `group_input` node
/// gives inside, and what its output node takes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GroupInterface {
    pub inputs: Vec<GroupSocket>,
    pub outputs: Vec<GroupSocket>,
}

/// A material: nodes, the groups they use, and the node whose output is the surface
/// (a `material_output` node; the only one if `output` is not given).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Graph {
    pub nodes: BTreeMap<String, Node>,
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub groups: BTreeMap<String, Group>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output: Option<String>,
    /// The editor's frames by id, in id order; written only when there are any.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub frames: BTreeMap<String, Frame>,
    /// Set only on a graph editor's view of a group's insides (its nodes as a graph of
    /// their own, `editor::graph_edit::group_view`): the group's interface, which gives
    /// the `group_input` node its outputs and the view's output node its inputs. Never
    /// saved; `None` for a material's graph.
    #[serde(skip)]
    pub interface: Option<GroupInterface>,
}

impl Graph {
    pub fn add(&mut self, id: &str, node: Node) -> &mut Self {
        self.nodes.insert(id.to_owned(), node);
        self
    }

    /// Whether `other` computes the same as this graph: equal but for where nodes are
    /// drawn and which show previews (which the compiler ignores), so a moved node needs
    /// no new compile.
    pub fn same_but_layout(&self, other: &Graph) -> bool {
        fn nodes_match(a: &BTreeMap<String, Node>, b: &BTreeMap<String, Node>) -> bool {
            a.len() == b.len()
                && a.iter().zip(b).all(|((ka, na), (kb, nb))| {
                    ka == kb
                        && na.kind == nb.kind
                        && na.params == nb.params
                        && na.inputs == nb.inputs
                        && na.muted == nb.muted
                })
        }
        self.output == other.output
            && nodes_match(&self.nodes, &other.nodes)
            && self.groups.len() == other.groups.len()
            && self
                .groups
                .iter()
                .zip(&other.groups)
                .all(|((ka, a), (kb, b))| {
                    ka == kb
                        && a.inputs == b.inputs
                        && a.outputs == b.outputs
                        && a.links == b.links
                        && nodes_match(&a.nodes, &b.nodes)
                })
    }

    /// The files its image-reading nodes (those with a file parameter) read, in the graph
    /// and its groups: resolved against the file's folder on loading, renamed on saving
    /// and on merging scenes.
    pub fn image_files_mut(&mut self) -> impl Iterator<Item = &mut String> {
        let groups = self.groups.values_mut().flat_map(|g| g.nodes.values_mut());
        self.nodes
            .values_mut()
            .chain(groups)
            .filter(|node| {
                super::nodes::find(&node.kind).is_some_and(|def| {
                    def.params.iter().any(|p| {
                        p.name == "file" && matches!(p.kind, super::nodes::ParamKind::File)
                    })
                })
            })
            .filter_map(|node| match node.params.get_mut("file") {
                Some(Param::Text(file)) => Some(file),
                _ => None,
            })
    }
}
