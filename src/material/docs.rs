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

## Worlds

The world (Blender's World) is a graph of the same nodes ending in a **World Output** node
instead of a Material Output: the radiance that arrives from each direction where a ray
leaves the scene. A scene names it with `world: (graph_file: \"sky.kmat\")` or an inline
`graph` (docs/SCENE_FORMAT.md); it takes the place of the constant environment and the
environment map. In a world the shading point looks from the origin: the position, the
generated and object coordinates (what a texture's vector reads unconnected) are the
view direction, +Y up, so a Gradient or Noise Texture varies over the sky and a Mapping
node rotates it. An **Environment Texture** reads an equirectangular image by direction;
the **Sky Texture** is a physically based clear sky.

```ron
(
    version: 1,
    name: \"Clear sky\",
    nodes: {
        \"sky\": (type: \"sky_texture\", inputs: { \"sun_elevation\": 35.0, \"sun_rotation\": 140.0 }),
        \"out\": (type: \"world_output\", inputs: { \"color\": \"sky.color\", \"strength\": 1.0 }),
    },
)
```

The renderer bakes the world into an equirectangular map (`resolution` texels wide, half
as high; 1024 unless the scene says) at the start of a render, and samples that map by
importance against BSDF sampling, as it does an environment map loaded from a file. A
world whose output reads no link keeps the constant environment's exact path. A Sky
Texture's sun is not baked: with `sun_disc` on, it becomes a sun light of the node's
size, sampled analytically and seen by camera and glossy rays, whose irradiance is the
node's `sun` output carried through what the graph does to the sky's colour (a strength,
a tint, a mix). So its elevation, rotation and size must be values, not links, and the
node must stand at the top level of the graph.

The Sky Texture integrates single scattering along each view ray in a spherical
atmosphere (Nishita 1993, the model of Cycles' Nishita sky): Rayleigh scattering by air
(8 km scale height), Mie scattering and absorption by aerosols (1.2 km), absorption by a
layer of ozone (300 Dobson units at 1), at 16 wavelengths from 380 to 755 nm under a
5778 K black-body sun of 1361 W/m², converted to linear Rec. 709 through the CIE 1931
colour-matching functions. Its unit is spectral radiance, W/(m²·sr·nm), averaged under
the luminance curve ȳ: a white surface under a sun 35° up in a clear sky receives about
0.85 in all, which the look-dev default exposes as +1.9 stops. Tested against Bucholtz's
Rayleigh optical depths and Kasten and Young's air mass (`tests/world.rs`): the sun
through clear air keeps what they predict within 0.4% (at the zenith and 30° up). Below
the horizon the view ray ends at a matte ground (`ground_albedo`, 0.3) lit by the sun
through the atmosphere, seen through the haze in front of it.
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

/// The declarations of node types `kinds` as RON, for material exporters that must type
/// every socket they write (`kiln_plugin_api::kmat::read::parse_library`): per type its
/// inputs with their types and constant defaults (or the WGSL of the shading-point
/// property an unconnected one reads, `sp.generated`), its outputs, and the defaults of
/// its choice and flag parameters. Unknown kinds (group
/// nodes, reroutes, outputs) are left out.
pub fn library_text<'a>(kinds: impl IntoIterator<Item = &'a str>) -> String {
    let mut kinds: Vec<&str> = kinds.into_iter().collect();
    kinds.sort_unstable();
    kinds.dedup();
    let mut out = String::from("[\n");
    for def in kinds.into_iter().filter_map(super::nodes::find) {
        let inputs: Vec<String> = def
            .inputs
            .iter()
            .map(|s| {
                let default = match &s.default {
                    Default::Value(v) => format!(", default: {}", value_text(v)),
                    Default::Implicit(expr, _) => format!(", implicit: {expr:?}"),
                };
                format!("(name: {:?}, type: {}{default})", s.name, s.ty.name())
            })
            .collect();
        let outputs: Vec<String> = def
            .outputs
            .iter()
            .map(|o| format!("(name: {:?}, type: {})", o.name, o.ty.name()))
            .collect();
        let params: Vec<String> = def
            .params
            .iter()
            .filter_map(|p| {
                let default = match p.kind {
                    ParamKind::Enum(options) => format!("{:?}", options.first()?),
                    ParamKind::Bool(b) => b.to_string(),
                    ParamKind::Ramp | ParamKind::File => return None,
                };
                Some(format!("(name: {:?}, default: {default})", p.name))
            })
            .collect();
        let _ = writeln!(
            out,
            "    (type: {:?}, inputs: [{}], outputs: [{}], params: [{}]),",
            def.kind,
            inputs.join(", "),
            outputs.join(", "),
            params.join(", ")
        );
    }
    out.push_str("]\n");
    out
}

/// A constant in RON, as `.kmat` files write it.
fn value_text(v: &Value) -> String {
    let f = |x: f32| format!("{x:?}");
    match v {
        Value::Float(x) => f(*x),
        Value::Vec2([x, y]) => format!("({}, {})", f(*x), f(*y)),
        Value::Vec3([x, y, z]) => format!("({}, {}, {})", f(*x), f(*y), f(*z)),
    }
}
