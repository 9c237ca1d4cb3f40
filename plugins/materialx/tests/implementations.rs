//! The node-graph implementations the exporter writes for Kiln nodes compute what Kiln
//! computes: each is evaluated here by a small interpreter of the MaterialX standard
//! nodes it uses, at constant inputs, and compared with Kiln's own constant folding of
//! the node (read back as a constant emission). Where an implementation is exact but for
//! Kiln's integer hashes (Brick's tint, Voronoi's feature points), the cases are those the
//! hash cannot change (a saturating bias, randomness 0); MaterialX's cell noise is
//! interpreted as MaterialX defines it. The volume shaders' closures are compared with the
//! coefficients Kiln's compiler gives. Approximations (noises, bump) are not compared: they
//! are documented as such.

#[path = "../../../tests/common/node_reference.rs"]
mod node_reference;

use std::collections::{BTreeMap, HashMap};

use kiln::material::{Graph, Input, Link, Node, Param, Value};
use kiln_materialx::implement::{self, Src};
use kiln_plugin_api::kmat::read;

/// A value: one or three channels.
type V = Vec<f32>;

fn parse(text: &str) -> V {
    text.split(',').map(|x| x.trim().parse().unwrap()).collect()
}

/// Channel `i` (a float in every channel).
fn at(v: &V, i: usize) -> f32 {
    if v.len() == 1 { v[0] } else { v[i] }
}

fn zip(a: &V, b: &V, f: impl Fn(f32, f32) -> f32) -> V {
    let n = a.len().max(b.len());
    (0..n).map(|i| f(at(a, i), at(b, i))).collect()
}

fn map(a: &V, f: impl Fn(f32) -> f32) -> V {
    a.iter().map(|&x| f(x)).collect()
}

fn dot(a: &V, b: &V) -> f32 {
    (0..3).map(|i| at(a, i) * at(b, i)).sum()
}

/// Rodrigues' rotation of `v` about unit `axis` by `degrees`.
fn rotate(v: &V, degrees: f32, axis: &V) -> V {
    let (s, c) = degrees.to_radians().sin_cos();
    let k = axis;
    let kv = dot(k, v);
    let cross = [
        k[1] * v[2] - k[2] * v[1],
        k[2] * v[0] - k[0] * v[2],
        k[0] * v[1] - k[1] * v[0],
    ];
    (0..3)
        .map(|i| v[i] * c + cross[i] * s + k[i] * kv * (1.0 - c))
        .collect()
}

fn rgb_to_hsv(c: &V) -> V {
    let (r, g, b) = (c[0], c[1], c[2]);
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let d = max - min;
    let s = if max > 0.0 { d / max } else { 0.0 };
    let mut h = if d == 0.0 {
        0.0
    } else if max == r {
        (g - b) / d
    } else if max == g {
        2.0 + (b - r) / d
    } else {
        4.0 + (r - g) / d
    } / 6.0;
    if h < 0.0 {
        h += 1.0;
    }
    vec![h, s, max]
}

fn hsv_to_rgb(c: &V) -> V {
    let (h, s, v) = (c[0], c[1], c[2]);
    if s == 0.0 {
        return vec![v; 3];
    }
    let h = (h - h.floor()) * 6.0;
    let i = h.floor();
    let f = h - i;
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    match i as i32 {
        0 => vec![v, t, p],
        1 => vec![q, v, p],
        2 => vec![p, v, t],
        3 => vec![p, q, v],
        4 => vec![t, p, v],
        _ => vec![v, p, q],
    }
}

/// Evaluates the graph's nodes (in order: each reads only earlier ones) with interface
/// values `interface`; every node's outputs by (node, output).
fn evaluate(g: &implement::Graph, interface: &HashMap<String, V>) -> HashMap<(String, String), V> {
    let text = format!("<g>{}</g>", g.text);
    let doc = roxmltree::Document::parse(&text).unwrap();
    let mut values: HashMap<(String, String), V> = HashMap::new();
    for node in doc.root_element().children().filter(|n| n.is_element()) {
        let name = node.attribute("name").unwrap().to_owned();
        let category = node.tag_name().name();
        let mut inputs: HashMap<&str, V> = HashMap::new();
        for i in node.children().filter(|n| n.is_element()) {
            let v = if let Some(x) = i.attribute("value") {
                if i.attribute("type") == Some("string") {
                    continue;
                }
                parse(x)
            } else if let Some(n) = i.attribute("interfacename") {
                interface
                    .get(n)
                    .unwrap_or_else(|| panic!("interface input {n}"))
                    .clone()
            } else {
                let n = i.attribute("nodename").unwrap().to_owned();
                let o = i.attribute("output").unwrap_or("out").to_owned();
                values
                    .get(&(n.clone(), o.clone()))
                    .unwrap_or_else(|| panic!("{n}.{o}"))
                    .clone()
            };
            inputs.insert(i.attribute("name").unwrap(), v);
        }
        let get = |n: &str| {
            inputs
                .get(n)
                .cloned()
                .unwrap_or_else(|| panic!("{category}: {n}"))
        };
        let out = match category {
            "add" => zip(&get("in1"), &get("in2"), |x, y| x + y),
            "subtract" => zip(&get("in1"), &get("in2"), |x, y| x - y),
            "multiply" => zip(&get("in1"), &get("in2"), |x, y| x * y),
            "divide" => zip(&get("in1"), &get("in2"), |x, y| x / y),
            "power" => zip(&get("in1"), &get("in2"), f32::powf),
            "min" => zip(&get("in1"), &get("in2"), f32::min),
            "max" => zip(&get("in1"), &get("in2"), f32::max),
            "modulo" => zip(&get("in1"), &get("in2"), |x, y| x - y * (x / y).floor()),
            "atan2" => zip(&get("iny"), &get("inx"), f32::atan2),
            "absval" => map(&get("in"), f32::abs),
            "floor" => map(&get("in"), f32::floor),
            "ceil" => map(&get("in"), f32::ceil),
            "sign" => map(&get("in"), |x| {
                if x > 0.0 {
                    1.0
                } else if x < 0.0 {
                    -1.0
                } else {
                    0.0
                }
            }),
            "sqrt" => map(&get("in"), f32::sqrt),
            "exp" => map(&get("in"), f32::exp),
            "ln" => map(&get("in"), f32::ln),
            "sin" => map(&get("in"), f32::sin),
            "cos" => map(&get("in"), f32::cos),
            "tan" => map(&get("in"), f32::tan),
            "asin" => map(&get("in"), f32::asin),
            "acos" => map(&get("in"), f32::acos),
            "dot" => get("in"),
            "convert" => {
                let v = get("in");
                let n = if node.attribute("type") == Some("float") {
                    1
                } else {
                    3
                };
                (0..n)
                    .map(|i| {
                        if i < v.len() || v.len() == 1 {
                            at(&v, i)
                        } else {
                            0.0
                        }
                    })
                    .collect()
            }
            "clamp" => {
                let (x, lo, hi) = (get("in"), get("low"), get("high"));
                let c = zip(&x, &lo, f32::max);
                zip(&c, &hi, f32::min)
            }
            "mix" => {
                let (fg, bg, t) = (get("fg"), get("bg"), get("mix")[0]);
                zip(&fg, &bg, |f, b| b + (f - b) * t)
            }
            "ifgreater" | "ifequal" => {
                let (v1, v2) = (get("value1")[0], get("value2")[0]);
                let take = if category == "ifgreater" {
                    v1 > v2
                } else {
                    v1 == v2
                };
                if take { get("in1") } else { get("in2") }
            }
            "dotproduct" => vec![dot(&get("in1"), &get("in2"))],
            "magnitude" => vec![dot(&get("in"), &get("in")).sqrt()],
            "distance" => {
                let d = zip(&get("in1"), &get("in2"), |x, y| x - y);
                vec![dot(&d, &d).sqrt()]
            }
            "crossproduct" => {
                let (a, b) = (get("in1"), get("in2"));
                vec![
                    a[1] * b[2] - a[2] * b[1],
                    a[2] * b[0] - a[0] * b[2],
                    a[0] * b[1] - a[1] * b[0],
                ]
            }
            "normalize" => {
                let v = get("in");
                let l = dot(&v, &v).sqrt();
                map(&v, |x| x / l)
            }
            "rotate3d" => rotate(&get("in"), get("amount")[0], &get("axis")),
            "reflect" => {
                let (i, n) = (get("in"), get("normal"));
                let d = 2.0 * dot(&i, &n);
                zip(&i, &n, |x, y| x - d * y)
            }
            "rgbtohsv" => rgb_to_hsv(&get("in")),
            "hsvtorgb" => hsv_to_rgb(&get("in")),
            "combine3" => vec![get("in1")[0], get("in2")[0], get("in3")[0]],
            "separate3" => {
                let v = get("in");
                for (i, o) in ["outr", "outg", "outb"].iter().enumerate() {
                    values.insert((name.clone(), o.to_string()), vec![v[i]]);
                }
                for (i, o) in ["outx", "outy", "outz"].iter().enumerate() {
                    values.insert((name.clone(), o.to_string()), vec![v[i]]);
                }
                continue;
            }
            "smoothstep" => {
                let (low, high) = (get("low")[0], get("high")[0]);
                map(&get("in"), |x| {
                    if x >= high {
                        1.0
                    } else if x <= low {
                        0.0
                    } else {
                        let t = (x - low) / (high - low);
                        t * t * (3.0 - 2.0 * t)
                    }
                })
            }
            "combine2" => vec![get("in1")[0], get("in2")[0]],
            "cellnoise2d" => vec![cell_noise(&get("texcoord"))],
            "cellnoise3d" => vec![cell_noise(&get("position"))],
            // A volume as [absorption, scattering, emission, anisotropy].
            "absorption_vdf" => [get("absorption"), vec![0.0; 3], vec![0.0]].concat(),
            "anisotropic_vdf" => {
                let or_zero = |n: &str| inputs.get(n).cloned().unwrap_or(vec![0.0; 3]);
                [
                    or_zero("absorption"),
                    or_zero("scattering"),
                    or_zero("anisotropy"),
                ]
                .concat()
            }
            "uniform_edf" => get("color"),
            "volume" => {
                let vdf = get("vdf");
                let edf = inputs.get("edf").cloned().unwrap_or(vec![0.0; 3]);
                [&vdf[..6], &edf[..], &vdf[6..7]].concat()
            }
            other => panic!("the test's interpreter lacks {other}"),
        };
        values.insert((name, "out".into()), out);
    }
    values
}

/// MaterialX's cell noise (mx_cell_noise_float): Bob Jenkins' lookup3 of the floored
/// coordinates as integers, scaled to [0, 1].
fn cell_noise(p: &[f32]) -> f32 {
    let seed = 0xdeadbeef_u32
        .wrapping_add((p.len() as u32) << 2)
        .wrapping_add(13);
    let mut abc = [seed; 3];
    for (k, x) in abc.iter_mut().zip(p) {
        *k = k.wrapping_add(x.floor() as i32 as u32);
    }
    let [a, b, c] = abc;
    node_reference::final_mix(a, b, c) as f32 / u32::MAX as f32
}

/// The offset added to a node's output before it becomes emission (which Kiln keeps
/// non-negative), and taken off the pixel again.
const OFFSET: f32 = 100.0;

/// What Kiln computes for output `socket` of each node: each node's output (plus
/// [`OFFSET`]) is the emission of a quad of its own, rendered head-on by Kiln's kernel,
/// one sample, no bounces, so that each quad's pixels are the value.
///
/// The cases are rendered through the interpreter, halved until each render's programs
/// fit its parameter buffer: a scene whose programs do not fit is rendered as compiled
/// graphs instead, whose code differs from render to render, and each such kernel took
/// lavapipe about a minute to build on a clean machine.
fn kiln_values(cases: &[(Node, &str)]) -> Vec<V> {
    use glam::{Affine3A, Quat, Vec3};
    use kiln::render::materials::interprets;
    use kiln::render::{GpuContext, KernelKind, RenderControl, RenderSettings, Renderer};
    use kiln::scene::{Camera, Material, Scene, shapes};
    const CELL: u32 = 8;
    let columns = 16usize;
    let rows = cases.len().div_ceil(columns);
    // The camera sees exactly `rows` units of the plane z = 0 vertically.
    let fov = 40.0f32;
    let distance = rows as f32 / 2.0 / (fov.to_radians() / 2.0).tan();
    let mut scene = Scene::empty(Camera::look_at(
        Vec3::new(0.0, 0.0, distance),
        Vec3::ZERO,
        fov,
    ));
    scene.environment = Vec3::ZERO;
    let quad = scene.add_mesh(shapes::quad());
    for (i, (node, socket)) in cases.iter().enumerate() {
        let float = kiln::material::nodes::find(&node.kind)
            .and_then(|d| d.output(socket))
            .is_some_and(|(_, o)| o.ty == kiln::material::SocketType::Float);
        let mut g = Graph::default();
        g.add("n", node.clone());
        let offset = if float {
            Node::new("math")
                .param("operation", Param::Text("add".into()))
                .input("a", Link::new("n", socket))
                .input("b", OFFSET)
        } else {
            Node::new("vector_math")
                .param("operation", Param::Text("add".into()))
                .input("a", Link::new("n", socket))
                .input("b", [OFFSET; 3])
        };
        g.add("offset", offset);
        let out = if float { "value" } else { "vector" };
        g.add(
            "s",
            Node::new("principled_bsdf")
                .input("base_color", [0.0; 3])
                .input("specular_weight", 0.0)
                .input("emission_strength", 1.0)
                .input("emission_color", Link::new("offset", out)),
        );
        g.add(
            "out",
            Node::new("material_output").input("surface", Link::new("s", "bsdf")),
        );
        let m = scene.add_material(Material::from_graph(&format!("case {i}"), g).unwrap());
        let (column, row) = ((i % columns) as f32, (i / columns) as f32);
        let at = Vec3::new(
            column - (columns as f32 - 1.0) / 2.0,
            (rows as f32 - 1.0) / 2.0 - row,
            0.0,
        );
        scene.add_instance(
            quad,
            m,
            Affine3A::from_scale_rotation_translation(
                Vec3::splat(0.9),
                Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
                at,
            ),
        );
    }
    if cases.len() > 1 && !interprets(&scene) {
        let (first, second) = cases.split_at(cases.len() / 2);
        return [kiln_values(first), kiln_values(second)].concat();
    }
    let settings = RenderSettings {
        width: columns as u32 * CELL,
        height: rows as u32 * CELL,
        samples_per_pixel: 1,
        max_bounces: 0,
        max_volume_bounces: kiln::scene::UNLIMITED_VOLUME_BOUNCES,
        seed: 1,
        sampling: kiln::shader::sampling::Sampling::default(),
        volume_resolution: kiln::scene::DEFAULT_VOLUME_RESOLUTION,
        clamp: kiln::scene::Clamp::default(),
        noise_threshold: 0.0,
        light_sampling: false,
        page_bytes: None,
        kernel: KernelKind::Interpreted,
        aovs: false,
        film_piece_bytes: None,
        ablation: kiln::shader::Ablation::Full,
        texel_reads: None,
    };
    // One device for every render: its pipeline cache keeps the kernel.
    static GPU: std::sync::OnceLock<std::sync::Arc<GpuContext>> = std::sync::OnceLock::new();
    let ctx = GPU.get_or_init(|| GpuContext::new(None).expect("an adapter"));
    let mut renderer = Renderer::new(std::sync::Arc::clone(ctx), &scene, settings).unwrap();
    renderer.render(0..1, RenderControl::default()).unwrap();
    let film = renderer.read_film().unwrap();
    (0..cases.len())
        .map(|i| {
            let (column, row) = ((i % columns) as u32, (i / columns) as u32);
            let p = film.pixel(column * CELL + CELL / 2, row * CELL + CELL / 2);
            vec![p.x - OFFSET, p.y - OFFSET, p.z - OFFSET]
        })
        .collect()
}

/// The implementation's value of output `socket` of `node`.
fn materialx_value(node: &Node, socket: &str) -> V {
    let library = kiln::material::docs::library_text([node.kind.as_str()]);
    let node_type = read::parse_library(&library).unwrap().remove(0);
    let mut params: Vec<(String, read::Param)> = node_type
        .params
        .iter()
        .map(|p| (p.name.clone(), p.default.clone()))
        .collect();
    let mut inputs = BTreeMap::new();
    for (k, p) in &node.params {
        let p = match p {
            Param::Text(t) => read::Param::Text(t.clone()),
            Param::Bool(b) => read::Param::Bool(*b),
            Param::Number(x) => read::Param::Number(*x),
            Param::Ramp(stops) => read::Param::Ramp(
                stops
                    .iter()
                    .map(|s| read::Stop {
                        position: s.position,
                        color: s.color,
                    })
                    .collect(),
            ),
        };
        params.retain(|(n, _)| n != k);
        params.push((k.clone(), p));
    }
    let mut interface = HashMap::new();
    for s in &node_type.inputs {
        let v = match node.inputs.get(&s.name) {
            Some(Input::Value(Value::Float(x))) => vec![*x],
            Some(Input::Value(Value::Vec3(c))) => c.to_vec(),
            Some(_) => panic!("constants only"),
            None => match &s.default {
                Some(read::Input::Float(x)) => vec![*x],
                Some(read::Input::Vec3(c)) => c.to_vec(),
                _ => vec![0.0; 3],
            },
        };
        if let Some(Input::Value(v)) = node.inputs.get(&s.name) {
            inputs.insert(
                s.name.clone(),
                match v {
                    Value::Float(x) => read::Input::Float(*x),
                    Value::Vec2(c) => read::Input::Vec2(*c),
                    Value::Vec3(c) => read::Input::Vec3(*c),
                },
            );
        }
        interface.insert(s.name.clone(), v);
    }
    let outputs: Vec<(String, String, String)> = node_type
        .outputs
        .iter()
        .map(|o| (o.name.clone(), o.name.clone(), o.ty.name().to_owned()))
        .collect();
    let g = implement::implement(&node.kind, &params, &inputs, &outputs)
        .unwrap_or_else(|| panic!("{} has no implementation", node.kind));
    let values = evaluate(&g, &interface);
    let (_, _, src) = g.outputs.iter().find(|(n, _, _)| n == socket).unwrap();
    match src {
        Src::N(n) => values[&(n.clone(), "out".to_owned())].clone(),
        Src::O(n, o) => values[&(n.clone(), o.to_string())].clone(),
        other => panic!("output from {other:?}"),
    }
}

/// Kiln's and the implementation's values of every case, compared (a float output
/// in every channel).
fn compare(cases: &[(Node, &str)]) {
    let kiln = kiln_values(cases);
    for ((node, socket), kiln) in cases.iter().zip(&kiln) {
        let mx = materialx_value(node, socket);
        for i in 0..3 {
            let (k, m) = (kiln[i], at(&mx, i));
            assert!(
                (k - m).abs() <= 1e-3 * k.abs().max(1.0),
                "{} {:?} {:?}.{socket}: Kiln {kiln:?}, MaterialX {mx:?}",
                node.kind,
                node.params,
                node.inputs
            );
        }
    }
    eprintln!("{} cases agree", cases.len());
}

/// The options of choice parameter `param` of node type `kind`, as Kiln declares them.
fn choices(kind: &str, param: &str) -> &'static [&'static str] {
    match kiln::material::nodes::find(kind)
        .and_then(|d| d.param(param))
        .map(|p| &p.kind)
    {
        Some(kiln::material::nodes::ParamKind::Enum(options)) => options,
        _ => panic!("{kind} has no choice {param}"),
    }
}

fn op(kind: &str, operation: &str) -> Node {
    Node::new(kind).param("operation", Param::Text(operation.into()))
}

#[test]
fn math_implementations_compute_what_kiln_does() {
    // Every operation Kiln has.
    let ops = kiln::material::nodes::MATH_OPERATIONS;
    let mut cases = Vec::new();
    for &operation in ops {
        for (a, b, c) in [(-1.25, 2.5, 0.1), (2.6, -0.4, 1.0)] {
            // Keep to each operation's domain (Kiln's safe variants differ outside it).
            let (a, b) = match operation {
                "power" | "logarithm" | "sqrt" | "inverse_sqrt" => {
                    (f32::abs(a) + 0.1, f32::abs(b) + 1.5)
                }
                "arcsine" | "arccosine" => (a.clamp(-0.9, 0.9), b),
                _ => (a, b),
            };
            let node = op("math", operation)
                .input("a", a)
                .input("b", b)
                .input("c", c);
            cases.push((node.clone(), "value"));
        }
        if matches!(operation, "add" | "multiply" | "sine") {
            let node = op("math", operation).input("a", 0.75).input("b", 0.75);
            cases.push((node.param("clamp", Param::Bool(true)), "value"));
        }
    }
    compare(&cases);
}

#[test]
fn vector_and_mix_implementations_compute_what_kiln_does() {
    let (a, b, c) = ([0.3, -0.6, 0.9], [0.5, 0.25, -1.5], [0.1, 0.2, 0.3]);
    let mut cases = Vec::new();
    // Every operation with a vector result but those without an implementation.
    let vector_results = kiln::material::nodes::VECTOR_MATH_OPERATIONS
        .iter()
        .filter(|o| !matches!(**o, "dot" | "distance" | "length"));
    for &operation in vector_results {
        let node = op("vector_math", operation)
            .input("a", a)
            .input("b", b)
            .input("c", c)
            .input("scale", 1.5);
        cases.push((node, "vector"));
    }
    // The edges: a zero divisor, an empty wrap range, total internal reflection.
    for (operation, a, b, c, scale) in [
        ("modulo", [-1.7, 2.5, 0.9], [0.5, 0.0, -0.4], c, 1.0),
        (
            "wrap",
            [2.3, -0.7, 0.1],
            [1.0, 1.0, 0.1],
            [0.0, -1.0, 0.1],
            1.0,
        ),
        ("refract", [0.9, 0.1, -0.2], [0.0, 0.0, 1.0], c, 1.5),
        ("refract", [0.2, 0.1, -0.97], [0.0, 0.0, 1.0], c, 0.67),
    ] {
        cases.push((
            op("vector_math", operation)
                .input("a", a)
                .input("b", b)
                .input("c", c)
                .input("scale", scale),
            "vector",
        ));
    }
    for operation in ["dot", "distance", "length"] {
        cases.push((
            op("vector_math", operation).input("a", a).input("b", b),
            "value",
        ));
    }
    for clamp in [false, true] {
        cases.push((
            Node::new("mix_float")
                .param("clamp_factor", Param::Bool(clamp))
                .input("factor", 0.7)
                .input("a", 0.2)
                .input("b", 0.9),
            "result",
        ));
    }
    // Channels of 0 (dodge and divide leave them), greys (no hue to give or saturate),
    // 1 − t b = 0 (dodge) and 1 − t + t b = 0 (burn), the factor's ends.
    let colours = [
        (0.6, [0.2, 0.5, 0.9], [0.7, 0.3, 0.4]),
        (0.9, [0.0, 0.6, 0.3], [0.5, 0.5, 0.5]),
        (0.0, [0.4, 0.4, 0.4], [0.9, 0.95, 0.2]),
        (1.0, [0.7, 0.2, 0.05], [1.0, 0.0, 0.6]),
        (0.35, [0.8, 0.1, 0.6], [0.2, 0.9, 0.0]),
    ];
    for &blend in choices("mix_color", "blend") {
        for (i, &(factor, a, b)) in colours.iter().enumerate() {
            for clamp in [false, true] {
                if clamp && i > 0 {
                    continue;
                }
                cases.push((
                    Node::new("mix_color")
                        .param("blend", Param::Text(blend.into()))
                        .param("clamp_result", Param::Bool(clamp))
                        .input("factor", factor)
                        .input("a", a)
                        .input("b", b),
                    "result",
                ));
            }
        }
    }
    for interpolation in ["linear", "stepped", "smoothstep", "smootherstep"] {
        for (value, clamp) in [(0.35, true), (1.7, true), (1.7, false), (-0.4, false)] {
            cases.push((
                Node::new("map_range")
                    .param("interpolation", Param::Text(interpolation.into()))
                    .param("clamp", Param::Bool(clamp))
                    .input("value", value)
                    .input("from_min", -0.5)
                    .input("from_max", 1.5)
                    .input("to_min", 2.0)
                    .input("to_max", -1.0)
                    .input("steps", 3.0),
                "result",
            ));
        }
    }
    let color = [0.2, 0.7, 0.4];
    for fac in [0.0, 0.4, 1.0] {
        cases.push((
            Node::new("invert").input("fac", fac).input("color", color),
            "color",
        ));
    }
    for gamma in [0.45, 1.0, 2.2] {
        cases.push((
            Node::new("gamma")
                .input("gamma", gamma)
                .input("color", [0.2, 0.0, 0.8]),
            "color",
        ));
    }
    for (bright, contrast) in [(0.1, 0.5), (-0.3, -0.4)] {
        cases.push((
            Node::new("brightness_contrast")
                .input("bright", bright)
                .input("contrast", contrast)
                .input("color", color),
            "color",
        ));
    }
    cases.push((Node::new("rgb_to_bw").input("color", color), "value"));
    for (hue, saturation, value, fac) in [
        (0.5, 1.0, 1.0, 1.0),
        (0.8, 1.5, 0.7, 0.6),
        (0.1, 0.3, 1.2, 1.0),
    ] {
        cases.push((
            Node::new("hue_saturation_value")
                .input("hue", hue)
                .input("saturation", saturation)
                .input("value", value)
                .input("fac", fac)
                .input("color", color),
            "color",
        ));
    }
    for mode in ["rgb", "hsv"] {
        for socket in ["red", "green", "blue"] {
            cases.push((
                Node::new("separate_color")
                    .param("mode", Param::Text(mode.into()))
                    .input("color", [0.2, 0.7, 0.4]),
                socket,
            ));
        }
        cases.push((
            Node::new("combine_color")
                .param("mode", Param::Text(mode.into()))
                .input("red", 0.3)
                .input("green", 0.6)
                .input("blue", 0.8),
            "color",
        ));
    }
    compare(&cases);
}

#[test]
fn texture_and_mapping_implementations_compute_what_kiln_does() {
    let mut cases = Vec::new();
    let stops = vec![
        kiln::material::RampStop {
            position: 0.1,
            color: [1.0, 0.0, 0.0, 1.0],
        },
        kiln::material::RampStop {
            position: 0.5,
            color: [0.0, 1.0, 0.0, 0.5],
        },
        kiln::material::RampStop {
            position: 0.9,
            color: [0.0, 0.0, 1.0, 0.0],
        },
    ];
    for interpolation in ["linear", "constant", "ease"] {
        for fac in [0.0, 0.3, 0.5, 0.72, 1.0] {
            for socket in ["color", "alpha"] {
                cases.push((
                    Node::new("color_ramp")
                        .param("stops", Param::Ramp(stops.clone()))
                        .param("interpolation", Param::Text(interpolation.into()))
                        .input("fac", fac),
                    socket,
                ));
            }
        }
    }
    for vector in [[0.3, 0.4, 0.2], [-0.7, 1.6, 0.2], [0.45, -0.2, -0.6]] {
        for socket in ["color", "fac"] {
            cases.push((
                Node::new("checker_texture")
                    .input("vector", vector)
                    .input("scale", 2.0)
                    .input("color1", [0.9, 0.1, 0.1])
                    .input("color2", [0.1, 0.1, 0.9]),
                socket,
            ));
        }
        for &kind in choices("gradient_texture", "gradient_type") {
            cases.push((
                Node::new("gradient_texture")
                    .param("gradient_type", Param::Text(kind.into()))
                    .input("vector", vector),
                "fac",
            ));
        }
        for &wave_type in choices("wave_texture", "wave_type") {
            for &direction in choices("wave_texture", "direction") {
                for &profile in choices("wave_texture", "profile") {
                    cases.push((
                        Node::new("wave_texture")
                            .param("wave_type", Param::Text(wave_type.into()))
                            .param("direction", Param::Text(direction.into()))
                            .param("profile", Param::Text(profile.into()))
                            .input("vector", vector)
                            .input("scale", 1.3)
                            .input("phase_offset", 0.7),
                        "fac",
                    ));
                }
            }
        }
        for vector_type in ["point", "texture", "vector", "normal"] {
            cases.push((
                Node::new("mapping")
                    .param("vector_type", Param::Text(vector_type.into()))
                    .input("vector", vector)
                    .input("location", [0.5, -0.25, 1.0])
                    .input("rotation", [0.3, -0.8, 1.2])
                    .input("scale", [1.5, 0.5, 2.0]),
                "vector",
            ));
        }
    }
    compare(&cases);
}

#[test]
fn brick_implementation_computes_what_kiln_does() {
    // The layout (Fac) everywhere; the colour where a bias of ±1 saturates the tint (a
    // hash of the brick in Kiln, MaterialX's cell noise in the implementation).
    let mut cases = Vec::new();
    let positions = [
        [0.3, 0.4, 0.2],
        [-0.7, 1.6, 0.2],
        [0.45, -0.2, -0.6],
        [0.123, 0.0505, 0.0],
        [0.2017, 0.3038, 0.0],
        [-0.333, -0.4471, 0.9],
    ];
    // squash, squash frequency, offset, offset frequency, mortar smoothness and size.
    let layouts = [
        [1.0, 2.0, 0.5, 2.0, 0.1, 0.02],
        [1.7, 3.0, 0.3, 3.0, 0.0, 0.05],
        [0.6, 1.0, 0.8, 2.0, 0.4, 0.1],
        [1.0, 2.0, 0.5, 2.0, 0.1, 0.0],
    ];
    for vector in positions {
        for [
            squash,
            squash_frequency,
            offset,
            offset_frequency,
            smooth,
            size,
        ] in layouts
        {
            for (bias, socket) in [(0.0, "fac"), (-1.0, "color"), (1.0, "color")] {
                cases.push((
                    Node::new("brick_texture")
                        .input("vector", vector)
                        .input("color1", [0.9, 0.3, 0.1])
                        .input("color2", [0.2, 0.6, 0.8])
                        .input("mortar", [0.05, 0.1, 0.15])
                        .input("squash", squash)
                        .input("squash_frequency", squash_frequency)
                        .input("offset", offset)
                        .input("offset_frequency", offset_frequency)
                        .input("mortar_smooth", smooth)
                        .input("mortar_size", size)
                        .input("bias", bias),
                    socket,
                ));
            }
        }
    }
    // Some of them are on mortar, some on its smooth edge, some on brick.
    let facs: Vec<f32> = cases
        .iter()
        .filter(|(_, socket)| *socket == "fac")
        .map(|(node, socket)| materialx_value(node, socket)[0])
        .collect();
    assert!(facs.contains(&0.0) && facs.contains(&1.0));
    assert!(facs.iter().any(|&f| f > 0.05 && f < 0.95), "{facs:?}");
    compare(&cases);
}

#[test]
fn voronoi_implementation_searches_as_kiln_does() {
    // At randomness 0 the feature points are the lattice's corners whatever the hash, so
    // distances and positions are exact there, in every metric; Smooth F1 at smoothness 0
    // is F1.
    let mut cases = Vec::new();
    for vector in [[0.3, 0.4, 0.2], [-0.7, 1.6, 0.2], [0.45, -0.2, -0.6]] {
        for &metric in choices("voronoi_texture", "distance") {
            for &feature in choices("voronoi_texture", "feature") {
                for socket in ["distance", "position"] {
                    cases.push((
                        Node::new("voronoi_texture")
                            .param("distance", Param::Text(metric.into()))
                            .param("feature", Param::Text(feature.into()))
                            .input("vector", vector)
                            .input("scale", 1.37)
                            .input("randomness", 0.0)
                            .input("smoothness", 0.0)
                            .input("exponent", 1.5),
                        socket,
                    ));
                }
            }
        }
    }
    compare(&cases);
}

#[test]
fn volume_implementations_give_kiln_coefficients() {
    let cases = [
        Node::new("volume_absorption")
            .input("color", [0.2, 0.7, 1.3])
            .input("density", 2.5),
        Node::new("volume_scatter")
            .input("color", [0.9, -0.1, 0.4])
            .input("density", 0.7)
            .input("anisotropy", 1.0),
        Node::new("principled_volume")
            .input("color", [0.3, 0.8, 1.2])
            .input("density", 1.5)
            .input("anisotropy", -0.4)
            .input("absorption_color", [0.25, 0.0, 0.9])
            .input("emission_strength", 3.0)
            .input("emission_color", [1.0, 0.5, -0.2]),
        Node::new("principled_volume").input("density", 0.0),
    ];
    for node in cases {
        let mut g = Graph::default();
        g.add("v", node.clone());
        g.add(
            "out",
            Node::new("material_output").input("volume", Link::new("v", "volume")),
        );
        let material = kiln::scene::Material::from_graph("volume", g).unwrap();
        let k = material
            .graph
            .unwrap()
            .traits
            .volume
            .expect("constant inputs");
        let kiln = [
            &k.absorption[..],
            &k.scattering[..],
            &k.emission[..],
            &[k.g][..],
        ]
        .concat();
        let mx = materialx_value(&node, "volume");
        assert_eq!(mx.len(), kiln.len());
        for (m, k) in mx.iter().zip(&kiln) {
            assert!(
                (m - k).abs() <= 1e-5 * k.abs().max(1.0),
                "{}: Kiln {kiln:?}, MaterialX {mx:?}",
                node.kind
            );
        }
    }
}
