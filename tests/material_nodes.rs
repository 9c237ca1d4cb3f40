//! Node values computed on the GPU by the generated WGSL, against values stated here or
//! computed by the CPU references in tests/common/node_reference.rs.

mod common;

use std::collections::BTreeSet;
use std::f32::consts::PI;

use common::node_reference as reference;
use common::{gpu, settings};
use glam::Vec3;
use kiln::material::compile::{compile_value_with_textures, link};
use kiln::material::nodes::{BLEND_MODES, MATH_OPERATIONS};
use kiln::material::{Graph, Link, Node, Param, RampStop, library};
use kiln::render::probe::{Probe, run_probe};
use kiln::scene::{Camera, Scene};

/// One evaluation: `node.socket` of `graph` at the point `p` (normal +z, UV = p.xy).
struct Case {
    graph: Graph,
    at: Link,
    p: [f32; 3],
}

fn case(graph: &Graph, node: &str, socket: &str, p: [f32; 3]) -> Case {
    Case {
        graph: graph.clone(),
        at: Link::new(node, socket),
        p,
    }
}

/// Evaluates every case in one kernel.
fn evaluate(cases: &[Case]) -> Vec<[f32; 4]> {
    evaluate_with_textures(Vec::new(), cases)
}

/// [`evaluate`] in a scene holding `materials`, so that their textures are bound.
fn evaluate_with_textures(materials: Vec<kiln::scene::Material>, cases: &[Case]) -> Vec<[f32; 4]> {
    let mut scene = Scene::empty(Camera::look_at(Vec3::Z, Vec3::ZERO, 40.0));
    scene.materials = materials;
    let mut textures = kiln::render::materials::scene_textures(&scene).index;
    // Cases sharing a graph and socket share a function.
    let mut functions: Vec<(String, usize)> = Vec::new();
    let mut code = String::new();
    let mut calls = BTreeSet::from(["ShadingPoint".to_owned(), "MaterialEval".to_owned()]);
    let mut which = Vec::new();
    for c in cases {
        let key = format!("{:?}{}", c.graph, c.at);
        let index = match functions.iter().position(|(k, _)| *k == key) {
            Some(i) => i,
            None => {
                let i = functions.len();
                let compiled = compile_value_with_textures(
                    "test",
                    &c.graph,
                    &c.at,
                    &format!("probe_value_{i}"),
                    &mut textures,
                )
                .unwrap_or_else(|e| panic!("{e}"));
                code.push_str(&compiled.code);
                calls.extend(compiled.calls);
                functions.push((key, i));
                i
            }
        };
        which.push(index);
    }
    code.push_str(
        "fn probe_value(which: u32, sp: ShadingPoint) -> vec4<f32> {\n    switch (which) {\n",
    );
    for (_, i) in &functions {
        code.push_str(&format!(
            "        case {i}u: {{ return probe_value_{i}(sp); }}\n"
        ));
    }
    code.push_str("        default: { return vec4<f32>(0.0); }\n    }\n}\n");
    let wgsl = library::closure(calls) + &code;

    let mut input: Vec<[f32; 4]> = vec![[cases.len() as f32, 0.0, 0.0, 0.0]];
    for (c, w) in cases.iter().zip(&which) {
        input.push([c.p[0], c.p[1], c.p[2], c.p[0]]);
        input.push([0.0, 0.0, 1.0, c.p[1]]);
        input.push([*w as f32, 0.0, 0.0, 0.0]);
    }
    let out = run_probe(
        &gpu(),
        &scene,
        &settings(1, 1, 1),
        &Probe {
            name: "node_probe",
            parts: &[
                ("(generated) graph values", &wgsl),
                (
                    "shaders/tests/node_probe.wgsl",
                    include_str!("../shaders/tests/node_probe.wgsl"),
                ),
            ],
            entry: "node_probe",
            input: bytemuck::cast_slice(&input),
            output_bytes: 16 * cases.len() as u64,
            invocations: cases.len() as u32,
            material_params: &[],
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    bytemuck::cast_slice::<u8, [f32; 4]>(&out).to_vec()
}

fn graph(nodes: &[(&str, Node)]) -> Graph {
    let mut g = Graph::default();
    for (id, n) in nodes {
        g.add(id, n.clone());
    }
    g
}

fn text(s: &str) -> Param {
    Param::Text(s.into())
}

fn assert_near(what: &str, got: f32, want: f32, tolerance: f32) {
    assert!(
        (got - want).abs() <= tolerance,
        "{what}: got {got}, want {want} ± {tolerance}"
    );
}

/// The position's x as a float the compiler cannot fold: operands that reach the GPU.
fn x_of_position() -> Vec<(&'static str, Node)> {
    vec![
        ("geo", Node::new("geometry")),
        (
            "x",
            Node::new("separate_xyz").input("vector", link("geo", "position")),
        ),
    ]
}

#[test]
fn math_operations_match_blender_values() {
    // (operation, a, b, c, expected); a arrives through the shading point.
    let table: &[(&str, f32, f32, f32, f32)] = &[
        ("add", 2.0, 3.0, 0.0, 5.0),
        ("subtract", 2.0, 3.0, 0.0, -1.0),
        ("multiply", 2.0, 3.0, 0.0, 6.0),
        ("divide", 3.0, 2.0, 0.0, 1.5),
        ("divide", 3.0, 0.0, 0.0, 0.0),
        ("multiply_add", 2.0, 3.0, 4.0, 10.0),
        ("power", 2.0, 3.0, 0.0, 8.0),
        ("power", -2.0, 0.5, 0.0, 0.0),
        ("logarithm", 8.0, 2.0, 0.0, 3.0),
        ("logarithm", -1.0, 2.0, 0.0, 0.0),
        ("sqrt", 9.0, 0.0, 0.0, 3.0),
        ("sqrt", -4.0, 0.0, 0.0, 0.0),
        ("inverse_sqrt", 4.0, 0.0, 0.0, 0.5),
        ("absolute", -2.5, 0.0, 0.0, 2.5),
        ("exponent", 1.0, 0.0, 0.0, std::f32::consts::E),
        ("minimum", 2.0, 3.0, 0.0, 2.0),
        ("maximum", 2.0, 3.0, 0.0, 3.0),
        ("less_than", 2.0, 3.0, 0.0, 1.0),
        ("greater_than", 2.0, 3.0, 0.0, 0.0),
        ("sign", -2.0, 0.0, 0.0, -1.0),
        ("compare", 1.0, 1.05, 0.1, 1.0),
        ("compare", 1.0, 1.5, 0.1, 0.0),
        // Cycles' smoothminf: h = max(c - |a - b|, 0) / c, min(a, b) - h³ c / 6.
        // h = 2/3 here: 1 - (8/27)(3/6) = 1 - 4/27.
        ("smooth_min", 1.0, 2.0, 3.0, 1.0 - 4.0 / 27.0),
        // Farther apart than the blend distance: the plain minimum.
        ("smooth_min", 1.0, 5.0, 1.0, 1.0),
        // A zero distance is the plain minimum (no division by zero).
        ("smooth_min", 4.0, 2.0, 0.0, 2.0),
        // -smoothmin(-a, -b, c): -(-2 - 4/27).
        ("smooth_max", 1.0, 2.0, 3.0, 2.0 + 4.0 / 27.0),
        ("smooth_max", 1.0, 5.0, 1.0, 5.0),
        ("round", 2.5, 0.0, 0.0, 3.0),
        ("floor", -1.5, 0.0, 0.0, -2.0),
        ("ceil", -1.5, 0.0, 0.0, -1.0),
        ("truncate", -1.5, 0.0, 0.0, -1.0),
        ("fraction", 1.25, 0.0, 0.0, 0.25),
        ("truncated_modulo", -3.0, 2.0, 0.0, -1.0),
        ("floored_modulo", -3.0, 2.0, 0.0, 1.0),
        // Cycles' wrapf(value, max, min) wraps into [min, max).
        ("wrap", 5.0, 3.0, 1.0, 1.0),
        ("wrap", -0.5, 1.0, 0.0, 0.5),
        ("wrap", 2.5, 3.0, 1.0, 2.5),
        // A zero-width range gives min.
        ("wrap", 2.0, 1.0, 1.0, 1.0),
        ("snap", 7.0, 3.0, 0.0, 6.0),
        ("pingpong", 5.0, 3.0, 0.0, 1.0),
        ("sine", PI / 2.0, 0.0, 0.0, 1.0),
        ("cosine", 0.0, 0.0, 0.0, 1.0),
        ("tangent", PI / 4.0, 0.0, 0.0, 1.0),
        ("arcsine", 1.0, 0.0, 0.0, PI / 2.0),
        ("arccosine", 1.0, 0.0, 0.0, 0.0),
        ("arctangent", 1.0, 0.0, 0.0, PI / 4.0),
        ("arctan2", 1.0, 1.0, 0.0, PI / 4.0),
        ("sinh", 0.0, 0.0, 0.0, 0.0),
        ("cosh", 0.0, 0.0, 0.0, 1.0),
        ("tanh", 0.0, 0.0, 0.0, 0.0),
        ("radians", 180.0, 0.0, 0.0, PI),
        ("degrees", PI, 0.0, 0.0, 180.0),
    ];
    let cases: Vec<Case> = table
        .iter()
        .map(|&(op, a, b, c, _)| {
            let mut nodes = x_of_position();
            nodes.push((
                "m",
                Node::new("math")
                    .param("operation", text(op))
                    .input("a", link("x", "x"))
                    .input("b", b)
                    .input("c", c),
            ));
            case(&graph(&nodes), "m", "value", [a, 0.0, 0.0])
        })
        .collect();
    let values = evaluate(&cases);
    for (&(op, a, b, c, want), got) in table.iter().zip(&values) {
        assert_near(
            &format!("{op}({a}, {b}, {c})"),
            got[0],
            want,
            2e-3 * want.abs().max(1.0),
        );
    }
    // Every operation is covered.
    let covered: BTreeSet<&str> = table.iter().map(|t| t.0).collect();
    let missing: Vec<&&str> = MATH_OPERATIONS
        .iter()
        .filter(|o| !covered.contains(**o))
        .collect();
    assert!(missing.is_empty(), "untested operations: {missing:?}");
}

#[test]
fn checker_alternates_by_cell_parity() {
    let g = graph(&[
        (
            "c",
            Node::new("checker_texture")
                .input("vector", link("t", "object"))
                .input("scale", 1.0)
                .input("color1", [1.0, 0.0, 0.0])
                .input("color2", [0.0, 0.0, 1.0]),
        ),
        ("t", Node::new("texture_coordinate")),
    ]);
    let cells: [[i32; 3]; 6] = [
        [0, 0, 0],
        [1, 0, 0],
        [1, 1, 0],
        [1, 1, 1],
        [-1, 0, 0],
        [2, 3, -1],
    ];
    let cases: Vec<Case> = cells
        .iter()
        .flat_map(|c| {
            let p = c.map(|i| i as f32 + 0.5);
            [case(&g, "c", "fac", p), case(&g, "c", "color", p)]
        })
        .collect();
    let v = evaluate(&cases);
    for (i, c) in cells.iter().enumerate() {
        let odd = (c[0] + c[1] + c[2]).rem_euclid(2) == 1;
        assert_eq!(
            v[2 * i][0],
            if odd { 1.0 } else { 0.0 },
            "fac in cell {c:?}"
        );
        let want = if odd {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 0.0, 1.0]
        };
        assert_eq!(&v[2 * i + 1][..3], &want, "colour in cell {c:?}");
    }
}

#[test]
fn color_ramp_interpolates_linearly_constantly_and_with_ease() {
    let ramp = |mode: &str| {
        let mut nodes = x_of_position();
        nodes.push((
            "r",
            Node::new("color_ramp")
                .param("interpolation", text(mode))
                .param(
                    "stops",
                    Param::Ramp(vec![
                        RampStop {
                            position: 0.2,
                            color: [0.0, 0.0, 0.0, 1.0],
                        },
                        RampStop {
                            position: 0.6,
                            color: [1.0, 0.5, 0.0, 0.0],
                        },
                        RampStop {
                            position: 1.0,
                            color: [0.0, 1.0, 1.0, 1.0],
                        },
                    ]),
                )
                .input("fac", link("x", "x")),
        ));
        graph(&nodes)
    };
    let (lin, con, ease) = (ramp("linear"), ramp("constant"), ramp("ease"));
    let v = evaluate(&[
        case(&lin, "r", "color", [0.1, 0.0, 0.0]),
        case(&lin, "r", "color", [0.3, 0.0, 0.0]),
        case(&lin, "r", "alpha", [0.3, 0.0, 0.0]),
        case(&lin, "r", "color", [0.8, 0.0, 0.0]),
        case(&lin, "r", "color", [1.5, 0.0, 0.0]),
        case(&con, "r", "color", [0.5, 0.0, 0.0]),
        case(&con, "r", "color", [0.7, 0.0, 0.0]),
        case(&ease, "r", "color", [0.3, 0.0, 0.0]),
    ]);
    let near3 = |what: &str, got: [f32; 4], want: [f32; 3]| {
        for k in 0..3 {
            assert_near(what, got[k], want[k], 1e-5);
        }
    };
    near3("below the first stop", v[0], [0.0, 0.0, 0.0]);
    near3("linear, a quarter of the way", v[1], [0.25, 0.125, 0.0]);
    assert_near("linear alpha", v[2][0], 0.75, 1e-5);
    near3("linear, second segment", v[3], [0.5, 0.75, 0.5]);
    near3("beyond the last stop", v[4], [0.0, 1.0, 1.0]);
    near3("constant keeps the stop below", v[5], [0.0, 0.0, 0.0]);
    near3("constant, second segment", v[6], [1.0, 0.5, 0.0]);
    // Ease: smoothstep of 0.25 is 0.15625.
    near3("ease", v[7], [0.15625, 0.078125, 0.0]);
}

#[test]
fn blend_modes_match_the_reference() {
    let a = [0.2, 0.5, 0.8];
    let b = [0.9, 0.3, 0.1];
    let cases: Vec<Case> = (0..BLEND_MODES.len())
        .map(|m| {
            let mut nodes = x_of_position();
            nodes.push((
                "mix",
                Node::new("mix_color")
                    .param("blend", text(BLEND_MODES[m]))
                    .input("factor", link("x", "x"))
                    .input("a", a)
                    .input("b", b),
            ));
            case(&graph(&nodes), "mix", "result", [0.7, 0.0, 0.0])
        })
        .collect();
    for (m, got) in evaluate(&cases).iter().enumerate() {
        let want = reference::mix_color(m as u32, 0.7, a, b);
        for k in 0..3 {
            assert_near(&format!("blend {}", BLEND_MODES[m]), got[k], want[k], 1e-4);
        }
    }
}

#[test]
fn hsv_round_trips_and_separates() {
    let mut cases = Vec::new();
    let colours: Vec<[f32; 3]> = (0..64)
        .map(|i| {
            let f = i as f32;
            [
                (f * 0.37).fract(),
                (f * 0.61).fract(),
                (f * 0.13 + 0.05).fract(),
            ]
        })
        .collect();
    for c in &colours {
        // The colour comes in through the position, so nothing folds.
        let g = graph(&[
            ("geo", Node::new("geometry")),
            (
                "sep",
                Node::new("separate_color")
                    .param("mode", text("hsv"))
                    .input("color", link("geo", "position")),
            ),
            (
                "comb",
                Node::new("combine_color")
                    .param("mode", text("hsv"))
                    .input("red", link("sep", "red"))
                    .input("green", link("sep", "green"))
                    .input("blue", link("sep", "blue")),
            ),
            (
                "hsv",
                Node::new("combine_xyz")
                    .input("x", link("sep", "red"))
                    .input("y", link("sep", "green"))
                    .input("z", link("sep", "blue")),
            ),
        ]);
        cases.push(case(&g, "comb", "color", *c));
        cases.push(case(&g, "hsv", "vector", *c));
    }
    let v = evaluate(&cases);
    for (i, c) in colours.iter().enumerate() {
        let back = v[2 * i];
        let hsv = v[2 * i + 1];
        let want = reference::rgb_to_hsv(*c);
        for k in 0..3 {
            assert_near(&format!("round trip of {c:?}"), back[k], c[k], 1e-5);
            assert_near(&format!("hsv of {c:?}"), hsv[k], want[k], 1e-5);
        }
    }
}

#[test]
fn map_range_clamp_and_mapping() {
    let mr = |mode: &str, clamp: bool| {
        let mut nodes = x_of_position();
        nodes.push((
            "m",
            Node::new("map_range")
                .param("interpolation", text(mode))
                .param("clamp", Param::Bool(clamp))
                .input("value", link("x", "x"))
                .input("from_min", 0.0)
                .input("from_max", 1.0)
                .input("to_min", 10.0)
                .input("to_max", 20.0)
                .input("steps", 4.0),
        ));
        graph(&nodes)
    };
    let mut nodes = x_of_position();
    nodes.push((
        "c",
        Node::new("clamp")
            .param("clamp_type", text("range"))
            .input("value", link("x", "x"))
            .input("min", 1.0)
            .input("max", -1.0),
    ));
    let clamp = graph(&nodes);
    let mapping = graph(&[
        ("geo", Node::new("geometry")),
        (
            "map",
            Node::new("mapping")
                .input("vector", link("geo", "position"))
                .input("location", [1.0, 2.0, 3.0])
                .input("rotation", [0.0, 0.0, PI / 2.0])
                .input("scale", [2.0, 2.0, 2.0]),
        ),
    ]);
    let v = evaluate(&[
        case(&mr("linear", true), "m", "result", [0.5, 0.0, 0.0]),
        case(&mr("linear", true), "m", "result", [1.5, 0.0, 0.0]),
        case(&mr("linear", false), "m", "result", [1.5, 0.0, 0.0]),
        case(&mr("stepped", true), "m", "result", [0.3, 0.0, 0.0]),
        case(&mr("smoothstep", true), "m", "result", [0.25, 0.0, 0.0]),
        case(&clamp, "c", "result", [3.0, 0.0, 0.0]),
        case(&mapping, "map", "vector", [1.0, 0.0, 0.0]),
    ]);
    assert_near("linear", v[0][0], 15.0, 1e-4);
    assert_near("clamped", v[1][0], 20.0, 1e-4);
    assert_near("unclamped", v[2][0], 25.0, 1e-4);
    assert_near("stepped", v[3][0], 12.5, 1e-4);
    assert_near("smoothstep", v[4][0], 11.5625, 1e-4);
    assert_near("clamp range swaps min and max", v[5][0], 1.0, 1e-6);
    // Point mapping: scale, rotate 90° about z, translate: (1,0,0) → (2,0,0) → (0,2,0) → (1,4,3).
    for (k, want) in [1.0, 4.0, 3.0].iter().enumerate() {
        assert_near("mapping", v[6][k], *want, 1e-3);
    }
}

#[test]
fn noise_is_deterministic_and_within_its_range() {
    let g = graph(&[
        ("t", Node::new("texture_coordinate")),
        (
            "noise",
            Node::new("noise_texture")
                .input("vector", link("t", "object"))
                .input("detail", 8.0)
                .input("roughness", 0.7)
                .input("distortion", 1.0),
        ),
    ]);
    let points: Vec<[f32; 3]> = (0..4096)
        .map(|i| {
            let f = i as f32;
            [
                (f * 0.7548).fract() * 20.0 - 10.0,
                (f * 0.5698).fract() * 20.0 - 10.0,
                f * 0.01,
            ]
        })
        .collect();
    let cases: Vec<Case> = points
        .iter()
        .map(|p| case(&g, "noise", "fac", *p))
        .collect();
    let first = evaluate(&cases);
    let second = evaluate(&cases);
    assert_eq!(first, second, "noise differs between runs");
    let values: Vec<f32> = first.iter().map(|v| v[0]).collect();
    let (lo, hi) = values
        .iter()
        .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
    let mean = values.iter().sum::<f32>() / values.len() as f32;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / values.len() as f32;
    eprintln!("noise: range [{lo}, {hi}], mean {mean}, std {}", var.sqrt());
    assert!(lo >= 0.0 && hi <= 1.0, "noise outside [0, 1]: [{lo}, {hi}]");
    assert!((mean - 0.5).abs() < 0.05, "noise mean {mean}");
    assert!(var.sqrt() > 0.05, "noise is nearly constant");
}

#[test]
fn voronoi_distances_match_a_brute_force_search() {
    let metrics = ["euclidean", "manhattan", "chebyshev"];
    let points: Vec<[f32; 3]> = (0..200)
        .map(|i| {
            let f = i as f32;
            [
                (f * 0.7548).fract() * 4.0 - 2.0,
                (f * 0.5698).fract() * 4.0 - 2.0,
                (f * 0.3141).fract() * 4.0,
            ]
        })
        .collect();
    for (m, metric) in metrics.iter().enumerate() {
        let node = |feature: &str| {
            Node::new("voronoi_texture")
                .param("feature", text(feature))
                .param("distance", text(metric))
                .input("vector", link("t", "object"))
                .input("scale", 3.0)
                .input("randomness", 0.8)
        };
        let g = graph(&[
            ("t", Node::new("texture_coordinate")),
            ("f1", node("f1")),
            ("f2", node("f2")),
        ]);
        let cases: Vec<Case> = points
            .iter()
            .flat_map(|p| {
                [
                    case(&g, "f1", "distance", *p),
                    case(&g, "f1", "position", *p),
                    case(&g, "f2", "distance", *p),
                ]
            })
            .collect();
        let v = evaluate(&cases);
        let mut f2_mismatches = 0;
        for (i, p) in points.iter().enumerate() {
            let (d1, d2, pos) = reference::voronoi_brute_force(*p, 3.0, 0.8, m as u32, 0.5);
            assert_near(&format!("{metric} F1 at {p:?}"), v[3 * i][0], d1, 1e-4);
            for k in 0..3 {
                assert_near(
                    &format!("{metric} F1 position at {p:?}"),
                    v[3 * i + 1][k],
                    pos[k],
                    1e-4,
                );
            }
            // Blender searches 3×3×3 cells for F2; the true F2 can lie further out.
            if (v[3 * i + 2][0] - d2).abs() > 1e-4 {
                f2_mismatches += 1;
            }
        }
        assert!(
            f2_mismatches <= points.len() / 50,
            "{metric}: F2 wrong at {f2_mismatches} points"
        );
    }
}

#[test]
fn white_noise_gradient_wave_and_brick_take_their_stated_values() {
    let t = ("t", Node::new("texture_coordinate"));
    let tex = |node: Node| graph(&[t.clone(), ("n", node.input("vector", link("t", "object")))]);
    let white = tex(Node::new("white_noise_texture"));
    let linear = tex(Node::new("gradient_texture"));
    let quadratic = tex(Node::new("gradient_texture").param("gradient_type", text("quadratic")));
    let spherical = tex(Node::new("gradient_texture").param("gradient_type", text("spherical")));
    let wave = tex(Node::new("wave_texture").input("scale", 1.0));
    let brick = tex(Node::new("brick_texture"));
    let p = [0.3, -1.7, 2.25];
    let v = evaluate(&[
        case(&white, "n", "value", p),
        case(&linear, "n", "fac", [0.3, 0.0, 0.0]),
        case(&quadratic, "n", "fac", [0.3, 0.0, 0.0]),
        case(&spherical, "n", "fac", [0.0, 0.0, 0.0]),
        case(&spherical, "n", "fac", [0.6, 0.0, 0.0]),
        case(&wave, "n", "fac", [0.0, 0.0, 0.0]),
        case(&wave, "n", "fac", [PI / 20.0, 0.0, 0.0]),
        // Scale 5: rows 0.25 high, bricks 0.5 wide; odd rows are not offset.
        case(&brick, "n", "fac", [0.25 / 5.0, 0.375 / 5.0, 0.0]),
        case(&brick, "n", "fac", [0.0, 0.375 / 5.0, 0.0]),
    ]);
    assert_eq!(
        v[0][0],
        reference::hash_vec3_to_float(p),
        "white noise is the hash of p"
    );
    assert_near("linear gradient", v[1][0], 0.3, 1e-6);
    assert_near("quadratic gradient", v[2][0], 0.09, 1e-6);
    // Blender's spherical gradient is 0.999999 - |p| (clamped), hence the tolerance.
    assert_near("spherical gradient at the centre", v[3][0], 1.0, 2e-6);
    assert_near("spherical gradient", v[4][0], 0.4, 2e-6);
    assert_near("sine bands at 0", v[5][0], 0.0, 1e-3);
    assert_near("sine bands at a crest", v[6][0], 1.0, 1e-3);
    assert_near("brick centre", v[7][0], 0.0, 1e-6);
    assert_near("mortar", v[8][0], 1.0, 1e-6);
}

#[test]
fn colour_adjustments_and_inputs_take_their_stated_values() {
    let geo = ("geo", Node::new("geometry"));
    let c = [0.2, 0.4, 0.8];
    let on = |node: Node| graph(&[geo.clone(), ("n", node)]);
    let colour_in = |node: Node| on(node.input("color", link("geo", "position")));
    let v = evaluate(&[
        case(
            &colour_in(Node::new("hue_saturation_value")),
            "n",
            "color",
            c,
        ),
        case(
            &colour_in(Node::new("hue_saturation_value").input("value", 0.5)),
            "n",
            "color",
            c,
        ),
        case(&colour_in(Node::new("invert")), "n", "color", c),
        case(
            &colour_in(Node::new("gamma").input("gamma", 2.0)),
            "n",
            "color",
            c,
        ),
        case(
            &colour_in(Node::new("brightness_contrast").input("bright", 0.1)),
            "n",
            "color",
            c,
        ),
        case(&colour_in(Node::new("rgb_to_bw")), "n", "value", c),
        case(&on(Node::new("fresnel")), "n", "fac", c),
        case(&on(Node::new("layer_weight")), "n", "fresnel", c),
        case(&on(Node::new("layer_weight")), "n", "facing", c),
        case(
            &graph(&[("n", Node::new("texture_coordinate"))]),
            "n",
            "uv",
            c,
        ),
        case(&on(Node::new("normal_map")), "n", "normal", c),
        case(&graph(&[("n", Node::new("object_info"))]), "n", "random", c),
        // The probe's second UV set is the first one swapped.
        case(
            &graph(&[("n", Node::new("texture_coordinate"))]),
            "n",
            "uv1",
            c,
        ),
    ]);
    let near3 = |what: &str, got: [f32; 4], want: [f32; 3]| {
        for k in 0..3 {
            assert_near(what, got[k], want[k], 1e-4);
        }
    };
    near3("neutral HSV", v[0], c);
    near3("half value", v[1], c.map(|x| x * 0.5));
    near3("invert", v[2], c.map(|x| 1.0 - x));
    near3("gamma", v[3], c.map(|x| x * x));
    near3("brightness", v[4], c.map(|x| x + 0.1));
    assert_near(
        "luminance",
        v[5][0],
        0.2126 * 0.2 + 0.7152 * 0.4 + 0.0722 * 0.8,
        1e-5,
    );
    assert_near("fresnel at normal incidence", v[6][0], 0.04, 1e-4);
    assert_near("layer weight fresnel", v[7][0], 1.0 / 9.0, 1e-4);
    assert_near("layer weight facing", v[8][0], 0.0, 1e-4);
    near3("uv", v[9], [c[0], c[1], 0.0]);
    near3("flat normal map", v[10], [0.0, 0.0, 1.0]);
    assert_near("instance random", v[11][0], 0.5, 0.0);
    near3("uv1", v[12], [c[1], c[0], 0.0]);
}

#[test]
fn bump_tilts_the_normal_by_the_height_slope() {
    let mut nodes = x_of_position();
    nodes.push((
        "bump",
        Node::new("bump")
            .input("height", link("x", "x"))
            .input("distance", 0.5),
    ));
    nodes.push(("flat", Node::new("bump").input("height", 0.3)));
    let g = graph(&nodes);
    let v = evaluate(&[
        case(&g, "bump", "normal", [0.4, 0.1, 0.0]),
        case(&g, "flat", "normal", [0.4, 0.1, 0.0]),
    ]);
    // Height h = x along the tangent +x, scaled by 0.5: n ∝ (-0.5, 0, 1).
    let want = Vec3::new(-0.5, 0.0, 1.0).normalize();
    for k in 0..3 {
        assert_near("bumped normal", v[0][k], want[k], 2e-3);
    }
    assert_eq!(
        &v[1][..3],
        &[0.0, 0.0, 1.0],
        "a constant height bumps nothing"
    );
}

fn image_graph(file: &str, params: &[(&str, &str)]) -> Graph {
    let mut node = Node::new("image_texture").param("file", text(file));
    for (k, v) in params {
        node = node.param(k, text(v));
    }
    let mut g = graph(&[("img", node)]);
    g.add(
        "s",
        Node::new("principled_bsdf").input("base_color", link("img", "color")),
    );
    g.add(
        "out",
        Node::new("material_output").input("surface", link("s", "bsdf")),
    );
    g
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[test]
fn image_textures_decode_wrap_and_filter() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("texels.png");
    // Row 0 (top, v near 1): red, green, blue, white; row 1: black, grey 128, magenta at
    // alpha 128, cyan.
    let texels: [[u8; 4]; 8] = [
        [255, 0, 0, 255],
        [0, 255, 0, 255],
        [0, 0, 255, 255],
        [255, 255, 255, 255],
        [0, 0, 0, 255],
        [128, 128, 128, 255],
        [255, 0, 255, 128],
        [0, 255, 255, 255],
    ];
    image::RgbaImage::from_raw(4, 2, texels.concat())
        .unwrap()
        .save(&png)
        .unwrap();
    let file = png.to_str().unwrap();
    let material = |params: &[(&str, &str)]| {
        kiln::scene::Material::from_graph("textured", image_graph(file, params)).unwrap()
    };
    let closest = image_graph(file, &[("interpolation", "closest")]);
    let linear = image_graph(file, &[]);
    let clip = image_graph(file, &[("extension", "clip"), ("interpolation", "closest")]);
    let extend = image_graph(
        file,
        &[("extension", "extend"), ("interpolation", "closest")],
    );
    let mirror = image_graph(
        file,
        &[("extension", "mirror"), ("interpolation", "closest")],
    );
    let data = image_graph(
        file,
        &[("color_space", "linear"), ("interpolation", "closest")],
    );
    let centre = |x: f32, row: f32| [(x + 0.5) / 4.0, 1.0 - (row + 0.5) / 2.0, 0.0];
    let v = evaluate_with_textures(
        vec![material(&[])],
        &[
            case(&closest, "img", "color", centre(0.0, 0.0)),
            case(&closest, "img", "color", centre(1.0, 1.0)),
            case(&closest, "img", "alpha", centre(2.0, 1.0)),
            case(&linear, "img", "color", [0.25, 0.75, 0.0]),
            case(&closest, "img", "color", [1.125, 0.75, 0.0]),
            case(&clip, "img", "color", [1.125, 0.75, 0.0]),
            case(&extend, "img", "color", [1.5, 0.75, 0.0]),
            case(&mirror, "img", "color", [1.125, 0.75, 0.0]),
            case(&data, "img", "color", centre(1.0, 1.0)),
        ],
    );
    let near3 = |what: &str, got: [f32; 4], want: [f32; 3]| {
        for k in 0..3 {
            assert_near(what, got[k], want[k], 1e-4);
        }
    };
    let grey = srgb_to_linear(128.0 / 255.0);
    near3("top-left texel", v[0], [1.0, 0.0, 0.0]);
    near3("sRGB grey decoded", v[1], [grey; 3]);
    assert_near("alpha", v[2][0], 128.0 / 255.0, 1e-4);
    near3("halfway between red and green", v[3], [0.5, 0.5, 0.0]);
    near3("repeat", v[4], [1.0, 0.0, 0.0]);
    near3("clip", v[5], [0.0, 0.0, 0.0]);
    near3("extend", v[6], [1.0, 1.0, 1.0]);
    near3("mirror", v[7], [1.0, 1.0, 1.0]);
    near3("linear data is not decoded", v[8], [128.0 / 255.0; 3]);
}

#[test]
fn float_images_keep_their_range() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("hdr.exr");
    image::Rgba32FImage::from_raw(2, 1, vec![5.0, 0.25, 100.0, 1.0, 0.0, 0.0, 0.0, 1.0])
        .unwrap()
        .save(&exr)
        .unwrap();
    let file = exr.to_str().unwrap();
    let g = image_graph(
        file,
        &[("color_space", "linear"), ("interpolation", "closest")],
    );
    let m = kiln::scene::Material::from_graph("hdr", g.clone()).unwrap();
    let v = evaluate_with_textures(vec![m], &[case(&g, "img", "color", [0.25, 0.5, 0.0])]);
    assert_near("hdr red", v[0][0], 5.0, 5e-3);
    assert_near("hdr green", v[0][1], 0.25, 1e-3);
    assert_near("hdr blue", v[0][2], 100.0, 0.1);
}

#[test]
fn bad_images_are_errors_naming_the_node() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.png");
    let e = kiln::scene::Material::from_graph("m", image_graph(missing.to_str().unwrap(), &[]))
        .unwrap_err();
    assert_eq!(
        (e.node.as_deref(), e.socket.as_deref()),
        (Some("img"), Some("file")),
        "{e}"
    );
    assert!(e.to_string().contains("missing.png"), "{e}");

    // A PNG header claiming 100000 × 100000 pixels is refused before any allocation.
    let huge = dir.path().join("huge.png");
    std::fs::write(&huge, common::png_header(100_000, 100_000)).unwrap();
    let e = kiln::scene::Material::from_graph("m", image_graph(huge.to_str().unwrap(), &[]))
        .unwrap_err();
    assert_eq!(e.node.as_deref(), Some("img"), "{e}");

    let g = graph(&[("img", Node::new("image_texture"))]);
    let mut g2 = g.clone();
    g2.add(
        "s",
        Node::new("principled_bsdf").input("base_color", link("img", "color")),
    );
    g2.add(
        "out",
        Node::new("material_output").input("surface", link("s", "bsdf")),
    );
    let e = kiln::material::compile("m", &g2, "m").unwrap_err();
    assert_eq!(e.socket.as_deref(), Some("file"), "{e}");
}

#[test]
fn vector_math_and_mixes_take_their_stated_values() {
    // a = the position (1, 2, 3); b = (4, -5, 6) and c = (0.5, 0.5, 0.5) constants.
    let op = |name: &str| {
        graph(&[
            ("geo", Node::new("geometry")),
            (
                "v",
                Node::new("vector_math")
                    .param("operation", text(name))
                    .input("a", link("geo", "position"))
                    .input("b", [4.0, -5.0, 6.0])
                    .input("c", [0.5, 0.5, 0.5])
                    .input("scale", 2.0),
            ),
        ])
    };
    let p = [1.0, 2.0, 3.0];
    let table: &[(&str, &str, [f32; 3])] = &[
        ("add", "vector", [5.0, -3.0, 9.0]),
        ("subtract", "vector", [-3.0, 7.0, -3.0]),
        ("multiply", "vector", [4.0, -10.0, 18.0]),
        ("cross", "vector", [27.0, 6.0, -13.0]),
        ("scale", "vector", [2.0, 4.0, 6.0]),
        ("minimum", "vector", [1.0, -5.0, 3.0]),
        ("absolute", "vector", [1.0, 2.0, 3.0]),
        ("dot", "value", [12.0, 0.0, 0.0]),
        ("length", "value", [14f32.sqrt(), 0.0, 0.0]),
        (
            "distance",
            "value",
            [(9.0f32 + 49.0 + 9.0).sqrt(), 0.0, 0.0],
        ),
    ];
    let mut cases: Vec<Case> = table
        .iter()
        .map(|(o, s, _)| case(&op(o), "v", s, p))
        .collect();
    let mixes = graph(&[
        ("geo", Node::new("geometry")),
        (
            "x",
            Node::new("separate_xyz").input("vector", link("geo", "position")),
        ),
        (
            "f",
            Node::new("mix_float")
                .input("factor", 0.25)
                .input("a", link("x", "x"))
                .input("b", 5.0),
        ),
        (
            "v",
            Node::new("mix_vector")
                .input("factor", 0.5)
                .input("a", link("geo", "position"))
                .input("b", [3.0, 4.0, 5.0]),
        ),
        (
            "c",
            Node::new("combine_xyz")
                .input("x", link("x", "z"))
                .input("y", link("x", "y"))
                .input("z", link("x", "x")),
        ),
        ("vc", Node::new("vertex_color")),
        (
            "rgb",
            Node::new("separate_color").input("color", link("geo", "position")),
        ),
    ]);
    cases.push(case(&mixes, "f", "result", p));
    cases.push(case(&mixes, "v", "result", p));
    cases.push(case(&mixes, "c", "vector", p));
    cases.push(case(&mixes, "vc", "color", p));
    cases.push(case(&mixes, "rgb", "green", p));
    let v = evaluate(&cases);
    for (i, (o, _, want)) in table.iter().enumerate() {
        for k in 0..3 {
            assert_near(&format!("vector math {o}"), v[i][k], want[k], 1e-4);
        }
    }
    let n = table.len();
    assert_near("mix float", v[n][0], 2.0, 1e-5);
    for (k, want) in [2.0, 3.0, 4.0].iter().enumerate() {
        assert_near("mix vector", v[n + 1][k], *want, 1e-5);
    }
    for (k, want) in [3.0, 2.0, 1.0].iter().enumerate() {
        assert_near("combine xyz", v[n + 2][k], *want, 1e-6);
    }
    for c in &v[n + 3][..3] {
        assert_near("vertex colour of a mesh without colours", *c, 1.0, 0.0);
    }
    assert_near("separate rgb", v[n + 4][0], 2.0, 0.0);
}
