//! Kernel specialisation: the kernel compiles only the lobes and light types a scene
//! uses, and renders the same image as the kernel with everything.

mod common;

use common::{gpu, mean, render, rmse, settings};
use kiln::accel::build_scene_accel;
use kiln::render::KernelKind;
use kiln::render::gpu_scene::GpuScene;
use kiln::scene::{Material, Scene, default_scene};
use kiln::shader::features::features_wgsl;
use kiln::shader::principled::Principled;
use kiln::shader::{KernelFeatures, lobes};

fn features(scene: &Scene) -> KernelFeatures {
    let accel = build_scene_accel(scene).unwrap();
    GpuScene::upload(
        &gpu(),
        scene,
        &accel,
        None,
        scene.settings.volume_resolution,
    )
    .unwrap()
    .features()
}

#[test]
fn the_cornell_box_compiles_only_diffuse_and_its_area_light() {
    let f = features(&default_scene().unwrap());
    assert_eq!(f.lobes, lobes::DIFFUSE);
    assert!(
        !f.environment_map && !f.analytic_lights && f.emissive_triangles && !f.shadow_catcher,
        "{f:?}"
    );
    let consts = features_wgsl(&f);
    assert!(
        consts.contains("const FEATURE_GLASS: bool = false;"),
        "{consts}"
    );
    assert!(
        consts.contains("const FEATURE_DIFFUSE: bool = true;"),
        "{consts}"
    );
}

#[test]
fn lobes_follow_the_materials_and_graphs() {
    let mut scene = default_scene().unwrap();
    let glass = scene.add_material(Material {
        name: "glass".into(),
        principled: Principled {
            transmission_weight: 1.0,
            ..Principled::default()
        },
        ..Material::default()
    });
    scene.instances[0].material = glass;
    assert_eq!(features(&scene).lobes & lobes::GLASS, lobes::GLASS);
    // A graph whose metallic varies could be metal anywhere.
    assert_eq!(
        varying("metallic").lobes(),
        lobes::METAL | lobes::DIFFUSE | lobes::SPECULAR
    );
    // An alpha that varies may cut the surface out anywhere.
    assert_eq!(varying("alpha").lobes() & lobes::CUTOUT, lobes::CUTOUT);

    let f = features(&cutout_glass_and_catcher());
    assert_eq!(
        f.lobes & (lobes::CUTOUT | lobes::GLASS),
        lobes::CUTOUT | lobes::GLASS
    );
    assert!(f.shadow_catcher, "{f:?}");
}

/// A graph material whose principled `input` varies over the surface (a noise texture).
fn varying(input: &str) -> Material {
    let text = format!(
        r#"(version: 1, nodes: {{
        "n": (type: "noise_texture"),
        "s": (type: "principled_bsdf", inputs: {{ "{input}": "n.fac" }}),
        "o": (type: "material_output", inputs: {{ "surface": "s.bsdf" }}),
    }})"#
    );
    let (_, graph) = kiln::material::parse_material(&text, "m.kmat").unwrap();
    Material::from_graph(&format!("varying {input}"), graph).unwrap()
}

/// The Cornell box with what a specialised kernel leaves out unless the scene has it: a
/// cut-out (the short block at alpha ½), a medium (the tall block of glass) and a shadow
/// catcher (the floor).
fn cutout_glass_and_catcher() -> Scene {
    let mut scene = default_scene().unwrap();
    let half = scene.add_material(Material {
        name: "half".into(),
        principled: Principled {
            alpha: 0.5,
            ..Principled::default()
        },
        ..Material::default()
    });
    let glass = scene.add_material(Material {
        name: "tinted glass".into(),
        principled: Principled {
            transmission_weight: 1.0,
            transmission_color: glam::Vec3::new(0.9, 0.5, 0.3),
            transmission_depth: 100.0,
            ..Principled::default()
        },
        ..Material::default()
    });
    scene.instances[6].material = half;
    scene.instances[7].material = glass;
    scene.instances[0].shadow_catcher = true;
    scene
}

#[test]
fn specialised_and_everything_kernels_render_the_same_image() {
    let scenes = [
        default_scene().unwrap(),
        kiln::scene::load_scene(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/assets/scenes/materials.kiln"
        )))
        .unwrap(),
        cutout_glass_and_catcher(),
    ];
    for scene in scenes {
        let mut s = settings(48, 32, 16);
        let special = render(&gpu(), &scene, s).radiance();
        s.kernel = KernelKind::General;
        let everything = render(&gpu(), &scene, s).radiance();
        let error = rmse(&special, &everything) / mean(&everything).max_element() as f64;
        assert!(error < 1e-4, "images differ: relative RMSE {error}");
    }
}
