//! pbrlib's closures (the BSDF and EDF nodes and the `surface` that combines them), as
//! tools that build shading from closures write it, folded onto one Principled BSDF by the
//! structure OpenPBR and Standard Surface are built of (docs/MATERIALX.md):
//!
//! - a diffuse BSDF (Oren–Nayar, Burley) is the base colour, weight and roughness;
//! - a reflecting dielectric is the specular lobe, or the coat where it is layered over
//!   a surface that already has one; a transmitting dielectric is transmission;
//! - a conductor (its reflectance at normal incidence and the tint at 82° from its complex
//!   index) or a generalized Schlick BSDF (its `color0` and `color82`) is the metal;
//! - sheen is fuzz (Conty–Kulla's roughness as Standard Surface's sheen is translated),
//!   subsurface is subsurface;
//! - `layer` puts its top over its base; `mix` weighs one side by its factor (a metal,
//!   transmission or subsurface side becomes that lobe's weight, as the Principled BSDF
//!   mixes them itself; two others have their weights summed and colours mixed); `add`
//!   and `multiply` add lobes and scale weights;
//! - a uniform EDF is the emission, the surface's opacity its alpha.
//!
//! A closure Kiln has no lobe for (hair, diffuse transmission, conical or measured
//! emission) is an error naming it.

use std::collections::BTreeMap;

use kiln_plugin_api::kmat::Value;

use super::{Build, Element, Scope, elements, input, name_of, position};
use crate::surface::{self, Ops, constant3};

/// What a closure graph folds into: OpenPBR's inputs, and the lobes seen that decide
/// what a later closure is (a coat over a reflecting surface) and which lobes stay off.
#[derive(Default)]
struct Fold {
    open_pbr: BTreeMap<String, Value>,
    diffuse: bool,
    specular: bool,
    metal: bool,
}

/// OpenPBR inputs that weigh a lobe: summed where two sides of a mix both set them.
const WEIGHTS: &[&str] = &[
    "base_weight",
    "base_metalness",
    "specular_weight",
    "transmission_weight",
    "subsurface_weight",
    "fuzz_weight",
    "coat_weight",
];

/// The lobe a closure is at heart (through `multiply`), where a mix makes its factor that
/// lobe's weight.
fn weighed_lobe(e: Element) -> Option<&'static str> {
    match e.tag_name().name() {
        "conductor_bsdf" | "generalized_schlick_bsdf" => Some("metal"),
        "subsurface_bsdf" => Some("subsurface"),
        "dielectric_bsdf" => {
            let mode = input(e, "scatter_mode").and_then(|i| i.attribute("value"));
            matches!(mode, Some("T" | "RT")).then_some("transmission")
        }
        "multiply" => {
            let container = e.parent()?;
            let source = input(e, "in1")?.attribute("nodename")?;
            weighed_lobe(elements(container).find(|c| c.attribute("name") == Some(source))?)
        }
        _ => None,
    }
}

/// A conductor's reflectance at normal incidence and at 82° for complex index `n + ik`
/// (unpolarised Fresnel), and the tint at 82° over Schlick's curve from the first, which
/// is how OpenPBR describes a metal (base colour and specular colour).
fn conductor_colors(n: [f32; 3], k: [f32; 3]) -> ([f32; 3], [f32; 3]) {
    let fresnel = |n: f32, k: f32, cos: f32| {
        let (c2, s2) = (cos * cos, 1.0 - cos * cos);
        let (n2, k2) = (n * n, k * k);
        let t0 = n2 - k2 - s2;
        let a2b2 = (t0 * t0 + 4.0 * n2 * k2).sqrt();
        let a = ((a2b2 + t0) * 0.5).max(0.0).sqrt();
        let t1 = a2b2 + c2;
        let t2 = 2.0 * cos * a;
        let rs = (t1 - t2) / (t1 + t2);
        let t3 = c2 * a2b2 + s2 * s2;
        let t4 = t2 * s2;
        let rp = rs * (t3 - t4) / (t3 + t4);
        0.5 * (rp + rs)
    };
    let cos82 = 82f32.to_radians().cos();
    let f0: [f32; 3] = std::array::from_fn(|i| fresnel(n[i], k[i], 1.0).clamp(0.0, 1.0));
    let tint = std::array::from_fn(|i| {
        let schlick = f0[i] + (1.0 - f0[i]) * (1.0 - cos82).powi(5);
        (fresnel(n[i], k[i], cos82) / schlick).clamp(0.0, 1.0)
    });
    (f0, tint)
}

impl<'a> Build<'_, 'a> {
    /// The node an input of `node` connects (in the same graph, or the document's top).
    fn closure_source(
        &mut self,
        scope: &Scope<'a>,
        node: Element<'a>,
        name: &str,
    ) -> Option<Element<'a>> {
        let source = input(node, name)?.attribute("nodename")?;
        let found = match scope.container {
            Some(c) => elements(c).find(|e| e.attribute("name") == Some(source)),
            None => self.doc.top(source),
        };
        if found.is_none() {
            self.warn(format!(
                "{} names node {source}, which is not in its graph",
                name_of(node)
            ));
        }
        found
    }

    /// Input `name` of closure `node` as a Kiln value, `default` where it is not set.
    fn closure_input(
        &mut self,
        scope: &mut Scope<'a>,
        node: Element<'a>,
        name: &str,
        default: Value,
    ) -> Value {
        input(node, name)
            .and_then(|i| self.resolve(scope, i))
            .unwrap_or(default)
    }

    /// A pbrlib `surface` node (`bsdf`, `edf`, `opacity`, `thin_walled`) as a Principled
    /// BSDF; the error names the closure Kiln has no lobe for.
    pub(super) fn closure_surface(
        &mut self,
        scope: &mut Scope<'a>,
        shader: Element<'a>,
    ) -> Result<Value, String> {
        let name = name_of(shader);
        let mut fold = Fold::default();
        if let Some(bsdf) = self.closure_source(scope, shader, "bsdf") {
            self.fold_bsdf(scope, bsdf, &mut fold, Value::Float(1.0))?;
        }
        if let Some(edf) = self.closure_source(scope, shader, "edf") {
            // Radiance as a colour in [0, 1] times a strength.
            let (color, strength) = match self.fold_edf(scope, edf)? {
                Value::Color(c) => {
                    let m = c[0].max(c[1]).max(c[2]);
                    if m > 0.0 {
                        (Value::Color(c.map(|x| x / m)), m)
                    } else {
                        (Value::Color(c), 0.0)
                    }
                }
                emission => (emission, 1.0),
            };
            fold.open_pbr.insert("emission_color".into(), color);
            fold.open_pbr
                .insert("emission_luminance".into(), Value::Float(strength));
        }
        let opacity = self.closure_input(scope, shader, "opacity", Value::Float(1.0));
        fold.open_pbr.insert("geometry_opacity".into(), opacity);
        // Lobes no closure gave are off (OpenPBR's defaults would turn them on).
        if !fold.specular {
            fold.open_pbr
                .entry("specular_weight".into())
                .or_insert(Value::Float(0.0));
        }
        if !fold.diffuse {
            fold.open_pbr
                .entry("base_weight".into())
                .or_insert(Value::Float(0.0));
        }
        let thin_walled = input(shader, "thin_walled")
            .and_then(|i| i.attribute("value"))
            .is_some_and(|v| v.trim() == "true");
        let node = surface::principled(name, &fold.open_pbr, thin_walled, &mut self.warnings);
        let node = position(shader, node);
        Ok(Value::link(&scope.graph.add(name, node), "bsdf"))
    }

    /// Sets OpenPBR input `key` from closure `node`. Where another closure set it
    /// already, weights add up; a colour or roughness shared by two lobes (a metal's and
    /// a dielectric's base colour) is mixed by `share`, the later lobe's weight, and the
    /// approximation named in a warning unless the two are equal.
    fn set(
        &mut self,
        scope: &mut Scope<'a>,
        fold: &mut Fold,
        node: Element,
        key: &str,
        value: Value,
        share: &Value,
    ) {
        let value = match fold.open_pbr.get(key).cloned() {
            None => value,
            Some(old) if old == value => value,
            Some(old) if WEIGHTS.contains(&key) => {
                let mut ops = ops(scope, node);
                ops.math(key, "add", old, value, |a, b| a + b)
            }
            Some(old) => {
                self.warn(format!(
                    "{} ({}) and another closure both set the Principled BSDF's {key}: mixed by its weight",
                    name_of(node),
                    node.tag_name().name()
                ));
                let color = matches!(value, Value::Color(_)) || matches!(old, Value::Color(_));
                ops(scope, node).mix(key, color, old, value, share.clone())
            }
        };
        fold.open_pbr.insert(key.to_owned(), value);
    }

    /// The specular lobe's roughness and anisotropy ([`Build::closure_roughness`]).
    fn set_roughness(
        &mut self,
        scope: &mut Scope<'a>,
        fold: &mut Fold,
        node: Element,
        (roughness, anisotropy): (Value, Value),
        share: &Value,
    ) {
        self.set(scope, fold, node, "specular_roughness", roughness, share);
        self.set(
            scope,
            fold,
            node,
            "specular_roughness_anisotropy",
            anisotropy,
            share,
        );
    }

    /// A BSDF closure (and what it is made of) folded into `fold` with weight `weight`.
    fn fold_bsdf(
        &mut self,
        scope: &mut Scope<'a>,
        e: Element<'a>,
        fold: &mut Fold,
        weight: Value,
    ) -> Result<(), String> {
        let name = name_of(e);
        let category = e.tag_name().name();
        let own = self.closure_input(scope, e, "weight", Value::Float(1.0));
        let w = scope
            .graph
            .multiply(&format!("{name}_weight"), weight.clone(), own);
        let one = Value::Float(1.0);
        match category {
            "oren_nayar_diffuse_bsdf" | "burley_diffuse_bsdf" => {
                let color = self.closure_input(scope, e, "color", Value::Color([0.18; 3]));
                let roughness = self.closure_input(scope, e, "roughness", Value::Float(0.0));
                self.set(scope, fold, e, "base_weight", w.clone(), &one);
                self.set(scope, fold, e, "base_color", color, &w);
                self.set(scope, fold, e, "base_diffuse_roughness", roughness, &w);
                fold.diffuse = true;
            }
            "dielectric_bsdf" => {
                let mode = input(e, "scatter_mode")
                    .and_then(|i| i.attribute("value"))
                    .unwrap_or("R");
                let tint = self.closure_input(scope, e, "tint", Value::Color([1.0; 3]));
                let ior = self.closure_input(scope, e, "ior", Value::Float(1.5));
                let (roughness, anisotropy) = self.closure_roughness(scope, e);
                match mode {
                    // Over a surface that reflects already, a reflecting dielectric is
                    // its coat.
                    "R" if fold.specular || fold.metal => {
                        self.set(scope, fold, e, "coat_weight", w, &one);
                        self.set(scope, fold, e, "coat_ior", ior, &one);
                        self.set(scope, fold, e, "coat_roughness", roughness, &one);
                        if constant3(&tint) != Some([1.0; 3]) {
                            self.warn(format!(
                                "{name} (dielectric_bsdf): the tint of a coat's reflection is not read (Kiln's coat colour tints what passes through it)"
                            ));
                        }
                    }
                    "R" | "T" | "RT" => {
                        let reflects = mode != "T";
                        let transmits = mode != "R";
                        if reflects {
                            self.set(scope, fold, e, "specular_weight", w.clone(), &one);
                            self.set(scope, fold, e, "specular_color", tint.clone(), &w);
                            fold.specular = true;
                        }
                        if transmits {
                            self.set(scope, fold, e, "transmission_weight", w.clone(), &one);
                            self.set(scope, fold, e, "transmission_color", tint, &w);
                        }
                        self.set(scope, fold, e, "specular_ior", ior, &w);
                        self.set_roughness(scope, fold, e, (roughness, anisotropy), &w);
                    }
                    other => {
                        return Err(format!("{name} (dielectric_bsdf, scatter mode {other})"));
                    }
                }
            }
            "conductor_bsdf" | "generalized_schlick_bsdf" => {
                let (color, tint) = if category == "conductor_bsdf" {
                    let n =
                        self.closure_input(scope, e, "ior", Value::Color([0.183, 0.421, 1.373]));
                    let k = self.closure_input(
                        scope,
                        e,
                        "extinction",
                        Value::Color([3.424, 2.346, 1.770]),
                    );
                    let (n, k) = match (constant3(&n), constant3(&k)) {
                        (Some(n), Some(k)) => (n, k),
                        _ => {
                            self.warn(format!(
                                "{name} (conductor_bsdf): a complex index that varies is not read; MaterialX's default (aluminium) stands for it"
                            ));
                            ([0.183, 0.421, 1.373], [3.424, 2.346, 1.770])
                        }
                    };
                    let (f0, f82) = conductor_colors(n, k);
                    (Value::Color(f0), Value::Color(f82))
                } else {
                    let mode = input(e, "scatter_mode").and_then(|i| i.attribute("value"));
                    if matches!(mode, Some("T" | "RT")) {
                        return Err(format!("{name} (generalized_schlick_bsdf, transmitting)"));
                    }
                    (
                        self.closure_input(scope, e, "color0", Value::Color([1.0; 3])),
                        self.closure_input(scope, e, "color82", Value::Color([1.0; 3])),
                    )
                };
                let (roughness, anisotropy) = self.closure_roughness(scope, e);
                self.set(scope, fold, e, "base_metalness", w.clone(), &one);
                self.set(scope, fold, e, "base_color", color, &w);
                self.set(scope, fold, e, "specular_color", tint, &w);
                self.set_roughness(scope, fold, e, (roughness, anisotropy), &w);
                fold.metal = true;
            }
            "sheen_bsdf" => {
                let color = self.closure_input(scope, e, "color", Value::Color([1.0; 3]));
                let roughness = self.closure_input(scope, e, "roughness", Value::Float(0.3));
                // Zeltner's sheen is OpenPBR's fuzz; Conty and Kulla's (the default, and
                // Standard Surface's) is translated as Standard Surface's sheen is.
                let mode = input(e, "mode").and_then(|i| i.attribute("value"));
                let roughness = if mode.map(str::trim) == Some("zeltner") {
                    roughness
                } else {
                    ops(scope, e).math(
                        "fuzz_roughness",
                        "power",
                        roughness,
                        Value::Float(0.4),
                        f32::powf,
                    )
                };
                self.set(scope, fold, e, "fuzz_weight", w, &one);
                self.set(scope, fold, e, "fuzz_color", color, &one);
                self.set(scope, fold, e, "fuzz_roughness", roughness, &one);
            }
            "subsurface_bsdf" => {
                // Kiln's subsurface scatters the base colour.
                let color = self.closure_input(scope, e, "color", Value::Color([0.18; 3]));
                let radius = self.closure_input(scope, e, "radius", Value::Color([1.0; 3]));
                let anisotropy = self.closure_input(scope, e, "anisotropy", Value::Float(0.0));
                let (scale, radius) = match constant3(&radius) {
                    Some(r) => {
                        let m = r[0].max(r[1]).max(r[2]).max(1e-6);
                        (Value::Float(m), Value::Color(r.map(|x| x / m)))
                    }
                    None => (Value::Float(1.0), radius),
                };
                self.set(scope, fold, e, "subsurface_weight", w.clone(), &one);
                self.set(scope, fold, e, "base_color", color, &w);
                self.set(scope, fold, e, "subsurface_radius", scale, &one);
                self.set(scope, fold, e, "subsurface_radius_scale", radius, &one);
                self.set(
                    scope,
                    fold,
                    e,
                    "subsurface_scatter_anisotropy",
                    anisotropy,
                    &one,
                );
            }
            "layer" => {
                if let Some(base) = self.closure_source(scope, e, "base") {
                    if input(e, "base").and_then(|i| i.attribute("type")) == Some("VDF") {
                        return Err(format!("{name} (layer over a volume)"));
                    }
                    self.fold_bsdf(scope, base, fold, weight.clone())?;
                }
                if let Some(top) = self.closure_source(scope, e, "top") {
                    self.fold_bsdf(scope, top, fold, weight)?;
                }
            }
            "mix" => {
                let t = self.closure_input(scope, e, "mix", Value::Float(0.0));
                let fg = self.closure_source(scope, e, "fg");
                let bg = self.closure_source(scope, e, "bg");
                let rest =
                    ops(scope, e).math("rest", "subtract", one.clone(), t.clone(), |a, b| a - b);
                let fg_w = scope
                    .graph
                    .multiply(&format!("{name}_fg"), weight.clone(), t.clone());
                let bg_w = scope
                    .graph
                    .multiply(&format!("{name}_bg"), weight.clone(), rest);
                // A metal, transmission or subsurface side is that lobe, weighed by the
                // factor; the Principled BSDF takes the rest from the other side itself.
                match (fg.and_then(weighed_lobe), bg.and_then(weighed_lobe)) {
                    (Some(_), _) => {
                        if let Some(bg) = bg {
                            self.fold_bsdf(scope, bg, fold, weight)?;
                        }
                        if let Some(fg) = fg {
                            self.fold_bsdf(scope, fg, fold, fg_w)?;
                        }
                    }
                    (None, Some(_)) => {
                        if let Some(fg) = fg {
                            self.fold_bsdf(scope, fg, fold, weight)?;
                        }
                        if let Some(bg) = bg {
                            self.fold_bsdf(scope, bg, fold, bg_w)?;
                        }
                    }
                    (None, None) => {
                        if let Some(bg) = bg {
                            self.fold_bsdf(scope, bg, fold, bg_w)?;
                        }
                        if let Some(fg) = fg {
                            self.fold_bsdf(scope, fg, fold, fg_w)?;
                        }
                    }
                }
            }
            "add" => {
                for side in ["in1", "in2"] {
                    if let Some(s) = self.closure_source(scope, e, side) {
                        self.fold_bsdf(scope, s, fold, weight.clone())?;
                    }
                }
            }
            "multiply" => {
                let factor = self.closure_input(scope, e, "in2", one.clone());
                let factor = match (&factor, constant3(&factor)) {
                    (Value::Float(_), _) => factor,
                    (_, Some(c)) => Value::Float((c[0] + c[1] + c[2]) / 3.0),
                    _ => {
                        self.warn(format!(
                            "{name} (multiply): a closure scaled by a varying colour is read unscaled"
                        ));
                        one
                    }
                };
                let w = scope.graph.multiply(&format!("{name}_by"), weight, factor);
                if let Some(s) = self.closure_source(scope, e, "in1") {
                    self.fold_bsdf(scope, s, fold, w)?;
                }
            }
            _ => return Err(format!("{name} ({category})")),
        }
        Ok(())
    }

    /// An EDF closure's emitted radiance.
    fn fold_edf(&mut self, scope: &mut Scope<'a>, e: Element<'a>) -> Result<Value, String> {
        let name = name_of(e);
        let side = |this: &mut Self, scope: &mut Scope<'a>, input: &str| -> Result<Value, String> {
            match this.closure_source(scope, e, input) {
                Some(s) => this.fold_edf(scope, s),
                None => Ok(Value::Color([0.0; 3])),
            }
        };
        Ok(match e.tag_name().name() {
            "uniform_edf" => self.closure_input(scope, e, "color", Value::Color([1.0; 3])),
            "multiply" => {
                let factor = self.closure_input(scope, e, "in2", Value::Float(1.0));
                let emission = side(self, scope, "in1")?;
                scope
                    .graph
                    .multiply_color(&format!("{name}_by"), emission, factor)
            }
            "add" => {
                let (a, b) = (side(self, scope, "in1")?, side(self, scope, "in2")?);
                let ops = ops(scope, e);
                match (constant3(&a), constant3(&b)) {
                    (Some(x), Some(y)) => Value::Color(std::array::from_fn(|i| x[i] + y[i])),
                    _ => {
                        let node = kiln_plugin_api::kmat::Node::new("mix_color")
                            .text("blend", "add")
                            .input("factor", Value::Float(1.0))
                            .input("a", a)
                            .input("b", b);
                        Value::link(&ops.graph.add(&format!("{name}_sum"), node), "result")
                    }
                }
            }
            "mix" => {
                let t = self.closure_input(scope, e, "mix", Value::Float(0.0));
                let (fg, bg) = (side(self, scope, "fg")?, side(self, scope, "bg")?);
                ops(scope, e).mix("mix", true, bg, fg, t)
            }
            category => return Err(format!("{name} ({category})")),
        })
    }

    /// A closure's `roughness` (MaterialX's α pair) as Kiln's roughness and anisotropy:
    /// read through a `roughness_anisotropy` node (Standard Surface's roughness and
    /// anisotropy, as its mapping reads them) or `roughness_dual`, or from constants
    /// (r = (αx αy)^¼, anisotropy 1 − αy/αx).
    fn closure_roughness(&mut self, scope: &mut Scope<'a>, e: Element<'a>) -> (Value, Value) {
        let zero = Value::Float(0.0);
        if let Some(source) = self.closure_source(scope, e, "roughness") {
            match source.tag_name().name() {
                "roughness_anisotropy" => {
                    let r = self.closure_input(scope, source, "roughness", zero.clone());
                    let a = self.closure_input(scope, source, "anisotropy", zero.clone());
                    return (r, a);
                }
                "roughness_dual" => {
                    let r = self.closure_input(scope, source, "roughness", Value::Vector([0.0; 3]));
                    if let Some([x, y, _]) = constant3(&r) {
                        let y = if y < 0.0 { x } else { y };
                        let (ax, ay) = ((x * x).max(y * y), (x * x).min(y * y));
                        return alphas(ax, ay);
                    }
                }
                _ => {}
            }
            self.warn(format!(
                "{} ({}): a roughness computed other than by roughness_anisotropy is not read; 0.05 stands for it",
                name_of(e),
                e.tag_name().name()
            ));
            return alphas(0.05, 0.05);
        }
        let r = self.closure_input(scope, e, "roughness", Value::Vector([0.05, 0.05, 0.0]));
        match constant3(&r) {
            Some([x, y, _]) => alphas(x.max(y), x.min(y)),
            None => alphas(0.05, 0.05),
        }
    }
}

/// Kiln's roughness and anisotropy for GGX's αs along and across (Standard Surface's
/// `roughness_anisotropy` inverted).
fn alphas(ax: f32, ay: f32) -> (Value, Value) {
    let (ax, ay) = (ax.max(0.0), ay.max(0.0));
    let r = (ax * ay).sqrt().sqrt();
    let anisotropy = if ax > 0.0 { 1.0 - ay / ax } else { 0.0 };
    (Value::Float(r), Value::Float(anisotropy))
}

/// Expressions added to the scope's graph, named after `node`.
fn ops<'s>(scope: &'s mut Scope<'_>, node: Element) -> Ops<'s> {
    Ops {
        graph: &mut scope.graph,
        prefix: name_of(node).to_owned(),
    }
}

/// A homogeneous medium's absorption, scattering and emission (per unit length) as the
/// Principled Volume's colour, density and absorption colour (Cycles' parameterisation:
/// scattering = colour × density, absorption = (1 − colour)(1 − √absorption colour) ×
/// density), and its emission as colour × strength: exact, with density the largest
/// extinction of the three channels.
fn principled_volume(
    absorption: [f32; 3],
    scattering: [f32; 3],
    emission: [f32; 3],
) -> ([f32; 3], f32, [f32; 3], [f32; 3], f32) {
    let (a, s) = (
        absorption.map(|x| x.max(0.0)),
        scattering.map(|x| x.max(0.0)),
    );
    let density = (0..3).map(|i| a[i] + s[i]).fold(0.0, f32::max);
    if density <= 0.0 {
        return ([0.0; 3], 0.0, [0.0; 3], [0.0; 3], 0.0);
    }
    let color = s.map(|x| x / density);
    let absorption_color = std::array::from_fn(|i| {
        let room = density - s[i];
        if room > 0.0 {
            (1.0 - a[i] / room).clamp(0.0, 1.0).powi(2)
        } else {
            0.0
        }
    });
    let strength = emission.iter().copied().fold(0.0, f32::max);
    let emission_color = if strength > 0.0 {
        emission.map(|x| x.max(0.0) / strength)
    } else {
        [0.0; 3]
    };
    (color, density, absorption_color, emission_color, strength)
}

impl<'a> Build<'_, 'a> {
    /// A pbrlib `volume` node (`vdf`: an absorption or anisotropic VDF; `edf`: a
    /// uniform EDF) of constants as a Principled Volume.
    pub(super) fn closure_volume(
        &mut self,
        scope: &mut Scope<'a>,
        shader: Element<'a>,
    ) -> Result<Value, String> {
        let name = name_of(shader);
        let zero = Value::Vector([0.0; 3]);
        let (mut absorption, mut scattering, mut anisotropy) =
            (zero.clone(), zero, Value::Float(0.0));
        if let Some(vdf) = self.closure_source(scope, shader, "vdf") {
            match vdf.tag_name().name() {
                "absorption_vdf" => {
                    absorption = self.closure_input(scope, vdf, "absorption", absorption);
                }
                "anisotropic_vdf" => {
                    absorption = self.closure_input(scope, vdf, "absorption", absorption);
                    scattering = self.closure_input(scope, vdf, "scattering", scattering);
                    anisotropy = self.closure_input(scope, vdf, "anisotropy", anisotropy);
                }
                category => return Err(format!("{} ({category})", name_of(vdf))),
            }
        }
        let emission = match self.closure_source(scope, shader, "edf") {
            Some(edf) => self.fold_edf(scope, edf)?,
            None => Value::Color([0.0; 3]),
        };
        let (Some(a), Some(s), Some(e), Value::Float(g)) = (
            constant3(&absorption),
            constant3(&scattering),
            constant3(&emission),
            &anisotropy,
        ) else {
            return Err(format!(
                "{name} (volume): a medium that varies (Kiln reads volumes of constants from MaterialX)"
            ));
        };
        let (color, density, absorption_color, emission_color, strength) =
            principled_volume(a, s, e);
        let node = kiln_plugin_api::kmat::Node::new("principled_volume")
            .input("color", Value::Color(color))
            .input("density", Value::Float(density))
            .input("anisotropy", Value::Float(g.clamp(-1.0, 1.0)))
            .input("absorption_color", Value::Color(absorption_color))
            .input("emission_color", Value::Color(emission_color))
            .input("emission_strength", Value::Float(strength));
        let node = position(shader, node);
        Ok(Value::link(&scope.graph.add(name, node), "volume"))
    }
}
