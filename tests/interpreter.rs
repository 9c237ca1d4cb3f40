//! The editor's interpreting kernel: graph materials run as programs from the parameter
//! buffer render what their compiled code renders, and a topology edit of a graph is a
//! buffer write, not a kernel.

mod common;

use std::path::Path;
use std::sync::Arc;

use common::{gpu, settings};
use kiln::material::compile::link;
use kiln::material::graph::Node;
use kiln::render::materials::scene_materials;
use kiln::render::{KernelKind, RenderControl, RenderSettings, Renderer};
use kiln::scene::{Material, Scene, load_scene};

const SAMPLES: u32 = 6;

/// The bundled materials side by side (every example graph: textures, ramps, bumps,
/// image-free).
fn showcase() -> Scene {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/showcase.kiln");
    load_scene(Path::new(path)).expect("the showcase scene loads")
}

fn render_settings(kernel: KernelKind) -> RenderSettings {
    RenderSettings {
        kernel,
        max_bounces: 3,
        ..settings(64, 40, SAMPLES)
    }
}

/// Mean radiance per pixel and channel.
fn radiance(renderer: &mut Renderer) -> Vec<f64> {
    let stats = renderer
        .render(0..SAMPLES, RenderControl::default())
        .expect("render");
    assert!(stats.completed);
    let film = renderer.read_film().expect("film");
    film.sums
        .iter()
        .flat_map(|s| [s[0] / s[3], s[1] / s[3], s[2] / s[3]])
        .collect()
}

fn relative_rmse(a: &[f64], b: &[f64]) -> f64 {
    let mean = b.iter().sum::<f64>() / b.len() as f64;
    let squares: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    (squares / a.len() as f64).sqrt() / mean
}

fn interpreted(scene: &Scene) -> bool {
    let materials = scene_materials(scene, KernelKind::Interpreted).expect("compiles");
    materials
        .wgsl
        .iter()
        .any(|(_, code)| code.contains("fn nd_interpret("))
}

/// The showcase's marble with an invert node between its ramp and the base colour: a
/// topology edit.
fn with_inverted_marble(scene: &Scene) -> Scene {
    let mut edited = scene.clone();
    let i = (edited.materials.iter())
        .position(|m| m.name == "marble")
        .expect("the showcase has marble");
    let mut graph = edited.materials[i]
        .graph
        .as_ref()
        .expect("a graph")
        .graph
        .clone();
    let (surface, base) = graph
        .nodes
        .iter()
        .find_map(|(id, n)| Some((id.clone(), n.inputs.get("base_color")?.clone())))
        .expect("a node with a linked base colour");
    let kiln::material::Input::Link(from) = base else {
        panic!("marble's base colour is linked");
    };
    graph.add(
        "inverted",
        Node::new("invert").input("color", link(&from.node, &from.socket)),
    );
    graph
        .nodes
        .get_mut(&surface)
        .unwrap()
        .inputs
        .insert("base_color".into(), link("inverted", "color"));
    edited.materials[i] = Material::from_graph("marble", graph).expect("the edit compiles");
    edited
}

#[test]
fn interpreted_graphs_render_what_their_compiled_code_renders() {
    let ctx = gpu();
    let scene = showcase();
    assert!(interpreted(&scene), "the showcase's graphs are interpreted");
    let mut compiled = Renderer::new(
        Arc::clone(&ctx),
        &scene,
        render_settings(KernelKind::General),
    )
    .expect("renderer");
    let mut interpreter = Renderer::new(
        Arc::clone(&ctx),
        &scene,
        render_settings(KernelKind::Interpreted),
    )
    .expect("renderer");
    let reference = radiance(&mut compiled);
    // The same arithmetic in another order (a loop over ramp stops, values through
    // registers) rounds differently in the last bits and sends a few paths elsewhere;
    // a wrong node or constant would differ by far more (the topology edit below: ~0.2).
    let error = relative_rmse(&radiance(&mut interpreter), &reference);
    assert!(
        error < 5e-3,
        "interpreted and compiled graphs differ: relative RMSE {error}"
    );
    let edited = with_inverted_marble(&scene);
    let edit = relative_rmse(
        &radiance(
            &mut Renderer::new(
                Arc::clone(&ctx),
                &edited,
                render_settings(KernelKind::General),
            )
            .expect("renderer"),
        ),
        &reference,
    );
    assert!(edit > 10.0 * error, "the edit shows: relative RMSE {edit}");
}

#[test]
fn a_topology_edit_is_a_parameter_write_in_the_interpreting_kernel() {
    let ctx = gpu();
    let old = showcase();
    let new = with_inverted_marble(&old);
    let (a, b) = (
        scene_materials(&old, KernelKind::Interpreted).unwrap(),
        scene_materials(&new, KernelKind::Interpreted).unwrap(),
    );
    assert_eq!(a.wgsl, b.wgsl, "the interpreter's code depends on a graph");
    assert_ne!(
        a.parameters, b.parameters,
        "the program is in the parameters"
    );
    // The compiled kernels differ: there the edit is a compile.
    assert_ne!(
        scene_materials(&old, KernelKind::General).unwrap().wgsl,
        scene_materials(&new, KernelKind::General).unwrap().wgsl
    );

    let s = render_settings(KernelKind::Interpreted);
    let mut renderer = Renderer::new(Arc::clone(&ctx), &old, s).expect("renderer");
    radiance(&mut renderer);
    let compiled = ctx.pipelines_compiled();
    let updated = renderer.update(&old, &new).expect("an in-place update");
    assert!(updated.materials, "{updated:?}");
    renderer.clear_film();
    let after = radiance(&mut renderer);
    assert_eq!(
        ctx.pipelines_compiled(),
        compiled,
        "the update compiled a kernel"
    );
    let fresh = radiance(&mut Renderer::new(Arc::clone(&ctx), &new, s).expect("renderer"));
    assert_eq!(
        after, fresh,
        "the updated renderer renders what a fresh one does"
    );
}
