//! A writer of `.kmat` text (docs/NODES.md): material graphs are assembled as nodes with
//! constant or linked inputs and printed in the RON syntax the host parses.
//!
//! It knows node types and sockets only as strings; the host compiles the graph and
//! reports mistakes. The arithmetic helpers fold constants, so a material without
//! textures is a single principled node with numbers.

use std::fmt::Write;

/// An input: a constant, or the output `socket` of node `node`.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Float(f32),
    Color([f32; 3]),
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
            Value::Link(_) => false,
        }
    }

    fn as_color(&self) -> Option<[f32; 3]> {
        match *self {
            Value::Float(v) => Some([v; 3]),
            Value::Color(c) => Some(c),
            Value::Link(_) => None,
        }
    }
}

/// A node parameter.
#[derive(Clone, Debug)]
pub enum Param {
    Text(String),
    Flag(bool),
}

/// One node: its type, parameters and set inputs.
#[derive(Clone, Debug)]
pub struct Node {
    kind: &'static str,
    params: Vec<(&'static str, Param)>,
    inputs: Vec<(&'static str, Value)>,
}

impl Node {
    pub fn new(kind: &'static str) -> Self {
        Self {
            kind,
            params: Vec::new(),
            inputs: Vec::new(),
        }
    }

    pub fn text(mut self, name: &'static str, value: &str) -> Self {
        self.params.push((name, Param::Text(value.to_owned())));
        self
    }

    pub fn flag(mut self, name: &'static str, value: bool) -> Self {
        self.params.push((name, Param::Flag(value)));
        self
    }

    pub fn input(mut self, name: &'static str, value: Value) -> Self {
        self.inputs.push((name, value));
        self
    }
}

/// A material graph under construction.
#[derive(Default)]
pub struct Graph {
    nodes: Vec<(String, Node)>,
}

impl Graph {
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

    /// `a × b` for floats: folded when both are constants or one is 1, a math node otherwise.
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

    /// `a × b` channel by channel for colours.
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

    /// The graph as `.kmat` text named `name`.
    pub fn to_kmat(&self, name: &str) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "(version: 1, name: {}, nodes: {{", quote(name));
        for (id, node) in &self.nodes {
            let _ = write!(s, "  {}: (type: {}", quote(id), quote(node.kind));
            if !node.params.is_empty() {
                s.push_str(", params: {");
                for (i, (name, param)) in node.params.iter().enumerate() {
                    let sep = if i == 0 { " " } else { ", " };
                    let value = match param {
                        Param::Text(t) => quote(t),
                        Param::Flag(f) => f.to_string(),
                    };
                    let _ = write!(s, "{sep}{}: {value}", quote(name));
                }
                s.push_str(" }");
            }
            if !node.inputs.is_empty() {
                s.push_str(", inputs: {");
                for (i, (name, value)) in node.inputs.iter().enumerate() {
                    let sep = if i == 0 { " " } else { ", " };
                    let _ = write!(s, "{sep}{}: {}", quote(name), value_text(value));
                }
                s.push_str(" }");
            }
            s.push_str("),\n");
        }
        s.push_str("})\n");
        s
    }
}

/// A RON float: always with a decimal point, never `inf` or `NaN` (0 instead; callers
/// clamp to meaningful ranges before this).
fn float_text(v: f32) -> String {
    let v = if v.is_finite() { v } else { 0.0 };
    let t = v.to_string();
    if t.contains('.') { t } else { format!("{t}.0") }
}

fn value_text(v: &Value) -> String {
    match v {
        Value::Float(x) => float_text(*x),
        Value::Color([r, g, b]) => {
            format!(
                "({}, {}, {})",
                float_text(*r),
                float_text(*g),
                float_text(*b)
            )
        }
        Value::Link(l) => quote(l),
    }
}

/// A RON string literal.
pub fn quote(s: &str) -> String {
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
        assert_eq!(quote("a\"b\\c\nd\u{1}"), "\"a\\\"b\\\\c\\nd\\u{1}\"");
    }

    #[test]
    fn floats_always_have_a_point_and_are_finite() {
        assert_eq!(float_text(1.0), "1.0");
        assert_eq!(float_text(0.25), "0.25");
        assert_eq!(float_text(f32::NAN), "0.0");
        assert_eq!(float_text(1e-7), "0.0000001");
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
}
