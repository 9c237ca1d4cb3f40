//! The editor's interpreting kernel: graph materials run as programs from the parameter
//! buffer render what their compiled code renders (every node of the library, and the
//! bundled graphs in a scene), and a topology edit of a graph is a buffer write, not a
//! kernel.

mod common;

use std::path::Path;
use std::sync::Arc;

use common::{fresh_gpu, gpu, settings};
use kiln::material::compile::link;
use kiln::material::graph::{Node, Param, SocketType};
use kiln::material::nodes::{ParamKind, library};
use kiln::render::materials::scene_materials;
use kiln::render::probe::{Probe, run_probe};
use kiln::render::{KernelKind, RenderControl, RenderSettings, Renderer};
use kiln::scene::{Material, Scene, load_scene};

const SAMPLES: u32 = 6;

/// The bundled surface materials side by side (every example graph: textures, ramps,
/// bumps, image-free). Without the showcase's cloud: a heterogeneous volume compiles the
/// interpreter a second time, into the bake kernel, which on lavapipe adds about a minute
/// to each build here and tests nothing more of the interpreter (the bake runs the same
/// `evaluate_material`).
fn showcase() -> Scene {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/showcase.kiln");
    let mut scene = load_scene(Path::new(path)).expect("the showcase scene loads");
    scene
        .instances
        .retain(|i| scene.materials[i.material].volume_majorant().is_none());
    scene
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
    // A device of its own: it counts the kernels compiled.
    let ctx = fresh_gpu();
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

/// One material per case: output `output` of a `kind` node with its defaults as the
/// emission colour of a principled surface; negated first when `negate` (emission is
/// clamped at 0, so negative values show through the negated case). A volume goes to the
/// material's volume.
fn node_case(kind: &str, output: &str, ty: SocketType, negate: bool) -> kiln::material::Graph {
    let mut g = kiln::material::Graph::default();
    g.add("n", Node::new(kind));
    let mut from = link("n", output);
    if ty == SocketType::Volume {
        g.add(
            "out",
            Node::new("material_output").input("volume", link("n", output)),
        );
        return g;
    }
    if negate {
        let negated = match ty {
            SocketType::Float => Node::new("math")
                .param("operation", Param::Text("multiply".into()))
                .input("a", from)
                .input("b", -1.0),
            _ => Node::new("vector_math")
                .param("operation", Param::Text("scale".into()))
                .input("a", from)
                .input("scale", -1.0),
        };
        g.add("negated", negated);
        let out = if ty == SocketType::Float {
            "value"
        } else {
            "vector"
        };
        from = link("negated", out);
    }
    g.add(
        "s",
        Node::new("principled_bsdf")
            .input("emission_color", from)
            .input("emission_strength", 1.0),
    );
    g.add(
        "out",
        Node::new("material_output").input("surface", link("s", "bsdf")),
    );
    g
}

/// The emission and volume (xyz) and opacity (w) of material `which` of `scene` at `points`, with
/// the scene's materials as a kernel of kind `kernel` holds them.
fn evaluate(scene: &Scene, kernel: KernelKind, cases: &[(u32, [f32; 3])]) -> Vec<[f32; 4]> {
    let materials = scene_materials(scene, kernel).expect("compiles");
    let mut wgsl: String = materials
        .wgsl
        .iter()
        .map(|(_, code)| code.as_str())
        .collect();
    wgsl.push_str(
        "fn material_from_buffer(id: u32, sp: ShadingPoint) -> MaterialEval {
    var none: MaterialEval;
    return none;
}

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn material_probe(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= u32(probe_in[0].x)) {
        return;
    }
    let a = probe_in[1u + i];
    let n = normalize(vec3<f32>(0.3, -0.2, 1.0));
    let sp = ShadingPoint(
        a.xyz, n, n, a.xy, a.yx, vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), n,
        a.xyz, n, fract(a.xyz), vec4<f32>(0.2, 0.5, 0.8, 1.0), 0.25, vec3<f32>(1.0, 2.0, 3.0), false,
    );
    let m = evaluate_material(u32(a.w), sp);
    // The volume's coefficients, weighted apart so that no error in one hides another.
    let v = m.volume;
    let volume = v.absorption + 2.0 * v.scattering + 4.0 * v.emission + vec3<f32>(8.0 * v.g);
    probe_out[i] = vec4<f32>(m.emission + volume, m.opacity);
}
",
    );
    let mut input = vec![[cases.len() as f32, 0.0, 0.0, 0.0]];
    input.extend(cases.iter().map(|(m, p)| [p[0], p[1], p[2], *m as f32]));
    let out = run_probe(
        &gpu(),
        scene,
        &settings(1, 1, 1),
        &Probe {
            name: "material_probe",
            parts: &[("(generated) materials and probe", &wgsl)],
            entry: "material_probe",
            input: bytemuck::cast_slice(&input),
            output_bytes: 16 * cases.len() as u64,
            invocations: cases.len() as u32,
            material_params: &materials.parameters,
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    bytemuck::cast_slice::<u8, [f32; 4]>(&out).to_vec()
}

#[test]
fn every_library_node_interprets_as_it_compiles() {
    let mut graphs = Vec::new();
    for def in library() {
        let reads_images = def.params.iter().any(|p| matches!(p.kind, ParamKind::File));
        if reads_images {
            continue;
        }
        for out in def.outputs.iter().filter(|o| o.ty != SocketType::Bsdf) {
            // A volume is read as it is: shaders cannot be negated.
            let negations: &[bool] = if out.ty == SocketType::Volume {
                &[false]
            } else {
                &[false, true]
            };
            for &negate in negations {
                let name = format!(
                    "{}.{}{}",
                    def.kind,
                    out.name,
                    if negate { " negated" } else { "" }
                );
                graphs.push((name, node_case(def.kind, out.name, out.ty, negate)));
            }
        }
    }
    assert!(graphs.len() > 60, "{} cases", graphs.len());
    let points = [
        [0.25, 0.5, 0.75],
        [1.3, -0.7, 0.2],
        [-2.1, 3.4, 5.9],
        [0.05, 0.95, 0.5],
    ];
    let mut compared = 0;
    // Batches whose programs fit the parameter buffer.
    for batch in graphs.chunks(24) {
        let mut scene = Scene::empty(kiln::scene::Camera::look_at(
            glam::Vec3::Z,
            glam::Vec3::ZERO,
            40.0,
        ));
        for (name, g) in batch {
            scene
                .materials
                .push(Material::from_graph(name, g.clone()).expect(name));
        }
        assert!(interpreted(&scene), "the batch fits the interpreter");
        let cases: Vec<(u32, [f32; 3])> = (0..batch.len() as u32)
            .flat_map(|m| points.map(|p| (m, p)))
            .collect();
        let compiled = evaluate(&scene, KernelKind::General, &cases);
        let run = evaluate(&scene, KernelKind::Interpreted, &cases);
        for (((m, p), c), r) in cases.iter().zip(&compiled).zip(&run) {
            let name = &batch[*m as usize].0;
            for k in 0..4 {
                let tolerance = 1e-4 * c[k].abs().max(1.0);
                assert!(
                    (c[k] - r[k]).abs() <= tolerance,
                    "{name} at {p:?}: compiled {c:?}, interpreted {r:?}"
                );
            }
            compared += 1;
        }
        // Not all zero: the cases show their nodes.
        assert!(
            compiled
                .iter()
                .any(|c| c[0] != 0.0 || c[1] != 0.0 || c[2] != 0.0)
        );
    }
    eprintln!("{compared} node outputs compared");
}
