//! The material-graph compiler: every node type compiles into a kernel naga accepts;
//! errors name the material, node and socket; dead branches emit no code; constants fold.

use kiln::material::compile::link;
use kiln::material::nodes::{Default as SocketDefault, ParamKind, library};
use kiln::material::{Graph, Node, Param, SocketType, compile, materials_wgsl, parse_material};
use kiln::render::kernel::{KernelFeatures, path_tracing_kernel};

/// A graph whose principled base colour is fed by `node`'s output `output`.
fn feeding_base_color(node: Node, output: &str) -> Graph {
    let mut g = Graph::default();
    g.add("n", node);
    g.add(
        "surface",
        Node::new("principled_bsdf").input("base_color", link("n", output)),
    );
    g.add(
        "out",
        Node::new("material_output").input("surface", link("surface", "bsdf")),
    );
    g
}

fn validate_kernel(graph: &Graph) -> Result<String, String> {
    let compiled = compile("test", graph, "material_0").map_err(|e| e.to_string())?;
    let wgsl = materials_wgsl(&[(0, &compiled)]);
    path_tracing_kernel(&KernelFeatures::default(), &wgsl)
        .validate()
        .map_err(|e| e.to_string())?;
    Ok(compiled.code)
}

#[test]
fn every_node_type_with_every_option_compiles_and_naga_accepts_the_kernel() {
    let mut checked = 0;
    for def in library() {
        if matches!(def.kind, "principled_bsdf" | "material_output") {
            continue;
        }
        // Each enum option once, every output once.
        let mut variants = vec![Node::new(def.kind)];
        for p in &def.params {
            if let ParamKind::Enum(options) = &p.kind {
                for o in options.iter().skip(1) {
                    variants.push(Node::new(def.kind).param(p.name, Param::Text((*o).into())));
                }
            }
        }
        for node in variants {
            for output in &def.outputs {
                // Connect every input that has an implicit default explicitly too, so both
                // paths compile.
                let mut node = node.clone();
                for s in &def.inputs {
                    if matches!(s.default, SocketDefault::Value(_)) && s.ty == SocketType::Float {
                        node = node.input(s.name, 0.25);
                    }
                }
                let graph = feeding_base_color(node.clone(), output.name);
                if let Err(e) = validate_kernel(&graph) {
                    panic!(
                        "{} output {} ({:?}): {e}",
                        def.kind, output.name, node.params
                    );
                }
                checked += 1;
            }
        }
    }
    assert!(checked > 100, "only {checked} variants");
}

#[test]
fn a_cycle_is_an_error_naming_a_node_on_it() {
    let mut g = feeding_base_color(Node::new("math").input("a", link("m2", "value")), "value");
    g.add("m2", Node::new("math").input("a", link("n", "value")));
    let e = compile("looped", &g, "material_0").unwrap_err();
    assert_eq!(e.material, "looped");
    assert!(matches!(e.node.as_deref(), Some("n") | Some("m2")), "{e}");
    assert!(e.to_string().contains("cycle"), "{e}");
}

#[test]
fn type_errors_name_node_and_socket() {
    // A BSDF cannot feed a colour.
    let mut g = feeding_base_color(Node::new("rgb"), "color");
    g.add(
        "bad",
        Node::new("invert").input("color", link("surface", "bsdf")),
    );
    g.nodes
        .get_mut("surface")
        .unwrap()
        .inputs
        .insert("coat_color".into(), link("bad", "color"));
    let e = compile("typed", &g, "material_0").unwrap_err();
    assert_eq!(
        (e.node.as_deref(), e.socket.as_deref()),
        (Some("bad"), Some("color")),
        "{e}"
    );
    assert!(e.to_string().contains("bsdf output"), "{e}");

    let g = feeding_base_color(Node::new("rgb").input("colour", 0.5), "color");
    let e = compile("typo", &g, "material_0").unwrap_err();
    assert_eq!(
        (e.node.as_deref(), e.socket.as_deref()),
        (Some("n"), Some("colour")),
        "{e}"
    );

    let g = feeding_base_color(Node::new("no_such_node"), "color");
    let e = compile("unknown", &g, "material_0").unwrap_err();
    assert!(
        e.to_string().contains("unknown node type \"no_such_node\""),
        "{e}"
    );

    let g = feeding_base_color(
        Node::new("math").param("operation", Param::Text("plus".into())),
        "value",
    );
    let e = compile("param", &g, "material_0").unwrap_err();
    assert_eq!(e.socket.as_deref(), Some("operation"), "{e}");

    let g = feeding_base_color(Node::new("rgb"), "colour");
    let e = compile("output", &g, "material_0").unwrap_err();
    assert!(e.to_string().contains("has no output \"colour\""), "{e}");
}

#[test]
fn dead_branches_emit_no_code_and_constants_fold() {
    let mut g = feeding_base_color(
        Node::new("math")
            .param("operation", Param::Text("multiply".into()))
            .input("a", link("two", "value"))
            .input("b", 0.25),
        "value",
    );
    g.add("two", Node::new("value").input("value", 2.0));
    // Dead: nothing reads it.
    g.add("dead", Node::new("voronoi_texture"));
    let code = validate_kernel(&g).unwrap();
    assert!(!code.contains("node_voronoi"), "dead node emitted:\n{code}");
    assert!(!code.contains("node_math"), "2 × 0.25 not folded:\n{code}");
    assert!(
        code.contains("vec3<f32>(0.5, 0.5, 0.5)"),
        "folded value missing:\n{code}"
    );
}

#[test]
fn identical_nodes_are_merged() {
    let mut g = feeding_base_color(
        Node::new("mix_color")
            .input("a", link("noise_a", "color"))
            .input("b", link("noise_b", "color")),
        "result",
    );
    g.add("noise_a", Node::new("noise_texture").input("scale", 3.0));
    g.add("noise_b", Node::new("noise_texture").input("scale", 3.0));
    let code = validate_kernel(&g).unwrap();
    assert_eq!(code.matches("node_noise(").count(), 1, "{code}");
}

#[test]
fn groups_expand_and_check_their_sockets() {
    let text = r#"(
        version: 1,
        name: "grouped",
        groups: {
            "tint": (
                inputs: [(name: "color", type: color, default: (1.0, 1.0, 1.0)), (name: "amount", type: float)],
                outputs: [(name: "result", type: color)],
                nodes: {
                    "inv": (type: "invert", inputs: { "color": "in.color", "fac": "in.amount" }),
                    "in": (type: "group_input"),
                },
                links: { "result": "inv.color" },
            ),
        },
        nodes: {
            "noise": (type: "noise_texture"),
            "g": (type: "group", params: { "group": "tint" }, inputs: { "color": "noise.color", "amount": 0.5 }),
            "surface": (type: "principled_bsdf", inputs: { "base_color": "g.result" }),
            "out": (type: "material_output", inputs: { "surface": "surface.bsdf" }),
        },
    )"#;
    let (name, graph) = parse_material(text, "grouped.kmat").unwrap();
    assert_eq!(name, "grouped");
    let code = validate_kernel(&graph).unwrap();
    assert!(code.contains("node_invert(0.5, n"), "{code}");

    // A group that contains itself is refused, not expanded forever.
    let mut looped = graph.clone();
    looped.groups.get_mut("tint").unwrap().nodes.insert(
        "again".into(),
        Node::new("group").param("group", Param::Text("tint".into())),
    );
    let e = compile("looped", &looped, "m").unwrap_err();
    assert!(e.to_string().contains("deeper"), "{e}");
}

#[test]
fn material_files_check_their_version() {
    let newer = parse_material("(version: 2, nodes: {})", "new.kmat").unwrap_err();
    assert!(newer.to_string().contains("update Kiln"), "{newer}");
    let older = parse_material("(version: 0, nodes: {})", "old.kmat").unwrap_err();
    assert!(older.to_string().contains("no longer read"), "{older}");
    let none = parse_material("(nodes: {})", "none.kmat").unwrap_err();
    assert!(none.to_string().contains("version"), "{none}");
    let typo = parse_material("(version: 1, nodez: {})", "typo.kmat").unwrap_err();
    assert!(typo.to_string().starts_with("typo.kmat:1:"), "{typo}");
}
