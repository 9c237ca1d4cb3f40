//! The material-graph compiler: every node type compiles into a kernel naga accepts;
//! errors name the material, node and socket; dead branches emit no code; constants fold.

use kiln::material::compile::link;
use kiln::material::graph::{GROUP, GROUP_INPUT, REROUTE};
use kiln::material::nodes::{self, Default as SocketDefault, ParamKind, library};
use kiln::material::{Graph, Node, Param, SocketType, compile, materials_wgsl, parse_material};
use kiln::render::kernel::path_tracing_kernel;
use kiln::shader::KernelFeatures;

/// A graph whose principled base colour is fed by `node`'s output `output`; a volume
/// output feeds the material's volume instead.
fn feeding_base_color(node: Node, output: &str) -> Graph {
    let mut g = Graph::default();
    let volume = nodes::find(&node.kind)
        .and_then(|d| d.output(output))
        .is_some_and(|(_, o)| o.ty == SocketType::Volume);
    g.add("n", node);
    if volume {
        g.add(
            "out",
            Node::new("material_output").input("volume", link("n", output)),
        );
        return g;
    }
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

/// Whether nodes of `def` read an image file (the image and environment textures).
fn reads_a_file(def: &kiln::material::nodes::NodeDef) -> bool {
    def.params.iter().any(|p| matches!(p.kind, ParamKind::File))
}

#[test]
fn every_node_type_with_every_option_compiles_and_naga_accepts_the_kernel() {
    let mut checked = 0;
    for def in library() {
        if matches!(def.kind, "principled_bsdf" | "material_output") {
            continue;
        }
        // Each enum option once, every output once.
        // Image-reading nodes need a file (compiling does not read it).
        let base = || {
            let n = Node::new(def.kind);
            if reads_a_file(def) {
                n.param("file", Param::Text("wall.png".into()))
            } else {
                n
            }
        };
        let mut variants = vec![base()];
        for p in &def.params {
            if let ParamKind::Enum(options) = &p.kind {
                for o in options.iter().skip(1) {
                    variants.push(base().param(p.name, Param::Text((*o).into())));
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
                        // 0.25, or the nearest value the input's range takes.
                        let range = s.range.expect("a float input declares its range");
                        node = node.input(s.name, 0.25f32.clamp(range.min, range.max));
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

/// `depth` groups, each using the next four times: 4^(depth - 1) noise nodes from a file of
/// a few kilobytes.
fn group_bomb(depth: usize) -> String {
    let groups: Vec<String> = (0..depth)
        .map(|d| {
            let (nodes, out) = if d + 1 == depth {
                (r#""n": (type: "noise_texture")"#.to_owned(), "n.color")
            } else {
                let uses: Vec<String> = (0..4)
                    .map(|i| format!(r#""c{i}": (type: "group", params: {{ "group": "g{}" }})"#, d + 1))
                    .collect();
                (uses.join(", "), "c0.out")
            };
            format!(
                r#""g{d}": (outputs: [(name: "out", type: color)], nodes: {{ {nodes} }}, links: {{ "out": "{out}" }})"#
            )
        })
        .collect();
    format!(
        r#"(
            version: 1,
            name: "bomb",
            groups: {{ {} }},
            nodes: {{
                "g": (type: "group", params: {{ "group": "g0" }}),
                "surface": (type: "principled_bsdf", inputs: {{ "base_color": "g.out" }}),
                "out": (type: "material_output", inputs: {{ "surface": "surface.bsdf" }}),
            }},
        )"#,
        groups.join(", ")
    )
}

#[test]
fn a_graph_expanding_past_the_node_limit_is_refused_before_it_exhausts_memory() {
    // 4^6 = 4096 noise nodes (and the groups around them) expand and compile.
    let (_, small) = parse_material(&group_bomb(7), "bomb.kmat").unwrap();
    compile("bomb", &small, "m").expect("a graph under the limit compiles");
    // 4^13 would take tens of gigabytes: refused after the limit's first nodes.
    let text = group_bomb(14);
    assert!(text.len() < 5000, "a small file: {} bytes", text.len());
    let (_, bomb) = parse_material(&text, "bomb.kmat").unwrap();
    let start = std::time::Instant::now();
    let e = compile("bomb", &bomb, "m").unwrap_err().to_string();
    assert!(
        e.contains(&format!(
            "expands to more than {} nodes",
            kiln::limits::Limits::DEFAULT.graph_nodes
        )),
        "{e}"
    );
    assert!(e.starts_with("material \"bomb\", node \"g/"), "{e}");
    eprintln!("refused in {:?}: {e}", start.elapsed());
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

    // A muted group passes its first colour input through, and a muted node inside one
    // its own.
    let mut muted = graph.clone();
    muted.nodes.get_mut("g").unwrap().muted = true;
    let code = validate_kernel(&muted).unwrap();
    assert!(!code.contains("node_invert"), "{code}");
    // The base colour reads the noise's colour.
    let noise = code
        .lines()
        .find_map(|l| l.trim().strip_prefix("let ")?.split_once(" = node_noise("))
        .map(|(var, _)| var.to_owned())
        .expect("the noise is computed");
    assert!(code.contains(&format!("nd_unit3({noise}.color)")), "{code}");
    let mut inner = graph.clone();
    inner
        .groups
        .get_mut("tint")
        .unwrap()
        .nodes
        .get_mut("inv")
        .unwrap()
        .muted = true;
    assert_eq!(validate_kernel(&inner).unwrap(), code);
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

#[test]
fn nodes_md_is_generated_from_the_declarations() {
    let committed = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/NODES.md"))
        .expect("docs/NODES.md");
    assert!(
        committed == kiln::material::docs::nodes_markdown(),
        "docs/NODES.md is stale: run `cargo run -- material nodes > docs/NODES.md`"
    );
}

/// What the compiler knows of a node comes from its declaration (folding, generated code:
/// `src/material/nodes.rs`); it names no node type of the library, and the structural
/// group kinds only through their constants.
#[test]
fn the_compiler_names_no_node_type() {
    // The compiler and the interpreter's code generator (which knows the bump through
    // its constant: the one node whose input is a function).
    let source = [
        include_str!("../src/material/compile.rs"),
        include_str!("../src/material/compile/program.rs"),
    ]
    .concat();
    assert!(library().len() > 30, "library of {} nodes", library().len());
    let named: Vec<&str> = library()
        .iter()
        .map(|d| d.kind)
        .chain([GROUP, GROUP_INPUT, REROUTE])
        .filter(|kind| source.contains(&format!("\"{kind}\"")))
        .collect();
    assert!(
        named.is_empty(),
        "src/material/compile.rs names node types {named:?}: declare their behaviour on the node"
    );
}

/// The compiler learns what a surface does (transmission, emission, lobes) and what a
/// volume holds (its coefficients) from the declaration of the node feeding the output:
/// every node with a shader output declares it, and no other node does.
#[test]
fn every_shader_node_declares_its_traits() {
    let (mut surfaces, mut volumes) = (0, 0);
    for def in library() {
        let shader = def.outputs.iter().any(|o| o.ty.is_shader());
        assert_eq!(
            def.traits.is_some(),
            shader,
            "{}: traits declared {}, shader output {shader}",
            def.kind,
            def.traits.is_some()
        );
        surfaces += usize::from(def.outputs.iter().any(|o| o.ty == SocketType::Bsdf));
        volumes += usize::from(def.outputs.iter().any(|o| o.ty == SocketType::Volume));
    }
    assert!(surfaces >= 1, "no surface node in the library");
    assert_eq!(
        volumes, 3,
        "Volume Absorption, Volume Scatter, Principled Volume"
    );
}

#[test]
fn the_example_materials_compile() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/materials");
    let mut count = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let (name, graph) = kiln::material::load_material(&path).unwrap_or_else(|e| panic!("{e}"));
        validate_kernel(&graph).unwrap_or_else(|e| panic!("{name}: {e}"));
        count += 1;
    }
    assert!(count >= 8, "{count} example materials");
}

mod random_graphs {
    //! Random graphs from the whole node library: well-typed ones always compile to WGSL
    //! naga accepts; ill-typed or cyclic ones always fail with an error naming a node.

    use super::*;
    use proptest::prelude::*;

    /// A recipe: per node, a type index and, per input, a choice of what feeds it.
    #[derive(Clone, Debug)]
    struct Recipe {
        nodes: Vec<(usize, Vec<u32>)>,
        surface_input: u32,
    }

    fn recipe() -> impl Strategy<Value = Recipe> {
        let kinds = library()
            .iter()
            .filter(|d| !d.outputs.is_empty() && d.kind != "principled_bsdf")
            .count();
        (
            prop::collection::vec((0..kinds, prop::collection::vec(any::<u32>(), 16)), 1..12),
            any::<u32>(),
        )
            .prop_map(|(nodes, surface_input)| Recipe {
                nodes,
                surface_input,
            })
    }

    /// Builds the graph: each input links, when the choice says so, to an earlier node's
    /// output of a convertible type; otherwise it keeps its default.
    fn build(r: &Recipe) -> Graph {
        let defs: Vec<_> = library()
            .iter()
            .filter(|d| !d.outputs.is_empty() && d.kind != "principled_bsdf")
            .collect();
        let mut g = Graph::default();
        let mut outputs: Vec<(String, &str, SocketType)> = Vec::new();
        for (i, (kind, choices)) in r.nodes.iter().enumerate() {
            let def = defs[*kind];
            let mut node = Node::new(def.kind);
            if reads_a_file(def) {
                node = node.param("file", Param::Text("wall.png".into()));
            }
            for (k, socket) in def.inputs.iter().enumerate() {
                let choice = choices[k % choices.len()];
                let usable: Vec<_> = outputs
                    .iter()
                    .filter(|o| o.2.converts_to(socket.ty).is_some())
                    .collect();
                if choice % 3 != 0 && !usable.is_empty() {
                    let o = usable[choice as usize % usable.len()];
                    node = node.input(socket.name, link(&o.0, o.1));
                }
            }
            for p in &def.params {
                if let ParamKind::Enum(options) = &p.kind {
                    let o = options[choices[p.name.len() % choices.len()] as usize % options.len()];
                    node = node.param(p.name, Param::Text(o.into()));
                }
            }
            let id = format!("n{i}");
            outputs.extend(def.outputs.iter().map(|o| (id.clone(), o.name, o.ty)));
            g.add(&id, node);
        }
        let colour: Vec<_> = outputs
            .iter()
            .filter(|o| o.2.converts_to(SocketType::Color).is_some())
            .collect();
        let mut surface = Node::new("principled_bsdf");
        if !colour.is_empty() {
            let o = colour[r.surface_input as usize % colour.len()];
            surface = surface.input("base_color", link(&o.0, o.1));
            let f = colour[(r.surface_input / 7) as usize % colour.len()];
            surface = surface.input("roughness", link(&f.0, f.1));
        }
        g.add("surface", surface);
        g.add(
            "out",
            Node::new("material_output").input("surface", link("surface", "bsdf")),
        );
        g
    }

    /// The case saved in tests/material_graph.proptest-regressions, kept as a plain test so
    /// that it runs even if the strategy changes and the saved seed draws something else.
    #[test]
    fn saved_regression_graph_compiles_to_wgsl_naga_accepts() {
        let r = Recipe {
            nodes: vec![
                (23, vec![0; 16]),
                (35, [0, 0, 181813].into_iter().chain([0; 13]).collect()),
                (
                    29,
                    vec![
                        0, 0, 0, 0, 0, 883888, 810781690, 1491251228, 659804826, 3410598157,
                        941585502, 2999617159, 337941281, 3503748511, 2765700171, 1002993382,
                    ],
                ),
                (
                    29,
                    vec![
                        3721592420, 2828449880, 961664440, 1098470598, 1497447500, 3751015802,
                        1970009009, 1259969231, 3249966144, 208169386, 3483773904, 820967387,
                        411751727, 1537567071, 188922359, 4102123990,
                    ],
                ),
                (
                    16,
                    vec![
                        2586941767, 2940236954, 2722001500, 3201404051, 1838218195, 556815603,
                        3334310184, 1548370087, 2354837781, 422380312, 3691918197, 2649572163,
                        2859358550, 3544293112, 920482437, 363547315,
                    ],
                ),
                (
                    12,
                    vec![
                        145398947, 140896700, 1792784705, 1443426680, 3226615556, 2569757146,
                        874151407, 1431912913, 1524600900, 4197086630, 3779246541, 3058945021,
                        1208300270, 85661394, 776627360, 1981883940,
                    ],
                ),
            ],
            surface_input: 3191564178,
        };
        let g = build(&r);
        if let Err(e) = validate_kernel(&g) {
            panic!("{e}\n{g:#?}");
        }
    }

    proptest! {
        // Failures are saved to, and replayed from, tests/material_graph.proptest-regressions.
        #![proptest_config(ProptestConfig {
            cases: 300,
            failure_persistence: Some(Box::new(proptest::test_runner::FileFailurePersistence::SourceParallel("proptest-regressions"))),
            ..ProptestConfig::default()
        })]

        #[test]
        fn well_typed_graphs_compile_to_wgsl_naga_accepts(r in recipe()) {
            let g = build(&r);
            if let Err(e) = validate_kernel(&g) {
                panic!("{e}\n{g:#?}");
            }
        }

        #[test]
        fn cycles_are_errors_naming_a_node(r in recipe(), from in any::<usize>()) {
            let mut g = build(&r);
            // Feed the last node's first output back into an input of an earlier node
            // (or itself) that the output reaches.
            let last = r.nodes.len() - 1;
            let defs: Vec<_> = library().iter().filter(|d| d.kind != "material_output" && d.kind != "principled_bsdf").collect();
            let out_def = defs[r.nodes[last].0];
            prop_assume!(!out_def.outputs.is_empty());
            // Make the last node read the surface's input chain: link the chosen earlier
            // node's first input to the last node, and the last node's first input to it.
            let target = from % (last + 1);
            let t_def = defs[r.nodes[target].0];
            prop_assume!(!t_def.inputs.is_empty() && !out_def.inputs.is_empty());
            let o = &out_def.outputs[0];
            prop_assume!(o.ty.converts_to(t_def.inputs[0].ty).is_some());
            let t_out = t_def.outputs.first();
            prop_assume!(t_out.is_some_and(|t| t.ty.converts_to(out_def.inputs[0].ty).is_some()));
            g.nodes.get_mut(&format!("n{target}")).unwrap().inputs.insert(t_def.inputs[0].name.into(), link(&format!("n{last}"), o.name));
            g.nodes.get_mut(&format!("n{last}")).unwrap().inputs.insert(out_def.inputs[0].name.into(), link(&format!("n{target}"), t_out.unwrap().name));
            // Route the cycle to the output so it is not pruned.
            g.nodes.get_mut("surface").unwrap().inputs.insert("coat_weight".into(), link(&format!("n{last}"), o.name));
            let e = compile("random", &g, "m").unwrap_err();
            prop_assert!(e.node.is_some(), "{}", e);
            prop_assert!(e.to_string().contains("cycle"), "{}", e);
        }

        #[test]
        fn ill_typed_links_are_errors_naming_node_and_socket(r in recipe(), pick in any::<usize>()) {
            let mut g = build(&r);
            // A BSDF fed into any non-BSDF input.
            let ids: Vec<String> = g.nodes.iter().filter(|(_, n)| n.kind != "material_output" && n.kind != "principled_bsdf").map(|(k, _)| k.clone()).collect();
            let id = &ids[pick % ids.len()];
            let def = kiln::material::nodes::find(&g.nodes[id].kind).unwrap();
            prop_assume!(!def.inputs.is_empty());
            let socket = def.inputs[pick % def.inputs.len()].name;
            g.nodes.get_mut(id).unwrap().inputs.insert(socket.into(), link("surface", "bsdf"));
            let e = compile("random", &g, "m").unwrap_err();
            prop_assert!(e.node.is_some() && e.socket.is_some(), "{}", e);
        }
    }
}
