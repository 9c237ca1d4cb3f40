//! Material graph → WGSL.
//!
//! The passes, in order: flatten node groups, reroutes and muted nodes (links through
//! them become links to what they pass) → check node types, parameters and socket
//! types → find the output and reject cycles → keep only what reaches the output → fold
//! constants → merge identical nodes → emit one WGSL function per material, its nodes in
//! topological order. Every error names the material, the node and the socket.
//!
//! The emitted function is `fn <name>(sp: ShadingPoint) -> MaterialEval`
//! (shaders/nodes/inputs.wgsl); it calls the node library's functions
//! (shaders/nodes/*.wgsl), of which kernel assembly includes only those called.
//!
//! Constants are written into the code ([`Constants::Inline`]: folded, merged, what final
//! renders compile) or, for the editor, read from the `material_params` buffer
//! ([`Constants::Live`]): then no constant is folded or merged, so two graphs that differ
//! only in their input values compile to the same code and a slider edit writes the
//! buffer instead of building a kernel.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fmt::Write as _;

use thiserror::Error;

use super::bounds::Bounds;
use super::graph::{
    Conversion, GROUP, GROUP_INPUT, GROUP_PARAM, Graph, Input, Link, Node, Param, REROUTE,
    REROUTE_INPUT, REROUTE_OUTPUT, RampStop, SocketType, Value,
};
use super::nodes::{
    self, Code, Default, Emit, MATERIAL_OUTPUT, NodeDef, ParamKind, Params, WORLD_OUTPUT,
};

/// A graph error, with where it is.
#[derive(Clone, Debug, Error, PartialEq)]
#[error("material \"{material}\"{}: {message}", location(.node, .socket))]
pub struct GraphError {
    pub material: String,
    pub node: Option<String>,
    pub socket: Option<String>,
    pub message: String,
}

fn location(node: &Option<String>, socket: &Option<String>) -> String {
    match (node, socket) {
        (Some(n), Some(s)) => format!(", node \"{n}\", socket \"{s}\""),
        (Some(n), None) => format!(", node \"{n}\""),
        _ => String::new(),
    }
}

/// What the renderer must know about a compiled material without running it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MaterialTraits {
    /// Light may pass through (transmission, thin walls): the surface keeps its front.
    pub transmissive: bool,
    /// Emission when it is the same everywhere (such surfaces are sampled as lights).
    pub constant_emission: Option<[f32; 3]>,
    /// Emission that varies over the surface (not sampled as a light).
    pub varying_emission: bool,
    /// Principled lobes the material can reach, and whether it has a volume
    /// ([`crate::shader::lobes`]).
    pub lobes: u32,
    /// A volume without a surface: the boundary only marks where the volume begins
    /// and ends, and light crosses it unchanged.
    pub boundary_only: bool,
    /// The volume inside, homogeneous (its inputs are constants).
    pub volume: Option<VolumeCoefficients>,
    /// For a heterogeneous volume (its coefficients vary inside): an extinction per scene
    /// unit that no point of it exceeds in any channel, proved from the bounds of the
    /// nodes feeding it ([`super::bounds`]); the integrator tracks through it by delta
    /// and ratio tracking, evaluating the volume's function at points inside.
    pub volume_majorant: Option<f32>,
}

/// A homogeneous volume's coefficients per scene unit and channel (what
/// shaders/nodes/volume.wgsl computes from the same inputs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VolumeCoefficients {
    pub absorption: [f32; 3],
    pub scattering: [f32; 3],
    /// Emitted radiance per unit length.
    pub emission: [f32; 3],
    /// The Henyey–Greenstein anisotropy, within ±0.999.
    pub g: f32,
}

/// Where a compiled material's constant inputs live.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Constants {
    /// In the code, folded through the nodes that only compute on constants.
    Inline,
    /// In `material_params` (`array<vec4<f32>>`), from element `base` on, one element per
    /// constant input ([`CompiledMaterial::parameters`]).
    Live { base: u32 },
}

#[derive(Clone, Debug)]
pub struct CompiledMaterial {
    /// The material's name, for messages.
    pub material: String,
    pub function: String,
    /// The material's WGSL: helper functions, then `function`.
    pub code: String,
    /// For a heterogeneous volume: `fn <volume_function>(sp: ShadingPoint) -> VolumeEval`
    /// in `code`, the volume at a point inside.
    pub volume_function: Option<String>,
    /// Node-library functions `code` calls (entry points; kernel assembly adds what
    /// they call in turn).
    pub calls: BTreeSet<String>,
    pub traits: MaterialTraits,
    /// Image files the material reads, with the node that reads each.
    pub images: BTreeMap<String, String>,
    /// With [`Constants::Live`]: the values of `material_params` from `base` on, in the
    /// order the code reads them (empty for inline constants).
    pub parameters: Vec<[f32; 4]>,
}

/// Where an input's value comes from after flattening.
#[derive(Clone, Debug, PartialEq)]
enum Src {
    Const(Value),
    Out(usize, usize),
    /// A shading-point expression of the given type: the declared default of a muted
    /// node's input that it passes through.
    Implicit(&'static str, SocketType),
    Default,
}

#[derive(Clone, Debug)]
struct FlatNode {
    id: String,
    def: &'static NodeDef,
    params: BTreeMap<String, Param>,
    /// One per `def.inputs`.
    inputs: Vec<Src>,
}

struct Ctx<'a> {
    material: &'a str,
}

impl Ctx<'_> {
    fn err(&self, node: Option<&str>, socket: Option<&str>, message: String) -> GraphError {
        GraphError {
            material: self.material.to_owned(),
            node: node.map(str::to_owned),
            socket: socket.map(str::to_owned),
            message,
        }
    }
}

/// Compiles `graph` into a function called `function`.
pub fn compile(
    material: &str,
    graph: &Graph,
    function: &str,
) -> Result<CompiledMaterial, GraphError> {
    compile_with_textures(material, graph, function, &mut BTreeMap::new())
}

/// [`compile`] with the scene's texture indices by file; files not yet in `textures` get
/// the next free index.
pub fn compile_with_textures(
    material: &str,
    graph: &Graph,
    function: &str,
    textures: &mut BTreeMap<String, u32>,
) -> Result<CompiledMaterial, GraphError> {
    compile_with(material, graph, function, textures, Constants::Inline)
}

/// [`compile_with_textures`] with its constants where `constants` says.
pub fn compile_with(
    material: &str,
    graph: &Graph,
    function: &str,
    textures: &mut BTreeMap<String, u32>,
    constants: Constants,
) -> Result<CompiledMaterial, GraphError> {
    let ctx = Ctx { material };
    let flat = Flattener::new(&ctx, graph).run()?;
    check_types(&ctx, &flat)?;
    let output = find_output(&ctx, graph, &flat)?;
    reject_cycles(&ctx, &flat, output)?;
    check_volume(&ctx, &flat, output)?;
    let mut material = emit_function(
        &ctx,
        flat.clone(),
        (output, 0),
        (function, "MaterialEval"),
        textures,
        constants,
        |flat, root| (root.to_owned(), traits(flat, output)),
    )?;
    if material.traits.volume_majorant.is_some() {
        // The volume alone, for the points inside where the integrator tracks through it.
        let Src::Out(volume, o) = flat[output].inputs[1] else {
            unreachable!("a heterogeneous volume is linked")
        };
        let name = format!("{function}_volume");
        let constants = match constants {
            Constants::Inline => Constants::Inline,
            Constants::Live { base } => Constants::Live {
                base: base + material.parameters.len() as u32,
            },
        };
        let inside = emit_function(
            &ctx,
            flat,
            (volume, o),
            (&name, "VolumeEval"),
            textures,
            constants,
            |_, root| (root.to_owned(), MaterialTraits::default()),
        )?;
        material.code.push_str(&inside.code);
        material.calls.extend(inside.calls);
        material.images.extend(inside.images);
        material.parameters.extend(inside.parameters);
        material.volume_function = Some(name);
    }
    Ok(material)
}

/// Rejects cycles toward `root`, folds constants, merges identical nodes and emits
/// `fn <function>(sp: ShadingPoint) -> <returns>` for `(function, returns)`; `finish`
/// turns the root's expression into the returned one and says what is known of the
/// material.
fn emit_function(
    ctx: &Ctx,
    mut flat: Vec<FlatNode>,
    root: (usize, usize),
    (function, returns): (&str, &str),
    textures: &mut BTreeMap<String, u32>,
    constants: Constants,
    finish: impl FnOnce(&[FlatNode], &str) -> (String, MaterialTraits),
) -> Result<CompiledMaterial, GraphError> {
    reject_cycles(ctx, &flat, root.0)?;
    if constants == Constants::Inline {
        // Folding and merging look at the values, which live constants must not fix
        // into the code.
        fold_constants(&mut flat, root.0);
        merge_identical(&mut flat, root.0);
    }
    let mut emitter = Emitter {
        flat: &flat,
        prefix: function,
        helpers: String::new(),
        helper_names: BTreeSet::new(),
        calls: BTreeSet::new(),
        textures,
        images: BTreeMap::new(),
        live: match constants {
            Constants::Inline => None,
            Constants::Live { base } => Some((base, Vec::new())),
        },
    };
    let body = emitter.function_body(&[root])?;
    let (value, traits) = finish(&flat, &body.roots[0]);
    let mut code = emitter.helpers.clone();
    let _ = writeln!(code, "fn {function}(sp: ShadingPoint) -> {returns} {{");
    code.push_str(&body.statements);
    let _ = writeln!(code, "    return {value};\n}}");
    Ok(CompiledMaterial {
        material: ctx.material.to_owned(),
        function: function.to_owned(),
        code,
        volume_function: None,
        calls: emitter.calls,
        traits,
        images: emitter.images,
        parameters: emitter.live.map(|(_, values)| values).unwrap_or_default(),
    })
}

/// Compiles the value of one output, `node.socket`, into `fn <function>(sp:
/// ShadingPoint) -> vec4<f32>` (floats in x, vectors and colours in xyz): previews and
/// the per-node tests evaluate single sockets this way.
pub fn compile_value(
    material: &str,
    graph: &Graph,
    at: &Link,
    function: &str,
) -> Result<CompiledMaterial, GraphError> {
    compile_value_with_textures(material, graph, at, function, &mut BTreeMap::new())
}

/// [`compile_value`] with the scene's texture indices (see [`compile_with_textures`]).
pub fn compile_value_with_textures(
    material: &str,
    graph: &Graph,
    at: &Link,
    function: &str,
    textures: &mut BTreeMap<String, u32>,
) -> Result<CompiledMaterial, GraphError> {
    if let Some((graph, at)) = muted_probe(graph, at) {
        return compile_value_with_textures(material, &graph, &at, function, textures);
    }
    let ctx = Ctx { material };
    let flat = Flattener::new(&ctx, graph).run()?;
    check_types(&ctx, &flat)?;
    let Some(node) = flat.iter().position(|n| n.id == at.node) else {
        return Err(ctx.err(None, None, format!("no node \"{}\"", at.node)));
    };
    let Some((output, def)) = flat[node].def.output(&at.socket) else {
        return Err(ctx.err(Some(&at.node), Some(&at.socket), "no such output".into()));
    };
    let ty = def.ty;
    if ty.is_shader() {
        return Err(ctx.err(
            Some(&at.node),
            Some(&at.socket),
            "a shader has no value to preview".into(),
        ));
    }
    emit_function(
        &ctx,
        flat,
        (node, output),
        (function, "vec4<f32>"),
        textures,
        Constants::Inline,
        |_, v| {
            let value = match ty {
                SocketType::Float => format!("vec4<f32>({v}, 0.0, 0.0, 0.0)"),
                SocketType::Vec2 => format!("vec4<f32>({v}, 0.0, 0.0)"),
                _ => format!("vec4<f32>({v}, 0.0)"),
            };
            (value, MaterialTraits::default())
        },
    )
}

/// For an output `at` of a muted node: the graph with a probe node ([`nodes::identity`]
/// of the output's type) reading it, and the probe's output, so that a preview shows what
/// the muted node passes on. `None` for a node that is not muted (or a type no probe
/// carries: a muted node's two-component output is previewed as computed).
fn muted_probe(graph: &Graph, at: &Link) -> Option<(Graph, Link)> {
    let node = graph.nodes.get(&at.node).filter(|n| n.muted)?;
    let ty = match node.kind.as_str() {
        GROUP => {
            let Some(Param::Text(name)) = node.params.get(GROUP_PARAM) else {
                return None;
            };
            let group = graph.groups.get(name)?;
            group.outputs.iter().find(|s| s.name == at.socket)?.ty
        }
        kind => nodes::find(kind)?.output(&at.socket)?.1.ty,
    };
    let (kind, input, output) = nodes::identity(ty)?;
    let mut id = format!("{}~preview", at.node);
    while graph.nodes.contains_key(&id) {
        id.push('~');
    }
    let mut probe = graph.clone();
    probe.add(&id, Node::new(kind).input(input, Input::Link(at.clone())));
    Some((probe, Link::new(&id, output)))
}

// ------------------------------------------------------------------ flattening

/// Expands groups into one flat node list with resolved links.
struct Flattener<'a> {
    ctx: &'a Ctx<'a>,
    graph: &'a Graph,
    nodes: Vec<FlatNode>,
    index: HashMap<String, usize>,
    /// Nodes met so far, group instances counted with what they contain.
    visited: usize,
}

/// A scope: the nodes of the material or of one group instance.
#[derive(Clone)]
struct Scope<'a> {
    prefix: String,
    nodes: &'a BTreeMap<String, Node>,
    /// For a group instance: the instance node and the scope it sits in.
    instance: Option<(&'a Node, Box<Scope<'a>>, &'a super::graph::Group)>,
    depth: usize,
}

// The most nodes a material may expand to ([`crate::limits::Limits::graph_nodes`]),
// every instance of a group counted with its nodes. A group used four times inside a group
// used four times … multiplies: a 4 KB file of 14 such groups expanded to 4^13 nodes and
// exhausted memory (docs/RELIABILITY.md). Hand-made graphs are hundreds of nodes; the
// kernel's code grows with the count.

impl<'a> Flattener<'a> {
    fn new(ctx: &'a Ctx<'a>, graph: &'a Graph) -> Self {
        Self {
            ctx,
            graph,
            nodes: Vec::new(),
            index: HashMap::new(),
            visited: 0,
        }
    }

    fn run(mut self) -> Result<Vec<FlatNode>, GraphError> {
        let root = Scope {
            prefix: String::new(),
            nodes: &self.graph.nodes,
            instance: None,
            depth: 0,
        };
        self.create(&root)?;
        self.resolve(&root)?;
        Ok(self.nodes)
    }

    fn group(
        &self,
        id: &str,
        node: &Node,
    ) -> Result<(&'a str, &'a super::graph::Group), GraphError> {
        let name = match node.params.get(GROUP_PARAM) {
            Some(Param::Text(name)) => name.as_str(),
            _ => {
                return Err(self.ctx.err(
                    Some(id),
                    None,
                    format!("a {GROUP} node needs params: {{ \"{GROUP_PARAM}\": \"name\" }}"),
                ));
            }
        };
        match self.graph.groups.get_key_value(name) {
            Some((k, g)) => Ok((k.as_str(), g)),
            None => Err(self
                .ctx
                .err(Some(id), None, format!("no group named \"{name}\""))),
        }
    }

    /// Creates the flat nodes of a scope (recursively for group instances).
    fn create(&mut self, scope: &Scope<'a>) -> Result<(), GraphError> {
        for (id, node) in scope.nodes {
            let full = format!("{}{id}", scope.prefix);
            self.visited += 1;
            let limit = crate::limits::current().graph_nodes;
            if self.visited > limit {
                return Err(self.ctx.err(
                    Some(&full),
                    None,
                    format!(
                        "the graph expands to more than {limit} nodes (each use of a group \
                         counts its nodes, so groups used inside groups multiply; \
                         --max-graph-nodes raises the limit)"
                    ),
                ));
            }
            match node.kind.as_str() {
                GROUP => {
                    let depth = crate::limits::current().group_depth;
                    if scope.depth >= depth {
                        return Err(self.ctx.err(
                            Some(&full),
                            None,
                            format!(
                                "groups nest deeper than {depth} (a group that contains itself? \
                                 --max-group-depth raises the limit)"
                            ),
                        ));
                    }
                    let (_, group) = self.group(&full, node)?;
                    self.create(&Scope {
                        prefix: format!("{full}/"),
                        nodes: &group.nodes,
                        instance: Some((node, Box::new(scope.clone()), group)),
                        depth: scope.depth + 1,
                    })?;
                }
                REROUTE => {
                    for (name, input) in &node.inputs {
                        if name != REROUTE_INPUT {
                            return Err(self.ctx.err(
                                Some(&full),
                                Some(name),
                                format!("a {REROUTE} has one input, \"{REROUTE_INPUT}\""),
                            ));
                        }
                        if matches!(input, Input::Value(_)) {
                            return Err(self.ctx.err(
                                Some(&full),
                                Some(name),
                                format!("a {REROUTE} passes a link on; it holds no value"),
                            ));
                        }
                    }
                    if let Some(name) = node.params.keys().next() {
                        return Err(self.ctx.err(
                            Some(&full),
                            Some(name),
                            format!("a {REROUTE} has no parameters"),
                        ));
                    }
                }
                GROUP_INPUT => {
                    if scope.instance.is_none() {
                        return Err(self.ctx.err(
                            Some(&full),
                            None,
                            format!("{GROUP_INPUT} is only meaningful inside a group"),
                        ));
                    }
                }
                kind => {
                    let Some(def) = nodes::find(kind) else {
                        return Err(self.ctx.err(
                            Some(&full),
                            None,
                            format!("unknown node type \"{kind}\""),
                        ));
                    };
                    for name in node.inputs.keys() {
                        if def.input(name).is_none() {
                            return Err(self.ctx.err(
                                Some(&full),
                                Some(name),
                                format!(
                                    "{kind} has no input \"{name}\" (inputs: {})",
                                    names(def.inputs.iter().map(|s| s.name))
                                ),
                            ));
                        }
                    }
                    for (name, value) in &node.params {
                        check_param(self.ctx, &full, def, name, value)?;
                    }
                    for p in &def.params {
                        if matches!(p.kind, ParamKind::File) && !node.params.contains_key(p.name) {
                            return Err(self.ctx.err(
                                Some(&full),
                                Some(p.name),
                                format!(
                                    "{kind} needs params: {{ \"{}\": \"image file\" }}",
                                    p.name
                                ),
                            ));
                        }
                    }
                    self.index.insert(full.clone(), self.nodes.len());
                    self.nodes.push(FlatNode {
                        id: full,
                        def,
                        params: node.params.clone(),
                        inputs: vec![Src::Default; def.inputs.len()],
                    });
                }
            }
        }
        Ok(())
    }

    /// Resolves every input of a scope's nodes.
    fn resolve(&mut self, scope: &Scope<'a>) -> Result<(), GraphError> {
        for (id, node) in scope.nodes {
            let full = format!("{}{id}", scope.prefix);
            if node.kind == GROUP {
                let (_, group) = self.group(&full, node)?;
                for name in node.inputs.keys() {
                    if !group.inputs.iter().any(|s| &s.name == name) {
                        return Err(self.ctx.err(
                            Some(&full),
                            Some(name),
                            format!("the group has no input \"{name}\""),
                        ));
                    }
                }
                self.resolve(&Scope {
                    prefix: format!("{full}/"),
                    nodes: &group.nodes,
                    instance: Some((node, Box::new(scope.clone()), group)),
                    depth: scope.depth + 1,
                })?;
                continue;
            }
            if node.kind == REROUTE {
                // Checked here so that an unused reroute's broken link is reported too.
                if let Some(input) = node.inputs.get(REROUTE_INPUT) {
                    self.source(scope, &full, REROUTE_INPUT, input, 0)?;
                }
                continue;
            }
            let Some(&index) = self.index.get(&full) else {
                continue;
            };
            let def = self.nodes[index].def;
            for (i, socket) in def.inputs.iter().enumerate() {
                if let Some(input) = node.inputs.get(socket.name) {
                    // A value set on the input keeps to its range; what reaches it through
                    // a link (a group's default, a muted node) is computed, and is not
                    // limited.
                    if let (Input::Value(Value::Float(x)), Some(range)) = (input, socket.range) {
                        if !range.contains(*x) {
                            return Err(self.ctx.err(
                                Some(&full),
                                Some(socket.name),
                                format!(
                                    "the value {x} lies outside the input's range {}",
                                    range.describe()
                                ),
                            ));
                        }
                    }
                    let src = self.source(scope, &full, socket.name, input, 0)?;
                    self.nodes[index].inputs[i] = src;
                }
            }
        }
        Ok(())
    }

    /// Where `input` (of node `at`, socket `socket`, in `scope`) gets its value.
    fn source(
        &self,
        scope: &Scope<'a>,
        at: &str,
        socket: &str,
        input: &Input,
        hops: usize,
    ) -> Result<Src, GraphError> {
        if hops > 64 * crate::limits::current().group_depth {
            return Err(self.ctx.err(
                Some(at),
                Some(socket),
                "links through groups, reroutes or muted nodes loop".into(),
            ));
        }
        let link = match input {
            Input::Value(v) => return Ok(Src::Const(v.clone())),
            Input::Link(link) => link,
        };
        let Some(target) = scope.nodes.get(&link.node) else {
            return Err(self.ctx.err(
                Some(at),
                Some(socket),
                format!("link to \"{link}\": no node \"{}\"", link.node),
            ));
        };
        let full = format!("{}{}", scope.prefix, link.node);
        match target.kind.as_str() {
            REROUTE => {
                if link.socket != REROUTE_OUTPUT {
                    return Err(self.ctx.err(
                        Some(at),
                        Some(socket),
                        format!("link to \"{link}\": a {REROUTE}'s output is \"{REROUTE_OUTPUT}\""),
                    ));
                }
                match target.inputs.get(REROUTE_INPUT) {
                    Some(input) => self.source(scope, at, socket, input, hops + 1),
                    None => Ok(Src::Default),
                }
            }
            GROUP => {
                let (_, group) = self.group(&full, target)?;
                let no_output = || {
                    self.ctx.err(
                        Some(at),
                        Some(socket),
                        format!(
                            "link to \"{link}\": the group has no output \"{}\"",
                            link.socket
                        ),
                    )
                };
                if target.muted {
                    let out = (group.outputs.iter())
                        .find(|s| s.name == link.socket)
                        .ok_or_else(no_output)?;
                    let inputs = group.inputs.iter().map(|s| {
                        let declared = s.default.clone().map_or_else(|| zero(s.ty), Src::Const);
                        (s.name.as_str(), s.ty, declared)
                    });
                    return self.muted_source(
                        scope,
                        at,
                        socket,
                        (&full, target),
                        inputs,
                        out.ty,
                        hops,
                    );
                }
                let inner = group.links.get(&link.socket).ok_or_else(no_output)?;
                let inner_scope = Scope {
                    prefix: format!("{full}/"),
                    nodes: &group.nodes,
                    instance: Some((target, Box::new(scope.clone()), group)),
                    depth: scope.depth + 1,
                };
                self.source(
                    &inner_scope,
                    at,
                    socket,
                    &Input::Link(inner.clone()),
                    hops + 1,
                )
            }
            GROUP_INPUT => {
                let Some((instance, outer, group)) = &scope.instance else {
                    return Err(self.ctx.err(
                        Some(&full),
                        None,
                        format!("{GROUP_INPUT} outside a group"),
                    ));
                };
                let Some(declared) = group.inputs.iter().find(|s| s.name == link.socket) else {
                    return Err(self.ctx.err(
                        Some(at),
                        Some(socket),
                        format!(
                            "link to \"{link}\": the group has no input \"{}\"",
                            link.socket
                        ),
                    ));
                };
                match instance.inputs.get(&link.socket) {
                    Some(outer_input) => self.source(outer, at, socket, outer_input, hops + 1),
                    None => Ok(declared.default.clone().map_or(Src::Default, Src::Const)),
                }
            }
            _ => {
                let index = self.index[&full];
                let def = self.nodes[index].def;
                match def.output(&link.socket) {
                    Some((_, out)) if target.muted => {
                        let inputs = def.inputs.iter().map(|s| {
                            let declared = match &s.default {
                                Default::Value(v) => Src::Const(v.clone()),
                                Default::Implicit(expr, _) => Src::Implicit(expr, s.ty),
                            };
                            (s.name, s.ty, declared)
                        });
                        self.muted_source(scope, at, socket, (&full, target), inputs, out.ty, hops)
                    }
                    Some((o, _)) => Ok(Src::Out(index, o)),
                    None => Err(self.ctx.err(
                        Some(at),
                        Some(socket),
                        format!(
                            "link to \"{link}\": {} has no output \"{}\" (outputs: {})",
                            def.kind,
                            link.socket,
                            names(def.outputs.iter().map(|o| o.name))
                        ),
                    )),
                }
            }
        }
    }
}

impl<'a> Flattener<'a> {
    /// What an output of type `ty` of the muted node `target` (id `id`, in `scope`) passes
    /// to input `socket` of node `at`: the first of the node's `inputs` (name, type, what
    /// it reads when not given) of type `ty`, resolved as a link to it would be; else the
    /// type's zero.
    #[allow(clippy::too_many_arguments)]
    fn muted_source<'i>(
        &self,
        scope: &Scope<'a>,
        at: &str,
        socket: &str,
        (id, target): (&str, &'a Node),
        mut inputs: impl Iterator<Item = (&'i str, SocketType, Src)>,
        ty: SocketType,
        hops: usize,
    ) -> Result<Src, GraphError> {
        let consumer = self
            .index
            .get(at)
            .and_then(|&n| self.nodes[n].def.input(socket))
            .map_or(ty, |s| s.ty);
        // Muting must not hide a wire the compiler would refuse.
        if ty.converts_to(consumer).is_none() {
            return Err(self.ctx.err(
                Some(at),
                Some(socket),
                format!(
                    "a {} output (of muted node {id}) cannot feed a {} input",
                    ty.name(),
                    consumer.name()
                ),
            ));
        }
        let src = match inputs.find(|(_, t, _)| *t == ty) {
            Some((name, _, declared)) => match target.inputs.get(name) {
                Some(input) => self.source(scope, at, socket, input, hops + 1)?,
                None => declared,
            },
            None => zero(ty),
        };
        // A constant is in the muted socket's type; the consumer reads it in its own.
        Ok(match src {
            Src::Const(v) => Src::Const(convert_const(&v, ty, consumer)),
            other => other,
        })
    }
}

/// The zero of a socket type, as a source: 0, black; a shader has none, and its consumer
/// reads its own default.
fn zero(ty: SocketType) -> Src {
    match ty {
        SocketType::Float => Src::Const(Value::Float(0.0)),
        SocketType::Vec2 => Src::Const(Value::Vec2([0.0; 2])),
        SocketType::Vector | SocketType::Color => Src::Const(Value::Vec3([0.0; 3])),
        SocketType::Bsdf | SocketType::Volume => Src::Default,
    }
}

fn names<'a>(it: impl Iterator<Item = &'a str>) -> String {
    let v: Vec<&str> = it.collect();
    if v.is_empty() {
        "none".into()
    } else {
        v.join(", ")
    }
}

fn check_param(
    ctx: &Ctx,
    node: &str,
    def: &NodeDef,
    name: &str,
    value: &Param,
) -> Result<(), GraphError> {
    let Some(p) = def.param(name) else {
        return Err(ctx.err(
            Some(node),
            Some(name),
            format!(
                "{} has no parameter \"{name}\" (parameters: {})",
                def.kind,
                names(def.params.iter().map(|p| p.name))
            ),
        ));
    };
    let ok = match (&p.kind, value) {
        (ParamKind::Enum(options), Param::Text(t)) => {
            if !options.contains(&t.as_str()) {
                return Err(ctx.err(
                    Some(node),
                    Some(name),
                    format!("\"{t}\" is not one of {}", options.join(", ")),
                ));
            }
            true
        }
        (ParamKind::Bool(_), Param::Bool(_)) => true,
        (ParamKind::File, Param::Text(_)) => true,
        (ParamKind::Ramp, Param::Ramp(stops)) => {
            if stops.is_empty() {
                return Err(ctx.err(
                    Some(node),
                    Some(name),
                    "a colour ramp needs at least one stop".into(),
                ));
            }
            if stops
                .iter()
                .any(|s| !s.position.is_finite() || s.color.iter().any(|c| !c.is_finite()))
            {
                return Err(ctx.err(Some(node), Some(name), "ramp stops must be finite".into()));
            }
            true
        }
        _ => false,
    };
    if ok {
        Ok(())
    } else {
        Err(ctx.err(
            Some(node),
            Some(name),
            format!("wrong kind of value: {value:?}"),
        ))
    }
}

// ----------------------------------------------------------------- type checks

fn output_type(flat: &[FlatNode], node: usize, output: usize) -> SocketType {
    flat[node].def.outputs[output].ty
}

fn check_types(ctx: &Ctx, flat: &[FlatNode]) -> Result<(), GraphError> {
    for node in flat {
        for (socket, src) in node.def.inputs.iter().zip(&node.inputs) {
            let fail = |m: String| Err(ctx.err(Some(&node.id), Some(socket.name), m));
            match src {
                Src::Out(n, o) => {
                    let from = output_type(flat, *n, *o);
                    if from.converts_to(socket.ty).is_none() {
                        return fail(format!(
                            "a {} output ({}.{}) cannot feed a {} input",
                            from.name(),
                            flat[*n].id,
                            flat[*n].def.outputs[*o].name,
                            socket.ty.name()
                        ));
                    }
                }
                Src::Const(v) => {
                    let fits = matches!(
                        (v, socket.ty),
                        (
                            Value::Float(_),
                            SocketType::Float | SocketType::Vector | SocketType::Color
                        ) | (Value::Vec2(_), SocketType::Vec2)
                            | (Value::Vec3(_), SocketType::Vector | SocketType::Color)
                    );
                    if !fits {
                        return fail(format!(
                            "the value {v:?} does not fit a {} input",
                            socket.ty.name()
                        ));
                    }
                    let finite = match v {
                        Value::Float(x) => x.is_finite(),
                        Value::Vec2(a) => a.iter().all(|x| x.is_finite()),
                        Value::Vec3(a) => a.iter().all(|x| x.is_finite()),
                    };
                    if !finite {
                        return fail("values must be finite".into());
                    }
                }
                Src::Implicit(_, from) => {
                    if from.converts_to(socket.ty).is_none() {
                        return fail(format!(
                            "a {} cannot feed a {} input",
                            from.name(),
                            socket.ty.name()
                        ));
                    }
                }
                Src::Default => {}
            }
        }
    }
    Ok(())
}

fn find_output(ctx: &Ctx, graph: &Graph, flat: &[FlatNode]) -> Result<usize, GraphError> {
    find_root(ctx, graph, flat, MATERIAL_OUTPUT)
}

/// The graph's node of kind `kind` (a material's or a world's output): the one `output`
/// names, or the only one at the top level.
fn find_root(ctx: &Ctx, graph: &Graph, flat: &[FlatNode], kind: &str) -> Result<usize, GraphError> {
    if let Some(id) = &graph.output {
        return match flat.iter().position(|n| &n.id == id) {
            Some(i) if flat[i].def.kind == kind => Ok(i),
            Some(_) => Err(ctx.err(Some(id), None, format!("the output must be a {kind} node"))),
            None => Err(ctx.err(None, None, format!("output node \"{id}\" does not exist"))),
        };
    }
    let outputs: Vec<usize> = (0..flat.len())
        .filter(|&i| flat[i].def.kind == kind && !flat[i].id.contains('/'))
        .collect();
    match outputs.as_slice() {
        [one] => Ok(*one),
        [] => Err(ctx.err(None, None, format!("the graph has no {kind} node"))),
        _ => Err(ctx.err(
            None,
            None,
            format!("several {kind} nodes: say which with `output: \"id\"`"),
        )),
    }
}

/// Compiles a world graph, the radiance its [`WORLD_OUTPUT`] node sees arrive from each
/// direction, into `fn <function>(sp: ShadingPoint) -> vec3<f32>`. The world's shading
/// point looks from the origin: its position and generated coordinates are the direction
/// (`render::world_bake` sets it up).
pub fn compile_world(
    graph: &Graph,
    function: &str,
    textures: &mut BTreeMap<String, u32>,
) -> Result<CompiledMaterial, GraphError> {
    let ctx = Ctx { material: "world" };
    let flat = Flattener::new(&ctx, graph).run()?;
    check_types(&ctx, &flat)?;
    let output = find_root(&ctx, graph, &flat, WORLD_OUTPUT)?;
    emit_function(
        &ctx,
        flat,
        (output, 0),
        (function, "vec3<f32>"),
        textures,
        Constants::Inline,
        |_, root| (root.to_owned(), MaterialTraits::default()),
    )
}

/// Depth-first search from the output; a node met again while still open closes a cycle.
fn reject_cycles(ctx: &Ctx, flat: &[FlatNode], output: usize) -> Result<(), GraphError> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        New,
        Open,
        Done,
    }
    let mut mark = vec![Mark::New; flat.len()];
    // Explicit stack: (node, next input to visit).
    let mut stack = vec![(output, 0usize)];
    mark[output] = Mark::Open;
    while let Some((node, next)) = stack.last_mut() {
        let node = *node;
        if *next >= flat[node].inputs.len() {
            mark[node] = Mark::Done;
            stack.pop();
            continue;
        }
        let i = *next;
        *next += 1;
        if let Src::Out(n, _) = flat[node].inputs[i] {
            match mark[n] {
                Mark::New => {
                    mark[n] = Mark::Open;
                    stack.push((n, 0));
                }
                Mark::Open => {
                    let start = stack.iter().position(|(s, _)| *s == n).unwrap_or(0);
                    let path: Vec<&str> = stack[start..]
                        .iter()
                        .map(|(s, _)| flat[*s].id.as_str())
                        .chain([flat[n].id.as_str()])
                        .collect();
                    return Err(ctx.err(
                        Some(&flat[n].id),
                        Some(flat[node].def.inputs[i].name),
                        format!("the graph has a cycle: {}", path.join(" ← ")),
                    ));
                }
                Mark::Done => {}
            }
        }
    }
    Ok(())
}

/// Nodes that reach `roots`, in topological order (inputs first).
fn topological(flat: &[FlatNode], roots: &[usize]) -> Vec<usize> {
    let mut order = Vec::new();
    let mut seen = vec![false; flat.len()];
    fn visit(flat: &[FlatNode], n: usize, seen: &mut [bool], order: &mut Vec<usize>) {
        if seen[n] {
            return;
        }
        seen[n] = true;
        for src in &flat[n].inputs {
            if let Src::Out(m, _) = src {
                visit(flat, *m, seen, order);
            }
        }
        order.push(n);
    }
    for &r in roots {
        visit(flat, r, &mut seen, &mut order);
    }
    order
}

// ------------------------------------------------------------ constant folding

/// The constant value of an input, if it has one.
fn constant(node: &FlatNode, input: usize) -> Option<Value> {
    match &node.inputs[input] {
        Src::Const(v) => Some(v.clone()),
        Src::Default => match &node.def.inputs[input].default {
            Default::Value(v) => Some(v.clone()),
            Default::Implicit(..) => None,
        },
        Src::Out(..) | Src::Implicit(..) => None,
    }
}

/// The node's parameters with the declaration's defaults.
fn params(node: &FlatNode) -> Params<'_> {
    Params::new(node.def, &node.params)
}

/// Replaces links from foldable nodes with their constant outputs, in topological order
/// so folds propagate.
fn fold_constants(flat: &mut [FlatNode], output: usize) {
    let order = topological(flat, &[output]);
    let mut folded: HashMap<usize, Vec<Value>> = HashMap::new();
    for n in order {
        // Substitute already-folded producers.
        for i in 0..flat[n].inputs.len() {
            if let Src::Out(m, o) = flat[n].inputs[i] {
                if let Some(values) = folded.get(&m) {
                    let v = values[o].clone();
                    // Keep the consumer's socket type: a colour output folds into a vec3.
                    flat[n].inputs[i] = Src::Const(convert_const(
                        &v,
                        output_type(flat, m, o),
                        flat[n].def.inputs[i].ty,
                    ));
                }
            }
        }
        let inputs: Option<Vec<Value>> = (0..flat[n].inputs.len())
            .map(|i| constant(&flat[n], i))
            .collect();
        if let Some(inputs) = inputs {
            if let Some(values) = flat[n].def.fold.and_then(|f| f(&inputs, params(&flat[n]))) {
                folded.insert(n, values);
            }
        }
    }
}

fn convert_const(v: &Value, from: SocketType, to: SocketType) -> Value {
    match from.converts_to(to) {
        Some(Conversion::Splat) => Value::Vec3([v.as_f32(); 3]),
        Some(Conversion::Luminance) => {
            let c = v.as_vec3();
            Value::Float(0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2])
        }
        Some(Conversion::Average) => Value::Float(v.as_f32()),
        _ => v.clone(),
    }
}

/// Common-subexpression elimination: nodes of the same type, parameters and inputs
/// compute the same values; later ones are redirected to the first.
fn merge_identical(flat: &mut [FlatNode], root: usize) {
    let order = topological(flat, &[root]);
    let mut first: HashMap<String, usize> = HashMap::new();
    let mut redirect: HashMap<usize, usize> = HashMap::new();
    for n in order {
        for src in flat[n].inputs.iter_mut() {
            if let Src::Out(m, _) = src {
                if let Some(&r) = redirect.get(m) {
                    *m = r;
                }
            }
        }
        if flat[n].def.outputs.is_empty() {
            continue;
        }
        let key = format!(
            "{}|{:?}|{:?}",
            flat[n].def.kind, flat[n].params, flat[n].inputs
        );
        match first.get(&key) {
            Some(&f) => {
                redirect.insert(n, f);
            }
            None => {
                first.insert(key, n);
            }
        }
    }
}

// ---------------------------------------------------------------------- traits

fn traits(flat: &[FlatNode], output: usize) -> MaterialTraits {
    let mut traits = surface_traits(flat, output);
    if let Src::Out(volume, _) = flat[output].inputs[1] {
        // The inside is entered and left: the surface keeps its front.
        traits.transmissive = true;
        traits.lobes |= crate::shader::lobes::VOLUME;
        // A volume without a surface: the boundary lets light through unchanged.
        traits.boundary_only = !matches!(flat[output].inputs[0], Src::Out(..));
        // Read after folding, so that constant arithmetic feeding it counts as constant
        // whether or not the code keeps its constants live.
        let mut folded = flat.to_vec();
        fold_constants(&mut folded, output);
        traits.volume = node_traits(&folded[volume]).volume;
        if traits.volume.is_none() {
            let mut ranges = Ranges::new(&folded);
            let sigma_t = ranges.output(volume, 0);
            let majorant = sigma_t.hi.into_iter().fold(0.0f32, f32::max);
            traits.volume_majorant = sigma_t.is_finite().then_some(majorant);
            traits.lobes |= crate::shader::lobes::HETEROGENEOUS;
        }
    }
    traits
}

/// A heterogeneous volume needs a bounded extinction (its majorant): a volume whose
/// extinction no bound is known for is refused, naming the node that makes it unbounded.
fn check_volume(ctx: &Ctx, flat: &[FlatNode], output: usize) -> Result<(), GraphError> {
    let Src::Out(volume, _) = flat[output].inputs[1] else {
        return Ok(());
    };
    let t = traits(flat, output);
    if t.volume.is_some() || t.volume_majorant.is_some() {
        return Ok(());
    }
    let mut folded = flat.to_vec();
    fold_constants(&mut folded, output);
    let mut ranges = Ranges::new(&folded);
    let culprit = ranges.unbounded_source(volume);
    let node = &folded[culprit];
    let message = if culprit == volume {
        "the volume's extinction has no upper bound (its density or colour is unbounded)".to_owned()
    } else {
        format!(
            "feeds a volume's density or colour, and no upper bound of its output is known \
             ({} node): a heterogeneous volume needs one for its majorant; pass the value \
             through a Clamp or a clamped Map Range node",
            node.def.label
        )
    };
    Err(ctx.err(Some(&node.id), None, message))
}

/// Bounds of node outputs by interval arithmetic ([`super::bounds`]), memoised.
struct Ranges<'a> {
    flat: &'a [FlatNode],
    memo: HashMap<usize, Vec<Bounds>>,
}

impl<'a> Ranges<'a> {
    fn new(flat: &'a [FlatNode]) -> Self {
        Self {
            flat,
            memo: HashMap::new(),
        }
    }

    /// The bounds of each input of `node`, in the input's type.
    fn inputs(&mut self, node: usize) -> Vec<Bounds> {
        let n = &self.flat[node];
        (0..n.inputs.len())
            .map(|i| match &n.inputs[i] {
                Src::Out(m, o) => {
                    let b = self.output(*m, *o);
                    let from = output_type(self.flat, *m, *o);
                    match from.converts_to(n.def.inputs[i].ty) {
                        Some(Conversion::Luminance) => b.luminance(),
                        Some(Conversion::Average) => b.average(),
                        _ => b,
                    }
                }
                // Shading-point values (coordinates, normals) are not bounded.
                Src::Implicit(..) => Bounds::UNBOUNDED,
                _ => constant(n, i).map_or(Bounds::UNBOUNDED, |v| Bounds::exact(&v)),
            })
            .collect()
    }

    fn output(&mut self, node: usize, output: usize) -> Bounds {
        if let Some(b) = self.memo.get(&node) {
            return b.get(output).copied().unwrap_or(Bounds::UNBOUNDED);
        }
        let n = &self.flat[node];
        let outputs = match n.def.range {
            Some(range) => {
                let inputs = self.inputs(node);
                range(&inputs, params(n))
            }
            None => Vec::new(),
        };
        let b = outputs.get(output).copied().unwrap_or(Bounds::UNBOUNDED);
        self.memo.insert(node, outputs);
        b
    }

    /// The node whose unbounded output makes `node`'s unbounded while its own inputs are
    /// bounded (or it declares no range): where a clamp would help.
    fn unbounded_source(&mut self, node: usize) -> usize {
        let inputs = self.flat[node].inputs.clone();
        for src in inputs {
            if let Src::Out(m, o) = src {
                if !self.output(m, o).is_finite() {
                    return self.unbounded_source(m);
                }
            }
        }
        node
    }
}

/// What a shader node declares of the material it makes.
fn node_traits(node: &FlatNode) -> MaterialTraits {
    // Only shader nodes feed the material output, and each declares its traits (a test
    // checks the library).
    let traits = node.def.traits.expect("a shader node declares its traits");
    let known = |name: &str| {
        // The traits read the inputs of their own declaration.
        let i = node
            .def
            .inputs
            .iter()
            .position(|s| s.name == name)
            .unwrap_or_else(|| panic!("{} has no input {name}", node.def.kind));
        constant(node, i)
    };
    traits(&known, params(node))
}

fn surface_traits(flat: &[FlatNode], output: usize) -> MaterialTraits {
    let surface = match &flat[output].inputs[0] {
        Src::Out(n, _) => *n,
        // The default surface: grey, opaque, not emissive.
        _ => {
            return MaterialTraits {
                lobes: super::principled_lobes(
                    Some(0.0),
                    Some(0.0),
                    Some(0.0),
                    Some(0.0),
                    Some(1.0),
                    Some(0.0),
                    false,
                ),
                ..MaterialTraits::default()
            };
        }
    };
    node_traits(&flat[surface])
}

// -------------------------------------------------------------------- emission

struct Emitter<'a> {
    flat: &'a [FlatNode],
    /// Names of helper functions start with the material function's name.
    prefix: &'a str,
    helpers: String,
    /// Helper functions already in `helpers` (a ramp inside a bump's height function may
    /// also be used directly).
    helper_names: BTreeSet<String>,
    calls: BTreeSet<String>,
    /// Texture index by image file, shared by a scene's materials.
    textures: &'a mut BTreeMap<String, u32>,
    /// Image files read, with the node reading each.
    images: BTreeMap<String, String>,
    /// With live constants: the first element of `material_params` this material uses,
    /// and the values of those it reads so far.
    live: Option<(u32, Vec<[f32; 4]>)>,
}

struct Body {
    statements: String,
    roots: Vec<String>,
}

fn literal(v: &Value, ty: SocketType) -> String {
    let f = |x: f32| {
        let s = format!("{x:?}");
        if s.contains('.') || s.contains('e') {
            s
        } else {
            format!("{s}.0")
        }
    };
    match (v, ty) {
        (Value::Float(x), SocketType::Float) => f(*x),
        (Value::Float(x), _) => format!("vec3<f32>({})", f(*x)),
        (Value::Vec2(a), _) => format!("vec2<f32>({}, {})", f(a[0]), f(a[1])),
        (Value::Vec3(a), SocketType::Float) => f((a[0] + a[1] + a[2]) / 3.0),
        (Value::Vec3(a), _) => format!("vec3<f32>({}, {}, {})", f(a[0]), f(a[1]), f(a[2])),
    }
}

fn convert(expr: String, from: SocketType, to: SocketType) -> String {
    match from.converts_to(to) {
        Some(Conversion::Splat) => format!("vec3<f32>({expr})"),
        Some(Conversion::Luminance) => format!("dot({expr}, vec3<f32>(0.2126, 0.7152, 0.0722))"),
        Some(Conversion::Average) => format!("dot({expr}, vec3<f32>(1.0 / 3.0))"),
        _ => expr,
    }
}

/// A constant of an input of type `ty` as an element of `material_params`: a float in x,
/// a vec2 in xy, a vector or colour in xyz.
fn packed_constant(v: &Value, ty: SocketType) -> [f32; 4] {
    match ty {
        SocketType::Float => [v.as_f32(), 0.0, 0.0, 0.0],
        SocketType::Vec2 => {
            let [x, y, _] = match v {
                Value::Float(x) => [*x; 3],
                _ => v.as_vec3(),
            };
            [x, y, 0.0, 0.0]
        }
        SocketType::Vector | SocketType::Color | SocketType::Bsdf | SocketType::Volume => {
            let [x, y, z] = v.as_vec3();
            [x, y, z, 0.0]
        }
    }
}

/// The components of a `vec4<f32>` that hold a value of type `ty` ([`packed_constant`]).
fn swizzle(ty: SocketType) -> &'static str {
    match ty {
        SocketType::Float => ".x",
        SocketType::Vec2 => ".xy",
        SocketType::Vector | SocketType::Color | SocketType::Bsdf | SocketType::Volume => ".xyz",
    }
}

/// A node's template with each `{name}` replaced by `value(name)`.
fn fill_template(template: &str, mut value: impl FnMut(&str) -> String) -> String {
    let mut code = String::new();
    let mut rest = template;
    while let Some(start) = rest.find('{') {
        code.push_str(&rest[..start]);
        // The library's templates close every brace (a test compiles every node).
        let end = rest[start..]
            .find('}')
            .map(|e| start + e)
            .expect("template brace");
        code.push_str(&value(&rest[start + 1..end]));
        rest = &rest[end + 1..];
    }
    code.push_str(rest);
    code
}

/// Identifiers called as functions in a template: `name(`.
fn called_functions(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let bytes = code.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i].is_ascii_alphabetic() || bytes[i] == b'_' {
            let start = i;
            while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                i += 1;
            }
            if i < bytes.len() && bytes[i] == b'(' {
                out.push(code[start..i].to_owned());
            }
        } else {
            i += 1;
        }
    }
    out
}

impl Emitter<'_> {
    /// Statements computing `roots` (node, output) and their expressions.
    fn function_body(&mut self, roots: &[(usize, usize)]) -> Result<Body, GraphError> {
        let root_nodes: Vec<usize> = roots.iter().map(|r| r.0).collect();
        let order = topological(self.flat, &root_nodes);
        let mut statements = String::new();
        for &n in &order {
            let node = &self.flat[n];
            let _ = writeln!(statements, "    // {} ({})", node.id, node.def.kind);
            let code = self.node_code(n)?;
            let _ = writeln!(statements, "    let n{n} = {code};");
        }
        let roots = roots.iter().map(|&(n, o)| self.output_expr(n, o)).collect();
        Ok(Body { statements, roots })
    }

    fn output_expr(&self, n: usize, o: usize) -> String {
        // An output node (a material's or a world's) is its template's value.
        if self.flat[n].def.outputs.is_empty() {
            return format!("n{n}");
        }
        format!("n{n}{}", self.flat[n].def.outputs[o].field)
    }

    /// A constant of an input of type `ty`: a literal, or with live constants a read of
    /// the next element of `material_params`, whose value is recorded.
    fn constant_expr(&mut self, v: &Value, ty: SocketType) -> String {
        let Some((base, values)) = self.live.as_mut() else {
            return literal(v, ty);
        };
        let index = *base + values.len() as u32;
        values.push(packed_constant(v, ty));
        format!("material_params[{index}u]{}", swizzle(ty))
    }

    /// The WGSL expression of input `i` of node `n`, in the input's type.
    fn input_expr(&mut self, n: usize, i: usize) -> String {
        let node = &self.flat[n];
        let socket = &node.def.inputs[i];
        match &node.inputs[i] {
            Src::Const(v) => self.constant_expr(v, socket.ty),
            Src::Out(m, o) => convert(
                self.output_expr(*m, *o),
                output_type(self.flat, *m, *o),
                socket.ty,
            ),
            Src::Implicit(expr, from) => {
                self.calls.extend(called_functions(expr));
                convert((*expr).to_owned(), *from, socket.ty)
            }
            Src::Default => match &socket.default {
                Default::Value(v) => self.constant_expr(v, socket.ty),
                Default::Implicit(expr, _) => {
                    self.calls.extend(called_functions(expr));
                    (*expr).to_owned()
                }
            },
        }
    }

    fn param_expr(&mut self, n: usize, name: &str) -> Option<String> {
        let node = &self.flat[n];
        let def = node.def.param(name)?;
        Some(match &def.kind {
            ParamKind::Enum(_) => format!("{}u", params(node).choice(name)),
            ParamKind::Bool(_) => params(node).flag(name).to_string(),
            ParamKind::Ramp => return None,
            ParamKind::File => {
                let file = match node.params.get(name) {
                    Some(Param::Text(f)) => f.clone(),
                    _ => String::new(),
                };
                self.images.insert(file.clone(), node.id.clone());
                let next = self.textures.len() as u32;
                format!("{}u", *self.textures.entry(file).or_insert(next))
            }
        })
    }

    fn node_code(&mut self, n: usize) -> Result<String, GraphError> {
        let node = &self.flat[n];
        match node.def.code {
            Code::Template(t) => {
                let def = node.def;
                let code = fill_template(t, |name| {
                    match def.inputs.iter().position(|s| s.name == name) {
                        Some(i) => self.input_expr(n, i),
                        None => self
                            .param_expr(n, name)
                            .unwrap_or_else(|| panic!("template of {} names {name}", def.kind)),
                    }
                });
                self.calls.extend(called_functions(t));
                Ok(code)
            }
            Code::Generated(generate) => generate(&mut NodeEmitter { emitter: self, n }),
        }
    }

    /// The index of input `name` of node `n`.
    fn input_index(&self, n: usize, name: &str) -> usize {
        let def = self.flat[n].def;
        // Generated code names the inputs of its own declaration; a name it lacks is a bug
        // in the library, caught by the test that compiles every node.
        def.inputs
            .iter()
            .position(|s| s.name == name)
            .unwrap_or_else(|| panic!("{} has no input {name}", def.kind))
    }
}

/// What a [`Code::Generated`] node sees of the emitter: its own inputs, parameters and
/// helper functions.
struct NodeEmitter<'e, 'a> {
    emitter: &'e mut Emitter<'a>,
    n: usize,
}

impl Emit for NodeEmitter<'_, '_> {
    fn input(&mut self, name: &str) -> String {
        let i = self.emitter.input_index(self.n, name);
        self.emitter.input_expr(self.n, i)
    }

    fn param(&mut self, name: &str) -> String {
        let n = self.n;
        // Generated code names the parameters of its own declaration.
        (self.emitter.param_expr(n, name))
            .unwrap_or_else(|| panic!("{} has no parameter {name}", self.emitter.flat[n].def.kind))
    }

    /// The stops become a helper function of the factor: a chain of comparisons, each
    /// mixing two stops with `nd_ramp_mix`.
    fn ramp(&mut self, param: &str, t: &str, mode: &str) -> String {
        let mut stops: Vec<RampStop> = match self.emitter.flat[self.n].params.get(param) {
            Some(Param::Ramp(s)) => s.clone(),
            _ => nodes::default_ramp_stops(),
        };
        stops.sort_by(|a, b| a.position.total_cmp(&b.position));
        let name = self.helper_name(param);
        let c = |s: &RampStop| {
            format!(
                "vec4<f32>({:?}, {:?}, {:?}, {:?})",
                s.color[0], s.color[1], s.color[2], s.color[3]
            )
        };
        let mut f = format!("fn {name}(t: f32) -> vec4<f32> {{\n");
        let _ = writeln!(
            f,
            "    if (!(t > {:?})) {{ return {}; }}",
            stops[0].position,
            c(&stops[0])
        );
        for w in stops.windows(2) {
            let _ = writeln!(
                f,
                "    if (t <= {:?}) {{ return nd_ramp_mix({}, {}, {:?}, {:?}, t, {mode}); }}",
                w[1].position,
                c(&w[0]),
                c(&w[1]),
                w[0].position,
                w[1].position
            );
        }
        // The compiler refuses an empty stop list (check_param), and the default has two.
        let _ = writeln!(f, "    return {};\n}}\n", c(stops.last().expect("stops")));
        self.add_helper(&name, f);
        format!("{name}({t})")
    }

    fn helper_name(&self, what: &str) -> String {
        format!("{}_{what}{}", self.emitter.prefix, self.n)
    }

    fn add_helper(&mut self, name: &str, code: String) {
        if self.emitter.helper_names.insert(name.to_owned()) {
            self.emitter.helpers.push_str(&code);
        }
    }

    fn call(&mut self, functions: &[&str]) {
        self.emitter
            .calls
            .extend(functions.iter().map(|f| (*f).to_owned()));
    }

    fn input_function(&mut self, name: &str) -> Result<Option<String>, GraphError> {
        let (n, i) = (self.n, self.emitter.input_index(self.n, name));
        let Src::Out(m, o) = self.emitter.flat[n].inputs[i] else {
            return Ok(None);
        };
        let function = self.helper_name(name);
        if !self.emitter.helper_names.contains(&function) {
            // The subgraph's own helpers (a ramp inside a bump's height) come first.
            let body = self.emitter.function_body(&[(m, o)])?;
            let ty = self.emitter.flat[n].def.inputs[i].ty;
            let value = convert(
                body.roots[0].clone(),
                output_type(self.emitter.flat, m, o),
                ty,
            );
            let _ = write!(
                self.emitter.helpers,
                "fn {function}(sp: ShadingPoint) -> {} {{\n{}    return {value};\n}}\n\n",
                ty.wgsl(),
                body.statements
            );
            self.emitter.helper_names.insert(function.clone());
        }
        Ok(Some(function))
    }
}

/// Links used for tests and tools: a node's output as `node.socket`.
pub fn link(node: &str, socket: &str) -> Input {
    Input::Link(Link::new(node, socket))
}

// The tests name library nodes, which this file does not (a test checks): they live in
// `compile/tests.rs`.
mod program;
#[cfg(test)]
mod tests;

pub use program::{
    INTERPRETER_REGISTERS, Interpreter, Program, ProgramError, compile_program, interpreter,
};
