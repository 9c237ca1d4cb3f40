//! HDR environment maps: importance sampling passes a chi-square test against its pdf, a
//! constant map gives the furnace result, lookups follow the map's orientation and
//! rotation, and maps load from scene files.

mod common;

use common::chi2::{SphereBins, chi2_conditional};
use common::{furnace_scene, gpu, mean, render, settings};
use glam::Vec3;
use kiln::render::probe::{Probe, run_probe};
use kiln::scene::{Camera, EnvironmentMap, Scene};

/// A 64 × 32 sky: a gradient, a bright sun and a dark band, so the distribution is far
/// from uniform.
fn test_map() -> EnvironmentMap {
    let (w, h) = (64u32, 32u32);
    let mut texels = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let mut c = Vec3::new(0.2 + x as f32 / w as f32, 0.3, 0.1 + y as f32 / h as f32);
            if (20..24).contains(&x) && (8..11).contains(&y) {
                c *= 200.0;
            }
            if y == 20 {
                c = Vec3::ZERO;
            }
            texels.push(c);
        }
    }
    EnvironmentMap {
        width: w,
        height: h,
        texels,
        strength: 1.5,
        rotation_degrees: 30.0,
    }
}

fn scene_with(map: EnvironmentMap) -> Scene {
    let mut scene = Scene::empty(Camera::look_at(Vec3::ZERO, -Vec3::Z, 1.0));
    scene.environment_map = Some(map);
    scene
}

fn probe(scene: &Scene, entry: &str, input: &[[u32; 4]], words: u64, invocations: u32) -> Vec<u32> {
    let out = run_probe(
        &gpu(),
        scene,
        &settings(1, 1, 1),
        &Probe {
            name: entry,
            parts: &[
                ("lobe kind", "const LOBE_KIND: u32 = ANY_KIND;"),
                (
                    "shaders/tests/lobe_dispatch.wgsl",
                    include_str!("../shaders/tests/lobe_dispatch.wgsl"),
                ),
                (
                    "shaders/tests/env_probe.wgsl",
                    include_str!("../shaders/tests/env_probe.wgsl"),
                ),
            ],
            entry,
            input: bytemuck::cast_slice(input),
            output_bytes: 4 * words,
            invocations,
            material_params: &[],
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    bytemuck::cast_slice(&out).to_vec()
}

#[test]
fn environment_sampling_passes_chi_square_against_its_pdf() {
    assert_sampling_matches_pdf(test_map());
}

/// A world graph's bake (a clear sky, its sun left to a light) is sampled by its pdf too.
#[test]
fn a_baked_sky_passes_chi_square_against_its_pdf() {
    let mut world = kiln::scene::lookdev::world();
    world.resolution = 64;
    let baked = kiln::render::world_bake::bake_world(&gpu(), &world).expect("bake");
    let kiln::render::world_bake::Environment::Map(map) = baked.environment else {
        panic!("a sky bakes into a map")
    };
    assert_sampling_matches_pdf(map);
}

/// Samples `map` by importance and checks the directions' histogram against its pdf.
fn assert_sampling_matches_pdf(map: EnvironmentMap) {
    let scene = scene_with(map);
    let samples = 1u32 << 20;
    let bins = SphereBins::for_sample_count(samples as usize);
    let cells = bins.cell_count() as u32;
    let input = [
        [samples, 9, bins.theta_bins as u32, bins.phi_bins as u32],
        [0, 0, 24, 0],
    ];
    let counts = probe(&scene, "env_sample", &input, cells as u64 + 1, samples);
    let pdf = probe(&scene, "env_pdf", &input, cells as u64, cells);
    let observed: Vec<u64> = counts[..cells as usize].iter().map(|&c| c as u64).collect();
    assert_eq!(counts[cells as usize], 0, "invalid environment samples");
    let expected: Vec<f64> = pdf.iter().map(|&b| f32::from_bits(b) as f64).collect();
    let integral: f64 = expected.iter().sum();
    assert!(
        (integral - 1.0).abs() < 5e-3,
        "the pdf integrates to {integral}"
    );
    // Directions are computed with the GPU's sin and cos, which Vulkan lets err by 2^-11:
    // a sample at the very edge of a texel next to a black one can land in a cell the pdf
    // gives nothing. At most 1e-4 of the samples may; they are left out of the test.
    // The integral was just bounded by 5e-3; the same bound keeps chi2_conditional's.
    let (outcome, stray) = chi2_conditional(&observed, &expected, 5e-3);
    assert!(
        stray as f64 <= 1e-4 * samples as f64,
        "{stray} samples where the pdf is 0"
    );
    assert!(
        outcome.p_value > 0.01,
        "p = {:.3e}\n{}",
        outcome.p_value,
        outcome.report
    );
}

#[test]
fn constant_environment_map_gives_the_furnace_result() {
    let ctx = gpu();
    let mut scene = furnace_scene(1.0, 0.0);
    scene.environment_map = Some(EnvironmentMap::constant(Vec3::ONE, 16, 8));
    for light_sampling in [false, true] {
        let mut s = settings(16, 16, 256);
        s.light_sampling = light_sampling;
        let m = mean(&render(&ctx, &scene, s).radiance());
        assert!(
            (m - Vec3::ONE).abs().max_element() < 0.01,
            "light sampling {light_sampling}: {m}"
        );
    }
}

#[test]
fn lookup_follows_orientation_strength_and_rotation() {
    let ctx = gpu();
    let mut map = EnvironmentMap::constant(Vec3::ZERO, 4, 2);
    // Texel (2, 0): upper half, u in [0.5, 0.75): seen looking toward −Z then turning to +X.
    map.texels[2] = Vec3::new(1.0, 2.0, 3.0);
    map.strength = 2.0;
    let look = |map: &EnvironmentMap, dir: Vec3| {
        let mut scene = scene_with(map.clone());
        scene.camera = Camera::look_at(Vec3::ZERO, dir, 1.0);
        render(&ctx, &scene, settings(2, 2, 4)).pixel(0, 0)
    };
    let toward = Vec3::new(0.5, 0.5, -0.5).normalize();
    assert!(
        (look(&map, toward) - Vec3::new(2.0, 4.0, 6.0)).length() < 1e-4,
        "{}",
        look(&map, toward)
    );
    assert_eq!(
        look(&map, Vec3::new(-0.5, 0.5, -0.5).normalize()),
        Vec3::ZERO
    );
    // Rotating the map by 90° about +Y moves that texel a quarter turn.
    map.rotation_degrees = 90.0;
    assert_eq!(look(&map, toward), Vec3::ZERO);
    let rotated = Vec3::new(0.5, 0.5, 0.5).normalize();
    assert!(
        (look(&map, rotated) - Vec3::new(2.0, 4.0, 6.0)).length() < 1e-4,
        "{}",
        look(&map, rotated)
    );
}

#[test]
fn environment_map_loads_from_a_scene_file() {
    let dir = tempfile::tempdir().unwrap();
    let sky = image::Rgb32FImage::from_fn(8, 4, |x, _| image::Rgb([x as f32, 0.5, 0.25]));
    sky.save(dir.path().join("sky.exr")).unwrap();
    let text = r#"(
        version: 1,
        camera: (position: (0, 0, 0), look_at: (0, 0, -1), projection: Perspective(fov_y: 40)),
        environment_map: (file: "sky.exr", strength: 2, rotation: 45),
    )"#;
    let path = dir.path().join("scene.kiln");
    std::fs::write(&path, text).unwrap();
    let scene = kiln::scene::load_scene(&path).unwrap();
    let map = scene.environment_map.expect("a map");
    assert_eq!(
        (map.width, map.height, map.strength, map.rotation_degrees),
        (8, 4, 2.0, 45.0)
    );
    assert_eq!(map.texels[3], Vec3::new(3.0, 0.5, 0.25));
    std::fs::write(&path, text.replace("sky.exr", "missing.hdr")).unwrap();
    let err = kiln::scene::load_scene(&path).unwrap_err().to_string();
    assert!(err.contains("missing.hdr"), "{err}");
}
