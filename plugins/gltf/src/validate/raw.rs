//! Checks that need the JSON as written: arrays the schema requires to be non-empty,
//! extension objects (declared, and in a place their extension defines), the lists of
//! extensions, `asset.minVersion`, properties the JSON model fills in with a default,
//! the ranges of material and light values, and the texture coordinates and tangents
//! that materials ask of the primitives using them.

use std::f64::consts::FRAC_PI_2;

use gltf::json;
use gltf::json::Value;
use gltf::json::mesh::Semantic;
use gltf::json::validation::Checked;

use super::{Report, list, named};

pub fn check(raw: &Value, root: &json::Root, report: &mut Report) {
    empty_arrays(raw, report);
    extension_lists(raw, report);
    extension_objects(raw, report);
    min_version(raw, report);
    missing_properties(raw, report);
    materials(raw, root, report);
    lights(raw, report);
}

/// A number, if `value` is one.
fn number(value: Option<&Value>) -> Option<f64> {
    value.and_then(Value::as_f64)
}

fn array<'a>(value: &'a Value, key: &str) -> &'a [Value] {
    value
        .get(key)
        .and_then(Value::as_array)
        .map_or(&[], Vec::as_slice)
}

/// EMPTY_ENTITY: arrays the schema gives `minItems: 1`, present but empty.
fn empty_arrays(raw: &Value, report: &mut Report) {
    let mut empty = Vec::new();
    let mut check = |value: &Value, key: &str, path: &dyn Fn() -> String| {
        if value
            .get(key)
            .and_then(Value::as_array)
            .is_some_and(Vec::is_empty)
        {
            empty.push(path());
        }
    };
    const TOP: [&str; 15] = [
        "accessors",
        "animations",
        "buffers",
        "bufferViews",
        "cameras",
        "images",
        "materials",
        "meshes",
        "nodes",
        "samplers",
        "scenes",
        "skins",
        "textures",
        "extensionsUsed",
        "extensionsRequired",
    ];
    for key in TOP {
        check(raw, key, &|| key.to_owned());
    }
    for (i, node) in array(raw, "nodes").iter().enumerate() {
        for key in ["children", "weights"] {
            check(node, key, &|| format!("nodes[{i}].{key}"));
        }
    }
    for (i, scene) in array(raw, "scenes").iter().enumerate() {
        check(scene, "nodes", &|| format!("scenes[{i}].nodes"));
    }
    for (i, skin) in array(raw, "skins").iter().enumerate() {
        check(skin, "joints", &|| format!("skins[{i}].joints"));
    }
    for (i, mesh) in array(raw, "meshes").iter().enumerate() {
        for key in ["primitives", "weights"] {
            check(mesh, key, &|| format!("meshes[{i}].{key}"));
        }
        for (j, primitive) in array(mesh, "primitives").iter().enumerate() {
            check(primitive, "targets", &|| {
                format!("meshes[{i}].primitives[{j}].targets")
            });
        }
    }
    for (i, animation) in array(raw, "animations").iter().enumerate() {
        for key in ["channels", "samplers"] {
            check(animation, key, &|| format!("animations[{i}].{key}"));
        }
    }
    if let Some(extensions) = raw.get("extensions") {
        if let Some(lights) = extensions.get("KHR_lights_punctual") {
            check(lights, "lights", &|| {
                "extensions.KHR_lights_punctual.lights".to_owned()
            });
        }
        if let Some(variants) = extensions.get("KHR_materials_variants") {
            check(variants, "variants", &|| {
                "extensions.KHR_materials_variants.variants".to_owned()
            });
        }
    }
    if !empty.is_empty() {
        report.add(format!(
            "empty arrays where glTF requires at least one entry (leave the property out instead): {}",
            list(&empty, 6)
        ));
    }
}

fn strings(raw: &Value, key: &str) -> Vec<String> {
    array(raw, key)
        .iter()
        .filter_map(Value::as_str)
        .map(str::to_owned)
        .collect()
}

/// DUPLICATE_ELEMENTS in the extension lists, required extensions that are not used
/// (UNUSED_EXTENSION_REQUIRED), and extensions that must be required but are only used
/// (NON_REQUIRED_EXTENSION: KHR_mesh_quantization changes what attributes mean, so a
/// reader without it would misread the file).
fn extension_lists(raw: &Value, report: &mut Report) {
    let used = strings(raw, "extensionsUsed");
    let required = strings(raw, "extensionsRequired");
    for (key, names) in [("extensionsUsed", &used), ("extensionsRequired", &required)] {
        let mut duplicates: Vec<&str> = Vec::new();
        for (i, name) in names.iter().enumerate() {
            if names[..i].contains(name) && !duplicates.contains(&name.as_str()) {
                duplicates.push(name);
            }
        }
        if !duplicates.is_empty() {
            report.add(format!(
                "{key} lists {} more than once",
                list(&duplicates, 4)
            ));
        }
    }
    let unused: Vec<&String> = required.iter().filter(|r| !used.contains(r)).collect();
    if !unused.is_empty() {
        report.add(format!(
            "extensionsRequired lists {}, missing from extensionsUsed",
            list(&unused, 4)
        ));
    }
    for name in ["KHR_mesh_quantization"] {
        if used.iter().any(|u| u == name) && !required.iter().any(|r| r == name) {
            report.add(format!(
                "{name} is in extensionsUsed but not in extensionsRequired; the extension must be required"
            ));
        }
    }
}

/// Where an extension object sits.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Place {
    Root,
    Node,
    Material,
    Texture,
    TextureInfo,
    Primitive,
    Buffer,
    BufferView,
    ChannelTarget,
    Other,
}

/// The place an object at `path` (keys and indices from the root) is.
fn place(path: &[Segment]) -> Place {
    use Segment::{Index as I, Key as K};
    match path {
        [] => Place::Root,
        [K("nodes"), I(_)] => Place::Node,
        [K("materials"), I(_)] => Place::Material,
        [K("textures"), I(_)] => Place::Texture,
        [K("meshes"), I(_), K("primitives"), I(_)] => Place::Primitive,
        [K("buffers"), I(_)] => Place::Buffer,
        [K("bufferViews"), I(_)] => Place::BufferView,
        [K("animations"), I(_), K("channels"), I(_), K("target")] => Place::ChannelTarget,
        [.., K(key)] if key.ends_with("Texture") => Place::TextureInfo,
        _ => Place::Other,
    }
}

/// Where a known extension may appear; None for extensions this table does not know.
fn allowed_places(extension: &str) -> Option<&'static [Place]> {
    Some(match extension {
        "KHR_lights_punctual" => &[Place::Root, Place::Node],
        "KHR_materials_variants" => &[Place::Root, Place::Primitive],
        "KHR_node_visibility" | "EXT_mesh_gpu_instancing" => &[Place::Node],
        "KHR_texture_transform" => &[Place::TextureInfo],
        "KHR_mesh_quantization" => &[],
        "EXT_texture_webp" | "KHR_texture_basisu" | "MSFT_texture_dds" | "EXT_texture_avif" => {
            &[Place::Texture]
        }
        "KHR_draco_mesh_compression" => &[Place::Primitive],
        "EXT_meshopt_compression" => &[Place::Buffer, Place::BufferView],
        "KHR_animation_pointer" => &[Place::ChannelTarget],
        "KHR_materials_clearcoat"
        | "KHR_materials_emissive_strength"
        | "KHR_materials_ior"
        | "KHR_materials_sheen"
        | "KHR_materials_specular"
        | "KHR_materials_transmission"
        | "KHR_materials_unlit"
        | "KHR_materials_volume"
        | "KHR_materials_pbrSpecularGlossiness"
        | "KHR_materials_anisotropy"
        | "KHR_materials_dispersion"
        | "KHR_materials_iridescence"
        | "KHR_materials_diffuse_transmission" => &[Place::Material],
        _ => return None,
    })
}

#[derive(Clone, Copy)]
enum Segment<'a> {
    Key(&'a str),
    Index(usize),
}

fn path_text(path: &[Segment]) -> String {
    let mut s = String::new();
    for segment in path {
        match segment {
            Segment::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Segment::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    if s.is_empty() {
        "the root".to_owned()
    } else {
        s
    }
}

/// UNDECLARED_EXTENSION and UNEXPECTED_EXTENSION_OBJECT: every `extensions` object
/// outside `extras`, its names against extensionsUsed and against the places their
/// extensions define.
fn extension_objects(raw: &Value, report: &mut Report) {
    let used = strings(raw, "extensionsUsed");
    let mut undeclared = Sightings::default();
    let mut misplaced = Sightings::default();
    let mut path = Vec::new();
    walk(raw, &mut path, &mut |path, name| {
        if !used.iter().any(|u| u == name) {
            undeclared.note(name, path);
        }
        if allowed_places(name).is_some_and(|places| !places.contains(&place(path))) {
            misplaced.note(name, path);
        }
    });
    for (name, places, count) in undeclared.0 {
        report.add(format!(
            "the extension {name} is used ({}) but not declared in extensionsUsed",
            Sightings::text(&places, count)
        ));
    }
    for (name, places, count) in misplaced.0 {
        report.add(format!(
            "the extension {name} appears where it does not apply ({}); ignored there",
            Sightings::text(&places, count)
        ));
    }
}

/// Where each extension name was seen: the first few places and how many in all.
#[derive(Default)]
struct Sightings(Vec<(String, Vec<String>, usize)>);

impl Sightings {
    const PLACES_KEPT: usize = 3;
    /// Distinct names followed; further names are not reported.
    const NAMES_KEPT: usize = 32;

    fn note(&mut self, name: &str, path: &[Segment]) {
        let i = match self.0.iter().position(|(n, _, _)| n == name) {
            Some(i) => i,
            None if self.0.len() < Self::NAMES_KEPT => {
                self.0.push((name.to_owned(), Vec::new(), 0));
                self.0.len() - 1
            }
            None => return,
        };
        let (_, places, count) = &mut self.0[i];
        *count += 1;
        if places.len() < Self::PLACES_KEPT {
            places.push(path_text(path));
        }
    }

    fn text(places: &[String], count: usize) -> String {
        let mut s = places.join(", ");
        if count > places.len() {
            s.push_str(&format!(" and {} more", count - places.len()));
        }
        s
    }
}

/// Calls `found(path of the object, extension name)` for every extension object.
fn walk<'a>(
    value: &'a Value,
    path: &mut Vec<Segment<'a>>,
    found: &mut dyn FnMut(&[Segment<'a>], &str),
) {
    match value {
        Value::Object(fields) => {
            if let Some(Value::Object(extensions)) = fields.get("extensions") {
                for name in extensions.keys() {
                    found(path, name);
                }
            }
            for (key, child) in fields {
                if key == "extras" || !(child.is_object() || child.is_array()) {
                    continue;
                }
                if key == "extensions" {
                    // Extension objects may hold extension objects of their own (a
                    // texture transform in a clearcoat texture).
                    if let Value::Object(extensions) = child {
                        for (name, object) in extensions {
                            path.push(Segment::Key("extensions"));
                            path.push(Segment::Key(name));
                            walk_children(object, path, found);
                            path.pop();
                            path.pop();
                        }
                    }
                    continue;
                }
                path.push(Segment::Key(key));
                walk(child, path, found);
                path.pop();
            }
        }
        Value::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                if item.is_object() || item.is_array() {
                    path.push(Segment::Index(i));
                    walk(item, path, found);
                    path.pop();
                }
            }
        }
        _ => {}
    }
}

/// [`walk`] into the members of an extension object (which is not itself a place).
fn walk_children<'a>(
    value: &'a Value,
    path: &mut Vec<Segment<'a>>,
    found: &mut dyn FnMut(&[Segment<'a>], &str),
) {
    if let Value::Object(fields) = value {
        for (key, child) in fields {
            if key != "extras" && (child.is_object() || child.is_array()) {
                path.push(Segment::Key(key));
                walk(child, path, found);
                path.pop();
            }
        }
    }
}

fn version(text: &str) -> Option<(u64, u64)> {
    let (major, minor) = text.split_once('.')?;
    Some((major.parse().ok()?, minor.parse().ok()?))
}

/// ASSET_MIN_VERSION_GREATER_THAN_VERSION.
fn min_version(raw: &Value, report: &mut Report) {
    let asset = raw.get("asset");
    let get = |key| asset.and_then(|a| a.get(key)).and_then(Value::as_str);
    if let (Some(v), Some(min)) = (get("version"), get("minVersion")) {
        if let (Some(pv), Some(pm)) = (version(v), version(min)) {
            if pm > pv {
                report.add(format!(
                    "asset.minVersion \"{min}\" is greater than asset.version \"{v}\""
                ));
            }
        }
    }
}

/// UNDEFINED_PROPERTY for required properties the JSON model defaults.
fn missing_properties(raw: &Value, report: &mut Report) {
    let missing: Vec<usize> = array(raw, "buffers")
        .iter()
        .enumerate()
        .filter(|(_, b)| b.is_object() && b.get("byteLength").is_none())
        .map(|(i, _)| i)
        .collect();
    if !missing.is_empty() {
        report.add(format!(
            "buffer(s) {} have no byteLength, which glTF requires",
            list(&missing, 6)
        ));
    }
}

/// A value's allowed range.
#[derive(Clone, Copy)]
enum Range {
    /// [0, 1]
    Unit,
    /// ≥ 0
    NonNegative,
    /// > 0
    Positive,
    /// ≥ 1
    AtLeastOne,
    /// 0, or ≥ 1 (KHR_materials_ior)
    Ior,
}

impl Range {
    fn contains(self, v: f64) -> bool {
        match self {
            Range::Unit => (0.0..=1.0).contains(&v),
            Range::NonNegative => v >= 0.0,
            Range::Positive => v > 0.0,
            Range::AtLeastOne => v >= 1.0,
            Range::Ior => v == 0.0 || v >= 1.0,
        }
    }

    fn text(self) -> &'static str {
        match self {
            Range::Unit => "in [0, 1]",
            Range::NonNegative => "≥ 0",
            Range::Positive => "> 0",
            Range::AtLeastOne => "≥ 1",
            Range::Ior => "0 or ≥ 1",
        }
    }
}

/// Material values and their ranges, by path inside the material (numbers or arrays of
/// numbers).
const MATERIAL_RANGES: &[(&[&str], Range)] = &[
    (&["pbrMetallicRoughness", "baseColorFactor"], Range::Unit),
    (&["pbrMetallicRoughness", "metallicFactor"], Range::Unit),
    (&["pbrMetallicRoughness", "roughnessFactor"], Range::Unit),
    (&["emissiveFactor"], Range::Unit),
    (&["alphaCutoff"], Range::NonNegative),
    (&["occlusionTexture", "strength"], Range::Unit),
    (
        &[
            "extensions",
            "KHR_materials_emissive_strength",
            "emissiveStrength",
        ],
        Range::NonNegative,
    ),
    (&["extensions", "KHR_materials_ior", "ior"], Range::Ior),
    (
        &[
            "extensions",
            "KHR_materials_transmission",
            "transmissionFactor",
        ],
        Range::Unit,
    ),
    (
        &[
            "extensions",
            "KHR_materials_diffuse_transmission",
            "diffuseTransmissionFactor",
        ],
        Range::Unit,
    ),
    (
        &[
            "extensions",
            "KHR_materials_diffuse_transmission",
            "diffuseTransmissionColorFactor",
        ],
        Range::Unit,
    ),
    (
        &["extensions", "KHR_materials_volume", "thicknessFactor"],
        Range::NonNegative,
    ),
    (
        &["extensions", "KHR_materials_volume", "attenuationDistance"],
        Range::Positive,
    ),
    (
        &["extensions", "KHR_materials_volume", "attenuationColor"],
        Range::Unit,
    ),
    (
        &["extensions", "KHR_materials_specular", "specularFactor"],
        Range::Unit,
    ),
    (
        &[
            "extensions",
            "KHR_materials_specular",
            "specularColorFactor",
        ],
        Range::NonNegative,
    ),
    (
        &["extensions", "KHR_materials_clearcoat", "clearcoatFactor"],
        Range::Unit,
    ),
    (
        &[
            "extensions",
            "KHR_materials_clearcoat",
            "clearcoatRoughnessFactor",
        ],
        Range::Unit,
    ),
    (
        &["extensions", "KHR_materials_sheen", "sheenColorFactor"],
        Range::Unit,
    ),
    (
        &["extensions", "KHR_materials_sheen", "sheenRoughnessFactor"],
        Range::Unit,
    ),
    (
        &[
            "extensions",
            "KHR_materials_pbrSpecularGlossiness",
            "diffuseFactor",
        ],
        Range::Unit,
    ),
    (
        &[
            "extensions",
            "KHR_materials_pbrSpecularGlossiness",
            "specularFactor",
        ],
        Range::Unit,
    ),
    (
        &[
            "extensions",
            "KHR_materials_pbrSpecularGlossiness",
            "glossinessFactor",
        ],
        Range::Unit,
    ),
    (
        &[
            "extensions",
            "KHR_materials_iridescence",
            "iridescenceFactor",
        ],
        Range::Unit,
    ),
    (
        &["extensions", "KHR_materials_iridescence", "iridescenceIor"],
        Range::AtLeastOne,
    ),
    (
        &[
            "extensions",
            "KHR_materials_iridescence",
            "iridescenceThicknessMinimum",
        ],
        Range::NonNegative,
    ),
    (
        &[
            "extensions",
            "KHR_materials_iridescence",
            "iridescenceThicknessMaximum",
        ],
        Range::NonNegative,
    ),
    (
        &[
            "extensions",
            "KHR_materials_anisotropy",
            "anisotropyStrength",
        ],
        Range::Unit,
    ),
    (
        &["extensions", "KHR_materials_dispersion", "dispersion"],
        Range::NonNegative,
    ),
];

/// The numbers at `path` under `value` (one, or each of an array) outside `range`, as
/// "path = v" texts.
fn out_of_range(value: &Value, path: &[&str], range: Range, out: &mut Vec<String>) {
    let Some(v) = path.iter().try_fold(value, |v, key| v.get(key)) else {
        return;
    };
    let name = path
        .iter()
        .filter(|k| **k != "extensions")
        .copied()
        .collect::<Vec<_>>()
        .join(".");
    match v {
        Value::Array(items) => {
            let bad: Vec<String> = items
                .iter()
                .filter_map(Value::as_f64)
                .filter(|&x| !range.contains(x))
                .map(|x| x.to_string())
                .collect();
            if !bad.is_empty() {
                out.push(format!(
                    "{name} has {} (each must be {})",
                    bad.join(", "),
                    range.text()
                ));
            }
        }
        v => {
            if let Some(x) = v.as_f64().filter(|&x| !range.contains(x)) {
                out.push(format!("{name} = {x} (must be {})", range.text()));
            }
        }
    }
}

/// The texture references (texture infos) of a material: where, and which texture
/// coordinate set each samples (KHR_texture_transform's `texCoord` overrides).
fn texture_infos<'a>(value: &'a Value, key: &'a str, out: &mut Vec<(&'a str, u64)>) {
    match value {
        Value::Object(fields) => {
            if key.ends_with("Texture") && fields.contains_key("index") {
                let set = value
                    .pointer("/extensions/KHR_texture_transform/texCoord")
                    .or_else(|| fields.get("texCoord"))
                    .and_then(Value::as_u64)
                    .unwrap_or(0);
                out.push((key, set));
            }
            for (k, child) in fields {
                if k != "extras" {
                    texture_infos(child, k, out);
                }
            }
        }
        Value::Array(items) => {
            for item in items {
                texture_infos(item, key, out);
            }
        }
        _ => {}
    }
}

/// VALUE_NOT_IN_RANGE for material values; MESH_PRIMITIVE_TOO_FEW_TEXCOORDS and
/// MESH_PRIMITIVE_NO_TANGENT_SPACE for the primitives that use each material.
fn materials(raw: &Value, root: &json::Root, report: &mut Report) {
    let raw_materials = array(raw, "materials");
    for (i, material) in raw_materials.iter().enumerate() {
        let mut bad = Vec::new();
        for (path, range) in MATERIAL_RANGES {
            out_of_range(material, path, *range, &mut bad);
        }
        if !bad.is_empty() {
            let name = material.get("name").and_then(Value::as_str);
            report.add(format!(
                "{}: values out of range: {}; Kiln clamps them or uses the default",
                named("material", i, name),
                bad.join("; ")
            ));
        }
    }
    // Per material: each texture coordinate set it samples, with the (first few)
    // textures that sample it.
    let mut infos: Vec<Vec<(u64, Vec<&str>)>> = Vec::with_capacity(raw_materials.len());
    for material in raw_materials {
        let mut found = Vec::new();
        texture_infos(material, "", &mut found);
        let mut sets: Vec<(u64, Vec<&str>)> = Vec::new();
        for (key, set) in found {
            match sets.iter_mut().find(|(s, _)| *s == set) {
                Some((_, keys)) if keys.len() < 4 => keys.push(key),
                Some(_) => {}
                None => sets.push((set, vec![key])),
            }
        }
        infos.push(sets);
    }
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let Some(material) = primitive.material.map(|i| i.value()) else {
                continue;
            };
            let Some(found) = infos.get(material) else {
                continue;
            };
            let has = |s: Semantic| primitive.attributes.contains_key(&Checked::Valid(s));
            let where_ = || {
                format!(
                    "{} primitive {p} (material {material})",
                    named("mesh", m, mesh.name.as_deref())
                )
            };
            let missing: Vec<String> = found
                .iter()
                .filter(|(set, _)| {
                    let set = u32::try_from(*set).unwrap_or(u32::MAX);
                    !has(Semantic::TexCoords(set))
                })
                .map(|(set, keys)| format!("TEXCOORD_{set} (for {})", keys.join(", ")))
                .collect();
            if !missing.is_empty() {
                report.add(format!(
                    "{}: the material samples texture coordinates the primitive lacks: {}",
                    where_(),
                    list(&missing, 4)
                ));
            }
            let raw_material = &raw_materials[material];
            let needs_tangents = raw_material
                .pointer("/extensions/KHR_materials_clearcoat/clearcoatNormalTexture")
                .is_some()
                || raw_material
                    .pointer("/extensions/KHR_materials_anisotropy")
                    .is_some();
            if needs_tangents
                && raw_material.get("normalTexture").is_none()
                && !has(Semantic::Tangents)
            {
                report.add(format!(
                    "{}: the material needs tangents, and the primitive has no TANGENT attribute and the material no normal map to derive them from",
                    where_()
                ));
            }
        }
    }
}

/// KHR_lights_punctual values out of their ranges, and spot cones whose outer angle is
/// not greater than the inner (KHR_LIGHTS_PUNCTUAL_LIGHT_SPOT_ANGLES).
fn lights(raw: &Value, report: &mut Report) {
    let Some(lights) = raw
        .pointer("/extensions/KHR_lights_punctual/lights")
        .and_then(Value::as_array)
    else {
        return;
    };
    for (i, light) in lights.iter().enumerate() {
        let mut bad = Vec::new();
        out_of_range(light, &["color"], Range::Unit, &mut bad);
        out_of_range(light, &["intensity"], Range::NonNegative, &mut bad);
        out_of_range(light, &["range"], Range::Positive, &mut bad);
        if let Some(spot) = light.get("spot") {
            let inner = number(spot.get("innerConeAngle"));
            let outer = number(spot.get("outerConeAngle"));
            if let Some(a) = inner.filter(|a| !(0.0..FRAC_PI_2).contains(a)) {
                bad.push(format!("spot.innerConeAngle = {a} (must be in [0, π/2))"));
            }
            if let Some(a) = outer.filter(|&a| !(a > 0.0 && a <= FRAC_PI_2)) {
                bad.push(format!("spot.outerConeAngle = {a} (must be in (0, π/2])"));
            }
            let (inner, outer) = (
                inner.unwrap_or(0.0),
                outer.unwrap_or(std::f64::consts::FRAC_PI_4),
            );
            if outer <= inner {
                bad.push(format!(
                    "spot.outerConeAngle {outer} is not greater than innerConeAngle {inner}"
                ));
            }
        }
        if !bad.is_empty() {
            let name = light.get("name").and_then(Value::as_str);
            report.add(format!(
                "KHR_lights_punctual {}: {}",
                named("light", i, name),
                bad.join("; ")
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn places_are_told_by_path() {
        use Segment::{Index as I, Key as K};
        assert_eq!(place(&[]), Place::Root);
        assert_eq!(place(&[K("materials"), I(2)]), Place::Material);
        assert_eq!(
            place(&[K("materials"), I(0), K("pbrMetallicRoughness")]),
            Place::Other
        );
        assert_eq!(
            place(&[
                K("materials"),
                I(0),
                K("pbrMetallicRoughness"),
                K("baseColorTexture")
            ]),
            Place::TextureInfo
        );
        assert_eq!(
            path_text(&[K("materials"), I(0), K("normalTexture")]),
            "materials[0].normalTexture"
        );
    }
}
