//! The firefly clamp (`Clamp`, Cycles' Light Paths ▸ Clamping): it only ever takes light
//! away, keeps each contribution's colour, splits direct from indirect light where Cycles
//! does, and changes nothing when off.

mod common;

use common::{gpu, mean, render, settings};
use glam::{Affine3A, Quat, Vec3};
use kiln::render::RenderSettings;
use kiln::scene::{Camera, Clamp, Material, Scene, shapes};

/// The emitter's radiance: its largest channel is 17.
const EMISSION: Vec3 = Vec3::new(17.0, 12.0, 4.0);

/// A matte floor lit by a small bright quad above it, both seen by the camera, and a
/// white sphere beside the light's footprint that bounces light onto the floor (indirect
/// light).
fn scene() -> Scene {
    let mut scene = Scene::empty(Camera::look_at(
        Vec3::new(0.0, 2.0, 4.0),
        Vec3::new(0.0, 0.5, 0.0),
        45.0,
    ));
    let matte = scene.add_material(Material::diffuse("floor", Vec3::splat(0.8)));
    let light = scene.add_material(Material::emitter("light", EMISSION));
    let quad = scene.add_mesh(shapes::quad());
    scene.add_instance(quad, matte, Affine3A::from_scale(Vec3::splat(10.0)));
    // Facing down (the quad faces +y), above the floor and in view.
    scene.add_instance(
        quad,
        light,
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.6),
            Quat::from_rotation_x(std::f32::consts::PI),
            Vec3::new(0.0, 1.5, 0.0),
        ),
    );
    let sphere = scene.add_mesh(shapes::uv_sphere(32, 16, true));
    let white = scene.add_material(Material::diffuse("sphere", Vec3::splat(0.9)));
    scene.add_instance(
        sphere,
        white,
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.4),
            Quat::IDENTITY,
            Vec3::new(0.8, 0.4, 0.0),
        ),
    );
    scene
}

fn clamped(direct: f32, indirect: f32) -> RenderSettings {
    RenderSettings {
        clamp: Clamp { direct, indirect },
        ..settings(48, 32, 16)
    }
}

#[test]
fn a_clamp_only_takes_light_away_pixel_by_pixel() {
    let ctx = gpu();
    let scene = scene();
    let free = render(&ctx, &scene, clamped(0.0, 0.0)).radiance();
    for (direct, indirect) in [(1.0, 0.0), (0.0, 0.05), (2.0, 0.1)] {
        let cut = render(&ctx, &scene, clamped(direct, indirect)).radiance();
        // The same seed draws the same paths: each contribution is scaled by at most one.
        for (i, (c, f)) in cut.iter().zip(&free).enumerate() {
            assert!(
                c.cmple(*f * (1.0 + 1e-5) + 1e-6).all(),
                "clamp ({direct}, {indirect}): pixel {i} is {c}, brighter than unclamped {f}"
            );
        }
        let (c, f) = (mean(&cut), mean(&free));
        assert!(
            c.x < f.x * 0.999,
            "clamp ({direct}, {indirect}) took no light away: mean {c} against {f}"
        );
    }
}

#[test]
fn a_limit_far_above_the_scene_changes_no_bit() {
    let ctx = gpu();
    let scene = scene();
    let free = render(&ctx, &scene, clamped(0.0, 0.0)).radiance();
    let loose = render(&ctx, &scene, clamped(1.0e30, 1.0e30)).radiance();
    assert!(free == loose, "a clamp no sample reaches changed the image");
}

#[test]
fn the_direct_clamp_caps_the_light_seen_and_keeps_its_colour() {
    // Seen directly, the emitter is direct light: with the direct limit at 1 its pixels
    // are its colour scaled to a largest channel of 1; the indirect limit does not touch it.
    let ctx = gpu();
    let mut scene = scene();
    scene.camera = Camera {
        up: Vec3::Z,
        ..Camera::look_at(Vec3::new(0.0, 0.2, 0.0), Vec3::new(0.0, 1.5, 0.0), 10.0)
    };
    let square = |direct, indirect| RenderSettings {
        width: 16,
        height: 16,
        ..clamped(direct, indirect)
    };
    let only_indirect = mean(&render(&ctx, &scene, square(0.0, 0.5)).radiance());
    assert!(
        (only_indirect - EMISSION).abs().max_element() < 1e-3 * EMISSION.x,
        "the indirect clamp cut direct light: {only_indirect}"
    );
    let direct = mean(&render(&ctx, &scene, square(1.0, 0.0)).radiance());
    let want = EMISSION / EMISSION.x;
    assert!(
        (direct - want).abs().max_element() < 1e-4,
        "the emitter under a direct clamp of 1: {direct}, expected {want}"
    );
}

#[test]
fn a_negative_or_infinite_limit_is_refused() {
    for bad in [-1.0, f32::NAN, f32::INFINITY] {
        let clamp = Clamp {
            direct: 0.0,
            indirect: bad,
        };
        let err = clamp.validate().expect_err("a bad limit is refused");
        assert!(err.contains("indirect"), "{err}");
    }
}

#[test]
fn light_that_scattered_once_is_direct_and_twice_indirect() {
    // With one bounce every path carries direct light alone (the emitter seen, and the
    // floor and sphere lit by it, sampled both ways): an indirect limit changes no bit.
    let ctx = gpu();
    let scene = scene();
    let one_bounce = |direct, indirect| RenderSettings {
        max_bounces: 1,
        ..clamped(direct, indirect)
    };
    let free = render(&ctx, &scene, one_bounce(0.0, 0.0)).radiance();
    let indirect_cut = render(&ctx, &scene, one_bounce(0.0, 1.0e-3)).radiance();
    assert!(free == indirect_cut, "an indirect limit cut direct light");
    let direct_cut = mean(&render(&ctx, &scene, one_bounce(1.0e-3, 0.0)).radiance());
    // At most two direct contributions a sample: the light sampled, and found by the BSDF.
    assert!(
        direct_cut.max_element() < 2.0e-3 * 1.01,
        "a direct limit of 0.001 left {direct_cut} of the direct light"
    );
    // A second bounce brings indirect light, which the indirect limit does cut.
    let two = |indirect| RenderSettings {
        max_bounces: 2,
        ..clamped(0.0, indirect)
    };
    let free = mean(&render(&ctx, &scene, two(0.0)).radiance());
    let cut = mean(&render(&ctx, &scene, two(1.0e-3)).radiance());
    assert!(
        cut.x < free.x * 0.999,
        "an indirect limit left the second bounce whole: {cut} against {free}"
    );
}
