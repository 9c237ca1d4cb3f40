//! The world: a node graph for the light arriving from every direction no geometry covers
//! (Blender's World), ending in a World Output node. It takes the place of the scene's
//! constant environment and environment map. The renderer bakes it into an environment
//! map it samples by importance, and turns each Sky Texture's sun into a sun light
//! (`render::world_bake`).

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::Vec3;

use crate::material::nodes::{self, WORLD_OUTPUT};
use crate::material::texture::{TextureImage, load_texture};
use crate::material::{Graph, GraphError, Input, Link, Node, Param, Value};

/// Widths of the environment map a world may be baked into (its height is half).
pub const WORLD_RESOLUTIONS: std::ops::RangeInclusive<u32> = 16..=4096;
/// The bake's width unless the scene says otherwise: a sky's gradients are smooth, and
/// its sun is a light of its own.
pub const DEFAULT_WORLD_RESOLUTION: u32 = 1024;

/// Where the node editor draws the output of the worlds made here, right of a texture at
/// the origin.
const OUTPUT_POSITION: [f32; 2] = [420.0, 0.0];

/// The Sky Texture node, whose sun the renderer places as a light.
pub const SKY_TEXTURE: &str = "sky_texture";

#[derive(Clone, Debug, PartialEq)]
pub struct World {
    pub graph: Graph,
    /// Width in texels of the environment map the world is baked into; height half.
    pub resolution: u32,
    /// The images its environment- and image-texture nodes read, by file.
    pub images: BTreeMap<String, Arc<TextureImage>>,
}

/// A Sky Texture's sun: where it is and how large, from the node's constant inputs.
#[derive(Clone, Debug, PartialEq)]
pub struct Sun {
    /// The Sky Texture node's id.
    pub node: String,
    /// Unit direction toward the sun.
    pub direction: Vec3,
    pub angular_diameter: f32,
}

impl World {
    /// A world of `graph`, compiled once here so that errors surface when it is made,
    /// naming the node and socket; its images are loaded.
    pub fn from_graph(graph: Graph) -> Result<Self, GraphError> {
        Self::from_graph_with(graph, &|file| load_texture(std::path::Path::new(file)))
    }

    /// [`World::from_graph`] with images loaded by `load`.
    pub fn from_graph_with(
        graph: Graph,
        load: &dyn Fn(&str) -> Result<TextureImage, String>,
    ) -> Result<Self, GraphError> {
        let compiled = crate::material::compile::compile_world(
            &graph,
            "world_radiance",
            &mut BTreeMap::new(),
        )?;
        let mut images = BTreeMap::new();
        for (file, node) in &compiled.images {
            let image = load(file).map_err(|message| GraphError {
                material: "world".into(),
                node: Some(node.clone()),
                socket: Some("file".into()),
                message,
            })?;
            images.insert(file.clone(), Arc::new(image));
        }
        let world = Self {
            graph,
            resolution: DEFAULT_WORLD_RESOLUTION,
            images,
        };
        world.suns()?;
        Ok(world)
    }

    /// A world of one colour (Background colour × strength).
    pub fn constant(colour: Vec3) -> Self {
        let mut graph = Graph::default();
        let mut output =
            Node::new(WORLD_OUTPUT).input("color", Input::Value(Value::Vec3(colour.to_array())));
        output.position = Some(OUTPUT_POSITION);
        graph.add("output", output);
        Self {
            graph,
            resolution: DEFAULT_WORLD_RESOLUTION,
            images: BTreeMap::new(),
        }
    }

    /// Blender's default-looking daylight: a Sky Texture with its sun at `elevation`
    /// and `rotation` degrees, into the output at `strength`.
    pub fn sky(elevation: f32, rotation: f32, strength: f32) -> Self {
        let mut graph = Graph::default();
        let mut sky = Node::new(SKY_TEXTURE)
            .input("sun_elevation", Input::Value(Value::Float(elevation)))
            .input("sun_rotation", Input::Value(Value::Float(rotation)));
        sky.position = Some([0.0, 0.0]);
        let mut output = Node::new(WORLD_OUTPUT)
            .input("color", Input::Link(Link::new("sky", "color")))
            .input("strength", Input::Value(Value::Float(strength)));
        output.position = Some(OUTPUT_POSITION);
        graph.add("sky", sky);
        graph.add("output", output);
        Self {
            graph,
            resolution: DEFAULT_WORLD_RESOLUTION,
            images: BTreeMap::new(),
        }
    }

    pub fn validate(&self) -> Result<(), String> {
        if !WORLD_RESOLUTIONS.contains(&self.resolution) {
            return Err(format!(
                "world resolution {} must be in {}..={}",
                self.resolution,
                WORLD_RESOLUTIONS.start(),
                WORLD_RESOLUTIONS.end()
            ));
        }
        Ok(())
    }

    /// The suns of the world's Sky Texture nodes with their disc on. A sun is a light
    /// placed from the node's elevation, rotation and size, so those must be values, and
    /// the node must be at the top level of the graph (a group's insides are instanced,
    /// and a sun per instance is not what anyone means): otherwise an error names the node.
    pub fn suns(&self) -> Result<Vec<Sun>, GraphError> {
        let err = |node: &str, socket: Option<&str>, message: &str| GraphError {
            material: "world".into(),
            node: Some(node.to_owned()),
            socket: socket.map(str::to_owned),
            message: message.to_owned(),
        };
        let disc = |node: &Node| {
            !node.muted && !matches!(node.params.get("sun_disc"), Some(Param::Bool(false)))
        };
        for (name, group) in &self.graph.groups {
            if let Some((id, _)) = group
                .nodes
                .iter()
                .find(|(_, n)| n.kind == SKY_TEXTURE && disc(n))
            {
                return Err(err(
                    &format!("{name}/{id}"),
                    None,
                    "a Sky Texture with its sun disc on must be at the top level of a world, \
                     not in a group: its sun is one light",
                ));
            }
        }
        let def = nodes::find(SKY_TEXTURE).expect("the library declares the sky");
        let mut suns = Vec::new();
        for (id, node) in &self.graph.nodes {
            if node.kind != SKY_TEXTURE || !disc(node) {
                continue;
            }
            let value = |socket: &str| -> Result<f32, GraphError> {
                match def.constant_input(node, socket) {
                    Some(Value::Float(v)) => Ok(v),
                    _ => Err(err(
                        id,
                        Some(socket),
                        "the sun is a light placed from the Sky Texture's sun elevation, \
                         rotation and size: give a value, not a link",
                    )),
                }
            };
            let (e, r) = (
                value("sun_elevation")?.to_radians(),
                value("sun_rotation")?.to_radians(),
            );
            suns.push(Sun {
                node: id.clone(),
                direction: Vec3::new(e.cos() * r.sin(), e.sin(), -e.cos() * r.cos()),
                angular_diameter: value("sun_size")?,
            });
        }
        Ok(suns)
    }
}
