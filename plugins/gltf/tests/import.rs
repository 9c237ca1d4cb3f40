//! The importer on small hand-written files (buffers as data URIs), driven through its
//! C ABI with a mock host that compiles every material graph.

mod common;

use std::path::{Path, PathBuf};

use base64::Engine;
use common::{Recorded, import};

/// A 1×1 PNG.
const PNG_1X1: &str = "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8BQDwAEhQGAhKmMIQAAAABJRU5ErkJggg==";

fn f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn u16s(v: &[u16]) -> Vec<u8> {
    let mut b: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
    while b.len() % 4 != 0 {
        b.push(0);
    }
    b
}

/// Concatenates parts into one buffer; returns it and each part's (offset, length).
fn pack(parts: &[Vec<u8>]) -> (Vec<u8>, Vec<(usize, usize)>) {
    let mut data = Vec::new();
    let mut views = Vec::new();
    for p in parts {
        views.push((data.len(), p.len()));
        data.extend_from_slice(p);
    }
    (data, views)
}

fn data_uri(bytes: &[u8]) -> String {
    format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    )
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write test file");
    path
}

/// The scene of the main test: a hierarchy, indexed, non-indexed, strip and broken
/// primitives, a textured material with KHR_texture_transform, a camera and three lights.
fn scene_gltf() -> String {
    let (data, views) = pack(&[
        f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
        f32s(&[0.0, 0.0, 1.0, 0.25, 0.5, 1.0]),
        u16s(&[0, 1, 2]),
        f32s(&[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0]),
        f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0]),
        u16s(&[0, 1, 5]),
    ]);
    let view = |i: usize| {
        format!(
            r#"{{"buffer":0,"byteOffset":{},"byteLength":{}}}"#,
            views[i].0, views[i].1
        )
    };
    let views_json: Vec<String> = (0..views.len()).map(view).collect();
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_texture_transform", "KHR_lights_punctual", "KHR_materials_emissive_strength", "EXT_unknown_thing"],
  "scene": 0,
  "scenes": [{{"nodes": [0, 4, 5, 6, 7, 8]}}],
  "nodes": [
    {{"name": "parent", "translation": [1, 2, 3], "children": [1, 2]}},
    {{"name": "child", "scale": [2, 2, 2], "mesh": 0}},
    {{"name": "other", "rotation": [0, 0.70710678, 0, 0.70710678], "mesh": 0, "children": [3]}},
    {{"name": "camera", "camera": 0, "translation": [0, 0, 5]}},
    {{"mesh": 1}},
    {{"mesh": 2}},
    {{"translation": [0, 3, 0], "extensions": {{"KHR_lights_punctual": {{"light": 0}}}}}},
    {{"rotation": [-0.70710678, 0, 0, 0.70710678], "extensions": {{"KHR_lights_punctual": {{"light": 1}}}}}},
    {{"extensions": {{"KHR_lights_punctual": {{"light": 2}}}}}}
  ],
  "meshes": [
    {{"name": "pair", "primitives": [
      {{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}, "indices": 2, "material": 0}},
      {{"attributes": {{"POSITION": 3}}}}
    ]}},
    {{"name": "strip", "primitives": [{{"attributes": {{"POSITION": 4}}, "mode": 5}}]}},
    {{"name": "broken", "primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 5}}]}}
  ],
  "materials": [{{
    "name": "textured",
    "pbrMetallicRoughness": {{
      "baseColorFactor": [1, 0.5, 0.5, 1],
      "baseColorTexture": {{"index": 0, "extensions": {{"KHR_texture_transform": {{"offset": [0.5, 0], "scale": [2, 2]}}}}}},
      "metallicFactor": 0, "roughnessFactor": 0.25
    }},
    "alphaMode": "MASK", "alphaCutoff": 0.3,
    "emissiveFactor": [1, 1, 0],
    "extensions": {{"KHR_materials_emissive_strength": {{"emissiveStrength": 5}}}}
  }}],
  "textures": [{{"source": 0, "sampler": 0}}],
  "samplers": [{{"wrapS": 33648, "wrapT": 33648, "magFilter": 9728}}],
  "images": [{{"uri": "data:image/png;base64,{PNG_1X1}"}}],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.8, "znear": 0.1}}}}],
  "extensions": {{"KHR_lights_punctual": {{"lights": [
    {{"type": "point", "color": [1, 0.5, 0], "intensity": 683}},
    {{"type": "spot", "intensity": 1366, "spot": {{"innerConeAngle": 0.2, "outerConeAngle": 0.4}}}},
    {{"type": "directional", "intensity": 6.83}}
  ]}}}},
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}},
    {{"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"}},
    {{"bufferView": 3, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,0,1]}},
    {{"bufferView": 4, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}},
    {{"bufferView": 5, "componentType": 5123, "count": 3, "type": "SCALAR"}}
  ],
  "bufferViews": [{}],
  "buffers": [{{"byteLength": {}, "uri": "{}"}}]
}}"#,
        views_json.join(", "),
        data.len(),
        data_uri(&data)
    )
}

fn import_scene() -> Recorded {
    let dir = common::scratch_dir();
    let path = write(dir.path(), "scene.gltf", &scene_gltf());
    let (result, recorded) = import(&path);
    result.expect("the scene imports");
    assert!(recorded.violations.is_empty(), "{:#?}", recorded.violations);
    recorded
}

fn close(a: &[f32], b: &[f32], tolerance: f32) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tolerance)
}

#[test]
fn each_primitive_is_uploaded_once_and_instanced_per_node() {
    let r = import_scene();
    let names: Vec<&str> = r.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["pair #0", "pair #1", "strip"]);
    let uses = |mesh: u32| r.instances.iter().filter(|i| i.0 == mesh).count();
    assert_eq!((uses(0), uses(1), uses(2)), (2, 2, 1));
}

#[test]
fn hierarchy_transforms_compose_parent_then_child() {
    let r = import_scene();
    let child = r.instances[0].2;
    let expected = [
        2.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 1.0, 2.0, 3.0, 1.0,
    ];
    assert!(close(&child, &expected, 1e-6), "{child:?}");
    // "other": 90° about y then (1, 2, 3): +x goes to −z.
    let other = r.instances[2].2;
    let expected = [
        0.0, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 1.0,
    ];
    assert!(close(&other, &expected, 1e-6), "{other:?}");
}

#[test]
fn non_indexed_primitives_get_sequential_indices_and_strips_unroll() {
    let r = import_scene();
    assert_eq!(r.meshes[1].indices, [0, 1, 2]);
    assert_eq!(r.meshes[2].indices, [0, 1, 2, 1, 3, 2]);
}

#[test]
fn uvs_are_flipped_to_v_up() {
    let r = import_scene();
    let uvs = r.meshes[0].uvs.as_ref().expect("TEXCOORD_0 passed");
    assert!(
        close(uvs.as_flattened(), &[0.0, 1.0, 1.0, 0.75, 0.5, 0.0], 1e-6),
        "{uvs:?}"
    );
    assert!(r.meshes[1].uvs.is_none());
    assert!(
        r.meshes[0].normals.is_none(),
        "missing normals stay missing (flat shading)"
    );
}

#[test]
fn out_of_range_indices_skip_the_primitive_with_a_warning() {
    let r = import_scene();
    assert!(
        r.warnings
            .iter()
            .any(|w| w.contains("broken") && w.contains("index 5 is out of range")),
        "{:#?}",
        r.warnings
    );
}

#[test]
fn texture_transform_becomes_a_mapping_node_for_flipped_uvs() {
    let r = import_scene();
    let material = r.instances[0].1;
    let kmat = r.material(material);
    // offset (0.5, 0), scale (2, 2): location (ox + sin·sy, 1 − cos·sy − oy) = (0.5, −1).
    assert!(kmat.contains(r#""location": (0.5, -1.0, 0.0)"#), "{kmat}");
    assert!(kmat.contains(r#""scale": (2.0, 2.0, 1.0)"#), "{kmat}");
    assert!(kmat.contains(r#""file": "image:0""#), "{kmat}");
    assert!(kmat.contains(r#""extension": "mirror""#), "{kmat}");
    assert!(kmat.contains(r#""interpolation": "closest""#), "{kmat}");
    assert!(kmat.contains(r#""color_space": "srgb""#), "{kmat}");
    assert_eq!(r.images.len(), 1);
    assert!(r.images[0].1.starts_with(b"\x89PNG"));
}

#[test]
fn mask_alpha_emission_and_factors_reach_the_principled_node() {
    let r = import_scene();
    let kmat = r.material(r.instances[0].1);
    assert!(kmat.contains(r#""operation": "less_than""#), "{kmat}");
    assert!(kmat.contains(r#""b": 0.3"#), "{kmat}");
    assert!(
        kmat.contains(r#""emission_color": (1.0, 1.0, 0.0)"#),
        "{kmat}"
    );
    assert!(kmat.contains(r#""emission_strength": 5.0"#), "{kmat}");
    assert!(kmat.contains(r#""roughness": 0.25"#), "{kmat}");
    assert!(kmat.contains(r#""metallic": 0.0"#), "{kmat}");
    // The untextured primitive has no material: the host's default.
    assert_eq!(r.instances[1].1, u32::MAX);
}

#[test]
fn camera_is_placed_by_its_node_with_yfov_in_degrees() {
    let r = import_scene();
    assert_eq!(r.cameras.len(), 1);
    let (m, fov) = r.cameras[0];
    assert!((fov - 0.8f32.to_degrees()).abs() < 1e-4, "{fov}");
    // (0, 0, 5) turned 90° about y is (5, 0, 0), then moved by (1, 2, 3).
    assert!(close(&m[12..15], &[6.0, 2.0, 3.0], 1e-5), "{m:?}");
}

#[test]
fn lights_convert_photometric_units_and_shine_down_minus_z() {
    let r = import_scene();
    assert_eq!(r.lights.len(), 3);
    let point = &r.lights[0];
    assert_eq!(point.kind, kiln_plugin_api::LIGHT_POINT);
    assert!(close(&point.position, &[0.0, 3.0, 0.0], 1e-6));
    assert!(
        close(&point.intensity, &[1.0, 0.5, 0.0], 1e-6),
        "683 cd → 1 W/sr"
    );
    let spot = &r.lights[1];
    assert_eq!(spot.kind, kiln_plugin_api::LIGHT_SPOT);
    assert!(
        close(&spot.direction, &[0.0, -1.0, 0.0], 1e-6),
        "{:?}",
        spot.direction
    );
    assert!(close(&spot.intensity, &[2.0; 3], 1e-6));
    assert!((spot.cone_angle_degrees - 0.4f32.to_degrees()).abs() < 1e-4);
    assert!((spot.blend - 0.5).abs() < 1e-6);
    let sun = &r.lights[2];
    assert_eq!(sun.kind, kiln_plugin_api::LIGHT_DISTANT);
    assert!(close(&sun.direction, &[0.0, 0.0, -1.0], 1e-6));
    assert!(close(&sun.intensity, &[0.01; 3], 1e-6));
}

#[test]
fn unsupported_used_extension_is_reported_once() {
    let r = import_scene();
    let n = r
        .warnings
        .iter()
        .filter(|w| w.contains("EXT_unknown_thing"))
        .count();
    assert_eq!(n, 1, "{:#?}", r.warnings);
}

#[test]
fn unsupported_required_extension_fails_naming_it() {
    let dir = common::scratch_dir();
    let path = write(
        dir.path(),
        "draco.gltf",
        r#"{"asset":{"version":"2.0"},"extensionsUsed":["KHR_draco_mesh_compression"],
            "extensionsRequired":["KHR_draco_mesh_compression"]}"#,
    );
    let (result, _) = import(&path);
    let e = result.expect_err("must fail");
    assert!(e.contains("KHR_draco_mesh_compression"), "{e}");
}

#[test]
fn handled_required_extension_imports() {
    let dir = common::scratch_dir();
    let path = write(
        dir.path(),
        "volume.gltf",
        r#"{"asset":{"version":"2.0"},"extensionsUsed":["KHR_materials_volume","KHR_mesh_quantization"],
            "extensionsRequired":["KHR_materials_volume","KHR_mesh_quantization"]}"#,
    );
    let (result, r) = import(&path);
    result.expect("handled extensions may be required");
    assert!(r.warnings.is_empty(), "{:#?}", r.warnings);
}

#[test]
fn missing_buffer_file_fails_naming_it() {
    let dir = common::scratch_dir();
    let path = write(
        dir.path(),
        "lost.gltf",
        r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":12,"uri":"nowhere.bin"}]}"#,
    );
    let (result, _) = import(&path);
    let e = result.expect_err("must fail");
    assert!(e.contains("nowhere.bin"), "{e}");
}

#[test]
fn an_external_image_that_is_not_a_file_is_reported_not_waited_on() {
    // A FIFO blocks whoever opens it until something writes: the import must not hang.
    let dir = common::scratch_dir();
    let fifo = dir.path().join("tex.png");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo {}", fifo.display());
    let gltf = scene_gltf().replace(&format!("data:image/png;base64,{PNG_1X1}"), "tex.png");
    let path = write(dir.path(), "fifo.gltf", &gltf);
    let (result, recorded) = import(&path);
    let said = match result {
        Ok(()) => recorded.warnings.join("\n"),
        Err(e) => e,
    };
    assert!(
        said.contains("tex.png") && said.contains("not a regular file"),
        "{said}"
    );
}

#[test]
fn glb_binary_chunk_feeds_the_first_buffer() {
    let positions = f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let mut json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
            "bufferViews":[{{"buffer":0,"byteLength":36}}],"buffers":[{{"byteLength":{}}}]}}"#,
        positions.len()
    )
    .into_bytes();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut glb = b"glTF".to_vec();
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&((12 + 8 + json.len() + 8 + positions.len()) as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(positions.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&positions);
    let dir = common::scratch_dir();
    let path = dir.path().join("tri.glb");
    std::fs::write(&path, glb).expect("write GLB");
    let (result, r) = import(&path);
    result.expect("GLB imports");
    assert_eq!(r.meshes.len(), 1);
    assert_eq!(r.meshes[0].positions[1], [1.0, 0.0, 0.0]);
}

#[test]
fn material_extensions_translate_to_graphs_that_compile() {
    let dir = common::scratch_dir();
    let texture = |i: usize| format!(r#"{{"index": {i}}}"#);
    let transformed = r#"{"index": 0, "extensions": {"KHR_texture_transform": {"rotation": 0.5}}}"#;
    let text = format!(
        r#"{{"asset":{{"version":"2.0"}},
  "materials": [
    {{"name": "glass", "extensions": {{
      "KHR_materials_transmission": {{"transmissionFactor": 1, "transmissionTexture": {t0}}},
      "KHR_materials_volume": {{"thicknessFactor": 1, "attenuationDistance": 2, "attenuationColor": [0.5, 0.9, 0.5]}},
      "KHR_materials_ior": {{"ior": 1.33}}}}}},
    {{"name": "thin", "extensions": {{"KHR_materials_transmission": {{"transmissionFactor": 0.5}}}}}},
    {{"name": "leaf", "pbrMetallicRoughness": {{"baseColorFactor": [0.2, 0.5, 0.1, 1]}}, "extensions": {{
      "KHR_materials_diffuse_transmission": {{"diffuseTransmissionFactor": 0.4, "diffuseTransmissionTexture": {t0},
                                             "diffuseTransmissionColorFactor": [0.6, 0.9, 0.2]}}}}}},
    {{"name": "coated", "normalTexture": {{"index": 1, "scale": 0.5, "extensions": {{"KHR_texture_transform": {{"offset": [0.1, 0.2]}}}}}},
      "pbrMetallicRoughness": {{"metallicRoughnessTexture": {t1}, "baseColorTexture": {transformed}}},
      "alphaMode": "BLEND",
      "extensions": {{
      "KHR_materials_clearcoat": {{"clearcoatFactor": 1, "clearcoatTexture": {t0}, "clearcoatRoughnessFactor": 0.2,
                                   "clearcoatRoughnessTexture": {t0}, "clearcoatNormalTexture": {t1}}},
      "KHR_materials_sheen": {{"sheenColorFactor": [1, 0.5, 0.2], "sheenColorTexture": {t0}, "sheenRoughnessFactor": 0.4, "sheenRoughnessTexture": {t1}}},
      "KHR_materials_specular": {{"specularFactor": 0.5, "specularTexture": {t0}, "specularColorFactor": [1, 0.8, 0.8], "specularColorTexture": {t1}}}}}}},
    {{"name": "unlit", "pbrMetallicRoughness": {{"baseColorFactor": [0.2, 0.4, 0.6, 0.5]}}, "alphaMode": "BLEND",
      "extensions": {{"KHR_materials_unlit": {{}}}}}},
    {{"name": "specgloss", "extensions": {{"KHR_materials_pbrSpecularGlossiness": {{
      "diffuseFactor": [0.5, 0.5, 0.5, 1], "glossinessFactor": 0.8, "specularGlossinessTexture": {t1}}}}}}},
    {{"name": "odd \"name\" \\ here", "emissiveFactor": [1e30, -1, 0.5], "pbrMetallicRoughness": {{"roughnessFactor": -3}}}}
  ],
  "textures": [{{"source": 0}}, {{"source": 0}}],
  "images": [{{"uri": "data:image/png;base64,{PNG_1X1}"}}]
}}"#,
        t0 = texture(0),
        t1 = texture(1),
    );
    let path = write(dir.path(), "materials.gltf", &text);
    let texts = kiln_gltf::material_texts(&path).expect("translates");
    assert_eq!(texts.len(), 7 * 2 + 1);
    for (name, kmat) in &texts {
        common::compile_kmat(name, kmat).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    let find = |n: &str| {
        &texts
            .iter()
            .find(|(name, _)| name == n)
            .expect("material")
            .1
    };
    let glass = find("glass");
    assert!(glass.contains(r#""transmission_depth": 2.0"#), "{glass}");
    assert!(
        glass.contains(r#""transmission_color": (0.5, 0.9, 0.5)"#),
        "{glass}"
    );
    assert!(glass.contains(r#""ior": 1.33"#), "{glass}");
    assert!(!glass.contains("thin_walled"), "{glass}");
    assert!(find("thin").contains(r#""thin_walled": true"#));
    // Diffuse transmission: the subsurface share of a thin wall, tinted by its colour,
    // its factor times the texture's alpha.
    let leaf = find("leaf");
    assert!(leaf.contains(r#""thin_walled": true"#), "{leaf}");
    assert!(
        leaf.contains(r#""transmission_color": (0.6, 0.9, 0.2)"#),
        "{leaf}"
    );
    assert!(leaf.contains(r#""subsurface_weight": "#), "{leaf}");
    assert!(leaf.contains(r#""base_color": (0.2, 0.5, 0.1)"#), "{leaf}");
    let coated = find("coated");
    for input in [
        "coat_weight",
        "coat_roughness",
        "sheen_weight",
        "sheen_color",
        "sheen_roughness",
        "specular_weight",
        "specular_color",
        "normal_map",
        "\"alpha\":",
    ] {
        assert!(coated.contains(input), "{input} missing:\n{coated}");
    }
    let unlit = find("unlit");
    assert!(
        unlit.contains(r#""emission_color": (0.2, 0.4, 0.6)"#),
        "{unlit}"
    );
    assert!(unlit.contains(r#""alpha": 0.5"#), "{unlit}");
}

#[test]
fn vertex_colours_multiply_the_base_colour() {
    let dir = common::scratch_dir();
    let (data, _) = pack(&[
        f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
        vec![255, 0, 0, 0, 0, 255, 0, 0, 0, 0, 255, 0],
    ]);
    let text = format!(
        r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0, 1]}}],"nodes":[{{"mesh":0}}, {{"mesh":1}}],
  "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"COLOR_0":1}},"material":0}}]}},
            {{"primitives":[{{"attributes":{{"POSITION":0,"COLOR_0":1}}}}]}}],
  "materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[0.5,0.5,0.5,1]}}}}],
  "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
               {{"bufferView":1,"componentType":5121,"normalized":true,"count":3,"type":"VEC3"}}],
  "bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":12,"byteStride":4}}],
  "buffers":[{{"byteLength":{},"uri":"{}"}}]}}"#,
        data.len(),
        data_uri(&data)
    );
    let path = write(dir.path(), "colors.gltf", &text);
    let (result, r) = import(&path);
    result.expect("imports");
    assert!(r.violations.is_empty(), "{:#?}", r.violations);
    let colors = r.meshes[0].colors.as_ref().expect("COLOR_0 passed");
    assert_eq!(colors[1], [0.0, 1.0, 0.0, 1.0], "{colors:?}");
    assert_eq!(
        r.materials.len(),
        2,
        "the material and the vertex-colour default"
    );
    // What each imported graph feeds the base colour, evaluated on the GPU at a vertex
    // whose COLOR_0 is green: the factor times the colour, and the colour alone where the
    // primitive has no material.
    let green = [0.0, 1.0, 0.0, 1.0];
    let with_factor = base_colour_at_vertex_colour(r.material(r.instances[0].1), green);
    let default = base_colour_at_vertex_colour(r.material(r.instances[1].1), green);
    for (what, got, want) in [
        ("factor 0.5 × green", with_factor, [0.0, 0.5, 0.0]),
        ("no material × green", default, [0.0, 1.0, 0.0]),
    ] {
        assert!(
            got.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-4),
            "{what}: base colour {got:?}, expected {want:?}"
        );
    }
}

/// The base colour `kmat` computes on a surface whose vertex colour is `color`: the graph
/// with the principled node's base-colour input moved to its emission (nothing else
/// emitting or reflecting, black sky), rendered on a quad that fills the view.
fn base_colour_at_vertex_colour(kmat: &str, color: [f32; 4]) -> [f32; 3] {
    use glam::{Affine3A, Vec3, Vec4};
    use kiln::material::{Input, Value};
    use kiln::render::{GpuContext, RenderControl, RenderSettings, Renderer};
    use kiln::scene::{Camera, Material, Scene, shapes};

    let (_, mut graph) = kiln::material::parse_material(kmat, "test.gltf").expect("parses");
    let surface = graph
        .nodes
        .values_mut()
        .find(|n| n.kind == "principled_bsdf")
        .expect("a principled node");
    let base = surface
        .inputs
        .remove("base_color")
        .expect("the base colour is wired");
    surface.inputs.clear();
    surface
        .inputs
        .insert("base_color".into(), Input::Value(Value::Vec3([0.0; 3])));
    surface
        .inputs
        .insert("specular_weight".into(), Input::Value(Value::Float(0.0)));
    surface.inputs.insert("emission_color".into(), base);
    surface
        .inputs
        .insert("emission_strength".into(), Input::Value(Value::Float(1.0)));

    let mut scene = Scene::empty(Camera {
        up: Vec3::Z,
        ..Camera::look_at(Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO, 10.0)
    });
    scene.environment = Vec3::ZERO;
    let m = scene.add_material(Material::from_graph("probe", graph).expect("compiles"));
    let mut quad = shapes::quad();
    quad.colors = vec![Vec4::from(color); 4];
    let q = scene.add_mesh(quad);
    scene.add_instance(q, m, Affine3A::from_scale(Vec3::splat(4.0)));
    let settings = RenderSettings {
        width: 4,
        height: 4,
        samples_per_pixel: 2,
        max_bounces: 4,
        ..RenderSettings::from_scene(&scene)
    };
    let ctx = GpuContext::new(None).expect("an adapter");
    let mut renderer = Renderer::new(ctx, &scene, settings).expect("renderer");
    renderer
        .render(0..2, RenderControl::default())
        .expect("renders");
    let pixels = renderer.read_film().expect("film").radiance();
    let first = pixels[0];
    assert!(
        pixels
            .iter()
            .all(|p| (*p - first).abs().max_element() < 1e-5),
        "the quad does not fill the view evenly: {pixels:?}"
    );
    first.to_array()
}

/// The real host (Kiln's plugin loader and builder) on the same scene: textures decoded,
/// graphs compiled, everything accepted. Needs the cdylib cargo builds beside the tests.
#[test]
fn kiln_host_accepts_the_imported_scene() {
    let exe = std::env::current_exe().expect("test executable");
    let deps = exe.parent().expect("deps folder");
    let library = deps.join(format!(
        "{}kiln_gltf{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    ));
    let Some(library) = common::resource::require(&library, "the kiln_gltf plugin library") else {
        return;
    };
    let mut host = kiln::plugin::PluginHost::default();
    host.load_file(&library).expect("the plugin loads");
    let dir = common::scratch_dir();
    let path = write(dir.path(), "scene.gltf", &scene_gltf());
    let imported = host.import(&path).expect("the host imports the scene");
    assert_eq!(imported.scene.meshes.len(), 3);
    assert_eq!(imported.scene.instances.len(), 5);
    assert_eq!(imported.scene.lights.len(), 3);
    assert!(imported.has_camera);
    let unexpected: Vec<&String> = imported
        .warnings
        .iter()
        .filter(|w| !w.contains("EXT_unknown_thing") && !w.contains("broken"))
        .collect();
    assert!(unexpected.is_empty(), "{unexpected:#?}");
}
