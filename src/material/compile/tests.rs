//! The compiler's unit tests: muted nodes, reroutes and input ranges.

use super::*;

/// noise → (`between`) → principled base colour → output.
fn noise_into_base_color(between: Option<(&str, Node, &str)>) -> Graph {
    let mut g = Graph::default();
    g.add("noise", Node::new("noise_texture"));
    let base = match between {
        Some((id, node, output)) => {
            g.add(id, node);
            link(id, output)
        }
        None => link("noise", "color"),
    };
    g.add(
        "surface",
        Node::new("principled_bsdf").input("base_color", base),
    );
    g.add(
        "out",
        Node::new(MATERIAL_OUTPUT).input("surface", link("surface", "bsdf")),
    );
    g
}

fn code(graph: &Graph) -> String {
    compile("m", graph, "material_0")
        .unwrap_or_else(|e| panic!("{e}"))
        .code
}

#[test]
fn a_constant_outside_its_hard_range_is_an_error_naming_node_and_socket() {
    let mut g = noise_into_base_color(None);
    g.nodes
        .get_mut("noise")
        .unwrap()
        .inputs
        .insert("scale".into(), (-1.0).into());
    let e = compile("m", &g, "material_0").unwrap_err();
    assert_eq!(
        (e.node.as_deref(), e.socket.as_deref()),
        (Some("noise"), Some("scale")),
        "{e}"
    );
    assert!(e.message.contains("[0, 1000]"), "{e}");
    // The bounds themselves are values the input takes.
    g.nodes
        .get_mut("noise")
        .unwrap()
        .inputs
        .insert("scale".into(), 0.0.into());
    code(&g);
    // The principled BSDF's ranges come from the principled table.
    g.nodes
        .get_mut("surface")
        .unwrap()
        .inputs
        .insert("roughness".into(), 1.5.into());
    let e = compile("m", &g, "material_0").unwrap_err();
    assert_eq!(e.socket.as_deref(), Some("roughness"), "{e}");
}

#[test]
fn a_muted_mix_passes_its_first_colour_input() {
    let mix = || {
        Node::new("mix_color")
            .input("a", link("noise", "color"))
            .input("b", [0.9, 0.1, 0.1])
            .input("factor", 1.0)
    };
    let mut muted = mix();
    muted.muted = true;
    let through_muted = noise_into_base_color(Some(("mix", muted, "result")));
    // The same nodes, the mix unused: what the muted mix must compile to.
    let mut direct = noise_into_base_color(Some(("mix", mix(), "result")));
    direct
        .nodes
        .get_mut("surface")
        .unwrap()
        .inputs
        .insert("base_color".into(), link("noise", "color"));
    assert_eq!(code(&through_muted), code(&direct));
    assert!(!code(&through_muted).contains("node_mix_color"));

    // A constant first colour is passed as that constant, and previewing the muted
    // node shows it.
    let mut constant = Node::new("mix_color").input("a", [0.1, 0.2, 0.3]);
    constant.muted = true;
    let g = noise_into_base_color(Some(("mix", constant, "result")));
    assert!(
        code(&g).contains("vec3<f32>(0.1, 0.2, 0.3)"),
        "{}",
        code(&g)
    );
    let preview = compile_value("m", &g, &Link::new("mix", "result"), "preview")
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        preview.code.contains("vec3<f32>(0.1, 0.2, 0.3)"),
        "{}",
        preview.code
    );
    assert!(!preview.code.contains("node_mix_color"), "{}", preview.code);
}

#[test]
fn a_value_passed_through_a_muted_node_is_not_held_to_the_consumers_range() {
    // 5 suits the muted math node's input, not the colour ramp's factor it reaches.
    let mut math = Node::new("math").input("a", 5.0);
    math.muted = true;
    let mut g = noise_into_base_color(Some((
        "ramp",
        Node::new("color_ramp").input("fac", link("math", "value")),
        "color",
    )));
    g.add("math", math);
    code(&g);
}

#[test]
fn a_muted_node_without_an_input_of_the_output_type_gives_its_zero_or_implicit_default() {
    // The noise texture has no colour input: black.
    let mut g = noise_into_base_color(None);
    g.nodes.get_mut("noise").unwrap().muted = true;
    let c = code(&g);
    assert!(c.contains("vec3<f32>(0.0, 0.0, 0.0)"), "{c}");
    assert!(!c.contains("node_noise"), "{c}");
    // A muted bump passes its normal input, which reads the shading normal unset.
    let mut g = noise_into_base_color(None);
    let mut bump = Node::new("bump").input("height", link("noise", "fac"));
    bump.muted = true;
    g.add("bump", bump);
    g.nodes
        .get_mut("surface")
        .unwrap()
        .inputs
        .insert("normal".into(), link("bump", "normal"));
    let c = code(&g);
    assert!(c.contains("nd_safe_normal(sp.n, sp.n)"), "{c}");
    assert!(!c.contains("nd_bump"), "{c}");
    // Muting does not hide a wire the types refuse.
    let mut g = noise_into_base_color(None);
    let mut mix = Node::new("mix_color");
    mix.muted = true;
    g.add("mix", mix);
    g.nodes
        .get_mut("out")
        .unwrap()
        .inputs
        .insert("surface".into(), link("mix", "result"));
    let e = compile("m", &g, "material_0").unwrap_err();
    assert_eq!(e.node.as_deref(), Some("out"), "{e}");
}

#[test]
fn a_reroute_compiles_to_nothing() {
    let direct = noise_into_base_color(None);
    let rerouted = noise_into_base_color(Some((
        "reroute",
        Node::new(REROUTE).input(REROUTE_INPUT, link("noise", "color")),
        REROUTE_OUTPUT,
    )));
    assert_eq!(code(&rerouted), code(&direct));
    // A chain of reroutes, too.
    let mut chained = rerouted.clone();
    chained.add(
        "reroute_2",
        Node::new(REROUTE).input(REROUTE_INPUT, link("reroute", REROUTE_OUTPUT)),
    );
    chained
        .nodes
        .get_mut("surface")
        .unwrap()
        .inputs
        .insert("base_color".into(), link("reroute_2", REROUTE_OUTPUT));
    assert_eq!(code(&chained), code(&direct));

    // An unconnected reroute gives its consumer the consumer's default.
    let mut g = noise_into_base_color(Some(("reroute", Node::new(REROUTE), REROUTE_OUTPUT)));
    let mut unconnected = noise_into_base_color(None);
    unconnected.nodes.get_mut("surface").unwrap().inputs.clear();
    unconnected.add("reroute", Node::new(REROUTE));
    assert_eq!(code(&g), code(&unconnected));

    // A reroute carries its source's type: a colour through it into a shader input is
    // refused; it holds no value.
    g.nodes
        .get_mut("reroute")
        .unwrap()
        .inputs
        .insert(REROUTE_INPUT.into(), link("noise", "color"));
    g.nodes
        .get_mut("out")
        .unwrap()
        .inputs
        .insert("surface".into(), link("reroute", REROUTE_OUTPUT));
    let e = compile("m", &g, "material_0").unwrap_err();
    assert_eq!(e.node.as_deref(), Some("out"), "{e}");
    let mut valued = direct.clone();
    valued.add("reroute", Node::new(REROUTE).input(REROUTE_INPUT, 0.5));
    let e = compile("m", &valued, "material_0").unwrap_err();
    assert_eq!(e.node.as_deref(), Some("reroute"), "{e}");
}
