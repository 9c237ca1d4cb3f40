//! glTF texture references as `image_texture` nodes: the sampler's wrap mode and filter,
//! `KHR_texture_transform` as a `mapping` node, and the UV convention.
//!
//! glTF's UV origin is the image's top-left and v runs down; Kiln samples with v up (row
//! 0 of the file at v = 1). Meshes are handed over with v' = 1 − v, and a texture
//! transform, defined on glTF's UVs, is rewritten for the flipped ones
//! ([`flipped_transform`]). Which image file a texture names is decided by an
//! [`ImageFiles`] (see `images`).

use gltf::json;
use gltf::json::texture::{MagFilter, WrappingMode};
use gltf::json::validation::Checked;

use kiln_plugin_api::kmat::{Graph, Node, Value};

/// Resolves glTF image `index` to the `file` parameter of an image-texture node
/// (`image:N` or a path relative to the glTF file), or None if it cannot be used (the
/// resolver has said why).
pub trait ImageFiles {
    fn file(&mut self, index: usize) -> Option<String>;
}

/// KHR_texture_transform's parameters (defaults: no change).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    pub offset: [f32; 2],
    pub rotation: f32,
    pub scale: [f32; 2],
}

/// A material's reference to a texture: which, with which UV set and transform.
#[derive(Clone, Debug)]
pub struct TextureRef {
    pub texture: usize,
    pub tex_coord: u32,
    pub transform: Option<UvTransform>,
}

fn transform_from_json(
    t: &json::extensions::texture::TextureTransform,
) -> (UvTransform, Option<u32>) {
    (
        UvTransform {
            offset: t.offset.0,
            rotation: t.rotation.0,
            scale: t.scale.0,
        },
        t.tex_coord,
    )
}

impl TextureRef {
    fn with(
        texture: usize,
        tex_coord: u32,
        transform: Option<&json::extensions::texture::TextureTransform>,
    ) -> Self {
        let (transform, tex_coord) = match transform.map(transform_from_json) {
            Some((t, override_coord)) => (Some(t), override_coord.unwrap_or(tex_coord)),
            None => (None, tex_coord),
        };
        Self {
            texture,
            tex_coord,
            transform,
        }
    }

    pub fn from_info(info: &json::texture::Info) -> Self {
        let transform = info
            .extensions
            .as_ref()
            .and_then(|e| e.texture_transform.as_ref());
        Self::with(info.index.value(), info.tex_coord, transform)
    }

    /// A normal texture, whose extensions the JSON model keeps as raw values.
    pub fn from_normal(info: &json::material::NormalTexture) -> Self {
        let transform = info
            .extensions
            .as_ref()
            .and_then(|e| e.others.get("KHR_texture_transform"))
            .and_then(|v| json::deserialize::from_value(v.clone()).ok());
        Self::with(info.index.value(), info.tex_coord, transform.as_ref())
    }

    /// A texture info inside an extension the JSON model does not parse
    /// (`KHR_materials_clearcoat`, `KHR_materials_sheen`).
    pub fn from_value(value: Option<&json::Value>) -> Option<Self> {
        let info: json::texture::Info = json::deserialize::from_value(value?.clone()).ok()?;
        Some(Self::from_info(&info))
    }
}

/// The transform of glTF UVs rewritten for Kiln's (u, 1 − v), as a `mapping` node of
/// type `point` (scale, then rotate about z, then translate).
///
/// glTF applies uv' = T·R·S·uv with R = [[c, s], [−s, c]] (KHR_texture_transform). With
/// V = 1 − v and V' = 1 − v':
///   u' = c·sx·u − s·sy·V + (ox + s·sy)
///   V' = s·sx·u + c·sy·V + (1 − c·sy − oy)
/// which is a rotation by +θ of the scaled (u, V), translated — what `mapping` computes.
/// Returns (location, rotation about z, scale).
pub fn flipped_transform(t: &UvTransform) -> ([f32; 2], f32, [f32; 2]) {
    let (s, c) = t.rotation.sin_cos();
    let [ox, oy] = t.offset;
    let [sx, sy] = t.scale;
    ([ox + s * sy, 1.0 - c * sy - oy], t.rotation, [sx, sy])
}

fn finite(v: f32, fallback: f32) -> f32 {
    if v.is_finite() { v } else { fallback }
}

/// Builds the nodes sampling texture `r` and returns the image node's id (outputs
/// `color`, `alpha`). `role` names the nodes; `srgb` picks the colour space. Problems go
/// to `warn`; None means the slot is left untextured.
pub fn texture_node(
    graph: &mut Graph,
    root: &json::Root,
    images: &mut dyn ImageFiles,
    r: &TextureRef,
    role: &str,
    srgb: bool,
    warn: &mut dyn FnMut(String),
) -> Option<String> {
    let Some(texture) = root.textures.get(r.texture) else {
        warn(format!("{role} texture {} does not exist", r.texture));
        return None;
    };
    let image = texture.source.value();
    if image >= root.images.len() {
        warn(format!(
            "{role} texture {} has no image Kiln can read (a PNG or JPEG `source`)",
            r.texture
        ));
        return None;
    }
    let file = images.file(image)?;
    // Kiln meshes carry two UV sets (TEXCOORD_0 and _1).
    let uv_output = match r.tex_coord {
        0 => "uv",
        1 => "uv1",
        n => {
            warn(format!(
                "{role} texture uses UV set {n}; Kiln meshes carry sets 0 and 1, so set 0 is used"
            ));
            "uv"
        }
    };
    let sampler = texture.sampler.and_then(|s| root.samplers.get(s.value()));
    let (extension, interpolation) = match sampler {
        None => ("repeat", "linear"),
        Some(s) => {
            let wrap = |w: &Checked<WrappingMode>| match w {
                Checked::Valid(WrappingMode::ClampToEdge) => "extend",
                Checked::Valid(WrappingMode::MirroredRepeat) => "mirror",
                _ => "repeat",
            };
            let (ws, wt) = (wrap(&s.wrap_s), wrap(&s.wrap_t));
            if ws != wt {
                warn(format!(
                    "{role} texture wraps differently along u ({ws}) and v ({wt}); Kiln uses one mode, {ws}"
                ));
            }
            let filter = match s.mag_filter {
                Some(Checked::Valid(MagFilter::Nearest)) => "closest",
                _ => "linear",
            };
            (ws, filter)
        }
    };
    let mut node = Node::new("image_texture")
        .text("file", &file)
        .text("color_space", if srgb { "srgb" } else { "linear" })
        .text("extension", extension)
        .text("interpolation", interpolation);
    if r.transform.is_none() && uv_output != "uv" {
        let uv = graph.add("uv", Node::new("texture_coordinate"));
        node = node.input("vector", Value::link(&uv, uv_output));
    }
    if let Some(t) = &r.transform {
        let t = UvTransform {
            offset: [finite(t.offset[0], 0.0), finite(t.offset[1], 0.0)],
            rotation: finite(t.rotation, 0.0),
            scale: [finite(t.scale[0], 1.0), finite(t.scale[1], 1.0)],
        };
        let (location, rotation, scale) = flipped_transform(&t);
        let uv = graph.add("uv", Node::new("texture_coordinate"));
        let mapping = Node::new("mapping")
            .text("vector_type", "point")
            .input("vector", Value::link(&uv, uv_output))
            .input("location", Value::Vector([location[0], location[1], 0.0]))
            .input("rotation", Value::Vector([0.0, 0.0, rotation]))
            .input("scale", Value::Vector([scale[0], scale[1], 1.0]));
        let mapping = graph.add(&format!("{role}_mapping"), mapping);
        node = node.input("vector", Value::link(&mapping, "vector"));
    }
    Some(graph.add(&format!("{role}_texture"), node))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// KHR_texture_transform on glTF UVs, as the extension's spec writes it.
    fn gltf_transform(t: &UvTransform, [u, v]: [f32; 2]) -> [f32; 2] {
        let (s, c) = t.rotation.sin_cos();
        let (x, y) = (u * t.scale[0], v * t.scale[1]);
        [c * x + s * y + t.offset[0], -s * x + c * y + t.offset[1]]
    }

    /// Kiln's mapping node, type point: R_z(θ)·(scale ⊙ p) + location.
    fn kiln_mapping(
        location: [f32; 2],
        rotation: f32,
        scale: [f32; 2],
        [u, v]: [f32; 2],
    ) -> [f32; 2] {
        let (s, c) = rotation.sin_cos();
        let (x, y) = (u * scale[0], v * scale[1]);
        [c * x - s * y + location[0], s * x + c * y + location[1]]
    }

    #[test]
    fn flipped_transform_matches_gltf_transform_on_flipped_uvs() {
        let transforms = [
            UvTransform {
                offset: [0.0, 0.0],
                rotation: 0.0,
                scale: [1.0, 1.0],
            },
            UvTransform {
                offset: [0.25, -0.5],
                rotation: 0.0,
                scale: [1.0, 1.0],
            },
            UvTransform {
                offset: [0.0, 0.0],
                rotation: 0.0,
                scale: [2.0, 3.0],
            },
            UvTransform {
                offset: [0.5, 0.25],
                rotation: 1.3,
                scale: [0.5, 2.0],
            },
            UvTransform {
                offset: [-1.0, 2.0],
                rotation: -2.7,
                scale: [-1.0, 0.3],
            },
        ];
        for t in &transforms {
            let (location, rotation, scale) = flipped_transform(t);
            for uv in [[0.0, 0.0], [1.0, 0.0], [0.3, 0.7], [-2.0, 5.0]] {
                let [u1, v1] = gltf_transform(t, uv);
                let expected = [u1, 1.0 - v1];
                let got = kiln_mapping(location, rotation, scale, [uv[0], 1.0 - uv[1]]);
                for k in 0..2 {
                    assert!(
                        (got[k] - expected[k]).abs() < 1e-5,
                        "{t:?} at {uv:?}: {got:?} != {expected:?}"
                    );
                }
            }
        }
    }
}
