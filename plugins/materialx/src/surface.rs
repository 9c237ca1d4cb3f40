//! Surface shaders: OpenPBR Surface is Kiln's Principled BSDF with other names (both are
//! the same layered model), so [`OPEN_PBR`] renames one to the other both ways. The
//! other shaders are translated to OpenPBR's inputs first ([`to_open_pbr`]): Standard
//! Surface by MaterialX's own `standard_surface_to_open_pbr` graph, glTF PBR, USD Preview
//! Surface and Disney Principled by the formulas documented in `docs/MATERIALX.md`.
//! Constants fold; linked inputs get the Kiln nodes that compute the same.

use std::collections::BTreeMap;

use kiln_plugin_api::kmat::{Graph, Node, Value};

/// An OpenPBR input and the Principled BSDF input it is: Kiln name, OpenPBR name,
/// MaterialX type, OpenPBR's default.
pub const OPEN_PBR: &[(&str, &str, &str, [f32; 3])] = &[
    ("base_color", "base_color", "color3", [0.8; 3]),
    ("base_weight", "base_weight", "float", [1.0; 3]),
    (
        "diffuse_roughness",
        "base_diffuse_roughness",
        "float",
        [0.0; 3],
    ),
    ("metallic", "base_metalness", "float", [0.0; 3]),
    ("roughness", "specular_roughness", "float", [0.3; 3]),
    (
        "anisotropy",
        "specular_roughness_anisotropy",
        "float",
        [0.0; 3],
    ),
    ("ior", "specular_ior", "float", [1.5; 3]),
    ("specular_weight", "specular_weight", "float", [1.0; 3]),
    ("specular_color", "specular_color", "color3", [1.0; 3]),
    (
        "transmission_weight",
        "transmission_weight",
        "float",
        [0.0; 3],
    ),
    (
        "transmission_color",
        "transmission_color",
        "color3",
        [1.0; 3],
    ),
    (
        "transmission_depth",
        "transmission_depth",
        "float",
        [0.0; 3],
    ),
    ("subsurface_weight", "subsurface_weight", "float", [0.0; 3]),
    (
        "subsurface_radius",
        "subsurface_radius_scale",
        "color3",
        [1.0, 0.5, 0.25],
    ),
    ("subsurface_scale", "subsurface_radius", "float", [1.0; 3]),
    (
        "subsurface_anisotropy",
        "subsurface_scatter_anisotropy",
        "float",
        [0.0; 3],
    ),
    ("coat_weight", "coat_weight", "float", [0.0; 3]),
    ("coat_roughness", "coat_roughness", "float", [0.0; 3]),
    ("coat_ior", "coat_ior", "float", [1.6; 3]),
    ("coat_color", "coat_color", "color3", [1.0; 3]),
    ("sheen_weight", "fuzz_weight", "float", [0.0; 3]),
    ("sheen_color", "fuzz_color", "color3", [1.0; 3]),
    ("sheen_roughness", "fuzz_roughness", "float", [0.5; 3]),
    ("emission_color", "emission_color", "color3", [1.0; 3]),
    ("emission_strength", "emission_luminance", "float", [0.0; 3]),
    ("alpha", "geometry_opacity", "float", [1.0; 3]),
];

/// OpenPBR's normal input, Kiln's `normal`.
pub const OPEN_PBR_NORMAL: &str = "geometry_normal";
/// OpenPBR's thin-walled flag, Kiln's `thin_walled` parameter.
pub const OPEN_PBR_THIN_WALLED: &str = "geometry_thin_walled";
/// Principled inputs OpenPBR has no input for, written as attributes of the shader node
/// when they are constants other than Kiln's defaults, so that Kiln reads back what it
/// wrote: Kiln name, attribute, Kiln default.
pub const KILN_ONLY: &[(&str, &str, f32)] = &[
    ("anisotropy_rotation", "kiln_anisotropy_rotation", 0.0),
    ("subsurface_ior", "kiln_subsurface_ior", 1.4),
];

/// OpenPBR inputs Kiln does not model: named in a warning when set to other than their
/// defaults.
const OPEN_PBR_UNSUPPORTED: &[(&str, f32)] = &[
    ("transmission_scatter", 0.0),
    ("transmission_scatter_anisotropy", 0.0),
    ("transmission_dispersion_scale", 0.0),
    ("coat_roughness_anisotropy", 0.0),
    ("thin_film_weight", 0.0),
];

/// Kiln's ranges of the Principled BSDF's float inputs that are not [0, 1]: constants
/// outside their range are brought in, with a warning.
fn kiln_range(input: &str) -> (f32, f32) {
    match input {
        "ior" | "coat_ior" | "subsurface_ior" => (1.0, 100.0),
        "specular_weight" | "transmission_depth" | "subsurface_scale" | "emission_strength" => {
            (0.0, f32::MAX)
        }
        "anisotropy_rotation" => (f32::MIN, f32::MAX),
        _ => (0.0, 1.0),
    }
}

/// The inputs a shader node sets, by name, already resolved to Kiln values, and the
/// uniform (non-socket) ones it sets as text.
#[derive(Default)]
pub struct ShaderInputs {
    pub values: BTreeMap<String, Value>,
    pub uniforms: BTreeMap<String, String>,
    pub attributes: BTreeMap<String, String>,
}

/// Builds the expressions of a translation in `graph`, naming new nodes after `prefix`.
pub(crate) struct Ops<'a> {
    pub(crate) graph: &'a mut Graph,
    pub(crate) prefix: String,
}

impl Ops<'_> {
    fn id(&self, what: &str) -> String {
        format!("{}_{what}", self.prefix)
    }

    /// `a + (b - a) t` of colours (`color`) or floats, folded for constants.
    pub(crate) fn mix(&mut self, what: &str, color: bool, a: Value, b: Value, t: Value) -> Value {
        match (&a, &b, &t) {
            (_, _, Value::Float(t)) if *t == 0.0 => a,
            (_, _, Value::Float(t)) if *t == 1.0 => b,
            (Value::Float(a), Value::Float(b), Value::Float(t)) => Value::Float(a + (b - a) * t),
            (_, _, Value::Float(t)) if constant3(&a).is_some() && constant3(&b).is_some() => {
                let (x, y) = (
                    constant3(&a).unwrap_or_default(),
                    constant3(&b).unwrap_or_default(),
                );
                Value::Color(std::array::from_fn(|i| x[i] + (y[i] - x[i]) * t))
            }
            _ => {
                // MaterialX's mix does not clamp its factor.
                let node = if color {
                    Node::new("mix_color")
                        .text("blend", "mix")
                        .flag("clamp_result", false)
                } else {
                    Node::new("mix_float").flag("clamp_factor", false)
                };
                let (a, b) = if color {
                    (as_color(a), as_color(b))
                } else {
                    (a, b)
                };
                let node = node.input("factor", t).input("a", a).input("b", b);
                Value::link(&self.graph.add(&self.id(what), node), "result")
            }
        }
    }

    pub(crate) fn multiply(&mut self, what: &str, color: bool, a: Value, b: Value) -> Value {
        if color {
            self.graph.multiply_color(&self.id(what), a, b)
        } else {
            self.graph.multiply(&self.id(what), a, b)
        }
    }

    /// A float operation of Kiln's math node, folded by `fold` for constants.
    pub(crate) fn math(
        &mut self,
        what: &str,
        op: &str,
        a: Value,
        b: Value,
        fold: fn(f32, f32) -> f32,
    ) -> Value {
        if let (Value::Float(x), Value::Float(y)) = (&a, &b) {
            return Value::Float(fold(*x, *y));
        }
        let node = Node::new("math")
            .text("operation", op)
            .input("a", a)
            .input("b", b);
        Value::link(&self.graph.add(&self.id(what), node), "value")
    }

    /// `x > y ? a : b`.
    fn greater(&mut self, what: &str, x: Value, y: Value, a: Value, b: Value) -> Value {
        let gt = self.math(what, "greater_than", x, y, |x, y| {
            f32::from(u8::from(x > y))
        });
        self.mix(&format!("{what}_select"), false, b, a, gt)
    }

    /// The first channel of a colour.
    fn first_channel(&mut self, what: &str, c: Value) -> Value {
        match c {
            Value::Color(c) | Value::Vector(c) => Value::Float(c[0]),
            Value::Float(_) => c,
            _ => {
                let node = Node::new("separate_color").input("color", c);
                Value::link(&self.graph.add(&self.id(what), node), "red")
            }
        }
    }
}

/// A constant's three channels (a float in each).
pub(crate) fn constant3(v: &Value) -> Option<[f32; 3]> {
    match v {
        Value::Float(x) => Some([*x; 3]),
        Value::Color(c) | Value::Vector(c) => Some(*c),
        _ => None,
    }
}

fn as_color(v: Value) -> Value {
    match v {
        Value::Float(x) => Value::Color([x; 3]),
        v => v,
    }
}

/// The shader categories this module reads.
pub const SHADERS: &[&str] = &[
    "open_pbr_surface",
    "standard_surface",
    "gltf_pbr",
    "UsdPreviewSurface",
    "disney_principled",
];

/// Standard Surface's defaults (MaterialX 1.39, `ND_standard_surface_surfaceshader`).
const STANDARD_SURFACE: &[(&str, [f32; 3])] = &[
    ("base", [1.0; 3]),
    ("base_color", [0.8; 3]),
    ("diffuse_roughness", [0.0; 3]),
    ("metalness", [0.0; 3]),
    ("specular", [1.0; 3]),
    ("specular_color", [1.0; 3]),
    ("specular_roughness", [0.2; 3]),
    ("specular_IOR", [1.5; 3]),
    ("specular_anisotropy", [0.0; 3]),
    ("specular_rotation", [0.0; 3]),
    ("transmission", [0.0; 3]),
    ("transmission_color", [1.0; 3]),
    ("transmission_depth", [0.0; 3]),
    ("transmission_scatter", [0.0; 3]),
    ("transmission_scatter_anisotropy", [0.0; 3]),
    ("transmission_dispersion", [0.0; 3]),
    ("subsurface", [0.0; 3]),
    ("subsurface_color", [1.0; 3]),
    ("subsurface_radius", [1.0; 3]),
    ("subsurface_scale", [1.0; 3]),
    ("subsurface_anisotropy", [0.0; 3]),
    ("sheen", [0.0; 3]),
    ("sheen_color", [1.0; 3]),
    ("sheen_roughness", [0.3; 3]),
    ("coat", [0.0; 3]),
    ("coat_color", [1.0; 3]),
    ("coat_roughness", [0.1; 3]),
    ("coat_IOR", [1.5; 3]),
    ("coat_affect_roughness", [0.0; 3]),
    ("thin_film_thickness", [0.0; 3]),
    ("emission", [0.0; 3]),
    ("emission_color", [1.0; 3]),
    ("opacity", [1.0; 3]),
];

const GLTF_PBR: &[(&str, [f32; 3])] = &[
    ("base_color", [1.0; 3]),
    ("metallic", [1.0; 3]),
    ("roughness", [1.0; 3]),
    ("transmission", [0.0; 3]),
    ("specular", [1.0; 3]),
    ("specular_color", [1.0; 3]),
    ("ior", [1.5; 3]),
    ("alpha", [1.0; 3]),
    ("alpha_mode", [0.0; 3]),
    ("alpha_cutoff", [0.5; 3]),
    ("iridescence", [0.0; 3]),
    ("sheen_color", [0.0; 3]),
    ("sheen_roughness", [0.0; 3]),
    ("clearcoat", [0.0; 3]),
    ("clearcoat_roughness", [0.0; 3]),
    ("emissive", [0.0; 3]),
    ("emissive_strength", [1.0; 3]),
    ("thickness", [0.0; 3]),
    ("attenuation_distance", [0.0; 3]),
    ("attenuation_color", [1.0; 3]),
    ("anisotropy_strength", [0.0; 3]),
    ("anisotropy_rotation", [0.0; 3]),
    ("dispersion", [0.0; 3]),
];

const USD_PREVIEW_SURFACE: &[(&str, [f32; 3])] = &[
    ("diffuseColor", [0.18; 3]),
    ("emissiveColor", [0.0; 3]),
    ("useSpecularWorkflow", [0.0; 3]),
    ("specularColor", [0.0; 3]),
    ("metallic", [0.0; 3]),
    ("roughness", [0.5; 3]),
    ("clearcoat", [0.0; 3]),
    ("clearcoatRoughness", [0.01; 3]),
    ("opacity", [1.0; 3]),
    ("opacityMode", [0.0; 3]),
    ("opacityThreshold", [0.0; 3]),
    ("ior", [1.5; 3]),
    ("displacement", [0.0; 3]),
];

const DISNEY_PRINCIPLED: &[(&str, [f32; 3])] = &[
    ("baseColor", [0.16; 3]),
    ("metallic", [0.0; 3]),
    ("roughness", [0.5; 3]),
    ("anisotropic", [0.0; 3]),
    ("specular", [0.5; 3]),
    ("specularTint", [0.0; 3]),
    ("sheen", [0.0; 3]),
    ("sheenTint", [0.5; 3]),
    ("clearcoat", [0.0; 3]),
    ("clearcoatGloss", [1.0; 3]),
    ("specTrans", [0.0; 3]),
    ("ior", [1.5; 3]),
    ("subsurface", [0.0; 3]),
    ("subsurfaceDistance", [1.0; 3]),
];

/// Reads the inputs of one shader with its defaults.
struct Reader<'a> {
    inputs: &'a ShaderInputs,
    defaults: &'static [(&'static str, [f32; 3])],
    /// Colour inputs whose names do not say so.
    colors: &'static [&'static str],
}

impl Reader<'_> {
    /// The input's value, or its default (a colour where the default table's three
    /// channels differ or the input is a colour).
    fn get(&self, name: &str) -> Value {
        if let Some(v) = self.inputs.values.get(name) {
            return v.clone();
        }
        let d = self
            .defaults
            .iter()
            .find(|(n, _)| *n == name)
            .map_or([0.0; 3], |(_, d)| *d);
        if name.contains("color") || name.contains("Color") || self.colors.contains(&name) {
            Value::Color(d)
        } else {
            Value::Float(d[0])
        }
    }

    fn set(&self, name: &str) -> bool {
        self.inputs.values.contains_key(name)
    }

    fn float(&self, name: &str) -> Option<f32> {
        match self.get(name) {
            Value::Float(x) => Some(x),
            _ => None,
        }
    }
}

/// The translation of shader `category`'s inputs into OpenPBR's (by OpenPBR name), plus
/// Kiln-only inputs (by Kiln name, prefixed `kiln:`), and warnings for what it leaves
/// out.
pub fn to_open_pbr(
    category: &str,
    node: &str,
    inputs: &ShaderInputs,
    graph: &mut Graph,
    warnings: &mut Vec<String>,
) -> BTreeMap<String, Value> {
    let mut out = BTreeMap::new();
    let mut ops = Ops {
        graph,
        prefix: node.to_owned(),
    };
    let mut notes = Vec::new();
    let mut unsupported = |input: &str, value: Option<f32>, default: f32| {
        if value.is_none_or(|v| v != default) {
            notes.push(format!(
                "{category} {node}: input {input} is not supported by Kiln and is ignored"
            ));
        }
    };
    match category {
        "open_pbr_surface" => {
            let r = Reader {
                inputs,
                defaults: &[],
                colors: &[],
            };
            for (_, mx, _, _) in OPEN_PBR {
                if let Some(v) = inputs.values.get(*mx) {
                    out.insert(mx.to_string(), v.clone());
                }
            }
            for (input, default) in OPEN_PBR_UNSUPPORTED {
                if r.set(input) {
                    unsupported(input, r.float(input).or(Some(f32::NAN)), *default);
                }
            }
            if let Some(v) = inputs.values.get(OPEN_PBR_NORMAL) {
                out.insert(OPEN_PBR_NORMAL.into(), v.clone());
            }
            // OpenPBR's subsurface has a colour of its own; Kiln's scatters the base
            // colour, which becomes the subsurface colour where subsurface weighs in.
            if let Some(color) = inputs.values.get("subsurface_color") {
                let weight = r.get("subsurface_weight");
                let base = out
                    .get("base_color")
                    .cloned()
                    .unwrap_or(Value::Color([0.8; 3]));
                let mixed = ops.mix("subsurface_color", true, base, color.clone(), weight);
                out.insert("base_color".into(), mixed);
            }
            for (kiln, attribute, _) in KILN_ONLY {
                if let Some(v) = inputs
                    .attributes
                    .get(*attribute)
                    .and_then(|t| t.parse().ok())
                {
                    out.insert(format!("kiln:{kiln}"), Value::Float(v));
                }
            }
        }
        "standard_surface" => {
            let r = Reader {
                inputs,
                defaults: STANDARD_SURFACE,
                colors: &["subsurface_radius", "opacity", "transmission_scatter"],
            };
            let coat = r.get("coat");
            let coat_tint = ops.mix(
                "coat_attenuation",
                true,
                Value::Color([1.0; 3]),
                r.get("coat_color"),
                coat.clone(),
            );
            let base_color = ops.multiply("base_color", true, r.get("base_color"), coat_tint);
            // Kiln's subsurface scatters the base colour (as above).
            let subsurface = r.get("subsurface");
            let base_color = ops.mix(
                "subsurface_color",
                true,
                base_color,
                r.get("subsurface_color"),
                subsurface.clone(),
            );
            out.insert("base_color".into(), base_color);
            out.insert("base_weight".into(), r.get("base"));
            out.insert("base_diffuse_roughness".into(), r.get("diffuse_roughness"));
            let metalness = r.get("metalness");
            out.insert("base_metalness".into(), metalness.clone());
            let specular_weight = ops.greater(
                "specular_weight",
                metalness.clone(),
                Value::Float(0.0),
                Value::Float(1.0),
                r.get("specular"),
            );
            out.insert("specular_weight".into(), specular_weight);
            // A black specular colour means white in the translation.
            let specular_color = match r.get("specular_color") {
                Value::Color(c) if c == [0.0; 3] => Value::Color([1.0; 3]),
                v => v,
            };
            out.insert("specular_color".into(), specular_color);
            out.insert("specular_roughness".into(), r.get("specular_roughness"));
            out.insert("specular_ior".into(), r.get("specular_IOR"));
            out.insert(
                "specular_roughness_anisotropy".into(),
                r.get("specular_anisotropy"),
            );
            if r.set("specular_rotation") {
                out.insert(
                    "kiln:anisotropy_rotation".into(),
                    r.get("specular_rotation"),
                );
            }
            out.insert("transmission_weight".into(), r.get("transmission"));
            out.insert("transmission_color".into(), r.get("transmission_color"));
            out.insert("transmission_depth".into(), r.get("transmission_depth"));
            out.insert("subsurface_weight".into(), subsurface);
            out.insert("subsurface_radius".into(), r.get("subsurface_scale"));
            out.insert("subsurface_radius_scale".into(), r.get("subsurface_radius"));
            out.insert(
                "subsurface_scatter_anisotropy".into(),
                r.get("subsurface_anisotropy"),
            );
            out.insert("fuzz_weight".into(), r.get("sheen"));
            out.insert("fuzz_color".into(), r.get("sheen_color"));
            let fuzz_roughness = ops.math(
                "fuzz_roughness",
                "power",
                r.get("sheen_roughness"),
                Value::Float(0.4),
                f32::powf,
            );
            out.insert("fuzz_roughness".into(), fuzz_roughness);
            // Coloured metals made with a coat over a metal keep the tint, not the coat.
            let coat_metal = ops.multiply("coat_metallic", false, coat.clone(), metalness);
            let coat_weight = ops.greater(
                "coat_weight",
                coat_metal,
                Value::Float(0.0),
                Value::Float(0.0),
                coat,
            );
            out.insert("coat_weight".into(), coat_weight);
            out.insert("coat_color".into(), r.get("coat_color"));
            out.insert("coat_roughness".into(), r.get("coat_roughness"));
            out.insert("coat_ior".into(), r.get("coat_IOR"));
            out.insert("emission_luminance".into(), r.get("emission"));
            out.insert("emission_color".into(), r.get("emission_color"));
            let opacity = ops.first_channel("opacity", r.get("opacity"));
            out.insert("geometry_opacity".into(), opacity);
            if let Some(n) = inputs.values.get("normal") {
                out.insert(OPEN_PBR_NORMAL.into(), n.clone());
            }
            for input in [
                "transmission_scatter",
                "transmission_scatter_anisotropy",
                "transmission_dispersion",
                "thin_film_thickness",
                "coat_affect_roughness",
                "coat_affect_color",
            ] {
                if r.set(input) {
                    let value = match r.get(input) {
                        Value::Float(x) => Some(x),
                        Value::Color(c) if c == [0.0; 3] => Some(0.0),
                        _ => None,
                    };
                    unsupported(input, value, 0.0);
                }
            }
        }
        "gltf_pbr" => {
            let r = Reader {
                inputs,
                defaults: GLTF_PBR,
                colors: &["emissive"],
            };
            let base_color = r.get("base_color");
            out.insert("base_color".into(), base_color.clone());
            out.insert("base_metalness".into(), r.get("metallic"));
            out.insert("specular_roughness".into(), r.get("roughness"));
            out.insert("specular_ior".into(), r.get("ior"));
            out.insert("specular_weight".into(), r.get("specular"));
            out.insert("specular_color".into(), r.get("specular_color"));
            out.insert("transmission_weight".into(), r.get("transmission"));
            // glTF tints transmitted light by the base colour, or by the attenuation
            // colour at the attenuation distance inside a volume.
            let volume = r.float("thickness").is_none_or(|t| t > 0.0)
                && r.float("attenuation_distance").is_none_or(|d| d > 0.0)
                && r.set("attenuation_distance");
            if volume {
                out.insert("transmission_color".into(), r.get("attenuation_color"));
                out.insert("transmission_depth".into(), r.get("attenuation_distance"));
            } else {
                out.insert("transmission_color".into(), base_color);
            }
            out.insert("coat_weight".into(), r.get("clearcoat"));
            out.insert("coat_roughness".into(), r.get("clearcoat_roughness"));
            out.insert("coat_ior".into(), Value::Float(1.5));
            let sheen = r.get("sheen_color");
            let fuzz = match &sheen {
                Value::Color(c) => Value::Float(f32::from(u8::from(c.iter().any(|&x| x > 0.0)))),
                _ => Value::Float(1.0),
            };
            out.insert("fuzz_weight".into(), fuzz);
            out.insert("fuzz_color".into(), sheen);
            out.insert("fuzz_roughness".into(), r.get("sheen_roughness"));
            out.insert("emission_color".into(), r.get("emissive"));
            out.insert("emission_luminance".into(), r.get("emissive_strength"));
            let opacity = match r.float("alpha_mode").unwrap_or(0.0) as i32 {
                0 => Value::Float(1.0),
                1 => {
                    let cutoff = r.get("alpha_cutoff");
                    ops.greater(
                        "alpha_mask",
                        r.get("alpha"),
                        cutoff,
                        Value::Float(1.0),
                        Value::Float(0.0),
                    )
                }
                _ => r.get("alpha"),
            };
            out.insert("geometry_opacity".into(), opacity);
            out.insert(
                "specular_roughness_anisotropy".into(),
                r.get("anisotropy_strength"),
            );
            if r.set("anisotropy_rotation") {
                let rotation = ops.multiply(
                    "anisotropy_rotation",
                    false,
                    r.get("anisotropy_rotation"),
                    Value::Float(1.0 / std::f32::consts::TAU),
                );
                out.insert("kiln:anisotropy_rotation".into(), rotation);
            }
            if let Some(n) = inputs.values.get("normal") {
                out.insert(OPEN_PBR_NORMAL.into(), n.clone());
            }
            for input in ["iridescence", "dispersion"] {
                if r.set(input) {
                    unsupported(input, r.float(input), 0.0);
                }
            }
        }
        "UsdPreviewSurface" => {
            let r = Reader {
                inputs,
                defaults: USD_PREVIEW_SURFACE,
                colors: &[],
            };
            out.insert("base_color".into(), r.get("diffuseColor"));
            out.insert("specular_roughness".into(), r.get("roughness"));
            out.insert("specular_ior".into(), r.get("ior"));
            if r.float("useSpecularWorkflow").unwrap_or(0.0) != 0.0 {
                warnings.push(format!(
                    "UsdPreviewSurface {node}: the specular workflow is approximated (specularColor tints a dielectric's reflection)"
                ));
                out.insert("base_metalness".into(), Value::Float(0.0));
                out.insert("specular_color".into(), r.get("specularColor"));
            } else {
                out.insert("base_metalness".into(), r.get("metallic"));
            }
            out.insert("coat_weight".into(), r.get("clearcoat"));
            out.insert("coat_roughness".into(), r.get("clearcoatRoughness"));
            out.insert("coat_ior".into(), Value::Float(1.5));
            let emissive = r.get("emissiveColor");
            out.insert("emission_color".into(), emissive);
            out.insert("emission_luminance".into(), Value::Float(1.0));
            // Below the threshold the surface is cut out; with no threshold, opacity
            // mixes in a clear dielectric (transmission), as MaterialX's implementation.
            let opacity = r.get("opacity");
            match r.float("opacityThreshold") {
                Some(t) if t > 0.0 => {
                    let cut = ops.greater(
                        "opacity_cutout",
                        Value::Float(t),
                        opacity,
                        Value::Float(0.0),
                        Value::Float(1.0),
                    );
                    out.insert("geometry_opacity".into(), cut);
                }
                _ => {
                    let transmission = ops.math(
                        "transmission",
                        "subtract",
                        Value::Float(1.0),
                        opacity,
                        |a, b| a - b,
                    );
                    out.insert("transmission_weight".into(), transmission);
                }
            }
            if r.set("normal") {
                warnings.push(format!(
                    "UsdPreviewSurface {node}: input normal (tangent space) is not supported by Kiln and is ignored"
                ));
            }
            if r.set("displacement") {
                unsupported("displacement", r.float("displacement"), 0.0);
            }
        }
        "disney_principled" => {
            let r = Reader {
                inputs,
                defaults: DISNEY_PRINCIPLED,
                colors: &["subsurfaceDistance"],
            };
            let base = r.get("baseColor");
            out.insert("base_color".into(), base.clone());
            out.insert("base_metalness".into(), r.get("metallic"));
            out.insert("specular_roughness".into(), r.get("roughness"));
            out.insert("specular_roughness_anisotropy".into(), r.get("anisotropic"));
            // Disney's specular 0.5 is the 4 % reflectance of IOR 1.5.
            let specular = ops.multiply("specular", false, r.get("specular"), Value::Float(2.0));
            out.insert("specular_weight".into(), specular);
            // Tints toward the base colour's hue (the colour over its luminance).
            let tint = match &base {
                Value::Color(c) => {
                    let l = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
                    Value::Color(if l > 0.0 { c.map(|x| x / l) } else { [1.0; 3] })
                }
                _ => Value::Color([1.0; 3]),
            };
            let specular_color = ops.mix(
                "specular_tint",
                true,
                Value::Color([1.0; 3]),
                tint.clone(),
                r.get("specularTint"),
            );
            out.insert("specular_color".into(), clamp_color(specular_color));
            out.insert("fuzz_weight".into(), r.get("sheen"));
            let sheen_color = ops.mix(
                "sheen_tint",
                true,
                Value::Color([1.0; 3]),
                tint,
                r.get("sheenTint"),
            );
            out.insert("fuzz_color".into(), clamp_color(sheen_color));
            // Disney's clear coat is a quarter-strength lobe whose GTR1 alpha runs from
            // 0.1 (gloss 0) to 0.001 (gloss 1); Kiln's roughness is alpha's square root.
            let coat = ops.multiply("clearcoat", false, r.get("clearcoat"), Value::Float(0.25));
            out.insert("coat_weight".into(), coat);
            let alpha = ops.mix(
                "clearcoat_alpha",
                false,
                Value::Float(0.1),
                Value::Float(0.001),
                r.get("clearcoatGloss"),
            );
            let roughness = ops.math(
                "clearcoat_roughness",
                "sqrt",
                alpha,
                Value::Float(0.0),
                |a, _| a.max(0.0).sqrt(),
            );
            out.insert("coat_roughness".into(), roughness);
            out.insert("coat_ior".into(), Value::Float(1.5));
            out.insert("transmission_weight".into(), r.get("specTrans"));
            out.insert("specular_ior".into(), r.get("ior"));
            out.insert("subsurface_weight".into(), r.get("subsurface"));
            out.insert(
                "subsurface_radius_scale".into(),
                r.get("subsurfaceDistance"),
            );
            if r.set("subsurface") {
                warnings.push(format!(
                    "disney_principled {node}: subsurface becomes a random walk of radius subsurfaceDistance × 0.05 scene units (Disney's is a diffuse approximation)"
                ));
            }
            out.insert("subsurface_radius".into(), Value::Float(0.05));
        }
        _ => {}
    }
    warnings.extend(notes);
    out
}

fn clamp_color(v: Value) -> Value {
    match v {
        Value::Color(c) => Value::Color(c.map(|x| x.clamp(0.0, 1.0))),
        v => v,
    }
}

/// The Principled BSDF for OpenPBR inputs `open_pbr` (unset ones at OpenPBR's defaults,
/// as the OpenPBR node would render them); constants outside Kiln's ranges are brought
/// in with a warning naming them.
pub fn principled(
    node: &str,
    open_pbr: &BTreeMap<String, Value>,
    thin_walled: bool,
    warnings: &mut Vec<String>,
) -> Node {
    let mut principled = Node::new("principled_bsdf");
    for (kiln, mx, ty, default) in OPEN_PBR {
        let value = open_pbr.get(*mx).cloned().unwrap_or(if *ty == "float" {
            Value::Float(default[0])
        } else {
            Value::Color(*default)
        });
        principled = principled.input(kiln, in_range(node, kiln, value, warnings));
    }
    for (kiln, _, _) in KILN_ONLY {
        if let Some(v) = open_pbr.get(&format!("kiln:{kiln}")) {
            principled = principled.input(kiln, in_range(node, kiln, v.clone(), warnings));
        }
    }
    if let Some(n) = open_pbr.get(OPEN_PBR_NORMAL) {
        principled = principled.input("normal", n.clone());
    }
    if thin_walled {
        principled = principled.flag("thin_walled", true);
    }
    principled
}

fn in_range(node: &str, input: &str, value: Value, warnings: &mut Vec<String>) -> Value {
    let (lo, hi) = kiln_range(input);
    let clamp = |x: f32| {
        if x.is_finite() {
            x.clamp(lo, hi)
        } else {
            lo.max(0.0)
        }
    };
    let clamped = match &value {
        Value::Float(x) => Value::Float(clamp(*x)),
        Value::Color(c) if input.ends_with("color") || input == "subsurface_radius" => {
            let (lo, hi) = if input == "emission_color" || input == "subsurface_radius" {
                (0.0, f32::MAX)
            } else {
                (0.0, 1.0)
            };
            Value::Color(c.map(|x| if x.is_finite() { x.clamp(lo, hi) } else { 0.0 }))
        }
        v => v.clone(),
    };
    if clamped != value {
        warnings.push(format!(
            "{node}: {input} {value:?} lies outside Kiln's range and was brought into it"
        ));
    }
    clamped
}
