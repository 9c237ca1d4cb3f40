//! Node-graph implementations of Kiln nodes in MaterialX's standard nodes, so that other
//! tools render the `kiln_TYPE` nodes the exporter writes ([`crate::export`]): for each
//! Kiln node (with its parameters; a colour ramp with its stops), a graph computing what
//! Kiln's WGSL does, reading the node definition's inputs by `interfacename`; where Kiln
//! hashes integers (its noises, Brick's tint, White Noise, Object Info's random number),
//! MaterialX's own noises stand in. Kiln nodes without one (Voronoi in other metrics, the
//! image nodes MaterialX reads directly, …) are declared without an implementation
//! (docs/MATERIALX.md lists them).

use std::fmt::Write as _;

use std::collections::BTreeMap;

use kiln_plugin_api::kmat::read::{Input, Param};

/// What feeds a node input in the graph.
#[derive(Clone, Debug)]
pub enum Src {
    /// The node definition's input.
    I(&'static str),
    /// A node's (only) output.
    N(String),
    /// A node's named output.
    O(String, &'static str),
    /// A constant, as MaterialX writes it.
    V(String),
}

fn v(x: f32) -> Src {
    Src::V(format!("{x}"))
}

fn v3(x: f32) -> Src {
    Src::V(format!("{x}, {x}, {x}"))
}

impl Src {
    fn attribute(&self) -> String {
        match self {
            Src::I(name) => format!("interfacename=\"{name}\""),
            Src::N(node) => format!("nodename=\"{node}\""),
            Src::O(node, output) => format!("nodename=\"{node}\" output=\"{output}\""),
            Src::V(value) => format!("value=\"{value}\""),
        }
    }
}

/// A node graph being written.
#[derive(Default)]
pub struct Graph {
    pub text: String,
    count: usize,
    /// MaterialX output name, type, source.
    pub outputs: Vec<(String, String, Src)>,
    /// What besides the parameters the graph depends on (a noise's octave count, from
    /// its constant detail), for the definition's name.
    pub variant: String,
}

impl Graph {
    /// Adds a node of `category` and type `ty` with `inputs` (name, type, source).
    fn node(&mut self, category: &str, ty: &str, inputs: &[(&str, &str, Src)]) -> Src {
        self.count += 1;
        let name = format!("{category}_{}", self.count);
        let _ = writeln!(self.text, "    <{category} name=\"{name}\" type=\"{ty}\">");
        for (input, ty, src) in inputs {
            let _ = writeln!(
                self.text,
                "      <input name=\"{input}\" type=\"{ty}\" {} />",
                src.attribute()
            );
        }
        let _ = writeln!(self.text, "    </{category}>");
        Src::N(name)
    }

    fn binary(&mut self, category: &str, ty: &str, a: Src, b: Src) -> Src {
        self.node(category, ty, &[("in1", ty, a), ("in2", ty, b)])
    }

    fn unary(&mut self, category: &str, ty: &str, a: Src) -> Src {
        self.node(category, ty, &[("in", ty, a)])
    }

    /// `value1 > value2 ? in1 : in2`.
    fn ifgreater(&mut self, ty: &str, value1: Src, value2: Src, in1: Src, in2: Src) -> Src {
        self.node(
            "ifgreater",
            ty,
            &[
                ("value1", "float", value1),
                ("value2", "float", value2),
                ("in1", ty, in1),
                ("in2", ty, in2),
            ],
        )
    }

    /// `x == 0 ? zero : otherwise`, of floats.
    fn if_zero(&mut self, x: Src, zero: Src, otherwise: Src) -> Src {
        let f = "float";
        self.node(
            "ifequal",
            f,
            &[
                ("value1", f, x),
                ("value2", f, v(0.0)),
                ("in1", f, zero),
                ("in2", f, otherwise),
            ],
        )
    }

    /// `bg + (fg - bg) mix`.
    fn mix(&mut self, ty: &str, bg: Src, fg: Src, mix: Src) -> Src {
        self.node(
            "mix",
            ty,
            &[("fg", ty, fg), ("bg", ty, bg), ("mix", "float", mix)],
        )
    }

    fn clamp(&mut self, ty: &str, x: Src, low: Src, high: Src) -> Src {
        self.node(
            "clamp",
            ty,
            &[("in", ty, x), ("low", ty, low), ("high", ty, high)],
        )
    }

    fn output(&mut self, name: &str, ty: &str, src: Src) {
        // An output reads a node (an interface input passes through a `dot`).
        let src = match src {
            Src::I(_) | Src::V(_) => self.unary("dot", ty, src),
            s => s,
        };
        self.outputs.push((name.to_owned(), ty.to_owned(), src));
    }
}

fn text<'a>(params: &'a [(String, Param)], name: &str) -> &'a str {
    params
        .iter()
        .find(|(n, _)| n == name)
        .and_then(|(_, p)| match p {
            Param::Text(t) => Some(t.as_str()),
            _ => None,
        })
        .unwrap_or("")
}

fn flag(params: &[(String, Param)], name: &str) -> bool {
    params
        .iter()
        .any(|(n, p)| n == name && *p == Param::Bool(true))
}

/// The implementation of Kiln node `kind` with `params` (every parameter, defaults
/// included), whose MaterialX outputs are `outputs` (MaterialX name, Kiln name, type);
/// `None` where there is none.
pub fn implement(
    kind: &str,
    params: &[(String, Param)],
    inputs: &BTreeMap<String, Input>,
    outputs: &[(String, String, String)],
) -> Option<Graph> {
    let mut g = Graph::default();
    let out_name = |kiln: &str| {
        outputs
            .iter()
            .find(|(_, k, _)| k == kiln)
            .map(|(m, _, _)| m.clone())
    };
    match kind {
        "math" => {
            let r = math(&mut g, text(params, "operation"))?;
            let r = if flag(params, "clamp") {
                g.clamp("float", r, v(0.0), v(1.0))
            } else {
                r
            };
            g.output(&out_name("value")?, "float", r);
        }
        "vector_math" => {
            let (vector, value) = vector_math(&mut g, text(params, "operation"))?;
            g.output(&out_name("vector")?, "vector3", vector);
            g.output(&out_name("value")?, "float", value);
        }
        "mix_float" | "mix_vector" => {
            let ty = if kind == "mix_float" {
                "float"
            } else {
                "vector3"
            };
            let factor = if flag(params, "clamp_factor") {
                g.clamp("float", Src::I("factor"), v(0.0), v(1.0))
            } else {
                Src::I("factor")
            };
            let r = g.mix(ty, Src::I("a"), Src::I("b"), factor);
            g.output(&out_name("result")?, ty, r);
        }
        "mix_color" => {
            // shaders/nodes/color.wgsl node_mix_color, whose factor is clamped.
            let (a, c) = (Src::I("a"), "color3");
            let blend = text(params, "blend");
            let t = g.clamp("float", Src::I("factor"), v(0.0), v(1.0));
            let r = match blend_target(&mut g, blend) {
                Some(blended) => g.mix(c, a, blended, t),
                None => blend_mode(&mut g, blend, t)?,
            };
            let r = if blend == "exclusion" {
                g.binary("max", c, r, v3(0.0))
            } else {
                r
            };
            let r = if flag(params, "clamp_result") {
                g.clamp(c, r, v3(0.0), v3(1.0))
            } else {
                r
            };
            g.output(&out_name("result")?, c, r);
        }
        "map_range" => {
            let interpolation = text(params, "interpolation");
            let span = g.binary("subtract", "float", Src::I("from_max"), Src::I("from_min"));
            let offset = g.binary("subtract", "float", Src::I("value"), Src::I("from_min"));
            let t = g.binary("divide", "float", offset, span);
            let t = match interpolation {
                "linear" => t,
                "stepped" => {
                    let steps1 = g.binary("add", "float", Src::I("steps"), v(1.0));
                    let scaled = g.binary("multiply", "float", t, steps1);
                    let floored = g.unary("floor", "float", scaled);
                    g.binary("divide", "float", floored, Src::I("steps"))
                }
                "smoothstep" => {
                    let t = g.clamp("float", t, v(0.0), v(1.0));
                    // t² (3 − 2t)
                    let t2 = g.binary("multiply", "float", t.clone(), t.clone());
                    let two_t = g.binary("multiply", "float", t, v(2.0));
                    let k = g.binary("subtract", "float", v(3.0), two_t);
                    g.binary("multiply", "float", t2, k)
                }
                "smootherstep" => {
                    let t = g.clamp("float", t, v(0.0), v(1.0));
                    // t³ (t (6t − 15) + 10)
                    let six_t = g.binary("multiply", "float", t.clone(), v(6.0));
                    let a = g.binary("subtract", "float", six_t, v(15.0));
                    let b = g.binary("multiply", "float", a, t.clone());
                    let k = g.binary("add", "float", b, v(10.0));
                    let t2 = g.binary("multiply", "float", t.clone(), t.clone());
                    let t3 = g.binary("multiply", "float", t2, t);
                    g.binary("multiply", "float", t3, k)
                }
                _ => return None,
            };
            let r = g.mix("float", Src::I("to_min"), Src::I("to_max"), t);
            // Blender clamps the linear and stepped maps only.
            let r = if flag(params, "clamp") && matches!(interpolation, "linear" | "stepped") {
                let low = g.binary("min", "float", Src::I("to_min"), Src::I("to_max"));
                let high = g.binary("max", "float", Src::I("to_min"), Src::I("to_max"));
                g.clamp("float", r, low, high)
            } else {
                r
            };
            g.output(&out_name("result")?, "float", r);
        }
        "separate_color" => {
            let color = match text(params, "mode") {
                "hsv" => g.unary("rgbtohsv", "color3", Src::I("color")),
                _ => Src::I("color"),
            };
            let split = g.node("separate3", "multioutput", &[("in", "color3", color)]);
            let Src::N(split) = split else { return None };
            for (kiln, mx) in [("red", "outr"), ("green", "outg"), ("blue", "outb")] {
                let channel = g.unary("dot", "float", Src::O(split.clone(), mx));
                g.output(&out_name(kiln)?, "float", channel);
            }
        }
        "combine_color" => {
            let joined = g.node(
                "combine3",
                "color3",
                &[
                    ("in1", "float", Src::I("red")),
                    ("in2", "float", Src::I("green")),
                    ("in3", "float", Src::I("blue")),
                ],
            );
            let r = match text(params, "mode") {
                "hsv" => g.unary("hsvtorgb", "color3", joined),
                _ => joined,
            };
            g.output(&out_name("color")?, "color3", r);
        }
        "color_ramp" => {
            let Some((_, Param::Ramp(stops))) = params.iter().find(|(n, _)| n == "stops") else {
                return None;
            };
            let mut stops = stops.clone();
            stops.sort_by(|a, b| a.position.total_cmp(&b.position));
            let first = stops.first()?;
            let interpolation = text(params, "interpolation");
            let rgb = |s: &kiln_plugin_api::kmat::read::Stop| {
                Src::V(format!("{}, {}, {}", s.color[0], s.color[1], s.color[2]))
            };
            let mut color = rgb(first);
            let mut alpha = v(first.color[3]);
            for pair in stops.windows(2) {
                let (p0, p1) = (&pair[0], &pair[1]);
                let t = match interpolation {
                    "constant" => {
                        g.ifgreater("float", Src::I("fac"), v(p1.position), v(1.0), v(0.0))
                    }
                    _ => {
                        let offset = g.binary("subtract", "float", Src::I("fac"), v(p0.position));
                        let span = (p1.position - p0.position).max(1e-6);
                        let t = g.binary("divide", "float", offset, v(span));
                        let t = g.clamp("float", t, v(0.0), v(1.0));
                        if interpolation == "ease" {
                            // t² (3 − 2t)
                            let t2 = g.binary("multiply", "float", t.clone(), t.clone());
                            let two_t = g.binary("multiply", "float", t, v(2.0));
                            let k = g.binary("subtract", "float", v(3.0), two_t);
                            g.binary("multiply", "float", t2, k)
                        } else {
                            t
                        }
                    }
                };
                color = g.mix("color3", color, rgb(p1), t.clone());
                alpha = g.mix("float", alpha, v(p1.color[3]), t);
            }
            g.output(&out_name("color")?, "color3", color);
            g.output(&out_name("alpha")?, "float", alpha);
        }
        "checker_texture" => {
            // In colour 1 where floor(p) sums to an odd number (shaders/nodes/textures.wgsl).
            let scaled = g.node(
                "multiply",
                "vector3",
                &[
                    ("in1", "vector3", Src::I("vector")),
                    ("in2", "float", Src::I("scale")),
                ],
            );
            let nudged = g.binary(
                "add",
                "vector3",
                scaled,
                Src::V("0.000001, 0.000001, 0.000001".into()),
            );
            let q = g.binary(
                "multiply",
                "vector3",
                nudged,
                Src::V("0.999999, 0.999999, 0.999999".into()),
            );
            let cells = g.unary("floor", "vector3", q);
            let sum = g.node(
                "dotproduct",
                "float",
                &[("in1", "vector3", cells), ("in2", "vector3", v3(1.0))],
            );
            let parity = g.binary("modulo", "float", sum, v(2.0));
            let color = g.ifgreater(
                "color3",
                parity.clone(),
                v(0.5),
                Src::I("color1"),
                Src::I("color2"),
            );
            let fac = g.ifgreater("float", parity, v(0.5), v(1.0), v(0.0));
            g.output(&out_name("color")?, "color3", color);
            g.output(&out_name("fac")?, "float", fac);
        }
        "mapping" => {
            let r = mapping(&mut g, text(params, "vector_type"))?;
            g.output(&out_name("vector")?, "vector3", r);
        }
        "gradient_texture" => {
            let t = "vector3";
            let split = g.node("separate3", "multioutput", &[("in", t, Src::I("vector"))]);
            let Src::N(split) = split else { return None };
            let (x, y) = (Src::O(split.clone(), "outx"), Src::O(split, "outy"));
            let f = "float";
            let length = || ("in", t, Src::I("vector"));
            let fac = match text(params, "gradient_type") {
                "linear" => g.unary("dot", f, x),
                "quadratic" => {
                    let r = g.binary("max", f, x, v(0.0));
                    g.binary("multiply", f, r.clone(), r)
                }
                "easing" => {
                    let r = g.clamp(f, x, v(0.0), v(1.0));
                    let t2 = g.binary("multiply", f, r.clone(), r.clone());
                    let a = g.binary("multiply", f, t2.clone(), v(3.0));
                    let b = g.binary("multiply", f, t2, r);
                    let b2 = g.binary("multiply", f, b, v(2.0));
                    g.binary("subtract", f, a, b2)
                }
                "diagonal" => {
                    let s = g.binary("add", f, x, y);
                    g.binary("multiply", f, s, v(0.5))
                }
                "radial" => {
                    let angle = g.node("atan2", f, &[("iny", f, y), ("inx", f, x)]);
                    let turns = g.binary("divide", f, angle, v(std::f32::consts::TAU));
                    g.binary("add", f, turns, v(0.5))
                }
                kind @ ("quadratic_sphere" | "spherical") => {
                    let l = g.node("magnitude", f, &[length()]);
                    let d = g.binary("subtract", f, v(0.999999), l);
                    let r = g.binary("max", f, d, v(0.0));
                    if kind == "spherical" {
                        r
                    } else {
                        g.binary("multiply", f, r.clone(), r)
                    }
                }
                _ => return None,
            };
            grey_outputs(&mut g, fac, out_name("color")?, out_name("fac")?);
        }
        "wave_texture" => {
            // shaders/nodes/textures.wgsl node_wave. Exact without distortion; the
            // distortion's noise is MaterialX's fractal noise standing for Kiln's (as the
            // Noise Texture's implementation).
            let (f, t) = ("float", "vector3");
            let octaves = octaves(inputs)?;
            // A wave whose distortion is a constant 0 (Kiln's default) needs no noise.
            let undistorted = matches!(inputs.get("distortion"), None | Some(Input::Float(0.0)));
            g.variant = if undistorted {
                "undistorted".into()
            } else {
                format!("octaves{octaves}")
            };
            // q = (p · scale + 10⁻⁶) · 0.999999 keeps unit coordinates off the band edges.
            let q = g.node(
                "multiply",
                t,
                &[("in1", t, Src::I("vector")), ("in2", f, Src::I("scale"))],
            );
            let q = g.node("add", t, &[("in1", t, q), ("in2", f, v(0.000001))]);
            let q = g.node("multiply", t, &[("in1", t, q), ("in2", f, v(0.999999))]);
            let axis = match text(params, "direction") {
                "x" => [1.0, 0.0, 0.0],
                "y" => [0.0, 1.0, 0.0],
                "z" => [0.0, 0.0, 1.0],
                "diagonal" => [0.5, 0.5, 0.5],
                _ => return None,
            };
            let n = match text(params, "wave_type") {
                "bands" => {
                    let along = Src::V(format!("{}, {}, {}", axis[0], axis[1], axis[2]));
                    let d = g.node("dotproduct", f, &[("in1", t, q.clone()), ("in2", t, along)]);
                    g.binary("multiply", f, d, v(20.0))
                }
                "rings" => {
                    // The distance from the axis (all three coordinates for diagonal).
                    let mask = match text(params, "direction") {
                        "x" => "0, 1, 1",
                        "y" => "1, 0, 1",
                        "z" => "1, 1, 0",
                        _ => "1, 1, 1",
                    };
                    let m = g.binary("multiply", t, q.clone(), Src::V(mask.into()));
                    let l = g.unary_typed("magnitude", f, t, m);
                    g.binary("multiply", f, l, v(20.0))
                }
                _ => return None,
            };
            let mut n = g.binary("add", f, n, Src::I("phase_offset"));
            if !undistorted {
                let noise_at = g.node(
                    "multiply",
                    t,
                    &[("in1", t, q), ("in2", f, Src::I("detail_scale"))],
                );
                let roughness = g.binary("max", f, Src::I("detail_roughness"), v(0.0));
                let noise = g.node(
                    "fractal3d",
                    f,
                    &[
                        ("amplitude", f, v(1.0)),
                        ("octaves", "integer", Src::V(octaves.to_string())),
                        ("lacunarity", f, v(2.0)),
                        ("diminish", f, roughness),
                        ("position", t, noise_at),
                    ],
                );
                let distorted = g.binary("multiply", f, noise, Src::I("distortion"));
                n = g.binary("add", f, n, distorted);
            }
            let tau = std::f32::consts::TAU;
            let fraction = |g: &mut Graph, x: Src| {
                let fl = g.unary("floor", f, x.clone());
                g.binary("subtract", f, x, fl)
            };
            let w = match text(params, "profile") {
                "saw" => {
                    let turns = g.binary("divide", f, n, v(tau));
                    fraction(&mut g, turns)
                }
                "triangle" => {
                    let turns = g.binary("divide", f, n, v(tau));
                    let shifted = g.binary("add", f, turns.clone(), v(0.5));
                    let fl = g.unary("floor", f, shifted);
                    let d = g.binary("subtract", f, turns, fl);
                    let d = g.unary("absval", f, d);
                    g.binary("multiply", f, d, v(2.0))
                }
                "sine" => {
                    // 0.5 + 0.5 sin(n − π/2), the argument reduced to [0, 2π) as Kiln's.
                    let shifted = g.binary("subtract", f, n, v(std::f32::consts::FRAC_PI_2));
                    let turns = g.binary("divide", f, shifted, v(tau));
                    let turns = fraction(&mut g, turns);
                    let angle = g.binary("multiply", f, turns, v(tau));
                    let s = g.unary("sin", f, angle);
                    let s = g.binary("multiply", f, s, v(0.5));
                    g.binary("add", f, s, v(0.5))
                }
                _ => return None,
            };
            grey_outputs(&mut g, w, out_name("color")?, out_name("fac")?);
        }
        "geometry" => {
            // The outputs MaterialX has nodes for are written as those nodes (the
            // exporter's `coordinate`); this definition serves the others. MaterialX has
            // no geometric normal: the true normal is the shading normal here. The view
            // direction points at the surface, Kiln's incoming away from it.
            let (f, t) = ("float", "vector3");
            let world = || ("space", "string", Src::V("world".into()));
            let view = g.node("viewdirection", t, &[world()]);
            let normal = g.node("normal", t, &[world()]);
            let facing = g.node(
                "dotproduct",
                f,
                &[("in1", t, view.clone()), ("in2", t, normal.clone())],
            );
            let backfacing = g.ifgreater(f, facing, v(0.0), v(1.0), v(0.0));
            let incoming = g.binary("multiply", t, view, v3(-1.0));
            let position = g.node("position", t, &[world()]);
            let tangent = g.node("tangent", t, &[world()]);
            for (kiln, ty, src) in [
                ("position", t, position),
                ("normal", t, normal.clone()),
                ("true_normal", t, normal),
                ("tangent", t, tangent),
                ("incoming", t, incoming),
                ("backfacing", f, backfacing),
            ] {
                g.output(&out_name(kiln)?, ty, src);
            }
        }
        "layer_weight" => {
            // shaders/nodes/inputs.wgsl nd_layer_weight; the view direction points at
            // the surface, Kiln's `wo` away from it.
            let f = "float";
            let c = view_cosine(&mut g, Src::I("normal"));
            let b = g.clamp(f, Src::I("blend"), v(0.0), v(0.99999));
            let one_minus = g.binary("subtract", f, v(1.0), b.clone());
            let eta = g.binary("max", f, one_minus.clone(), v(1e-5));
            let inverse = g.binary("divide", f, v(1.0), eta.clone());
            let eta = g.ifgreater(f, v(0.0), c.clone(), eta, inverse);
            let cos = g.unary("absval", f, c);
            let fresnel = fresnel_dielectric(&mut g, cos.clone(), eta);
            // facing = 1 − |c|^e, e = b < 0.5 ? 2b : 0.5 / (1 − b)
            let twice = g.binary("multiply", f, b.clone(), v(2.0));
            let half = g.binary("divide", f, v(0.5), one_minus);
            let e = g.ifgreater(f, v(0.5), b, twice, half);
            let p = g.binary("power", f, cos, e);
            let facing = g.binary("subtract", f, v(1.0), p);
            g.output(&out_name("fresnel")?, f, fresnel);
            g.output(&out_name("facing")?, f, facing);
        }
        "noise_texture" => {
            // An approximation: MaterialX's fractal noise with Kiln's frequency, octave
            // count, roughness and lacunarity, mapped from [-1, 1] onto [0, 1] as Kiln's
            // noise lies; not Kiln's values, and without distortion.
            let octaves = octaves(inputs)?;
            g.variant = format!("octaves{octaves}");
            let t = "vector3";
            let p = g.node(
                "multiply",
                t,
                &[
                    ("in1", t, Src::I("vector")),
                    ("in2", "float", Src::I("scale")),
                ],
            );
            let noise = |g: &mut Graph, ty: &str, amplitude: Src| {
                g.node(
                    "fractal3d",
                    ty,
                    &[
                        (
                            "amplitude",
                            if ty == "float" { "float" } else { t },
                            amplitude,
                        ),
                        ("octaves", "integer", Src::V(octaves.to_string())),
                        ("lacunarity", "float", Src::I("lacunarity")),
                        ("diminish", "float", Src::I("roughness")),
                        ("position", t, p.clone()),
                    ],
                )
            };
            let fac = noise(&mut g, "float", v(0.5));
            let fac = g.binary("add", "float", fac, v(0.5));
            let fac = g.clamp("float", fac, v(0.0), v(1.0));
            let color = noise(&mut g, "color3", v3(0.5));
            let color = g.binary("add", "color3", color, v3(0.5));
            let color = g.clamp("color3", color, v3(0.0), v3(1.0));
            g.output(&out_name("color")?, "color3", color);
            g.output(&out_name("fac")?, "float", fac);
        }
        "texture_coordinate" => {
            let t = "vector3";
            let position = |g: &mut Graph, space: &str| {
                g.node("position", t, &[("space", "string", Src::V(space.into()))])
            };
            let uv = |g: &mut Graph, index: &str| {
                let uv = g.node(
                    "texcoord",
                    "vector2",
                    &[("index", "integer", Src::V(index.into()))],
                );
                g.unary_typed("convert", t, "vector2", uv)
            };
            // Generated coordinates are the object position in the mesh's bounding
            // box, which MaterialX does not know: the object position stands for them.
            let generated = position(&mut g, "object");
            g.output(&out_name("generated")?, t, generated);
            let normal = g.node("normal", t, &[("space", "string", Src::V("object".into()))]);
            g.output(&out_name("normal")?, t, normal);
            let uv0 = uv(&mut g, "0");
            g.output(&out_name("uv")?, t, uv0);
            let uv1 = uv(&mut g, "1");
            g.output(&out_name("uv1")?, t, uv1);
            let object = position(&mut g, "object");
            g.output(&out_name("object")?, t, object);
            let world = position(&mut g, "world");
            g.output(&out_name("world")?, t, world);
            let view = g.node(
                "viewdirection",
                t,
                &[("space", "string", Src::V("world".into()))],
            );
            let reflection = g.node("reflect", t, &[("in", t, view)]);
            g.output(&out_name("reflection")?, t, reflection);
        }
        "voronoi_texture" => {
            let (distance, color, position) =
                voronoi(&mut g, text(params, "distance"), text(params, "feature"))?;
            g.output(&out_name("distance")?, "float", distance);
            g.output(&out_name("color")?, "color3", color);
            g.output(&out_name("position")?, "vector3", position);
        }
        "brick_texture" => {
            // shaders/nodes/textures.wgsl node_brick, exact but for the brick's tint:
            // Kiln's integer hash of the brick and row has no standard node, so
            // MaterialX's cell noise of (brick, row) stands for it (the same in [0, 1),
            // not the same values). A bias of ±1 saturates the tint: then exact too.
            let (f, t) = ("float", "vector3");
            let q = g.node(
                "multiply",
                t,
                &[("in1", t, Src::I("vector")), ("in2", f, Src::I("scale"))],
            );
            let q = match g.node("separate3", "multioutput", &[("in", t, q)]) {
                Src::N(name) => name,
                _ => unreachable!("a node is named"),
            };
            let (qx, qy) = (Src::O(q.clone(), "outx"), Src::O(q, "outy"));
            let rh = g.binary("max", f, Src::I("row_height"), v(1e-6));
            let row = g.binary("divide", f, qy.clone(), rh.clone());
            let row = g.unary("floor", f, row);
            let rounded = |g: &mut Graph, x: &'static str| {
                let h = g.binary("add", f, Src::I(x), v(0.5));
                g.unary("floor", f, h)
            };
            let offset_frequency = rounded(&mut g, "offset_frequency");
            let squash_frequency = rounded(&mut g, "squash_frequency");
            // `when` where the row is a multiple of `frequency` and neither frequency is
            // 0, `otherwise` elsewhere.
            let every = |g: &mut Graph, frequency: Src, when: Src, otherwise: Src| {
                let m = g.binary("modulo", f, row.clone(), frequency);
                let r = g.if_zero(m, when, otherwise.clone());
                let r = g.if_zero(squash_frequency.clone(), otherwise.clone(), r);
                g.if_zero(offset_frequency.clone(), otherwise, r)
            };
            let squashed = g.binary("multiply", f, Src::I("brick_width"), Src::I("squash"));
            let bw = every(
                &mut g,
                squash_frequency.clone(),
                squashed,
                Src::I("brick_width"),
            );
            let shift = g.binary("multiply", f, bw.clone(), Src::I("offset"));
            let shift = every(&mut g, offset_frequency.clone(), shift, v(0.0));
            let bw = g.binary("max", f, bw, v(1e-6));
            let shifted = g.binary("add", f, qx, shift);
            let brick = g.binary("divide", f, shifted.clone(), bw.clone());
            let brick = g.unary("floor", f, brick);
            let start = g.binary("multiply", f, bw.clone(), brick.clone());
            let x = g.binary("subtract", f, shifted, start);
            let bottom = g.binary("multiply", f, rh.clone(), row.clone());
            let y = g.binary("subtract", f, qy, bottom);
            let to_right = g.binary("subtract", f, bw, x.clone());
            let to_top = g.binary("subtract", f, rh, y.clone());
            let near = g.binary("min", f, x, y);
            let far = g.binary("min", f, to_right, to_top);
            let min_dist = g.binary("min", f, near, far);
            // Mortar where min_dist < mortar_size: 1 without smoothing, else a smoothstep.
            let ratio = g.binary("divide", f, min_dist.clone(), Src::I("mortar_size"));
            let ratio = g.if_zero(Src::I("mortar_size"), v(0.0), ratio);
            let inside = g.binary("subtract", f, v(1.0), ratio);
            let stepped = g.binary("divide", f, inside, Src::I("mortar_smooth"));
            let stepped = g.node(
                "smoothstep",
                f,
                &[("in", f, stepped), ("low", f, v(0.0)), ("high", f, v(1.0))],
            );
            let mortar = g.if_zero(Src::I("mortar_smooth"), v(1.0), stepped);
            let fac = g.ifgreater(f, Src::I("mortar_size"), min_dist, mortar, v(0.0));
            let cell = g.node("combine2", "vector2", &[("in1", f, brick), ("in2", f, row)]);
            let noise = g.node("cellnoise2d", f, &[("texcoord", "vector2", cell)]);
            let tint = g.binary("add", f, noise, Src::I("bias"));
            let tint = g.clamp(f, tint, v(0.0), v(1.0));
            let c = "color3";
            let brick_color = g.mix(c, Src::I("color1"), Src::I("color2"), tint);
            let color = g.mix(c, brick_color, Src::I("mortar"), fac.clone());
            g.output(&out_name("color")?, c, color);
            g.output(&out_name("fac")?, f, fac);
        }
        "white_noise_texture" => {
            // An approximation, as MaterialX's randomfloat: Kiln hashes the bits of the
            // position, MaterialX's cell noise its floor, so the position is scaled by
            // 4096 first. Equal in distribution (uniform in [0, 1), one value per point
            // of a floored input), not in value.
            let t = "vector3";
            let p = g.binary("multiply", t, Src::I("vector"), v3(4096.0));
            let noise = |g: &mut Graph, offset: [f32; 3]| {
                let at = g.binary(
                    "add",
                    t,
                    p.clone(),
                    Src::V(format!("{}, {}, {}", offset[0], offset[1], offset[2])),
                );
                g.node("cellnoise3d", "float", &[("position", t, at)])
            };
            let value = noise(&mut g, [0.0; 3]);
            let channels = [
                noise(&mut g, [65536.0, 0.0, 0.0]),
                noise(&mut g, [0.0, 65536.0, 0.0]),
                noise(&mut g, [0.0, 0.0, 65536.0]),
            ];
            let color = g.node(
                "combine3",
                "color3",
                &[
                    ("in1", "float", channels[0].clone()),
                    ("in2", "float", channels[1].clone()),
                    ("in3", "float", channels[2].clone()),
                ],
            );
            g.output(&out_name("value")?, "float", value);
            g.output(&out_name("color")?, "color3", color);
        }
        "object_info" => {
            // The instance's origin exactly; its random number, which MaterialX has no
            // notion of, as a cell noise of that origin (one value per instance, uniform
            // in [0, 1), not Kiln's).
            let t = "vector3";
            let location = g.node(
                "transformpoint",
                t,
                &[
                    ("in", t, v3(0.0)),
                    ("fromspace", "string", Src::V("object".into())),
                    ("tospace", "string", Src::V("world".into())),
                ],
            );
            let at = g.binary("multiply", t, location.clone(), v3(4096.0));
            let random = g.node("cellnoise3d", "float", &[("position", t, at)]);
            g.output(&out_name("random")?, "float", random);
            g.output(&out_name("location")?, t, location);
        }
        "volume_absorption" | "volume_scatter" | "principled_volume" => {
            // shaders/nodes/volume.wgsl's coefficients as MaterialX's VDF (absorption and
            // scattering per unit length, Henyey–Greenstein anisotropy) and EDF
            // (emission per unit length): exact.
            volume(&mut g, kind, &out_name("volume")?);
        }
        "fresnel" => {
            // shaders/nodes/inputs.wgsl nd_fresnel: seen from behind, the interface is
            // crossed the other way.
            let f = "float";
            let c = view_cosine(&mut g, Src::I("normal"));
            let eta = g.binary("max", f, Src::I("ior"), v(1e-5));
            let inverse = g.binary("divide", f, v(1.0), eta.clone());
            let eta = g.ifgreater(f, v(0.0), c.clone(), inverse, eta);
            let cos = g.unary("absval", f, c);
            let r = fresnel_dielectric(&mut g, cos, eta);
            g.output(&out_name("fac")?, f, r);
        }
        "invert" => {
            let c = "color3";
            let inverse = g.binary("subtract", c, v3(1.0), Src::I("color"));
            let r = g.mix(c, Src::I("color"), inverse, Src::I("fac"));
            g.output(&out_name("color")?, c, r);
        }
        "gamma" => {
            // Only positive channels are raised; gamma 0 gives white.
            let c = "color3";
            let base = g.binary("max", c, Src::I("color"), v3(1e-30));
            let raised = g.node(
                "power",
                c,
                &[("in1", c, base), ("in2", "float", Src::I("gamma"))],
            );
            let split = |g: &mut Graph, x: Src| {
                let s = g.node("separate3", "multioutput", &[("in", c, x)]);
                let Src::N(s) = s else { unreachable!("a node") };
                s
            };
            let (color, powered) = (split(&mut g, Src::I("color")), split(&mut g, raised));
            let mut channels = Vec::new();
            for o in ["outr", "outg", "outb"] {
                channels.push(g.ifgreater(
                    "float",
                    Src::O(color.clone(), o),
                    v(0.0),
                    Src::O(powered.clone(), o),
                    Src::O(color.clone(), o),
                ));
            }
            let joined = g.node(
                "combine3",
                c,
                &[
                    ("in1", "float", channels[0].clone()),
                    ("in2", "float", channels[1].clone()),
                    ("in3", "float", channels[2].clone()),
                ],
            );
            let r = g.node(
                "ifequal",
                c,
                &[
                    ("value1", "float", Src::I("gamma")),
                    ("value2", "float", v(0.0)),
                    ("in1", c, v3(1.0)),
                    ("in2", c, joined),
                ],
            );
            g.output(&out_name("color")?, c, r);
        }
        "brightness_contrast" => {
            // max((1 + contrast) c + bright − contrast / 2, 0)
            let (c, f) = ("color3", "float");
            let a = g.binary("add", f, Src::I("contrast"), v(1.0));
            let half = g.binary("multiply", f, Src::I("contrast"), v(0.5));
            let b = g.binary("subtract", f, Src::I("bright"), half);
            let scaled = g.node("multiply", c, &[("in1", c, Src::I("color")), ("in2", f, a)]);
            let shifted = g.node("add", c, &[("in1", c, scaled), ("in2", f, b)]);
            let r = g.binary("max", c, shifted, v3(0.0));
            g.output(&out_name("color")?, c, r);
        }
        "rgb_to_bw" => {
            let c = g.unary_typed("convert", "vector3", "color3", Src::I("color"));
            let r = g.node(
                "dotproduct",
                "float",
                &[
                    ("in1", "vector3", c),
                    ("in2", "vector3", Src::V("0.2126, 0.7152, 0.0722".into())),
                ],
            );
            g.output(&out_name("value")?, "float", r);
        }
        "hue_saturation_value" => {
            let (c, f) = ("color3", "float");
            let hsv = g.unary("rgbtohsv", c, Src::I("color"));
            let s = g.node("separate3", "multioutput", &[("in", c, hsv)]);
            let Src::N(s) = s else { return None };
            let h = g.binary("add", f, Src::O(s.clone(), "outr"), Src::I("hue"));
            let h = g.binary("add", f, h, v(0.5));
            let fl = g.unary("floor", f, h.clone());
            let h = g.binary("subtract", f, h, fl);
            let sat = g.binary(
                "multiply",
                f,
                Src::O(s.clone(), "outg"),
                Src::I("saturation"),
            );
            let sat = g.clamp(f, sat, v(0.0), v(1.0));
            let val = g.binary("multiply", f, Src::O(s, "outb"), Src::I("value"));
            let joined = g.node(
                "combine3",
                c,
                &[("in1", f, h), ("in2", f, sat), ("in3", f, val)],
            );
            let shifted = g.unary("hsvtorgb", c, joined);
            let r = g.mix(c, Src::I("color"), shifted, Src::I("fac"));
            let r = g.binary("max", c, r, v3(0.0));
            g.output(&out_name("color")?, c, r);
        }
        "vertex_color" => {
            let colour = g.node(
                "geomcolor",
                "color4",
                &[("index", "integer", Src::V("0".into()))],
            );
            let rgb = g.unary_typed("convert", "color3", "color4", colour.clone());
            let alpha = g.node(
                "extract",
                "float",
                &[
                    ("in", "color4", colour),
                    ("index", "integer", Src::V("3".into())),
                ],
            );
            g.output(&out_name("color")?, "color3", rgb);
            g.output(&out_name("alpha")?, "float", alpha);
        }
        "bump" => {
            // An approximation: MaterialX derives the slope of the height in texture
            // space (heighttonormal), Kiln in world space by two extra evaluations.
            let f = "float";
            let scale = if flag(params, "invert") {
                g.binary("multiply", f, Src::I("distance"), v(-1.0))
            } else {
                Src::I("distance")
            };
            let tangent = g.node(
                "heighttonormal",
                "vector3",
                &[("in", f, Src::I("height")), ("scale", f, scale)],
            );
            let n = g.node(
                "normalmap",
                "vector3",
                &[
                    ("in", "vector3", tangent),
                    ("scale", f, Src::I("strength")),
                    ("normal", "vector3", Src::I("normal")),
                ],
            );
            g.output(&out_name("normal")?, "vector3", n);
        }
        _ => return None,
    }
    Some(g)
}

/// Blender's scalar math (shaders/nodes/math.wgsl) on inputs `a`, `b`, `c`.
fn math(g: &mut Graph, op: &str) -> Option<Src> {
    let f = "float";
    let (a, b, c) = (Src::I("a"), Src::I("b"), Src::I("c"));
    Some(match op {
        "add" => g.binary("add", f, a, b),
        "subtract" => g.binary("subtract", f, a, b),
        "multiply" => g.binary("multiply", f, a, b),
        // Division by zero gives 0.
        "divide" => {
            let q = g.binary("divide", f, a, b.clone());
            g.if_zero(b, v(0.0), q)
        }
        "multiply_add" => {
            let p = g.binary("multiply", f, a, b);
            g.binary("add", f, p, c)
        }
        "power" => g.binary("power", f, a, b),
        "logarithm" => {
            let la = g.unary("ln", f, a);
            let lb = g.unary("ln", f, b);
            g.binary("divide", f, la, lb)
        }
        "sqrt" => g.unary("sqrt", f, a),
        "inverse_sqrt" => {
            let s = g.unary("sqrt", f, a);
            g.binary("divide", f, v(1.0), s)
        }
        "absolute" => g.unary("absval", f, a),
        "exponent" => g.unary("exp", f, a),
        "minimum" => g.binary("min", f, a, b),
        "maximum" => g.binary("max", f, a, b),
        "less_than" => g.ifgreater(f, b, a, v(1.0), v(0.0)),
        "greater_than" => g.ifgreater(f, a, b, v(1.0), v(0.0)),
        "sign" => g.unary("sign", f, a),
        "compare" => {
            let d = g.binary("subtract", f, a, b);
            let d = g.unary("absval", f, d);
            g.ifgreater(f, d, c, v(0.0), v(1.0))
        }
        "round" => {
            let h = g.binary("add", f, a, v(0.5));
            g.unary("floor", f, h)
        }
        "floor" => g.unary("floor", f, a),
        "ceil" => g.unary("ceil", f, a),
        "truncate" => trunc(g, a),
        "fraction" => {
            let fl = g.unary("floor", f, a.clone());
            g.binary("subtract", f, a, fl)
        }
        "truncated_modulo" => truncated_modulo(g, a, b),
        "floored_modulo" => g.binary("modulo", f, a, b),
        "snap" => {
            let q = g.binary("divide", f, a, b.clone());
            let fl = g.unary("floor", f, q);
            g.binary("multiply", f, fl, b)
        }
        "sine" => g.unary("sin", f, a),
        "cosine" => g.unary("cos", f, a),
        "tangent" => g.unary("tan", f, a),
        "arcsine" => g.unary("asin", f, a),
        "arccosine" => g.unary("acos", f, a),
        "arctangent" => g.node("atan2", f, &[("iny", f, a), ("inx", f, v(1.0))]),
        "arctan2" => g.node("atan2", f, &[("iny", f, a), ("inx", f, b)]),
        "radians" => g.binary("multiply", f, a, v(std::f32::consts::PI / 180.0)),
        "wrap" => wrap(g, a, b, c),
        // |fract((a − b) / 2b) · 2b − b|; 0 where b is 0.
        "pingpong" => {
            let twice = g.binary("multiply", f, b.clone(), v(2.0));
            let d = g.binary("subtract", f, a, b.clone());
            let t = g.binary("divide", f, d, twice.clone());
            let fl = g.unary("floor", f, t.clone());
            let fr = g.binary("subtract", f, t, fl);
            let s = g.binary("multiply", f, fr, twice);
            let s = g.binary("subtract", f, s, b.clone());
            let r = g.unary("absval", f, s);
            g.if_zero(b, v(0.0), r)
        }
        "smooth_min" => smooth_min(g, a, b, c),
        "smooth_max" => {
            let na = g.binary("multiply", f, a, v(-1.0));
            let nb = g.binary("multiply", f, b, v(-1.0));
            let m = smooth_min(g, na, nb, c);
            g.binary("multiply", f, m, v(-1.0))
        }
        op @ ("sinh" | "cosh" | "tanh") => {
            // From exponentials; tanh of |x| > 10 is its sign (as Kiln's).
            let x = if op == "tanh" {
                g.clamp(f, a, v(-10.0), v(10.0))
            } else {
                a
            };
            let ep = g.unary("exp", f, x.clone());
            let nx = g.binary("multiply", f, x, v(-1.0));
            let en = g.unary("exp", f, nx);
            let sinh = g.binary("subtract", f, ep.clone(), en.clone());
            let cosh = g.binary("add", f, ep, en);
            match op {
                "sinh" => g.binary("multiply", f, sinh, v(0.5)),
                "cosh" => g.binary("multiply", f, cosh, v(0.5)),
                _ => g.binary("divide", f, sinh, cosh),
            }
        }
        "degrees" => g.binary("multiply", f, a, v(180.0 / std::f32::consts::PI)),
        _ => return None,
    })
}

/// Blender's smooth minimum: `min(a, b) − h³ k / 6`, `h = max(k − |a − b|, 0) / k`;
/// the minimum where k is 0.
fn smooth_min(g: &mut Graph, a: Src, b: Src, k: Src) -> Src {
    let f = "float";
    let d = g.binary("subtract", f, a.clone(), b.clone());
    let d = g.unary("absval", f, d);
    let h = g.binary("subtract", f, k.clone(), d);
    let h = g.binary("max", f, h, v(0.0));
    let h = g.binary("divide", f, h, k.clone());
    let h2 = g.binary("multiply", f, h.clone(), h.clone());
    let h3 = g.binary("multiply", f, h2, h);
    let t = g.binary("multiply", f, h3, k.clone());
    let t = g.binary("multiply", f, t, v(1.0 / 6.0));
    let m = g.binary("min", f, a, b);
    let smooth = g.binary("subtract", f, m.clone(), t);
    g.if_zero(k, m, smooth)
}

/// The cosine between `normal` and the direction toward the viewer (Kiln's `wo`; the
/// view direction points at the surface).
fn view_cosine(g: &mut Graph, normal: Src) -> Src {
    let (f, t) = ("float", "vector3");
    let view = g.node(
        "viewdirection",
        t,
        &[("space", "string", Src::V("world".into()))],
    );
    let c = g.node("dotproduct", f, &[("in1", t, view), ("in2", t, normal)]);
    g.binary("multiply", f, c, v(-1.0))
}

/// The Fresnel reflectance of a dielectric at cosine `cos` and relative index `eta`
/// (Kiln's `fresnel_dielectric`); 1 past total internal reflection.
fn fresnel_dielectric(g: &mut Graph, cos: Src, eta: Src) -> Src {
    let f = "float";
    let c2 = g.binary("multiply", f, cos.clone(), cos.clone());
    let e2 = g.binary("multiply", f, eta.clone(), eta);
    let g2 = g.binary("add", f, e2, c2);
    let g2 = g.binary("subtract", f, g2, v(1.0));
    let root = g.binary("max", f, g2.clone(), v(0.0));
    let root = g.unary("sqrt", f, root);
    let gm = g.binary("subtract", f, root.clone(), cos.clone());
    let gp = g.binary("add", f, root, cos.clone());
    let a = g.binary("divide", f, gm.clone(), gp.clone());
    let num = g.binary("multiply", f, cos.clone(), gp);
    let num = g.binary("subtract", f, num, v(1.0));
    let den = g.binary("multiply", f, cos, gm);
    let den = g.binary("add", f, den, v(1.0));
    let b = g.binary("divide", f, num, den);
    let a2 = g.binary("multiply", f, a.clone(), a);
    let b2 = g.binary("multiply", f, b.clone(), b);
    let b2 = g.binary("add", f, b2, v(1.0));
    let r = g.binary("multiply", f, a2, b2);
    let r = g.binary("multiply", f, r, v(0.5));
    g.ifgreater(f, g2, v(0.0), r, v(1.0))
}

/// A texture's value clamped to [0, 1], as its `fac` and its grey `color`.
fn grey_outputs(g: &mut Graph, value: Src, color: String, fac: String) {
    let value = g.clamp("float", value, v(0.0), v(1.0));
    let grey = g.unary_typed("convert", "color3", "float", value.clone());
    g.output(&color, "color3", grey);
    g.output(&fac, "float", value);
}

/// The octaves of Kiln's fractal noise from a constant `detail` input (Kiln's default 2):
/// `floor(clamp(detail, 0, 15)) + 1`; None for a connected detail.
fn octaves(inputs: &BTreeMap<String, Input>) -> Option<i32> {
    let detail = match inputs.get("detail") {
        Some(Input::Float(d)) => *d,
        None => 2.0,
        _ => return None,
    };
    Some(detail.clamp(0.0, 15.0).floor() as i32 + 1)
}

/// Cycles' `wrapf(value, max, min)`: value − range · floor((value − min) / range), range =
/// max − min; min where the range is empty.
fn wrap(g: &mut Graph, value: Src, max: Src, min: Src) -> Src {
    let f = "float";
    let range = g.binary("subtract", f, max, min.clone());
    let from = g.binary("subtract", f, value.clone(), min.clone());
    let q = g.binary("divide", f, from, range.clone());
    let fl = g.unary("floor", f, q);
    let p = g.binary("multiply", f, range.clone(), fl);
    let wrapped = g.binary("subtract", f, value, p);
    g.if_zero(range, min, wrapped)
}

/// C's `fmodf` (the remainder truncated toward zero): a − b · trunc(a / b); 0 where b is 0.
fn truncated_modulo(g: &mut Graph, a: Src, b: Src) -> Src {
    let f = "float";
    let q = g.binary("divide", f, a.clone(), b.clone());
    let t = trunc(g, q);
    let p = g.binary("multiply", f, b.clone(), t);
    let r = g.binary("subtract", f, a, p);
    g.if_zero(b, v(0.0), r)
}

/// A volume shader node (shaders/nodes/volume.wgsl) as MaterialX's `volume` of a VDF and,
/// for the Principled Volume, a uniform EDF: output `output`.
fn volume(g: &mut Graph, kind: &str, output: &str) {
    let (f, t, c) = ("float", "vector3", "color3");
    let density = g.binary("max", f, Src::I("density"), v(0.0));
    let times_density = |g: &mut Graph, x: Src| {
        let x = g.node("multiply", c, &[("in1", c, x), ("in2", f, density.clone())]);
        g.unary_typed("convert", t, c, x)
    };
    let anisotropy = |g: &mut Graph| g.clamp(f, Src::I("anisotropy"), v(-0.999), v(0.999));
    let mut closures = Vec::new();
    match kind {
        "volume_absorption" => {
            let colour = g.clamp(c, Src::I("color"), v3(0.0), v3(1.0));
            let lost = g.binary("subtract", c, v3(1.0), colour);
            let absorption = times_density(g, lost);
            let vdf = g.node("absorption_vdf", "VDF", &[("absorption", t, absorption)]);
            closures.push(("vdf", "VDF", vdf));
        }
        "volume_scatter" => {
            let colour = g.binary("max", c, Src::I("color"), v3(0.0));
            let scattering = times_density(g, colour);
            let anisotropy = anisotropy(g);
            let vdf = g.node(
                "anisotropic_vdf",
                "VDF",
                &[("scattering", t, scattering), ("anisotropy", f, anisotropy)],
            );
            closures.push(("vdf", "VDF", vdf));
        }
        _ => {
            let colour = g.binary("max", c, Src::I("color"), v3(0.0));
            let tint = g.binary("max", c, Src::I("absorption_color"), v3(0.0));
            // MaterialX has no square root of a colour.
            let tint = g.node("power", c, &[("in1", c, tint), ("in2", f, v(0.5))]);
            let tint = g.binary("subtract", c, v3(1.0), tint);
            let tint = g.binary("max", c, tint, v3(0.0));
            let lost = g.binary("subtract", c, v3(1.0), colour.clone());
            let lost = g.binary("max", c, lost, v3(0.0));
            let lost = g.binary("multiply", c, lost, tint);
            let absorption = times_density(g, lost);
            let scattering = times_density(g, colour);
            let anisotropy = anisotropy(g);
            let vdf = g.node(
                "anisotropic_vdf",
                "VDF",
                &[
                    ("absorption", t, absorption),
                    ("scattering", t, scattering),
                    ("anisotropy", f, anisotropy),
                ],
            );
            let strength = g.binary("max", f, Src::I("emission_strength"), v(0.0));
            let emission = g.binary("max", c, Src::I("emission_color"), v3(0.0));
            let emission = g.node("multiply", c, &[("in1", c, emission), ("in2", f, strength)]);
            let edf = g.node("uniform_edf", "EDF", &[("color", c, emission)]);
            closures.push(("vdf", "VDF", vdf));
            closures.push(("edf", "EDF", edf));
        }
    }
    let shader = g.node("volume", "volumeshader", &closures);
    g.output(output, "volumeshader", shader);
}

/// The colour a Mix node's blend mode mixes toward by the factor, for the modes that are
/// such a mix (`a + t (blended − a)`); `None` for the others.
fn blend_target(g: &mut Graph, mode: &str) -> Option<Src> {
    let (a, b, c) = (Src::I("a"), Src::I("b"), "color3");
    Some(match mode {
        "mix" => b,
        "multiply" => g.binary("multiply", c, a, b),
        "add" => g.binary("add", c, a, b),
        "subtract" => g.binary("subtract", c, a, b),
        "darken" => g.binary("min", c, a, b),
        "lighten" => g.binary("max", c, a, b),
        "difference" => {
            let d = g.binary("subtract", c, a, b);
            g.unary("absval", c, d)
        }
        "screen" => {
            let ia = g.binary("subtract", c, v3(1.0), a);
            let ib = g.binary("subtract", c, v3(1.0), b);
            let p = g.binary("multiply", c, ia, ib);
            g.binary("subtract", c, v3(1.0), p)
        }
        "exclusion" => {
            let s = g.binary("add", c, a.clone(), b.clone());
            let p = g.binary("multiply", c, a, b);
            let p2 = g.binary("multiply", c, p, v3(2.0));
            g.binary("subtract", c, s, p2)
        }
        "linear_light" => {
            let b2 = g.binary("multiply", c, b, v3(2.0));
            let s = g.binary("add", c, a, b2);
            g.binary("subtract", c, s, v3(1.0))
        }
        _ => return None,
    })
}

/// The Mix node's other blend modes by factor `t` (already clamped), as
/// shaders/nodes/color.wgsl computes them: per channel (overlay, dodge, burn), soft
/// light, and the HSV modes (hue, saturation, value, color); divide, which leaves a
/// channel alone where b's is 0.
fn blend_mode(g: &mut Graph, mode: &str, t: Src) -> Option<Src> {
    let (a, b, c, f) = (Src::I("a"), Src::I("b"), "color3", "float");
    let tm = g.binary("subtract", f, v(1.0), t.clone());
    let per_channel = |g: &mut Graph, op: &dyn Fn(&mut Graph, Src, Src) -> Src| {
        let vectors = [a.clone(), b.clone()].map(|x| g.unary_typed("convert", "vector3", c, x));
        let r = per_component(g, &vectors, |g, ab| op(g, ab[0].clone(), ab[1].clone()));
        g.unary_typed("convert", c, "vector3", r)
    };
    // The hue, saturation and value of a colour.
    let hsv = |g: &mut Graph, x: Src| {
        let hsv = g.unary("rgbtohsv", c, x);
        match g.node("separate3", "multioutput", &[("in", c, hsv)]) {
            Src::N(s) => ["outr", "outg", "outb"].map(|o| Src::O(s.clone(), o)),
            _ => unreachable!("a node is named"),
        }
    };
    let rgb = |g: &mut Graph, [h, s, v]: [Src; 3]| {
        let joined = g.node(
            "combine3",
            c,
            &[("in1", f, h), ("in2", f, s), ("in3", f, v)],
        );
        g.unary("hsvtorgb", c, joined)
    };
    let lerp = |g: &mut Graph, x: Src, y: Src| {
        let a = g.binary("multiply", f, tm.clone(), x);
        let b = g.binary("multiply", f, t.clone(), y);
        g.binary("add", f, a, b)
    };
    Some(match mode {
        "overlay" => per_channel(g, &|g, a, b| {
            // a < 0.5: a (tm + 2 t b); else 1 − (tm + 2 t (1 − b)) (1 − a).
            let t2 = g.binary("multiply", f, t.clone(), v(2.0));
            let low = g.binary("multiply", f, t2.clone(), b.clone());
            let low = g.binary("add", f, tm.clone(), low);
            let low = g.binary("multiply", f, a.clone(), low);
            let ib = g.binary("subtract", f, v(1.0), b);
            let high = g.binary("multiply", f, t2, ib);
            let high = g.binary("add", f, tm.clone(), high);
            let ia = g.binary("subtract", f, v(1.0), a.clone());
            let high = g.binary("multiply", f, high, ia);
            let high = g.binary("subtract", f, v(1.0), high);
            g.ifgreater(f, v(0.5), a, low, high)
        }),
        "dodge" => per_channel(g, &|g, a, b| {
            // a where a = 0; 1 where 1 − t b ≤ 0; else min(a / (1 − t b), 1).
            let tb = g.binary("multiply", f, t.clone(), b);
            let d = g.binary("subtract", f, v(1.0), tb);
            let q = g.binary("divide", f, a.clone(), d.clone());
            let q = g.binary("min", f, q, v(1.0));
            let r = g.ifgreater(f, d, v(0.0), q, v(1.0));
            g.if_zero(a.clone(), a, r)
        }),
        "divide" => per_channel(g, &|g, a, b| {
            // a where b = 0; else tm a + t a / b.
            let q = g.binary("divide", f, a.clone(), b.clone());
            let r = lerp(g, a.clone(), q);
            g.if_zero(b, a, r)
        }),
        "burn" => per_channel(g, &|g, a, b| {
            // 0 where 1 − t + t b ≤ 0; else clamp(1 − (1 − a) / (1 − t + t b), 0, 1).
            let tb = g.binary("multiply", f, t.clone(), b);
            let d = g.binary("add", f, tm.clone(), tb);
            let ia = g.binary("subtract", f, v(1.0), a);
            let q = g.binary("divide", f, ia, d.clone());
            let q = g.binary("subtract", f, v(1.0), q);
            let q = g.clamp(f, q, v(0.0), v(1.0));
            g.ifgreater(f, d, v(0.0), q, v(0.0))
        }),
        "soft_light" => {
            // tm a + t ((1 − a) b a + a (1 − (1 − b)(1 − a))).
            let ia = g.binary("subtract", c, v3(1.0), a.clone());
            let ib = g.binary("subtract", c, v3(1.0), b.clone());
            let screen = g.binary("multiply", c, ib, ia.clone());
            let screen = g.binary("subtract", c, v3(1.0), screen);
            let x = g.binary("multiply", c, ia, b);
            let x = g.binary("multiply", c, x, a.clone());
            let y = g.binary("multiply", c, a.clone(), screen);
            let soft = g.binary("add", c, x, y);
            g.mix(c, a, soft, t)
        }
        "hue" | "color" => {
            // Nothing where b is grey (no hue to give).
            let [hb, sb, _] = hsv(g, b.clone());
            let [_, sa, va] = hsv(g, a.clone());
            let s = if mode == "hue" { sa } else { sb.clone() };
            let shifted = rgb(g, [hb, s, va]);
            let r = g.mix(c, a.clone(), shifted, t.clone());
            g.node(
                "ifequal",
                c,
                &[
                    ("value1", f, sb),
                    ("value2", f, v(0.0)),
                    ("in1", c, a),
                    ("in2", c, r),
                ],
            )
        }
        "saturation" => {
            // Nothing where a is grey (no hue to saturate).
            let [ha, sa, va] = hsv(g, a.clone());
            let [_, sb, _] = hsv(g, b);
            let s = lerp(g, sa.clone(), sb);
            let r = rgb(g, [ha, s, va]);
            g.node(
                "ifequal",
                c,
                &[
                    ("value1", f, sa),
                    ("value2", f, v(0.0)),
                    ("in1", c, a),
                    ("in2", c, r),
                ],
            )
        }
        "value" => {
            let [ha, sa, va] = hsv(g, a);
            let [_, _, vb] = hsv(g, b);
            let value = lerp(g, va, vb);
            rgb(g, [ha, sa, value])
        }
        _ => return None,
    })
}

/// Voronoi F1 or F2 in `metric` (shaders/nodes/textures.wgsl node_voronoi): the 27 cells
/// around the point searched node by node as Kiln's kernel searches them, each cell's
/// feature point at its corner plus a random offset times the randomness. Kiln's offsets
/// hash the cell's bits, which no standard node does, so MaterialX's cell noise gives
/// them: exact at randomness 0, the same distribution otherwise; the colour is the chosen
/// cell's offset. Smooth F1 (a blend over 125 cells in Kiln) is F1 here. Returns the
/// distance, colour and position.
fn voronoi(g: &mut Graph, metric: &str, feature: &str) -> Option<(Src, Src, Src)> {
    let (f, t) = ("float", "vector3");
    let second = match feature {
        "f1" | "smooth_f1" => false,
        "f2" => true,
        _ => return None,
    };
    let exponent = g.binary("max", f, Src::I("exponent"), v(0.05));
    let inverse = g.binary("divide", f, v(1.0), exponent.clone());
    let distance = |g: &mut Graph, d: Src| -> Option<Src> {
        Some(match metric {
            "euclidean" => g.unary_typed("magnitude", f, t, d),
            "manhattan" => {
                let a = g.unary("absval", t, d);
                g.node("dotproduct", f, &[("in1", t, a), ("in2", t, v3(1.0))])
            }
            "chebyshev" => {
                let a = g.unary("absval", t, d);
                let Src::N(a) = g.node("separate3", "multioutput", &[("in", t, a)]) else {
                    unreachable!("a node is named")
                };
                let xy = g.binary(
                    "max",
                    f,
                    Src::O(a.clone(), "outx"),
                    Src::O(a.clone(), "outy"),
                );
                g.binary("max", f, xy, Src::O(a, "outz"))
            }
            "minkowski" => {
                let a = g.unary("absval", t, d);
                let powered = g.node("power", t, &[("in1", t, a), ("in2", f, exponent.clone())]);
                let sum = g.node("dotproduct", f, &[("in1", t, powered), ("in2", t, v3(1.0))]);
                let r = g.binary("power", f, sum.clone(), inverse.clone());
                g.ifgreater(f, sum, v(0.0), r, v(0.0))
            }
            _ => return None,
        })
    };
    let p = g.node(
        "multiply",
        t,
        &[("in1", t, Src::I("vector")), ("in2", f, Src::I("scale"))],
    );
    let base = g.unary("floor", t, p.clone());
    let randomness = g.clamp(f, Src::I("randomness"), v(0.0), v(1.0));
    let far = || v(3.4e38);
    let (mut d1, mut point1, mut offset1) = (far(), v3(0.0), v3(0.0));
    let (mut d2, mut point2, mut offset2) = (far(), v3(0.0), v3(0.0));
    for k in -1..=1 {
        for j in -1..=1 {
            for i in -1..=1 {
                let cell = g.binary("add", t, base.clone(), Src::V(format!("{i}, {j}, {k}")));
                let random = [[0.0; 3], [0.0, 0.0, 65536.0], [0.0, 65536.0, 0.0]].map(|o| {
                    let at = if o == [0.0; 3] {
                        cell.clone()
                    } else {
                        g.binary(
                            "add",
                            t,
                            cell.clone(),
                            Src::V(format!("{}, {}, {}", o[0], o[1], o[2])),
                        )
                    };
                    g.node("cellnoise3d", f, &[("position", t, at)])
                });
                let offset = g.node(
                    "combine3",
                    t,
                    &[
                        ("in1", f, random[0].clone()),
                        ("in2", f, random[1].clone()),
                        ("in3", f, random[2].clone()),
                    ],
                );
                let jitter = g.node(
                    "multiply",
                    t,
                    &[("in1", t, offset.clone()), ("in2", f, randomness.clone())],
                );
                let point = g.binary("add", t, cell, jitter);
                let d = g.binary("subtract", t, point.clone(), p.clone());
                let dist = distance(g, d)?;
                // Strictly nearer than the nearest, or else than the second: the first of
                // equal candidates stays, as in Kiln.
                let nearer = |g: &mut Graph, ty: &str, than: &Src, new: Src, old: Src| {
                    g.ifgreater(ty, than.clone(), dist.clone(), new, old)
                };
                if second {
                    let d2_new = nearer(g, f, &d2, dist.clone(), d2.clone());
                    let point2_new = nearer(g, t, &d2, point.clone(), point2.clone());
                    let offset2_new = nearer(g, t, &d2, offset.clone(), offset2.clone());
                    d2 = nearer(g, f, &d1, d1.clone(), d2_new);
                    point2 = nearer(g, t, &d1, point1.clone(), point2_new);
                    offset2 = nearer(g, t, &d1, offset1.clone(), offset2_new);
                }
                point1 = nearer(g, t, &d1, point, point1.clone());
                offset1 = nearer(g, t, &d1, offset, offset1.clone());
                d1 = g.binary("min", f, d1, dist.clone());
            }
        }
    }
    let (d, point, offset) = if second {
        (d2, point2, offset2)
    } else {
        (d1, point1, offset1)
    };
    let color = g.unary_typed("convert", "color3", t, offset);
    let position = g.node(
        "divide",
        t,
        &[("in1", t, point), ("in2", f, Src::I("scale"))],
    );
    let position = g.node(
        "ifequal",
        t,
        &[
            ("value1", f, Src::I("scale")),
            ("value2", f, v(0.0)),
            ("in1", t, v3(0.0)),
            ("in2", t, position),
        ],
    );
    Some((d, color, position))
}

/// A float operation applied to each component of vectors: their components separated,
/// `op` on each, combined.
fn per_component(g: &mut Graph, inputs: &[Src], op: impl Fn(&mut Graph, &[Src]) -> Src) -> Src {
    let (f, t) = ("float", "vector3");
    let separated: Vec<String> = inputs
        .iter()
        .map(
            |x| match g.node("separate3", "multioutput", &[("in", t, x.clone())]) {
                Src::N(name) => name,
                _ => unreachable!("a node is named"),
            },
        )
        .collect();
    let mut parts = Vec::new();
    for axis in ["outx", "outy", "outz"] {
        let components: Vec<Src> = separated.iter().map(|s| Src::O(s.clone(), axis)).collect();
        parts.push(op(g, &components));
    }
    g.node(
        "combine3",
        t,
        &[
            ("in1", f, parts[0].clone()),
            ("in2", f, parts[1].clone()),
            ("in3", f, parts[2].clone()),
        ],
    )
}

/// `sign(x) floor(|x|)`.
fn trunc(g: &mut Graph, x: Src) -> Src {
    let s = g.unary("sign", "float", x.clone());
    let m = g.unary("absval", "float", x);
    let fl = g.unary("floor", "float", m);
    g.binary("multiply", "float", s, fl)
}

/// Blender's vector math: the vector and the value output.
fn vector_math(g: &mut Graph, op: &str) -> Option<(Src, Src)> {
    let t = "vector3";
    let (a, b, c) = (Src::I("a"), Src::I("b"), Src::I("c"));
    let zero = || v(0.0);
    let zero3 = || Src::V("0, 0, 0".into());
    Some(match op {
        "add" => (g.binary("add", t, a, b), zero()),
        "subtract" => (g.binary("subtract", t, a, b), zero()),
        "multiply" => (g.binary("multiply", t, a, b), zero()),
        "divide" => (g.binary("divide", t, a, b), zero()),
        "multiply_add" => {
            let p = g.binary("multiply", t, a, b);
            (g.binary("add", t, p, c), zero())
        }
        "cross" => (g.binary("crossproduct", t, a, b), zero()),
        "dot" => (
            zero3(),
            g.node("dotproduct", "float", &[("in1", t, a), ("in2", t, b)]),
        ),
        "distance" => (
            zero3(),
            g.node("distance", "float", &[("in1", t, a), ("in2", t, b)]),
        ),
        "length" => (zero3(), g.unary_typed("magnitude", "float", t, a)),
        "scale" => (
            g.node(
                "multiply",
                t,
                &[("in1", t, a), ("in2", "float", Src::I("scale"))],
            ),
            zero(),
        ),
        "normalize" => (g.unary("normalize", t, a), zero()),
        "absolute" => (g.unary("absval", t, a), zero()),
        "minimum" => (g.binary("min", t, a, b), zero()),
        "maximum" => (g.binary("max", t, a, b), zero()),
        "floor" => (g.unary("floor", t, a), zero()),
        "ceil" => (g.unary("ceil", t, a), zero()),
        "fraction" => {
            let fl = g.unary("floor", t, a.clone());
            (g.binary("subtract", t, a, fl), zero())
        }
        "sine" => (g.unary("sin", t, a), zero()),
        "cosine" => (g.unary("cos", t, a), zero()),
        "tangent" => (g.unary("tan", t, a), zero()),
        // b · dot(a, b) / dot(b, b)
        "project" => {
            let ab = g.node(
                "dotproduct",
                "float",
                &[("in1", t, a), ("in2", t, b.clone())],
            );
            let bb = g.node(
                "dotproduct",
                "float",
                &[("in1", t, b.clone()), ("in2", t, b.clone())],
            );
            let k = g.binary("divide", "float", ab, bb);
            (
                g.node("multiply", t, &[("in1", t, b), ("in2", "float", k)]),
                zero(),
            )
        }
        // a − 2 dot(a, n) n, n = normalize(b)
        "reflect" => {
            let n = g.unary("normalize", t, b);
            (
                g.node("reflect", t, &[("in", t, a), ("normal", t, n)]),
                zero(),
            )
        }
        // dot(c, b) < 0 ? a : −a
        "faceforward" => {
            let d = g.node("dotproduct", "float", &[("in1", t, c), ("in2", t, b)]);
            let neg = g.binary("multiply", t, a.clone(), v3(-1.0));
            (g.ifgreater(t, v(0.0), d, a, neg), zero())
        }
        "snap" => {
            let q = g.binary("divide", t, a, b.clone());
            let fl = g.unary("floor", t, q);
            (g.binary("multiply", t, fl, b), zero())
        }
        "modulo" => (
            per_component(g, &[a, b], |g, x| {
                truncated_modulo(g, x[0].clone(), x[1].clone())
            }),
            zero(),
        ),
        // Per component: Cycles' wrapf(a, b, c), b the max and c the min.
        "wrap" => (
            per_component(g, &[a, b, c], |g, x| {
                wrap(g, x[0].clone(), x[1].clone(), x[2].clone())
            }),
            zero(),
        ),
        // Cycles' refract of a by the unit normal n = normalize(b) at IOR ratio eta:
        // k = 1 − eta² (1 − dot(n, a)²); eta a − (eta dot(n, a) + sqrt(k)) n, 0 where k < 0.
        "refract" => {
            let f = "float";
            let eta = Src::I("scale");
            let n = g.unary("normalize", t, b);
            let d = g.node(
                "dotproduct",
                f,
                &[("in1", t, n.clone()), ("in2", t, a.clone())],
            );
            let d2 = g.binary("multiply", f, d.clone(), d.clone());
            let sin2 = g.binary("subtract", f, v(1.0), d2);
            let e2 = g.binary("multiply", f, eta.clone(), eta.clone());
            let k = g.binary("multiply", f, e2, sin2);
            let k = g.binary("subtract", f, v(1.0), k);
            let root = g.binary("max", f, k.clone(), v(0.0));
            let root = g.unary("sqrt", f, root);
            let ed = g.binary("multiply", f, eta.clone(), d);
            let along = g.binary("add", f, ed, root);
            let ea = g.node("multiply", t, &[("in1", t, a), ("in2", f, eta)]);
            let an = g.node("multiply", t, &[("in1", t, n), ("in2", f, along)]);
            let r = g.binary("subtract", t, ea, an);
            (g.ifgreater(t, v(0.0), k, zero3(), r), zero())
        }
        _ => return None,
    })
}

impl Graph {
    /// A one-input node whose input type differs from its output's.
    fn unary_typed(&mut self, category: &str, ty: &str, input_ty: &str, a: Src) -> Src {
        self.node(category, ty, &[("in", input_ty, a)])
    }
}

/// Blender's Mapping node: point (scale, rotate X then Y then Z, translate), texture
/// (the inverse), vector (no translation), normal (the inverse transpose, normalised).
fn mapping(g: &mut Graph, vector_type: &str) -> Option<Src> {
    let t = "vector3";
    let degrees = g.node(
        "multiply",
        t,
        &[
            ("in1", t, Src::I("rotation")),
            ("in2", "float", v(180.0 / std::f32::consts::PI)),
        ],
    );
    let Src::N(deg) = degrees else { return None };
    let split = g.node("separate3", "multioutput", &[("in", t, Src::N(deg))]);
    let Src::N(split) = split else { return None };
    let angle = |g: &mut Graph, axis: &'static str, sign: f32| {
        let a = Src::O(split.clone(), axis);
        g.binary("multiply", "float", a, v(sign))
    };
    let rotate = |g: &mut Graph, x: Src, axis: &'static str, amount: Src| {
        let axis_vector = match axis {
            "outx" => "1, 0, 0",
            "outy" => "0, 1, 0",
            _ => "0, 0, 1",
        };
        g.node(
            "rotate3d",
            t,
            &[
                ("in", t, x),
                ("amount", "float", amount),
                ("axis", t, Src::V(axis_vector.into())),
            ],
        )
    };
    let forward = |g: &mut Graph, x: Src| {
        let mut x = x;
        for axis in ["outx", "outy", "outz"] {
            let a = angle(g, axis, 1.0);
            x = rotate(g, x, axis, a);
        }
        x
    };
    let inverse = |g: &mut Graph, x: Src| {
        let mut x = x;
        for axis in ["outz", "outy", "outx"] {
            let a = angle(g, axis, -1.0);
            x = rotate(g, x, axis, a);
        }
        x
    };
    Some(match vector_type {
        "point" => {
            let s = g.binary("multiply", t, Src::I("vector"), Src::I("scale"));
            let r = forward(g, s);
            g.binary("add", t, r, Src::I("location"))
        }
        "texture" => {
            let d = g.binary("subtract", t, Src::I("vector"), Src::I("location"));
            let r = inverse(g, d);
            g.binary("divide", t, r, Src::I("scale"))
        }
        "vector" => {
            let s = g.binary("multiply", t, Src::I("vector"), Src::I("scale"));
            forward(g, s)
        }
        "normal" => {
            let s = g.binary("divide", t, Src::I("vector"), Src::I("scale"));
            let r = forward(g, s);
            g.unary("normalize", t, r)
        }
        _ => return None,
    })
}
