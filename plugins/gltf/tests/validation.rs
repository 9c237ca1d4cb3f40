//! The importer's checks of the glTF rules parsing does not enforce (`validate`), on small
//! hand-written files: each broken property gives one specific warning, a file that
//! follows the rules gives none, and the value checks stop early on huge accessors.

mod common;

use std::path::{Path, PathBuf};

use base64::Engine;

/// A 1×1 PNG.
const PNG_1X1: &str = "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8BQDwAEhQGAhKmMIQAAAABJRU5ErkJggg==";

fn f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn data_uri(bytes: &[u8]) -> String {
    format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    )
}

fn write(dir: &Path, text: &str) -> PathBuf {
    let path = dir.join("test.gltf");
    std::fs::write(&path, text).expect("write test file");
    path
}

/// Imports `text` as a .gltf; the warnings (the import must succeed).
fn warnings(text: &str) -> Vec<String> {
    let dir = common::scratch_dir();
    let (result, recorded) = common::import(&write(dir.path(), text));
    result.expect("the file imports");
    assert!(recorded.violations.is_empty(), "{:#?}", recorded.violations);
    recorded.warnings
}

/// The one warning containing every string of `needles`.
fn find<'a>(warnings: &'a [String], needles: &[&str]) -> &'a str {
    let found: Vec<&String> = warnings
        .iter()
        .filter(|w| needles.iter().all(|n| w.contains(n)))
        .collect();
    assert_eq!(found.len(), 1, "{needles:?} in {warnings:#?}");
    found[0]
}

/// A triangle with unit normals, indices and a textured material: valid glTF.
/// `positions`, `normals`, `indices` and `extra` (more top-level properties) vary it.
fn triangle(
    positions: &[f32; 9],
    min_max: &str,
    normals: &[f32; 9],
    indices: [u16; 3],
    extra: &str,
) -> String {
    let mut data = f32s(positions);
    data.extend(f32s(normals));
    data.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    data.extend([0, 0]);
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
  "nodes":[{{"mesh":0,"rotation":[0,0,0.70710678,0.70710678]}}],
  "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1}},"indices":2}}]}}],
  "accessors":[
    {{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"{min_max}}},
    {{"bufferView":0,"byteOffset":36,"componentType":5126,"count":3,"type":"VEC3"}},
    {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}],
  "bufferViews":[{{"buffer":0,"byteLength":72,"byteStride":12,"target":34962}},
                 {{"buffer":0,"byteOffset":72,"byteLength":6,"target":34963}}],
  "buffers":[{{"byteLength":80,"uri":"{}"}}]{extra}}}"#,
        data_uri(&data)
    )
}

const POSITIONS: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
const BOUNDS: &str = r#","min":[0,0,0],"max":[1,1,0]"#;
const NORMALS: [f32; 9] = [0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0];

#[test]
fn a_valid_file_gives_no_warnings() {
    let w = warnings(&triangle(&POSITIONS, BOUNDS, &NORMALS, [0, 1, 2], ""));
    assert!(w.is_empty(), "{w:#?}");
}

#[test]
fn position_values_outside_min_max_and_nan_are_reported_once_per_accessor() {
    let mut positions = POSITIONS;
    positions[4] = 5.0;
    positions[8] = f32::NAN;
    let w = warnings(&triangle(&positions, BOUNDS, &NORMALS, [0, 1, 2], ""));
    let warning = find(&w, &["accessor 0 (POSITION of mesh 0)"]);
    assert!(
        warning.contains("1 element(s) above its declared max"),
        "{warning}"
    );
    assert!(
        warning.contains("NaN or infinity (the first at index 2)"),
        "{warning}"
    );
    // The max does not describe the data either (5 > 1).
    assert!(
        warning.contains("declared max [1, 1, 0] is not the data's"),
        "{warning}"
    );
}

#[test]
fn loose_bounds_non_unit_normals_and_bad_indices_are_reported() {
    let mut normals = NORMALS;
    normals[3] = 1.0; // (1, 0, 1): length √2
    let loose = r#","min":[-1,0,0],"max":[1,1,0]"#;
    let w = warnings(&triangle(&POSITIONS, loose, &normals, [0, 1, 7], ""));
    let position = find(&w, &["accessor 0 (POSITION of mesh 0)"]);
    assert!(
        position.contains("declared min [-1, 0, 0] is not the data's, [0, 0, 0]"),
        "{position}"
    );
    let normal = find(&w, &["accessor 1 (NORMAL of mesh 0)"]);
    assert!(
        normal.contains("1 vector(s) are not of unit length (element 1: 1.4142)"),
        "{normal}"
    );
    let indices = find(&w, &["accessor 2 (indices of mesh 0)"]);
    assert!(
        indices.contains("past the primitive's 3 vertices (element 2: 7)"),
        "{indices}"
    );
    let w = warnings(&triangle(&POSITIONS, BOUNDS, &NORMALS, [0, 1, 65535], ""));
    let restart = find(&w, &["accessor 2 (indices of mesh 0)"]);
    assert!(
        restart.contains("primitive-restart value 65535"),
        "{restart}"
    );
}

#[test]
fn position_without_bounds_is_reported_for_morph_targets() {
    let text = triangle(&POSITIONS, BOUNDS, &NORMALS, [0, 1, 2], "").replace(
        r#""indices":2}"#,
        r#""indices":2,"targets":[{"POSITION":1}]}"#,
    );
    let w = warnings(&text);
    find(
        &w,
        &[
            "mesh 0 primitive 0",
            "morph target 0's POSITION (accessor 1) has no min and max",
        ],
    );
}

#[test]
fn node_transforms_and_hierarchy_are_checked() {
    let extra =
        r#","cameras":[{"type":"perspective","perspective":{"yfov":0.8,"znear":10,"zfar":1}}]"#;
    let text = triangle(&POSITIONS, BOUNDS, &NORMALS, [0, 1, 2], extra).replace(
        r#""nodes":[{"mesh":0,"rotation":[0,0,0.70710678,0.70710678]}]"#,
        r#""nodes":[{"mesh":0,"rotation":[0,0,1,1],"children":[1]},
                    {"name":"both","matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1],"scale":[2,2,2],"children":[2]},
                    {"matrix":[1,0,0,0,0.5,1,0,0,0,0,1,0,0,0,0,1],"children":[1]}]"#,
    );
    let w = warnings(&text);
    find(&w, &["node 0:", "not a unit quaternion"]);
    find(
        &w,
        &[
            "node 1 (\"both\")",
            "both a matrix and translation/rotation/scale",
        ],
    );
    find(&w, &["node 2:", "not a translation · rotation · scale"]);
    find(&w, &["node(s) 1 are children of more than one node"]);
    find(&w, &["cycle (through node(s) 1, 2)"]);
    find(&w, &["camera 0:", "zfar 1 is not greater than znear 10"]);
}

#[test]
fn extension_values_places_and_declarations_are_checked() {
    let extra = r#","extensionsUsed":["KHR_materials_ior","KHR_materials_transmission","KHR_materials_clearcoat","KHR_lights_punctual"],
      "materials":[{"name":"glass","extensions":{
        "KHR_materials_ior":{"ior":-0.5},
        "KHR_materials_transmission":{"transmissionFactor":1.5},
        "KHR_materials_clearcoat":{"clearcoatFactor":2}},
        "pbrMetallicRoughness":{"extensions":{"KHR_materials_ior":{"ior":1.5}}}}],
      "extensions":{"KHR_lights_punctual":{"lights":[{"type":"spot","spot":{"innerConeAngle":0.5,"outerConeAngle":0.4}}]}},
      "samplers":[{"extensions":{"EXT_unheard_of":{}}}]"#;
    let w = warnings(&triangle(&POSITIONS, BOUNDS, &NORMALS, [0, 1, 2], extra));
    let material = find(&w, &["material 0 (\"glass\"): values out of range"]);
    for value in [
        "KHR_materials_ior.ior = -0.5 (must be 0 or ≥ 1)",
        "KHR_materials_transmission.transmissionFactor = 1.5 (must be in [0, 1])",
        "KHR_materials_clearcoat.clearcoatFactor = 2",
    ] {
        assert!(material.contains(value), "{value} not in {material}");
    }
    find(
        &w,
        &[
            "KHR_materials_ior appears where it does not apply",
            "materials[0].pbrMetallicRoughness",
        ],
    );
    find(
        &w,
        &["EXT_unheard_of is used (samplers[0]) but not declared"],
    );
    find(
        &w,
        &[
            "light 0",
            "outerConeAngle 0.4 is not greater than innerConeAngle 0.5",
        ],
    );
}

#[test]
fn image_mime_type_is_checked_against_the_content() {
    let extra = format!(
        r#","images":[{{"uri":"data:image/png;base64,{PNG_1X1}","mimeType":"image/jpeg"}},
                      {{"uri":"data:image/webp;base64,{PNG_1X1}"}},
                      {{"uri":"missing.png"}}]"#
    );
    let w = warnings(&triangle(&POSITIONS, BOUNDS, &NORMALS, [0, 1, 2], &extra));
    find(
        &w,
        &[
            "image 0:",
            "its mimeType declares \"image/jpeg\" but the data is image/png",
        ],
    );
    find(
        &w,
        &[
            "image 1:",
            "its data URI declares \"image/webp\"",
            "EXT_texture_webp",
        ],
    );
    find(&w, &["image 2 (\"missing.png\")", "cannot be read"]);
}

#[test]
fn buffer_view_and_accessor_layout_problems_are_named() {
    // The index view gets a stride; the normals start at an unaligned offset.
    let text = triangle(&POSITIONS, BOUNDS, &NORMALS, [0, 1, 2], "")
        .replace(
            r#""byteOffset":72,"byteLength":6,"target":34963"#,
            r#""byteOffset":72,"byteLength":6,"byteStride":4"#,
        )
        .replace(
            r#""byteOffset":36,"componentType""#,
            r#""byteOffset":34,"componentType""#,
        );
    let w = warnings(&text);
    find(&w, &["buffer view 1:", "byteStride", "it holds indices"]);
    find(
        &w,
        &[
            "accessor 1 (NORMAL of mesh 0)",
            "byteOffset 34 is not a multiple of its component size 4",
        ],
    );
}

#[test]
fn value_checks_stop_at_their_limit_and_say_so() {
    // 2^23 zeros with one sparse NaN, used by nothing: checked up to 2^22 elements.
    let mut data = vec![0u8; 4];
    data.extend(f32s(&[f32::NAN]));
    let text = format!(
        r#"{{"asset":{{"version":"2.0"}},
  "accessors":[{{"componentType":5126,"count":8388608,"type":"SCALAR",
    "sparse":{{"count":1,"indices":{{"bufferView":0,"componentType":5125}},"values":{{"bufferView":1}}}}}}],
  "bufferViews":[{{"buffer":0,"byteLength":4}},{{"buffer":0,"byteOffset":4,"byteLength":4}}],
  "buffers":[{{"byteLength":8,"uri":"{}"}}]}}"#,
        data_uri(&data)
    );
    let w = warnings(&text);
    let warning = find(&w, &["accessor 0:"]);
    assert!(
        warning.contains("NaN or infinity (the first at index 0)"),
        "{warning}"
    );
    assert!(
        warning.contains("checked the first 4194304 of 8388608 elements only"),
        "{warning}"
    );
}
