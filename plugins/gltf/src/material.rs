//! glTF materials as Kiln material graphs: the metallic-roughness model and its
//! extensions mapped onto one `principled_bsdf`.
//!
//! | glTF | principled input |
//! |---|---|
//! | baseColorFactor × baseColorTexture (sRGB) × COLOR_0 | `base_color` |
//! | its alpha (BLEND), or alpha ≥ alphaCutoff (MASK) | `alpha` |
//! | metallicFactor × texture B, roughnessFactor × texture G | `metallic`, `roughness` |
//! | normalTexture, scale | `normal` through `normal_map` (strength = scale) |
//! | emissiveFactor × emissiveTexture × KHR_materials_emissive_strength | `emission_color`, `emission_strength` |
//! | KHR_materials_ior | `ior` |
//! | KHR_materials_transmission (factor × texture R) | `transmission_weight`; thin-walled without volume |
//! | KHR_materials_volume (attenuation colour, distance) | `transmission_color`, `transmission_depth` |
//! | KHR_materials_diffuse_transmission (factor × texture A, colour × RGB) | `subsurface_weight`, `transmission_color`; thin-walled (diffuse transmission) |
//! | KHR_materials_specular (factor × A, colour × RGB) | `specular_weight`, `specular_color` |
//! | KHR_materials_clearcoat (factor × R, roughness × G) | `coat_weight`, `coat_roughness` |
//! | KHR_materials_sheen (colour × RGB, roughness × A) | `sheen_weight` 1, `sheen_color`, `sheen_roughness` |
//! | KHR_materials_unlit | the base colour emitted, no reflection |
//! | KHR_materials_pbrSpecularGlossiness | approximated: diffuse → base, 1 − glossiness → roughness |
//!
//! The occlusion texture is a rasteriser's stand-in for what a path tracer computes, and
//! is left out. Numbers are clamped to their ranges; non-finite ones take the default.

use gltf::json;
use gltf::json::material::AlphaMode;
use gltf::json::validation::Checked;

use crate::texture::{ImageFiles, TextureRef, texture_node};
use kiln_plugin_api::kmat::{Graph, Node, Value};

/// What varies between the graphs made from one glTF material.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Variant {
    /// Multiply the base colour (and alpha) by the mesh's vertex colour (COLOR_0).
    pub vertex_colors: bool,
    /// Use textures; off for the retry after the host refused a textured graph.
    pub textures: bool,
}

/// A translated material.
pub struct MaterialText {
    pub name: String,
    pub kmat: String,
}

fn finite_or(v: f32, default: f32) -> f32 {
    if v.is_finite() { v } else { default }
}

fn unit(v: f32, default: f32) -> f32 {
    finite_or(v, default).clamp(0.0, 1.0)
}

fn unit3(v: [f32; 3], default: f32) -> [f32; 3] {
    v.map(|x| unit(x, default))
}

/// A number field of a raw extension object.
fn number(object: &json::Value, field: &str, default: f32) -> f32 {
    object
        .get(field)
        .and_then(json::Value::as_f64)
        .map_or(default, |v| finite_or(v as f32, default))
}

fn color3(object: &json::Value, field: &str, default: [f32; 3]) -> [f32; 3] {
    match object.get(field).and_then(json::Value::as_array) {
        Some(a) if a.len() == 3 => std::array::from_fn(|i| {
            a[i].as_f64()
                .map_or(default[i], |v| finite_or(v as f32, default[i]))
        }),
        _ => default,
    }
}

/// Graph construction for one material: textures resolved on demand.
struct Translation<'a> {
    graph: Graph,
    root: &'a json::Root,
    images: &'a mut dyn ImageFiles,
    textures: bool,
    warnings: Vec<String>,
    inputs: Vec<(&'static str, Value)>,
}

impl Translation<'_> {
    /// The image node of texture `r` (outputs `color`, `alpha`), or None.
    fn texture(&mut self, r: Option<TextureRef>, role: &str, srgb: bool) -> Option<String> {
        if !self.textures {
            return None;
        }
        let r = r?;
        let warnings = &mut self.warnings;
        texture_node(
            &mut self.graph,
            self.root,
            self.images,
            &r,
            role,
            srgb,
            &mut |m| warnings.push(m),
        )
    }

    /// One channel (`red`, `green`, `blue`) of a texture's colour.
    fn channel(&mut self, texture: &str, channel: &str) -> Value {
        let node = Node::new("separate_color").input("color", Value::link(texture, "color"));
        let id = self.graph.add(&format!("{texture}_channels"), node);
        Value::link(&id, channel)
    }

    /// `factor`, times a channel of a texture if there is one.
    fn scalar(&mut self, factor: f32, r: Option<TextureRef>, role: &str, channel: &str) -> Value {
        let mut v = Value::Float(factor);
        if let Some(t) = self.texture(r, role, false) {
            let c = if channel == "alpha" {
                Value::link(&t, "alpha")
            } else {
                self.channel(&t, channel)
            };
            v = self.graph.multiply(role, v, c);
        }
        v
    }

    /// `factor`, times the colour of an sRGB texture if there is one.
    fn color(
        &mut self,
        factor: [f32; 3],
        r: Option<TextureRef>,
        role: &str,
    ) -> (Value, Option<String>) {
        let mut v = Value::Color(factor);
        let t = self.texture(r, role, true);
        if let Some(t) = &t {
            v = self.graph.multiply_color(role, v, Value::link(t, "color"));
        }
        (v, t)
    }

    fn set(&mut self, input: &'static str, value: Value) {
        self.inputs.retain(|(name, _)| *name != input);
        self.inputs.push((input, value));
    }

    fn product(&mut self, id: &str, terms: Vec<Value>) -> Value {
        terms
            .into_iter()
            .fold(Value::Float(1.0), |acc, t| self.graph.multiply(id, acc, t))
    }

    fn one_minus(&mut self, id: &str, v: Value) -> Value {
        match v {
            Value::Float(x) => Value::Float(1.0 - x),
            v => {
                let node = Node::new("math")
                    .text("operation", "subtract")
                    .input("a", Value::Float(1.0))
                    .input("b", v);
                Value::link(&self.graph.add(id, node), "value")
            }
        }
    }
}

/// The graph of glTF material `index` (None: the vertex-colour default, for primitives
/// without a material). Warnings are returned, prefixed with the material's name.
pub fn translate(
    root: &json::Root,
    index: Option<usize>,
    variant: Variant,
    images: &mut dyn ImageFiles,
) -> (MaterialText, Vec<String>) {
    let mut t = Translation {
        graph: Graph::default(),
        root,
        images,
        textures: variant.textures,
        warnings: Vec::new(),
        inputs: Vec::new(),
    };
    let material = index.and_then(|i| root.materials.get(i));
    let name = match (material, index) {
        (Some(m), Some(i)) => m.name.clone().unwrap_or_else(|| format!("material {i}")),
        _ => "vertex colours".to_owned(),
    };
    let thin_walled = match material {
        Some(m) => surface(&mut t, m, variant.vertex_colors),
        None => {
            let vc = t.graph.add("vertex_color", Node::new("vertex_color"));
            t.set("base_color", Value::link(&vc, "color"));
            false
        }
    };
    let mut principled = Node::new("principled_bsdf");
    if thin_walled {
        principled = principled.flag("thin_walled", true);
    }
    for (input, value) in std::mem::take(&mut t.inputs) {
        principled = principled.input(input, value);
    }
    let surface = t.graph.add("surface", principled);
    t.graph.add(
        "out",
        Node::new("material_output").input("surface", Value::link(&surface, "bsdf")),
    );
    let warnings = t
        .warnings
        .into_iter()
        .map(|w| format!("material \"{name}\": {w}"))
        .collect();
    let kmat = t.graph.to_kmat(&name, &[]);
    (MaterialText { name, kmat }, warnings)
}

/// Fills `t.inputs` from material `m`; returns whether the surface is thin-walled.
fn surface(t: &mut Translation, m: &json::Material, vertex_colors: bool) -> bool {
    let pbr = &m.pbr_metallic_roughness;
    let ext = m.extensions.as_ref();
    let spec_gloss = ext.and_then(|e| e.pbr_specular_glossiness.as_ref());
    let unlit = ext.is_some_and(|e| e.unlit.is_some());

    // Base colour and alpha.
    let (factor, base_texture) = match spec_gloss {
        Some(sg) => (sg.diffuse_factor.0, sg.diffuse_texture.as_ref()),
        None => (pbr.base_color_factor.0, pbr.base_color_texture.as_ref()),
    };
    let (mut base, texture) = t.color(
        unit3([factor[0], factor[1], factor[2]], 1.0),
        base_texture.map(TextureRef::from_info),
        "base_color",
    );
    let mut alpha_terms = vec![Value::Float(unit(factor[3], 1.0))];
    if let Some(texture) = texture {
        alpha_terms.push(Value::link(&texture, "alpha"));
    }
    if vertex_colors {
        let vc = t.graph.add("vertex_color", Node::new("vertex_color"));
        base = t
            .graph
            .multiply_color("base_color", base, Value::link(&vc, "color"));
        alpha_terms.push(Value::link(&vc, "alpha"));
    }
    let alpha = match m.alpha_mode {
        Checked::Valid(AlphaMode::Blend) => Some(t.product("alpha", alpha_terms)),
        Checked::Valid(AlphaMode::Mask) => {
            let cutoff = m.alpha_cutoff.map_or(0.5, |c| finite_or(c.0, 0.5));
            Some(match t.product("alpha", alpha_terms) {
                Value::Float(a) => Value::Float(if a >= cutoff { 1.0 } else { 0.0 }),
                a => {
                    // alpha ≥ cutoff as 1 − (alpha < cutoff): math's comparisons are strict.
                    let below = Node::new("math")
                        .text("operation", "less_than")
                        .input("a", a)
                        .input("b", Value::Float(cutoff));
                    let below = t.graph.add("alpha_below_cutoff", below);
                    t.one_minus("alpha_mask", Value::link(&below, "value"))
                }
            })
        }
        _ => None,
    };
    if let Some(alpha) = alpha.filter(|a| *a != Value::Float(1.0)) {
        t.set("alpha", alpha);
    }

    if unlit {
        // Unlit: the base colour is what the eye sees, whatever the lighting.
        t.set("base_color", Value::Color([0.0; 3]));
        t.set("specular_weight", Value::Float(0.0));
        t.set("emission_color", base);
        t.set("emission_strength", Value::Float(1.0));
        return false;
    }
    t.set("base_color", base.clone());

    if let Some(sg) = spec_gloss {
        // An approximation: the specular colour becomes the dielectric tint relative to
        // F0 = 0.04 (KHR_materials_specular's meaning), so coloured metals lose their hue.
        let (specular, sg_texture) = t.color(
            sg.specular_factor.0.map(|v| finite_or(v, 1.0).max(0.0)),
            sg.specular_glossiness_texture
                .as_ref()
                .map(TextureRef::from_info),
            "specular_glossiness",
        );
        let mut gloss = Value::Float(unit(sg.glossiness_factor.0, 1.0));
        if let Some(sg_texture) = sg_texture {
            gloss = t
                .graph
                .multiply("glossiness", gloss, Value::link(&sg_texture, "alpha"));
        }
        let roughness = t.one_minus("roughness", gloss);
        t.set("roughness", roughness);
        t.set("metallic", Value::Float(0.0));
        let tint = t
            .graph
            .multiply_color("specular_color", specular, Value::Color([25.0; 3]));
        t.set("specular_color", tint);
        t.warnings.push(
            "KHR_materials_pbrSpecularGlossiness is approximated with the metallic-roughness model"
                .into(),
        );
    } else {
        let mr = pbr
            .metallic_roughness_texture
            .as_ref()
            .map(TextureRef::from_info);
        let mut metallic = Value::Float(unit(pbr.metallic_factor.0, 1.0));
        let mut roughness = Value::Float(unit(pbr.roughness_factor.0, 1.0));
        if let Some(tex) = t.texture(mr, "metallic_roughness", false) {
            let green = t.channel(&tex, "green");
            let blue = t.channel(&tex, "blue");
            roughness = t.graph.multiply("roughness", roughness, green);
            metallic = t.graph.multiply("metallic", metallic, blue);
        }
        t.set("metallic", metallic);
        t.set("roughness", roughness);
    }

    if let Some(n) = &m.normal_texture {
        if let Some(tex) = t.texture(Some(TextureRef::from_normal(n)), "normal", false) {
            let map = Node::new("normal_map")
                .input("strength", Value::Float(finite_or(n.scale, 1.0)))
                .input("color", Value::link(&tex, "color"));
            let map = t.graph.add("normal_map", map);
            t.set("normal", Value::link(&map, "normal"));
        }
    }

    let strength = ext
        .and_then(|e| e.emissive_strength.as_ref())
        .map_or(1.0, |s| finite_or(s.emissive_strength.0, 1.0).max(0.0));
    let emissive = unit3(m.emissive_factor.0, 0.0);
    if strength > 0.0 && emissive.iter().any(|&v| v > 0.0) {
        let (color, _) = t.color(
            emissive,
            m.emissive_texture.as_ref().map(TextureRef::from_info),
            "emission",
        );
        t.set("emission_color", color);
        t.set("emission_strength", Value::Float(strength));
    }

    if let Some(ior) = ext.and_then(|e| e.ior.as_ref()) {
        let v = ior.ior.0;
        if v.is_finite() && v >= 1.0 {
            t.set("ior", Value::Float(v.min(10.0)));
        } else {
            t.warnings.push(format!(
                "index of refraction {v} is not supported; 1.5 used"
            ));
        }
    }

    let mut thin_walled = false;
    if let Some(tr) = ext.and_then(|e| e.transmission.as_ref()) {
        let factor = unit(tr.transmission_factor.0, 0.0);
        if factor > 0.0 {
            let r = tr.transmission_texture.as_ref().map(TextureRef::from_info);
            let weight = t.scalar(factor, r, "transmission", "red");
            t.set("transmission_weight", weight);
            // glTF tints transmitted light by the base colour at the surface; with a
            // volume, by its attenuation inside (Kiln's glass has one of the two).
            let volume = ext.and_then(|e| e.volume.as_ref());
            let thickness = volume.map_or(0.0, |v| finite_or(v.thickness_factor.0, 0.0));
            let distance = volume.map_or(f32::INFINITY, |v| v.attenuation_distance.0);
            if thickness <= 0.0 {
                thin_walled = true;
                t.set("transmission_color", base.clone());
            } else if distance.is_finite() && distance > 0.0 {
                let color = volume.map_or([1.0; 3], |v| unit3(v.attenuation_color.0, 1.0));
                t.set("transmission_color", Value::Color(color));
                t.set("transmission_depth", Value::Float(distance));
            } else {
                t.set("transmission_color", base.clone());
            }
        }
    }

    let others = ext.map(|e| &e.others);
    if let Some(dt) = others.and_then(|o| o.get("KHR_materials_diffuse_transmission")) {
        let factor = unit(number(dt, "diffuseTransmissionFactor", 0.0), 0.0);
        let glass = ext
            .and_then(|e| e.transmission.as_ref())
            .is_some_and(|tr| unit(tr.transmission_factor.0, 0.0) > 0.0);
        let thick = ext
            .and_then(|e| e.volume.as_ref())
            .is_some_and(|v| finite_or(v.thickness_factor.0, 0.0) > 0.0);
        if factor > 0.0 && glass && thick {
            t.warnings.push(
                "diffuse transmission into a volume behind glass is not supported: the glass is kept, the diffuse transmission ignored"
                    .into(),
            );
        } else if factor > 0.0 {
            // Kiln's thin wall passes the subsurface share of the diffuse base through
            // diffusely, tinted by the transmission colour: glTF's
            // mix(diffuse BRDF(base colour), diffuse BTDF(its colour), factor).
            if thick {
                t.warnings.push(
                    "diffuse transmission into a volume is rendered through a thin wall: the volume's attenuation does not apply to it"
                        .into(),
                );
            }
            let r = TextureRef::from_value(dt.get("diffuseTransmissionTexture"));
            let weight = t.scalar(factor, r, "diffuse_transmission", "alpha");
            let r = TextureRef::from_value(dt.get("diffuseTransmissionColorTexture"));
            let factor =
                color3(dt, "diffuseTransmissionColorFactor", [1.0; 3]).map(|v| unit(v, 1.0));
            let (color, _) = t.color(factor, r, "diffuse_transmission_color");
            if glass && color != base {
                t.warnings.push(
                    "a thin wall tints its glass and its diffuse transmission alike: the glass takes the diffuse transmission colour"
                        .into(),
                );
            }
            t.set("subsurface_weight", weight);
            t.set("transmission_color", color);
            thin_walled = true;
        }
    }

    if let Some(s) = ext.and_then(|e| e.specular.as_ref()) {
        let r = s.specular_texture.as_ref().map(TextureRef::from_info);
        let weight = t.scalar(unit(s.specular_factor.0, 1.0), r, "specular", "alpha");
        let (color, _) = t.color(
            s.specular_color_factor
                .0
                .map(|v| finite_or(v, 1.0).max(0.0)),
            s.specular_color_texture.as_ref().map(TextureRef::from_info),
            "specular_color",
        );
        if weight != Value::Float(1.0) {
            t.set("specular_weight", weight);
        }
        if color != Value::Color([1.0; 3]) {
            t.set("specular_color", color);
        }
    }

    if let Some(cc) = others.and_then(|o| o.get("KHR_materials_clearcoat")) {
        let factor = unit(number(cc, "clearcoatFactor", 0.0), 0.0);
        if factor > 0.0 {
            let r = TextureRef::from_value(cc.get("clearcoatTexture"));
            let weight = t.scalar(factor, r, "coat", "red");
            let r = TextureRef::from_value(cc.get("clearcoatRoughnessTexture"));
            let roughness = unit(number(cc, "clearcoatRoughnessFactor", 0.0), 0.0);
            let roughness = t.scalar(roughness, r, "coat_roughness", "green");
            t.set("coat_weight", weight);
            t.set("coat_roughness", roughness);
            if cc.get("clearcoatNormalTexture").is_some() {
                t.warnings.push(
                    "the clearcoat normal map is not supported: the coat follows the base normal"
                        .into(),
                );
            }
        }
    }

    if let Some(sh) = others.and_then(|o| o.get("KHR_materials_sheen")) {
        let factor = color3(sh, "sheenColorFactor", [0.0; 3]).map(|v| v.max(0.0));
        if factor.iter().any(|&v| v > 0.0) {
            let r = TextureRef::from_value(sh.get("sheenColorTexture"));
            let (color, _) = t.color(factor, r, "sheen_color");
            let r = TextureRef::from_value(sh.get("sheenRoughnessTexture"));
            let roughness = unit(number(sh, "sheenRoughnessFactor", 0.0), 0.0);
            let roughness = t.scalar(roughness, r, "sheen_roughness", "alpha");
            t.set("sheen_weight", Value::Float(1.0));
            t.set("sheen_color", color);
            t.set("sheen_roughness", roughness);
        }
    }
    thin_walled
}
