//! `docs/NODES.md`, generated from the node declarations (`kiln material nodes`); a test
//! keeps the committed file in step with the library.

use std::fmt::Write as _;

use super::graph::Value;
use super::nodes::{Default, ParamKind, library};

const HEADER: &str = "# Material nodes

Generated from `src/material/nodes.rs` by `kiln material nodes > docs/NODES.md`; do not edit.

A material is a graph of these nodes, saved as a `.kmat` file (RON):

```ron
(
    version: 1,
    name: \"Checker floor\",
    nodes: {
        \"checker\": (type: \"checker_texture\", inputs: { \"scale\": 8.0 }),
        \"surface\": (type: \"principled_bsdf\", inputs: { \"base_color\": \"checker.color\" }),
        \"out\": (type: \"material_output\", inputs: { \"surface\": \"surface.bsdf\" }),
    },
)
```

An input is a value (`0.5`, `(0.1, 0.2, 0.3)`) or a link `\"node.output\"`; inputs left out take
the defaults below. Floats feed vector and colour inputs (every channel), colours feed
floats (luminance) and vectors feed floats (the mean), as in Blender; other types do not
mix. `groups: { \"name\": (inputs: [(name: \"x\", type: float, default: 1.0)], outputs:
[(name: \"y\", type: color)], nodes: {...}, links: { \"y\": \"inner.socket\" }) }` declares a
node group, used as `(type: \"group\", params: { \"group\": \"name\" })`; inside, node type
`group_input` has one output per group input. `frames: { \"frame\": (label: \"Veins\", color: (0.2,
0.3, 0.4), nodes: [\"veins\", \"ramp\"]) }` (in a graph or a group) are the editor's labelled boxes
around nodes, and a group's `output_position` where the editor draws its output node; neither
means anything to the compiler.

A float input's range is the values it may be set to: the compiler reports a value outside
it, naming node and socket (what a link brings is not limited; the Principled BSDF clamps
what it is fed). `(type: \"reroute\", inputs: { \"input\": \"node.output\" })` passes
a wire on with the type of what feeds it (its output is `output`; it compiles to nothing).
`muted: true` mutes a node: each output passes the node's first input of the same type (a
link, a value or that input's default), or 0 / black when it has none (a shader output:
what its consumer reads unconnected). `preview: true` shows the node's output as an image
under it in the node editor; the compiler ignores it.
";

fn value(v: &Value) -> String {
    match v {
        Value::Float(x) => format!("{x}"),
        Value::Vec2(a) => format!("({}, {})", a[0], a[1]),
        Value::Vec3(a) => format!("({}, {}, {})", a[0], a[1], a[2]),
    }
}

pub fn nodes_markdown() -> String {
    let mut out = String::from(HEADER);
    let mut category = "";
    for def in library() {
        if def.category != category {
            category = def.category;
            let _ = writeln!(out, "\n## {category}\n");
        }
        let _ = writeln!(out, "### {} (`{}`)\n\n{}\n", def.label, def.kind, def.doc);
        if !def.inputs.is_empty() {
            out.push_str("| input | type | default | range | |\n|---|---|---|---|---|\n");
            for s in &def.inputs {
                let default = match &s.default {
                    Default::Value(v) => value(v),
                    Default::Implicit(_, what) => (*what).to_owned(),
                };
                let range = s.range.map(|r| r.describe()).unwrap_or_default();
                let _ = writeln!(
                    out,
                    "| `{}` | {} | {} | {} | {} |",
                    s.name,
                    s.ty.name(),
                    default,
                    range,
                    s.doc
                );
            }
            out.push('\n');
        }
        if !def.outputs.is_empty() {
            out.push_str("| output | type | |\n|---|---|---|\n");
            for o in &def.outputs {
                let _ = writeln!(out, "| `{}` | {} | {} |", o.name, o.ty.name(), o.doc);
            }
            out.push('\n');
        }
        if !def.params.is_empty() {
            out.push_str("| parameter | values | |\n|---|---|---|\n");
            for p in &def.params {
                let values = match &p.kind {
                    ParamKind::Enum(options) => options
                        .iter()
                        .map(|o| format!("`{o}`"))
                        .collect::<Vec<_>>()
                        .join(", "),
                    ParamKind::Bool(d) => format!("`true`/`false` (default `{d}`)"),
                    ParamKind::Ramp => "`[(position: 0.0, color: (r, g, b, a)), …]`".into(),
                    ParamKind::File => "a file path".into(),
                };
                let _ = writeln!(out, "| `{}` | {} | {} |", p.name, values, p.doc);
            }
            out.push('\n');
        }
    }
    out
}
