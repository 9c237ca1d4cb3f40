//! Which glTF extensions this importer understands, and what happens to the others: a
//! required one it does not handle fails the import (the spec forbids loading the file
//! without it); a used one is reported once and ignored.

use gltf::json;

/// Extensions this importer translates.
pub const HANDLED: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "KHR_mesh_quantization",
    "KHR_node_visibility",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_specular",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_unlit",
    "KHR_materials_pbrSpecularGlossiness",
];

/// `Err` naming the first required extension that is not handled; warnings for the
/// used ones that are not.
pub fn check(root: &json::Root, warnings: &mut Vec<String>) -> Result<(), String> {
    let unhandled = |name: &&String| !HANDLED.contains(&name.as_str());
    if let Some(name) = root.extensions_required.iter().find(unhandled) {
        return Err(format!(
            "the file requires the glTF extension {name}, which this importer does not support"
        ));
    }
    let mut reported = Vec::new();
    for name in root.extensions_used.iter().filter(unhandled) {
        if !reported.contains(&name) {
            warnings.push(format!(
                "the glTF extension {name} is not supported; what it adds is ignored"
            ));
            reported.push(name);
        }
    }
    Ok(())
}
