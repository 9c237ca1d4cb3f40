//! A scene's material: the principled parameters (declared once, with their defaults and
//! ranges, in `crate::shader::principled`), or a node graph that computes them per shading
//! point.

use std::sync::Arc;

use glam::Vec3;

use crate::material::texture::{TextureImage, load_texture};
use crate::material::{Graph, GraphError, Input, Link, MaterialTraits, Node, Param, Value};
use crate::shader::principled::{self, ParamValue, Principled};

#[derive(Clone, Debug, PartialEq, Default)]
pub struct Material {
    pub name: String,
    /// The fixed parameters. A graph material keeps here only what the renderer must know
    /// in advance: its constant emission, if any.
    pub principled: Principled,
    /// A node graph computing the parameters per shading point.
    pub graph: Option<Arc<GraphMaterial>>,
}

/// A material's node graph with what compiling it told about it.
#[derive(Clone, Debug, PartialEq)]
pub struct GraphMaterial {
    pub graph: Graph,
    pub traits: MaterialTraits,
    /// The images its image-texture nodes read, by file.
    pub images: std::collections::BTreeMap<String, Arc<TextureImage>>,
}

impl Material {
    /// A purely Lambertian surface (no specular layer).
    pub fn diffuse(name: &str, base_color: Vec3) -> Self {
        Self::with(
            name,
            Principled {
                base_color,
                specular_weight: 0.0,
                ..Principled::default()
            },
        )
    }

    /// A material with these fixed parameters.
    pub fn with(name: &str, principled: Principled) -> Self {
        Self {
            name: name.to_owned(),
            principled,
            graph: None,
        }
    }

    /// A black surface emitting `radiance` from its front side.
    pub fn emitter(name: &str, radiance: Vec3) -> Self {
        Self::with(
            name,
            Principled {
                base_color: Vec3::ZERO,
                specular_weight: 0.0,
                emission_color: radiance,
                emission_strength: 1.0,
                ..Principled::default()
            },
        )
    }

    /// A material computed by a node graph. The graph is compiled once here, so errors
    /// surface when the material is made, naming the node and socket.
    pub fn from_graph(name: &str, graph: Graph) -> Result<Self, GraphError> {
        Self::from_graph_with(name, graph, &|file| {
            load_texture(std::path::Path::new(file))
        })
    }

    /// [`Material::from_graph`] with images loaded by `load` (importers resolve images
    /// embedded in the imported file).
    pub fn from_graph_with(
        name: &str,
        graph: Graph,
        load: &dyn Fn(&str) -> Result<TextureImage, String>,
    ) -> Result<Self, GraphError> {
        let compiled = crate::material::compile(name, &graph, "material")?;
        let mut images = std::collections::BTreeMap::new();
        for (file, node) in &compiled.images {
            let image = load(file).map_err(|message| GraphError {
                material: name.to_owned(),
                node: Some(node.clone()),
                socket: Some("file".into()),
                message,
            })?;
            images.insert(file.clone(), Arc::new(image));
        }
        let traits = compiled.traits;
        let emission = traits.constant_emission.map_or(Vec3::ZERO, Vec3::from);
        Ok(Self {
            name: name.to_owned(),
            principled: Principled {
                emission_color: emission,
                emission_strength: if emission == Vec3::ZERO { 0.0 } else { 1.0 },
                ..Principled::default()
            },
            graph: Some(Arc::new(GraphMaterial {
                graph,
                traits,
                images,
            })),
        })
    }

    /// The principled lobes this material can reach ([`crate::shader::lobes`]).
    pub fn lobes(&self) -> u32 {
        if let Some(g) = &self.graph {
            return g.traits.lobes;
        }
        let p = &self.principled;
        crate::material::principled_lobes(
            Some(p.coat_weight),
            Some(p.sheen_weight),
            Some(p.metallic),
            Some(p.transmission_weight),
            Some(p.specular_weight),
            Some(p.subsurface_weight),
            p.thin_walled,
        ) | crate::material::cutout_lobes(Some(p.alpha))
    }

    /// The emitted radiance known in advance (a graph's constant emission).
    pub fn emission(&self) -> Vec3 {
        self.principled.emission()
    }

    pub fn is_emissive(&self) -> bool {
        self.emission().max_element() > 0.0
    }

    /// Whether light can pass through (refraction, thin walls, cut-outs): such surfaces
    /// keep their geometric orientation instead of being turned toward the viewer.
    pub fn is_transmissive(&self) -> bool {
        if let Some(g) = &self.graph {
            return g.traits.transmissive;
        }
        self.principled.transmission_weight > 0.0 || self.principled.thin_walled
    }

    /// The homogeneous volume inside, from a graph's Volume socket.
    pub fn volume(&self) -> Option<crate::material::compile::VolumeCoefficients> {
        self.graph.as_ref().and_then(|g| g.traits.volume)
    }

    /// A heterogeneous volume's majorant ([`crate::material::compile::MaterialTraits`]).
    pub fn volume_majorant(&self) -> Option<f32> {
        self.graph.as_ref().and_then(|g| g.traits.volume_majorant)
    }

    /// Whether the surface is only a volume's boundary (a graph with a volume and no
    /// surface), which light crosses unchanged.
    pub fn is_boundary_only(&self) -> bool {
        self.graph.as_ref().is_some_and(|g| g.traits.boundary_only)
    }

    pub fn validate(&self) -> Result<(), String> {
        self.principled.validate()
    }
}

/// The graph of a fixed-parameter material: one principled node holding its values, so
/// that every material can be edited, saved and compiled as a graph.
pub fn graph_from_principled(m: &Material) -> Graph {
    let mut surface = Node::new("principled_bsdf");
    for p in &principled::PARAMETERS {
        surface = match m
            .principled
            .get(p.name)
            .expect("every parameter is a field")
        {
            ParamValue::Float(x) => surface.input(p.name, Input::Value(Value::Float(x))),
            ParamValue::Color(c) => surface.input(p.name, Input::Value(Value::Vec3(c.to_array()))),
            ParamValue::Bool(b) => surface.param(p.name, Param::Bool(b)),
        };
    }
    let mut g = Graph::default();
    g.add("surface", surface);
    g.add(
        "output",
        Node::new("material_output").input("surface", Input::Link(Link::new("surface", "bsdf"))),
    );
    g
}
