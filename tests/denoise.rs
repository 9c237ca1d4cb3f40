//! The denoisers (`--denoise atrous`, and `oidn` in builds with the `oidn` feature): each
//! keeps the image's energy, never makes a NaN, leaves a converged image as it was, lowers the error against a reference, and
//! keeps the edges of the albedo (a checker texture) and of the normals (the Cornell
//! box's corners). The emission the camera sees directly is passed through unfiltered,
//! so the light's own pixels and its rim keep their noise and are left out of the error.

mod common;

use std::sync::Arc;

use common::{gpu, settings};
use glam::{Affine3A, Quat, Vec3};
use kiln::film::Film;
use kiln::material::parse_material;
use kiln::render::denoise::denoise_film;
use kiln::render::{Aovs, GpuContext, RenderControl, RenderSettings, Renderer};
use kiln::scene::{Camera, Denoiser, Material, Scene, default_scene, shapes};

/// A render's film, AOVs and second moments, and the film denoised.
struct Denoised {
    noisy: Film,
    aovs: Aovs,
    denoised: Film,
}

fn render_and_denoise(
    ctx: &Arc<GpuContext>,
    scene: &Scene,
    s: RenderSettings,
    denoiser: Denoiser,
) -> Denoised {
    let s = RenderSettings { aovs: true, ..s };
    let mut r = Renderer::new(Arc::clone(ctx), scene, s).expect("renderer");
    let stats = r
        .render(0..s.samples_per_pixel, RenderControl::default())
        .expect("render");
    assert!(stats.completed);
    let noisy = r.read_film().unwrap();
    let aovs = r.read_aovs().unwrap().expect("AOVs");
    let moments = r.read_second_moments().unwrap().expect("second moments");
    let denoised = denoise_film(ctx, &noisy, &aovs, &moments, denoiser).unwrap();
    assert_eq!(
        denoised.sums.iter().map(|s| s[3]).collect::<Vec<_>>(),
        noisy.sums.iter().map(|s| s[3]).collect::<Vec<_>>(),
        "the denoiser keeps the sample counts"
    );
    Denoised {
        noisy,
        aovs,
        denoised,
    }
}

fn rmse(a: &[Vec3], b: &[Vec3], pixels: impl Iterator<Item = usize>) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for p in pixels {
        sum += (a[p] - b[p]).length_squared() as f64 / 3.0;
        n += 1;
    }
    (sum / n.max(1) as f64).sqrt()
}

fn mean(v: &[Vec3]) -> Vec3 {
    v.iter().copied().sum::<Vec3>() / v.len() as f32
}

/// Pixels where a guide changes: a neighbour's value differs by more than `jump`.
fn edges(width: usize, height: usize, values: &[Vec3], jump: f32) -> Vec<usize> {
    (0..width * height)
        .filter(|&p| {
            let (x, y) = (p % width, p / width);
            [(1, 0), (0, 1), (-1, 0), (0, -1)].iter().any(|&(dx, dy)| {
                let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                (0..width as i64).contains(&nx)
                    && (0..height as i64).contains(&ny)
                    && (values[ny as usize * width + nx as usize] - values[p]).length() > jump
            })
        })
        .collect()
}

fn vec3s(flat: &[f32]) -> Vec<Vec3> {
    flat.chunks_exact(3).map(Vec3::from_slice).collect()
}

fn the_cornell_box_denoised_keeps_its_energy_and_corners_and_is_closer_to_the_reference(
    denoiser: Denoiser,
) {
    let ctx = gpu();
    let scene = default_scene().unwrap();
    let (w, h) = (48, 48);
    let reference = render_and_denoise(&ctx, &scene, settings(w, h, 1024), denoiser);
    // The light and the pixels its edge crosses (through the pixel filter's tails), which
    // the denoiser passes through unfiltered: their emission seen directly is exact.
    let dark: Vec<usize> = (0..(w * h) as usize)
        .filter(|&p| reference.aovs.emission[3 * p..3 * p + 3] == [0.0; 3])
        .collect();
    let reference = reference.noisy.radiance();
    let d = render_and_denoise(&ctx, &scene, settings(w, h, 16), denoiser);
    let (noisy, denoised) = (d.noisy.radiance(), d.denoised.radiance());
    assert!(
        denoised
            .iter()
            .all(|c| c.is_finite() && c.min_element() >= 0.0)
    );
    // Energy: the image's mean moves by less than 2 % (measured 0.7 %).
    let (m0, m1) = (mean(&noisy), mean(&denoised));
    for c in 0..3 {
        assert!(
            (m1[c] / m0[c] - 1.0).abs() < 0.02,
            "channel {c}: mean {} → {}",
            m0[c],
            m1[c]
        );
    }
    let lit = || dark.iter().copied();
    let (before, after) = (
        rmse(&noisy, &reference, lit()),
        rmse(&denoised, &reference, lit()),
    );
    // Measured 0.56×.
    assert!(
        after < 0.7 * before,
        "RMSE against 1024 spp: {before:.4} noisy, {after:.4} denoised"
    );
    // The corners of the box and the blocks' edges: the denoised image is closer to the
    // reference there too, not blurred across them.
    let corners: Vec<usize> = edges(w as usize, h as usize, &vec3s(&d.aovs.normal), 0.5)
        .into_iter()
        .filter(|p| dark.contains(p))
        .collect();
    assert!(corners.len() > 50, "{} corner pixels", corners.len());
    let (before, after) = (
        rmse(&noisy, &reference, corners.iter().copied()),
        rmse(&denoised, &reference, corners.iter().copied()),
    );
    assert!(
        after < before,
        "RMSE at the corners: {before:.4} noisy, {after:.4} denoised"
    );
}

/// A converged image (4096 samples) changes by less than 1 % of its mean per pixel in
/// RMS, and nowhere by more than 10 % of the pixel's value plus 0.01: where the noise is
/// gone the luminance weight stops the filter.
fn a_converged_image_is_left_as_it_was(denoiser: Denoiser) {
    let ctx = gpu();
    let scene = default_scene().unwrap();
    let (w, h) = (24, 24);
    let d = render_and_denoise(&ctx, &scene, settings(w, h, 4096), denoiser);
    let (noisy, denoised) = (d.noisy.radiance(), d.denoised.radiance());
    let level = mean(&noisy).length() as f64;
    let change = rmse(&noisy, &denoised, 0..(w * h) as usize);
    assert!(
        change < 0.01 * level,
        "RMS change {change:.5} against a mean of {level:.3}"
    );
    for (p, (a, b)) in noisy.iter().zip(&denoised).enumerate() {
        assert!(
            (*a - *b).abs().max_element() <= 0.1 * a.max_element() + 0.01,
            "pixel {p}: {a} → {b}"
        );
    }
}

/// A checker floor (albedo 0.8 and 0.05) lit by a small light: after denoising the
/// squares' edges are as sharp as in the reference, since the filter runs on the image
/// divided by the albedo and stops at albedo changes.
fn the_edges_of_a_checker_texture_survive(denoiser: Denoiser) {
    let ctx = gpu();
    let text = r#"(
        version: 1,
        name: "checker",
        nodes: {
            "coords": (type: "texture_coordinate"),
            "checker": (type: "checker_texture", inputs: {
                "vector": "coords.world", "scale": 1.0, "color1": (0.8, 0.8, 0.8), "color2": (0.05, 0.05, 0.05),
            }),
            "surface": (type: "principled_bsdf", inputs: { "base_color": "checker.color", "roughness": 1.0 }),
            "out": (type: "material_output", inputs: { "surface": "surface.bsdf" }),
        },
    )"#;
    let (name, graph) = parse_material(text, "checker.kmat").unwrap();
    let mut scene = Scene::empty(Camera::look_at(Vec3::new(0.0, 4.0, 3.0), Vec3::ZERO, 50.0));
    scene.environment = Vec3::splat(0.05);
    let checker = scene.add_material(Material::from_graph(&name, graph).unwrap());
    let light = scene.add_material(Material::emitter("light", Vec3::splat(20.0)));
    let quad = scene.add_mesh(shapes::quad());
    scene.add_instance(quad, checker, Affine3A::from_scale(Vec3::splat(12.0)));
    scene.add_instance(
        quad,
        light,
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.5),
            Quat::from_rotation_x(std::f32::consts::PI),
            Vec3::new(0.5, 2.5, 0.5),
        ),
    );
    let (w, h) = (64, 48);
    let reference = common::render(&ctx, &scene, settings(w, h, 1024)).radiance();
    // One sample per pixel, so that noise is what the edges' error is made of: since light
    // samples are split per shading point (src/render/light_distribution.rs), 8 spp left
    // the edges within 0.007 of the reference, where the filter has little to take away
    // (0.0068 → 0.0066). At 1 spp: 0.040 → 0.028 measured.
    let d = render_and_denoise(&ctx, &scene, settings(w, h, 1), denoiser);
    let (noisy, denoised) = (d.noisy.radiance(), d.denoised.radiance());
    let squares = edges(w as usize, h as usize, &vec3s(&d.aovs.albedo), 0.3);
    assert!(squares.len() > 200, "{} edge pixels", squares.len());
    let (before, after) = (
        rmse(&noisy, &reference, squares.iter().copied()),
        rmse(&denoised, &reference, squares.iter().copied()),
    );
    eprintln!("RMSE at the checker's edges: {before:.4} noisy, {after:.4} denoised");
    assert!(
        after < 0.75 * before,
        "RMSE at the checker's edges: {before:.4} noisy, {after:.4} denoised"
    );
}

/// Black surfaces (albedo 0), one sample per pixel, a light seen directly, the sky seen
/// through the box's open side: every pixel stays finite and non-negative.
fn extremes_make_no_nan(denoiser: Denoiser) {
    let ctx = gpu();
    let mut scene = default_scene().unwrap();
    for m in &mut scene.materials {
        if m.principled.emission_strength == 0.0 {
            m.principled.base_color = Vec3::ZERO;
        }
    }
    scene.environment = Vec3::splat(1.0e4);
    for spp in [1, 2] {
        let d = render_and_denoise(&ctx, &scene, settings(24, 24, spp), denoiser);
        for (p, c) in d.denoised.radiance().iter().enumerate() {
            assert!(
                c.is_finite() && c.min_element() >= 0.0,
                "{spp} spp, pixel {p}: {c}"
            );
        }
    }
}

/// Each check, for each denoiser this build has.
macro_rules! for_each_denoiser {
    ($($check:ident),* $(,)?) => {
        mod atrous {
            $(#[test]
            fn $check() {
                super::$check(kiln::scene::Denoiser::Atrous);
            })*
        }
        #[cfg(feature = "oidn")]
        mod oidn {
            $(#[test]
            fn $check() {
                super::$check(kiln::scene::Denoiser::Oidn);
            })*
        }
    };
}

for_each_denoiser!(
    the_cornell_box_denoised_keeps_its_energy_and_corners_and_is_closer_to_the_reference,
    a_converged_image_is_left_as_it_was,
    the_edges_of_a_checker_texture_survive,
    extremes_make_no_nan,
);
