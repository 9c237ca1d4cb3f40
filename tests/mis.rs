//! Multiple importance sampling must never be worse than BSDF sampling alone: a glass, a
//! rough gold and a coated sphere under an HDR sky with a small bright sun and a small,
//! bright area light,
//! rendered with both strategies over several seeds. Both converge to the same image, and
//! the pixel variance with NEE + MIS is at most that of BSDF sampling (within the noise of
//! the variance estimate itself).
//!
//! Cut-outs let light through shadow rays as camera paths pass them: a floor in the shadow
//! of a half-transparent plane comes out the same with and without light sampling.

mod common;

use common::{gpu, render, settings};
use glam::{Affine3A, Vec3};
use kiln::scene::{Camera, EnvironmentMap, Material, Scene, shapes};
use kiln::shader::principled::Principled;

const SEEDS: u32 = 8;
const SIZE: u32 = 24;

fn scene(material: Material) -> Scene {
    let mut scene = Scene::empty(Camera::look_at(
        Vec3::new(0.0, 0.6, 3.0),
        Vec3::new(0.0, 0.3, 0.0),
        40.0,
    ));
    // An HDR sky: dim blue gradient with a small sun 100× brighter.
    let (w, h) = (64u32, 32u32);
    let texels = (0..h)
        .flat_map(|y| {
            (0..w).map(move |x| {
                if (40..43).contains(&x) && (6..8).contains(&y) {
                    Vec3::new(60.0, 55.0, 50.0)
                } else {
                    Vec3::new(0.2, 0.25, 0.3 + 0.2 * y as f32 / h as f32)
                }
            })
        })
        .collect();
    scene.environment_map = Some(EnvironmentMap {
        width: w,
        height: h,
        texels,
        strength: 1.0,
        rotation_degrees: 0.0,
    });
    let m = scene.add_material(material);
    let floor = scene.add_material(Material::diffuse("floor", Vec3::splat(0.5)));
    let lamp = scene.add_material(Material::emitter("lamp", Vec3::splat(40.0)));
    let sphere = scene.add_mesh(shapes::uv_sphere(48, 24, true));
    let quad = scene.add_mesh(shapes::quad());
    scene.add_instance(
        sphere,
        m,
        Affine3A::from_translation(Vec3::new(0.0, 0.5, 0.0))
            * Affine3A::from_scale(Vec3::splat(0.5)),
    );
    scene.add_instance(quad, floor, Affine3A::from_scale(Vec3::splat(8.0)));
    scene.add_instance(
        quad,
        lamp,
        Affine3A::from_translation(Vec3::new(1.0, 2.5, 1.0))
            * Affine3A::from_rotation_x(std::f32::consts::PI)
            * Affine3A::from_scale(Vec3::splat(0.4)),
    );
    scene
}

/// A floor lit by an area light through a plane with `cutout`'s alpha, seen from
/// below the plane: most of what the camera sees lies in its shadow.
fn cutout_scene(cutout: Material) -> Scene {
    let mut scene = Scene::empty(Camera::look_at(
        Vec3::new(0.0, 0.5, 2.0),
        Vec3::new(0.0, 0.0, 0.0),
        40.0,
    ));
    let cutout = scene.add_material(cutout);
    let floor = scene.add_material(Material::diffuse("floor", Vec3::splat(0.5)));
    let lamp = scene.add_material(Material::emitter("lamp", Vec3::splat(6.0)));
    let quad = scene.add_mesh(shapes::quad());
    scene.add_instance(quad, floor, Affine3A::from_scale(Vec3::splat(8.0)));
    scene.add_instance(
        quad,
        cutout,
        Affine3A::from_translation(Vec3::new(0.0, 0.8, 0.0))
            * Affine3A::from_scale(Vec3::splat(2.0)),
    );
    scene.add_instance(
        quad,
        lamp,
        Affine3A::from_translation(Vec3::new(0.0, 2.0, 0.0))
            * Affine3A::from_rotation_x(std::f32::consts::PI)
            * Affine3A::from_scale(Vec3::splat(0.8)),
    );
    scene
}

/// Mean image and mean per-pixel variance (over seeds) of one strategy.
fn statistics(scene: &Scene, light_sampling: bool) -> (f64, f64) {
    let ctx = gpu();
    let images: Vec<Vec<Vec3>> = (0..SEEDS)
        .map(|seed| {
            let mut s = settings(SIZE, SIZE, 16);
            s.seed = seed;
            s.max_bounces = 8;
            s.light_sampling = light_sampling;
            render(&ctx, scene, s).radiance()
        })
        .collect();
    let pixels = images[0].len();
    let mut mean_sum = 0.0;
    let mut variance_sum = 0.0;
    for p in 0..pixels {
        let values: Vec<f64> = images
            .iter()
            .map(|img| img[p].element_sum() as f64 / 3.0)
            .collect();
        let m = values.iter().sum::<f64>() / SEEDS as f64;
        let v = values.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (SEEDS - 1) as f64;
        mean_sum += m;
        variance_sum += v;
    }
    (mean_sum / pixels as f64, variance_sum / pixels as f64)
}

#[test]
fn mis_is_never_noisier_than_bsdf_sampling_and_agrees_with_it() {
    let materials = [
        (
            "glass",
            Material {
                principled: Principled {
                    transmission_weight: 1.0,
                    roughness: 0.0,
                    ..Principled::default()
                },
                ..Material::default()
            },
        ),
        (
            "rough gold",
            Material {
                principled: Principled {
                    base_color: Vec3::new(1.0, 0.78, 0.34),
                    metallic: 1.0,
                    roughness: 0.35,
                    ..Principled::default()
                },
                ..Material::default()
            },
        ),
        (
            "coated red",
            Material {
                principled: Principled {
                    base_color: Vec3::new(0.6, 0.05, 0.05),
                    coat_weight: 1.0,
                    coat_roughness: 0.05,
                    ..Principled::default()
                },
                ..Material::default()
            },
        ),
    ];
    for (name, material) in materials {
        let scene = scene(material);
        let (mean_mis, var_mis) = statistics(&scene, true);
        let (mean_bsdf, var_bsdf) = statistics(&scene, false);
        eprintln!(
            "{name}: mean {mean_mis:.4} vs {mean_bsdf:.4}, variance {var_mis:.5} vs {var_bsdf:.5}"
        );
        // The variance estimate from 8 seeds is itself uncertain by ~sqrt(2/7) per pixel;
        // averaged over 576 pixels, 15% covers it.
        assert!(
            var_mis <= 1.15 * var_bsdf,
            "{name}: MIS variance {var_mis} > BSDF variance {var_bsdf}"
        );
        // Same expectation: the difference of means is within a few standard errors.
        let standard_error = ((var_mis + var_bsdf) / (SEEDS as f64 * (SIZE * SIZE) as f64)).sqrt();
        assert!(
            (mean_mis - mean_bsdf).abs() < 0.02 * mean_bsdf + 5.0 * standard_error,
            "{name}: means differ, {mean_mis} vs {mean_bsdf}"
        );
    }
}

#[test]
fn shadows_through_cutouts_agree_with_bsdf_sampling() {
    let constant = Material {
        name: "half".into(),
        principled: Principled {
            base_color: Vec3::splat(0.8),
            alpha: 0.5,
            ..Principled::default()
        },
        ..Material::default()
    };
    // Alpha from a texture: shadow rays evaluate the graph where they cross it.
    let (_, graph) = kiln::material::parse_material(
        r#"(version: 1, nodes: {
            "n": (type: "noise_texture", inputs: { "scale": 3.0 }),
            "s": (type: "principled_bsdf", inputs: { "alpha": "n.fac" }),
            "o": (type: "material_output", inputs: { "surface": "s.bsdf" }),
        })"#,
        "cutout.kmat",
    )
    .unwrap();
    let textured = Material::from_graph("noise alpha", graph).unwrap();
    for material in [constant, textured] {
        let name = material.name.clone();
        let scene = cutout_scene(material);
        let (mean_nee, var_nee) = statistics(&scene, true);
        let (mean_bsdf, var_bsdf) = statistics(&scene, false);
        // Shadow rays stopped by the cut-out would leave the light-sampled floor about
        // half as bright in its shadow.
        let standard_error = ((var_nee + var_bsdf) / (SEEDS as f64 * (SIZE * SIZE) as f64)).sqrt();
        eprintln!(
            "{name}: mean {mean_nee:.4} (light sampling) vs {mean_bsdf:.4} (BSDF only), \
             standard error {standard_error:.4}"
        );
        assert!(
            (mean_nee - mean_bsdf).abs() < 0.03 * mean_bsdf + 5.0 * standard_error,
            "{name}: means differ, {mean_nee} (light sampling) vs {mean_bsdf} (BSDF only)"
        );
    }
}
