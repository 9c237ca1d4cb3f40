//! Graph materials in renders: a graph of constants renders what the same fixed
//! parameters render; graph emitters are lights; textured graphs stay finite.

mod common;

use common::{gpu, mean, render, rmse, settings};
use glam::{Affine3A, Vec3};
use kiln::material::compile::link;
use kiln::material::{Graph, Node};
use kiln::scene::graph_from_principled;
use kiln::scene::{Camera, Light, Material, Scene, shapes};
use kiln::shader::principled::Principled;

/// Spheres of the given materials on a floor, under an area light, a sphere light and a sky.
fn spheres(materials: Vec<Material>) -> Scene {
    let mut scene = Scene::empty(Camera::look_at(
        Vec3::new(0.0, 1.2, 5.0),
        Vec3::new(0.0, 0.4, 0.0),
        40.0,
    ));
    scene.environment = Vec3::new(0.2, 0.25, 0.3);
    let floor = scene.add_material(Material::diffuse("floor", Vec3::splat(0.5)));
    let lamp = scene.add_material(Material::emitter("lamp", Vec3::splat(8.0)));
    let quad = scene.add_mesh(shapes::quad());
    let ball = scene.add_mesh(shapes::uv_sphere(32, 16, true));
    scene.add_instance(quad, floor, Affine3A::from_scale(Vec3::splat(20.0)));
    scene.add_instance(
        quad,
        lamp,
        Affine3A::from_translation(Vec3::new(0.0, 3.0, 1.0))
            * Affine3A::from_rotation_x(std::f32::consts::PI),
    );
    scene.add_light(Light::Point {
        position: Vec3::new(2.0, 2.0, 2.0),
        intensity: Vec3::splat(3.0),
        radius: 0.2,
    });
    let n = materials.len();
    for (i, m) in materials.into_iter().enumerate() {
        let id = scene.add_material(m);
        let x = (i as f32 - (n - 1) as f32 / 2.0) * 1.1;
        scene.add_instance(
            ball,
            id,
            Affine3A::from_scale_rotation_translation(
                Vec3::splat(0.5),
                Default::default(),
                Vec3::new(x, 0.5, 0.0),
            ),
        );
    }
    scene
}

fn fixed_materials() -> Vec<Material> {
    vec![
        Material {
            name: "plastic".into(),
            principled: Principled {
                base_color: Vec3::new(0.1, 0.35, 0.8),
                roughness: 0.25,
                ..Principled::default()
            },
            ..Material::default()
        },
        Material {
            name: "gold".into(),
            principled: Principled {
                base_color: Vec3::new(1.0, 0.78, 0.34),
                metallic: 1.0,
                roughness: 0.35,
                ..Principled::default()
            },
            ..Material::default()
        },
        Material {
            name: "glass".into(),
            principled: Principled {
                transmission_weight: 1.0,
                roughness: 0.2,
                ..Principled::default()
            },
            ..Material::default()
        },
        Material {
            name: "coated velvet".into(),
            principled: Principled {
                base_color: Vec3::new(0.15, 0.02, 0.25),
                sheen_weight: 1.0,
                coat_weight: 0.5,
                anisotropy: 0.5,
                anisotropy_rotation: 0.2,
                ..Principled::default()
            },
            ..Material::default()
        },
    ]
}

#[test]
fn a_graph_of_constants_renders_like_the_same_fixed_parameters() {
    let fixed = fixed_materials();
    let graphs: Vec<Material> = fixed
        .iter()
        .map(|m| Material::from_graph(&m.name, graph_from_principled(m)).unwrap())
        .collect();
    let s = settings(48, 32, 32);
    let a = render(&gpu(), &spheres(fixed), s).radiance();
    let b = render(&gpu(), &spheres(graphs), s).radiance();
    let scale = mean(&a).max_element() as f64;
    let error = rmse(&a, &b) / scale;
    eprintln!("relative RMSE, graph vs fixed: {error:e}");
    assert!(error < 1e-3, "graph materials render differently: {error}");
}

#[test]
fn a_constant_graph_emitter_is_sampled_as_a_light() {
    let mut g = Graph::default();
    g.add(
        "e",
        Node::new("principled_bsdf")
            .input("base_color", [0.0; 3])
            .input("emission_strength", 8.0)
            .input("specular_weight", 0.0),
    );
    g.add(
        "out",
        Node::new("material_output").input("surface", link("e", "bsdf")),
    );
    let emitter = Material::from_graph("lamp", g).unwrap();
    assert_eq!(
        emitter.emission(),
        Vec3::splat(8.0),
        "constant emission known in advance"
    );
    let lit = |lamp: Material| {
        let mut scene = spheres(vec![Material::diffuse("white", Vec3::splat(0.8))]);
        scene.materials[1] = Material {
            name: "lamp".into(),
            ..lamp
        };
        scene.environment = Vec3::ZERO;
        scene.lights.clear();
        render(&gpu(), &scene, settings(32, 24, 64)).radiance()
    };
    let fixed = lit(Material::emitter("lamp", Vec3::splat(8.0)));
    let graph = lit(emitter);
    let error = rmse(&fixed, &graph) / mean(&fixed).max_element() as f64;
    assert!(error < 1e-3, "graph emitter differs: {error}");
}

#[test]
fn the_example_materials_render_finite_images() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/materials");
    let mut materials = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let (name, graph) = kiln::material::load_material(&entry.unwrap().path()).unwrap();
        materials.push(Material::from_graph(&name, graph).unwrap());
    }
    // `render` asserts that no sample was NaN or infinite.
    let px = render(&gpu(), &spheres(materials), settings(64, 24, 8)).radiance();
    assert!(mean(&px).max_element() > 0.0);
}

#[test]
fn an_image_textured_material_renders_its_image() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("red.png");
    image::RgbImage::from_pixel(8, 8, image::Rgb([230, 20, 10]))
        .save(&png)
        .unwrap();
    let text = format!(
        r#"(version: 1, nodes: {{
            "img": (type: "image_texture", params: {{ "file": "{}" }}),
            "s": (type: "principled_bsdf", inputs: {{ "base_color": "img.color", "specular_weight": 0.0 }}),
            "o": (type: "material_output", inputs: {{ "surface": "s.bsdf" }}),
        }})"#,
        png.file_name().unwrap().to_str().unwrap()
    );
    let kmat = dir.path().join("red.kmat");
    std::fs::write(&kmat, text).unwrap();
    let (name, graph) = kiln::material::load_material(&kmat).unwrap();
    let m = Material::from_graph(&name, graph).unwrap();
    let px = render(&gpu(), &spheres(vec![m]), settings(32, 24, 16)).radiance();
    // The centre of the sphere is red.
    let c = px[12 * 32 + 16];
    assert!(c.x > 4.0 * c.y && c.x > 4.0 * c.z, "centre pixel {c}");
}

/// A quad of `mesh` filling the view, emitting the colour of `node.output` (a node with
/// no inputs) and reflecting nothing, with an extra quad of plain mesh out of view; the
/// image's pixels.
fn emitted_attribute(node: &str, output: &str, mesh: kiln::scene::Mesh) -> Vec<Vec3> {
    let mut g = Graph::default();
    g.add("attribute", Node::new(node));
    g.add(
        "s",
        Node::new("principled_bsdf")
            .input("base_color", [0.0; 3])
            .input("specular_weight", 0.0)
            .input("emission_color", link("attribute", output))
            .input("emission_strength", 1.0),
    );
    g.add(
        "out",
        Node::new("material_output").input("surface", link("s", "bsdf")),
    );
    let mut scene = Scene::empty(Camera {
        up: Vec3::Z,
        ..Camera::look_at(Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO, 10.0)
    });
    let m = scene.add_material(Material::from_graph("attribute", g).unwrap());
    let q = scene.add_mesh(mesh);
    scene.add_instance(q, m, Affine3A::from_scale(Vec3::splat(4.0)));
    // A mesh without the attribute shares the scene (it reads the defaults).
    let plain = scene.add_mesh(shapes::quad());
    scene.add_instance(
        plain,
        m,
        Affine3A::from_translation(Vec3::new(0.0, -5.0, 0.0)),
    );
    render(&gpu(), &scene, settings(8, 8, 4)).radiance()
}

#[test]
fn vertex_colours_reach_the_color_attribute_node() {
    let mut quad = shapes::quad();
    quad.colors = vec![glam::Vec4::new(1.0, 0.0, 0.0, 1.0); 4];
    for p in emitted_attribute("vertex_color", "color", quad) {
        assert!(
            (p - Vec3::new(1.0, 0.0, 0.0)).abs().max_element() < 1e-3,
            "pixel {p}"
        );
    }
}

#[test]
fn the_second_uv_set_reaches_the_texture_coordinate_node() {
    let mut quad = shapes::quad();
    quad.uvs1 = vec![glam::Vec2::new(0.25, 0.75); 4];
    for p in emitted_attribute("texture_coordinate", "uv1", quad) {
        assert!(
            (p - Vec3::new(0.25, 0.75, 0.0)).abs().max_element() < 1e-5,
            "pixel {p}"
        );
    }
}
