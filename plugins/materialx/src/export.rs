//! Kiln graphs as MaterialX 1.39: the Principled BSDF as `open_pbr_surface` (the same
//! model, [`crate::surface::OPEN_PBR`]), nodes matching a [`crate::table`] row as that
//! standard-library node, coordinates and images as `texcoord`, `position`, `normal`,
//! `tangent` and `image`, node groups as node definitions implemented by node graphs
//! (`kiln_group_NAME`), and every other Kiln node as a node of category `kiln_TYPE`
//! declared by a node definition, so that every file written is valid MaterialX.
//! Implicit conversions between Kiln's socket types become `convert` nodes (colour to
//! float: a luminance dot product, as Kiln converts).

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fmt::Write as _;

use kiln_plugin_api::kmat::read::{self, File, Input, Node, NodeType, Param, SocketType};

use crate::implement::{self, Src};
use crate::import::{
    KILN_GROUP_PREFIX, KILN_NODE_PREFIX, POSITION_SCALE, SPARE_OF, VOLUME_MATERIAL, WITH_SURFACE,
};
use crate::surface::{KILN_ONLY, OPEN_PBR, OPEN_PBR_NORMAL, OPEN_PBR_THIN_WALLED};
use crate::table::{self, Fixed};

/// The MaterialX document of material `name` with graph `kmat`, whose node types
/// `library` declares.
pub fn export(name: &str, kmat: &str, library: &str) -> Result<String, String> {
    let file = read::parse(kmat).map_err(|e| format!("the material's graph: {e}"))?;
    let library: HashMap<String, NodeType> = read::parse_library(library)
        .map_err(|e| format!("the node library: {e}"))?
        .into_iter()
        .map(|t| (t.kind.clone(), t))
        .collect();
    let output = match &file.output {
        Some(o) => o.clone(),
        None => file
            .nodes
            .iter()
            .find(|(_, n)| n.kind == "material_output")
            .map(|(id, _)| id.clone())
            .ok_or("the graph has no material_output node")?,
    };
    let shader = |socket: &str| {
        file.nodes
            .get(&output)
            .and_then(|n| n.inputs.get(socket))
            .and_then(Input::link)
    };
    let (surface, volume) = (shader("surface"), shader("volume"));
    if surface.is_none() && volume.is_none() {
        return Err(format!(
            "output node {output} has neither a surface nor a volume connected"
        ));
    }
    let mut doc = Document {
        file: &file,
        library: &library,
        definitions: BTreeMap::new(),
        implementations: BTreeMap::new(),
        declared_params: BTreeMap::new(),
        groups_written: BTreeSet::new(),
        group_text: String::new(),
    };
    let mut scope = Scope::new(&file.nodes, None);
    let mut shaders = Vec::new();
    for (input, link) in [("surfaceshader", surface), ("volumeshader", volume)] {
        if let Some((node, socket)) = link {
            let out = doc.emit(&mut scope, node, socket)?;
            shaders.push((input, out.reference()));
        }
    }
    // Nodes nothing reads are kept too (a graph's spare nodes are the user's), marked
    // as the material's.
    let material = sanitize(name);
    scope.mark = format!(" {SPARE_OF}=\"{material}\"");
    doc.emit_rest(&mut scope)?;
    scope.mark.clear();
    let mut text = String::from(
        "<?xml version=\"1.0\"?>\n<materialx version=\"1.39\" colorspace=\"lin_rec709\">\n",
    );
    for definition in doc.definitions.values() {
        text.push_str(definition);
    }
    for implementation in doc.implementations.values() {
        text.push_str(implementation);
    }
    text.push_str(&doc.group_text);
    text.push_str(&scope.text);
    // A volume is a material of its own in MaterialX; beside a surface, it names the
    // surface material it belongs with.
    let surface_name = scope.unique(&material);
    for (input, reference) in shaders {
        let (element, name, with) = if input == "surfaceshader" {
            ("surfacematerial", surface_name.clone(), String::new())
        } else if surface.is_some() {
            let name = scope.unique(&format!("{material}_volume"));
            (
                VOLUME_MATERIAL,
                name,
                format!(" {WITH_SURFACE}=\"{surface_name}\""),
            )
        } else {
            (VOLUME_MATERIAL, surface_name.clone(), String::new())
        };
        let _ = write!(
            text,
            "  <{element} name=\"{name}\" type=\"material\"{with}>\n    <input name=\"{input}\" type=\"{input}\" {reference} />\n  </{element}>\n"
        );
    }
    text.push_str("</materialx>\n");
    Ok(text)
}

/// Marks the nodes that stand for Kiln's implicit conversions, which the importer
/// reads as plain connections.
const CONVERSION: &str = " kiln_conversion=\"true\"";

/// A MaterialX name: letters, digits and underscores, not starting with a digit.
pub fn sanitize(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    s
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn number(x: f32) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        "0".into()
    }
}

/// A constant as MaterialX writes a value of type `ty`.
fn value_text(v: &Input, ty: &str) -> String {
    let c = match v {
        Input::Float(x) => [*x; 3],
        Input::Vec2([x, y]) => [*x, *y, 0.0],
        Input::Vec3(c) => *c,
        Input::Link(_) => [0.0; 3],
    };
    match ty {
        "float" => number(match v {
            Input::Vec3([r, g, b]) => (r + g + b) / 3.0,
            _ => c[0],
        }),
        "vector2" => format!("{}, {}", number(c[0]), number(c[1])),
        _ => format!("{}, {}, {}", number(c[0]), number(c[1]), number(c[2])),
    }
}

/// The MaterialX names of a node's outputs (Kiln name, MaterialX type): a single
/// output is `out`, as MaterialX requires of single-output nodes; several keep Kiln's
/// names (`out_NAME` where an input has the name). Returns (MaterialX name, Kiln name,
/// type) and the node's type.
fn output_names(
    outputs: &[(String, String)],
    inputs: &[&str],
) -> (Vec<(String, String, String)>, String) {
    if let [(kiln, ty)] = outputs {
        return (vec![("out".into(), kiln.clone(), ty.clone())], ty.clone());
    }
    let names = outputs
        .iter()
        .map(|(kiln, ty)| {
            let mx = if inputs.contains(&kiln.as_str()) {
                format!("out_{kiln}")
            } else {
                sanitize(kiln)
            };
            (mx, kiln.clone(), ty.clone())
        })
        .collect();
    (names, "multioutput".into())
}

/// What an exported socket is: a node's output, or the enclosing graph's interface.
#[derive(Clone, Debug)]
struct Out {
    node: String,
    /// The output's name, for multi-output nodes.
    output: Option<String>,
    interface: bool,
    ty: String,
}

impl Out {
    fn reference(&self) -> String {
        if self.interface {
            return format!("interfacename=\"{}\"", self.node);
        }
        match &self.output {
            Some(o) => format!("nodename=\"{}\" output=\"{o}\"", self.node),
            None => format!("nodename=\"{}\"", self.node),
        }
    }
}

/// One graph being written: the document's top level, or a group's node graph.
struct Scope<'f> {
    nodes: &'f BTreeMap<String, Node>,
    /// The group's inputs, inside a group.
    interface: Option<&'f [read::Socket]>,
    done: HashMap<(String, String), Out>,
    names: BTreeSet<String>,
    text: String,
    indent: &'static str,
    /// Attributes every node written gets (spare nodes name their material).
    mark: String,
    /// Nodes written as part of another (a tiled image's mapping).
    consumed: BTreeSet<String>,
}

impl<'f> Scope<'f> {
    fn new(nodes: &'f BTreeMap<String, Node>, interface: Option<&'f [read::Socket]>) -> Self {
        Self {
            nodes,
            interface,
            done: HashMap::new(),
            names: BTreeSet::new(),
            text: String::new(),
            indent: if interface.is_some() { "    " } else { "  " },
            mark: String::new(),
            consumed: BTreeSet::new(),
        }
    }

    /// `name`, made unique in this graph.
    fn unique(&mut self, name: &str) -> String {
        let base = sanitize(name);
        let mut n = base.clone();
        let mut i = 1;
        while self.names.contains(&n) {
            i += 1;
            n = format!("{base}_{i}");
        }
        self.names.insert(n.clone());
        n
    }

    /// Writes a node element: category, name, type, extra attributes and inputs
    /// (`name`, `type`, the rest of the input's attributes).
    fn write(
        &mut self,
        category: &str,
        name: &str,
        ty: &str,
        attributes: &str,
        inputs: &[(String, String, String)],
    ) {
        let i = self.indent;
        let mark = &self.mark;
        let _ = writeln!(
            self.text,
            "{i}<{category} name=\"{name}\" type=\"{ty}\"{attributes}{mark}>"
        );
        for (input, ty, rest) in inputs {
            let _ = writeln!(
                self.text,
                "{i}  <input name=\"{input}\" type=\"{ty}\" {rest} />"
            );
        }
        let _ = writeln!(self.text, "{i}</{category}>");
    }
}

struct Document<'f> {
    file: &'f File,
    library: &'f HashMap<String, NodeType>,
    /// Node definitions of `kiln_*` categories, by category.
    definitions: BTreeMap<String, String>,
    /// Their node-graph implementations, where Kiln's node has one.
    implementations: BTreeMap<String, String>,
    /// The parameters each `kiln_*` definition declares (name → MaterialX type): those
    /// any node of the category set.
    declared_params: BTreeMap<String, BTreeMap<String, String>>,
    groups_written: BTreeSet<String>,
    group_text: String,
}

impl<'f> Document<'f> {
    fn node_type(&self, kind: &str) -> Result<&'f NodeType, String> {
        self.library
            .get(kind)
            .ok_or(format!("node type {kind} is not declared by the host"))
    }

    /// A node's parameter, or its declared default.
    fn param(&self, node: &Node, name: &str) -> Option<Param> {
        node.params.get(name).cloned().or_else(|| {
            let t = self.library.get(&node.kind)?;
            t.params
                .iter()
                .find(|p| p.name == name)
                .map(|p| p.default.clone())
        })
    }

    /// A node's input: set, or its declared default (`None` for an implicit one).
    fn input(&self, node: &Node, name: &str) -> Option<Input> {
        node.inputs.get(name).cloned().or_else(|| {
            let t = self.library.get(&node.kind)?;
            t.inputs.iter().find(|s| s.name == name)?.default.clone()
        })
    }

    /// Writes the nodes of `scope` not yet written (by their first output).
    fn emit_rest(&mut self, scope: &mut Scope<'f>) -> Result<(), String> {
        for (id, node) in scope.nodes {
            if matches!(
                node.kind.as_str(),
                "material_output" | "group_input" | "reroute"
            ) || scope.done.keys().any(|(n, _)| n == id)
                || scope.consumed.contains(id)
            {
                continue;
            }
            let first = match node.kind.as_str() {
                "group" => match node.params.get("group") {
                    Some(Param::Text(g)) => self
                        .file
                        .groups
                        .get(g)
                        .and_then(|g| g.outputs.first())
                        .map(|o| o.name.clone()),
                    _ => None,
                },
                kind => self
                    .library
                    .get(kind)
                    .and_then(|t| t.outputs.first())
                    .map(|o| o.name.clone()),
            };
            if let Some(socket) = first {
                self.emit(scope, id, &socket)?;
            }
        }
        Ok(())
    }

    /// Writes (once) what computes output `socket` of node `id`, and returns it.
    fn emit(&mut self, scope: &mut Scope<'f>, id: &str, socket: &str) -> Result<Out, String> {
        let key = (id.to_owned(), socket.to_owned());
        if let Some(out) = scope.done.get(&key) {
            return Ok(out.clone());
        }
        let node = scope
            .nodes
            .get(id)
            .ok_or(format!("a link names node {id}, which is not in the graph"))?;
        let out = self.emit_new(scope, id, node, socket)?;
        scope.done.insert(key, out.clone());
        Ok(out)
    }

    fn emit_new(
        &mut self,
        scope: &mut Scope<'f>,
        id: &str,
        node: &'f Node,
        socket: &str,
    ) -> Result<Out, String> {
        let position = match node.position {
            Some([x, y]) => format!(
                " xpos=\"{}\" ypos=\"{}\"",
                number(x / POSITION_SCALE),
                number(y / POSITION_SCALE)
            ),
            None => String::new(),
        };
        match node.kind.as_str() {
            "group_input" => {
                let socket_type = scope
                    .interface
                    .and_then(|i| i.iter().find(|s| s.name == socket))
                    .ok_or(format!("group input {socket} is not declared"))?;
                return Ok(Out {
                    node: socket.to_owned(),
                    output: None,
                    interface: true,
                    ty: table::mx_type(socket_type.ty.name()).to_owned(),
                });
            }
            "reroute" => {
                let (from, from_socket) = node
                    .inputs
                    .get("input")
                    .and_then(Input::link)
                    .ok_or(format!("reroute {id} is not connected"))?;
                return self.emit(scope, from, from_socket);
            }
            "principled_bsdf" => return self.principled(scope, id, node, &position),
            "group" => return self.group_node(scope, id, node, socket, &position),
            "texture_coordinate" | "geometry" => {
                if let Some(out) = self.coordinate(scope, id, node, socket, &position)? {
                    return Ok(out);
                }
            }
            "image_texture" if socket == "color" => {
                return self.image(scope, id, node, &position);
            }
            _ => {}
        }
        let node_type = self.node_type(&node.kind)?;
        let output_ty = node_type
            .outputs
            .iter()
            .find(|o| o.name == socket)
            .map(|o| table::mx_type(o.ty.name()))
            .ok_or(format!("node {id} ({}) has no output {socket}", node.kind))?;
        if let Some(row) = self.row_for(node, output_ty) {
            let name = scope.unique(id);
            let mut inputs = Vec::new();
            for (mx, value) in row.mx_fixed {
                inputs.push((
                    mx.to_string(),
                    output_ty.to_owned(),
                    format!("value=\"{}\"", number(*value)),
                ));
            }
            for (mx, kiln, _) in row.inputs {
                let ty = table::mx_input_type(row, mx).unwrap_or_else(|| {
                    node_type
                        .inputs
                        .iter()
                        .find(|s| s.name == *kiln)
                        .map_or("float", |s| table::mx_type(s.ty.name()))
                });
                inputs.push(self.input_xml(scope, node, mx, kiln, ty)?);
            }
            let multi = row.outputs.len() > 1;
            let mx_output = row
                .outputs
                .iter()
                .find(|(_, k)| *k == socket)
                .map(|(m, _)| m.to_string());
            let node_ty = if multi { "multioutput" } else { output_ty };
            scope.write(row.mx, &name, node_ty, &position, &inputs);
            // Every output of a multi-output node is this one node.
            for (mx, kiln) in row.outputs {
                let ty = node_type
                    .outputs
                    .iter()
                    .find(|o| o.name == *kiln)
                    .map_or(output_ty, |o| table::mx_type(o.ty.name()));
                let out = Out {
                    node: name.clone(),
                    output: multi.then(|| mx.to_string()),
                    interface: false,
                    ty: ty.to_owned(),
                };
                scope.done.insert((id.to_owned(), kiln.to_string()), out);
            }
            if mx_output.is_some() {
                return Ok(scope.done[&(id.to_owned(), socket.to_owned())].clone());
            }
        }
        self.custom(scope, id, node, socket, &position)
    }

    /// The table row a Kiln node computes exactly: same type, parameters, and the
    /// values of the inputs the row fixes.
    fn row_for(&self, node: &Node, output_ty: &str) -> Option<&'static table::Row> {
        table::ROWS.iter().find(|row| {
            // A node with several outputs is told apart by its first input's type.
            let ty = match row.inputs.first() {
                Some((_, kiln, _)) if row.outputs.len() > 1 => self
                    .library
                    .get(&node.kind)
                    .and_then(|t| t.inputs.iter().find(|s| s.name == *kiln))
                    .map_or(output_ty, |s| table::mx_type(s.ty.name())),
                _ => output_ty,
            };
            row.kiln == node.kind
                && row.types.contains(&ty)
                && row.params.iter().all(|(p, v)| {
                    let want = match v {
                        Fixed::Text(t) => Param::Text(t.to_string()),
                        Fixed::Flag(b) => Param::Bool(*b),
                    };
                    self.param(node, p) == Some(want)
                })
                && row.fixed.iter().all(|(i, v)| self.input(node, i) == Some(Input::Float(*v)))
                && !node.muted
                // Every set input has a place in the row.
                && node.inputs.keys().all(|k| {
                    row.inputs.iter().any(|(_, kiln, _)| kiln == k)
                        || row.fixed.iter().any(|(f, _)| f == k)
                })
                // Params the row does not fix keep their defaults (math's clamp).
                && node.params.keys().all(|k| row.params.iter().any(|(p, _)| p == k) || self.library.get(&node.kind).and_then(|t| t.params.iter().find(|d| d.name == *k)).is_some_and(|d| node.params.get(k) == Some(&d.default)))
        })
    }

    /// `<input>` attributes for Kiln input `kiln` of `node` as MaterialX input `mx` of
    /// type `ty`: its value, or a connection (converted where types differ).
    fn input_xml(
        &mut self,
        scope: &mut Scope<'f>,
        node: &Node,
        mx: &str,
        kiln: &str,
        ty: &str,
    ) -> Result<(String, String, String), String> {
        match self.input(node, kiln) {
            Some(Input::Link(l)) => {
                let (from, socket) = l
                    .rsplit_once('.')
                    .ok_or(format!("link {l} has no socket"))?;
                let out = self.emit(scope, from, socket)?;
                let out = self.convert(scope, out, ty);
                Ok((mx.to_owned(), ty.to_owned(), out.reference()))
            }
            Some(v) => Ok((
                mx.to_owned(),
                ty.to_owned(),
                format!("value=\"{}\"", value_text(&v, ty)),
            )),
            // An implicit default (the shading point's): MaterialX's own default,
            // which for these inputs is the same geometric property.
            None => Ok((mx.to_owned(), ty.to_owned(), String::new())),
        }
    }

    /// `out` as type `ty`: itself, or through `convert` nodes as Kiln converts
    /// implicitly (float to all channels, colour to float by Rec. 709 luminance, vector
    /// to float by the mean).
    fn convert(&mut self, scope: &mut Scope<'f>, out: Out, ty: &str) -> Out {
        if out.ty == ty || ty == "surfaceshader" {
            return out;
        }
        let to_float = ty == "float";
        if to_float {
            let vector = if out.ty == "vector3" {
                out.clone()
            } else {
                self.convert_node(scope, &out, "vector3")
            };
            let weights = if out.ty == "color3" {
                "0.2126, 0.7152, 0.0722"
            } else {
                "0.333333, 0.333333, 0.333333"
            };
            let name = scope.unique(&format!("{}_to_float", out.node));
            let inputs = vec![
                ("in1".to_owned(), "vector3".to_owned(), vector.reference()),
                (
                    "in2".to_owned(),
                    "vector3".to_owned(),
                    format!("value=\"{weights}\""),
                ),
            ];
            scope.write("dotproduct", &name, "float", CONVERSION, &inputs);
            return Out {
                node: name,
                output: None,
                interface: false,
                ty: "float".into(),
            };
        }
        self.convert_node(scope, &out, ty)
    }

    fn convert_node(&mut self, scope: &mut Scope<'f>, out: &Out, ty: &str) -> Out {
        let name = scope.unique(&format!("{}_to_{ty}", out.node));
        let inputs = vec![("in".to_owned(), out.ty.clone(), out.reference())];
        scope.write("convert", &name, ty, CONVERSION, &inputs);
        Out {
            node: name,
            output: None,
            interface: false,
            ty: ty.to_owned(),
        }
    }

    fn principled(
        &mut self,
        scope: &mut Scope<'f>,
        id: &str,
        node: &Node,
        position: &str,
    ) -> Result<Out, String> {
        let name = scope.unique(id);
        let mut inputs = Vec::new();
        for (kiln, mx, ty, _) in OPEN_PBR {
            inputs.push(self.input_xml(scope, node, mx, kiln, ty)?);
        }
        if node.inputs.contains_key("normal") {
            inputs.push(self.input_xml(scope, node, OPEN_PBR_NORMAL, "normal", "vector3")?);
        }
        if let Some(Param::Bool(true)) = node.params.get("thin_walled") {
            inputs.push((
                OPEN_PBR_THIN_WALLED.to_owned(),
                "boolean".to_owned(),
                "value=\"true\"".to_owned(),
            ));
        }
        let mut attributes = position.to_owned();
        for (kiln, attribute, default) in KILN_ONLY {
            match node.inputs.get(*kiln) {
                Some(Input::Float(x)) if *x != *default => {
                    let _ = write!(attributes, " {attribute}=\"{}\"", number(*x));
                }
                Some(Input::Link(_)) => {
                    return Err(format!(
                        "{id}: a linked {kiln} cannot be written (OpenPBR has no such input)"
                    ));
                }
                _ => {}
            }
        }
        scope.write(
            "open_pbr_surface",
            &name,
            "surfaceshader",
            &attributes,
            &inputs,
        );
        Ok(Out {
            node: name,
            output: None,
            interface: false,
            ty: "surfaceshader".into(),
        })
    }

    /// Texture and geometry coordinates as MaterialX's geometric nodes, one per output
    /// used (named `id__output`, which the importer joins again); `None` for outputs
    /// MaterialX has no node for.
    fn coordinate(
        &mut self,
        scope: &mut Scope<'f>,
        id: &str,
        node: &Node,
        socket: &str,
        position: &str,
    ) -> Result<Option<Out>, String> {
        let (category, ty, uniform): (&str, &str, Option<(&str, &str, &str)>) =
            match (node.kind.as_str(), socket) {
                ("texture_coordinate", "uv") => ("texcoord", "vector2", None),
                ("texture_coordinate", "uv1") => {
                    ("texcoord", "vector2", Some(("index", "integer", "1")))
                }
                ("texture_coordinate", "object") => {
                    ("position", "vector3", Some(("space", "string", "object")))
                }
                ("texture_coordinate", "normal") => {
                    ("normal", "vector3", Some(("space", "string", "object")))
                }
                ("texture_coordinate", "world") | ("geometry", "position") => {
                    ("position", "vector3", Some(("space", "string", "world")))
                }
                ("geometry", "normal") => ("normal", "vector3", Some(("space", "string", "world"))),
                ("geometry", "tangent") => {
                    ("tangent", "vector3", Some(("space", "string", "world")))
                }
                _ => return Ok(None),
            };
        let name = scope.unique(&format!("{id}__{socket}"));
        let position = format!(
            "{position} kiln_node=\"{}\" kiln_output=\"{socket}\"",
            node.kind
        );
        let position = position.as_str();
        let inputs: Vec<_> = uniform
            .map(|(n, t, v)| (n.to_owned(), t.to_owned(), format!("value=\"{v}\"")))
            .into_iter()
            .collect();
        scope.write(category, &name, ty, position, &inputs);
        Ok(Some(Out {
            node: name,
            output: None,
            interface: false,
            ty: ty.into(),
        }))
    }

    fn image(
        &mut self,
        scope: &mut Scope<'f>,
        id: &str,
        node: &Node,
        position: &str,
    ) -> Result<Out, String> {
        let text = |p: Option<Param>| match p {
            Some(Param::Text(t)) => t,
            _ => String::new(),
        };
        let file = text(self.param(node, "file"));
        let srgb = text(self.param(node, "color_space")) == "srgb";
        let address = match text(self.param(node, "extension")).as_str() {
            "extend" => "clamp",
            "clip" => "constant",
            "mirror" => "mirror",
            _ => "periodic",
        };
        let filter = if text(self.param(node, "interpolation")) == "closest" {
            "closest"
        } else {
            "linear"
        };
        let colorspace = if srgb {
            " colorspace=\"srgb_texture\""
        } else {
            ""
        };
        let mut inputs = vec![
            (
                "file".to_owned(),
                "filename".to_owned(),
                format!("value=\"{}\"{colorspace}", escape(&file)),
            ),
            (
                "uaddressmode".to_owned(),
                "string".to_owned(),
                format!("value=\"{address}\""),
            ),
            (
                "vaddressmode".to_owned(),
                "string".to_owned(),
                format!("value=\"{address}\""),
            ),
            (
                "filtertype".to_owned(),
                "string".to_owned(),
                format!("value=\"{filter}\""),
            ),
        ];
        let mut category = "image";
        if let Some((mapping, tiling, offset)) = self.tiling(scope, node) {
            // A Mapping node only this image reads, scaling and moving its UVs: the
            // tiling and offset of MaterialX's tiled image.
            category = "tiledimage";
            inputs.retain(|(n, _, _)| n == "file" || n == "filtertype");
            inputs.push(self.input_xml(scope, mapping, "texcoord", "vector", "vector2")?);
            inputs.push((
                "uvtiling".into(),
                "vector2".into(),
                format!("value=\"{}, {}\"", number(tiling[0]), number(tiling[1])),
            ));
            inputs.push((
                "uvoffset".into(),
                "vector2".into(),
                format!("value=\"{}, {}\"", number(offset[0]), number(offset[1])),
            ));
        } else if node.inputs.contains_key("vector") {
            inputs.push(self.input_xml(scope, node, "texcoord", "vector", "vector2")?);
        }
        let name = scope.unique(id);
        scope.write(category, &name, "color3", position, &inputs);
        Ok(Out {
            node: name,
            output: None,
            interface: false,
            ty: "color3".into(),
        })
    }

    /// The Mapping node feeding image `id`'s coordinates, when it is a tiled image's
    /// tiling and offset (a point mapping of linked coordinates by constant scale and
    /// location, no rotation, read by nothing else; address modes stay periodic), with
    /// the tiling and offset; the node is then part of the image.
    fn tiling(&self, scope: &mut Scope<'f>, node: &Node) -> Option<(&'f Node, [f32; 2], [f32; 2])> {
        let (mapping_id, _) = node.inputs.get("vector").and_then(Input::link)?;
        let mapping = scope
            .nodes
            .get(mapping_id)
            .filter(|m| m.kind == "mapping" && !m.muted)?;
        let readers = scope
            .nodes
            .values()
            .flat_map(|n| n.inputs.values())
            .filter(|i| i.link().is_some_and(|(n, _)| n == mapping_id))
            .count();
        let point = self.param(mapping, "vector_type") == Some(Param::Text("point".into()));
        let constant = |name: &str, default: [f32; 3]| match self.input(mapping, name) {
            None => Some(default),
            Some(Input::Vec3(v)) => Some(v),
            Some(Input::Float(x)) => Some([x; 3]),
            _ => None,
        };
        let scale = constant("scale", [1.0; 3])?;
        let location = constant("location", [0.0; 3])?;
        let rotation = constant("rotation", [0.0; 3])?;
        let repeat = self.param(node, "extension") == Some(Param::Text("repeat".into()));
        let linked = mapping
            .inputs
            .get("vector")
            .is_some_and(|v| v.link().is_some());
        if readers != 1
            || !point
            || !linked
            || !repeat
            || rotation != [0.0; 3]
            || scale[2] != 1.0
            || location[2] != 0.0
        {
            return None;
        }
        scope.consumed.insert(mapping_id.to_owned());
        Some((mapping, [scale[0], scale[1]], [-location[0], -location[1]]))
    }

    /// A group's instance, and (once) its node definition and node graph.
    fn group_node(
        &mut self,
        scope: &mut Scope<'f>,
        id: &str,
        node: &Node,
        socket: &str,
        position: &str,
    ) -> Result<Out, String> {
        let group_name = match node.params.get("group") {
            Some(Param::Text(g)) => g.clone(),
            _ => return Err(format!("group node {id} names no group")),
        };
        let file = self.file;
        let group = file.groups.get(&group_name).ok_or(format!(
            "group node {id} uses group {group_name}, which the graph does not declare"
        ))?;
        let category = format!("{KILN_GROUP_PREFIX}{}", sanitize(&group_name));
        if self.groups_written.insert(group_name.clone()) {
            self.write_group(&category, group)?;
        }
        let name = scope.unique(id);
        let mut inputs = Vec::new();
        for s in &group.inputs {
            let ty = table::mx_type(s.ty.name());
            if let Some(v) = node.inputs.get(&s.name) {
                let (n, t, rest) = match v {
                    Input::Link(l) => {
                        let (from, from_socket) = l
                            .rsplit_once('.')
                            .ok_or(format!("link {l} has no socket"))?;
                        let out = self.emit(scope, from, from_socket)?;
                        let out = self.convert(scope, out, ty);
                        (s.name.clone(), ty.to_owned(), out.reference())
                    }
                    v => (
                        s.name.clone(),
                        ty.to_owned(),
                        format!("value=\"{}\"", value_text(v, ty)),
                    ),
                };
                inputs.push((n, t, rest));
            }
        }
        let (outputs, node_ty) = group_outputs(group);
        scope.write(&category, &name, &node_ty, position, &inputs);
        let multi = outputs.len() > 1;
        for (mx, kiln, ty) in outputs {
            let out = Out {
                node: name.clone(),
                output: multi.then_some(mx),
                interface: false,
                ty,
            };
            scope.done.insert((id.to_owned(), kiln), out);
        }
        scope
            .done
            .get(&(id.to_owned(), socket.to_owned()))
            .cloned()
            .ok_or(format!("group {group_name} has no output {socket}"))
    }

    fn write_group(&mut self, category: &str, group: &'f read::Group) -> Result<(), String> {
        let mut def = format!("  <nodedef name=\"ND_{category}\" node=\"{category}\">\n");
        for s in &group.inputs {
            let ty = table::mx_type(s.ty.name());
            let value = s
                .default
                .as_ref()
                .map(|d| format!(" value=\"{}\"", value_text(d, ty)))
                .unwrap_or_else(|| format!(" value=\"{}\"", value_text(&Input::Float(0.0), ty)));
            let _ = writeln!(
                def,
                "    <input name=\"{}\" type=\"{ty}\"{value} />",
                sanitize(&s.name)
            );
        }
        let (names, _) = group_outputs(group);
        for (mx, kiln, ty) in &names {
            let _ = writeln!(
                def,
                "    <output name=\"{mx}\" type=\"{ty}\" kiln_output=\"{}\" />",
                escape(kiln)
            );
        }
        def.push_str("  </nodedef>\n");
        let mut inner = Scope::new(&group.nodes, Some(&group.inputs));
        let mut outputs = String::new();
        for (mx, kiln, ty) in &names {
            let link = group
                .links
                .get(kiln)
                .ok_or(format!("group output {kiln} is not connected"))?;
            let (from, socket) = link
                .rsplit_once('.')
                .ok_or(format!("link {link} has no socket"))?;
            let out = self.emit(&mut inner, from, socket)?;
            let out = self.convert(&mut inner, out, ty);
            let _ = writeln!(
                outputs,
                "    <output name=\"{mx}\" type=\"{ty}\" {} />",
                out.reference()
            );
        }
        self.emit_rest(&mut inner)?;
        let _ = write!(
            self.group_text,
            "{def}  <nodegraph name=\"NG_{category}\" nodedef=\"ND_{category}\">\n{}{outputs}  </nodegraph>\n",
            inner.text
        );
        Ok(())
    }

    /// A Kiln node as category `kiln_TYPE`, declared by a node definition listing its
    /// sockets and (as uniform inputs) its parameters.
    fn custom(
        &mut self,
        scope: &mut Scope<'f>,
        id: &str,
        node: &Node,
        socket: &str,
        position: &str,
    ) -> Result<Out, String> {
        let node_type = self.node_type(&node.kind)?;
        // Every parameter, defaults included: the implementation depends on them.
        let mut all_params: Vec<(String, Param)> = node_type
            .params
            .iter()
            .map(|p| {
                let value = node.params.get(&p.name).cloned();
                (p.name.clone(), value.unwrap_or(p.default.clone()))
            })
            .collect();
        for (k, p) in &node.params {
            if !all_params.iter().any(|(n, _)| n == k) {
                all_params.push((k.clone(), p.clone()));
            }
        }
        let (kiln_outputs, _) = type_outputs(node_type);
        let implementation =
            implement::implement(&node.kind, &all_params, &node.inputs, &kiln_outputs);
        // One definition per implementation: parameters that change the graph (a
        // ramp's stops: the node) name a variant.
        let mut variant: Vec<String> = all_params
            .iter()
            .filter(|(name, _)| name != "file")
            .map(|(name, p)| match p {
                Param::Text(t) => sanitize(t),
                Param::Bool(b) => format!("{}{b}", sanitize(name)),
                Param::Number(x) => sanitize(&number(*x)),
                Param::Ramp(_) => sanitize(id),
            })
            .collect();
        if let Some(g) = &implementation
            && !g.variant.is_empty()
        {
            variant.push(g.variant.clone());
        }
        let category = if implementation.is_some() && !variant.is_empty() {
            format!("{KILN_NODE_PREFIX}{}__{}", node.kind, variant.join("_"))
        } else {
            format!("{KILN_NODE_PREFIX}{}", node.kind)
        };
        let name = scope.unique(id);
        let mut inputs = Vec::new();
        for s in &node_type.inputs {
            if node.inputs.contains_key(&s.name) {
                let ty = table::mx_type(s.ty.name());
                inputs.push(self.input_xml(scope, node, &s.name, &s.name, ty)?);
            }
        }
        let mut params = Vec::new();
        for (p, v) in &node.params {
            let (ty, value) = match v {
                Param::Bool(b) => ("boolean", b.to_string()),
                Param::Number(x) => ("float", number(*x)),
                Param::Text(t) => (if p == "file" { "filename" } else { "string" }, escape(t)),
                Param::Ramp(stops) => {
                    let v: Vec<String> = stops
                        .iter()
                        .flat_map(|s| std::iter::once(s.position).chain(s.color))
                        .map(number)
                        .collect();
                    ("floatarray", v.join(", "))
                }
            };
            params.push((p.clone(), ty.to_owned()));
            inputs.push((
                p.clone(),
                ty.to_owned(),
                format!("value=\"{value}\" uniform=\"true\""),
            ));
        }
        let (outputs, ty) = type_outputs(node_type);
        let muted = if node.muted {
            " kiln_muted=\"true\""
        } else {
            ""
        };
        scope.write(
            &category,
            &name,
            &ty,
            &format!("{position}{muted}"),
            &inputs,
        );
        self.declare(&category, node_type, &params);
        if let Some(g) = implementation {
            let mut text = format!(
                "  <nodegraph name=\"NG_{category}\" nodedef=\"ND_{category}\">\n{}",
                g.text
            );
            for (name, ty, src) in &g.outputs {
                let _ = writeln!(
                    text,
                    "    <output name=\"{name}\" type=\"{ty}\" {} />",
                    src_reference(src)
                );
            }
            text.push_str("  </nodegraph>\n");
            self.implementations.insert(category.clone(), text);
        }
        let multi = outputs.len() > 1;
        for (mx, kiln, t) in outputs {
            let out = Out {
                node: name.clone(),
                output: multi.then_some(mx),
                interface: false,
                ty: t,
            };
            scope.done.insert((id.to_owned(), kiln), out);
        }
        scope
            .done
            .get(&(id.to_owned(), socket.to_owned()))
            .cloned()
            .ok_or(format!("node {id} ({}) has no output {socket}", node.kind))
    }

    /// Declares `kiln_TYPE` (once; later uses add the parameters they set).
    fn declare(&mut self, category: &str, node_type: &NodeType, params: &[(String, String)]) {
        let mut def =
            format!("  <nodedef name=\"ND_{category}\" node=\"{category}\" nodegroup=\"kiln\">\n");
        for s in &node_type.inputs {
            if matches!(s.ty, SocketType::Bsdf | SocketType::Volume) {
                let _ = writeln!(
                    def,
                    "    <input name=\"{}\" type=\"{}\" />",
                    s.name,
                    table::mx_type(s.ty.name())
                );
                continue;
            }
            let ty = table::mx_type(s.ty.name());
            // What an unconnected input reads: MaterialX's geometric property where it
            // has one (object position for Kiln's generated coordinates, whose bounding
            // box MaterialX does not know).
            let geomprop = match (s.implicit.as_deref(), ty) {
                (Some("sp.n"), "vector3") => Some("Nworld"),
                (Some("sp.generated"), "vector3") => Some("Pobject"),
                _ => None,
            };
            if let Some(geomprop) = geomprop {
                let _ = writeln!(
                    def,
                    "    <input name=\"{}\" type=\"{ty}\" defaultgeomprop=\"{geomprop}\" />",
                    s.name
                );
                continue;
            }
            let value = s
                .default
                .as_ref()
                .map(|d| value_text(d, ty))
                .unwrap_or_else(|| value_text(&Input::Float(0.0), ty));
            let _ = writeln!(
                def,
                "    <input name=\"{}\" type=\"{ty}\" value=\"{value}\" />",
                s.name
            );
        }
        let all_params = self.declared_params.entry(category.to_owned()).or_default();
        for (p, ty) in params {
            all_params.insert(p.clone(), ty.clone());
        }
        for (p, ty) in all_params.iter() {
            let value = match ty.as_str() {
                "boolean" => "false",
                "float" => "0",
                _ => "",
            };
            let _ = writeln!(
                def,
                "    <input name=\"{p}\" type=\"{ty}\" value=\"{value}\" uniform=\"true\" />"
            );
        }
        for (mx, kiln, ty) in type_outputs(node_type).0 {
            let _ = writeln!(
                def,
                "    <output name=\"{mx}\" type=\"{ty}\" kiln_output=\"{kiln}\" />"
            );
        }
        def.push_str("  </nodedef>\n");
        self.definitions.insert(category.to_owned(), def);
    }
}

/// A group's outputs as MaterialX names them ([`output_names`]), and its node type.
fn group_outputs(group: &read::Group) -> (Vec<(String, String, String)>, String) {
    let outputs: Vec<(String, String)> = group
        .outputs
        .iter()
        .map(|o| (o.name.clone(), table::mx_type(o.ty.name()).to_owned()))
        .collect();
    let inputs: Vec<&str> = group.inputs.iter().map(|s| s.name.as_str()).collect();
    output_names(&outputs, &inputs)
}

/// A Kiln node type's outputs as MaterialX names them (apart from its inputs and its
/// parameters, which are inputs too: Voronoi's `distance` is both), and its node type.
fn type_outputs(node_type: &NodeType) -> (Vec<(String, String, String)>, String) {
    let outputs: Vec<(String, String)> = node_type
        .outputs
        .iter()
        .map(|o| (o.name.clone(), table::mx_type(o.ty.name()).to_owned()))
        .collect();
    let inputs: Vec<&str> = node_type
        .inputs
        .iter()
        .map(|s| s.name.as_str())
        .chain(node_type.params.iter().map(|p| p.name.as_str()))
        .collect();
    output_names(&outputs, &inputs)
}

/// A node graph output's connection attributes.
fn src_reference(src: &Src) -> String {
    match src {
        Src::N(node) => format!("nodename=\"{node}\""),
        Src::O(node, output) => format!("nodename=\"{node}\" output=\"{output}\""),
        Src::I(name) => format!("interfacename=\"{name}\""),
        Src::V(value) => format!("value=\"{value}\""),
    }
}
