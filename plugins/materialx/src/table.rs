//! The MaterialX standard-library nodes that are one Kiln node each, declared once: the
//! importer maps them to Kiln, the exporter maps Kiln nodes matching a row back to them.
//! Nodes that need several Kiln nodes (images, noises, colour-space conversions) are
//! mapped in code in [`crate::import`] and [`crate::export`].

/// One MaterialX node (a category at some output types) as one Kiln node.
pub struct Row {
    /// The MaterialX node category.
    pub mx: &'static str,
    /// The MaterialX types the row covers: of the output, or for a node with several
    /// outputs, of its first input.
    pub types: &'static [&'static str],
    /// The Kiln node type and the parameters that make it this node.
    pub kiln: &'static str,
    pub params: &'static [(&'static str, Fixed)],
    /// Kiln inputs the MaterialX node has no counterpart for, and the values that make
    /// the Kiln node compute what it does.
    pub fixed: &'static [(&'static str, f32)],
    /// MaterialX input, Kiln input, and the MaterialX default (in every channel).
    pub inputs: &'static [(&'static str, &'static str, f32)],
    /// MaterialX output, Kiln output; a single-output MaterialX node's is `out`.
    pub outputs: &'static [(&'static str, &'static str)],
    /// MaterialX inputs the Kiln node has no counterpart for, and the values that make
    /// the MaterialX node compute what the Kiln node does.
    pub mx_fixed: &'static [(&'static str, f32)],
}

/// A parameter value a row sets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fixed {
    Text(&'static str),
    Flag(bool),
}

const FLOAT: &[&str] = &["float"];
const VEC3: &[&str] = &["color3", "vector3"];
const COLOR: &[&str] = &["color3"];
const VECTOR: &[&str] = &["vector3"];

const fn op(name: &'static str) -> [(&'static str, Fixed); 1] {
    [("operation", Fixed::Text(name))]
}

const BINARY_0: &[(&str, &str, f32)] = &[("in1", "a", 0.0), ("in2", "b", 0.0)];
const BINARY_1: &[(&str, &str, f32)] = &[("in1", "a", 0.0), ("in2", "b", 1.0)];
const UNARY: &[(&str, &str, f32)] = &[("in", "a", 0.0)];
const VALUE: &[(&str, &str)] = &[("out", "value")];
const VECTOR_OUT: &[(&str, &str)] = &[("out", "vector")];

macro_rules! math {
    ($mx:literal, $kiln:literal, $inputs:expr) => {
        Row {
            mx: $mx,
            types: FLOAT,
            kiln: "math",
            params: &op($kiln),
            fixed: &[],
            inputs: $inputs,
            outputs: VALUE,
            mx_fixed: &[],
        }
    };
}

macro_rules! vector_math {
    ($mx:literal, $kiln:literal, $inputs:expr) => {
        Row {
            mx: $mx,
            types: VEC3,
            kiln: "vector_math",
            params: &op($kiln),
            fixed: &[],
            inputs: $inputs,
            outputs: VECTOR_OUT,
            mx_fixed: &[],
        }
    };
}

pub const ROWS: &[Row] = &[
    // Kiln's comparison is MaterialX's conditional choosing 1 or 0.
    Row {
        mx: "ifgreater",
        types: FLOAT,
        kiln: "math",
        params: &op("greater_than"),
        fixed: &[],
        inputs: &[("value1", "a", 1.0), ("value2", "b", 0.0)],
        outputs: VALUE,
        mx_fixed: &[("in1", 1.0), ("in2", 0.0)],
    },
    math!("add", "add", BINARY_0),
    math!("subtract", "subtract", BINARY_0),
    math!("multiply", "multiply", BINARY_1),
    math!("divide", "divide", BINARY_1),
    math!("power", "power", BINARY_1),
    math!("max", "maximum", BINARY_0),
    math!("min", "minimum", BINARY_0),
    math!("modulo", "floored_modulo", BINARY_1),
    math!("sin", "sine", UNARY),
    math!("cos", "cosine", UNARY),
    math!("tan", "tangent", UNARY),
    math!("asin", "arcsine", UNARY),
    math!("acos", "arccosine", UNARY),
    math!("sqrt", "sqrt", UNARY),
    math!("absval", "absolute", UNARY),
    math!("floor", "floor", UNARY),
    math!("ceil", "ceil", UNARY),
    math!("round", "round", UNARY),
    math!("sign", "sign", UNARY),
    math!("exp", "exponent", UNARY),
    math!("atan2", "arctan2", &[("iny", "a", 0.0), ("inx", "b", 1.0)]),
    // MaterialX's invert is `amount - in`.
    math!(
        "invert",
        "subtract",
        &[("amount", "a", 1.0), ("in", "b", 0.0)]
    ),
    vector_math!("add", "add", BINARY_0),
    vector_math!("subtract", "subtract", BINARY_0),
    vector_math!("multiply", "multiply", BINARY_1),
    vector_math!("divide", "divide", BINARY_1),
    vector_math!("max", "maximum", BINARY_0),
    vector_math!("min", "minimum", BINARY_0),
    vector_math!("absval", "absolute", UNARY),
    vector_math!("floor", "floor", UNARY),
    vector_math!("ceil", "ceil", UNARY),
    vector_math!("sin", "sine", UNARY),
    vector_math!("cos", "cosine", UNARY),
    vector_math!("tan", "tangent", UNARY),
    vector_math!(
        "invert",
        "subtract",
        &[("amount", "a", 1.0), ("in", "b", 0.0)]
    ),
    vector_math!("crossproduct", "cross", BINARY_0),
    vector_math!("normalize", "normalize", UNARY),
    Row {
        mx: "dotproduct",
        types: FLOAT,
        kiln: "vector_math",
        params: &op("dot"),
        fixed: &[],
        inputs: BINARY_0,
        outputs: VALUE,
        mx_fixed: &[],
    },
    Row {
        mx: "magnitude",
        types: FLOAT,
        kiln: "vector_math",
        params: &op("length"),
        fixed: &[],
        inputs: UNARY,
        outputs: VALUE,
        mx_fixed: &[],
    },
    Row {
        mx: "distance",
        types: FLOAT,
        kiln: "vector_math",
        params: &op("distance"),
        fixed: &[],
        inputs: BINARY_0,
        outputs: VALUE,
        mx_fixed: &[],
    },
    Row {
        mx: "mix",
        types: FLOAT,
        kiln: "mix_float",
        params: &[("clamp_factor", Fixed::Flag(false))],
        fixed: &[],
        inputs: &[("fg", "b", 0.0), ("bg", "a", 0.0), ("mix", "factor", 0.0)],
        outputs: &[("out", "result")],
        mx_fixed: &[],
    },
    Row {
        mx: "mix",
        types: VECTOR,
        kiln: "mix_vector",
        params: &[("clamp_factor", Fixed::Flag(false))],
        fixed: &[],
        inputs: &[("fg", "b", 0.0), ("bg", "a", 0.0), ("mix", "factor", 0.0)],
        outputs: &[("out", "result")],
        mx_fixed: &[],
    },
    Row {
        mx: "mix",
        types: COLOR,
        kiln: "mix_color",
        params: &[
            ("blend", Fixed::Text("mix")),
            ("clamp_result", Fixed::Flag(false)),
        ],
        fixed: &[],
        inputs: &[("fg", "b", 0.0), ("bg", "a", 0.0), ("mix", "factor", 0.0)],
        outputs: &[("out", "result")],
        mx_fixed: &[],
    },
    Row {
        mx: "clamp",
        types: FLOAT,
        kiln: "clamp",
        params: &[("clamp_type", Fixed::Text("min_max"))],
        fixed: &[],
        inputs: &[
            ("in", "value", 0.0),
            ("low", "min", 0.0),
            ("high", "max", 1.0),
        ],
        outputs: &[("out", "result")],
        mx_fixed: &[],
    },
    Row {
        mx: "smoothstep",
        types: FLOAT,
        kiln: "map_range",
        params: &[
            ("interpolation", Fixed::Text("smoothstep")),
            ("clamp", Fixed::Flag(true)),
        ],
        fixed: &[("to_min", 0.0), ("to_max", 1.0)],
        inputs: &[
            ("in", "value", 0.0),
            ("low", "from_min", 0.0),
            ("high", "from_max", 1.0),
        ],
        outputs: &[("out", "result")],
        mx_fixed: &[],
    },
    Row {
        mx: "remap",
        types: FLOAT,
        kiln: "map_range",
        params: &[
            ("interpolation", Fixed::Text("linear")),
            ("clamp", Fixed::Flag(false)),
        ],
        fixed: &[],
        inputs: &[
            ("in", "value", 0.0),
            ("inlow", "from_min", 0.0),
            ("inhigh", "from_max", 1.0),
            ("outlow", "to_min", 0.0),
            ("outhigh", "to_max", 1.0),
        ],
        outputs: &[("out", "result")],
        mx_fixed: &[],
    },
    Row {
        mx: "normalmap",
        types: VECTOR,
        kiln: "normal_map",
        params: &[],
        fixed: &[],
        inputs: &[("in", "color", 0.5), ("scale", "strength", 1.0)],
        outputs: &[("out", "normal")],
        mx_fixed: &[],
    },
    Row {
        mx: "constant",
        types: FLOAT,
        kiln: "value",
        params: &[],
        fixed: &[],
        inputs: &[("value", "value", 0.0)],
        outputs: VALUE,
        mx_fixed: &[],
    },
    Row {
        mx: "constant",
        types: COLOR,
        kiln: "rgb",
        params: &[],
        fixed: &[],
        inputs: &[("value", "color", 0.0)],
        outputs: &[("out", "color")],
        mx_fixed: &[],
    },
    Row {
        mx: "constant",
        types: VECTOR,
        kiln: "vector",
        params: &[],
        fixed: &[],
        inputs: &[("value", "vector", 0.0)],
        outputs: VECTOR_OUT,
        mx_fixed: &[],
    },
    Row {
        mx: "separate3",
        types: COLOR,
        kiln: "separate_color",
        params: &[("mode", Fixed::Text("rgb"))],
        fixed: &[],
        inputs: &[("in", "color", 0.0)],
        outputs: &[("outr", "red"), ("outg", "green"), ("outb", "blue")],
        mx_fixed: &[],
    },
    Row {
        mx: "separate3",
        types: VECTOR,
        kiln: "separate_xyz",
        params: &[],
        fixed: &[],
        inputs: &[("in", "vector", 0.0)],
        outputs: &[("outx", "x"), ("outy", "y"), ("outz", "z")],
        mx_fixed: &[],
    },
    Row {
        mx: "combine3",
        types: COLOR,
        kiln: "combine_color",
        params: &[("mode", Fixed::Text("rgb"))],
        fixed: &[],
        inputs: &[
            ("in1", "red", 0.0),
            ("in2", "green", 0.0),
            ("in3", "blue", 0.0),
        ],
        outputs: &[("out", "color")],
        mx_fixed: &[],
    },
    Row {
        mx: "combine3",
        types: VECTOR,
        kiln: "combine_xyz",
        params: &[],
        fixed: &[],
        inputs: &[("in1", "x", 0.0), ("in2", "y", 0.0), ("in3", "z", 0.0)],
        outputs: VECTOR_OUT,
        mx_fixed: &[],
    },
];

/// Whether input `input` of Kiln node type `kind` (one the table maps to) is a float;
/// the others are three-channel.
pub fn kiln_input_is_float(kind: &str, input: &str) -> bool {
    match kind {
        "vector_math" => input == "scale",
        "mix_vector" | "mix_color" => input == "factor",
        "normal_map" => input == "strength",
        "rgb" | "vector" | "separate_color" | "separate_xyz" => false,
        _ => true,
    }
}

/// MaterialX input types that differ from the Kiln socket's (a normal map's input is a
/// vector in MaterialX, a colour in Kiln).
pub fn mx_input_type(row: &Row, mx: &str) -> Option<&'static str> {
    match (row.mx, mx) {
        ("normalmap", "in") => Some("vector3"),
        _ => None,
    }
}

/// The row for MaterialX node `category` of type `ty` (see [`Row::types`]) whose fixed
/// inputs have the values `mx_input` gives (`None`: not a constant).
pub fn for_materialx(
    category: &str,
    ty: &str,
    mx_input: impl Fn(&str) -> Option<f32>,
) -> Option<&'static Row> {
    ROWS.iter().find(|r| {
        r.mx == category
            && r.types.contains(&ty)
            && r.mx_fixed.iter().all(|(i, v)| mx_input(i) == Some(*v))
    })
}

/// The MaterialX type of a Kiln socket type.
pub fn mx_type(kiln: &str) -> &'static str {
    match kiln {
        "float" => "float",
        "vec2" => "vector2",
        "color" => "color3",
        "bsdf" => "surfaceshader",
        "volume" => "volumeshader",
        _ => "vector3",
    }
}

/// The Kiln socket type of a MaterialX type (two-component vectors become vectors with
/// z = 0, as Kiln's texture coordinates are); `None` for types no socket carries.
pub fn kiln_type(mx: &str) -> Option<&'static str> {
    Some(match mx {
        "float" | "integer" | "boolean" => "float",
        "color3" | "color4" => "color",
        "vector2" | "vector3" | "vector4" => "vector",
        "surfaceshader" => "bsdf",
        "volumeshader" => "volume",
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_category_and_type_has_at_most_one_row() {
        for (i, a) in ROWS.iter().enumerate() {
            for b in &ROWS[i + 1..] {
                let overlap = a.types.iter().any(|t| b.types.contains(t));
                assert!(!(a.mx == b.mx && overlap), "{} twice", a.mx);
            }
        }
    }
}
