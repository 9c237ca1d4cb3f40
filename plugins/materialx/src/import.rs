//! MaterialX documents into Kiln graphs: one graph per `surfacematerial`, its surface
//! shader a Principled BSDF ([`crate::surface`]), compound node graphs node groups with
//! their interface as the group's inputs, node definitions implemented by node graphs
//! groups used as nodes, standard-library nodes Kiln nodes ([`crate::table`] and the
//! cases below). What has no Kiln counterpart is named in a warning and left at its
//! default; a material whose shader cannot be mapped is left out with a warning, and a
//! file none of whose materials can be read is an error.

use std::collections::HashMap;
use std::path::Path;

use kiln_plugin_api::kmat::{Graph, Group, Node, Param, Socket, Value};
use kiln_plugin_api::read::{MAX_FILE_BYTES, read_text_bounded};

use crate::surface::{self, ShaderInputs};

mod closures;
use crate::table::{self, Fixed};

/// The graphs a document's materials become, by material name, and what was reported.
pub struct Imported {
    pub materials: Vec<(String, String)>,
    pub warnings: Vec<String>,
}

/// Prefix of the node categories the exporter gives Kiln node types without a
/// standard-library counterpart (`kiln_noise_texture`).
pub const KILN_NODE_PREFIX: &str = "kiln_";
/// Prefix of the node categories the exporter gives Kiln node groups.
pub const KILN_GROUP_PREFIX: &str = "kiln_group_";
/// The element of a material that is only a volume.
pub const VOLUME_MATERIAL: &str = "volumematerial";
/// The attribute of a volume material naming the surface material whose inside it
/// fills (Kiln's materials hold both; MaterialX's one or the other).
pub const WITH_SURFACE: &str = "kiln_surface_material";
/// The attribute of a top-level node nothing reads that belongs to a material's graph
/// (the exporter keeps a graph's spare nodes).
pub const SPARE_OF: &str = "kiln_material";
/// MaterialX positions (`xpos`, `ypos`) are in units of about a node; Kiln's are points.
pub const POSITION_SCALE: f32 = 100.0;

/// The most files one import reads (the document and those it includes).
const MAX_FILES: usize = 64;

/// Reads the MaterialX document `text` (the file `path`, whose folder image files are
/// checked against) and the documents it includes (`xi:include`).
pub fn import(text: &str, path: &Path) -> Result<Imported, String> {
    let mut texts = vec![(path.to_owned(), text.to_owned())];
    let mut next = 0;
    while next < texts.len() {
        let (from, text) = texts[next].clone();
        next += 1;
        for href in includes(&text) {
            let file = from.parent().unwrap_or(Path::new("")).join(&href);
            if texts.iter().any(|(p, _)| *p == file) {
                continue;
            }
            if texts.len() == MAX_FILES {
                return Err(format!(
                    "{} includes more than {MAX_FILES} files",
                    path.display()
                ));
            }
            let text = read_text_bounded(&file, MAX_FILE_BYTES).map_err(|e| {
                format!(
                    "cannot read {}, included by {}: {e}",
                    file.display(),
                    from.display()
                )
            })?;
            texts.push((file, text));
        }
    }
    let mut docs = Vec::new();
    for (file, text) in &texts {
        let doc = roxmltree::Document::parse_with_options(text, xml_options())
            .map_err(|e| format!("{} is not valid XML: {e}", file.display()))?;
        let name = doc.root_element().tag_name().name().to_owned();
        if name != "materialx" {
            return Err(format!(
                "{} is not a MaterialX document (its root element is <{name}>)",
                file.display()
            ));
        }
        docs.push(doc);
    }
    let roots: Vec<Element> = docs.iter().map(|d| d.root_element()).collect();
    let mut warnings = Vec::new();
    if let Some(v) = roots[0].attribute("version")
        && !(v.starts_with("1.38") || v.starts_with("1.39"))
    {
        warnings.push(format!(
            "MaterialX version {v}: Kiln reads 1.38 and 1.39 and reads this one as those"
        ));
    }
    let doc = Doc {
        roots,
        folder: path.parent().unwrap_or(Path::new("")).to_owned(),
    };
    let mut materials = Vec::new();
    let mut errors = Vec::new();
    // Surface materials, and volume materials that do not fill one of them.
    let top_materials: Vec<_> = doc
        .top_elements()
        .filter(|e| match e.tag_name().name() {
            "surfacematerial" => true,
            VOLUME_MATERIAL => e
                .attribute(WITH_SURFACE)
                .is_none_or(|s| doc.top(s).is_none()),
            _ => false,
        })
        .collect();
    if top_materials.is_empty() {
        return Err(format!(
            "{} holds no surfacematerial or volumematerial: nothing to import",
            path.display()
        ));
    }
    for m in top_materials {
        let name = m.attribute("name").unwrap_or("material").to_owned();
        let mut build = Build {
            doc: &doc,
            material: name.clone(),
            groups: Vec::new(),
            warnings: Vec::new(),
            unrenderable: Vec::new(),
        };
        match build.material(m) {
            Ok(graph) => {
                warnings.extend(build.warnings);
                materials.push((name.clone(), graph.to_kmat(&name, &[])));
            }
            Err(e) => {
                warnings.extend(build.warnings);
                errors.push(format!("material {name}: {e}"));
            }
        }
    }
    if materials.is_empty() {
        return Err(errors.join("; "));
    }
    warnings.extend(errors.into_iter().map(|e| format!("{e}; left out")));
    Ok(Imported {
        materials,
        warnings,
    })
}

fn xml_options() -> roxmltree::ParsingOptions {
    roxmltree::ParsingOptions {
        allow_dtd: false,
        ..Default::default()
    }
}

/// The files an XML text includes (`<xi:include href="…"/>`); none when it does not
/// parse (the import reports that).
fn includes(text: &str) -> Vec<String> {
    let Ok(doc) = roxmltree::Document::parse_with_options(text, xml_options()) else {
        return Vec::new();
    };
    elements(doc.root_element())
        .filter(|e| e.tag_name().name() == "include")
        .filter_map(|e| e.attribute("href").map(str::to_owned))
        .collect()
}

fn elements<'a, 'i>(
    node: roxmltree::Node<'a, 'i>,
) -> impl Iterator<Item = roxmltree::Node<'a, 'i>> {
    node.children().filter(|c| c.is_element())
}

type Element<'a> = roxmltree::Node<'a, 'a>;

/// A document with the documents it includes.
struct Doc<'a> {
    roots: Vec<Element<'a>>,
    folder: std::path::PathBuf,
}

impl<'a> Doc<'a> {
    fn top_elements(&self) -> impl Iterator<Item = Element<'a>> + '_ {
        self.roots.iter().flat_map(|r| elements(*r))
    }

    /// The top-level element named `name` (a node, node graph or node definition).
    fn top(&self, name: &str) -> Option<Element<'a>> {
        self.top_elements()
            .find(|e| e.attribute("name") == Some(name))
    }

    /// The node definition of custom node `category` implemented by a node graph, and
    /// that graph.
    fn definition(&self, category: &str) -> Option<(Element<'a>, Element<'a>)> {
        let nodedef = self
            .top_elements()
            .find(|e| e.tag_name().name() == "nodedef" && e.attribute("node") == Some(category))?;
        let name = nodedef.attribute("name")?;
        let graph = self
            .top_elements()
            .find(|e| e.tag_name().name() == "nodegraph" && e.attribute("nodedef") == Some(name))?;
        Some((nodedef, graph))
    }
}

/// One graph being built: the material's, or a group's.
struct Scope<'a> {
    graph: Graph,
    /// Where its nodes are looked up: a node graph, or (`None`) the document's top level.
    container: Option<Element<'a>>,
    /// The node graph's interface, for a group: (name, element).
    interface: Vec<Element<'a>>,
    /// The Kiln values of each MaterialX node's outputs, once mapped.
    mapped: HashMap<String, HashMap<String, Value>>,
    /// The group's `group_input` node, once something reads it.
    group_input: Option<String>,
    /// Node graph → the id of the group node using it here.
    instances: HashMap<String, String>,
}

impl<'a> Scope<'a> {
    fn new(container: Option<Element<'a>>, interface: Vec<Element<'a>>) -> Self {
        Self {
            graph: Graph::default(),
            container,
            interface,
            mapped: HashMap::new(),
            group_input: None,
            instances: HashMap::new(),
        }
    }

    fn interface_input(&self, name: &str) -> Option<Element<'a>> {
        self.interface
            .iter()
            .copied()
            .find(|e| e.attribute("name") == Some(name))
    }

    fn group_input(&mut self) -> String {
        if let Some(id) = &self.group_input {
            return id.clone();
        }
        let id = self.graph.add("group_input", Node::new("group_input"));
        self.group_input = Some(id.clone());
        id
    }
}

struct Build<'d, 'a> {
    doc: &'d Doc<'a>,
    material: String,
    groups: Vec<(String, Group)>,
    warnings: Vec<String>,
    /// Shading nodes (BSDFs, shaders) the material uses that Kiln cannot render.
    unrenderable: Vec<String>,
}

/// A constant of MaterialX type `ty` written `text`.
fn constant(ty: &str, text: &str) -> Option<Value> {
    let numbers: Vec<f32> = text
        .split(',')
        .map(|s| s.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .ok()?;
    Some(match (ty, numbers.as_slice()) {
        ("float" | "integer", [x]) => Value::Float(*x),
        ("color3" | "color4", [r, g, b, ..]) => Value::Color([*r, *g, *b]),
        ("vector3" | "vector4", [x, y, z, ..]) => Value::Vector([*x, *y, *z]),
        ("vector2", [x, y]) => Value::Vector([*x, *y, 0.0]),
        _ => return None,
    })
}

/// Whether values of MaterialX type `ty` are shading closures rather than numbers.
fn is_closure(ty: &str) -> bool {
    matches!(
        ty,
        "surfaceshader"
            | "volumeshader"
            | "displacementshader"
            | "BSDF"
            | "EDF"
            | "VDF"
            | "lightshader"
            | "material"
    )
}

fn boolean(text: &str) -> bool {
    text.trim() == "true"
}

/// A constant widened to three channels (what Kiln's vector and colour inputs take).
fn splat(v: Value) -> Value {
    match v {
        Value::Float(x) => Value::Vector([x; 3]),
        v => v,
    }
}

fn input<'a>(node: Element<'a>, name: &str) -> Option<Element<'a>> {
    elements(node).find(|e| e.tag_name().name() == "input" && e.attribute("name") == Some(name))
}

fn name_of<'a>(e: Element<'a>) -> &'a str {
    e.attribute("name").unwrap_or("?")
}

impl<'a> Build<'_, 'a> {
    fn warn(&mut self, message: String) {
        let message = format!("material {}: {message}", self.material);
        if !self.warnings.contains(&message) {
            self.warnings.push(message);
        }
    }

    fn material(&mut self, m: Element<'a>) -> Result<Graph, String> {
        let mut scope = Scope::new(None, Vec::new());
        let mut output = Node::new("material_output");
        let surface_input = input(m, "surfaceshader");
        let name = name_of(m);
        let volume_input = input(m, "volumeshader").or_else(|| {
            let fill = self.doc.top_elements().find(|v| {
                v.tag_name().name() == VOLUME_MATERIAL && v.attribute(WITH_SURFACE) == Some(name)
            })?;
            input(fill, "volumeshader")
        });
        if surface_input.is_none() && volume_input.is_none() {
            return Err("it has neither a surfaceshader nor a volumeshader input".into());
        }
        if let Some(i) = surface_input {
            let surface = self.surface(&mut scope, i)?;
            output = output.input("surface", surface);
        }
        if let Some(i) = volume_input {
            let name = i.attribute("nodename").unwrap_or("?");
            let shader = self
                .doc
                .top(name)
                .ok_or(format!("its volume shader {name} is not in the file"))?;
            if shader.tag_name().name() == "volume" {
                let v = self.closure_volume(&mut scope, shader).map_err(|part| {
                    format!("its volume is made of {part}, which Kiln cannot render")
                })?;
                output = output.input("volume", v);
            } else {
                match self.custom_node(&mut scope, shader)? {
                    Some(outputs) => {
                        let socket = i.attribute("output").unwrap_or("out");
                        let v = outputs
                            .get(socket)
                            .cloned()
                            .ok_or(format!("its volume shader {name} has no output {socket}"))?;
                        output = output.input("volume", v);
                    }
                    None => self.warn(format!(
                        "volume shader {name} ({}) is not read: Kiln's volumes are its own nodes",
                        shader.tag_name().name()
                    )),
                }
            }
        }
        let spare: Vec<Element> = self
            .doc
            .top_elements()
            .filter(|e| e.attribute(SPARE_OF) == Some(name))
            .collect();
        for e in spare {
            self.map_node(&mut scope, e);
        }
        if !self.unrenderable.is_empty() {
            return Err(format!(
                "its shading is made of {}, which Kiln cannot render",
                self.unrenderable.join(", ")
            ));
        }
        scope.graph.add("output", output);
        for (name, group) in std::mem::take(&mut self.groups) {
            scope.graph.add_group(&name, group);
        }
        Ok(scope.graph)
    }

    /// The Principled BSDF (or custom shader) a material's `surfaceshader` input names.
    fn surface(
        &mut self,
        scope: &mut Scope<'a>,
        shader_input: Element<'a>,
    ) -> Result<Value, String> {
        let shader_name = shader_input
            .attribute("nodename")
            .ok_or("its surfaceshader input names no node".to_owned())?;
        let shader = self.doc.top(shader_name).ok_or(format!(
            "its surface shader {shader_name} is not in the file"
        ))?;
        let category = shader.tag_name().name();
        if surface::SHADERS.contains(&category) {
            let mut inputs = ShaderInputs::default();
            for i in elements(shader).filter(|e| e.tag_name().name() == "input") {
                let name = name_of(i).to_owned();
                match i.attribute("type") {
                    Some("boolean" | "string" | "integer") if i.attribute("value").is_some() => {
                        let text = i.attribute("value").unwrap_or_default().to_owned();
                        if i.attribute("type") == Some("integer")
                            && let Ok(v) = text.trim().parse::<f32>()
                        {
                            inputs.values.insert(name.clone(), Value::Float(v));
                        }
                        inputs.uniforms.insert(name, text);
                    }
                    _ => {
                        if let Some(v) = self.resolve(scope, i) {
                            inputs.values.insert(name, v);
                        }
                    }
                }
            }
            for a in shader.attributes() {
                inputs
                    .attributes
                    .insert(a.name().to_owned(), a.value().to_owned());
            }
            let thin_walled = inputs
                .uniforms
                .get(surface::OPEN_PBR_THIN_WALLED)
                .or(inputs.uniforms.get("thin_walled"))
                .is_some_and(|t| boolean(t));
            let open_pbr = surface::to_open_pbr(
                category,
                shader_name,
                &inputs,
                &mut scope.graph,
                &mut self.warnings,
            );
            let node = surface::principled(shader_name, &open_pbr, thin_walled, &mut self.warnings);
            let node = position(shader, node);
            return Ok(Value::link(&scope.graph.add(shader_name, node), "bsdf"));
        }
        if category == "surface" {
            return self.closure_surface(scope, shader).map_err(|part| {
                format!("its shading is made of {part}, which Kiln cannot render")
            });
        }
        match self.custom_node(scope, shader)? {
            Some(outputs) => {
                let output = shader_input.attribute("output").unwrap_or("out");
                outputs.get(output).cloned().ok_or(format!(
                    "its surface shader {shader_name} has no output {output}"
                ))
            }
            None => Err(format!(
                "its surface shader {shader_name} is a {category}, which Kiln cannot render"
            )),
        }
    }

    /// The Kiln value an `<input>` (or `<output>`) element gives: its constant, the
    /// output of the node it connects, or the group input its interface name is.
    fn resolve(&mut self, scope: &mut Scope<'a>, i: Element<'a>) -> Option<Value> {
        let ty = i.attribute("type").unwrap_or("float");
        if let Some(node) = i.attribute("nodename") {
            let output = i.attribute("output").unwrap_or("out");
            let found = match scope.container {
                Some(c) => elements(c).find(|e| e.attribute("name") == Some(node)),
                None => self.doc.top(node),
            };
            let Some(e) = found else {
                self.warn(format!(
                    "{} names node {node}, which is not in its graph",
                    name_of(i)
                ));
                return None;
            };
            let outputs = self.map_node(scope, e)?;
            let v = outputs.get(output).cloned();
            if v.is_none() {
                self.warn(format!("node {node} has no output {output} Kiln can read"));
            }
            return v;
        }
        if let Some(graph) = i.attribute("nodegraph") {
            return self.nodegraph_output(scope, graph, i.attribute("output"));
        }
        if let Some(name) = i.attribute("interfacename") {
            let Some(socket) = scope.interface_input(name) else {
                self.warn(format!(
                    "{} names interface input {name}, which its graph does not declare",
                    name_of(i)
                ));
                return None;
            };
            // Interface inputs of types no socket carries (files, strings) are read
            // where they are used ([`Build::uniform`]).
            table::kiln_type(socket.attribute("type").unwrap_or(""))?;
            let id = scope.group_input();
            return Some(Value::link(&id, name));
        }
        let text = i.attribute("value")?;
        let v = constant(ty, text);
        if v.is_none() && table::kiln_type(ty).is_some() {
            self.warn(format!("{} has value \"{text}\", not a {ty}", name_of(i)));
        }
        v
    }

    /// A uniform input's text (a file name, an address mode), through the interface of
    /// the graph it is in; file names get their `fileprefix`.
    fn uniform(&self, scope: &Scope<'a>, node: Element<'a>, name: &str) -> Option<String> {
        let i = input(node, name)?;
        let (source, value) = match i.attribute("interfacename") {
            Some(n) => {
                let s = scope.interface_input(n)?;
                (s, s.attribute("value")?)
            }
            None => (i, i.attribute("value")?),
        };
        if i.attribute("type") != Some("filename") {
            return Some(value.to_owned());
        }
        let prefix = source
            .ancestors()
            .find_map(|a| a.attribute("fileprefix"))
            .unwrap_or("");
        Some(format!("{prefix}{value}"))
    }

    /// The group node for compound node graph `graph` (one per scope) and its output
    /// `output` (the first where not given).
    fn nodegraph_output(
        &mut self,
        scope: &mut Scope<'a>,
        graph: &str,
        output: Option<&str>,
    ) -> Option<Value> {
        let Some(ng) = self
            .doc
            .top(graph)
            .filter(|e| e.tag_name().name() == "nodegraph")
        else {
            self.warn(format!("node graph {graph} is not in the file"));
            return None;
        };
        let output = match output {
            Some(o) => o.to_owned(),
            None => name_of(elements(ng).find(|e| e.tag_name().name() == "output")?).to_owned(),
        };
        let id = match scope.instances.get(graph) {
            Some(id) => id.clone(),
            None => {
                let interface: Vec<Element> = elements(ng)
                    .filter(|e| e.tag_name().name() == "input")
                    .collect();
                self.group(graph, ng, &interface, None);
                let id = scope.graph.add(graph, position(ng, Node::group(graph)));
                scope.instances.insert(graph.to_owned(), id.clone());
                id
            }
        };
        Some(Value::link(&id, &output))
    }

    /// Builds group `name` from node graph `ng` with interface inputs `interface` (its
    /// own `<input>`s, or its node definition's), once per material.
    fn group(
        &mut self,
        name: &str,
        ng: Element<'a>,
        interface: &[Element<'a>],
        nodedef: Option<Element<'a>>,
    ) {
        if self.groups.iter().any(|(n, _)| n == name) {
            return;
        }
        // Claimed first: a graph that uses itself is not built forever.
        self.groups.push((name.to_owned(), Group::default()));
        let mut scope = Scope::new(Some(ng), interface.to_vec());
        let inputs = interface
            .iter()
            .filter_map(|i| {
                let ty = table::kiln_type(i.attribute("type")?)?;
                let default = i
                    .attribute("value")
                    .and_then(|v| constant(i.attribute("type")?, v))
                    .map(|v| if ty == "float" { v } else { splat(v) });
                Some(Socket {
                    name: name_of(*i).to_owned(),
                    ty: ty.to_owned(),
                    default,
                })
            })
            .collect();
        let mut outputs = Vec::new();
        let mut links = Vec::new();
        for o in elements(ng).filter(|e| e.tag_name().name() == "output") {
            let Some(ty) = o.attribute("type").and_then(table::kiln_type) else {
                continue;
            };
            let out = kiln_output_name(nodedef, name_of(o));
            let value = self.resolve(&mut scope, o);
            // A group output is fed by a node's socket: a constant gets a node of its own.
            let link = match value {
                Some(Value::Link(l)) => l,
                Some(v) => {
                    let node = match (&v, ty) {
                        (Value::Float(_), _) => Node::new("value").input("value", v),
                        (_, "color") => Node::new("rgb").input("color", v),
                        _ => Node::new("vector").input("vector", v),
                    };
                    let socket = match ty {
                        "float" => "value",
                        "color" => "color",
                        _ => "vector",
                    };
                    format!("{}.{socket}", scope.graph.add(&out, node))
                }
                None => {
                    self.warn(format!("output {out} of node graph {name} computes nothing Kiln can read; it gives the type's zero"));
                    let node = Node::new("value").input("value", Value::Float(0.0));
                    format!("{}.value", scope.graph.add(&out, node))
                }
            };
            outputs.push(Socket {
                name: out.clone(),
                ty: ty.to_owned(),
                default: None,
            });
            links.push((out, link));
        }
        // Nodes no output reads are part of the group too.
        for e in elements(ng).filter(|e| !matches!(e.tag_name().name(), "input" | "output")) {
            self.map_node(&mut scope, e);
        }
        let group = Group {
            inputs,
            outputs,
            nodes: scope.graph,
            links,
        };
        if let Some(slot) = self.groups.iter_mut().find(|(n, _)| n == name) {
            slot.1 = group;
        }
    }

    /// The Kiln values of `e`'s outputs, mapping it (and what feeds it) on first use;
    /// `None`, with a warning, for a node Kiln cannot represent.
    fn map_node(
        &mut self,
        scope: &mut Scope<'a>,
        e: Element<'a>,
    ) -> Option<HashMap<String, Value>> {
        let name = name_of(e).to_owned();
        if let Some(m) = scope.mapped.get(&name) {
            return Some(m.clone());
        }
        // Claimed first, empty: a cycle reads nothing instead of recursing forever.
        scope.mapped.insert(name.clone(), HashMap::new());
        let mapped = self.map_new_node(scope, e);
        match &mapped {
            Some(m) => {
                scope.mapped.insert(name, m.clone());
            }
            None if is_closure(e.attribute("type").unwrap_or("")) => {
                // A shading node: what it is made of names what cannot be rendered.
                let mut parts = vec![format!("{name} ({})", e.tag_name().name())];
                let container = e.parent().unwrap_or(e);
                for i in elements(e) {
                    let Some(source) = i
                        .attribute("nodename")
                        .and_then(|n| elements(container).find(|c| c.attribute("name") == Some(n)))
                    else {
                        continue;
                    };
                    if is_closure(source.attribute("type").unwrap_or("")) {
                        parts.push(format!(
                            "{} ({})",
                            name_of(source),
                            source.tag_name().name()
                        ));
                    }
                }
                self.unrenderable.push(parts.join(" from "));
            }
            None => {
                self.warn(format!(
                    "node {name} ({}) is not supported by Kiln; what it feeds takes its default",
                    e.tag_name().name()
                ));
            }
        }
        mapped
    }

    fn map_new_node(
        &mut self,
        scope: &mut Scope<'a>,
        e: Element<'a>,
    ) -> Option<HashMap<String, Value>> {
        let category = e.tag_name().name();
        let ty = e.attribute("type").unwrap_or("float");
        let name = name_of(e).to_owned();
        let out = |v: Value| Some(HashMap::from([("out".to_owned(), v)]));
        // Inputs as Kiln values: set, connected, or `default`.
        macro_rules! get {
            ($input:expr) => {
                input(e, $input).and_then(|i| self.resolve(scope, i))
            };
        }
        // A procedural node's coordinates: its position (3D) or texture coordinates
        // (2D), by default the object position or the UVs, as MaterialX's.
        macro_rules! coords {
            () => {{
                let three_d = category.ends_with("3d");
                let given = if three_d {
                    get!("position")
                } else {
                    get!("texcoord")
                };
                given.unwrap_or_else(|| {
                    let id = coordinates(scope, &format!("{name}_coords"), e, "texture_coordinate");
                    Value::link(&id, if three_d { "object" } else { "uv" })
                })
            }};
        }
        // The exporter's stand-ins for Kiln's implicit conversions are plain connections.
        if e.attribute("kiln_conversion") == Some("true") {
            return out(get!("in").or(get!("in1"))?);
        }
        // A node with several outputs is told apart by its input's type.
        let key = if ty == "multioutput" {
            elements(e)
                .find(|i| i.tag_name().name() == "input")
                .and_then(|i| i.attribute("type"))
                .unwrap_or("color3")
        } else {
            ty
        };
        let fixed = |name: &str| {
            input(e, name)
                .and_then(|i| i.attribute("value"))
                .and_then(|v| v.trim().parse::<f32>().ok())
        };
        if let Some(row) = table::for_materialx(category, key, fixed) {
            let mut node = Node::new(row.kiln);
            for (param, value) in row.params {
                node = match value {
                    Fixed::Text(t) => node.text(param, t),
                    Fixed::Flag(b) => node.flag(param, *b),
                };
            }
            for (kiln, value) in row.fixed {
                node = node.input(kiln, Value::Float(*value));
            }
            for (mx, kiln, default) in row.inputs {
                let float = table::kiln_input_is_float(row.kiln, kiln);
                let value = get!(mx).unwrap_or(match (float, row.kiln) {
                    (true, _) => Value::Float(*default),
                    (false, "normal_map") => Value::Color([0.5, 0.5, 1.0]),
                    (false, _) => Value::Vector([*default; 3]),
                });
                node = node.input(kiln, if float { value } else { splat(value) });
            }
            let id = scope.graph.add(&name, position(e, node));
            return Some(
                row.outputs
                    .iter()
                    .map(|(mx, kiln)| (mx.to_string(), Value::link(&id, kiln)))
                    .collect(),
            );
        }
        match category {
            "dot" | "convert" => out(get!("in")?),
            // A shader made of closures, inside a node graph (a custom shader's).
            "surface" if ty == "surfaceshader" => match self.closure_surface(scope, e) {
                Ok(v) => out(v),
                Err(part) => {
                    self.unrenderable.push(part);
                    Some(HashMap::new())
                }
            },
            "volume" if ty == "volumeshader" => match self.closure_volume(scope, e) {
                Ok(v) => out(v),
                Err(part) => {
                    self.unrenderable.push(part);
                    Some(HashMap::new())
                }
            },
            // Closures (and their roughness) are read by the surface or volume made of
            // them.
            _ if matches!(ty, "BSDF" | "EDF" | "VDF") => Some(HashMap::new()),
            "roughness_anisotropy" | "roughness_dual" => Some(HashMap::new()),
            // What the exporter split off one Kiln node says which node and output.
            "texcoord" | "position" | "normal" | "tangent"
                if e.attribute("kiln_node").is_some() && e.attribute("kiln_output").is_some() =>
            {
                let kind = e.attribute("kiln_node").unwrap_or_default();
                let socket = e.attribute("kiln_output").unwrap_or_default();
                let id = coordinates(scope, &name, e, kind);
                out(Value::link(&id, socket))
            }
            "texcoord" => {
                let index = self.uniform(scope, e, "index").unwrap_or_default();
                let socket = if index.trim() == "1" { "uv1" } else { "uv" };
                let id = coordinates(scope, &name, e, "texture_coordinate");
                out(Value::link(&id, socket))
            }
            "position" | "normal" | "tangent" => {
                let space = self.uniform(scope, e, "space").unwrap_or("object".into());
                let world = space == "world" || category == "tangent";
                let id = coordinates(
                    scope,
                    &name,
                    e,
                    if world {
                        "geometry"
                    } else {
                        "texture_coordinate"
                    },
                );
                let socket = match (category, world) {
                    ("position", true) => "position",
                    ("position", false) => "object",
                    _ => {
                        if category == "tangent" {
                            "tangent"
                        } else {
                            "normal"
                        }
                    }
                };
                out(Value::link(&id, socket))
            }
            "geomcolor" => {
                let id = scope
                    .graph
                    .add(&name, position(e, Node::new("vertex_color")));
                out(Value::link(
                    &id,
                    if ty == "float" { "alpha" } else { "color" },
                ))
            }
            "image" | "tiledimage" | "hextiledimage" | "gltf_image" | "gltf_colorimage"
            | "gltf_normalmap" => self.image(scope, e),
            "luminance" => {
                let node = Node::new("rgb_to_bw").input("color", get!("in")?);
                let id = scope.graph.add(&name, position(e, node));
                out(Value::link(&id, "value"))
            }
            "rgbtohsv" | "hsvtorgb" => {
                let (from, to) = if category == "rgbtohsv" {
                    ("hsv", "rgb")
                } else {
                    ("rgb", "hsv")
                };
                let split = Node::new("separate_color")
                    .text("mode", from)
                    .input("color", get!("in")?);
                let split = scope.graph.add(&format!("{name}_split"), split);
                let join = Node::new("combine_color")
                    .text("mode", to)
                    .input("red", Value::link(&split, "red"))
                    .input("green", Value::link(&split, "green"))
                    .input("blue", Value::link(&split, "blue"));
                let id = scope.graph.add(&name, position(e, join));
                out(Value::link(&id, "color"))
            }
            "extract" => {
                let i = input(e, "in")?;
                let from = i.attribute("type").unwrap_or("color3");
                let index: usize = self
                    .uniform(scope, e, "index")
                    .and_then(|t| t.trim().parse().ok())
                    .unwrap_or(0);
                let value = self.resolve(scope, i)?;
                if let Value::Color(c) | Value::Vector(c) = value {
                    return out(Value::Float(c[index.min(2)]));
                }
                let (kind, input_name, sockets) = if from.starts_with("color") {
                    ("separate_color", "color", ["red", "green", "blue"])
                } else {
                    ("separate_xyz", "vector", ["x", "y", "z"])
                };
                let id = scope
                    .graph
                    .add(&name, position(e, Node::new(kind).input(input_name, value)));
                out(Value::link(&id, sockets[index.min(2)]))
            }
            "ifgreater" | "ifgreatereq" | "ifequal" => {
                let a = get!("value1").unwrap_or(Value::Float(1.0));
                let b = get!("value2").unwrap_or(Value::Float(0.0));
                let zero = if ty == "float" {
                    Value::Float(0.0)
                } else {
                    Value::Color([0.0; 3])
                };
                let in1 = get!("in1").unwrap_or(zero.clone());
                let in2 = get!("in2").unwrap_or(zero);
                // greater: a > b; greater or equal: not a < b; equal: |a - b| ≤ 0.
                let (op, swap) = match category {
                    "ifgreater" => ("greater_than", false),
                    "ifgreatereq" => ("less_than", true),
                    _ => ("compare", false),
                };
                let test = Node::new("math")
                    .text("operation", op)
                    .input("a", a)
                    .input("b", b)
                    .input("c", Value::Float(0.0));
                let test = scope.graph.add(&format!("{name}_test"), test);
                let (when0, when1) = if swap { (in1, in2) } else { (in2, in1) };
                let mix = if ty == "float" {
                    Node::new("mix_float")
                } else {
                    Node::new("mix_color").text("blend", "mix")
                };
                let mix = mix
                    .input("factor", Value::link(&test, "value"))
                    .input("a", when0)
                    .input("b", when1);
                let id = scope.graph.add(&name, position(e, mix));
                out(Value::link(&id, "result"))
            }
            "noise2d" | "noise3d" | "fractal3d" | "fractal2d" => {
                let coords = coords!();
                let fractal = category.starts_with("fractal");
                let mut noise = Node::new("noise_texture")
                    .input("vector", coords)
                    .input("scale", Value::Float(1.0))
                    .input("distortion", Value::Float(0.0));
                if fractal {
                    let octaves = get!("octaves")
                        .and_then(|v| match v {
                            Value::Float(x) => Some(x),
                            _ => None,
                        })
                        .unwrap_or(3.0);
                    noise = noise
                        .input("detail", Value::Float((octaves - 1.0).clamp(0.0, 15.0)))
                        .input(
                            "lacunarity",
                            get!("lacunarity").unwrap_or(Value::Float(2.0)),
                        )
                        .input("roughness", get!("diminish").unwrap_or(Value::Float(0.5)));
                } else {
                    noise = noise
                        .input("detail", Value::Float(0.0))
                        .input("roughness", Value::Float(0.5))
                        .input("lacunarity", Value::Float(2.0));
                }
                let noise = scope.graph.add(&format!("{name}_noise"), noise);
                // Kiln's noise lies in [0, 1] about 0.5; MaterialX's in [-1, 1] about 0,
                // times the amplitude, plus the pivot.
                let amplitude = match get!("amplitude") {
                    Some(Value::Float(a)) => a,
                    Some(Value::Color(c) | Value::Vector(c)) => c[0],
                    _ => 1.0,
                };
                let pivot = match get!("pivot") {
                    Some(Value::Float(p)) => p,
                    _ => 0.0,
                };
                let range = Node::new("map_range")
                    .text("interpolation", "linear")
                    .flag("clamp", false)
                    .input("value", Value::link(&noise, "fac"))
                    .input("from_min", Value::Float(0.0))
                    .input("from_max", Value::Float(1.0))
                    .input("to_min", Value::Float(pivot - amplitude))
                    .input("to_max", Value::Float(pivot + amplitude));
                let id = scope.graph.add(&name, position(e, range));
                out(Value::link(&id, "result"))
            }
            "cellnoise2d" | "cellnoise3d" => {
                let coords = coords!();
                let floor = Node::new("vector_math")
                    .text("operation", "floor")
                    .input("a", coords);
                let floor = scope.graph.add(&format!("{name}_cell"), floor);
                let node =
                    Node::new("white_noise_texture").input("vector", Value::link(&floor, "vector"));
                let id = scope.graph.add(&name, position(e, node));
                out(Value::link(
                    &id,
                    if ty == "float" { "value" } else { "color" },
                ))
            }
            "worleynoise2d" | "worleynoise3d" => {
                let coords = coords!();
                let node = Node::new("voronoi_texture")
                    .text("feature", "f1")
                    .text("distance", "euclidean")
                    .input("vector", coords)
                    .input("scale", Value::Float(1.0))
                    .input("randomness", get!("jitter").unwrap_or(Value::Float(1.0)));
                let id = scope.graph.add(&name, position(e, node));
                out(Value::link(&id, "distance"))
            }
            "place2d" => {
                // MaterialX's NG_place2d: scale, rotate (clockwise by `rotate` degrees),
                // offset, about the pivot (order SRT), or offset, rotate, scale (TRS).
                let texcoord = get!("texcoord").unwrap_or_else(|| {
                    let id = coordinates(scope, &format!("{name}_coords"), e, "texture_coordinate");
                    Value::link(&id, "uv")
                });
                let pivot = get!("pivot").unwrap_or(Value::Vector([0.0; 3]));
                let offset = get!("offset").unwrap_or(Value::Vector([0.0; 3]));
                let scale = match get!("scale") {
                    Some(Value::Vector([x, y, _])) => Value::Vector([x, y, 1.0]),
                    Some(v) => v,
                    None => Value::Vector([1.0; 3]),
                };
                let rotation = match get!("rotate") {
                    Some(Value::Float(degrees)) => Value::Vector([0.0, 0.0, -degrees.to_radians()]),
                    Some(v) => {
                        let radians = Node::new("math")
                            .text("operation", "multiply")
                            .input("a", v)
                            .input("b", Value::Float(-std::f32::consts::PI / 180.0));
                        let radians = scope.graph.add(&format!("{name}_radians"), radians);
                        let z = Node::new("combine_xyz").input("z", Value::link(&radians, "value"));
                        Value::link(&scope.graph.add(&format!("{name}_angle"), z), "vector")
                    }
                    None => Value::Vector([0.0; 3]),
                };
                let trs = self
                    .uniform(scope, e, "operationorder")
                    .is_some_and(|o| o.trim() == "1");
                let step = |scope: &mut Scope<'a>, what: &str, node: Node, socket: &str| {
                    Value::link(&scope.graph.add(&format!("{name}_{what}"), node), socket)
                };
                let math = |op: &str, a: Value, b: Value| {
                    Node::new("vector_math")
                        .text("operation", op)
                        .input("a", a)
                        .input("b", b)
                };
                let rotate = |v: Value| {
                    Node::new("mapping")
                        .text("vector_type", "vector")
                        .input("vector", v)
                        .input("rotation", rotation.clone())
                };
                let centred = step(
                    scope,
                    "centred",
                    math("subtract", texcoord, pivot.clone()),
                    "vector",
                );
                let placed = if trs {
                    let moved = step(scope, "offset", math("subtract", centred, offset), "vector");
                    let turned = step(scope, "rotated", rotate(moved), "vector");
                    step(scope, "scaled", math("divide", turned, scale), "vector")
                } else {
                    let scaled = step(scope, "scaled", math("divide", centred, scale), "vector");
                    let turned = step(scope, "rotated", rotate(scaled), "vector");
                    step(scope, "offset", math("subtract", turned, offset), "vector")
                };
                let node = math("add", placed, pivot);
                let id = scope.graph.add(&name, position(e, node));
                out(Value::link(&id, "vector"))
            }
            "ramplr" | "ramptb" | "splitlr" | "splittb" | "ramp4" => {
                // MaterialX's NG definitions: mix(a, b, clamp(s)) for the ramps,
                // mix(a, b, aastep(center, s)) for the splits (a step here, unfiltered),
                // and ramp4's mix(mix(tl, tr, x), mix(bl, br, x), y).
                let coords = get!("texcoord").unwrap_or_else(|| {
                    let id = coordinates(scope, &format!("{name}_coords"), e, "texture_coordinate");
                    Value::link(&id, "uv")
                });
                let split = scope.graph.add(
                    &format!("{name}_split"),
                    Node::new("separate_xyz").input("vector", coords),
                );
                let horizontal = matches!(category, "ramplr" | "splitlr");
                let (x, y) = (Value::link(&split, "x"), Value::link(&split, "y"));
                let constant = |v: f32| {
                    if ty == "float" {
                        Value::Float(v)
                    } else {
                        Value::Color([v; 3])
                    }
                };
                let mix = |scope: &mut Scope<'a>, id: &str, t: Value, a: Value, b: Value| {
                    let mix = if ty == "float" {
                        Node::new("mix_float")
                    } else {
                        Node::new("mix_color").text("blend", "mix")
                    };
                    let id = scope.graph.add(
                        id,
                        position(e, mix.input("factor", t).input("a", a).input("b", b)),
                    );
                    Value::link(&id, "result")
                };
                if category == "ramp4" {
                    // MaterialX's defaults are 0 for every value.
                    let tl = get!("valuetl").unwrap_or(constant(0.0));
                    let tr = get!("valuetr").unwrap_or(constant(0.0));
                    let bl = get!("valuebl").unwrap_or(constant(0.0));
                    let br = get!("valuebr").unwrap_or(constant(0.0));
                    let top = mix(scope, &format!("{name}_top"), x.clone(), tl, tr);
                    let bottom = mix(scope, &format!("{name}_bottom"), x, bl, br);
                    return out(mix(scope, &name, y, top, bottom));
                }
                let t = if horizontal { x } else { y };
                let (a, b) = if horizontal {
                    ("valuel", "valuer")
                } else {
                    ("valuet", "valueb")
                };
                let t = if category.starts_with("split") {
                    let center = get!("center").unwrap_or(Value::Float(0.5));
                    let step = Node::new("math")
                        .text("operation", "greater_than")
                        .input("a", t)
                        .input("b", center);
                    Value::link(&scope.graph.add(&format!("{name}_step"), step), "value")
                } else {
                    t
                };
                let (a, b) = (
                    get!(a).unwrap_or(constant(0.0)),
                    get!(b).unwrap_or(constant(0.0)),
                );
                out(mix(scope, &name, t, a, b))
            }
            "clamp" if ty != "float" => {
                // Colour clamps to [0, 1] are the clamped result of a no-op mix.
                let low = get!("low");
                let high = get!("high");
                let unit = low.as_ref().is_none_or(|l| {
                    matches!(l, Value::Float(0.0))
                        || *l == Value::Color([0.0; 3])
                        || *l == Value::Vector([0.0; 3])
                }) && high.as_ref().is_none_or(|h| {
                    matches!(h, Value::Float(1.0))
                        || *h == Value::Color([1.0; 3])
                        || *h == Value::Vector([1.0; 3])
                });
                if !unit {
                    return None;
                }
                let node = Node::new("mix_color")
                    .text("blend", "mix")
                    .flag("clamp_result", true)
                    .input("factor", Value::Float(0.0))
                    .input("a", splat(get!("in")?));
                let id = scope.graph.add(&name, position(e, node));
                out(Value::link(&id, "result"))
            }
            _ => match self.custom_node(scope, e) {
                Ok(outputs) => outputs,
                Err(message) => {
                    self.warn(message);
                    None
                }
            },
        }
    }

    /// A node of a custom category: a Kiln node type the exporter wrote (`kiln_*`), or
    /// a node definition implemented by a node graph (a group). `Ok(None)` when it is
    /// neither; else the Kiln values of its outputs by name, `out` being the first.
    fn custom_node(
        &mut self,
        scope: &mut Scope<'a>,
        e: Element<'a>,
    ) -> Result<Option<HashMap<String, Value>>, String> {
        let category = e.tag_name().name();
        let name = name_of(e).to_owned();
        let group_name = category.strip_prefix(KILN_GROUP_PREFIX);
        // `kiln_TYPE`, or `kiln_TYPE__VARIANT` where the implementation depends on
        // the parameters.
        let kiln_kind = category
            .strip_prefix(KILN_NODE_PREFIX)
            .filter(|_| group_name.is_none())
            .map(|rest| rest.split("__").next().unwrap_or(rest));
        let mut node = if let Some(kind) = kiln_kind {
            Node::new(kind)
        } else if let Some((nodedef, ng)) = self.doc.definition(category) {
            let group = group_name.unwrap_or(category).to_owned();
            let interface: Vec<Element> = elements(nodedef)
                .filter(|c| c.tag_name().name() == "input")
                .collect();
            self.group(&group, ng, &interface, Some(nodedef));
            Node::group(&group)
        } else if group_name.is_some() {
            return Err(format!(
                "node {name}: group {category} has no node graph in the file"
            ));
        } else {
            return Ok(None);
        };
        for i in elements(e).filter(|c| c.tag_name().name() == "input") {
            let input_name = name_of(i);
            let input_type = i.attribute("type").unwrap_or("float");
            if i.attribute("uniform") == Some("true") || table::kiln_type(input_type).is_none() {
                let Some(text) = self.uniform(scope, e, input_name) else {
                    continue;
                };
                let param = match input_type {
                    "boolean" => Param::Bool(boolean(&text)),
                    "float" => Param::Number(text.trim().parse().unwrap_or(0.0)),
                    "floatarray" => {
                        let v: Vec<f32> = text
                            .split(',')
                            .filter_map(|x| x.trim().parse().ok())
                            .collect();
                        Param::Ramp(
                            v.chunks_exact(5)
                                .map(|c| (c[0], [c[1], c[2], c[3], c[4]]))
                                .collect(),
                        )
                    }
                    _ => Param::Text(text),
                };
                node = node.param(input_name, param);
            } else if let Some(v) = self.resolve(scope, i) {
                node = node.input(input_name, v);
            }
        }
        if e.attribute("kiln_muted") == Some("true") {
            node = node.mute();
        }
        let id = scope.graph.add(&name, position(e, node));
        // Output names (MaterialX's, Kiln's): the node definition's, else what
        // connections name.
        let nodedef = self
            .doc
            .top_elements()
            .find(|d| d.tag_name().name() == "nodedef" && d.attribute("node") == Some(category));
        let mut names: Vec<(String, String)> = nodedef
            .map(|d| {
                elements(d)
                    .filter(|o| o.tag_name().name() == "output")
                    .map(|o| (name_of(o).to_owned(), kiln_output_name(Some(d), name_of(o))))
                    .collect()
            })
            .unwrap_or_default();
        if names.is_empty() {
            let container = e.parent().unwrap_or(e);
            for i in container
                .descendants()
                .filter(|d| d.attribute("nodename") == Some(&name))
            {
                if let Some(o) = i.attribute("output")
                    && !names.iter().any(|(n, _)| n == o)
                {
                    names.push((o.to_owned(), o.to_owned()));
                }
            }
        }
        let mut outputs: HashMap<String, Value> = names
            .iter()
            .map(|(mx, kiln)| (mx.clone(), Value::link(&id, kiln)))
            .collect();
        if let Some((_, first)) = names.first() {
            outputs
                .entry("out".to_owned())
                .or_insert(Value::link(&id, first));
        }
        Ok(Some(outputs))
    }

    /// An image node as Kiln's Image Texture, with a Mapping node for tiling and a
    /// Separate Color for a float image (MaterialX reads a float image's first channel).
    fn image(&mut self, scope: &mut Scope<'a>, e: Element<'a>) -> Option<HashMap<String, Value>> {
        let name = name_of(e).to_owned();
        let category = e.tag_name().name();
        let ty = e.attribute("type").unwrap_or("color3");
        let Some(file) = self.uniform(scope, e, "file") else {
            self.warn(format!("image {name} names no file"));
            return None;
        };
        if !file.is_empty() && !self.doc.folder.join(&file).is_file() {
            self.warn(format!("texture {file} (image {name}) is not found"));
        }
        if category == "hextiledimage" {
            self.warn(format!(
                "image {name}: hexagonal tiling is not supported; the image is tiled as a grid"
            ));
        }
        let srgb = input(e, "file")
            .and_then(|f| f.attribute("colorspace"))
            .is_some_and(|c| c.starts_with("srgb"))
            || (category == "gltf_colorimage" && ty.starts_with("color"));
        let extension = match self.uniform(scope, e, "uaddressmode").as_deref() {
            Some("clamp") => "extend",
            Some("constant") => "clip",
            Some("mirror") => "mirror",
            _ => "repeat",
        };
        let interpolation = match self.uniform(scope, e, "filtertype").as_deref() {
            Some("closest") => "closest",
            _ => "linear",
        };
        let mut node = Node::new("image_texture")
            .text("file", &file)
            .text("color_space", if srgb { "srgb" } else { "linear" })
            .text("extension", extension)
            .text("interpolation", interpolation);
        let texcoord = input(e, "texcoord").and_then(|i| self.resolve(scope, i));
        let tiling = input(e, "uvtiling")
            .or(input(e, "tiling"))
            .and_then(|i| self.resolve(scope, i));
        let offset = input(e, "uvoffset")
            .or(input(e, "offset"))
            .and_then(|i| self.resolve(scope, i));
        let tiled = tiling
            .as_ref()
            .is_some_and(|t| *t != Value::Vector([1.0, 1.0, 0.0]))
            || offset
                .as_ref()
                .is_some_and(|o| *o != Value::Vector([0.0; 3]));
        let coords = if tiled {
            let coords = texcoord.unwrap_or_else(|| {
                let id = coordinates(scope, &format!("{name}_coords"), e, "texture_coordinate");
                Value::link(&id, "uv")
            });
            let scale = match tiling {
                Some(Value::Vector([x, y, _])) => Value::Vector([x, y, 1.0]),
                Some(Value::Float(s)) => Value::Vector([s, s, 1.0]),
                Some(v) => v,
                None => Value::Vector([1.0; 3]),
            };
            let location = match offset {
                Some(Value::Vector([x, y, _])) => Value::Vector([-x, -y, 0.0]),
                _ => Value::Vector([0.0; 3]),
            };
            let mapping = Node::new("mapping")
                .text("vector_type", "point")
                .input("vector", coords)
                .input("scale", scale)
                .input("location", location);
            Some(Value::link(
                &scope.graph.add(&format!("{name}_tiling"), mapping),
                "vector",
            ))
        } else {
            texcoord
        };
        if let Some(c) = coords {
            node = node.input("vector", c);
        }
        let id = scope.graph.add(&name, position(e, node));
        let color = Value::link(&id, "color");
        if category == "gltf_colorimage" {
            return Some(HashMap::from([
                ("outcolor".to_owned(), color.clone()),
                ("out".to_owned(), color),
                ("outa".to_owned(), Value::link(&id, "alpha")),
            ]));
        }
        let value = if category == "gltf_normalmap" {
            let n = Node::new("normal_map").input("color", color);
            Value::link(&scope.graph.add(&format!("{name}_normal"), n), "normal")
        } else if ty == "float" {
            let split = Node::new("separate_color")
                .text("mode", "rgb")
                .input("color", color);
            Value::link(&scope.graph.add(&format!("{name}_red"), split), "red")
        } else {
            color
        };
        Some(HashMap::from([("out".to_owned(), value)]))
    }
}

/// The Kiln name of output `mx` of a node definition: its `kiln_output` attribute (what
/// the exporter writes where MaterialX's naming rules change the name), or the name.
fn kiln_output_name(nodedef: Option<Element>, mx: &str) -> String {
    nodedef
        .and_then(|d| {
            elements(d).find(|o| o.tag_name().name() == "output" && o.attribute("name") == Some(mx))
        })
        .and_then(|o| o.attribute("kiln_output"))
        .unwrap_or(mx)
        .to_owned()
}

/// A coordinate node for MaterialX node `e`: nodes the exporter split off one Kiln node
/// (`uvs__uv`, `uvs__object`) become that node again.
fn coordinates(scope: &mut Scope, name: &str, e: Element, kind: &str) -> String {
    if let Some((base, _)) = name.split_once("__")
        && let Some((id, _)) = scope
            .graph
            .nodes()
            .iter()
            .find(|(id, n)| id == base && n.kind() == kind)
    {
        return id.clone();
    }
    let base = name.split_once("__").map_or(name, |(b, _)| b);
    scope.graph.add(base, position(e, Node::new(kind)))
}

/// `node` at `e`'s `xpos`/`ypos`, where it has them.
fn position(e: Element, node: Node) -> Node {
    let get = |a: &str| e.attribute(a).and_then(|v| v.trim().parse::<f32>().ok());
    match (get("xpos"), get("ypos")) {
        (Some(x), Some(y)) => node.at(x * POSITION_SCALE, y * POSITION_SCALE),
        _ => node,
    }
}
