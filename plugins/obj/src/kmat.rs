//! Writing `.kmat` material graphs (RON text, docs/NODES.md) without depending on Kiln:
//! nodes with typed inputs and parameters, numbers always written as RON floats and
//! strings escaped. It writes graphs; it does not check them (Kiln does when the host
//! adds the material).

use std::fmt::Write;

/// A node input: a constant or a link to another node's output.
#[derive(Clone, Debug, PartialEq)]
pub enum Input {
    Float(f32),
    Color([f32; 3]),
    Vector([f32; 3]),
    /// `"node.socket"`.
    Link(String),
}

impl Input {
    pub fn link(node: &str, socket: &str) -> Self {
        Input::Link(format!("{node}.{socket}"))
    }
}

/// A node parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum Param {
    Text(String),
    Bool(bool),
}

#[derive(Clone, Debug)]
struct Node {
    id: String,
    kind: String,
    params: Vec<(String, Param)>,
    inputs: Vec<(String, Input)>,
}

/// A graph being written, nodes in the order added.
#[derive(Clone, Debug, Default)]
pub struct Kmat {
    nodes: Vec<Node>,
}

impl Kmat {
    /// Adds node `id` of type `kind`; returns its index for [`Kmat::set_input`].
    pub fn node(
        &mut self,
        id: &str,
        kind: &str,
        params: Vec<(&str, Param)>,
        inputs: Vec<(&str, Input)>,
    ) -> usize {
        self.nodes.push(Node {
            id: id.to_owned(),
            kind: kind.to_owned(),
            params: params.into_iter().map(|(k, v)| (k.to_owned(), v)).collect(),
            inputs: inputs.into_iter().map(|(k, v)| (k.to_owned(), v)).collect(),
        });
        self.nodes.len() - 1
    }

    /// Sets (or replaces) an input of the node at `index`.
    pub fn set_input(&mut self, index: usize, name: &str, input: Input) {
        let inputs = &mut self.nodes[index].inputs;
        match inputs.iter_mut().find(|(k, _)| k == name) {
            Some(slot) => slot.1 = input,
            None => inputs.push((name.to_owned(), input)),
        }
    }

    /// The `.kmat` text, named `name`, preceded by `comment` lines.
    pub fn to_text(&self, name: &str, comment: &[String]) -> String {
        let mut out = String::new();
        for line in comment {
            let _ = writeln!(out, "// {}", line.replace(['\n', '\r'], " "));
        }
        let _ = writeln!(
            out,
            "(\n    version: 1,\n    name: {},\n    nodes: {{",
            string(name)
        );
        for node in &self.nodes {
            let _ = write!(
                out,
                "        {}: (type: {}",
                string(&node.id),
                string(&node.kind)
            );
            if !node.params.is_empty() {
                let params: Vec<String> = node
                    .params
                    .iter()
                    .map(|(k, v)| {
                        let v = match v {
                            Param::Text(t) => string(t),
                            Param::Bool(b) => b.to_string(),
                        };
                        format!("{}: {v}", string(k))
                    })
                    .collect();
                let _ = write!(out, ", params: {{ {} }}", params.join(", "));
            }
            if !node.inputs.is_empty() {
                let inputs: Vec<String> = node
                    .inputs
                    .iter()
                    .map(|(k, v)| {
                        let v = match v {
                            Input::Float(x) => float(*x),
                            Input::Color(c) | Input::Vector(c) => {
                                format!("({}, {}, {})", float(c[0]), float(c[1]), float(c[2]))
                            }
                            Input::Link(l) => string(l),
                        };
                        format!("{}: {v}", string(k))
                    })
                    .collect();
                let _ = write!(out, ", inputs: {{ {} }}", inputs.join(", "));
            }
            out.push_str("),\n");
        }
        out.push_str("    },\n)\n");
        out
    }
}

/// A RON float: always with a decimal point (RON reads `1` as an integer), and finite
/// (callers drop non-finite values; 0 is written if one slips through).
pub fn float(x: f32) -> String {
    let x = if x.is_finite() { x } else { 0.0 };
    let s = format!("{x}");
    if s.contains('.') { s } else { format!("{s}.0") }
}

/// A RON string literal.
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
            // Names never need them; a space keeps the text readable and valid.
            c if c.is_control() => out.push(' '),
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
    fn floats_always_have_a_decimal_point() {
        assert_eq!(float(1.0), "1.0");
        assert_eq!(float(-0.25), "-0.25");
        assert_eq!(float(f32::NAN), "0.0");
        assert_eq!(float(1e20), "100000000000000000000.0");
    }

    #[test]
    fn strings_escape_quotes_and_backslashes() {
        assert_eq!(string(r#"a"b\c"#), r#""a\"b\\c""#);
    }
}
