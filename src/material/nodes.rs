//! The node library: every node type declared once, with its sockets, defaults,
//! parameters, documentation, the WGSL it compiles to and, where the CPU can compute it
//! exactly, its constant folding. `docs/NODES.md` is generated from these declarations
//! (`kiln material nodes`), and the compiler ([`super::compile`]) reads nothing else about
//! a node: it knows no node by name, only the structural [`MATERIAL_OUTPUT`] and
//! [`WORLD_OUTPUT`] and the
//! group kinds of [`super::graph`].
//!
//! Code is given as a template: `{name}` is replaced by the WGSL expression of the input
//! `name` (converted to the input's type), or by a parameter's value (an enum parameter
//! by its option's index, `3u`). A node with several outputs evaluates its template once
//! and reads each output as a field of the result (`.fac`, `.color`).
//! The functions the templates call live in `shaders/nodes/`.

use std::collections::BTreeMap;
use std::sync::OnceLock;

use super::bounds::{self, RangeFn};
use super::compile::{GraphError, MaterialTraits, VolumeCoefficients};
use super::graph::{Param, RampStop, SocketType, Value};
use crate::shader::principled::{self, ParamValue};

/// The node a material renders: the root of compilation, part of the graph model rather
/// than a node the library could do without.
pub const MATERIAL_OUTPUT: &str = "material_output";

/// The node a world graph renders: the radiance arriving from each direction
/// ([`super::compile::compile_world`]).
pub const WORLD_OUTPUT: &str = "world_output";

/// The bump node: the one node that evaluates an input (its height) as a function of the
/// shading point ([`Emit::input_function`]), so the editor's interpreter
/// (`compile::interpreter`) runs it as a subroutine instead of through its code.
pub const BUMP: &str = "bump";

/// What an unconnected input reads: a constant, or a property of the shading point.
#[derive(Clone, Debug)]
pub enum Default {
    Value(Value),
    /// A WGSL expression over the shading point `sp` (e.g. `sp.generated`).
    Implicit(&'static str, &'static str),
}

/// An input's declaration: name, type, what it reads unconnected, and for a float its
/// range.
#[derive(Clone, Debug)]
pub struct SocketDef {
    pub name: &'static str,
    pub ty: SocketType,
    pub default: Default,
    /// The values a float input takes (every float input declares one; a library test
    /// checks it holds the default); `None` for other types.
    pub range: Option<FloatRange>,
    pub doc: &'static str,
}

/// The values a float input takes, as Blender declares its sockets' `min`/`max` and
/// `soft_min`/`soft_max`.
///
/// - The hard range `[min, max]` bounds a value set on the input: the compiler rejects a
///   graph with one outside it, naming the node and socket (a loaded file is reported,
///   never silently changed), an edit setting one is refused, and the editor's field
///   clamps to it. What reaches the input through a link (computed, a group's default, a
///   muted node's pass-through) is not limited: every node takes any finite input, as
///   Blender's do (the Principled BSDF clamps what it is fed to its parameters' ranges).
/// - The soft range `[soft_min, soft_max]`, inside the hard one, is where dragging the
///   field stops (typing reaches the hard range) and what sets the drag's speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FloatRange {
    pub min: f32,
    pub max: f32,
    pub soft_min: f32,
    pub soft_max: f32,
}

impl FloatRange {
    /// `[min, max]`, with the soft range the same.
    pub const fn new(min: f32, max: f32) -> Self {
        Self {
            min,
            max,
            soft_min: min,
            soft_max: max,
        }
    }

    /// The range with soft range `[soft_min, soft_max]`.
    pub const fn soft(self, soft_min: f32, soft_max: f32) -> Self {
        Self {
            soft_min,
            soft_max,
            ..self
        }
    }

    /// Whether `x` lies in the hard range.
    pub fn contains(&self, x: f32) -> bool {
        self.min <= x && x <= self.max
    }

    /// The editor's drag speed, in value per point: the soft range over 400 points, at
    /// most 0.05 (a wide or unbounded range still moves by small steps).
    pub fn drag_speed(&self) -> f64 {
        (f64::from(self.soft_max) - f64::from(self.soft_min)).min(20.0) / 400.0
    }

    /// The hard range as the docs and messages write it: `[0, 1]`, `≥ 0`, `any`.
    pub fn describe(&self) -> String {
        match (self.min.is_finite(), self.max.is_finite()) {
            (true, true) => format!("[{}, {}]", self.min, self.max),
            (true, false) => format!("≥ {}", self.min),
            (false, true) => format!("≤ {}", self.max),
            (false, false) => "any".to_owned(),
        }
    }
}

/// Any finite number (Blender's math inputs).
pub const ANY: FloatRange = FloatRange::new(f32::NEG_INFINITY, f32::INFINITY);
/// A factor, an amount, a roughness: `[0, 1]`.
pub const UNIT: FloatRange = FloatRange::new(0.0, 1.0);
/// A texture's scale: at least 0 (a negative scale only mirrors), dragged up to 100.
pub const TEXTURE_SCALE: FloatRange = FloatRange::new(0.0, 1000.0).soft(0.0, 100.0);
/// Octaves of noise, `[0, 15]` as Blender's.
pub const DETAIL: FloatRange = FloatRange::new(0.0, 15.0);
/// Offsets and distortions, `[-1000, 1000]`, dragged within ±10.
pub const LARGE: FloatRange = FloatRange::new(-1000.0, 1000.0).soft(-10.0, 10.0);
/// An index of refraction: at least 1, dragged within [1, 3].
/// A volume's density: coefficients per scene unit.
pub const DENSITY: FloatRange = FloatRange::new(0.0, f32::INFINITY).soft(0.0, 100.0);
/// A phase function's mean cosine (|g| is kept below 0.999 where it is used).
pub const ANISOTROPY: FloatRange = FloatRange::new(-1.0, 1.0);
pub const IOR: FloatRange = FloatRange::new(1.0, 1000.0).soft(1.0, 3.0);

#[derive(Clone, Debug)]
pub struct OutputDef {
    pub name: &'static str,
    pub ty: SocketType,
    /// Field of the template's result this output reads (`.fac`), or "" for the result.
    pub field: &'static str,
    pub doc: &'static str,
}

#[derive(Clone, Debug)]
pub enum ParamKind {
    /// One of the options, by name; the first is the default.
    Enum(&'static [&'static str]),
    Bool(bool),
    /// Colour-ramp stops.
    Ramp,
    /// An image file, relative to the material file (the compiler turns it into the
    /// scene's texture index).
    File,
}

#[derive(Clone, Debug)]
pub struct ParamDef {
    pub name: &'static str,
    pub kind: ParamKind,
    pub doc: &'static str,
}

/// How a node becomes WGSL.
#[derive(Clone, Debug)]
pub enum Code {
    Template(&'static str),
    /// Generated by a function of the node, for code a template cannot say: the colour
    /// ramp (its stops become code), bump mapping (evaluates its height input at displaced
    /// points) and the principled BSDF (clamps every input to its range).
    Generated(Generate),
}

/// Writes a node's WGSL expression through what the compiler offers ([`Emit`]).
pub type Generate = fn(&mut dyn Emit) -> Result<String, GraphError>;

/// A node's outputs computed on the CPU from its constant inputs (one value per
/// declared input; a float may stand for a vector or colour) and its parameters; `None` where it cannot be
/// computed exactly as the WGSL does, and the node stays code.
pub type Fold = fn(&[Value], Params) -> Option<Vec<Value>>;

/// What a surface (BSDF) node lets the renderer know without running it, from the values
/// of its constant inputs (by name; `None` for an input that is not constant) and its
/// parameters.
pub type SurfaceTraits = fn(&dyn Fn(&str) -> Option<Value>, Params) -> MaterialTraits;

/// What the compiler offers a [`Generate`] function, for the node being emitted.
pub trait Emit {
    /// The WGSL expression of input `name`, in the input's type.
    fn input(&mut self, name: &str) -> String;
    /// The WGSL expression of parameter `name`: an enum's option index (`3u`), a flag
    /// (`true`), an image's texture index; compiled constants, or reads of the program
    /// where the material is interpreted.
    fn param(&mut self, name: &str) -> String;
    /// The WGSL expression of the colour ramp of parameter `param` (its stops) at `t`,
    /// interpolated by mode `mode` (an expression of `nd_ramp_mix`'s modes).
    fn ramp(&mut self, param: &str, t: &str, mode: &str) -> String;
    /// A helper function name unique to this node in the material: `<material>_<what><n>`.
    fn helper_name(&self, what: &str) -> String;
    /// Adds the helper function `code`, called `name`, unless the material has it already.
    fn add_helper(&mut self, name: &str, code: String);
    /// Node-library functions the generated code calls.
    fn call(&mut self, functions: &[&str]);
    /// For an input fed by a link: the name of a helper function
    /// `fn(sp: ShadingPoint) -> <input type>` that evaluates the input's subgraph at any
    /// shading point (added once per node); `None` for a constant input.
    fn input_function(&mut self, name: &str) -> Result<Option<String>, GraphError>;
}

/// A node's parameter values, read with the declaration's defaults.
#[derive(Clone, Copy, Debug)]
pub struct Params<'a> {
    def: &'a NodeDef,
    values: &'a BTreeMap<String, Param>,
}

impl<'a> Params<'a> {
    pub fn new(def: &'a NodeDef, values: &'a BTreeMap<String, Param>) -> Self {
        Self { def, values }
    }

    /// The value given, if any.
    pub fn get(&self, name: &str) -> Option<&'a Param> {
        self.values.get(name)
    }

    /// An enum parameter's option, by index; the first (the default) when not given.
    pub fn choice(&self, name: &str) -> usize {
        match (self.def.param(name).map(|p| &p.kind), self.values.get(name)) {
            (Some(ParamKind::Enum(options)), Some(Param::Text(t))) => {
                options.iter().position(|o| o == t).unwrap_or(0)
            }
            _ => 0,
        }
    }

    /// A boolean parameter, or its declared default.
    pub fn flag(&self, name: &str) -> bool {
        match (self.def.param(name).map(|p| &p.kind), self.values.get(name)) {
            (_, Some(Param::Bool(b))) => *b,
            (Some(ParamKind::Bool(default)), _) => *default,
            _ => false,
        }
    }
}

#[derive(Clone, Debug)]
pub struct NodeDef {
    pub kind: &'static str,
    pub label: &'static str,
    pub category: &'static str,
    pub doc: &'static str,
    pub inputs: Vec<SocketDef>,
    pub outputs: Vec<OutputDef>,
    pub params: Vec<ParamDef>,
    /// What a node with a BSDF output lets the renderer know of the material.
    pub traits: Option<SurfaceTraits>,
    /// Constant folding; nodes without stay code even when their inputs are constant.
    pub fold: Option<Fold>,
    /// How bounds of the inputs bound the outputs ([`super::bounds`]); nodes without are
    /// unbounded, which a heterogeneous volume's density may not depend on.
    pub range: Option<RangeFn>,
    pub code: Code,
}

impl NodeDef {
    pub fn input(&self, name: &str) -> Option<&SocketDef> {
        self.inputs.iter().find(|s| s.name == name)
    }

    pub fn output(&self, name: &str) -> Option<(usize, &OutputDef)> {
        self.outputs
            .iter()
            .enumerate()
            .find(|(_, s)| s.name == name)
    }

    pub fn param(&self, name: &str) -> Option<&ParamDef> {
        self.params.iter().find(|p| p.name == name)
    }

    /// The value input `name` of `node` (a node of this kind) takes: the value given, or
    /// the declared default when none is; `None` for a link, an implicit default (a
    /// property of the shading point) or no such input.
    pub fn constant_input(&self, node: &super::graph::Node, name: &str) -> Option<Value> {
        match node.inputs.get(name) {
            Some(super::graph::Input::Value(v)) => Some(v.clone()),
            Some(super::graph::Input::Link(_)) => None,
            None => match &self.input(name)?.default {
                Default::Value(v) => Some(v.clone()),
                Default::Implicit(..) => None,
            },
        }
    }
}

/// Every node type, in the order `docs/NODES.md` lists them.
pub fn library() -> &'static [NodeDef] {
    static LIBRARY: OnceLock<Vec<NodeDef>> = OnceLock::new();
    LIBRARY.get_or_init(build)
}

pub fn find(kind: &str) -> Option<&'static NodeDef> {
    library().iter().find(|d| d.kind == kind)
}

/// The node that passes a value of type `ty` on unchanged: its type, input and output (the
/// Value, RGB and Vector nodes); `None` for types none carries.
pub fn identity(ty: SocketType) -> Option<(&'static str, &'static str, &'static str)> {
    match ty {
        SocketType::Float => Some(("value", "value", "value")),
        SocketType::Color => Some(("rgb", "color", "color")),
        SocketType::Vector => Some(("vector", "vector", "vector")),
        SocketType::Vec2 | SocketType::Bsdf | SocketType::Volume => None,
    }
}

// Declaration helpers: sockets by type, with their defaults.
fn float(name: &'static str, v: f32, range: FloatRange, doc: &'static str) -> SocketDef {
    SocketDef {
        name,
        ty: SocketType::Float,
        default: Default::Value(Value::Float(v)),
        range: Some(range),
        doc,
    }
}

fn color(name: &'static str, v: [f32; 3], doc: &'static str) -> SocketDef {
    SocketDef {
        name,
        ty: SocketType::Color,
        default: Default::Value(Value::Vec3(v)),
        range: None,
        doc,
    }
}

fn vector(name: &'static str, v: [f32; 3], doc: &'static str) -> SocketDef {
    SocketDef {
        name,
        ty: SocketType::Vector,
        default: Default::Value(Value::Vec3(v)),
        range: None,
        doc,
    }
}

/// A vector input that reads a shading-point property when unconnected.
fn implicit(
    name: &'static str,
    expr: &'static str,
    what: &'static str,
    doc: &'static str,
) -> SocketDef {
    SocketDef {
        name,
        ty: SocketType::Vector,
        default: Default::Implicit(expr, what),
        range: None,
        doc,
    }
}

fn out(name: &'static str, ty: SocketType, field: &'static str, doc: &'static str) -> OutputDef {
    OutputDef {
        name,
        ty,
        field,
        doc,
    }
}

fn choice(name: &'static str, options: &'static [&'static str], doc: &'static str) -> ParamDef {
    ParamDef {
        name,
        kind: ParamKind::Enum(options),
        doc,
    }
}

/// Operations of the math node, in the order `node_math` (shaders/nodes/math.wgsl)
/// numbers them.
pub const MATH_OPERATIONS: &[&str] = &[
    "add",
    "subtract",
    "multiply",
    "divide",
    "multiply_add",
    "power",
    "logarithm",
    "sqrt",
    "inverse_sqrt",
    "absolute",
    "exponent",
    "minimum",
    "maximum",
    "less_than",
    "greater_than",
    "sign",
    "compare",
    "smooth_min",
    "smooth_max",
    "round",
    "floor",
    "ceil",
    "truncate",
    "fraction",
    "truncated_modulo",
    "floored_modulo",
    "wrap",
    "snap",
    "pingpong",
    "sine",
    "cosine",
    "tangent",
    "arcsine",
    "arccosine",
    "arctangent",
    "arctan2",
    "sinh",
    "cosh",
    "tanh",
    "radians",
    "degrees",
];

/// Operations of the vector math node, in `node_vector_math`'s order.
pub const VECTOR_MATH_OPERATIONS: &[&str] = &[
    "add",
    "subtract",
    "multiply",
    "divide",
    "multiply_add",
    "cross",
    "project",
    "reflect",
    "refract",
    "faceforward",
    "dot",
    "distance",
    "length",
    "scale",
    "normalize",
    "absolute",
    "minimum",
    "maximum",
    "floor",
    "ceil",
    "fraction",
    "modulo",
    "wrap",
    "snap",
    "sine",
    "cosine",
    "tangent",
];

/// Blend modes of the mix-colour node, in `node_mix_color`'s order.
pub const BLEND_MODES: &[&str] = &[
    "mix",
    "multiply",
    "screen",
    "overlay",
    "add",
    "subtract",
    "difference",
    "lighten",
    "darken",
    "divide",
    "dodge",
    "burn",
    "hue",
    "saturation",
    "value",
    "color",
    "soft_light",
    "linear_light",
    "exclusion",
];

const TEXTURE_VECTOR: &str = "texture coordinates; unconnected: the generated coordinates";

fn build() -> Vec<NodeDef> {
    use SocketType::*;
    let tex_out = || {
        vec![
            out("color", Color, ".color", "colour"),
            out("fac", Float, ".fac", "scalar value"),
        ]
    };
    vec![
        // ---------------------------------------------------------------- inputs
        NodeDef {
            kind: "texture_coordinate",
            label: "Texture Coordinate",
            category: "Input",
            doc: "Coordinates of the shading point for texturing.",
            inputs: vec![],
            outputs: vec![
                out(
                    "generated",
                    Vector,
                    ".generated",
                    "object-space position scaled to the mesh's bounding box, 0 to 1",
                ),
                out(
                    "normal",
                    Vector,
                    ".normal",
                    "shading normal in object space",
                ),
                out("uv", Vector, ".uv", "the mesh's UV coordinates (z = 0)"),
                out(
                    "uv1",
                    Vector,
                    ".uv1",
                    "the mesh's second UV set (z = 0; zero where it has none)",
                ),
                out("object", Vector, ".object", "object-space position"),
                out("world", Vector, ".world", "world-space position"),
                out(
                    "reflection",
                    Vector,
                    ".reflection",
                    "the view direction mirrored about the normal, world space",
                ),
            ],
            params: vec![],
            traits: None,
            fold: None,
            range: Some(bounds::texture_coordinate),
            code: Code::Template("nd_texture_coordinate(sp)"),
        },
        NodeDef {
            kind: "geometry",
            label: "Geometry",
            category: "Input",
            doc: "Geometric properties of the shading point, in world space.",
            inputs: vec![],
            outputs: vec![
                out("position", Vector, ".p", "position"),
                out("normal", Vector, ".n", "shading (interpolated) normal"),
                out(
                    "true_normal",
                    Vector,
                    ".ng",
                    "geometric normal of the triangle",
                ),
                out(
                    "tangent",
                    Vector,
                    ".tangent",
                    "unit tangent along the UV u direction (an arbitrary one without UVs)",
                ),
                out(
                    "incoming",
                    Vector,
                    ".wo",
                    "unit direction toward where the light goes (the viewer)",
                ),
                out(
                    "backfacing",
                    Float,
                    ".backfacing",
                    "1 on the back side of the surface",
                ),
            ],
            params: vec![],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template("nd_geometry(sp)"),
        },
        NodeDef {
            kind: "vertex_color",
            label: "Color Attribute",
            category: "Input",
            doc: "The mesh's vertex colour (glTF COLOR_0, 8 bits per channel), interpolated; white where the mesh has none.",
            inputs: vec![],
            outputs: vec![
                out("color", Color, ".rgb", "colour"),
                out("alpha", Float, ".a", "alpha"),
            ],
            params: vec![],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template("sp.vertex_color"),
        },
        NodeDef {
            kind: "object_info",
            label: "Object Info",
            category: "Input",
            doc: "Properties of the instance the shading point belongs to.",
            inputs: vec![],
            outputs: vec![
                out(
                    "random",
                    Float,
                    ".random",
                    "a random number in [0, 1) per instance",
                ),
                out(
                    "location",
                    Vector,
                    ".location",
                    "the instance's origin in world space",
                ),
            ],
            params: vec![],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template("nd_object_info(sp)"),
        },
        NodeDef {
            kind: "fresnel",
            label: "Fresnel",
            category: "Input",
            doc: "Dielectric Fresnel reflectance toward the viewer.",
            inputs: vec![
                float("ior", 1.5, IOR, "index of refraction"),
                implicit("normal", "sp.n", "the shading normal", "normal"),
            ],
            outputs: vec![out("fac", Float, "", "reflectance")],
            params: vec![],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template("nd_fresnel({ior}, {normal}, sp)"),
        },
        NodeDef {
            kind: "layer_weight",
            label: "Layer Weight",
            category: "Input",
            doc: "Blending weights for layering, from the view angle.",
            inputs: vec![
                float("blend", 0.5, UNIT, "bias toward the edge"),
                implicit("normal", "sp.n", "the shading normal", "normal"),
            ],
            outputs: vec![
                out(
                    "fresnel",
                    Float,
                    ".x",
                    "Fresnel reflectance for IOR 1 / (1 - blend)",
                ),
                out("facing", Float, ".y", "1 - |cos θ| biased by blend"),
            ],
            params: vec![],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template("nd_layer_weight({blend}, {normal}, sp)"),
        },
        NodeDef {
            kind: "value",
            label: "Value",
            category: "Input",
            doc: "A constant number.",
            inputs: vec![float("value", 0.5, ANY, "the number")],
            outputs: vec![out("value", Float, "", "the number")],
            params: vec![],
            traits: None,
            fold: Some(fold_value),
            range: Some(bounds::identity),
            code: Code::Template("{value}"),
        },
        NodeDef {
            kind: "rgb",
            label: "RGB",
            category: "Input",
            doc: "A constant colour (linear RGB).",
            inputs: vec![color("color", [0.5, 0.5, 0.5], "the colour")],
            outputs: vec![out("color", Color, "", "the colour")],
            params: vec![],
            traits: None,
            fold: Some(fold_vec3),
            range: Some(bounds::identity),
            code: Code::Template("{color}"),
        },
        NodeDef {
            kind: "vector",
            label: "Vector",
            category: "Input",
            doc: "A constant vector.",
            inputs: vec![vector("vector", [0.0; 3], "the vector")],
            outputs: vec![out("vector", Vector, "", "the vector")],
            params: vec![],
            traits: None,
            fold: Some(fold_vec3),
            range: Some(bounds::identity),
            code: Code::Template("{vector}"),
        },
        // -------------------------------------------------------------- textures
        NodeDef {
            kind: "image_texture",
            label: "Image Texture",
            category: "Texture",
            doc: "An image file (PNG, JPEG, EXR, HDR, …) looked up by UV, filtered bilinearly or by nearest texel. Transform the UVs with a Mapping node (texture type).",
            inputs: vec![implicit(
                "vector",
                "vec3<f32>(sp.uv, 0.0)",
                "the mesh's UVs",
                "texture coordinates (x, y used)",
            )],
            outputs: vec![
                out("color", Color, ".rgb", "colour, linear"),
                out("alpha", Float, ".a", "alpha (1 for images without)"),
            ],
            params: vec![
                ParamDef {
                    name: "file",
                    kind: ParamKind::File,
                    doc: "the image, relative to the material (or scene) file",
                },
                choice(
                    "color_space",
                    &["srgb", "linear"],
                    "srgb decodes 8-bit colour to linear; linear for data (normal, roughness maps) and float images",
                ),
                choice(
                    "extension",
                    &["repeat", "extend", "clip", "mirror"],
                    "outside [0, 1]: tile, stretch the edge, transparent black, or mirror",
                ),
                choice(
                    "interpolation",
                    &["linear", "closest"],
                    "bilinear, or the nearest texel",
                ),
            ],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template(
                "node_image({file}, {vector}.xy, {color_space}, {extension}, {interpolation})",
            ),
        },
        NodeDef {
            kind: "environment_texture",
            label: "Environment Texture",
            category: "Texture",
            doc: "An equirectangular image looked up by direction (Blender's Environment Texture): +Y up, the image's middle looks down −Z and its right half toward +X. For worlds; rotate it with a Mapping node.",
            inputs: vec![implicit(
                "vector",
                "sp.generated",
                "the view direction, in a world",
                "the direction to look up",
            )],
            outputs: vec![
                out("color", Color, ".rgb", "colour, linear"),
                out("alpha", Float, ".a", "alpha (1 for images without)"),
            ],
            params: vec![
                ParamDef {
                    name: "file",
                    kind: ParamKind::File,
                    doc: "the image, relative to the scene or material file",
                },
                choice(
                    "color_space",
                    &["linear", "srgb"],
                    "linear for HDR and EXR images; srgb decodes 8-bit colour",
                ),
                choice(
                    "interpolation",
                    &["linear", "closest"],
                    "bilinear, or the nearest texel",
                ),
            ],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template(
                "node_image({file}, nd_equirectangular_uv({vector}), 1u - {color_space}, 0u, {interpolation})",
            ),
        },
        NodeDef {
            kind: "sky_texture",
            label: "Sky Texture",
            category: "Texture",
            doc: "A clear sky by single scattering (Nishita, as Cycles' Nishita sky): air, aerosols and ozone over a spherical Earth at 16 wavelengths, in spectral radiance W/(m²·sr·nm) averaged under the CIE ȳ curve. The sun's disc is not in `color`: in a world the renderer adds it as a sun light of irradiance `sun` and angular diameter `sun_size`, sampled analytically.",
            inputs: vec![
                implicit(
                    "vector",
                    "sp.generated",
                    "the view direction, in a world",
                    "the direction to look along, world space, +Y up",
                ),
                float(
                    "sun_elevation",
                    15.0,
                    FloatRange::new(-90.0, 90.0),
                    "the sun's angle above the horizon, degrees",
                ),
                float(
                    "sun_rotation",
                    0.0,
                    FloatRange::new(-360.0, 360.0),
                    "the sun's angle about +Y, degrees: 0 toward −Z, 90 toward +X",
                ),
                float(
                    "sun_size",
                    0.545,
                    FloatRange::new(0.0, 45.0).soft(0.0, 10.0),
                    "the sun disc's angular diameter, degrees (softens shadows; the sun's irradiance stays)",
                ),
                float(
                    "sun_intensity",
                    1.0,
                    FloatRange::new(0.0, 1000.0).soft(0.0, 10.0),
                    "multiplies the sun's irradiance",
                ),
                float(
                    "altitude",
                    0.0,
                    FloatRange::new(0.0, 59000.0).soft(0.0, 10000.0),
                    "the viewer's height above sea level, metres",
                ),
                float(
                    "air",
                    1.0,
                    FloatRange::new(0.0, 10.0),
                    "density of air molecules (Rayleigh scattering: the blue)",
                ),
                float(
                    "dust",
                    1.0,
                    FloatRange::new(0.0, 10.0),
                    "density of aerosols (Mie scattering: haze around the sun)",
                ),
                float(
                    "ozone",
                    1.0,
                    FloatRange::new(0.0, 10.0),
                    "density of ozone (absorbs orange: the blue of twilight)",
                ),
                float(
                    "ground_albedo",
                    0.3,
                    UNIT,
                    "the ground below the horizon: how much of the sun's light it reflects",
                ),
            ],
            outputs: vec![
                out(
                    "color",
                    Color,
                    ".color",
                    "the sky's radiance along the vector",
                ),
                out(
                    "sun",
                    Color,
                    ".sun",
                    "the sun's irradiance on a surface facing it, after the atmosphere",
                ),
            ],
            params: vec![ParamDef {
                name: "sun_disc",
                kind: ParamKind::Bool(true),
                doc: "add the sun (in a world: a sun light)",
            }],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template(
                "nd_sky({vector}, {sun_elevation}, {sun_rotation}, {altitude}, {air}, {dust}, {ozone}, {ground_albedo}, {sun_intensity}, {sun_disc})",
            ),
        },
        NodeDef {
            kind: "checker_texture",
            label: "Checker Texture",
            category: "Texture",
            doc: "A 3D checkerboard of two colours.",
            inputs: vec![
                implicit(
                    "vector",
                    "sp.generated",
                    "generated coordinates",
                    TEXTURE_VECTOR,
                ),
                color("color1", [0.8; 3], "colour of the cells where fac = 1"),
                color("color2", [0.2; 3], "colour of the other cells"),
                float("scale", 5.0, TEXTURE_SCALE, "cells per unit"),
            ],
            outputs: tex_out(),
            params: vec![],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template("node_checker({vector}, {color1}, {color2}, {scale})"),
        },
        NodeDef {
            kind: "gradient_texture",
            label: "Gradient Texture",
            category: "Texture",
            doc: "A gradient along x, or around or away from the origin.",
            inputs: vec![implicit(
                "vector",
                "sp.generated",
                "generated coordinates",
                TEXTURE_VECTOR,
            )],
            outputs: tex_out(),
            params: vec![choice(
                "gradient_type",
                &[
                    "linear",
                    "quadratic",
                    "easing",
                    "diagonal",
                    "radial",
                    "quadratic_sphere",
                    "spherical",
                ],
                "shape of the gradient",
            )],
            traits: None,
            fold: None,
            range: Some(bounds::unit),
            code: Code::Template("node_gradient({vector}, {gradient_type})"),
        },
        NodeDef {
            kind: "noise_texture",
            label: "Noise Texture",
            category: "Texture",
            doc: "Gradient (Perlin) noise, summed over octaves (fBm); fac lies in [0, 1].",
            inputs: vec![
                implicit(
                    "vector",
                    "sp.generated",
                    "generated coordinates",
                    TEXTURE_VECTOR,
                ),
                float("scale", 5.0, TEXTURE_SCALE, "frequency of the base octave"),
                float(
                    "detail",
                    2.0,
                    DETAIL,
                    "octaves beyond the first, 0 to 15 (fractions blend)",
                ),
                float("roughness", 0.5, UNIT, "amplitude ratio between octaves"),
                float(
                    "lacunarity",
                    2.0,
                    FloatRange::new(0.0, 1000.0).soft(0.0, 5.0),
                    "frequency ratio between octaves",
                ),
                float(
                    "distortion",
                    0.0,
                    LARGE,
                    "displaces the coordinates by noise first",
                ),
            ],
            outputs: tex_out(),
            params: vec![],
            traits: None,
            fold: None,
            range: Some(bounds::unit),
            code: Code::Template(
                "node_noise({vector}, {scale}, {detail}, {roughness}, {lacunarity}, {distortion})",
            ),
        },
        NodeDef {
            kind: "voronoi_texture",
            label: "Voronoi Texture",
            category: "Texture",
            doc: "Worley noise: distance to the nearest feature points of a jittered grid.",
            inputs: vec![
                implicit(
                    "vector",
                    "sp.generated",
                    "generated coordinates",
                    TEXTURE_VECTOR,
                ),
                float("scale", 5.0, TEXTURE_SCALE, "cells per unit"),
                float("smoothness", 1.0, UNIT, "blend width of smooth F1"),
                float(
                    "exponent",
                    0.5,
                    FloatRange::new(0.0, 32.0),
                    "exponent of the Minkowski metric",
                ),
                float(
                    "randomness",
                    1.0,
                    UNIT,
                    "how far feature points stray from the cell corner, 0 to 1",
                ),
            ],
            outputs: vec![
                out(
                    "distance",
                    Float,
                    ".distance",
                    "distance to the feature point",
                ),
                out(
                    "color",
                    Color,
                    ".color",
                    "a random colour per feature point",
                ),
                out(
                    "position",
                    Vector,
                    ".position",
                    "the feature point, in input coordinates",
                ),
            ],
            params: vec![
                choice(
                    "feature",
                    &["f1", "f2", "smooth_f1"],
                    "nearest, second nearest, or a smooth blend of the nearest",
                ),
                choice(
                    "distance",
                    &["euclidean", "manhattan", "chebyshev", "minkowski"],
                    "the metric",
                ),
            ],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template(
                "node_voronoi({vector}, {scale}, {smoothness}, {exponent}, {randomness}, {feature}, {distance})",
            ),
        },
        NodeDef {
            kind: "wave_texture",
            label: "Wave Texture",
            category: "Texture",
            doc: "Bands or rings, distorted by noise.",
            inputs: vec![
                implicit(
                    "vector",
                    "sp.generated",
                    "generated coordinates",
                    TEXTURE_VECTOR,
                ),
                float("scale", 5.0, TEXTURE_SCALE, "waves per unit"),
                float(
                    "distortion",
                    0.0,
                    LARGE,
                    "amount of noise added to the phase",
                ),
                float("detail", 2.0, DETAIL, "octaves of the distortion noise"),
                float("detail_scale", 1.0, LARGE, "scale of the distortion noise"),
                float(
                    "detail_roughness",
                    0.5,
                    UNIT,
                    "roughness of the distortion noise",
                ),
                float("phase_offset", 0.0, LARGE, "shifts the waves"),
            ],
            outputs: tex_out(),
            params: vec![
                choice(
                    "wave_type",
                    &["bands", "rings"],
                    "straight bands or concentric rings",
                ),
                choice(
                    "direction",
                    &["x", "y", "z", "diagonal"],
                    "axis of the bands (for rings, diagonal means spherical)",
                ),
                choice("profile", &["sine", "saw", "triangle"], "shape of one wave"),
            ],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template(
                "node_wave({vector}, {scale}, {distortion}, {detail}, {detail_scale}, {detail_roughness}, {phase_offset}, {wave_type}, {direction}, {profile})",
            ),
        },
        NodeDef {
            kind: "brick_texture",
            label: "Brick Texture",
            category: "Texture",
            doc: "Rows of bricks separated by mortar.",
            inputs: vec![
                implicit(
                    "vector",
                    "sp.generated",
                    "generated coordinates",
                    TEXTURE_VECTOR,
                ),
                color("color1", [0.8; 3], "brick colour"),
                color("color2", [0.2; 3], "second brick colour, mixed in by bias"),
                color("mortar", [0.0; 3], "mortar colour"),
                float("scale", 5.0, TEXTURE_SCALE, "overall scale"),
                float(
                    "mortar_size",
                    0.02,
                    FloatRange::new(0.0, 0.125),
                    "mortar width",
                ),
                float("mortar_smooth", 0.1, UNIT, "softness of the mortar's edge"),
                float(
                    "bias",
                    0.0,
                    FloatRange::new(-1.0, 1.0),
                    "bias of the brick colour between colour 1 and 2, -1 to 1",
                ),
                float(
                    "brick_width",
                    0.5,
                    FloatRange::new(0.01, 100.0).soft(0.01, 2.0),
                    "brick length",
                ),
                float(
                    "row_height",
                    0.25,
                    FloatRange::new(0.01, 100.0).soft(0.01, 2.0),
                    "brick height",
                ),
                float(
                    "offset",
                    0.5,
                    UNIT,
                    "offset of alternate rows, as a fraction of a brick",
                ),
                float(
                    "offset_frequency",
                    2.0,
                    FloatRange::new(1.0, 99.0).soft(1.0, 10.0),
                    "every how many rows are offset",
                ),
                float(
                    "squash",
                    1.0,
                    FloatRange::new(0.0, 99.0).soft(0.0, 10.0),
                    "scales the width of alternate rows",
                ),
                float(
                    "squash_frequency",
                    2.0,
                    FloatRange::new(1.0, 99.0).soft(1.0, 10.0),
                    "every how many rows are squashed",
                ),
            ],
            outputs: vec![
                out("color", Color, ".color", "colour"),
                out("fac", Float, ".fac", "1 on mortar, 0 on brick"),
            ],
            params: vec![],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template(
                "node_brick({vector}, {color1}, {color2}, {mortar}, {scale}, {mortar_size}, {mortar_smooth}, {bias}, {brick_width}, {row_height}, {offset}, {offset_frequency}, {squash}, {squash_frequency})",
            ),
        },
        NodeDef {
            kind: "white_noise_texture",
            label: "White Noise Texture",
            category: "Texture",
            doc: "A random value per input point (a hash), in [0, 1).",
            inputs: vec![implicit(
                "vector",
                "sp.generated",
                "generated coordinates",
                TEXTURE_VECTOR,
            )],
            outputs: vec![
                out("value", Float, ".fac", "random value"),
                out("color", Color, ".color", "random colour"),
            ],
            params: vec![],
            traits: None,
            fold: None,
            range: Some(bounds::unit),
            code: Code::Template("node_white_noise({vector})"),
        },
        // ------------------------------------------------------------------ math
        NodeDef {
            kind: "math",
            label: "Math",
            category: "Math",
            doc: "A scalar operation. Safe as in Blender: division by zero, logarithms and roots of invalid arguments give 0.",
            inputs: vec![
                float("a", 0.5, ANY, "first operand"),
                float("b", 0.5, ANY, "second operand"),
                float(
                    "c",
                    0.5,
                    ANY,
                    "third operand (multiply_add, compare's epsilon, wrap, smooth min/max)",
                ),
            ],
            outputs: vec![out("value", Float, "", "result")],
            params: vec![
                choice("operation", MATH_OPERATIONS, "the operation"),
                ParamDef {
                    name: "clamp",
                    kind: ParamKind::Bool(false),
                    doc: "clamp the result to [0, 1]",
                },
            ],
            traits: None,
            fold: Some(fold_math),
            range: Some(bounds::math),
            code: Code::Template("nd_clamp_if(node_math({operation}, {a}, {b}, {c}), {clamp})"),
        },
        NodeDef {
            kind: "clamp",
            label: "Clamp",
            category: "Math",
            doc: "Limits a value to a range.",
            inputs: vec![
                float("value", 1.0, ANY, "input"),
                float("min", 0.0, ANY, "lower bound"),
                float("max", 1.0, ANY, "upper bound"),
            ],
            outputs: vec![out("result", Float, "", "clamped value")],
            params: vec![choice(
                "clamp_type",
                &["min_max", "range"],
                "range swaps min and max when min > max",
            )],
            traits: None,
            fold: Some(fold_clamp),
            range: Some(bounds::clamp),
            code: Code::Template("node_clamp({clamp_type}, {value}, {min}, {max})"),
        },
        NodeDef {
            kind: "map_range",
            label: "Map Range",
            category: "Math",
            doc: "Remaps a value from one range to another.",
            inputs: vec![
                float("value", 1.0, ANY, "input"),
                float("from_min", 0.0, ANY, "input range start"),
                float("from_max", 1.0, ANY, "input range end"),
                float("to_min", 0.0, ANY, "output range start"),
                float("to_max", 1.0, ANY, "output range end"),
                float(
                    "steps",
                    4.0,
                    FloatRange::new(0.0, f32::INFINITY).soft(0.0, 100.0),
                    "number of steps (stepped)",
                ),
            ],
            outputs: vec![out("result", Float, "", "remapped value")],
            params: vec![
                choice(
                    "interpolation",
                    &["linear", "stepped", "smoothstep", "smootherstep"],
                    "the mapping",
                ),
                ParamDef {
                    name: "clamp",
                    kind: ParamKind::Bool(true),
                    doc: "clamp the result to the output range",
                },
            ],
            traits: None,
            fold: None,
            range: Some(bounds::map_range),
            code: Code::Template(
                "node_map_range({interpolation}, {value}, {from_min}, {from_max}, {to_min}, {to_max}, {steps}, {clamp})",
            ),
        },
        NodeDef {
            kind: "vector_math",
            label: "Vector Math",
            category: "Math",
            doc: "A vector operation.",
            inputs: vec![
                vector("a", [0.0; 3], "first operand"),
                vector("b", [0.0; 3], "second operand"),
                vector(
                    "c",
                    [0.0; 3],
                    "third operand (multiply_add, wrap, faceforward)",
                ),
                float("scale", 1.0, ANY, "scale factor (scale), IOR (refract)"),
            ],
            outputs: vec![
                out("vector", Vector, ".vector", "vector result"),
                out(
                    "value",
                    Float,
                    ".value",
                    "scalar result (dot, distance, length)",
                ),
            ],
            params: vec![choice("operation", VECTOR_MATH_OPERATIONS, "the operation")],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template("node_vector_math({operation}, {a}, {b}, {c}, {scale})"),
        },
        NodeDef {
            kind: "mix_float",
            label: "Mix (Float)",
            category: "Math",
            doc: "Linear interpolation between two numbers.",
            inputs: vec![
                float("factor", 0.5, UNIT, "0 gives a, 1 gives b"),
                float("a", 0.0, ANY, "first value"),
                float("b", 1.0, ANY, "second value"),
            ],
            outputs: vec![out("result", Float, "", "mixed value")],
            params: vec![ParamDef {
                name: "clamp_factor",
                kind: ParamKind::Bool(true),
                doc: "clamp the factor to [0, 1]",
            }],
            traits: None,
            fold: Some(fold_mix_float),
            range: Some(bounds::mix),
            code: Code::Template("mix({a}, {b}, nd_clamp_if({factor}, {clamp_factor}))"),
        },
        NodeDef {
            kind: "mix_vector",
            label: "Mix (Vector)",
            category: "Math",
            doc: "Linear interpolation between two vectors.",
            inputs: vec![
                float("factor", 0.5, UNIT, "0 gives a, 1 gives b"),
                vector("a", [0.0; 3], "first vector"),
                vector("b", [0.0; 3], "second vector"),
            ],
            outputs: vec![out("result", Vector, "", "mixed vector")],
            params: vec![ParamDef {
                name: "clamp_factor",
                kind: ParamKind::Bool(true),
                doc: "clamp the factor to [0, 1]",
            }],
            traits: None,
            fold: None,
            range: Some(bounds::mix),
            code: Code::Template("mix({a}, {b}, vec3<f32>(nd_clamp_if({factor}, {clamp_factor})))"),
        },
        // ----------------------------------------------------------------- colour
        NodeDef {
            kind: "mix_color",
            label: "Mix (Color)",
            category: "Color",
            doc: "Blends colour b over colour a with a blend mode, by factor.",
            inputs: vec![
                float("factor", 0.5, UNIT, "strength of b, 0 to 1"),
                color("a", [0.5; 3], "base colour"),
                color("b", [0.5; 3], "blended colour"),
            ],
            outputs: vec![out("result", Color, "", "blended colour")],
            params: vec![
                choice("blend", BLEND_MODES, "the blend mode"),
                ParamDef {
                    name: "clamp_result",
                    kind: ParamKind::Bool(false),
                    doc: "clamp the result to [0, 1]",
                },
            ],
            traits: None,
            fold: None,
            range: Some(bounds::mix_color),
            code: Code::Template(
                "nd_clamp3_if(node_mix_color({blend}, clamp({factor}, 0.0, 1.0), {a}, {b}), {clamp_result})",
            ),
        },
        NodeDef {
            kind: "color_ramp",
            label: "Color Ramp",
            category: "Color",
            doc: "Maps a value to a colour through stops.",
            inputs: vec![float("fac", 0.5, UNIT, "position along the ramp")],
            outputs: vec![
                out("color", Color, ".rgb", "colour"),
                out("alpha", Float, ".a", "alpha"),
            ],
            params: vec![
                ParamDef {
                    name: "stops",
                    kind: ParamKind::Ramp,
                    doc: "(position, (r, g, b, a)) stops; default black to white",
                },
                choice(
                    "interpolation",
                    &["linear", "constant", "ease"],
                    "between stops",
                ),
            ],
            traits: None,
            fold: None,
            range: Some(bounds::color_ramp),
            code: Code::Generated(generate_color_ramp),
        },
        NodeDef {
            kind: "hue_saturation_value",
            label: "Hue/Saturation/Value",
            category: "Color",
            doc: "Shifts hue, scales saturation and value.",
            inputs: vec![
                float("hue", 0.5, UNIT, "hue shift; 0.5 leaves it"),
                float(
                    "saturation",
                    1.0,
                    FloatRange::new(0.0, 2.0),
                    "saturation scale",
                ),
                float("value", 1.0, FloatRange::new(0.0, 2.0), "value scale"),
                float("fac", 1.0, UNIT, "strength of the change"),
                color("color", [0.8; 3], "input colour"),
            ],
            outputs: vec![out("color", Color, "", "adjusted colour")],
            params: vec![],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template(
                "node_hue_saturation_value({hue}, {saturation}, {value}, {fac}, {color})",
            ),
        },
        NodeDef {
            kind: "invert",
            label: "Invert Color",
            category: "Color",
            doc: "1 - colour, by factor.",
            inputs: vec![
                float("fac", 1.0, UNIT, "strength"),
                color("color", [0.0; 3], "input colour"),
            ],
            outputs: vec![out("color", Color, "", "inverted colour")],
            params: vec![],
            traits: None,
            fold: Some(fold_invert),
            range: Some(bounds::invert),
            code: Code::Template("node_invert({fac}, {color})"),
        },
        NodeDef {
            kind: "gamma",
            label: "Gamma",
            category: "Color",
            doc: "Raises the colour to a power.",
            inputs: vec![
                color("color", [1.0; 3], "input colour"),
                float("gamma", 1.0, FloatRange::new(0.001, 10.0), "exponent"),
            ],
            outputs: vec![out("color", Color, "", "result")],
            params: vec![],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template("node_gamma({color}, {gamma})"),
        },
        NodeDef {
            kind: "brightness_contrast",
            label: "Brightness/Contrast",
            category: "Color",
            doc: "Adds brightness and scales contrast about mid grey.",
            inputs: vec![
                color("color", [1.0; 3], "input colour"),
                float(
                    "bright",
                    0.0,
                    FloatRange::new(-100.0, 100.0).soft(-1.0, 1.0),
                    "added brightness",
                ),
                float(
                    "contrast",
                    0.0,
                    FloatRange::new(-100.0, 100.0).soft(-1.0, 1.0),
                    "contrast change",
                ),
            ],
            outputs: vec![out("color", Color, "", "result")],
            params: vec![],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template("node_bright_contrast({color}, {bright}, {contrast})"),
        },
        NodeDef {
            kind: "rgb_to_bw",
            label: "RGB to BW",
            category: "Color",
            doc: "Luminance (Rec. 709) of a colour.",
            inputs: vec![color("color", [0.5; 3], "input colour")],
            outputs: vec![out("value", Float, "", "luminance")],
            params: vec![],
            traits: None,
            fold: None,
            range: Some(bounds::rgb_to_bw),
            code: Code::Template("node_rgb_to_bw({color})"),
        },
        // ------------------------------------------------------------- converters
        NodeDef {
            kind: "separate_color",
            label: "Separate Color",
            category: "Converter",
            doc: "Splits a colour into RGB or HSV channels.",
            inputs: vec![color("color", [0.8; 3], "input colour")],
            outputs: vec![
                out("red", Float, ".x", "red, or hue"),
                out("green", Float, ".y", "green, or saturation"),
                out("blue", Float, ".z", "blue, or value"),
            ],
            params: vec![choice("mode", &["rgb", "hsv"], "channels")],
            traits: None,
            fold: None,
            range: Some(bounds::separate),
            code: Code::Template("nd_separate_color({color}, {mode})"),
        },
        NodeDef {
            kind: "combine_color",
            label: "Combine Color",
            category: "Converter",
            doc: "Builds a colour from RGB or HSV channels.",
            inputs: vec![
                float("red", 0.0, UNIT, "red, or hue"),
                float("green", 0.0, UNIT, "green, or saturation"),
                float("blue", 0.0, UNIT, "blue, or value"),
            ],
            outputs: vec![out("color", Color, "", "colour")],
            params: vec![choice("mode", &["rgb", "hsv"], "channels")],
            traits: None,
            fold: None,
            range: Some(bounds::combine),
            code: Code::Template("nd_combine_color(vec3<f32>({red}, {green}, {blue}), {mode})"),
        },
        NodeDef {
            kind: "separate_xyz",
            label: "Separate XYZ",
            category: "Converter",
            doc: "Splits a vector into components.",
            inputs: vec![vector("vector", [0.0; 3], "input vector")],
            outputs: vec![
                out("x", Float, ".x", "x"),
                out("y", Float, ".y", "y"),
                out("z", Float, ".z", "z"),
            ],
            params: vec![],
            traits: None,
            fold: Some(fold_separate_xyz),
            range: Some(bounds::separate),
            code: Code::Template("{vector}"),
        },
        NodeDef {
            kind: "combine_xyz",
            label: "Combine XYZ",
            category: "Converter",
            doc: "Builds a vector from components.",
            inputs: vec![
                float("x", 0.0, ANY, "x"),
                float("y", 0.0, ANY, "y"),
                float("z", 0.0, ANY, "z"),
            ],
            outputs: vec![out("vector", Vector, "", "vector")],
            params: vec![],
            traits: None,
            fold: Some(fold_combine_xyz),
            range: Some(bounds::combine),
            code: Code::Template("vec3<f32>({x}, {y}, {z})"),
        },
        NodeDef {
            kind: "mapping",
            label: "Mapping",
            category: "Vector",
            doc: "Translates, rotates (Euler XYZ, radians) and scales a vector.",
            inputs: vec![
                vector("vector", [0.0; 3], "input vector"),
                vector("location", [0.0; 3], "translation"),
                vector("rotation", [0.0; 3], "Euler XYZ rotation in radians"),
                vector("scale", [1.0; 3], "scale"),
            ],
            outputs: vec![out("vector", Vector, "", "mapped vector")],
            params: vec![choice(
                "vector_type",
                &["point", "texture", "vector", "normal"],
                "point: scale, rotate, translate; texture: the inverse; vector: no translation; normal: inverse-transpose, normalised",
            )],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template(
                "node_mapping({vector_type}, {vector}, {location}, {rotation}, {scale})",
            ),
        },
        NodeDef {
            kind: "normal_map",
            label: "Normal Map",
            category: "Vector",
            doc: "Perturbs the shading normal by a tangent-space normal map colour.",
            inputs: vec![
                float(
                    "strength",
                    1.0,
                    FloatRange::new(0.0, 10.0).soft(0.0, 1.0),
                    "0 keeps the normal, 1 applies the map fully",
                ),
                color(
                    "color",
                    [0.5, 0.5, 1.0],
                    "tangent-space normal encoded as colour",
                ),
            ],
            outputs: vec![out("normal", Vector, "", "world-space normal")],
            params: vec![],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template("nd_normal_map({strength}, {color}, sp)"),
        },
        NodeDef {
            kind: BUMP,
            label: "Bump",
            category: "Vector",
            doc: "Perturbs the shading normal by the slope of a height field, found by evaluating the height at two displaced points.",
            inputs: vec![
                float(
                    "strength",
                    1.0,
                    UNIT,
                    "0 keeps the normal, 1 applies the bump fully",
                ),
                float(
                    "distance",
                    1.0,
                    FloatRange::new(0.0, 1000.0).soft(0.0, 1.0),
                    "height multiplier",
                ),
                float("height", 0.0, ANY, "height; connect a texture"),
                implicit("normal", "sp.n", "the shading normal", "normal to perturb"),
            ],
            outputs: vec![out("normal", Vector, "", "world-space normal")],
            params: vec![ParamDef {
                name: "invert",
                kind: ParamKind::Bool(false),
                doc: "bump inward",
            }],
            traits: None,
            fold: None,
            range: None,
            code: Code::Generated(generate_bump),
        },
        // ---------------------------------------------------------------- shaders
        NodeDef {
            kind: "principled_bsdf",
            label: "Principled BSDF",
            category: "Shader",
            doc: "The layered surface of shaders/bsdf/principled.wgsl (Blender's Principled BSDF). Inputs are clamped to their valid ranges.",
            inputs: principled_inputs(),
            outputs: vec![out("bsdf", Bsdf, "", "the surface")],
            params: principled_params(),
            traits: Some(principled_bsdf_traits),
            fold: None,
            range: None,
            code: Code::Generated(generate_principled_bsdf),
        },
        NodeDef {
            kind: "volume_absorption",
            label: "Volume Absorption",
            category: "Shader",
            doc: "A volume that only absorbs: (1 − colour) × density per scene unit, so light crossing it keeps e^(−(1 − colour) density length) (Beer–Lambert).",
            inputs: vec![
                color("color", [0.8; 3], "the colour light keeps"),
                float("density", 1.0, DENSITY, "absorption per scene unit"),
            ],
            outputs: vec![out("volume", Volume, "", "the volume")],
            params: vec![],
            traits: Some(volume_absorption_traits),
            fold: None,
            range: Some(bounds::volume_absorption),
            code: Code::Template("nd_volume_absorption({color}, {density})"),
        },
        NodeDef {
            kind: "volume_scatter",
            label: "Volume Scatter",
            category: "Shader",
            doc: "A volume that scatters light without absorbing it, by the Henyey–Greenstein phase function.",
            inputs: vec![
                color(
                    "color",
                    [0.8; 3],
                    "scattering per unit of density, per channel",
                ),
                float("density", 1.0, DENSITY, "scattering per scene unit"),
                float(
                    "anisotropy",
                    0.0,
                    ANISOTROPY,
                    "mean cosine of the scattering angle: 0 isotropic, > 0 forward, < 0 backward",
                ),
            ],
            outputs: vec![out("volume", Volume, "", "the volume")],
            params: vec![],
            traits: Some(volume_scatter_traits),
            fold: None,
            range: Some(bounds::volume_scatter),
            code: Code::Template("nd_volume_scatter({color}, {density}, {anisotropy})"),
        },
        NodeDef {
            kind: "principled_volume",
            label: "Principled Volume",
            category: "Shader",
            doc: "Scattering, absorption and emission in one volume, as Cycles' Principled Volume: scattering colour × density, absorption (1 − colour)(1 − √absorption colour) × density, emission strength × colour per unit length.",
            inputs: vec![
                color("color", [0.5; 3], "scattering colour"),
                float(
                    "density",
                    1.0,
                    DENSITY,
                    "scattering and absorption per scene unit",
                ),
                float(
                    "anisotropy",
                    0.0,
                    ANISOTROPY,
                    "mean cosine of the scattering angle",
                ),
                color("absorption_color", [0.0; 3], "tint of what is absorbed"),
                float(
                    "emission_strength",
                    0.0,
                    FloatRange::new(0.0, f32::INFINITY).soft(0.0, 100.0),
                    "emitted radiance per scene unit",
                ),
                color("emission_color", [1.0; 3], "colour of the emission"),
            ],
            outputs: vec![out("volume", Volume, "", "the volume")],
            params: vec![],
            traits: Some(principled_volume_traits),
            fold: None,
            range: Some(bounds::principled_volume),
            code: Code::Template(
                "nd_principled_volume({color}, {density}, {anisotropy}, {absorption_color}, {emission_strength}, {emission_color})",
            ),
        },
        NodeDef {
            kind: MATERIAL_OUTPUT,
            label: "Material Output",
            category: "Output",
            doc: "The surface the material renders and the volume inside it. With a volume and no surface, the surface lets light through unchanged (index-matched).",
            inputs: vec![
                SocketDef {
                    name: "surface",
                    ty: Bsdf,
                    default: Default::Implicit(
                        "nd_default_surface(sp)",
                        "the default grey surface",
                    ),
                    range: None,
                    doc: "the surface shader",
                },
                SocketDef {
                    name: "volume",
                    ty: Volume,
                    default: Default::Implicit("nd_no_volume()", "no volume"),
                    range: None,
                    doc: "the volume inside a closed mesh",
                },
            ],
            outputs: vec![],
            params: vec![],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template("nd_material_output({surface}, {volume})"),
        },
        NodeDef {
            kind: WORLD_OUTPUT,
            label: "World Output",
            category: "Output",
            doc: "The world: the radiance that arrives from each direction where a ray leaves the scene, colour × strength (Blender's Background into World Output). The renderer bakes it into an environment map it samples by importance; a Sky Texture's sun becomes a sun light.",
            inputs: vec![
                color("color", [0.05; 3], "the radiance seen in each direction"),
                float(
                    "strength",
                    1.0,
                    FloatRange::new(0.0, f32::INFINITY).soft(0.0, 10.0),
                    "multiplies the colour",
                ),
            ],
            outputs: vec![],
            params: vec![],
            traits: None,
            fold: None,
            range: None,
            code: Code::Template("nd_world_output({color}, {strength})"),
        },
    ]
}

// ------------------------------------------------------------- constant folding
//
// Only nodes whose result the CPU computes exactly as the WGSL does: constants, component
// shuffles and the elementary math operations.

fn fold_value(inputs: &[Value], _: Params) -> Option<Vec<Value>> {
    Some(vec![Value::Float(inputs[0].as_f32())])
}

fn fold_vec3(inputs: &[Value], _: Params) -> Option<Vec<Value>> {
    Some(vec![Value::Vec3(inputs[0].as_vec3())])
}

fn fold_combine_xyz(inputs: &[Value], _: Params) -> Option<Vec<Value>> {
    let f = |i: usize| inputs[i].as_f32();
    Some(vec![Value::Vec3([f(0), f(1), f(2)])])
}

fn fold_separate_xyz(inputs: &[Value], _: Params) -> Option<Vec<Value>> {
    Some(inputs[0].as_vec3().map(Value::Float).to_vec())
}

fn fold_mix_float(inputs: &[Value], params: Params) -> Option<Vec<Value>> {
    let f = |i: usize| inputs[i].as_f32();
    let t = if params.flag("clamp_factor") {
        f(0).clamp(0.0, 1.0)
    } else {
        f(0)
    };
    Some(vec![Value::Float(f(1) + (f(2) - f(1)) * t)])
}

fn fold_math(inputs: &[Value], params: Params) -> Option<Vec<Value>> {
    let (a, b) = (inputs[0].as_f32(), inputs[1].as_f32());
    let r = match MATH_OPERATIONS[params.choice("operation")] {
        "add" => a + b,
        "subtract" => a - b,
        "multiply" => a * b,
        // Safe division, as node_math.
        "divide" => {
            if b == 0.0 {
                0.0
            } else {
                a / b
            }
        }
        "minimum" => a.min(b),
        "maximum" => a.max(b),
        "absolute" => a.abs(),
        "floor" => a.floor(),
        "ceil" => a.ceil(),
        _ => return None,
    };
    let r = if params.flag("clamp") {
        r.clamp(0.0, 1.0)
    } else {
        r
    };
    Some(vec![Value::Float(r)])
}

fn fold_clamp(inputs: &[Value], params: Params) -> Option<Vec<Value>> {
    let f = |i: usize| inputs[i].as_f32();
    let (x, lo, hi) = (f(0), f(1), f(2));
    // "range" swaps reversed bounds, as node_clamp.
    let (lo, hi) = if params.choice("clamp_type") == 1 && lo > hi {
        (hi, lo)
    } else {
        (lo, hi)
    };
    Some(vec![Value::Float(x.max(lo).min(hi))])
}

fn fold_invert(inputs: &[Value], _: Params) -> Option<Vec<Value>> {
    let (t, c) = (inputs[0].as_f32(), inputs[1].as_vec3());
    Some(vec![Value::Vec3(c.map(|x| x + (1.0 - 2.0 * x) * t))])
}

// ---------------------------------------------------------------- generated code

/// The stops of a colour ramp whose node sets none: black to white.
pub fn default_ramp_stops() -> Vec<RampStop> {
    vec![
        RampStop {
            position: 0.0,
            color: [0.0, 0.0, 0.0, 1.0],
        },
        RampStop {
            position: 1.0,
            color: [1.0; 4],
        },
    ]
}

/// The ramp's stops, interpolated at the factor (`Emit::ramp`).
fn generate_color_ramp(e: &mut dyn Emit) -> Result<String, GraphError> {
    let mode = e.param("interpolation");
    let fac = e.input("fac");
    e.call(&["nd_ramp_mix"]);
    Ok(e.ramp("stops", &fac, &mode))
}

/// The height input becomes a function of the shading point, evaluated at the point and
/// one step along each tangent direction; a constant height has no slope.
fn generate_bump(e: &mut dyn Emit) -> Result<String, GraphError> {
    let normal = e.input("normal");
    let Some(height) = e.input_function("height")? else {
        return Ok(normal);
    };
    let strength = e.input("strength");
    let distance = e.input("distance");
    let invert = e.param("invert");
    e.call(&[
        "frame_from_normal_tangent",
        "nd_bump",
        "nd_bump_step",
        "nd_displaced",
    ]);
    Ok(format!(
        "nd_bump({strength}, {distance}, {height}(sp), {height}(nd_displaced(sp, frame_from_normal_tangent({normal}, sp.dpdu, 0.0).t, nd_bump_step(sp))), \
         {height}(nd_displaced(sp, frame_from_normal_tangent({normal}, sp.dpdu, 0.0).b, nd_bump_step(sp))), nd_bump_step(sp), {normal}, \
         frame_from_normal_tangent({normal}, sp.dpdu, 0.0), {invert})"
    ))
}

/// `material_eval(Principled(..), normal)`: one field per principled parameter in the
/// table's order, each input clamped to the parameter's range (non-finite values replaced
/// by the default) and each flag from the node's parameters.
fn generate_principled_bsdf(e: &mut dyn Emit) -> Result<String, GraphError> {
    let mut fields = Vec::new();
    for p in &principled::PARAMETERS {
        fields.push(match p.default_value() {
            ParamValue::Bool(_) => e.param(p.name),
            ParamValue::Float(d) => p.range.clamp_wgsl(p.kind, &e.input(p.name), d),
            ParamValue::Color(_) => p.range.clamp_wgsl(p.kind, &e.input(p.name), 0.0),
        });
    }
    let code = format!(
        "material_eval(Principled({}), nd_safe_normal({}, sp.n))",
        fields.join(", "),
        e.input("normal")
    );
    e.call(&[
        "nd_unit",
        "nd_unit3",
        "nd_finite",
        "nd_finite3",
        "nd_safe_normal",
    ]);
    Ok(code)
}

/// The Principled BSDF's sockets: one per principled parameter (`crate::shader::principled`,
/// flags aside), then the shading normal.
fn principled_inputs() -> Vec<SocketDef> {
    let mut inputs: Vec<SocketDef> = principled::PARAMETERS
        .iter()
        .filter_map(|p| match p.default_value() {
            ParamValue::Float(x) => Some(float(p.name, x, principled_range(p.range), p.doc)),
            ParamValue::Color(c) => Some(color(p.name, c.to_array(), p.doc)),
            ParamValue::Bool(_) => None,
        })
        .collect();
    inputs.push(implicit(
        "normal",
        "sp.n",
        "the shading normal",
        "shading normal (world space)",
    ));
    inputs
}

/// A principled parameter's socket range, from the table's [`principled::Range`] (the one
/// declaration of what the parameter accepts): its hard bounds are the ones scene files are
/// validated against and the WGSL clamps to.
fn principled_range(range: principled::Range) -> FloatRange {
    use principled::Range;
    match range {
        Range::Unit => UNIT,
        Range::NonNegative => FloatRange::new(0.0, f32::INFINITY).soft(0.0, 10.0),
        // clamp_wgsl's bound.
        Range::Ior => FloatRange::new(1.0, 100.0).soft(1.0, 3.0),
        // The one finite parameter, the anisotropy's rotation, is in turns.
        Range::Finite => ANY.soft(0.0, 1.0),
        Range::Flag => unreachable!("flags are parameters, not sockets"),
    }
}

/// The Principled BSDF's parameters: the principled flags.
fn principled_params() -> Vec<ParamDef> {
    principled::PARAMETERS
        .iter()
        .filter_map(|p| match p.default_value() {
            ParamValue::Bool(b) => Some(ParamDef {
                name: p.name,
                kind: ParamKind::Bool(b),
                doc: p.doc,
            }),
            _ => None,
        })
        .collect()
}

// ------------------------------------------------------------------ surface traits

// The volume nodes' coefficients from constant inputs, as shaders/nodes/volume.wgsl
// computes them; `None` where an input varies.

fn volume_traits(volume: Option<VolumeCoefficients>) -> MaterialTraits {
    MaterialTraits {
        volume,
        ..MaterialTraits::default()
    }
}

fn known_inputs<const N: usize>(
    known: &dyn Fn(&str) -> Option<Value>,
    names: [&str; N],
) -> Option<[Value; N]> {
    let values: Option<Vec<Value>> = names.iter().map(|n| known(n)).collect();
    values.and_then(|v| v.try_into().ok())
}

fn phase_g(v: &Value) -> f32 {
    v.as_f32().clamp(-0.999, 0.999)
}

fn volume_absorption_traits(known: &dyn Fn(&str) -> Option<Value>, _: Params) -> MaterialTraits {
    volume_traits(known_inputs(known, ["color", "density"]).map(|[c, d]| {
        let d = d.as_f32().max(0.0);
        VolumeCoefficients {
            absorption: c.as_vec3().map(|c| (1.0 - c.clamp(0.0, 1.0)) * d),
            ..VolumeCoefficients::default()
        }
    }))
}

fn volume_scatter_traits(known: &dyn Fn(&str) -> Option<Value>, _: Params) -> MaterialTraits {
    volume_traits(
        known_inputs(known, ["color", "density", "anisotropy"]).map(|[c, d, g]| {
            let d = d.as_f32().max(0.0);
            VolumeCoefficients {
                scattering: c.as_vec3().map(|c| c.max(0.0) * d),
                g: phase_g(&g),
                ..VolumeCoefficients::default()
            }
        }),
    )
}

fn principled_volume_traits(known: &dyn Fn(&str) -> Option<Value>, _: Params) -> MaterialTraits {
    let names = [
        "color",
        "density",
        "anisotropy",
        "absorption_color",
        "emission_strength",
        "emission_color",
    ];
    volume_traits(known_inputs(known, names).map(|[c, d, g, a, s, e]| {
        let d = d.as_f32().max(0.0);
        let (c, a, e) = (c.as_vec3(), a.as_vec3(), e.as_vec3());
        let s = s.as_f32().max(0.0);
        VolumeCoefficients {
            absorption: std::array::from_fn(|i| {
                let tint = (1.0 - a[i].max(0.0).sqrt()).max(0.0);
                (1.0 - c[i].max(0.0)).max(0.0) * tint * d
            }),
            scattering: c.map(|c| c.max(0.0) * d),
            emission: e.map(|e| e.max(0.0) * s),
            g: phase_g(&g),
        }
    }))
}

/// Transmissive where it may let light through, emissive as its emission inputs say, and
/// the lobes its weights can reach.
fn principled_bsdf_traits(known: &dyn Fn(&str) -> Option<Value>, params: Params) -> MaterialTraits {
    let transmission = known("transmission_weight").map(|v| v.as_f32());
    let transmissive = params.flag("thin_walled") || transmission != Some(0.0);
    let (strength, color) = (known("emission_strength"), known("emission_color"));
    let (constant_emission, varying_emission) = match (strength, color) {
        (Some(s), Some(c)) => {
            let e = c.as_vec3().map(|x| x.max(0.0) * s.as_f32().max(0.0));
            (e.iter().any(|&x| x > 0.0).then_some(e), false)
        }
        (Some(s), None) if s.as_f32() == 0.0 => (None, false),
        (None, Some(c)) if c.as_vec3() == [0.0; 3] => (None, false),
        _ => (None, true),
    };
    let weight = |name: &str| known(name).map(|v| v.as_f32());
    let lobes = super::principled_lobes(
        weight("coat_weight"),
        weight("sheen_weight"),
        weight("metallic"),
        transmission,
        weight("specular_weight"),
        weight("subsurface_weight"),
        params.flag("thin_walled"),
    ) | super::cutout_lobes(weight("alpha"));
    MaterialTraits {
        transmissive,
        constant_emission,
        varying_emission,
        lobes,
        ..MaterialTraits::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_float_input_declares_a_range_holding_its_default() {
        let mut checked = 0;
        for def in library() {
            for s in &def.inputs {
                let at = format!("{}.{}", def.kind, s.name);
                if s.ty != SocketType::Float {
                    assert!(s.range.is_none(), "{at}: a range on a {}", s.ty.name());
                    continue;
                }
                let r = s.range.unwrap_or_else(|| panic!("{at} declares no range"));
                assert!(
                    r.min <= r.soft_min && r.soft_min <= r.soft_max && r.soft_max <= r.max,
                    "{at}: the soft range lies in the hard one: {r:?}"
                );
                assert!(r.soft_min.is_finite() || r.min == r.soft_min, "{at}: {r:?}");
                let Default::Value(Value::Float(d)) = s.default else {
                    panic!("{at}: a float input's default is a float");
                };
                assert!(
                    r.contains(d) && r.soft_min <= d && d <= r.soft_max,
                    "{at}: default {d} outside {r:?}"
                );
                checked += 1;
            }
        }
        assert!(checked > 60, "{checked} float inputs");
    }

    #[test]
    fn ranges_follow_blender_and_the_principled_table() {
        let range =
            |kind: &str, input: &str| find(kind).unwrap().input(input).unwrap().range.unwrap();
        assert_eq!(range("noise_texture", "scale").min, 0.0);
        assert_eq!(range("noise_texture", "roughness"), UNIT);
        assert_eq!(range("fresnel", "ior").min, 1.0);
        assert_eq!(range("mix_color", "factor"), UNIT);
        assert_eq!(range("principled_bsdf", "roughness"), UNIT);
        assert_eq!(range("principled_bsdf", "ior").min, 1.0);
        assert_eq!(
            range("principled_bsdf", "emission_strength").max,
            f32::INFINITY
        );
        assert_eq!(range("math", "a"), ANY);
        assert_eq!(range("noise_texture", "scale").describe(), "[0, 1000]");
        assert_eq!(
            range("principled_bsdf", "emission_strength").describe(),
            "≥ 0"
        );
        assert_eq!(ANY.describe(), "any");
    }
}
