//! The principled surface material: the parameters of Blender's Principled BSDF / OpenPBR
//! Surface, evaluated by `shaders/bsdf/principled.wgsl`. Defaults are Blender's.
//!
//! This is the fixed parameter set every material has. A material made from a node graph
//! keeps its compiled graph beside it, which computes these parameters per shading point
//! (the fixed values are then what the graph folds to, where it is constant).

use std::sync::Arc;

use glam::Vec3;

use crate::material::texture::{TextureImage, load_texture};
use crate::material::{Graph, GraphError, Input, Link, MaterialTraits, Node, Param, Value};

#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Diffuse albedo, or metal reflectance at normal incidence (linear RGB in [0, 1]).
    pub base_color: Vec3,
    pub base_weight: f32,
    /// Oren–Nayar roughness of the diffuse base in [0, 1]; 0 is Lambertian.
    pub diffuse_roughness: f32,
    pub metallic: f32,
    /// Perceptual roughness in [0, 1] (GGX alpha = roughness²).
    pub roughness: f32,
    /// Stretches the highlight along the tangent, in [0, 1].
    pub anisotropy: f32,
    /// Turns the tangent about the shading normal, in turns (Blender's "Anisotropic
    /// Rotation": 0.25 is 90°). The tangent follows the texture's u direction where the
    /// mesh has UVs.
    pub anisotropy_rotation: f32,
    pub specular_weight: f32,
    /// Tints dielectric reflection; for metals, the edge tint at 82° (F82).
    pub specular_color: Vec3,
    pub ior: f32,
    pub transmission_weight: f32,
    pub transmission_color: Vec3,
    /// Depth at which light inside reaches `transmission_color` (Beer–Lambert); 0 tints
    /// the surface instead.
    pub transmission_depth: f32,
    pub coat_weight: f32,
    pub coat_roughness: f32,
    pub coat_ior: f32,
    pub coat_color: Vec3,
    pub sheen_weight: f32,
    pub sheen_color: Vec3,
    pub sheen_roughness: f32,
    /// Emitted radiance (colour × strength), from the front side.
    pub emission: Vec3,
    /// 1 opaque, 0 invisible (alpha cut-out).
    pub opacity: f32,
    /// A surface with no inside (leaves, paper, soap film): light passes without bending.
    pub thin_walled: bool,
    /// A node graph computing the parameters per shading point; the fields above then
    /// only carry what the renderer must know in advance (constant emission).
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

impl Default for Material {
    fn default() -> Self {
        Self {
            name: String::new(),
            base_color: Vec3::splat(0.8),
            base_weight: 1.0,
            diffuse_roughness: 0.0,
            metallic: 0.0,
            roughness: 0.5,
            anisotropy: 0.0,
            anisotropy_rotation: 0.0,
            specular_weight: 1.0,
            specular_color: Vec3::ONE,
            ior: 1.5,
            transmission_weight: 0.0,
            transmission_color: Vec3::ONE,
            transmission_depth: 0.0,
            coat_weight: 0.0,
            coat_roughness: 0.03,
            coat_ior: 1.5,
            coat_color: Vec3::ONE,
            sheen_weight: 0.0,
            sheen_color: Vec3::ONE,
            sheen_roughness: 0.3,
            emission: Vec3::ZERO,
            opacity: 1.0,
            thin_walled: false,
            graph: None,
        }
    }
}

impl Material {
    /// A purely Lambertian surface (no specular layer).
    pub fn diffuse(name: &str, base_color: Vec3) -> Self {
        Self {
            name: name.to_owned(),
            base_color,
            specular_weight: 0.0,
            ..Self::default()
        }
    }

    /// A black surface emitting `radiance` from its front side.
    pub fn emitter(name: &str, radiance: Vec3) -> Self {
        Self {
            base_color: Vec3::ZERO,
            emission: radiance,
            ..Self::diffuse(name, Vec3::ZERO)
        }
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
        Ok(Self {
            name: name.to_owned(),
            emission: traits.constant_emission.map_or(Vec3::ZERO, Vec3::from),
            graph: Some(Arc::new(GraphMaterial {
                graph,
                traits,
                images,
            })),
            ..Self::default()
        })
    }

    /// The principled lobes this material can reach ([`crate::shader::lobes`]).
    pub fn lobes(&self) -> u32 {
        if let Some(g) = &self.graph {
            return g.traits.lobes;
        }
        crate::material::principled_lobes(
            Some(self.coat_weight),
            Some(self.sheen_weight),
            Some(self.metallic),
            Some(self.transmission_weight),
            Some(self.specular_weight),
        )
    }

    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    /// Whether light can pass through (refraction, thin walls, cut-outs): such surfaces
    /// keep their geometric orientation instead of being turned toward the viewer.
    pub fn is_transmissive(&self) -> bool {
        if let Some(g) = &self.graph {
            return g.traits.transmissive;
        }
        self.transmission_weight > 0.0 || self.thin_walled
    }

    pub fn validate(&self) -> Result<(), String> {
        let colours = [
            ("base_color", self.base_color),
            ("specular_color", self.specular_color),
            ("transmission_color", self.transmission_color),
            ("coat_color", self.coat_color),
            ("sheen_color", self.sheen_color),
        ];
        for (field, c) in colours {
            if !c.is_finite() || c.min_element() < 0.0 || c.max_element() > 1.0 {
                return Err(format!("{field} {c} must lie in [0, 1]"));
            }
        }
        let unit = [
            ("base_weight", self.base_weight),
            ("diffuse_roughness", self.diffuse_roughness),
            ("metallic", self.metallic),
            ("roughness", self.roughness),
            ("anisotropy", self.anisotropy),
            ("transmission_weight", self.transmission_weight),
            ("coat_weight", self.coat_weight),
            ("coat_roughness", self.coat_roughness),
            ("sheen_weight", self.sheen_weight),
            ("sheen_roughness", self.sheen_roughness),
            ("opacity", self.opacity),
        ];
        for (field, v) in unit {
            if !(0.0..=1.0).contains(&v) {
                return Err(format!("{field} {v} must lie in [0, 1]"));
            }
        }
        if !self.anisotropy_rotation.is_finite() {
            return Err(format!(
                "anisotropy_rotation {} must be finite",
                self.anisotropy_rotation
            ));
        }
        if !(self.specular_weight.is_finite() && self.specular_weight >= 0.0) {
            return Err(format!(
                "specular_weight {} must be finite and non-negative",
                self.specular_weight
            ));
        }
        for (field, v) in [("ior", self.ior), ("coat_ior", self.coat_ior)] {
            if !(v.is_finite() && v >= 1.0) {
                return Err(format!("{field} {v} must be at least 1"));
            }
        }
        if !(self.transmission_depth.is_finite() && self.transmission_depth >= 0.0) {
            return Err(format!(
                "transmission_depth {} must be finite and non-negative",
                self.transmission_depth
            ));
        }
        if !self.emission.is_finite() || self.emission.min_element() < 0.0 {
            return Err(format!(
                "emission {} must be finite and non-negative",
                self.emission
            ));
        }
        Ok(())
    }
}

/// The graph of a fixed-parameter material: one principled node holding its values, so
/// that every material can be edited, saved and compiled as a graph.
pub fn graph_from_principled(m: &Material) -> Graph {
    let v = |c: glam::Vec3| Input::Value(Value::Vec3(c.to_array()));
    let f = |x: f32| Input::Value(Value::Float(x));
    let strength = m.emission.max_element();
    let emission_color = if strength > 0.0 {
        m.emission / strength
    } else {
        glam::Vec3::ONE
    };
    let inputs = [
        ("base_color", v(m.base_color)),
        ("base_weight", f(m.base_weight)),
        ("diffuse_roughness", f(m.diffuse_roughness)),
        ("metallic", f(m.metallic)),
        ("roughness", f(m.roughness)),
        ("anisotropy", f(m.anisotropy)),
        ("anisotropy_rotation", f(m.anisotropy_rotation)),
        ("ior", f(m.ior)),
        ("specular_weight", f(m.specular_weight)),
        ("specular_color", v(m.specular_color)),
        ("transmission_weight", f(m.transmission_weight)),
        ("transmission_color", v(m.transmission_color)),
        ("transmission_depth", f(m.transmission_depth)),
        ("coat_weight", f(m.coat_weight)),
        ("coat_roughness", f(m.coat_roughness)),
        ("coat_ior", f(m.coat_ior)),
        ("coat_color", v(m.coat_color)),
        ("sheen_weight", f(m.sheen_weight)),
        ("sheen_color", v(m.sheen_color)),
        ("sheen_roughness", f(m.sheen_roughness)),
        ("emission_color", v(emission_color)),
        ("emission_strength", f(strength)),
        ("alpha", f(m.opacity)),
    ];
    let mut surface = Node::new("principled_bsdf").param("thin_walled", Param::Bool(m.thin_walled));
    for (name, input) in inputs {
        surface = surface.input(name, input);
    }
    let mut g = Graph::default();
    g.add("surface", surface);
    g.add(
        "output",
        Node::new("material_output").input("surface", Input::Link(Link::new("surface", "bsdf"))),
    );
    g
}
