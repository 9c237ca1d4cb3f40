//! Point, sphere, spot and distant lights against closed-form irradiance: a matte plane
//! of albedo 0.5 seen straight down through a 2° field of view (every pixel sees nearly
//! the same point), lit directly, reflects L = albedo / π · E.

mod common;

use common::{gpu, mean, render, run_scene_kernel, settings};
use glam::{Affine3A, Vec3};
use kiln::scene::{Camera, Light, Material, Scene, shapes};

const ALBEDO: f32 = 0.5;

fn lit_plane(light: Light) -> f32 {
    lit_plane_with(light, true, 64)
}

fn lit_plane_with(light: Light, light_sampling: bool, spp: u32) -> f32 {
    let mut scene = matte_plane();
    scene.add_light(light);
    plane_radiance(&scene, light_sampling, spp)
}

/// The matte plane seen straight down, unlit.
fn matte_plane() -> Scene {
    let mut scene = Scene::empty(Camera {
        up: Vec3::Z,
        ..Camera::look_at(Vec3::new(0.0, 1.0, 0.0), Vec3::ZERO, 2.0)
    });
    let m = scene.add_material(Material::diffuse("matte", Vec3::splat(ALBEDO)));
    let quad = scene.add_mesh(shapes::quad());
    scene.add_instance(quad, m, Affine3A::from_scale(Vec3::splat(100.0)));
    scene
}

/// Adds a unit quad emitting `radiance`, turned to face down, at `placement` (applied
/// after the turn).
fn add_lamp_facing_down(scene: &mut Scene, radiance: f32, placement: Affine3A) {
    let lamp = scene.add_material(Material::emitter("lamp", Vec3::splat(radiance)));
    let quad = scene.add_mesh(shapes::quad());
    scene.add_instance(
        quad,
        lamp,
        placement * Affine3A::from_rotation_x(std::f32::consts::PI),
    );
}

/// The mean radiance of `scene` (a [`matte_plane`] with lights) by direct light alone.
fn plane_radiance(scene: &Scene, light_sampling: bool, spp: u32) -> f32 {
    let mut s = settings(8, 8, spp);
    s.max_bounces = 1;
    s.light_sampling = light_sampling;
    mean(&render(&gpu(), scene, s).radiance()).x
}

fn expected(irradiance: f32) -> f32 {
    ALBEDO / std::f32::consts::PI * irradiance
}

fn assert_close(name: &str, got: f32, want: f32, tolerance: f32) {
    assert!(
        (got - want).abs() <= tolerance * want.max(1e-6),
        "{name}: {got}, expected {want} ± {:.1}%",
        tolerance * 100.0
    );
}

#[test]
fn point_and_sphere_lights_give_inverse_square_irradiance() {
    let point = Light::Point {
        position: Vec3::new(0.0, 2.0, 0.0),
        intensity: Vec3::splat(10.0),
        radius: 0.0,
    };
    assert_close("point light", lit_plane(point), expected(10.0 / 4.0), 0.005);
    // A sphere of radiance I / (π r²) delivers I / d² to the point below its centre.
    let sphere = Light::Point {
        position: Vec3::new(0.0, 2.0, 0.0),
        intensity: Vec3::splat(10.0),
        radius: 0.5,
    };
    assert_close(
        "sphere light",
        lit_plane(sphere),
        expected(10.0 / 4.0),
        0.02,
    );
}

#[test]
fn spot_light_lights_inside_its_cone_only() {
    let spot = |direction: Vec3| Light::Spot {
        position: Vec3::new(0.0, 2.0, 0.0),
        direction,
        intensity: Vec3::splat(10.0),
        cone_angle: 30.0,
        blend: 0.2,
        radius: 0.0,
    };
    assert_close(
        "spot pointing down",
        lit_plane(spot(-Vec3::Y)),
        expected(2.5),
        0.005,
    );
    assert_eq!(
        lit_plane(spot(Vec3::Y)),
        0.0,
        "a spot pointing away lights the plane"
    );
    // 40° off the axis is outside the 30° cone.
    let tilted = Vec3::new(40f32.to_radians().sin(), -40f32.to_radians().cos(), 0.0);
    assert_eq!(lit_plane(spot(tilted)), 0.0, "light outside the cone");
}

#[test]
fn distant_light_gives_cosine_weighted_irradiance() {
    let sun = |degrees: f32, angular_diameter: f32| Light::Distant {
        direction: Vec3::new(degrees.to_radians().sin(), -degrees.to_radians().cos(), 0.0),
        irradiance: Vec3::splat(3.0),
        angular_diameter,
    };
    assert_close(
        "overhead delta sun",
        lit_plane(sun(0.0, 0.0)),
        expected(3.0),
        0.005,
    );
    assert_close(
        "overhead sun disk",
        lit_plane(sun(0.0, 0.53)),
        expected(3.0),
        0.01,
    );
    assert_close(
        "sun at 60°",
        lit_plane(sun(60.0, 0.53)),
        expected(1.5),
        0.01,
    );
    assert_eq!(
        lit_plane(sun(120.0, 0.0)),
        0.0,
        "a sun below the horizon lights the plane"
    );
}

#[test]
fn area_lights_are_found_by_bsdf_rays_too() {
    // Sphere lights and sun disks are hit by BSDF-sampled rays, so rendering without light
    // sampling converges to the same irradiance, and with both strategies MIS weighs them
    // without double counting. Each light fills about 3% of the cosine-weighted
    // hemisphere: 2^18 BSDF samples give a relative standard deviation near 1.1%.
    let cases = [
        (
            "sphere light",
            Light::Point {
                position: Vec3::new(0.0, 2.0, 0.0),
                intensity: Vec3::splat(10.0),
                radius: 0.5,
            },
            2.5,
        ),
        (
            "spot light with a radius",
            Light::Spot {
                position: Vec3::new(0.0, 2.0, 0.0),
                direction: -Vec3::Y,
                intensity: Vec3::splat(10.0),
                cone_angle: 120.0,
                blend: 0.0,
                radius: 0.5,
            },
            2.5,
        ),
        (
            "wide sun disk",
            Light::Distant {
                direction: -Vec3::Y,
                irradiance: Vec3::splat(3.0),
                angular_diameter: 30.0,
            },
            3.0,
        ),
    ];
    for (name, light, irradiance) in cases {
        let want = expected(irradiance);
        let mis = lit_plane_with(light.clone(), true, 1024);
        assert_close(&format!("{name}, NEE + MIS"), mis, want, 0.01);
        let bsdf_only = lit_plane_with(light, false, 4096);
        assert_close(
            &format!("{name}, BSDF sampling only"),
            bsdf_only,
            want,
            0.045,
        );
    }
}

#[test]
fn light_samples_split_between_sky_sun_and_lamps_keep_the_image() {
    // Next-event estimation splits its samples at each shading point between the lights
    // at infinity and the local ones (src/render/light_distribution.rs): under a sky, a
    // wide sun disk and an emissive quad off to the side, NEE + MIS must converge to what
    // BSDF sampling alone finds. The split picks the quad for about half the samples here,
    // the sun and the sky by their irradiance for the rest.
    let mut scene = matte_plane();
    scene.environment = Vec3::splat(0.2);
    // 25°-48° off the vertical seen from the origin: clear of the sun.
    add_lamp_facing_down(
        &mut scene,
        20.0,
        Affine3A::from_translation(Vec3::new(1.2, 1.5, 0.0)),
    );
    scene.add_light(Light::Distant {
        direction: -Vec3::Y,
        irradiance: Vec3::splat(3.0),
        angular_diameter: 30.0,
    });
    let mis = plane_radiance(&scene, true, 1024);
    let bsdf_only = plane_radiance(&scene, false, 16384);
    // The sky alone gives 0.2 π, the sun 3: the lamp adds to both.
    assert!(mis > expected(0.2 * std::f32::consts::PI + 3.0), "{mis}");
    assert_close("NEE + MIS against BSDF sampling", mis, bsdf_only, 0.015);
}

#[test]
fn a_light_sample_has_the_density_mis_weighs_that_light_by() {
    // Every kind of light at once, at shading points spread from beside the lamps to
    // far below them, so that the split between the sky and sun and the local lights
    // varies: the density of each light sample must be the one the integrator gives a
    // BSDF ray that reaches the same light, or MIS would be biased.
    let mut scene = Scene::empty(Camera::look_at(Vec3::Z, Vec3::ZERO, 40.0));
    scene.environment = Vec3::new(0.3, 0.4, 0.5);
    add_lamp_facing_down(
        &mut scene,
        5.0,
        Affine3A::from_translation(Vec3::new(0.0, 2.0, 0.0))
            * Affine3A::from_scale(Vec3::splat(2.0)),
    );
    scene.lights = [
        Light::Point {
            // Off the sun's side: a BSDF ray toward the sun that met the sphere would end on
            // it (sphere lights are opaque to rays, but cast no shadow).
            position: Vec3::new(-3.0, 1.5, 0.0),
            intensity: Vec3::splat(10.0),
            radius: 0.4,
        },
        Light::Point {
            position: Vec3::new(3.0, 2.0, 1.0),
            intensity: Vec3::splat(4.0),
            radius: 0.0,
        },
        Light::Distant {
            direction: Vec3::new(-0.3, -1.0, -0.2),
            irradiance: Vec3::splat(2.0),
            angular_diameter: 10.0,
        },
    ]
    .map(Into::into)
    .to_vec();
    let samples = 1u32 << 14;
    let corner = |v: Vec3| {
        let [x, y, z] = v.to_array().map(f32::to_bits);
        [x, y, z, 0]
    };
    let input = [
        [samples, 11, 0, 0],
        corner(Vec3::new(-2.0, -6.0, -2.0)),
        corner(Vec3::new(2.0, 1.0, 2.0)),
    ];
    let out = run_scene_kernel(
        &scene,
        (
            "shaders/tests/light_probe.wgsl",
            include_str!("../shaders/tests/light_probe.wgsl"),
        ),
        "light_probe",
        bytemuck::cast_slice(&input),
        16 * samples as u64,
        samples,
    );
    let rows: &[[u32; 4]] = bytemuck::cast_slice(&out);
    let mut per_kind = [0u32; 3];
    for (i, &[kind, sampled, weighed, _]) in rows.iter().enumerate() {
        if kind == u32::MAX {
            // The point light: a delta, which no BSDF ray reaches.
            continue;
        }
        per_kind[kind as usize] += 1;
        let (sampled, weighed) = (f32::from_bits(sampled), f32::from_bits(weighed));
        assert!(
            (sampled - weighed).abs() <= 1e-3 * sampled,
            "sample {i} of kind {kind}: sampled with density {sampled}, weighed by {weighed}"
        );
    }
    // The environment, the quad and the sphere light and sun disk each get their share.
    for (kind, count) in per_kind.iter().enumerate() {
        assert!(
            *count > samples / 20,
            "light kind {kind} sampled {count} times of {samples}: {per_kind:?}"
        );
    }
}
