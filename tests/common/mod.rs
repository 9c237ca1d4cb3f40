//! Helpers shared by the integration tests: the GPU context and small scenes.
#![allow(dead_code)]
pub mod chi2;
pub mod exr;
pub mod node_reference;
pub mod resource;

use std::sync::{Arc, OnceLock};

use glam::{Affine3A, Vec3};
use kiln::film::Film;
use kiln::render::{GpuContext, KernelKind, RenderControl, RenderSettings, Renderer};
use kiln::scene::{Camera, Material, Scene, shapes};

/// The test adapter's device, whatever wgpu picks (lavapipe in CI), opened once per test
/// binary and shared by its tests, so that a kernel one test compiled is in the pipeline
/// cache for the next: lavapipe translates and optimises every new pipeline again (seconds
/// each, even for tests/bsdf.rs's small lobe kernels, which build on the whole library),
/// even when Mesa's disk cache holds its machine code. Tests that count the kernels a
/// context compiles, change its cache or lose the device use [`fresh_gpu`].
pub fn gpu() -> Arc<GpuContext> {
    static SHARED: OnceLock<Arc<GpuContext>> = OnceLock::new();
    Arc::clone(SHARED.get_or_init(fresh_gpu))
}

/// A device of its own on the test adapter, with an empty pipeline cache.
pub fn fresh_gpu() -> Arc<GpuContext> {
    GpuContext::new(None).unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"))
}

pub fn settings(width: u32, height: u32, spp: u32) -> RenderSettings {
    RenderSettings {
        width,
        height,
        samples_per_pixel: spp,
        max_bounces: 64,
        max_volume_bounces: kiln::scene::UNLIMITED_VOLUME_BOUNCES,
        seed: 1,
        sampling: kiln::shader::sampling::Sampling::default(),
        volume_resolution: kiln::scene::DEFAULT_VOLUME_RESOLUTION,
        clamp: kiln::scene::Clamp::default(),
        noise_threshold: 0.0,
        light_sampling: true,
        page_bytes: None,
        kernel: KernelKind::Specialized,
        aovs: false,
        film_piece_bytes: None,
        ablation: kiln::shader::Ablation::Full,
        texel_reads: None,
    }
}

/// Renders samples `0..spp` and returns the film.
pub fn render(ctx: &Arc<GpuContext>, scene: &Scene, settings: RenderSettings) -> Film {
    let mut r = Renderer::new(Arc::clone(ctx), scene, settings).expect("renderer");
    let stats = r
        .render(0..settings.samples_per_pixel, RenderControl::default())
        .expect("render");
    assert!(stats.completed);
    assert_eq!(stats.non_finite, 0, "non-finite samples");
    r.read_film().expect("film")
}

/// A unit sphere of the given albedo at the origin, filling most of the view, inside a
/// uniform environment. Faceted, so the geometric normal is the shading normal and the
/// convex sphere never sees itself.
pub fn furnace_scene(albedo: f32, environment: f32) -> Scene {
    let mut scene = Scene::empty(Camera::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 45.0));
    scene.environment = Vec3::splat(environment);
    let m = scene.add_material(Material::diffuse("albedo", Vec3::splat(albedo)));
    let sphere = scene.add_mesh(shapes::uv_sphere(48, 24, false));
    scene.add_instance(sphere, m, Affine3A::IDENTITY);
    scene
}

/// A render of `scene` (a [`furnace_scene`] with its sphere's material changed) and the
/// pixels of it fully on the sphere: those a black sphere covers in every sample.
pub fn furnace_render(
    ctx: &Arc<GpuContext>,
    scene: &Scene,
    settings: RenderSettings,
) -> (Vec<Vec3>, Vec<Vec3>) {
    let px = render(ctx, scene, settings).radiance();
    let coverage = render(ctx, &furnace_scene(0.0, 1.0), settings).radiance();
    let on_sphere = px
        .iter()
        .zip(&coverage)
        .filter(|(_, c)| c.x < 1e-3)
        .map(|(p, _)| *p)
        .collect();
    (px, on_sphere)
}

pub fn mean(values: &[Vec3]) -> Vec3 {
    values.iter().copied().sum::<Vec3>() / values.len() as f32
}

/// Root-mean-square difference over all channels.
pub fn rmse(a: &[Vec3], b: &[Vec3]) -> f64 {
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).length_squared() as f64)
        .sum();
    (sum / (3 * a.len()) as f64).sqrt()
}

/// The signature and IHDR chunk of a PNG with the given size (no image data).
pub fn png_header(width: u32, height: u32) -> Vec<u8> {
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend(width.to_be_bytes());
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([8, 6, 0, 0, 0]);
    let crc = {
        let mut c = !0u32;
        for &b in &ihdr {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xedb8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    };
    let mut out = vec![0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
    out.extend(13u32.to_be_bytes());
    out.extend(ihdr);
    out.extend(crc.to_be_bytes());
    out
}

/// Asserts that the image at `path` is complete (`width` × `height`, every value finite)
/// and lit, not black or uniform: its brightest pixel is above 1 and ten times its darkest.
pub fn assert_lit_image(path: &std::path::Path, width: u32, height: u32) {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .into_rgb32f();
    assert_eq!((img.width(), img.height()), (width, height));
    let luminance: Vec<f32> = img.pixels().map(|p| p.0.iter().sum::<f32>()).collect();
    assert!(luminance.iter().all(|v| v.is_finite()), "non-finite pixels");
    let (lo, hi) = luminance
        .iter()
        .fold((f32::MAX, f32::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    assert!(
        hi > 1.0 && hi > 10.0 * lo.max(1e-3),
        "a flat image: luminance from {lo} to {hi}"
    );
}

/// Runs the test kernel `entry` of the WGSL file `path` (its text `source`) over an empty
/// scene, one invocation each of `invocations`, with `input` bound as `probe_in`; returns
/// the `output_bytes` it wrote to `probe_out`.
pub fn run_test_kernel(
    file: (&str, &str),
    entry: &str,
    input: &[u8],
    output_bytes: u64,
    invocations: u32,
) -> Vec<u8> {
    let scene = Scene::empty(Camera::look_at(Vec3::Z, Vec3::ZERO, 40.0));
    run_scene_kernel(&scene, file, entry, input, output_bytes, invocations)
}

/// [`run_test_kernel`] over `scene`, whose lights, geometry and materials the kernel sees.
pub fn run_scene_kernel(
    scene: &Scene,
    (path, source): (&str, &str),
    entry: &str,
    input: &[u8],
    output_bytes: u64,
    invocations: u32,
) -> Vec<u8> {
    kiln::render::probe::run_probe(
        &gpu(),
        scene,
        &settings(1, 1, 1),
        &kiln::render::probe::Probe {
            name: entry,
            parts: &[(path, source)],
            entry,
            input,
            output_bytes,
            invocations,
            material_params: &[],
        },
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// The bundled plugins, as `cargo build` left them next to the test executable.
pub fn bundled_plugins() -> kiln::plugin::PluginHost {
    let exe = std::env::current_exe().unwrap();
    let mut plugins = kiln::plugin::PluginHost::default();
    plugins.load_dir(exe.parent().unwrap(), true);
    plugins
}
