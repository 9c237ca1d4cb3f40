//! The OBJ importer driven through its C ABI with the plugin API's recording
//! `SceneBuilder`; the generated materials are compiled by Kiln itself.

use std::collections::BTreeMap;
use std::ffi::{CStr, CString, c_char};
use std::path::{Path, PathBuf};

use kiln::material::{Input, Param, Value};
use kiln_obj::kiln_plugin_descriptor;
use kiln_plugin_api as api;
use kiln_plugin_api::recording::{Recorded, Recorder};

fn descriptor() -> &'static api::PluginDescriptor {
    // The descriptor is static data of the library.
    unsafe { &*kiln_plugin_descriptor() }
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn import(path: &Path) -> Recorded {
    let (result, recorded) = Recorder::default().import(descriptor(), path);
    if let Err(message) = result {
        panic!("import failed: {message}");
    }
    recorded
}

fn import_error(path: &Path) -> String {
    let (result, _) = Recorder::default().import(descriptor(), path);
    let message = result.expect_err("import should fail");
    assert!(!message.is_empty(), "an error comes with a message");
    message
}

const IDENTITY: [f32; 16] = [
    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
];

/// The scene fixture's materials parsed by Kiln as the host does (paths resolved against
/// the .obj's folder), by name.
fn scene_graphs() -> BTreeMap<String, kiln::material::Graph> {
    let obj = fixture("scene.obj");
    import(&obj)
        .materials
        .iter()
        .map(|(name, kmat)| {
            let (_, graph) = kiln::material::parse_material(kmat, &obj.display().to_string())
                .unwrap_or_else(|e| panic!("material {name} does not parse: {e}\n{kmat}"));
            (name.clone(), graph)
        })
        .collect()
}

fn surface_input<'a>(graph: &'a kiln::material::Graph, input: &str) -> Option<&'a Input> {
    graph.nodes["surface"].inputs.get(input)
}

fn float_input(graph: &kiln::material::Graph, input: &str) -> f32 {
    match surface_input(graph, input) {
        Some(Input::Value(Value::Float(v))) => *v,
        other => panic!("{input} is {other:?}, not a number"),
    }
}

fn link_input(graph: &kiln::material::Graph, input: &str) -> (String, String) {
    match surface_input(graph, input) {
        Some(Input::Link(l)) => (l.node.clone(), l.socket.clone()),
        other => panic!("{input} is {other:?}, not a link"),
    }
}

fn file_of(graph: &kiln::material::Graph, node: &str) -> String {
    let n = &graph.nodes[node];
    assert_eq!(n.kind, "image_texture");
    match n.params.get("file") {
        Some(Param::Text(f)) => f.clone(),
        other => panic!("{node} has file {other:?}"),
    }
}

fn text_param(graph: &kiln::material::Graph, node: &str, param: &str) -> String {
    match graph.nodes[node].params.get(param) {
        Some(Param::Text(t)) => t.clone(),
        other => panic!("{node}.{param} is {other:?}"),
    }
}

#[test]
fn descriptor_declares_an_obj_importer_of_this_abi() {
    let d = descriptor();
    assert_eq!(d.abi_version, api::ABI_VERSION);
    assert_eq!(d.kind, api::KIND_IMPORTER);
    assert!(d.import.is_some() && d.export.is_none());
    let text = |p| unsafe { CStr::from_ptr(p) }.to_str().unwrap();
    assert_eq!(text(d.name), "Wavefront OBJ");
    assert_eq!(text(d.extensions), "obj");
    assert_eq!(text(d.version), env!("CARGO_PKG_VERSION"));
}

#[test]
fn each_object_becomes_one_mesh_and_one_identity_instance() {
    let r = import(&fixture("scene.obj"));
    let names: Vec<&str> = r.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(
        names,
        ["Plain", "Box", "Glass", "Lamp", "Metal", "Leaf", "Wall"]
    );
    assert_eq!(r.instances.len(), r.meshes.len());
    for (i, (mesh, _, transform)) in r.instances.iter().enumerate() {
        assert_eq!(*mesh as usize, i);
        assert_eq!(*transform, IDENTITY);
    }
    // The quads are two triangles each; the point-only object is skipped with a warning.
    let triangles: Vec<usize> = r.meshes.iter().map(|m| m.indices.len() / 3).collect();
    assert_eq!(triangles, [1, 2, 1, 2, 1, 1, 1]);
    assert!(
        r.warnings.iter().any(|w| w.contains("Dots")),
        "{:?}",
        r.warnings
    );
    // OBJ has no cameras, lights or embedded images.
    assert_eq!((r.cameras.len(), r.lights.len(), r.images.len()), (0, 0, 0));
}

#[test]
fn normals_and_uvs_are_passed_as_written() {
    let r = import(&fixture("scene.obj"));
    let boxed = &r.meshes[1];
    assert_eq!(boxed.positions.len(), 4);
    let normals = boxed.normals.as_ref().expect("the box has normals");
    assert!(normals.iter().all(|n| *n == [0.0, 0.0, 1.0]));
    let uvs = boxed.uvs.as_ref().expect("the box has texture coordinates");
    // Each vertex keeps its (u, v): v is not flipped.
    for (p, t) in boxed.positions.iter().zip(uvs) {
        assert_eq!([p[0], p[1]], *t, "vertex {p:?} has uv {t:?}");
    }
    let plain = &r.meshes[0];
    assert!(plain.normals.is_none() && plain.uvs.is_none());
    assert_eq!(
        plain.positions,
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]
    );
    let metal = &r.meshes[4];
    assert!(metal.normals.is_none() && metal.uvs.is_some());
}

#[test]
fn meshes_get_their_material_and_unmaterialled_meshes_get_none() {
    let r = import(&fixture("scene.obj"));
    let material_of = |mesh: &str| {
        let i = r.meshes.iter().position(|m| m.name == mesh).unwrap();
        let id = r.instances[i].1;
        (id != u32::MAX).then(|| r.materials[id as usize].0.as_str())
    };
    assert_eq!(material_of("Plain"), None);
    assert_eq!(material_of("Box"), Some("textured"));
    assert_eq!(material_of("Glass"), Some("glass"));
    assert_eq!(material_of("Lamp"), Some("emissive"));
    assert_eq!(material_of("Metal"), Some("pbr"));
    assert_eq!(material_of("Leaf"), Some("classic"));
    assert_eq!(material_of("Wall"), Some("matte"));
    // Each material is handed over once.
    assert_eq!(r.materials.len(), 6);
}

#[test]
fn every_generated_material_compiles_in_kiln() {
    let r = import(&fixture("scene.obj"));
    for (name, kmat) in &r.materials {
        let (parsed_name, graph) = kiln::material::parse_material(kmat, "x.kmat")
            .unwrap_or_else(|e| panic!("{name} does not parse: {e}\n{kmat}"));
        assert_eq!(&parsed_name, name);
        kiln::material::compile(name, &graph, "m")
            .unwrap_or_else(|e| panic!("{name} does not compile: {e}\n{kmat}"));
    }
}

#[test]
fn diffuse_map_is_multiplied_by_kd_and_stays_relative_to_the_obj() {
    let graphs = scene_graphs();
    let g = &graphs["textured"];
    let (mix, socket) = link_input(g, "base_color");
    assert_eq!(socket, "result");
    assert_eq!(g.nodes[&mix].kind, "mix_color");
    assert_eq!(text_param(g, &mix, "blend"), "multiply");
    assert_eq!(
        g.nodes[&mix].inputs["a"],
        Input::Value(Value::Vec3([0.8, 0.6, 0.4]))
    );
    let Input::Link(texture) = &g.nodes[&mix].inputs["b"] else {
        panic!("the map feeds b")
    };
    // Written `textures\wood floor.png`: backslash made portable, space kept, and the
    // host resolves it against the .obj's folder.
    let expected = fixture("textures/wood floor.png");
    assert_eq!(file_of(g, &texture.node), expected.display().to_string());
    assert_eq!(text_param(g, &texture.node, "color_space"), "srgb");
    // -s 2 2 -o 0.5 0: a mapping node scales then offsets the UVs.
    let Input::Link(uv) = &g.nodes[&texture.node].inputs["vector"] else {
        panic!("-s/-o feed a mapping")
    };
    let mapping = &g.nodes[&uv.node];
    assert_eq!(mapping.kind, "mapping");
    assert_eq!(
        mapping.inputs["scale"],
        Input::Value(Value::Vec3([2.0, 2.0, 1.0]))
    );
    assert_eq!(
        mapping.inputs["location"],
        Input::Value(Value::Vec3([0.5, 0.0, 0.0]))
    );
    // The text itself keeps the path as written (relative).
    let r = import(&fixture("scene.obj"));
    let kmat = &r.materials.iter().find(|(n, _)| n == "textured").unwrap().1;
    assert!(kmat.contains("\"textures/wood floor.png\""), "{kmat}");
}

#[test]
fn phong_terms_become_specular_weight_and_roughness() {
    let graphs = scene_graphs();
    let g = &graphs["textured"];
    // Ks 0.5 grey: an ordinary dielectric (Blender's convention), untinted.
    assert!((float_input(g, "specular_weight") - 1.0).abs() < 1e-6);
    assert_eq!(
        surface_input(g, "specular_color"),
        Some(&Input::Value(Value::Vec3([1.0, 1.0, 1.0])))
    );
    // Ns 100: α = sqrt(2/102), roughness = sqrt(α) = 0.3742.
    let roughness = float_input(g, "roughness");
    assert!((roughness - 0.374_19).abs() < 1e-4, "{roughness}");
    assert!((kiln_obj::mtl::roughness_from_shininess(0.0) - 1.0).abs() < 1e-6);
    assert!(kiln_obj::mtl::roughness_from_shininess(1000.0) < 0.22);
    // A tinted Ks: the weight from its largest channel, the hue as specular colour.
    let classic = &graphs["classic"];
    assert!((float_input(classic, "specular_weight") - 0.08).abs() < 1e-6);
    assert_eq!(
        surface_input(classic, "specular_color"),
        Some(&Input::Value(Value::Vec3([1.0, 0.5, 0.5])))
    );
    // illum 1: no highlights. Ni 1 is treated as unset.
    let matte = &graphs["matte"];
    assert_eq!(float_input(matte, "specular_weight"), 0.0);
    assert!(surface_input(matte, "ior").is_none());
    // Tr 0.25 is d 0.75.
    assert!((float_input(matte, "alpha") - 0.75).abs() < 1e-6);
}

#[test]
fn bump_maps_drive_a_bump_node_with_the_bm_strength() {
    let graphs = scene_graphs();
    let g = &graphs["textured"];
    let (bump, socket) = link_input(g, "normal");
    assert_eq!(
        (g.nodes[&bump].kind.as_str(), socket.as_str()),
        ("bump", "normal")
    );
    assert_eq!(
        g.nodes[&bump].inputs["strength"],
        Input::Value(Value::Float(0.5))
    );
    let Input::Link(height) = &g.nodes[&bump].inputs["height"] else {
        panic!("an image feeds the height")
    };
    assert_eq!(text_param(g, &height.node, "color_space"), "linear");
    assert!(file_of(g, &height.node).ends_with("textures/height.png"));
}

#[test]
fn glass_illumination_models_transmit() {
    let graphs = scene_graphs();
    let g = &graphs["glass"];
    assert_eq!(float_input(g, "transmission_weight"), 1.0);
    assert!((float_input(g, "ior") - 1.5).abs() < 1e-6);
    assert_eq!(
        surface_input(g, "transmission_color"),
        Some(&Input::Value(Value::Vec3([0.9, 1.0, 0.9])))
    );
    assert!(surface_input(&graphs["textured"], "transmission_weight").is_none());
}

#[test]
fn ke_and_map_ke_emit() {
    let graphs = scene_graphs();
    let g = &graphs["emissive"];
    assert_eq!(float_input(g, "emission_strength"), 1.0);
    let (mix, _) = link_input(g, "emission_color");
    assert_eq!(
        g.nodes[&mix].inputs["a"],
        Input::Value(Value::Vec3([4.0, 4.0, 3.0]))
    );
    let r = import(&fixture("scene.obj"));
    let (_, kmat) = r.materials.iter().find(|(n, _)| n == "emissive").unwrap();
    let compiled = kiln::material::compile("emissive", &graphs["emissive"], "m").unwrap();
    assert!(
        compiled.images.keys().any(|f| f.ends_with("lamp.png")),
        "{kmat}"
    );
}

#[test]
fn pbr_extension_drives_roughness_metallic_and_normal_map() {
    let graphs = scene_graphs();
    let g = &graphs["pbr"];
    // map_Pr replaces Pr; -clamp on extends the edge.
    let (rough, socket) = link_input(g, "roughness");
    assert_eq!(socket, "color");
    assert_eq!(text_param(g, &rough, "extension"), "extend");
    assert_eq!(text_param(g, &rough, "color_space"), "linear");
    // map_Pm -imfchan b reads the blue channel.
    let (split, socket) = link_input(g, "metallic");
    assert_eq!(
        (g.nodes[&split].kind.as_str(), socket.as_str()),
        ("separate_color", "blue")
    );
    // Kd 1 with a map: the map alone.
    let (albedo, _) = link_input(g, "base_color");
    assert_eq!(g.nodes[&albedo].kind, "image_texture");
    // norm: a tangent-space normal map at the -bm strength.
    let (normal_map, _) = link_input(g, "normal");
    assert_eq!(g.nodes[&normal_map].kind, "normal_map");
    assert_eq!(
        g.nodes[&normal_map].inputs["strength"],
        Input::Value(Value::Float(0.75))
    );
    assert_eq!(float_input(g, "anisotropy"), 0.5);
    assert_eq!(float_input(g, "anisotropy_rotation"), 0.25);
    assert_eq!(float_input(g, "coat_weight"), 1.0);
    assert!((float_input(g, "coat_roughness") - 0.1).abs() < 1e-6);
    assert!((float_input(g, "sheen_weight") - 0.2).abs() < 1e-6);
    // The PBR terms replace the Phong ones.
    assert!(surface_input(g, "specular_weight").is_none());
}

#[test]
fn dissolve_and_its_map_multiply_into_alpha() {
    let graphs = scene_graphs();
    let g = &graphs["classic"];
    let (alpha, _) = link_input(g, "alpha");
    assert_eq!(g.nodes[&alpha].kind, "math");
    assert_eq!(g.nodes[&alpha].inputs["b"], Input::Value(Value::Float(0.5)));
    // -imfchan m: the image's alpha.
    let Input::Link(map) = &g.nodes[&alpha].inputs["a"] else {
        panic!("the map feeds a")
    };
    assert_eq!(map.socket, "alpha");
}

#[test]
fn unsupported_statements_and_options_are_reported() {
    let r = import(&fixture("scene.obj"));
    let has = |needle: &str| r.warnings.iter().any(|w| w.contains(needle));
    assert!(has("\"classic\"") && has("refl"), "{:?}", r.warnings);
    assert!(has("-mm"), "{:?}", r.warnings);
    // Ambient terms are dropped quietly.
    assert!(
        !r.warnings.iter().any(|w| w.contains("Ka")),
        "{:?}",
        r.warnings
    );
}

#[test]
fn a_missing_material_library_is_a_warning_and_meshes_stay_grey() {
    let r = import(&fixture("missing_mtl.obj"));
    assert!(
        r.warnings.iter().any(|w| w.contains("nowhere.mtl")),
        "{:?}",
        r.warnings
    );
    assert_eq!(r.meshes.len(), 1);
    assert_eq!(r.instances[0].1, u32::MAX);
    assert!(r.materials.is_empty());
}

#[test]
fn a_missing_file_is_an_error_naming_it() {
    let message = import_error(&fixture("does_not_exist.obj"));
    assert!(message.contains("does_not_exist.obj"), "{message}");
}

#[test]
fn malformed_and_empty_files_are_errors_naming_them() {
    let message = import_error(&fixture("broken.obj"));
    assert!(message.contains("broken.obj"), "{message}");
    let message = import_error(&fixture("no_faces.obj"));
    assert!(
        message.contains("no_faces.obj") && message.contains("no faces"),
        "{message}"
    );
    // A folder, not a file.
    let message = import_error(&fixture(""));
    assert!(message.contains("fixtures"), "{message}");
}

#[test]
fn a_host_refusing_everything_gets_no_instances() {
    let refusing = Recorder {
        refuse: true,
        ..Recorder::default()
    };
    let (result, r) = refusing.import(descriptor(), &fixture("scene.obj"));
    assert_eq!(result, Ok(()));
    assert!(r.meshes.is_empty() && r.instances.is_empty());
}

#[test]
fn null_arguments_are_errors_not_crashes() {
    let import = descriptor().import.unwrap();
    let mut message = vec![0 as c_char; 256];
    let mut error = api::ErrorBuffer {
        data: message.as_mut_ptr(),
        capacity: message.len(),
    };
    let path = CString::new(fixture("scene.obj").to_str().unwrap()).unwrap();
    let status = unsafe { import(path.as_ptr(), std::ptr::null(), &mut error) };
    assert_eq!(status, api::STATUS_ERROR);
    assert!(
        !unsafe { CStr::from_ptr(message.as_ptr()) }
            .to_bytes()
            .is_empty()
    );
    let mut recorder = Recorder::default();
    let builder = recorder.scene_builder();
    let status = unsafe { import(std::ptr::null(), &builder, std::ptr::null_mut()) };
    assert_eq!(status, api::STATUS_ERROR);
}
