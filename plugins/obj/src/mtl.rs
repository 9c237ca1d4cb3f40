//! MTL materials as `.kmat` graphs on Kiln's principled BSDF.
//!
//! | MTL                      | principled input                                         |
//! |--------------------------|----------------------------------------------------------|
//! | `Kd`, `map_Kd`           | `base_color` (the map, sRGB, multiplied by `Kd`)         |
//! | `Ks`                     | `specular_weight` (see [`specular_weight_from_ks`]), `specular_color` (its hue) |
//! | `Ns`                     | `roughness` (see [`roughness_from_shininess`])           |
//! | `Ke`, `map_Ke`           | `emission_color`, `emission_strength` 1                  |
//! | `d`, `Tr`, `map_d`       | `alpha` (`Tr` is 1 − `d`)                                |
//! | `Ni`                     | `ior`                                                    |
//! | `illum` 4, 6, 7          | `transmission_weight` 1 (glass); `Tf` tints it           |
//! | `illum` 0, 1             | `specular_weight` 0 (no highlights)                      |
//! | `Pr`, `map_Pr`           | `roughness` (PBR extension; replaces `Ns` and `Ks`)      |
//! | `Pm`, `map_Pm`           | `metallic`                                               |
//! | `Pc`, `Pcr`, `Ps`        | `coat_weight`, `coat_roughness`, `sheen_weight`          |
//! | `aniso`, `anisor`        | `anisotropy`, `anisotropy_rotation`                      |
//! | `norm`                   | `normal` through a `normal_map` node (tangent space)     |
//! | `bump`, `map_Bump`       | `normal` through a `bump` node (height, strength `-bm`)  |
//!
//! Colour maps are sRGB, data maps (roughness, metallic, alpha, bump, normal) linear.
//! Of the texture options, `-s` and `-o` become a mapping node, `-clamp on` the
//! `extend` edge mode, `-imfchan` the channel a data map reads, `-bm` the bump or
//! normal-map strength; `-mm` and `-t` are reported as unsupported.
//! Texture paths stay as written, relative to the .obj's folder; the host resolves
//! them. Ambient terms (`Ka`, `map_Ka`) mean nothing to a path tracer and are dropped
//! quietly; other statements Kiln cannot use are reported as warnings.

use kiln_formats::obj::Material;

use crate::texture::{Channel, TextureRef, parse_texture};
use kiln_plugin_api::kmat::{Graph, Node, Value};

/// The height range of a bump map, in scene units, that the bump node's `distance`
/// gives a map going from 0 to 1: MTL heights have no unit, and this is a small
/// relief against a scene a few units across (as the bundled brick wall's).
pub const BUMP_HEIGHT: f32 = 0.01;

/// A material's graph and what the conversion could not keep.
pub struct Converted {
    pub kmat: String,
    pub warnings: Vec<String>,
}

/// Perceptual roughness (Kiln's `roughness`, whose square is the GGX α) for a Phong
/// exponent `Ns`. A Phong lobe cosⁿ matches a Beckmann lobe of α = sqrt(2 / (n + 2))
/// (Walter et al. 2007, "Microfacet Models for Refraction", section 5.2), the common
/// conversion of MTL shininess; GGX's α is close enough at these widths, and the
/// square root turns that α into the perceptual roughness the principled BSDF takes.
pub fn roughness_from_shininess(ns: f32) -> f32 {
    let alpha = (2.0 / (ns.max(0.0) + 2.0)).sqrt();
    alpha.sqrt().clamp(0.0, 1.0)
}

/// Kiln's `specular_weight` for the largest channel of `Ks`. Phong's Ks is no Fresnel
/// reflectance (an ordinary dielectric reflects 4 % head-on, and MTL files write Ks 0.5
/// or 1 for glossy plastic), so this follows Blender, whose OBJ exporter writes its
/// Specular as Ks and whose importer reads it back: Ks 0.5 is an ordinary dielectric
/// (weight 1, F0 0.04 at IOR 1.5), Ks 0 reflects nothing, Ks 1 doubles the reflection.
pub fn specular_weight_from_ks(ks: f32) -> f32 {
    2.0 * ks.clamp(0.0, 1.0)
}

/// Statements of `unknown_param` this conversion uses (lower case).
const USED: [&str; 17] = [
    "tr", "tf", "pr", "pm", "ps", "pc", "pcr", "aniso", "anisor", "map_pr", "map_pm", "map_ke",
    "norm", "map_kd", "map_d", "map_bump", "bump",
];
/// Statements dropped without a warning: ambient terms, and the texture-map anti-aliasing
/// switch.
const QUIET: [&str; 3] = ["ka", "map_ka", "map_aat"];

struct Converter<'a> {
    material: &'a Material,
    graph: Graph,
    /// The principled BSDF's inputs.
    surface: Node,
    warnings: Vec<String>,
    has_uv_node: bool,
}

impl<'a> Converter<'a> {
    /// A statement tobj did not parse itself, by case-insensitive name.
    fn statement(&self, name: &str) -> Option<&'a str> {
        self.material
            .unknown_param
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }

    /// The first number of statement `name`; non-finite or unparsable values are
    /// reported and dropped.
    fn number(&mut self, name: &str) -> Option<f32> {
        let text = self.statement(name)?;
        let value = text
            .split_whitespace()
            .next()
            .and_then(|w| w.parse::<f32>().ok());
        self.finite(name, value.unwrap_or(f32::NAN))
    }

    fn finite(&mut self, name: &str, value: f32) -> Option<f32> {
        if value.is_finite() {
            Some(value)
        } else {
            self.warnings
                .push(format!("{name}: not a finite number, ignored"));
            None
        }
    }

    fn finite3(&mut self, name: &str, value: Option<[f32; 3]>) -> Option<[f32; 3]> {
        let v = value?;
        if v.iter().all(|x| x.is_finite()) {
            Some(v)
        } else {
            self.warnings
                .push(format!("{name}: not finite numbers, ignored"));
            None
        }
    }

    /// A texture statement: tobj's field, or the first statement of `names` present.
    fn texture(&mut self, field: Option<&'a String>, names: &[&str]) -> Option<TextureRef> {
        let name = names[0];
        let text = field
            .map(String::as_str)
            .or_else(|| names.iter().find_map(|n| self.statement(n)))?;
        let parsed = parse_texture(text);
        match &parsed {
            None => self.warnings.push(format!("{name} names no file, ignored")),
            Some(t) => {
                for option in &t.ignored {
                    self.warnings
                        .push(format!("{name}: texture option {option} is not supported"));
                }
            }
        }
        parsed
    }

    /// Adds an image texture node `id` (with a mapping node for `-s`/`-o`); returns `id`.
    fn image(&mut self, id: &str, texture: &TextureRef, color_space: &str) -> String {
        let extension = if texture.clamp { "extend" } else { "repeat" };
        let mut node = Node::new("image_texture")
            .text("file", &texture.file)
            .text("color_space", color_space)
            .text("extension", extension);
        if texture.scale.is_some() || texture.offset.is_some() {
            if !self.has_uv_node {
                self.graph.add("uv", Node::new("texture_coordinate"));
                self.has_uv_node = true;
            }
            let [su, sv] = texture.scale.unwrap_or([1.0, 1.0]);
            let [ou, ov] = texture.offset.unwrap_or([0.0, 0.0]);
            let mapping = format!("{id}_mapping");
            // `point`: scale, then translate, as MTL's -s and -o.
            let mapping = self.graph.add(
                &mapping,
                Node::new("mapping")
                    .text("vector_type", "point")
                    .input("vector", Value::link("uv", "uv"))
                    .input("scale", Value::Vector([su, sv, 1.0]))
                    .input("location", Value::Vector([ou, ov, 0.0])),
            );
            node = node.input("vector", Value::link(&mapping, "vector"));
        }
        self.graph.add(id, node)
    }

    /// A data map read as one number (`-imfchan`, luminance by default).
    fn scalar_image(&mut self, id: &str, texture: &TextureRef) -> Value {
        let node = self.image(id, texture, "linear");
        let socket = match texture.channel {
            Some(Channel::Matte) => return Value::link(&node, "alpha"),
            Some(Channel::Red) => "red",
            Some(Channel::Green) => "green",
            Some(Channel::Blue) => "blue",
            Some(Channel::Luminance) | None => return Value::link(&node, "color"),
        };
        let split = format!("{id}_channels");
        let node = Node::new("separate_color").input("color", Value::link(&node, "color"));
        Value::link(&self.graph.add(&split, node), socket)
    }

    /// `value × map` (the map alone for a white value), or whichever of them exists.
    fn multiply_color(
        &mut self,
        id: &str,
        value: Option<[f32; 3]>,
        map: Option<Value>,
    ) -> Option<Value> {
        match (value, map) {
            (Some(v), Some(m)) => Some(self.graph.multiply_color(id, Value::Color(v), m)),
            (v, m) => m.or(v.map(Value::Color)),
        }
    }

    /// Sets a principled input; a later statement (a map after its value) replaces it.
    fn set(&mut self, input: &str, value: Value) {
        self.surface.set_input(input, value);
    }

    fn convert(mut self) -> Converted {
        let m = self.material;
        let pbr = ["pr", "pm", "map_pr", "map_pm"]
            .iter()
            .any(|k| self.statement(k).is_some());

        // Base colour.
        let kd = self.finite3("Kd", m.diffuse);
        let kd_map = self
            .texture(m.diffuse_texture.as_ref(), &["map_Kd"])
            .map(|t| Value::link(&self.image("kd_texture", &t, "srgb"), "color"));
        if let Some(color) = self.multiply_color("base_color", kd, kd_map) {
            self.set("base_color", color);
        }

        // Specular and roughness: the PBR extension's terms, or Phong's.
        if pbr {
            if let Some(pr) = self.number("Pr") {
                self.set("roughness", Value::Float(pr.clamp(0.0, 1.0)));
            }
            if let Some(t) = self.texture(None, &["map_Pr"]) {
                let v = self.scalar_image("pr_texture", &t);
                self.set("roughness", v);
            }
            if let Some(pm) = self.number("Pm") {
                self.set("metallic", Value::Float(pm.clamp(0.0, 1.0)));
            }
            if let Some(t) = self.texture(None, &["map_Pm"]) {
                let v = self.scalar_image("pm_texture", &t);
                self.set("metallic", v);
            }
        } else {
            if matches!(m.illumination_model, Some(0 | 1)) {
                self.set("specular_weight", Value::Float(0.0));
            } else if let Some(ks) = self.finite3("Ks", m.specular) {
                let peak = ks.iter().copied().fold(0.0f32, f32::max).clamp(0.0, 1.0);
                self.set(
                    "specular_weight",
                    Value::Float(specular_weight_from_ks(peak)),
                );
                if peak > 0.0 {
                    let tint = ks.map(|c| (c / peak).clamp(0.0, 1.0));
                    self.set("specular_color", Value::Color(tint));
                }
            }
            if let Some(ns) = m.shininess.and_then(|ns| self.finite("Ns", ns)) {
                self.set("roughness", Value::Float(roughness_from_shininess(ns)));
            }
        }
        if m.specular_texture.is_some() {
            self.warnings.push("map_Ks is not supported".into());
        }
        if m.shininess_texture.is_some() {
            self.warnings
                .push("map_Ns is not supported (use map_Pr)".into());
        }

        // Emission. A black Ke beside a map_Ke is taken as unset rather than as a factor
        // that blacks the map out: exporters write the emission colour socket's unused
        // value there when a texture drives it.
        let ke = self
            .finite3("Ke", m.emissive)
            .filter(|c| c.iter().any(|&x| x > 0.0));
        let ke_map = self
            .texture(None, &["map_Ke"])
            .map(|t| Value::link(&self.image("ke_texture", &t, "srgb"), "color"));
        let emits = ke.is_some() || ke_map.is_some();
        if let Some(color) = self.multiply_color("emission", ke, ke_map) {
            self.set("emission_color", color);
        }
        if emits {
            self.set("emission_strength", Value::Float(1.0));
        }

        // Opacity: d, or Tr = 1 − d.
        let d = match m.dissolve.and_then(|d| self.finite("d", d)) {
            Some(d) => Some(d),
            None => self.number("Tr").map(|tr| 1.0 - tr),
        }
        .map(|d| d.clamp(0.0, 1.0));
        let d_map = self
            .texture(m.dissolve_texture.as_ref(), &["map_d"])
            .map(|t| self.scalar_image("d_texture", &t));
        match (d, d_map) {
            (Some(d), None) if d < 1.0 => self.set("alpha", Value::Float(d)),
            (Some(d), Some(map)) if d < 1.0 => {
                let alpha = self.graph.multiply("alpha", map, Value::Float(d));
                self.set("alpha", alpha);
            }
            (_, Some(map)) => self.set("alpha", map),
            _ => {}
        }

        // Refraction. Ni 1 (or below) is what exporters write when they have no IOR; as
        // an IOR it would take every reflection off the surface, so it keeps the default.
        let ni = m.optical_density.and_then(|ni| self.finite("Ni", ni));
        if let Some(ni) = ni.filter(|&ni| ni > 1.0) {
            self.set("ior", Value::Float(ni));
        }
        if matches!(m.illumination_model, Some(4 | 6 | 7)) {
            self.set("transmission_weight", Value::Float(1.0));
        }
        if let Some(tf) = self.statement("Tf") {
            let numbers: Vec<f32> = tf
                .split_whitespace()
                .map_while(|w| w.parse::<f32>().ok())
                .collect();
            match numbers[..] {
                [g] if g.is_finite() => self.set("transmission_color", Value::Color([g; 3])),
                [r, g, b, ..] if [r, g, b].iter().all(|x| x.is_finite()) => {
                    self.set("transmission_color", Value::Color([r, g, b]))
                }
                _ => self
                    .warnings
                    .push(format!("Tf {tf}: only RGB filters are supported")),
            }
        }

        // Further PBR extension terms.
        for (statement, input) in [
            ("Pc", "coat_weight"),
            ("Pcr", "coat_roughness"),
            ("Ps", "sheen_weight"),
            ("aniso", "anisotropy"),
        ] {
            if let Some(v) = self.number(statement) {
                self.set(input, Value::Float(v.clamp(0.0, 1.0)));
            }
        }
        if let Some(v) = self.number("anisor") {
            self.set("anisotropy_rotation", Value::Float(v));
        }

        // Shading normal: a tangent-space normal map, then a bump map on top of it.
        let mut normal = None;
        if let Some(t) = self.texture(None, &["norm"]) {
            let image = self.image("norm_texture", &t, "linear");
            let strength = t.bump_multiplier.unwrap_or(1.0).clamp(0.0, 1.0);
            let map = Node::new("normal_map")
                .input("color", Value::link(&image, "color"))
                .input("strength", Value::Float(strength));
            let map = self.graph.add("normal_map", map);
            normal = Some(Value::link(&map, "normal"));
        }
        if let Some(t) = self.texture(m.normal_texture.as_ref(), &["map_Bump", "bump"]) {
            let height = self.scalar_image("bump_texture", &t);
            let strength = t.bump_multiplier.unwrap_or(1.0).clamp(0.0, 1.0);
            let mut bump = Node::new("bump")
                .input("height", height)
                .input("strength", Value::Float(strength))
                .input("distance", Value::Float(BUMP_HEIGHT));
            if let Some(n) = normal.take() {
                bump = bump.input("normal", n);
            }
            let bump = self.graph.add("bump", bump);
            normal = Some(Value::link(&bump, "normal"));
        }
        if let Some(n) = normal {
            self.set("normal", n);
        }

        let mut ignored: Vec<&str> = m
            .unknown_param
            .keys()
            .map(String::as_str)
            .filter(|k| {
                let k = k.to_ascii_lowercase();
                !USED.contains(&k.as_str()) && !QUIET.contains(&k.as_str())
            })
            .collect();
        ignored.sort_unstable();
        if !ignored.is_empty() {
            self.warnings
                .push(format!("statements not supported: {}", ignored.join(", ")));
        }

        let surface = std::mem::replace(&mut self.surface, Node::new("principled_bsdf"));
        let surface = self.graph.add("surface", surface);
        self.graph.add(
            "out",
            Node::new("material_output").input("surface", Value::link(&surface, "bsdf")),
        );
        let comment = [format!(
            "Converted by kiln-obj from the MTL material \"{}\".",
            m.name
        )];
        let name = m.name.clone();
        Converted {
            kmat: self.graph.to_kmat(&name, &comment),
            warnings: self
                .warnings
                .into_iter()
                .map(|w| format!("material \"{name}\": {w}"))
                .collect(),
        }
    }
}

/// The `.kmat` graph of an MTL material.
pub fn convert(material: &Material) -> Converted {
    Converter {
        material,
        graph: Graph::default(),
        surface: Node::new("principled_bsdf"),
        warnings: Vec::new(),
        has_uv_node: false,
    }
    .convert()
}
