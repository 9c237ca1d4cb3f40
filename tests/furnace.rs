//! White-furnace tests: in a uniform environment, a closed object of albedo 1 is invisible,
//! and a convex object of albedo a reflects exactly a times the environment. Run with BSDF
//! sampling alone and with next-event estimation + MIS, which must agree.

mod common;

use common::{furnace_scene, gpu, mean, render, settings};
use glam::{Affine3A, Vec3};
use kiln::scene::{Camera, Material, Scene, shapes};

const SIZE: u32 = 24;

fn check_albedo_one(light_sampling: bool, spp: u32, pixel_tolerance: f32) {
    let ctx = gpu();
    let mut s = settings(SIZE, SIZE, spp);
    s.light_sampling = light_sampling;
    let film = render(&ctx, &furnace_scene(1.0, 1.0), s);
    let px = film.radiance();
    let m = mean(&px);
    assert!(
        (m - Vec3::ONE).abs().max_element() < 0.005,
        "mean {m}, expected 1"
    );
    for (i, p) in px.iter().enumerate() {
        assert!(
            (*p - Vec3::ONE).abs().max_element() < pixel_tolerance,
            "pixel {i} = {p}, expected 1 ± {pixel_tolerance}"
        );
    }
}

#[test]
fn furnace_albedo_one_is_one_with_bsdf_sampling() {
    // Every path escapes after one bounce with weight exactly 1: no noise at all.
    check_albedo_one(false, 16, 1e-5);
}

#[test]
fn furnace_albedo_one_is_one_with_light_sampling_and_mis() {
    check_albedo_one(true, 512, 0.05);
}

/// Albedo 0.5: pixels covered by the sphere read 0.5, the rest 1. Coverage comes from an
/// albedo-0 render with the same seed, whose camera rays are the same.
fn check_albedo_half(light_sampling: bool, spp: u32, pixel_tolerance: f32) {
    let ctx = gpu();
    let mut s = settings(SIZE, SIZE, spp);
    s.light_sampling = light_sampling;
    let half = render(&ctx, &furnace_scene(0.5, 1.0), s).radiance();
    let black = render(&ctx, &furnace_scene(0.0, 1.0), s).radiance();
    let mut covered = 0;
    let mut sum_error = Vec3::ZERO;
    for (i, (h, b)) in half.iter().zip(&black).enumerate() {
        let coverage = 1.0 - b.x;
        let expected = 1.0 - 0.5 * coverage;
        let err = (*h - Vec3::splat(expected)).abs().max_element();
        assert!(
            err < pixel_tolerance,
            "pixel {i} = {h}, expected {expected} ± {pixel_tolerance}"
        );
        sum_error += *h - Vec3::splat(expected);
        if coverage > 0.999 {
            covered += 1;
        }
    }
    let mean_error = sum_error / half.len() as f32;
    assert!(
        mean_error.abs().max_element() < 0.003,
        "mean error {mean_error}"
    );
    assert!(
        covered > (SIZE * SIZE / 3) as usize,
        "the sphere covers only {covered} pixels"
    );
}

#[test]
fn furnace_albedo_half_is_half_with_bsdf_sampling() {
    // One bounce then escape: each covered sample is exactly 0.5.
    check_albedo_half(false, 64, 1e-4);
}

#[test]
fn furnace_albedo_half_is_half_with_light_sampling_and_mis() {
    check_albedo_half(true, 512, 0.04);
}

/// A white sphere inside a closed box whose walls emit 1 and reflect nothing, seen from
/// inside: every pixel is 1. This exercises next-event estimation of emissive triangles
/// and its MIS weights against BSDF hits on the same triangles.
#[test]
fn emissive_enclosure_furnace_is_one_with_triangle_light_sampling() {
    let ctx = gpu();
    let mut scene = Scene::empty(Camera::look_at(Vec3::new(0.0, 0.0, 1.8), Vec3::ZERO, 70.0));
    let white = scene.add_material(Material::diffuse("white", Vec3::ONE));
    let wall = scene.add_material(Material {
        name: "emitter".into(),
        base_color: Vec3::ZERO,
        emission: Vec3::ONE,
    });
    let sphere = scene.add_mesh(shapes::uv_sphere(32, 16, false));
    let mut cube = shapes::cube();
    // Turn the faces inward so they emit into the box.
    for t in &mut cube.indices {
        t.swap(1, 2);
    }
    let cube = scene.add_mesh(cube);
    scene.add_instance(sphere, white, Affine3A::from_scale(Vec3::splat(0.5)));
    scene.add_instance(cube, wall, Affine3A::from_scale(Vec3::splat(4.0)));
    for light_sampling in [false, true] {
        let mut s = settings(SIZE, SIZE, 256);
        s.light_sampling = light_sampling;
        let px = render(&ctx, &scene, s).radiance();
        let m = mean(&px);
        assert!(
            (m - Vec3::ONE).abs().max_element() < 0.01,
            "light sampling {light_sampling}: mean {m}"
        );
        for (i, p) in px.iter().enumerate() {
            assert!(
                (*p - Vec3::ONE).abs().max_element() < 0.1,
                "light sampling {light_sampling}: pixel {i} = {p}"
            );
        }
    }
}
