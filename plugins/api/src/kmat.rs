//! A writer of `.kmat` material graphs (RON text, `docs/NODES.md`) for importers, which
//! hand materials to the host as that text ([`crate::Builder::add_material`]) and must
//! not depend on Kiln to write it.
//!
//! A [`Graph`] is assembled from [`Node`]s with typed constant or linked inputs and text
//! or boolean parameters, and printed with every number a RON float and every string
//! escaped. It knows node types and sockets only as strings and does not check the graph:
//! the host parses and compiles it and reports mistakes. The multiply helpers fold
//! constants, so a material without textures stays a single principled node with numbers.

pub mod read;

use std::fmt::Write;

/// A node input: a constant, or the output `socket` of node `node`.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Float(f32),
    Vec2([f32; 2]),
    Color([f32; 3]),
    Vector([f32; 3]),
    /// `"node.socket"`.
    Link(String),
}

impl Value {
    pub fn link(node: &str, socket: &str) -> Self {
        Value::Link(format!("{node}.{socket}"))
    }

    fn is_one(&self) -> bool {
        match self {
            Value::Float(v) => *v == 1.0,
            Value::Color(c) => c.iter().all(|&v| v == 1.0),
            Value::Vec2(_) | Value::Vector(_) | Value::Link(_) => false,
        }
    }

    /// The constant as a colour (a float promoted to grey).
    fn as_color(&self) -> Option<[f32; 3]> {
        match *self {
            Value::Float(v) => Some([v; 3]),
            Value::Color(c) => Some(c),
            Value::Vec2(_) | Value::Vector(_) | Value::Link(_) => None,
        }
    }

    fn text(&self) -> String {
        match self {
            Value::Float(x) => float(*x),
            Value::Vec2([x, y]) => format!("({}, {})", float(*x), float(*y)),
            Value::Color([r, g, b]) | Value::Vector([r, g, b]) => {
                format!("({}, {}, {})", float(*r), float(*g), float(*b))
            }
            Value::Link(l) => string(l),
        }
    }
}

/// A node parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum Param {
    Text(String),
    Bool(bool),
    Number(f32),
    /// Colour-ramp stops: position and linear RGBA.
    Ramp(Vec<(f32, [f32; 4])>),
}

impl Param {
    fn text(&self) -> String {
        match self {
            Param::Text(t) => string(t),
            Param::Bool(b) => b.to_string(),
            Param::Number(x) => float(*x),
            Param::Ramp(stops) => {
                let stops: Vec<String> = stops
                    .iter()
                    .map(|(p, c)| {
                        let c: Vec<String> = c.iter().map(|&x| float(x)).collect();
                        format!("(position: {}, color: ({}))", float(*p), c.join(", "))
                    })
                    .collect();
                format!("[{}]", stops.join(", "))
            }
        }
    }
}

/// One node: its type, parameters and set inputs, in the order given.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    kind: String,
    params: Vec<(String, Param)>,
    inputs: Vec<(String, Value)>,
    position: Option<[f32; 2]>,
    muted: bool,
}

impl Node {
    pub fn new(kind: &str) -> Self {
        Self {
            kind: kind.to_owned(),
            params: Vec::new(),
            inputs: Vec::new(),
            position: None,
            muted: false,
        }
    }

    /// A muted node computes nothing (its outputs pass its first input of their type).
    pub fn mute(mut self) -> Self {
        self.muted = true;
        self
    }

    /// Where a graph editor draws the node.
    pub fn at(mut self, x: f32, y: f32) -> Self {
        self.position = Some([x, y]);
        self
    }

    /// A node instantiating group `group` of the graph.
    pub fn group(group: &str) -> Self {
        Self::new("group").text("group", group)
    }

    pub fn kind(&self) -> &str {
        &self.kind
    }

    /// Sets a text parameter.
    pub fn text(self, name: &str, value: &str) -> Self {
        self.param(name, Param::Text(value.to_owned()))
    }

    /// Sets a boolean parameter.
    pub fn flag(self, name: &str, value: bool) -> Self {
        self.param(name, Param::Bool(value))
    }

    /// Sets parameter `name`, replacing an earlier value.
    pub fn param(mut self, name: &str, value: Param) -> Self {
        set(&mut self.params, name, value);
        self
    }

    /// Sets input `name`, replacing an earlier value.
    pub fn input(mut self, name: &str, value: Value) -> Self {
        self.set_input(name, value);
        self
    }

    /// Sets input `name` in place, replacing an earlier value (a map read after the
    /// constant it overrides keeps the constant's place in the text).
    pub fn set_input(&mut self, name: &str, value: Value) {
        set(&mut self.inputs, name, value);
    }

    /// The input set as `name`, if any.
    pub fn get_input(&self, name: &str) -> Option<&Value> {
        self.inputs.iter().find(|(k, _)| k == name).map(|(_, v)| v)
    }
}

fn set<T>(list: &mut Vec<(String, T)>, name: &str, value: T) {
    match list.iter_mut().find(|(k, _)| k == name) {
        Some(slot) => slot.1 = value,
        None => list.push((name.to_owned(), value)),
    }
}

/// A socket a group exposes: its name, type (`float`, `vector`, `color`, `bsdf`, …) and,
/// for an input, the value it takes unconnected.
#[derive(Clone, Debug, PartialEq)]
pub struct Socket {
    pub name: String,
    pub ty: String,
    pub default: Option<Value>,
}

/// A node group: a graph used as a node. Inside, a node of type `group_input` has one
/// output per input; `outputs` are fed by `links` (output name, inner `"node.socket"`).
#[derive(Clone, Debug, Default)]
pub struct Group {
    pub inputs: Vec<Socket>,
    pub outputs: Vec<Socket>,
    pub nodes: Graph,
    pub links: Vec<(String, String)>,
}

/// A material graph under construction, nodes in the order added, with the groups its
/// nodes use.
#[derive(Clone, Debug, Default)]
pub struct Graph {
    nodes: Vec<(String, Node)>,
    groups: Vec<(String, Group)>,
}

impl Graph {
    /// Adds group `name`, replacing one of that name.
    pub fn add_group(&mut self, name: &str, group: Group) {
        set(&mut self.groups, name, group);
    }

    pub fn nodes(&self) -> &[(String, Node)] {
        &self.nodes
    }

    /// Adds `node` as `id` (or `id_2`, `id_3`, … if taken) and returns the id used.
    pub fn add(&mut self, id: &str, node: Node) -> String {
        let mut unique = id.to_owned();
        let mut n = 1;
        while self.nodes.iter().any(|(existing, _)| *existing == unique) {
            n += 1;
            unique = format!("{id}_{n}");
        }
        self.nodes.push((unique.clone(), node));
        unique
    }

    /// `a × b` for floats: folded when both are constants or one is 1, a `math` node
    /// (added as `id`) otherwise.
    pub fn multiply(&mut self, id: &str, a: Value, b: Value) -> Value {
        match (&a, &b) {
            (Value::Float(x), Value::Float(y)) => Value::Float(x * y),
            _ if a.is_one() => b,
            _ if b.is_one() => a,
            _ => {
                let node = Node::new("math")
                    .text("operation", "multiply")
                    .input("a", a)
                    .input("b", b);
                Value::link(&self.add(id, node), "value")
            }
        }
    }

    /// `a × b` channel by channel for colours (a float constant is grey): folded when
    /// both are constants or one is white, a multiplying `mix_color` node otherwise.
    pub fn multiply_color(&mut self, id: &str, a: Value, b: Value) -> Value {
        if let (Some(x), Some(y)) = (a.as_color(), b.as_color()) {
            return Value::Color([x[0] * y[0], x[1] * y[1], x[2] * y[2]]);
        }
        if a.is_one() {
            return b;
        }
        if b.is_one() {
            return a;
        }
        let node = Node::new("mix_color")
            .text("blend", "multiply")
            .input("factor", Value::Float(1.0))
            .input("a", a)
            .input("b", b);
        Value::link(&self.add(id, node), "result")
    }

    /// The graph as `.kmat` text named `name`, preceded by `comment` lines (line breaks
    /// in them become spaces).
    pub fn to_kmat(&self, name: &str, comment: &[String]) -> String {
        let mut out = String::new();
        for line in comment {
            let _ = writeln!(out, "// {}", line.replace(['\n', '\r'], " "));
        }
        let _ = writeln!(
            out,
            "(\n    version: 1,\n    name: {},\n    nodes: {{",
            string(name)
        );
        self.write_nodes(&mut out, "        ");
        out.push_str("    },\n");
        if !self.groups.is_empty() {
            out.push_str("    groups: {\n");
            for (name, group) in &self.groups {
                let sockets = |list: &[Socket]| -> String {
                    let items: Vec<String> = list
                        .iter()
                        .map(|s| {
                            let default = s
                                .default
                                .as_ref()
                                .map(|d| format!(", default: {}", d.text()))
                                .unwrap_or_default();
                            format!("(name: {}, type: {}{default})", string(&s.name), s.ty)
                        })
                        .collect();
                    items.join(", ")
                };
                let _ = writeln!(
                    out,
                    "        {}: (\n            inputs: [{}],\n            outputs: [{}],\n            nodes: {{",
                    string(name),
                    sockets(&group.inputs),
                    sockets(&group.outputs)
                );
                group.nodes.write_nodes(&mut out, "                ");
                let links: Vec<String> = group
                    .links
                    .iter()
                    .map(|(k, v)| format!("{}: {}", string(k), string(v)))
                    .collect();
                let _ = writeln!(
                    out,
                    "            }},\n            links: {{ {} }},\n        ),",
                    links.join(", ")
                );
            }
            out.push_str("    },\n");
        }
        out.push_str(")\n");
        out
    }

    fn write_nodes(&self, out: &mut String, indent: &str) {
        for (id, node) in &self.nodes {
            let _ = write!(out, "{indent}{}: (type: {}", string(id), string(&node.kind));
            if !node.params.is_empty() {
                let params = entries(&node.params, Param::text);
                let _ = write!(out, ", params: {{ {params} }}");
            }
            if !node.inputs.is_empty() {
                let inputs = entries(&node.inputs, Value::text);
                let _ = write!(out, ", inputs: {{ {inputs} }}");
            }
            if let Some([x, y]) = node.position {
                let _ = write!(out, ", position: ({}, {})", float(x), float(y));
            }
            if node.muted {
                out.push_str(", muted: true");
            }
            out.push_str("),\n");
        }
    }
}

/// `"name": value, …` of a RON map.
fn entries<T>(list: &[(String, T)], text: impl Fn(&T) -> String) -> String {
    let items: Vec<String> = list
        .iter()
        .map(|(k, v)| format!("{}: {}", string(k), text(v)))
        .collect();
    items.join(", ")
}

/// A RON float: always with a decimal point (RON reads `1` as an integer), and finite
/// (callers drop or clamp non-finite values; 0 is written if one slips through).
pub fn float(x: f32) -> String {
    let x = if x.is_finite() { x } else { 0.0 };
    let s = x.to_string();
    if s.contains('.') { s } else { format!("{s}.0") }
}

/// A RON string literal: quotes, backslashes and line breaks escaped, other control
/// characters as `\u{…}`.
pub fn string(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{{{:x}}}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strings_are_escaped_in_ron_style() {
        assert_eq!(string("a\"b\\c\nd\u{1}"), "\"a\\\"b\\\\c\\nd\\u{1}\"");
        assert_eq!(string(r#"a"b\c"#), r#""a\"b\\c""#);
    }

    #[test]
    fn floats_always_have_a_point_and_are_finite() {
        assert_eq!(float(1.0), "1.0");
        assert_eq!(float(-0.25), "-0.25");
        assert_eq!(float(f32::NAN), "0.0");
        assert_eq!(float(f32::INFINITY), "0.0");
        assert_eq!(float(1e-7), "0.0000001");
        assert_eq!(float(1e20), "100000000000000000000.0");
    }

    #[test]
    fn constant_products_fold_and_ids_stay_unique() {
        let mut g = Graph::default();
        assert_eq!(
            g.multiply("m", Value::Float(0.5), Value::Float(0.5)),
            Value::Float(0.25)
        );
        let l = Value::link("tex", "alpha");
        assert_eq!(g.multiply("m", Value::Float(1.0), l.clone()), l);
        assert_eq!(
            g.multiply("m", l.clone(), Value::Float(0.5)),
            Value::link("m", "value")
        );
        assert_eq!(
            g.multiply("m", l, Value::Float(0.5)),
            Value::link("m_2", "value")
        );
    }

    #[test]
    fn colour_products_fold_promote_floats_and_skip_white() {
        let mut g = Graph::default();
        assert_eq!(
            g.multiply_color("c", Value::Color([0.5, 1.0, 2.0]), Value::Float(0.5)),
            Value::Color([0.25, 0.5, 1.0])
        );
        let l = Value::link("tex", "color");
        assert_eq!(g.multiply_color("c", Value::Color([1.0; 3]), l.clone()), l);
        assert_eq!(
            g.multiply_color("c", Value::Color([0.5; 3]), l),
            Value::link("c", "result")
        );
        let text = g.to_kmat("m", &[]);
        assert!(text.contains(r#""blend": "multiply""#), "{text}");
        assert!(text.contains(r#""a": (0.5, 0.5, 0.5)"#), "{text}");
    }

    #[test]
    fn text_has_comments_params_typed_inputs_and_replaced_inputs_in_place() {
        let mut g = Graph::default();
        let mut node = Node::new("principled_bsdf")
            .flag("thin_walled", true)
            .text("name", "a \"b\"")
            .input("roughness", Value::Float(1.0))
            .input("normal", Value::Vector([0.0, 0.0, 1.0]));
        node.set_input("roughness", Value::link("tex", "color"));
        assert_eq!(
            node.get_input("roughness"),
            Some(&Value::link("tex", "color"))
        );
        g.add("surface", node);
        let text = g.to_kmat("x", &["two\nlines".to_owned()]);
        let expected = concat!(
            "// two lines\n",
            "(\n    version: 1,\n    name: \"x\",\n    nodes: {\n",
            r#"        "surface": (type: "principled_bsdf", params: { "thin_walled": true, "name": "a \"b\"" }, inputs: { "roughness": "tex.color", "normal": (0.0, 0.0, 1.0) }),"#,
            "\n    },\n)\n"
        );
        assert_eq!(text, expected);
    }
}
