//! "Preview this node" (Blender's Node Wrangler, Ctrl+Shift+click): the viewport shows one
//! node's output on its material's surfaces instead of the material, until cleared.
//!
//! The mechanism is Node Wrangler's: the material's graph is rewired for the viewport
//! only. A shader output becomes the surface itself; a value (float, vector, colour)
//! becomes the emission of a Principled BSDF that reflects nothing (black base, no
//! specular, coat, sheen or transmission), so the surface shows exactly the value as
//! radiance, which the viewport's Standard view shows as the value (floats as grey).
//! It is a view state, not a document edit: the document, its undo history, its files,
//! final renders and `kiln render` never see the rewired graph — the app swaps the
//! rewired material into the scene it hands the viewport ([`preview_scene`]) and nowhere
//! else.

use std::path::Path;

use super::graph_edit::sockets_of;
use crate::material::nodes::MATERIAL_OUTPUT;
use crate::material::texture::load_texture;
use crate::material::{Graph, Input, Link, Node, SocketType, Value};
use crate::scene::{Material, Scene};

/// The node the viewport previews: material `material`'s node `node`, its output number
/// `output` (repeated Ctrl+Shift+clicks step through a node's outputs, as Node Wrangler's
/// do).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ViewportPreview {
    pub material: usize,
    pub node: String,
    pub output: usize,
}

/// `graph` rewired so that its surface shows output number `output` of node `node`; with
/// the name of that output. A two-component value has no colour to show and is refused,
/// as is a node that is not there or has no such output.
pub fn preview_graph(graph: &Graph, node: &str, output: usize) -> Result<(Graph, String), String> {
    let Some(n) = graph.nodes.get(node) else {
        return Err(format!("no node \"{node}\""));
    };
    let sockets = sockets_of(graph, n)?;
    let Some((socket, ty)) = sockets.outputs.get(output).cloned() else {
        return Err(format!("node \"{node}\" has no output {output}"));
    };
    let at = Input::Link(Link::new(node, &socket));
    let mut rewired = graph.clone();
    let fresh = |graph: &Graph, base: &str| {
        let mut id = format!("{node}~{base}");
        while graph.nodes.contains_key(&id) {
            id.push('~');
        }
        id
    };
    let (surface, volume) = match ty {
        SocketType::Bsdf => (Some(at), None),
        // A volume alone: its boundary lets light through.
        SocketType::Volume => (None, Some(at)),
        SocketType::Vec2 => {
            return Err(format!(
                "output \"{socket}\" of node \"{node}\" has two components: no colour to show"
            ));
        }
        SocketType::Float | SocketType::Vector | SocketType::Color => {
            let id = fresh(&rewired, "preview_emission");
            let black = || Input::Value(Value::Vec3([0.0; 3]));
            let zero = || Input::Value(Value::Float(0.0));
            let emission = Node::new("principled_bsdf")
                .input("base_color", black())
                .input("specular_weight", zero())
                .input("coat_weight", zero())
                .input("sheen_weight", zero())
                .input("transmission_weight", zero())
                .input("emission_color", at)
                .input("emission_strength", Input::Value(Value::Float(1.0)));
            rewired.add(&id, emission);
            (Some(Input::Link(Link::new(&id, "bsdf"))), None)
        }
    };
    let output_id = fresh(&rewired, "preview_output");
    let mut output = Node::new(MATERIAL_OUTPUT);
    if let Some(surface) = surface {
        output = output.input("surface", surface);
    }
    if let Some(volume) = volume {
        output = output.input("volume", volume);
    }
    rewired.add(&output_id, output);
    rewired.output = Some(output_id);
    Ok((rewired, socket))
}

/// Replaces material `preview.material` of `scene` (the viewport's) by its graph `graph`
/// (the document's edited graph) rewired to show the previewed output; returns that
/// output's name. The material's images are reused, not read again.
pub fn preview_scene(
    scene: &mut Scene,
    graph: &Graph,
    preview: &ViewportPreview,
) -> Result<String, String> {
    let Some(material) = scene.materials.get(preview.material) else {
        return Err(format!("no material {}", preview.material));
    };
    let (rewired, socket) = preview_graph(graph, &preview.node, preview.output)?;
    let known = material
        .graph
        .as_ref()
        .map(|g| g.images.clone())
        .unwrap_or_default();
    let load = |file: &str| match known.get(file) {
        Some(image) => Ok((**image).clone()),
        None => load_texture(Path::new(file)),
    };
    let shown =
        Material::from_graph_with(&material.name, rewired, &load).map_err(|e| e.to_string())?;
    scene.materials[preview.material] = shown;
    Ok(socket)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::compile;

    fn graph() -> Graph {
        let mut g = Graph::default();
        g.add(
            "red",
            Node::new("rgb").input("color", Input::Value(Value::Vec3([1.0, 0.0, 0.0]))),
        );
        g.add("noise", Node::new("noise_texture"));
        g.add(
            "surface",
            Node::new("principled_bsdf").input("base_color", Link::new("noise", "color")),
        );
        g.add(
            "output",
            Node::new(MATERIAL_OUTPUT).input("surface", Link::new("surface", "bsdf")),
        );
        g
    }

    #[test]
    fn a_constant_colour_becomes_the_only_emission_of_a_black_surface() {
        let (rewired, socket) = preview_graph(&graph(), "red", 0).unwrap();
        assert_eq!(socket, "color");
        let compiled = compile("m", &rewired, "material").unwrap();
        // Constant emission of exactly the value: the surface is sampled as a light of
        // that colour, and nothing of it reflects.
        assert_eq!(compiled.traits.constant_emission, Some([1.0, 0.0, 0.0]));
        use crate::shader::lobes;
        let layers = lobes::COAT | lobes::SHEEN | lobes::METAL | lobes::GLASS;
        assert_eq!(
            compiled.traits.lobes & layers,
            0,
            "{:b}",
            compiled.traits.lobes
        );
        assert!(!compiled.traits.transmissive);
    }

    #[test]
    fn every_output_type_but_two_components_rewires_to_a_graph_that_compiles() {
        let g = graph();
        for (node, output) in [("noise", 0), ("noise", 1), ("surface", 0), ("red", 0)] {
            let (rewired, _) = preview_graph(&g, node, output)
                .unwrap_or_else(|e| panic!("{node} output {output}: {e}"));
            compile("m", &rewired, "material")
                .unwrap_or_else(|e| panic!("{node} output {output}: {e}"));
            assert!(rewired.output.is_some() && rewired.output != g.output);
        }
        let e = preview_graph(&g, "noise", 7).unwrap_err();
        assert!(e.contains("noise") && e.contains('7'), "{e}");
        let e = preview_graph(&g, "nowhere", 0).unwrap_err();
        assert!(e.contains("nowhere"), "{e}");
    }

    #[test]
    fn the_preview_replaces_only_the_viewports_copy_of_the_material() {
        let g = graph();
        let material = Material::from_graph("m", g.clone()).unwrap();
        let mut scene = Scene::empty(crate::scene::Camera::look_at(
            glam::Vec3::Z,
            glam::Vec3::ZERO,
            40.0,
        ));
        scene.materials = vec![material.clone()];
        let preview = ViewportPreview {
            material: 0,
            node: "red".into(),
            output: 0,
        };
        preview_scene(&mut scene, &g, &preview).unwrap();
        assert_ne!(scene.materials[0], material);
        assert_eq!(scene.materials[0].name, "m");
        let missing = ViewportPreview {
            material: 3,
            ..preview
        };
        assert!(
            preview_scene(&mut scene, &g, &missing)
                .unwrap_err()
                .contains('3')
        );
    }
}
