//! A reader of `.kmat` text for material exporters, which receive the graph they write
//! as that text ([`crate::MaterialFormat::export`]) and must not depend on Kiln to read
//! it. It reads the file format of `docs/NODES.md` as it is (what only the editor uses,
//! frames and previews, is skipped), checking nothing about node types: the host
//! compiled the graph before handing it over.

use std::collections::BTreeMap;

use serde::Deserialize;

/// A `.kmat` file.
#[derive(Clone, Debug, Deserialize)]
pub struct File {
    pub version: u32,
    #[serde(default)]
    pub name: Option<String>,
    pub nodes: BTreeMap<String, Node>,
    #[serde(default)]
    pub groups: BTreeMap<String, Group>,
    #[serde(default)]
    pub output: Option<String>,
}

/// One node: its type, parameters, set inputs and where an editor draws it.
#[derive(Clone, Debug, Default, Deserialize)]
pub struct Node {
    #[serde(rename = "type")]
    pub kind: String,
    #[serde(default)]
    pub params: BTreeMap<String, Param>,
    #[serde(default)]
    pub inputs: BTreeMap<String, Input>,
    #[serde(default)]
    pub position: Option<[f32; 2]>,
    #[serde(default)]
    pub muted: bool,
}

/// A parameter: a flag, a number, a choice or file, or colour-ramp stops.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum Param {
    Bool(bool),
    Number(f32),
    Text(String),
    Ramp(Vec<Stop>),
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct Stop {
    pub position: f32,
    pub color: [f32; 4],
}

/// What feeds an input: a link `"node.socket"` or a constant.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum Input {
    Link(String),
    Float(f32),
    Vec2([f32; 2]),
    Vec3([f32; 3]),
}

impl Input {
    /// A link's node and socket (the socket after the last dot).
    pub fn link(&self) -> Option<(&str, &str)> {
        match self {
            Input::Link(l) => l.rsplit_once('.'),
            _ => None,
        }
    }
}

/// The types of sockets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SocketType {
    Float,
    Vec2,
    Vector,
    Color,
    Bsdf,
    Volume,
}

impl SocketType {
    /// The name the file uses.
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
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct Socket {
    pub name: String,
    #[serde(rename = "type")]
    pub ty: SocketType,
    #[serde(default)]
    pub default: Option<Input>,
    /// In a node type's declaration: what an unconnected input reads instead of a
    /// constant, as Kiln's WGSL names it (`sp.generated`, `sp.n`, `sp.uv`).
    #[serde(default)]
    pub implicit: Option<String>,
}

/// A node group: inner nodes, exposed sockets, and which inner socket feeds each output.
#[derive(Clone, Debug, Deserialize)]
pub struct Group {
    #[serde(default)]
    pub inputs: Vec<Socket>,
    pub outputs: Vec<Socket>,
    pub nodes: BTreeMap<String, Node>,
    pub links: BTreeMap<String, String>,
    #[serde(default)]
    pub output_position: Option<[f32; 2]>,
}

/// A node type as the host declares it to exporters: its inputs (typed, with the
/// constant each takes unconnected, if any) and outputs.
#[derive(Clone, Debug, Deserialize)]
pub struct NodeType {
    #[serde(rename = "type")]
    pub kind: String,
    pub inputs: Vec<Socket>,
    pub outputs: Vec<Socket>,
    /// The defaults of its choice and flag parameters.
    #[serde(default)]
    pub params: Vec<ParamDefault>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct ParamDefault {
    pub name: String,
    pub default: Param,
}

/// Parses `.kmat` text; the error gives the line and column.
pub fn parse(text: &str) -> Result<File, String> {
    from_ron(text)
}

/// Parses the host's declarations of the node types a graph uses.
pub fn parse_library(text: &str) -> Result<Vec<NodeType>, String> {
    from_ron(text)
}

fn from_ron<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, String> {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(text)
        .map_err(|e| format!("{}:{}: {}", e.span.start.line, e.span.start.col, e.code))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kmat::{Graph, Group as WriteGroup, Node as WriteNode, Param as WriteParam};
    use crate::kmat::{Socket as WriteSocket, Value};

    #[test]
    fn what_the_writer_writes_reads_back() {
        let mut inner = Graph::default();
        inner.add(
            "m",
            WriteNode::new("math")
                .text("operation", "add")
                .input("a", Value::link("group_input", "x"))
                .at(10.0, -20.0),
        );
        let mut g = Graph::default();
        g.add_group(
            "g",
            WriteGroup {
                inputs: vec![WriteSocket {
                    name: "x".into(),
                    ty: "float".into(),
                    default: Some(Value::Float(0.5)),
                }],
                outputs: vec![WriteSocket {
                    name: "y".into(),
                    ty: "float".into(),
                    default: None,
                }],
                nodes: inner,
                links: vec![("y".into(), "m.value".into())],
            },
        );
        g.add(
            "ramp",
            WriteNode::new("color_ramp")
                .param("stops", WriteParam::Ramp(vec![(0.0, [1.0, 0.0, 0.0, 1.0])]))
                .param("n", WriteParam::Number(3.0))
                .input("fac", Value::Vec2([0.25, 0.5])),
        );
        g.add("gi", WriteNode::group("g").input("x", Value::Float(2.0)));
        let file = parse(&g.to_kmat("t", &[])).unwrap();
        assert_eq!(file.name.as_deref(), Some("t"));
        let group = &file.groups["g"];
        assert_eq!(group.inputs[0].ty, SocketType::Float);
        assert_eq!(group.inputs[0].default, Some(Input::Float(0.5)));
        assert_eq!(group.links["y"], "m.value");
        assert_eq!(group.nodes["m"].position, Some([10.0, -20.0]));
        assert_eq!(
            group.nodes["m"].inputs["a"].link(),
            Some(("group_input", "x"))
        );
        let ramp = &file.nodes["ramp"];
        assert_eq!(ramp.params["n"], Param::Number(3.0));
        assert_eq!(ramp.inputs["fac"], Input::Vec2([0.25, 0.5]));
        assert!(matches!(&ramp.params["stops"], Param::Ramp(s) if s[0].color[0] == 1.0));
        assert_eq!(file.nodes["gi"].params["group"], Param::Text("g".into()));
    }
}
