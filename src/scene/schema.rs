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

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) enum LightDesc {
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
        #[serde(default)]
        radius: f32,
    },
    Spot {
        position: [f32; 3],
        direction: [f32; 3],
        intensity: [f32; 3],
        cone_angle: f32,
        #[serde(default)]
        blend: f32,
        #[serde(default)]
        radius: f32,
    },
    Distant {
        direction: [f32; 3],
        irradiance: [f32; 3],
        #[serde(default)]
        angular_diameter: f32,
    },
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct RenderDesc {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) samples_per_pixel: u32,
    pub(super) max_bounces: u32,
}

impl Default for RenderDesc {
    fn default() -> Self {
        let s = SceneSettings::default();
        Self {
            width: s.width,
            height: s.height,
            samples_per_pixel: s.samples_per_pixel,
            max_bounces: s.max_bounces,
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

/// The principled material's parameters (docs/SCENE_FORMAT.md lists them); any left out
/// take Blender's defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct MaterialDesc {
    pub(super) base_color: [f32; 3],
    pub(super) base_weight: f32,
    pub(super) diffuse_roughness: f32,
    pub(super) metallic: f32,
    pub(super) roughness: f32,
    pub(super) anisotropy: f32,
    pub(super) anisotropy_rotation: f32,
    pub(super) specular_weight: f32,
    pub(super) specular_color: [f32; 3],
    pub(super) ior: f32,
    pub(super) transmission_weight: f32,
    pub(super) transmission_color: [f32; 3],
    pub(super) transmission_depth: f32,
    pub(super) coat_weight: f32,
    pub(super) coat_roughness: f32,
    pub(super) coat_ior: f32,
    pub(super) coat_color: [f32; 3],
    pub(super) sheen_weight: f32,
    pub(super) sheen_color: [f32; 3],
    pub(super) sheen_roughness: f32,
    pub(super) emission: [f32; 3],
    pub(super) emission_strength: f32,
    pub(super) opacity: f32,
    pub(super) thin_walled: bool,
    /// A node graph (docs/NODES.md) computing the parameters instead of the fields above.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) graph: Option<crate::material::Graph>,
    /// A `.kmat` material file, relative to the scene file, instead of the fields above.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) graph_file: Option<String>,
}

impl Default for MaterialDesc {
    fn default() -> Self {
        Self::from_params(&Material::default())
    }
}

impl MaterialDesc {
    /// The fixed parameters of `m` (its graph, if any, aside).
    pub(super) fn from_params(m: &Material) -> Self {
        Self {
            base_color: m.base_color.into(),
            base_weight: m.base_weight,
            diffuse_roughness: m.diffuse_roughness,
            metallic: m.metallic,
            roughness: m.roughness,
            anisotropy: m.anisotropy,
            anisotropy_rotation: m.anisotropy_rotation,
            specular_weight: m.specular_weight,
            specular_color: m.specular_color.into(),
            ior: m.ior,
            transmission_weight: m.transmission_weight,
            transmission_color: m.transmission_color.into(),
            transmission_depth: m.transmission_depth,
            coat_weight: m.coat_weight,
            coat_roughness: m.coat_roughness,
            coat_ior: m.coat_ior,
            coat_color: m.coat_color.into(),
            sheen_weight: m.sheen_weight,
            sheen_color: m.sheen_color.into(),
            sheen_roughness: m.sheen_roughness,
            emission: m.emission.into(),
            emission_strength: 1.0,
            opacity: m.opacity,
            thin_walled: m.thin_walled,
            graph: None,
            graph_file: None,
        }
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
    pub(super) mesh: String,
    pub(super) material: String,
    #[serde(default)]
    pub(super) transform: TransformDesc,
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
