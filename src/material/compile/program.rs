//! Materials as programs for an interpreter: the editor's kernel evaluates every graph
//! with one fixed WGSL function that reads the graph from the `material_params` buffer, as
//! Cycles' SVM does, so that no graph edit needs a new kernel — a topology edit (a node
//! added, a wire moved) becomes a buffer write, like a value edit. Final renders keep the
//! compiled, folded WGSL ([`super::compile_with`]), which runs faster.
//!
//! A program is a list of instructions in the order the compiler's passes put the nodes
//! (flattened, checked, topological), each `[op, output registers…, input words…,
//! parameter words…]`, where `op` is the node type's index in the library and an input
//! word says where the value is: a register (an earlier node's output, with the implicit
//! conversion to the input's type), a constant of the material, or a property of the
//! shading point. The program ends with a return; then come the subroutines of bump nodes
//! (their heights, evaluated at displaced points). Words are integers stored as `f32`
//! (exact below 2²⁴), four to an element of `material_params`; constants follow them,
//! one element each.
//!
//! What the interpreter cannot run — more values alive than its registers, a bump inside
//! a bump's height — is a [`ProgramError::Unsupported`]: the caller compiles WGSL instead.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fmt::Write as _;
use std::sync::OnceLock;

use super::{
    Ctx, Flattener, GraphError, MaterialTraits, Src, check_types, check_volume, fill_template,
    find_output, output_type, packed_constant, params, reject_cycles, swizzle, traits,
};
use crate::material::graph::{Conversion, Graph, Param, RampStop, SocketType};
use crate::material::nodes::{
    self, BUMP, Code, Default, Emit, MATERIAL_OUTPUT, NodeDef, ParamKind,
};

/// Registers of the interpreter (`vec4<f32>` each): the most node outputs a program keeps.
/// The last is where unread outputs go.
pub const INTERPRETER_REGISTERS: usize = 64;
const SINK: u32 = INTERPRETER_REGISTERS as u32 - 1;

/// Instructions beyond the node types (whose op is their index in the library).
const OP_RETURN: u32 = 1000;
const OP_SUBROUTINE_END: u32 = 1001;

/// Where an input word's value is (bits 18 and up).
const FROM_REGISTER: u32 = 0;
const FROM_CONSTANT: u32 = 1;
const FROM_SHADING_POINT: u32 = 2;

/// An input word: where the value is, the conversion to the input's type (bits 16–17, as
/// `nd_arg` numbers them) and the register, constant or shading-point property (bits
/// 0–15).
fn input_word(from: u32, conversion: Option<Conversion>, index: usize) -> u32 {
    let conversion = match conversion {
        None | Some(Conversion::None) => 0,
        Some(Conversion::Splat) => 1,
        Some(Conversion::Luminance) => 2,
        Some(Conversion::Average) => 3,
    };
    debug_assert!(index < 1 << 16);
    index as u32 | conversion << 16 | from << 18
}

/// Why a graph has no program.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ProgramError {
    /// The graph does not compile at all.
    #[error(transparent)]
    Graph(#[from] GraphError),
    /// The graph compiles, but the interpreter cannot run it.
    #[error("the editor's interpreter cannot run material \"{material}\": {reason}")]
    Unsupported { material: String, reason: String },
}

/// A material compiled for the interpreter.
#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    /// The instructions; addresses in them are relative to the first word.
    pub words: Vec<u32>,
    /// The constants the instructions read, by index.
    pub constants: Vec<[f32; 4]>,
    pub traits: MaterialTraits,
    /// Image files the material reads, with the node that reads each.
    pub images: BTreeMap<String, String>,
}

/// Compiles `graph` into a program, with the scene's texture indices by file (files not
/// yet in `textures` get the next free index). Errors are those of
/// [`compile_with`](super::compile_with), or what the interpreter cannot run.
pub fn compile_program(
    material: &str,
    graph: &Graph,
    textures: &mut BTreeMap<String, u32>,
) -> Result<Program, ProgramError> {
    let ctx = Ctx { material };
    let flat = Flattener::new(&ctx, graph).run()?;
    check_types(&ctx, &flat)?;
    let output = find_output(&ctx, graph, &flat)?;
    reject_cycles(&ctx, &flat, output)?;
    check_volume(&ctx, &flat, output)?;
    let mut writer = Writer {
        material,
        flat: &flat,
        words: Vec::new(),
        constants: Vec::new(),
        registers: 0,
        textures,
        images: BTreeMap::new(),
        subroutines: Vec::new(),
    };
    let main = order(&flat, output);
    let mut registers = writer.allocate(&main, None)?;
    for &n in main.iter().filter(|&&n| n != output) {
        writer.instruction(n, &registers, false)?;
    }
    let surface = matches!(flat[output].inputs[0], Src::Out(..));
    writer.words.extend([OP_RETURN, u32::from(surface)]);
    // Each bump's height, as a subroutine (nested ones were refused above).
    let jobs = std::mem::take(&mut writer.subroutines);
    for (patch, (m, o)) in jobs {
        writer.words[patch] = writer.words.len() as u32;
        let nodes = order(&flat, m);
        registers = writer.allocate(&nodes, Some((m, o)))?;
        for &n in &nodes {
            writer.instruction(n, &registers, true)?;
        }
        let from = output_type(&flat, m, o);
        let height = input_word(
            FROM_REGISTER,
            from.converts_to(SocketType::Float),
            registers[&(m, o)] as usize,
        );
        writer.words.extend([OP_SUBROUTINE_END, height]);
    }
    Ok(Program {
        words: writer.words,
        constants: writer.constants,
        traits: traits(&flat, output),
        images: writer.images,
    })
}

/// The outputs node `n` reads from registers: its linked inputs but a bump's height (a
/// subroutine's) and a shader (the surface, not held in a register).
fn register_reads(flat: &[super::FlatNode], n: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
    let def = flat[n].def;
    (flat[n].inputs.iter().enumerate()).filter_map(move |(i, src)| match *src {
        Src::Out(m, o)
            if !(output_type(flat, m, o).is_shader()
                || def.kind == BUMP && def.inputs[i].name == "height") =>
        {
            Some((m, o))
        }
        _ => None,
    })
}

/// The nodes computing `root`, inputs first; a bump's height is not among its inputs (it
/// is a subroutine of its own).
fn order(flat: &[super::FlatNode], root: usize) -> Vec<usize> {
    fn visit(flat: &[super::FlatNode], n: usize, seen: &mut [bool], order: &mut Vec<usize>) {
        if std::mem::replace(&mut seen[n], true) {
            return;
        }
        for (i, src) in flat[n].inputs.iter().enumerate() {
            if let Src::Out(m, _) = src {
                if !(flat[n].def.kind == BUMP && flat[n].def.inputs[i].name == "height") {
                    visit(flat, *m, seen, order);
                }
            }
        }
        order.push(n);
    }
    let mut order = Vec::new();
    visit(flat, root, &mut vec![false; flat.len()], &mut order);
    order
}

struct Writer<'a> {
    material: &'a str,
    flat: &'a [super::FlatNode],
    words: Vec<u32>,
    constants: Vec<[f32; 4]>,
    /// Registers used by the ranges written so far.
    registers: u32,
    textures: &'a mut BTreeMap<String, u32>,
    images: BTreeMap<String, String>,
    /// Bumps whose height is a subroutine: the word to patch with its address, and the
    /// height's (node, output).
    subroutines: Vec<(usize, (usize, usize))>,
}

impl Writer<'_> {
    fn unsupported(&self, reason: String) -> ProgramError {
        ProgramError::Unsupported {
            material: self.material.to_owned(),
            reason,
        }
    }

    /// A register for every output of `nodes` (in execution order) that an input among
    /// them (or `result`, read after the last) reads; the others go to the sink. A
    /// register is reused once its value's last reader has read it: an instruction reads
    /// all its inputs before it writes an output, so its outputs may take its inputs'
    /// registers. Ranges of the program get registers above those of the ranges before
    /// (a subroutine must not overwrite what the main program still holds).
    fn allocate(
        &mut self,
        nodes: &[usize],
        result: Option<(usize, usize)>,
    ) -> Result<HashMap<(usize, usize), u32>, ProgramError> {
        let flat = self.flat;
        let reads = |n: usize| register_reads(flat, n);
        let mut last_read: HashMap<(usize, usize), usize> = HashMap::new();
        for (at, &n) in nodes.iter().enumerate() {
            for value in reads(n) {
                last_read.insert(value, at);
            }
        }
        if let Some(value) = result {
            last_read.insert(value, nodes.len());
        }
        let mut registers = HashMap::new();
        let mut free: Vec<u32> = Vec::new();
        let mut next = self.registers;
        for (at, &n) in nodes.iter().enumerate() {
            let dying: BTreeSet<u32> = reads(n)
                .filter(|value| last_read[value] == at)
                .map(|value| registers[&value])
                .collect();
            free.extend(dying.into_iter().rev());
            for o in 0..self.flat[n].def.outputs.len() {
                if last_read.contains_key(&(n, o)) {
                    let register = free.pop().unwrap_or_else(|| {
                        next += 1;
                        next - 1
                    });
                    registers.insert((n, o), register);
                }
            }
        }
        if next > SINK {
            return Err(self.unsupported(format!(
                "it keeps more than {} values at once",
                INTERPRETER_REGISTERS - 1
            )));
        }
        self.registers = next;
        Ok(registers)
    }

    fn constant(&mut self, value: [f32; 4]) -> usize {
        self.constants.push(value);
        self.constants.len() - 1
    }

    /// Writes node `n`'s instruction ([`layout`]).
    fn instruction(
        &mut self,
        n: usize,
        registers: &HashMap<(usize, usize), u32>,
        in_subroutine: bool,
    ) -> Result<(), ProgramError> {
        let node = &self.flat[n];
        let def = node.def;
        let op = nodes::library()
            .iter()
            .position(|d| d.kind == def.kind)
            .expect("a flattened node's type is in the library");
        self.words.push(op as u32);
        for (o, out) in def.outputs.iter().enumerate() {
            if !out.ty.is_shader() {
                self.words
                    .push(registers.get(&(n, o)).copied().unwrap_or(SINK));
            }
        }
        let mut height = None;
        for (i, socket) in def.inputs.iter().enumerate() {
            let word = match &node.inputs[i] {
                Src::Out(m, o) if def.kind == BUMP && socket.name == "height" => {
                    if in_subroutine {
                        return Err(self.unsupported(format!(
                            "bump node \"{}\" is inside the height of another bump",
                            node.id
                        )));
                    }
                    height = Some((*m, *o));
                    0
                }
                Src::Out(m, o) => {
                    let from = output_type(self.flat, *m, *o);
                    let register = registers[&(*m, *o)];
                    input_word(
                        FROM_REGISTER,
                        from.converts_to(socket.ty),
                        register as usize,
                    )
                }
                Src::Const(v) => {
                    let c = self.constant(packed_constant(v, socket.ty));
                    input_word(FROM_CONSTANT, None, c)
                }
                Src::Implicit(expr, from) => {
                    let id = self.shading_point(expr)?;
                    input_word(FROM_SHADING_POINT, from.converts_to(socket.ty), id)
                }
                Src::Default => match &socket.default {
                    Default::Value(v) => {
                        let c = self.constant(packed_constant(v, socket.ty));
                        input_word(FROM_CONSTANT, None, c)
                    }
                    Default::Implicit(expr, _) => {
                        input_word(FROM_SHADING_POINT, None, self.shading_point(expr)?)
                    }
                },
            };
            self.words.push(word);
        }
        let values = params(node);
        for p in &def.params {
            match &p.kind {
                ParamKind::Enum(_) => self.words.push(values.choice(p.name) as u32),
                ParamKind::Bool(_) => self.words.push(u32::from(values.flag(p.name))),
                ParamKind::File => {
                    let file = match node.params.get(p.name) {
                        Some(Param::Text(f)) => f.clone(),
                        _ => String::new(),
                    };
                    self.images.insert(file.clone(), node.id.clone());
                    let next = self.textures.len() as u32;
                    self.words.push(*self.textures.entry(file).or_insert(next));
                }
                ParamKind::Ramp => {
                    let mut stops: Vec<RampStop> = match values.get(p.name) {
                        Some(Param::Ramp(s)) => s.clone(),
                        _ => nodes::default_ramp_stops(),
                    };
                    stops.sort_by(|a, b| a.position.total_cmp(&b.position));
                    let first = self.constants.len();
                    for stop in &stops {
                        self.constants.push(stop.color);
                        self.constants.push([stop.position, 0.0, 0.0, 0.0]);
                    }
                    self.words.extend([first as u32, stops.len() as u32]);
                }
            }
        }
        if def.kind == BUMP {
            // The subroutine's address, once it is written (0: the height is constant).
            if let Some(h) = height {
                self.subroutines.push((self.words.len(), h));
            }
            self.words.push(0);
        }
        Ok(())
    }

    /// The interpreter's number for a shading-point property (`nd_implicit`).
    fn shading_point(&self, expr: &str) -> Result<usize, ProgramError> {
        // Both interpreters read the same properties.
        let table = &interpreter(false).shading_points;
        table
            .iter()
            .position(|e| *e == expr)
            .ok_or_else(|| self.unsupported(format!("the interpreter does not read \"{expr}\"")))
    }
}

/// The interpreter: WGSL that defines `nd_interpret(start, constants, sp) ->
/// MaterialEval`, the same for every graph.
#[derive(Debug)]
pub struct Interpreter {
    pub code: String,
    /// Node-library functions `code` calls.
    pub calls: BTreeSet<String>,
    /// The shading-point properties unconnected inputs read, numbered as `nd_implicit`.
    shading_points: Vec<&'static str>,
}

/// The interpreter, generated once from the node library: with image textures, for a
/// kernel that binds them, or without (the image-texture node does nothing then, and no
/// program of such a scene uses it).
pub fn interpreter(textures: bool) -> &'static Interpreter {
    static WITH: OnceLock<Interpreter> = OnceLock::new();
    static WITHOUT: OnceLock<Interpreter> = OnceLock::new();
    if textures {
        WITH.get_or_init(|| generate(true))
    } else {
        WITHOUT.get_or_init(|| generate(false))
    }
}

/// Where the words of a node type's instruction are, relative to its op.
struct Layout {
    outputs: Vec<Option<usize>>,
    inputs: Vec<usize>,
    params: Vec<usize>,
    len: usize,
}

fn layout(def: &NodeDef) -> Layout {
    let mut next = 1;
    let mut take = |n: usize| {
        let at = next;
        next += n;
        at
    };
    let outputs = (def.outputs.iter())
        .map(|o| (!o.ty.is_shader()).then(|| take(1)))
        .collect();
    let inputs = def.inputs.iter().map(|_| take(1)).collect();
    let params = (def.params.iter())
        .map(|p| {
            take(if matches!(p.kind, ParamKind::Ramp) {
                2
            } else {
                1
            })
        })
        .collect();
    // A bump's subroutine address.
    let len = next + usize::from(def.kind == BUMP);
    Layout {
        outputs,
        inputs,
        params,
        len,
    }
}

/// What a node type's code sees when it is generated for the interpreter: its inputs and
/// parameters read from the instruction at `pc`.
struct KindEmitter<'a> {
    def: &'static NodeDef,
    layout: &'a Layout,
    calls: &'a mut BTreeSet<String>,
    helpers: &'a mut String,
    helper_names: &'a mut BTreeSet<String>,
}

impl KindEmitter<'_> {
    fn input_expr(&self, i: usize) -> String {
        format!(
            "nd_arg(nd_word(pc + {}u), constants, &registers, sp){}",
            self.layout.inputs[i],
            swizzle(self.def.inputs[i].ty)
        )
    }

    fn param_at(&self, name: &str) -> (usize, &'static ParamKind) {
        let i = (self.def.params.iter())
            .position(|p| p.name == name)
            .unwrap_or_else(|| panic!("{} has no parameter {name}", self.def.kind));
        (self.layout.params[i], &self.def.params[i].kind)
    }
}

impl Emit for KindEmitter<'_> {
    fn input(&mut self, name: &str) -> String {
        let i = (self.def.inputs.iter())
            .position(|s| s.name == name)
            .unwrap_or_else(|| panic!("{} has no input {name}", self.def.kind));
        self.input_expr(i)
    }

    fn param(&mut self, name: &str) -> String {
        match self.param_at(name) {
            (at, ParamKind::Bool(_)) => format!("(nd_word(pc + {at}u) != 0u)"),
            (at, _) => format!("nd_word(pc + {at}u)"),
        }
    }

    fn ramp(&mut self, param: &str, t: &str, mode: &str) -> String {
        let (at, _) = self.param_at(param);
        self.calls.insert("nd_ramp_mix".into());
        format!(
            "nd_ramp_interpret(constants + nd_word(pc + {at}u), nd_word(pc + {}u), {t}, {mode})",
            at + 1
        )
    }

    fn helper_name(&self, what: &str) -> String {
        format!("nd_interpret_{}_{what}", self.def.kind)
    }

    fn add_helper(&mut self, name: &str, code: String) {
        if self.helper_names.insert(name.to_owned()) {
            self.helpers.push_str(&code);
        }
    }

    fn call(&mut self, functions: &[&str]) {
        self.calls.extend(functions.iter().map(|f| (*f).to_owned()));
    }

    fn input_function(&mut self, name: &str) -> Result<Option<String>, GraphError> {
        // Only the bump evaluates an input as a function, and the interpreter runs it as a
        // subroutine instead (`generate`).
        panic!("{}: input {name} as a function", self.def.kind)
    }
}

/// `vec4<f32>` holding a value of type `ty` written as `expr`.
fn pack(expr: &str, ty: SocketType) -> String {
    match ty {
        SocketType::Float => format!("vec4<f32>({expr}, 0.0, 0.0, 0.0)"),
        SocketType::Vec2 => format!("vec4<f32>({expr}, 0.0, 0.0)"),
        SocketType::Vector | SocketType::Color | SocketType::Bsdf | SocketType::Volume => {
            format!("vec4<f32>({expr}, 0.0)")
        }
    }
}

fn generate(textures: bool) -> Interpreter {
    let library = nodes::library();
    let mut calls: BTreeSet<String> = [
        "nd_default_surface",
        "nd_material_output",
        "nd_no_volume",
        "nd_ramp_mix",
        "nd_bump",
        "nd_bump_step",
        "nd_displaced",
        "frame_from_normal_tangent",
    ]
    .map(String::from)
    .into();
    let mut helpers = String::new();
    let mut helper_names = BTreeSet::new();
    // The shading-point properties inputs read unconnected (all vectors; the material
    // output's default surface is the return's).
    let mut shading_points: Vec<&'static str> = Vec::new();
    for socket in library.iter().flat_map(|d| &d.inputs) {
        if let Default::Implicit(expr, _) = socket.default {
            if !socket.ty.is_shader() && !shading_points.contains(&expr) {
                shading_points.push(expr);
                calls.extend(super::called_functions(expr));
            }
        }
    }

    let mut cases = String::new();
    for (op, def) in library.iter().enumerate() {
        let reads_images = def.params.iter().any(|p| matches!(p.kind, ParamKind::File));
        if def.kind == MATERIAL_OUTPUT || (reads_images && !textures) {
            continue;
        }
        let layout = layout(def);
        let _ = writeln!(cases, "            case {op}u: {{ // {}", def.kind);
        let mut emitter = KindEmitter {
            def,
            layout: &layout,
            calls: &mut calls,
            helpers: &mut helpers,
            helper_names: &mut helper_names,
        };
        if def.kind == BUMP {
            let _ = write!(cases, "{}", bump_case(&mut emitter, &layout));
            continue;
        }
        let code = match def.code {
            Code::Template(t) => {
                emitter.call(
                    &super::called_functions(t)
                        .iter()
                        .map(String::as_str)
                        .collect::<Vec<_>>(),
                );
                fill_template(t, |name| {
                    match def.inputs.iter().position(|s| s.name == name) {
                        Some(i) => emitter.input_expr(i),
                        None => emitter.param(name),
                    }
                })
            }
            Code::Generated(generate) => {
                generate(&mut emitter).expect("the library's generated code takes any graph")
            }
        };
        let _ = writeln!(cases, "                let r = {code};");
        for (out, at) in def.outputs.iter().zip(&layout.outputs) {
            match at {
                Some(at) => {
                    let value = format!("r{}", out.field);
                    let _ = writeln!(
                        cases,
                        "                registers[nd_word(pc + {at}u)] = {};",
                        pack(&value, out.ty)
                    );
                }
                None => {
                    let target = match out.ty {
                        SocketType::Volume => "volume",
                        _ => "surface",
                    };
                    let _ = writeln!(cases, "                {target} = r{};", out.field);
                }
            }
        }
        let _ = writeln!(
            cases,
            "                pc += {}u;\n            }}",
            layout.len
        );
    }

    let mut implicit = String::new();
    for (id, expr) in shading_points.iter().enumerate() {
        let _ = writeln!(
            implicit,
            "        case {id}u: {{ return {}; }}",
            pack(expr, SocketType::Vector)
        );
    }
    let code = format!(
        "{helpers}{}",
        INTERPRETER_WGSL
            .replace("REGISTERS", &INTERPRETER_REGISTERS.to_string())
            .replace("OP_RETURN", &OP_RETURN.to_string())
            .replace("OP_SUBROUTINE_END", &OP_SUBROUTINE_END.to_string())
            .replace("//IMPLICIT\n", &implicit)
            .replace("//CASES\n", &cases)
    );
    Interpreter {
        code,
        calls,
        shading_points,
    }
}

/// The bump's instruction: with a height subroutine, it runs it three times — at the point
/// and one step along each tangent — then computes the normal as `nd_bump` does in
/// compiled code (nodes::generate_bump).
fn bump_case(e: &mut KindEmitter, layout: &Layout) -> String {
    let normal = e.input("normal");
    let strength = e.input("strength");
    let distance = e.input("distance");
    // Its one parameter: whether the bump goes inward.
    let invert = e.param(e.def.params[0].name);
    let out = layout.outputs[0].expect("the bump's normal output");
    let (sub, len) = (layout.len - 1, layout.len);
    format!(
        "                let normal = {normal};
                let sub = nd_word(pc + {sub}u);
                let f = frame_from_normal_tangent(normal, sp0.dpdu, 0.0);
                if (sub == 0u) {{
                    registers[nd_word(pc + {out}u)] = vec4<f32>(normal, 0.0);
                    pc += {len}u;
                }} else if (phase < 3u) {{
                    if (phase == 1u) {{ sp = nd_displaced(sp0, f.t, nd_bump_step(sp0)); }}
                    if (phase == 2u) {{ sp = nd_displaced(sp0, f.b, nd_bump_step(sp0)); }}
                    caller = pc;
                    pc = start + sub;
                }} else {{
                    let bumped = nd_bump({strength}, {distance}, heights.x, heights.y, heights.z, nd_bump_step(sp0), normal, f, {invert});
                    registers[nd_word(pc + {out}u)] = vec4<f32>(bumped, 0.0);
                    phase = 0u;
                    pc += {len}u;
                }}
            }}
"
    )
}

/// The interpreter around the node types' cases.
const INTERPRETER_WGSL: &str = "// Program word i: an integer stored as f32, four to an element of material_params.
fn nd_word(i: u32) -> u32 {
    return u32(material_params[i >> 2u][i & 3u]);
}

// The shading-point properties unconnected inputs read.
fn nd_implicit(id: u32, sp: ShadingPoint) -> vec4<f32> {
    switch (id) {
//IMPLICIT
        default: { return vec4<f32>(0.0); }
    }
}

// An input's value: from a register, a constant or the shading point, converted to the
// input's type.
fn nd_arg(w: u32, constants: u32, registers: ptr<function, array<vec4<f32>, REGISTERS>>, sp: ShadingPoint) -> vec4<f32> {
    let index = w & 0xffffu;
    let source = w >> 18u;
    var v: vec4<f32>;
    if (source == 0u) {
        v = (*registers)[index];
    } else if (source == 1u) {
        v = material_params[constants + index];
    } else {
        v = nd_implicit(index, sp);
    }
    switch ((w >> 16u) & 3u) {
        case 1u: { v = vec4<f32>(v.xxx, 0.0); }
        case 2u: { v = vec4<f32>(dot(v.xyz, vec3<f32>(0.2126, 0.7152, 0.0722)), 0.0, 0.0, 0.0); }
        case 3u: { v = vec4<f32>(dot(v.xyz, vec3<f32>(1.0 / 3.0)), 0.0, 0.0, 0.0); }
        default: {}
    }
    return v;
}

// A colour ramp of `count` stops from constant `first` on (colour, then position), at t:
// what compiled code's chain of comparisons computes.
fn nd_ramp_interpret(first: u32, count: u32, t: f32, mode: u32) -> vec4<f32> {
    if (!(t > material_params[first + 1u].x)) {
        return material_params[first];
    }
    for (var i = 1u; i < count; i++) {
        let b = first + 2u * i;
        if (t <= material_params[b + 1u].x) {
            return nd_ramp_mix(material_params[b - 2u], material_params[b], material_params[b - 1u].x, material_params[b + 1u].x, t, mode);
        }
    }
    return material_params[first + 2u * (count - 1u)];
}

// Runs the program at word `start`, whose constants start at element `constants`.
fn nd_interpret(start: u32, constants: u32, sp0: ShadingPoint) -> MaterialEval {
    var registers: array<vec4<f32>, REGISTERS>;
    var surface: MaterialEval;
    var volume = nd_no_volume();
    var sp = sp0;
    var pc = start;
    // A bump's height subroutine: the bump's instruction, which height is being
    // computed (0 at the point, 1 and 2 one step along the tangents), the heights.
    var caller = 0u;
    var phase = 0u;
    var heights = vec3<f32>(0.0);
    for (var step = 0u; step < 65536u; step++) {
        switch (nd_word(pc)) {
//CASES
            case OP_RETURNu: {
                if (nd_word(pc + 1u) == 0u) {
                    surface = nd_default_surface(sp0);
                }
                return nd_material_output(surface, volume);
            }
            case OP_SUBROUTINE_ENDu: {
                heights[phase] = nd_arg(nd_word(pc + 1u), constants, &registers, sp).x;
                phase += 1u;
                sp = sp0;
                pc = caller;
            }
            default: {
                return nd_default_surface(sp0);
            }
        }
    }
    return nd_default_surface(sp0);
}
";
