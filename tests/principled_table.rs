//! The principled parameters are declared once (`kiln::shader::principled`): the scene
//! file's material fields, the Principled BSDF node and the docs all follow that table.

use std::path::Path;

use glam::Vec3;
use kiln::material::Value;
use kiln::material::nodes::{self, ParamKind};
use kiln::scene::parse_scene;
use kiln::shader::principled::{PARAMETERS, ParamValue, Principled};

fn scene_with_material(fields: &str) -> Result<kiln::scene::Scene, String> {
    let text = format!(
        "(version: 1, camera: (position: (0, 0, 5), look_at: (0, 0, 0), projection: Perspective(fov_y: 40)), \
         materials: {{ \"m\": ({fields}) }}, meshes: {{ \"q\": Quad }}, \
         instances: [(mesh: \"q\", material: \"m\")])"
    );
    parse_scene(&text, Path::new("test.kiln"), Path::new(".")).map_err(|e| e.to_string())
}

/// A valid value unlike the default.
fn other_value(default: ParamValue) -> ParamValue {
    match default {
        ParamValue::Float(x) => ParamValue::Float(if x == 1.0 { 0.25 } else { x + 0.5 }),
        ParamValue::Color(c) => ParamValue::Color(Vec3::new(0.1, 0.2, 0.3) + c * 0.0),
        ParamValue::Bool(b) => ParamValue::Bool(!b),
    }
}

fn ron(value: ParamValue) -> String {
    match value {
        ParamValue::Float(x) => format!("{x:?}"),
        ParamValue::Color(c) => format!("({:?}, {:?}, {:?})", c.x, c.y, c.z),
        ParamValue::Bool(b) => format!("{b}"),
    }
}

#[test]
fn every_parameter_is_a_scene_file_field_of_its_name() {
    for p in &PARAMETERS {
        let value = other_value(p.default_value());
        let scene = scene_with_material(&format!("{}: {}", p.name, ron(value)))
            .unwrap_or_else(|e| panic!("{}: {e}", p.name));
        let m = &scene.materials[0];
        assert_eq!(m.principled.get(p.name), Some(value), "{}", p.name);
        let mut expected = Principled::default();
        expected.set(p.name, value).unwrap();
        assert_eq!(m.principled, expected, "only {} changes", p.name);
    }
}

#[test]
fn scene_files_refuse_unknown_fields_and_out_of_range_values_by_name() {
    let e = scene_with_material("roughnes: 0.2").unwrap_err();
    assert!(e.contains("roughnes"), "{e}");
    let e = scene_with_material("coat_ior: 0.5").unwrap_err();
    assert!(e.contains("coat_ior 0.5 must be at least 1"), "{e}");
    let e = scene_with_material("metallic: 0.5, metallic: 0.2").unwrap_err();
    assert!(e.contains("metallic"), "{e}");
    // A value of the wrong type: the position of the value, and what was expected.
    let e = scene_with_material("roughness: true").unwrap_err();
    assert!(e.contains("test.kiln:1:") && e.contains("float"), "{e}");
    let e = scene_with_material(
        "roughness: 0.2, graph: (nodes: { \"out\": (type: \"material_output\") })",
    )
    .unwrap_err();
    assert!(e.contains("remove `roughness`"), "{e}");
}

#[test]
fn emission_and_opacity_shorthands_read_as_before() {
    // `emission` alone is a radiance: strength 1.
    let m = &scene_with_material("emission: (17, 12, 4)")
        .unwrap()
        .materials[0];
    assert_eq!(m.emission(), Vec3::new(17.0, 12.0, 4.0));
    let m = &scene_with_material("emission: (1, 0.5, 0.25), emission_strength: 4")
        .unwrap()
        .materials[0];
    assert_eq!(m.emission(), Vec3::new(4.0, 2.0, 1.0));
    let m = &scene_with_material("opacity: 0.25").unwrap().materials[0];
    assert_eq!(m.principled.alpha, 0.25);
    let e = scene_with_material("opacity: 0.25, alpha: 0.5").unwrap_err();
    assert!(e.contains("alpha"), "{e}");
}

#[test]
fn the_principled_bsdf_node_has_a_socket_or_flag_per_parameter_with_its_default() {
    let node = nodes::find("principled_bsdf").expect("the node exists");
    for p in &PARAMETERS {
        match p.default_value() {
            ParamValue::Bool(b) => {
                let param = node
                    .params
                    .iter()
                    .find(|d| d.name == p.name)
                    .unwrap_or_else(|| panic!("no flag {}", p.name));
                assert!(
                    matches!(param.kind, ParamKind::Bool(d) if d == b),
                    "{}",
                    p.name
                );
            }
            default => {
                let socket = node
                    .inputs
                    .iter()
                    .find(|s| s.name == p.name)
                    .unwrap_or_else(|| panic!("no socket {}", p.name));
                let expected = match default {
                    ParamValue::Float(x) => Value::Float(x),
                    ParamValue::Color(c) => Value::Vec3(c.to_array()),
                    ParamValue::Bool(_) => unreachable!(),
                };
                assert!(
                    matches!(&socket.default, nodes::Default::Value(v) if *v == expected),
                    "{}: {:?}",
                    p.name,
                    socket.default
                );
            }
        }
    }
    // Nothing else but the shading normal.
    assert_eq!(node.inputs.len() + node.params.len(), PARAMETERS.len() + 1);
}

#[test]
fn the_scene_format_page_lists_every_parameter() {
    let page = include_str!("../docs/SCENE_FORMAT.md");
    for p in &PARAMETERS {
        assert!(
            page.contains(&format!("`{}`", p.name)),
            "docs/SCENE_FORMAT.md does not list {}",
            p.name
        );
    }
}
