//! The serde types of the `.kiln` scene file: what a file may say, field by field, with
//! the defaults a field takes when it is left out.
//!
//! This is deliberately only the schema: turning these types into a [`Scene`](super::Scene)
//! (and validating them) is [`load`](super::load)'s job, the reverse is [`save`](super::save)'s,
//! and mesh files are [`obj`](super::obj)'s. `docs/SCENE_FORMAT.md` documents every field.

use std::collections::BTreeSet;
use std::fmt;
use std::marker::PhantomData;

use serde::de::{Error as _, MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::{Material, SceneSettings};
use crate::shader::principled::{self, Kind, ParamValue, Principled};
use crate::shader::sampling::{PixelFilter, Sampler};

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub(super) version: u32,
    #[serde(default)]
    pub(super) render: RenderDesc,
    pub(super) camera: CameraDesc,
    #[serde(default)]
    pub(super) environment: [f32; 3],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) environment_map: Option<EnvironmentMapDesc>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) world: Option<WorldDesc>,
    #[serde(default)]
    pub(super) materials: Named<MaterialDesc>,
    #[serde(default)]
    pub(super) meshes: Named<MeshDesc>,
    #[serde(default)]
    pub(super) instances: Vec<InstanceDesc>,
    #[serde(default)]
    pub(super) lights: Vec<LightDesc>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct EnvironmentMapDesc {
    /// An equirectangular `.hdr` or `.exr`, relative to the scene file.
    pub(super) file: String,
    #[serde(default = "unit_strength")]
    pub(super) strength: f32,
    /// Degrees about +Y.
    #[serde(default)]
    pub(super) rotation: f32,
}

/// The world: a node graph ending in a `world_output` node, inline or in a graph file,
/// and the width of the environment map it is baked into.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct WorldDesc {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) graph: Option<crate::material::Graph>,
    /// A graph file (`.kmat` format), relative to the scene file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) graph_file: Option<String>,
    #[serde(default = "default_world_resolution")]
    pub(super) resolution: u32,
}

fn default_world_resolution() -> u32 {
    super::DEFAULT_WORLD_RESOLUTION
}

/// A RON map from names to entries, kept in the order the file lists them: the scene's
/// materials and meshes take that order, so a saved scene reloads with the same indices.
/// A name given twice is an error (a map type would silently keep the last).
#[derive(Debug)]
pub(super) struct Named<T>(pub(super) Vec<(String, T)>);

impl<T> Default for Named<T> {
    fn default() -> Self {
        Self(Vec::new())
    }
}

impl<T: Serialize> Serialize for Named<T> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_map(self.0.iter().map(|(name, entry)| (name, entry)))
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Named<T> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct NamedVisitor<T>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for NamedVisitor<T> {
            type Value = Named<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a map from names to entries")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Named<T>, A::Error> {
                let mut seen = BTreeSet::new();
                let mut entries = Vec::new();
                while let Some((name, entry)) = map.next_entry::<String, T>()? {
                    if !seen.insert(name.clone()) {
                        return Err(A::Error::custom(format!("\"{name}\" is defined twice")));
                    }
                    entries.push((name, entry));
                }
                Ok(Named(entries))
            }
        }
        deserializer.deserialize_map(NamedVisitor(PhantomData))
    }
}

pub(super) fn unit_strength() -> f32 {
    1.0
}

/// A light. Every kind may carry the outliner's `name` and `visible` besides its own
/// fields (serde cannot flatten shared fields into RON's enum variants, so each variant
/// lists them; [`LightDesc::object`] reads them in one place).
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) enum LightDesc {
    Point {
        #[serde(default, skip_serializing_if = "String::is_empty")]
        name: String,
        position: [f32; 3],
        intensity: [f32; 3],
        #[serde(default)]
        radius: f32,
        #[serde(default = "yes", skip_serializing_if = "is_true")]
        visible: bool,
    },
    Spot {
        #[serde(default, skip_serializing_if = "String::is_empty")]
        name: String,
        position: [f32; 3],
        direction: [f32; 3],
        intensity: [f32; 3],
        cone_angle: f32,
        #[serde(default)]
        blend: f32,
        #[serde(default)]
        radius: f32,
        #[serde(default = "yes", skip_serializing_if = "is_true")]
        visible: bool,
    },
    Distant {
        #[serde(default, skip_serializing_if = "String::is_empty")]
        name: String,
        direction: [f32; 3],
        irradiance: [f32; 3],
        #[serde(default)]
        angular_diameter: f32,
        #[serde(default = "yes", skip_serializing_if = "is_true")]
        visible: bool,
    },
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct RenderDesc {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) samples_per_pixel: u32,
    pub(super) max_bounces: u32,
    #[serde(skip_serializing_if = "is_unlimited_volume_bounces")]
    pub(super) max_volume_bounces: u32,
    #[serde(skip_serializing_if = "is_zero_seed")]
    pub(super) seed: u32,
    /// A [`Sampler::key`]: "sobol", "independent".
    #[serde(skip_serializing_if = "is_default_sampler")]
    pub(super) sampler: String,
    /// A [`FilterKind::key`]: "blackman-harris", "box", "tent", "gaussian".
    #[serde(skip_serializing_if = "is_default_filter")]
    pub(super) filter: String,
    /// The pixel filter's width in pixels.
    #[serde(skip_serializing_if = "is_default_filter_width")]
    pub(super) filter_width: f32,
    /// Grid points along the longest side of a heterogeneous volume.
    #[serde(skip_serializing_if = "is_default_volume_resolution")]
    pub(super) volume_resolution: u32,
    /// The firefly clamp's limits ([`super::Clamp`]); 0: off.
    #[serde(skip_serializing_if = "is_zero_scalar")]
    pub(super) clamp_direct: f32,
    #[serde(skip_serializing_if = "is_zero_scalar")]
    pub(super) clamp_indirect: f32,
    /// Adaptive sampling's noise threshold ([`super::SceneSettings::noise_threshold`]);
    /// 0: off.
    #[serde(skip_serializing_if = "is_zero_scalar")]
    pub(super) noise_threshold: f32,
    /// A [`Denoiser::key`](super::Denoiser::key): "none", "atrous".
    #[serde(skip_serializing_if = "is_default_denoiser")]
    pub(super) denoise: String,
    /// Stops (EV) before the view transform.
    #[serde(skip_serializing_if = "is_zero_scalar")]
    pub(super) exposure: f32,
    /// A [`Tonemap::key`](crate::shader::view::Tonemap::key): "agx", "none", "aces",
    /// "pbr-neutral".
    #[serde(skip_serializing_if = "is_default_view_transform")]
    pub(super) view_transform: String,
}

fn is_unlimited_volume_bounces(bounces: &u32) -> bool {
    *bounces == super::UNLIMITED_VOLUME_BOUNCES
}

fn is_default_volume_resolution(resolution: &u32) -> bool {
    *resolution == super::DEFAULT_VOLUME_RESOLUTION
}

fn is_default_denoiser(key: &String) -> bool {
    *key == super::Denoiser::default().key()
}

fn is_default_sampler(key: &String) -> bool {
    *key == Sampler::default().key()
}

fn is_default_filter(key: &String) -> bool {
    *key == PixelFilter::default().kind.key()
}

fn is_default_filter_width(width: &f32) -> bool {
    width.to_bits() == PixelFilter::default().width.to_bits()
}

fn is_zero_seed(seed: &u32) -> bool {
    *seed == 0
}

fn is_zero_scalar(value: &f32) -> bool {
    // Bit for bit, so that -0 is written and read back as itself.
    value.to_bits() == 0
}

fn is_default_view_transform(key: &String) -> bool {
    *key == crate::shader::view::Tonemap::default().key()
}

impl Default for RenderDesc {
    fn default() -> Self {
        let s = SceneSettings::default();
        Self {
            width: s.width,
            height: s.height,
            samples_per_pixel: s.samples_per_pixel,
            max_bounces: s.max_bounces,
            max_volume_bounces: s.max_volume_bounces,
            seed: s.seed,
            sampler: s.sampling.sampler.key().to_owned(),
            filter: s.sampling.filter.kind.key().to_owned(),
            filter_width: s.sampling.filter.width,
            volume_resolution: s.volume_resolution,
            clamp_direct: s.clamp.direct,
            clamp_indirect: s.clamp.indirect,
            noise_threshold: s.noise_threshold,
            denoise: s.denoiser.key().to_owned(),
            exposure: s.view.exposure_ev,
            view_transform: s.view.tonemap.key().to_owned(),
        }
    }
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraDesc {
    pub(super) position: [f32; 3],
    pub(super) look_at: [f32; 3],
    #[serde(default = "default_up")]
    pub(super) up: [f32; 3],
    pub(super) projection: Projection,
}

pub(super) fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) enum Projection {
    Perspective {
        fov_y: f32,
    },
    ThinLens {
        fov_y: f32,
        aperture_radius: f32,
        focus_distance: f32,
    },
}

/// A material: principled parameters by name (the table of `crate::shader::principled`;
/// any left out take Blender's defaults), or a node graph. docs/SCENE_FORMAT.md lists the
/// fields.
///
/// Two shorthands are read besides the table's names: `emission`, a radiance (the emission
/// colour, with strength 1 unless `emission_strength` is given), and `opacity` for
/// `alpha`. Writing uses the table's names.
#[derive(Clone, Debug, PartialEq, Default)]
pub(super) struct MaterialDesc {
    pub(super) principled: Principled,
    /// The parameters the file gave, by their table names.
    pub(super) given: BTreeSet<&'static str>,
    /// A node graph (docs/NODES.md) computing the parameters instead.
    pub(super) graph: Option<crate::material::Graph>,
    /// A `.kmat` material file, relative to the scene file, instead of parameters.
    pub(super) graph_file: Option<String>,
}

const EMISSION_SHORTHAND: &str = "emission";
const OPACITY_SHORTHAND: &str = "opacity";

/// Every field name a material may have, for serde's messages.
const MATERIAL_FIELDS: [&str; principled::PARAMETERS.len() + 4] = {
    let mut fields = [""; principled::PARAMETERS.len() + 4];
    let mut i = 0;
    while i < principled::PARAMETERS.len() {
        fields[i] = principled::PARAMETERS[i].name;
        i += 1;
    }
    fields[i] = "graph";
    fields[i + 1] = "graph_file";
    fields[i + 2] = EMISSION_SHORTHAND;
    fields[i + 3] = OPACITY_SHORTHAND;
    fields
};

impl MaterialDesc {
    /// The fixed parameters of `m` (its graph, if any, aside), every one given.
    pub(super) fn from_params(m: &Material) -> Self {
        Self {
            principled: m.principled,
            given: principled::PARAMETERS.iter().map(|p| p.name).collect(),
            graph: None,
            graph_file: None,
        }
    }

    /// A material computed by `graph`.
    pub(super) fn from_graph(graph: crate::material::Graph) -> Self {
        Self {
            graph: Some(graph),
            ..Self::default()
        }
    }
}

impl Serialize for MaterialDesc {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let parameters = principled::PARAMETERS
            .iter()
            .filter(|p| self.given.contains(p.name));
        let count = parameters.clone().count()
            + self.graph.is_some() as usize
            + self.graph_file.is_some() as usize;
        let mut out = serializer.serialize_struct("MaterialDesc", count)?;
        for p in parameters {
            match self
                .principled
                .get(p.name)
                .expect("every parameter is a field")
            {
                ParamValue::Float(x) => out.serialize_field(p.name, &x)?,
                ParamValue::Color(c) => out.serialize_field(p.name, &c.to_array())?,
                ParamValue::Bool(b) => out.serialize_field(p.name, &b)?,
            }
        }
        if let Some(graph) = &self.graph {
            out.serialize_field("graph", graph)?;
        }
        if let Some(file) = &self.graph_file {
            out.serialize_field("graph_file", file)?;
        }
        out.end()
    }
}

impl<'de> Deserialize<'de> for MaterialDesc {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct FieldName(String);
        impl<'de> Deserialize<'de> for FieldName {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                struct Name;
                impl Visitor<'_> for Name {
                    type Value = FieldName;
                    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                        f.write_str("a material field name")
                    }
                    fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<FieldName, E> {
                        Ok(FieldName(v.to_owned()))
                    }
                }
                d.deserialize_identifier(Name)
            }
        }

        struct Fields;
        impl<'de> Visitor<'de> for Fields {
            type Value = MaterialDesc;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a material's fields")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<MaterialDesc, A::Error> {
                let mut desc = MaterialDesc::default();
                let mut seen = BTreeSet::new();
                let mut emission_shorthand = false;
                while let Some(FieldName(key)) = map.next_key()? {
                    let Some(field) = MATERIAL_FIELDS.iter().find(|f| **f == key) else {
                        return Err(A::Error::unknown_field(&key, &MATERIAL_FIELDS));
                    };
                    if !seen.insert(*field) {
                        return Err(A::Error::duplicate_field(field));
                    }
                    let name = match *field {
                        "graph" => {
                            desc.graph = Some(map.next_value()?);
                            continue;
                        }
                        "graph_file" => {
                            desc.graph_file = Some(map.next_value()?);
                            continue;
                        }
                        EMISSION_SHORTHAND => {
                            emission_shorthand = true;
                            "emission_color"
                        }
                        OPACITY_SHORTHAND => "alpha",
                        name => name,
                    };
                    let p = Principled::parameter(name).expect("a table name");
                    let value = match p.kind {
                        Kind::Float => ParamValue::Float(map.next_value()?),
                        Kind::Color => ParamValue::Color(map.next_value::<[f32; 3]>()?.into()),
                        Kind::Bool => ParamValue::Bool(map.next_value()?),
                    };
                    if !desc.given.insert(p.name) {
                        return Err(A::Error::custom(format!(
                            "`{key}` gives {} a second time",
                            p.name
                        )));
                    }
                    desc.principled
                        .set(p.name, value)
                        .map_err(A::Error::custom)?;
                }
                if emission_shorthand && !desc.given.contains("emission_strength") {
                    desc.principled.emission_strength = 1.0;
                    desc.given.insert("emission_strength");
                }
                Ok(desc)
            }
        }

        deserializer.deserialize_struct("MaterialDesc", &MATERIAL_FIELDS, Fields)
    }
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) enum MeshDesc {
    /// Vertices listed in the file.
    Inline {
        positions: Vec<[f32; 3]>,
        #[serde(default)]
        normals: Vec<[f32; 3]>,
        #[serde(default)]
        uvs: Vec<[f32; 2]>,
        /// A second UV set.
        #[serde(default)]
        uvs1: Vec<[f32; 2]>,
        /// Linear RGBA.
        #[serde(default)]
        colors: Vec<[f32; 4]>,
        indices: Vec<[u32; 3]>,
    },
    /// A Wavefront OBJ file, relative to the scene file; all its shapes become one mesh
    /// ([`obj`](super::obj) says how, and which extensions Kiln reads and writes).
    Obj(String),
    Quad,
    Cube,
    Sphere {
        #[serde(default = "default_segments")]
        segments: u32,
        #[serde(default = "default_rings")]
        rings: u32,
        #[serde(default = "yes")]
        smooth: bool,
    },
}

pub(super) fn default_segments() -> u32 {
    64
}

pub(super) fn default_rings() -> u32 {
    32
}

pub(super) fn yes() -> bool {
    true
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct InstanceDesc {
    /// The object's name; the editor names unnamed objects after their mesh.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub(super) name: String,
    pub(super) mesh: String,
    pub(super) material: String,
    #[serde(default)]
    pub(super) transform: TransformDesc,
    /// Hidden objects are kept but not rendered.
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub(super) visible: bool,
    /// The camera sees only the shadows cast on it, as alpha.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub(super) shadow_catcher: bool,
}

fn is_true(b: &bool) -> bool {
    *b
}

/// Scale, then rotate (Euler angles in degrees, about X, then Y, then Z), then translate;
/// or a full row-major 4x4 `matrix`, which then must be the only field.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TransformDesc {
    #[serde(default, skip_serializing_if = "is_zero")]
    pub(super) translate: [f32; 3],
    #[serde(default, skip_serializing_if = "is_zero")]
    pub(super) rotate: [f32; 3],
    #[serde(default = "unit_scale", skip_serializing_if = "is_unit_scale")]
    pub(super) scale: [f32; 3],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) matrix: Option<[[f32; 4]; 4]>,
}

pub(super) fn unit_scale() -> [f32; 3] {
    [1.0; 3]
}

fn is_zero(v: &[f32; 3]) -> bool {
    *v == [0.0; 3]
}

fn is_unit_scale(v: &[f32; 3]) -> bool {
    *v == unit_scale()
}

impl Default for TransformDesc {
    fn default() -> Self {
        Self {
            translate: [0.0; 3],
            rotate: [0.0; 3],
            scale: unit_scale(),
            matrix: None,
        }
    }
}
