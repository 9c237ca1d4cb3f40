//! Volumes in material graphs (shaders/nodes/volume.wgsl) and the volumetric path tracer
//! (shaders/integrator/media.wgsl, path.wgsl): energy in a white furnace, Beer–Lambert
//! absorption through nested media and along a density gradient (heterogeneous: delta and
//! ratio tracking), single scattering in a slab against a numerically integrated closed
//! form, majorants from bounds, convergence of chromatic media at the Monte Carlo rate, and
//! finite samples at the parameters' extremes.

mod common;

use std::sync::Arc;

use common::{gpu, mean, render, settings};
use glam::{Affine3A, Vec3};
use kiln::material::parse_material;

use kiln::render::{KernelKind, RenderControl, Renderer};
use kiln::scene::{Camera, Material, Scene, shapes};

/// A material from the nodes of a `.kmat` file's `nodes` map.
fn graph_material(name: &str, nodes: &str) -> Material {
    let text = format!("(version: 1, name: \"{name}\", nodes: {{ {nodes} }})");
    let (_, graph) = parse_material(&text, name).expect("the test graph parses");
    Material::from_graph(name, graph).expect("the test graph compiles")
}

/// A volume with no surface: its boundary only marks where it begins and ends.
fn bare_volume(name: &str, volume: &str) -> Material {
    graph_material(
        name,
        &format!(
            "\"v\": {volume}, \"out\": (type: \"material_output\", inputs: {{ \"volume\": \"v.volume\" }}),"
        ),
    )
}

fn scatter(color: [f32; 3], density: f32, anisotropy: f32) -> String {
    format!(
        "(type: \"volume_scatter\", inputs: {{ \"color\": ({}, {}, {}), \"density\": {density:?}, \"anisotropy\": {anisotropy:?} }})",
        color[0], color[1], color[2]
    )
}

fn absorption(color: [f32; 3], density: f32) -> String {
    format!(
        "(type: \"volume_absorption\", inputs: {{ \"color\": ({}, {}, {}), \"density\": {density:?} }})",
        color[0], color[1], color[2]
    )
}

/// A unit sphere of `material` in a uniform environment of radiance 1, seen whole.
fn sphere_scene(material: Material) -> Scene {
    let mut scene = common::furnace_scene(0.5, 1.0);
    scene.materials[0] = material;
    scene
}

/// The pixels fully on the furnace sphere, from a render of the scene without it.
fn on_sphere(scene: &Scene, spp: u32, light_sampling: bool) -> Vec<Vec3> {
    let ctx = gpu();
    let mut s = settings(24, 24, spp);
    s.light_sampling = light_sampling;
    common::furnace_render(&ctx, scene, s).1
}

/// Mean and standard error of the mean of channel `c` over `pixels`.
fn channel_mean(pixels: &[Vec3], c: usize) -> (f32, f32) {
    let n = pixels.len() as f32;
    let m = pixels.iter().map(|p| p[c]).sum::<f32>() / n;
    let var = pixels.iter().map(|p| (p[c] - m).powi(2)).sum::<f32>() / (n - 1.0);
    (m, (var / n).sqrt())
}

#[test]
fn a_white_scattering_volume_in_a_white_furnace_is_one_in_every_channel() {
    // A medium that scatters and absorbs nothing (albedo 1) loses no light: whatever
    // enters leaves, so the sphere reads 1 whether its boundary is bare (index-matched)
    // or a smooth dielectric, with chromatic coefficients (sampled by MIS over the
    // channels) and forward scattering, with and without next-event estimation through
    // the boundary.
    let glass = "\"glass\": (type: \"principled_bsdf\", inputs: { \"base_color\": (1.0, 1.0, 1.0), \"transmission_weight\": 1.0, \"roughness\": 0.0, \"ior\": 1.5 }),";
    let cases = [
        (
            "bare, grey",
            bare_volume("bare", &scatter([1.0; 3], 2.0, 0.0)),
        ),
        (
            "bare, chromatic, forward",
            bare_volume("chromatic", &scatter([1.0, 0.5, 0.25], 4.0, 0.7)),
        ),
        (
            // Density from fractal noise (a majorant of 4 from its bounds): delta tracking
            // for free flights, ratio tracking for transmittance, spectral weights.
            "heterogeneous, chromatic",
            graph_material(
                "cloud",
                "\"noise\": (type: \"noise_texture\", inputs: { \"scale\": 4.0 }),
                 \"density\": (type: \"math\", params: { \"operation\": \"multiply\" }, inputs: { \"a\": \"noise.fac\", \"b\": 4.0 }),
                 \"v\": (type: \"volume_scatter\", inputs: { \"color\": (1.0, 0.5, 0.25), \"density\": \"density.value\", \"anisotropy\": 0.3 }),
                 \"out\": (type: \"material_output\", inputs: { \"volume\": \"v.volume\" }),",
            ),
        ),
        (
            "behind a smooth dielectric",
            graph_material(
                "glass",
                &format!(
                    "{glass} \"v\": {}, \"out\": (type: \"material_output\", inputs: {{ \"surface\": \"glass.bsdf\", \"volume\": \"v.volume\" }}),",
                    scatter([1.0; 3], 2.0, -0.5)
                ),
            ),
        ),
    ];
    for (name, material) in cases {
        let scene = sphere_scene(material);
        // Per-channel free flights make chromatic media noisier, and so does the
        // dielectric's choice between reflection and refraction.
        let spp = match name {
            n if n.contains("chromatic") => 512,
            n if n.contains("dielectric") => 384,
            _ => 256,
        };
        if name.contains("heterogeneous") {
            let m = &scene.materials[0];
            assert_eq!(
                m.volume_majorant(),
                Some(4.0),
                "{name}: the majorant from bounds"
            );
        }
        for light_sampling in [false, true] {
            let pixels = on_sphere(&scene, spp, light_sampling);
            for c in 0..3 {
                let (m, se) = channel_mean(&pixels, c);
                eprintln!("{name}, light sampling {light_sampling}, channel {c}: {m} ± {se}");
                assert!(se < 0.005, "{name}: standard error {se} too large to test");
                assert!(
                    (m - 1.0).abs() < 4.0 * se + 1e-4,
                    "{name} (light sampling {light_sampling}) channel {c}: mean {m} ± {se}, expected 1"
                );
            }
        }
    }
}

#[test]
fn chromatic_media_converge_at_the_monte_carlo_rate() {
    // The chromatic furnace sphere reads exactly 1, so its error is known at every
    // sample count: the RMS error falls as 1/√spp (4× from 16 to 256 spp, within 1.5×
    // either way), and the largest pixel error does not grow with the sample count, as
    // it would if rare samples carried weights that grow without bound (fireflies).
    let scene = sphere_scene(bare_volume(
        "chromatic",
        &scatter([1.0, 0.5, 0.25], 4.0, 0.7),
    ));
    let errors = [16, 64, 256].map(|spp| {
        let pixels = on_sphere(&scene, spp, true);
        let squares: Vec<f32> = pixels
            .iter()
            .flat_map(|p| (*p - Vec3::ONE).to_array())
            .map(|e| e * e)
            .collect();
        let rms = (squares.iter().sum::<f32>() / squares.len() as f32).sqrt();
        let largest = squares.iter().copied().fold(0.0f32, f32::max).sqrt();
        eprintln!("{spp} spp: RMS error {rms}, largest {largest}");
        (rms, largest)
    });
    let ratio = errors[0].0 / errors[2].0;
    assert!(
        (4.0 / 1.5..4.0 * 1.5).contains(&ratio),
        "RMS error from 16 to 256 spp fell {ratio}×, not about 4× ({errors:?})"
    );
    assert!(
        errors[1].0 < errors[0].0 && errors[2].0 < errors[1].0,
        "{errors:?}"
    );
    assert!(
        errors[2].1 <= errors[0].1,
        "the largest pixel error grew with spp: {errors:?}"
    );
}

/// A camera on +z looking down at the origin with a narrow view: every ray crosses the
/// slab |z| < half-thickness within `max_angle` of its normal.
fn slab_camera() -> Camera {
    Camera::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 10.0)
}

/// The directions of `slab_camera`'s rays through pixel centres, as the cosine with the
/// view axis.
fn pixel_cosines(width: u32, height: u32) -> Vec<f32> {
    let half = (10.0f32.to_radians() / 2.0).tan();
    let aspect = width as f32 / height as f32;
    let mut out = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let u = ((x as f32 + 0.5) / width as f32 * 2.0 - 1.0) * half * aspect;
            let v = ((y as f32 + 0.5) / height as f32 * 2.0 - 1.0) * half;
            out.push(1.0 / (1.0 + u * u + v * v).sqrt());
        }
    }
    out
}

#[test]
fn absorption_through_nested_volumes_is_beer_lambert() {
    // An absorbing cube of side 1 inside another of side 2, both with bare boundaries, in
    // front of a uniform environment: a ray through both crosses 1 unit of the outer
    // medium and 1 of the inner one (divided by the cosine of its angle with the axis),
    // so it keeps exp(-(σo + σi) / cos θ) — only if the inner medium replaces the outer
    // one inside it and the outer one is back once the ray leaves the inner cube.
    let ctx = gpu();
    let mut scene = Scene::empty(slab_camera());
    scene.environment = Vec3::ONE;
    let outer = scene.add_material(bare_volume("outer", &absorption([0.5, 0.75, 0.9], 1.0)));
    let inner = scene.add_material(bare_volume("inner", &absorption([0.9, 0.5, 0.0], 0.5)));
    let cube = scene.add_mesh(shapes::cube());
    scene.add_instance(cube, outer, Affine3A::from_scale(Vec3::splat(2.0)));
    scene.add_instance(cube, inner, Affine3A::IDENTITY);
    let sigma_outer = Vec3::new(0.5, 0.25, 0.1);
    let sigma_inner = Vec3::new(0.05, 0.25, 0.5);
    let cosines = pixel_cosines(16, 16);
    // Pixel filters reach a pixel beyond the centre: the path length lies between the
    // axis's and that of the widest ray.
    let widest = cosines.iter().copied().fold(1.0f32, f32::min) * 0.995;
    for light_sampling in [false, true] {
        let mut s = settings(16, 16, 4);
        s.light_sampling = light_sampling;
        let px = render(&ctx, &scene, s).radiance();
        for (i, p) in px.iter().enumerate() {
            let longest = (-(sigma_outer + sigma_inner) / widest).exp();
            let shortest = (-(sigma_outer + sigma_inner)).exp();
            for c in 0..3 {
                assert!(
                    p[c] >= longest[c] - 1e-4 && p[c] <= shortest[c] + 1e-4,
                    "pixel {i} channel {c}: {} outside [{}, {}] (light sampling {light_sampling})",
                    p[c],
                    longest[c],
                    shortest[c]
                );
            }
        }
        // And the centre pixels, whose rays are all but on the axis, close to it.
        let centre = px[8 * 16 + 8];
        assert!(
            (centre - shortest_of(sigma_outer + sigma_inner))
                .abs()
                .max_element()
                < 2e-3,
            "centre {centre}"
        );
    }
}

#[test]
fn a_camera_inside_nested_volumes_starts_in_their_media() {
    // The camera at the centre of an absorbing sphere of radius 1 inside another of
    // radius 2, in a uniform environment: every ray crosses 1 unit of each medium and
    // keeps exp(-(σi + σo)) (a little more: the faceted spheres are up to 0.3% smaller).
    // A path started in vacuum would keep 1; one started with the media in the wrong
    // order, exp(-2 σo).
    let ctx = gpu();
    let mut scene = Scene::empty(Camera::look_at(Vec3::ZERO, -Vec3::Z, 60.0));
    scene.environment = Vec3::ONE;
    let inner = scene.add_material(bare_volume("inner", &absorption([0.5, 0.75, 0.9], 1.0)));
    let outer = scene.add_material(bare_volume("outer", &absorption([0.9, 0.5, 0.0], 0.5)));
    let sphere = scene.add_mesh(shapes::uv_sphere(96, 48, false));
    scene.add_instance(sphere, inner, Affine3A::IDENTITY);
    scene.add_instance(sphere, outer, Affine3A::from_scale(Vec3::splat(2.0)));
    let sigma = Vec3::new(0.5, 0.25, 0.1) + Vec3::new(0.05, 0.25, 0.5);
    let (lowest, highest) = ((-sigma).exp(), (-sigma * 0.997).exp());
    let mut renderer =
        Renderer::new(Arc::clone(&ctx), &scene, settings(12, 12, 2)).expect("renderer");
    let inside = |renderer: &mut Renderer| {
        renderer.clear_film();
        let stats = renderer
            .render(0..2, RenderControl::default())
            .expect("render");
        assert!(stats.completed);
        renderer.read_film().expect("film").radiance()
    };
    for (i, p) in inside(&mut renderer).iter().enumerate() {
        assert!(
            p.cmpge(lowest - 1e-4).all() && p.cmple(highest + 1e-4).all(),
            "pixel {i}: {p} outside [{lowest}, {highest}]"
        );
    }
    // Moved out of both, looking away from them: nothing between the camera and the sky.
    renderer.set_camera(&Camera::look_at(Vec3::Z * 3.0, Vec3::Z * 4.0, 60.0));
    for (i, p) in inside(&mut renderer).iter().enumerate() {
        assert!(
            (*p - Vec3::ONE).abs().max_element() < 1e-4,
            "pixel {i} outside: {p}"
        );
    }
    // Between the spheres (z = 1.5), looking out along +z: the rays cross 0.5 units of
    // the outer medium (up to 0.3% less, to the faceted sphere).
    renderer.set_camera(&Camera::look_at(Vec3::Z * 1.5, Vec3::Z * 4.0, 1.0));
    let centre = inside(&mut renderer)[6 * 12 + 6];
    let expected = (-Vec3::new(0.05, 0.25, 0.5) * 0.5).exp();
    assert!(
        (centre - expected).abs().max_element() < 4e-3,
        "between the spheres: {centre}, expected {expected}"
    );
}

#[test]
fn past_the_volume_bounce_limit_a_medium_only_absorbs() {
    // A white scattering cube of side 1 (σs = 1, albedo 1) in front of a uniform
    // environment. With no volume bounces nothing scatters: every ray keeps exp(-σt / cos θ)
    // of the environment, as through an absorber of the same extinction (Cycles'
    // absorption-only volumes). One bounce brings single scattering back, and without a
    // limit nothing is lost: the white furnace reads 1.
    let ctx = gpu();
    let mut scene = Scene::empty(slab_camera());
    scene.environment = Vec3::ONE;
    let white = scene.add_material(bare_volume("white", &scatter([1.0; 3], 1.0, 0.0)));
    let cube = scene.add_mesh(shapes::cube());
    scene.add_instance(cube, white, Affine3A::IDENTITY);
    let widest = pixel_cosines(16, 16).into_iter().fold(1.0f32, f32::min) * 0.995;
    let centre_mean = |max_volume_bounces: u32| {
        let mut s = settings(16, 16, 64);
        s.max_volume_bounces = max_volume_bounces;
        let px = render(&ctx, &scene, s).radiance();
        (px.clone(), mean(&px[5 * 16 + 5..5 * 16 + 11]))
    };
    let (none, _) = centre_mean(0);
    for (i, p) in none.iter().enumerate() {
        let (longest, shortest) = ((-1.0 / widest).exp(), (-1.0f32).exp());
        assert!(
            p.cmpge(Vec3::splat(longest - 1e-4)).all()
                && p.cmple(Vec3::splat(shortest + 1e-4)).all(),
            "pixel {i} with no volume bounces: {p} outside [{longest}, {shortest}]"
        );
    }
    let (_, single) = centre_mean(1);
    assert!(
        single.min_element() > (-1.0f32).exp() + 0.1,
        "one volume bounce adds single scattering: {single}"
    );
    let (_, unlimited) = centre_mean(kiln::scene::UNLIMITED_VOLUME_BOUNCES);
    assert!(
        (unlimited - Vec3::ONE).abs().max_element() < 0.03
            && unlimited.max_element() > single.max_element(),
        "without a limit the white furnace reads 1: {unlimited} (one bounce: {single})"
    );
}

fn shortest_of(sigma: Vec3) -> Vec3 {
    (-sigma).exp()
}

/// Radiance single scattering adds along a ray at cosine `mu0` with the normal of a slab of
/// thickness `l` (isotropic phase function, uniform unit environment on both sides,
/// bare boundaries), by the midpoint rule over the depth along the ray and the exit
/// direction's cosine: ∫ σs e^(-σt r) ½ ∫₀¹ (e^(-σt s/μ) + e^(-σt (l - s)/μ)) dμ dr,
/// s = r μ0 the depth of the scattering point.
fn single_scattering(sigma_s: f64, sigma_t: f64, l: f64, mu0: f64) -> f64 {
    let (nr, nm) = (2000, 2000);
    let r_max = l / mu0;
    let mut total = 0.0;
    for i in 0..nr {
        let r = (i as f64 + 0.5) / nr as f64 * r_max;
        let s = r * mu0;
        let mut exit = 0.0;
        for j in 0..nm {
            let mu = (j as f64 + 0.5) / nm as f64;
            exit += (-sigma_t * s / mu).exp() + (-sigma_t * (l - s) / mu).exp();
        }
        exit *= 0.5 / nm as f64;
        total += sigma_s * (-sigma_t * r).exp() * exit;
    }
    total * r_max / nr as f64
}

#[test]
fn single_scattering_in_a_slab_matches_the_integrated_closed_form() {
    // A wide slab (100 × 100 × 2) of isotropically scattering, partly absorbing medium
    // between the camera and a uniform environment, one bounce allowed: each pixel sees
    // the environment through the slab plus the light scattered once toward it. The
    // image mean is compared with the mean of the numerically integrated expectation at
    // the pixels' centres (the pixel filter's effect on a function this smooth is far
    // below the noise).
    let ctx = gpu();
    let mut scene = Scene::empty(slab_camera());
    scene.environment = Vec3::ONE;
    // Volume Scatter adds no absorption; Principled Volume with colour c absorbs 1 - c
    // per unit density: σs = 0.6, σa = 0.4 (grey).
    let slab = scene.add_material(bare_volume(
        "slab",
        "(type: \"principled_volume\", inputs: { \"color\": (0.6, 0.6, 0.6), \"density\": 1.0 })",
    ));
    let cube = scene.add_mesh(shapes::cube());
    scene.add_instance(
        cube,
        slab,
        Affine3A::from_scale(Vec3::new(100.0, 100.0, 2.0)),
    );
    let (sigma_s, sigma_t, l) = (0.6, 1.0, 2.0);
    let cosines = pixel_cosines(16, 16);
    let expected: f64 = cosines
        .iter()
        .map(|&mu0| {
            let mu0 = mu0 as f64;
            (-sigma_t * l / mu0).exp() + single_scattering(sigma_s, sigma_t, l, mu0)
        })
        .sum::<f64>()
        / cosines.len() as f64;
    for light_sampling in [false, true] {
        let mut s = settings(16, 16, 1024);
        s.light_sampling = light_sampling;
        s.max_bounces = 1;
        let px = render(&ctx, &scene, s).radiance();
        let (m, se) = channel_mean(&px, 0);
        eprintln!("light sampling {light_sampling}: {m} ± {se}, expected {expected}");
        assert!(se < 0.003, "standard error {se} too large to test");
        assert!(
            ((m as f64) - expected).abs() < 4.0 * se as f64 + 1e-3,
            "light sampling {light_sampling}: mean {m} ± {se}, expected {expected}"
        );
        // Grey in, grey out.
        let rgb = mean(&px);
        assert!(
            (rgb.x - rgb.z).abs() < 1e-3 && (rgb.x - rgb.y).abs() < 1e-3,
            "{rgb}"
        );
    }
}

#[test]
fn volumes_stay_finite_at_parameter_extremes() {
    let ctx = gpu();
    let mut checked = 0;
    for density in [0.0, 1e-6, 1.0, 1e6] {
        for (color, anisotropy) in [
            ([0.0; 3], 0.0),
            ([1.0; 3], 0.999),
            ([1.0, 0.5, 0.0], -0.999),
        ] {
            for scale in [1e-4f32, 1e4] {
                let v = format!(
                    "(type: \"principled_volume\", inputs: {{ \"color\": ({}, {}, {}), \"density\": {density:?}, \"anisotropy\": {anisotropy:?}, \"emission_strength\": 1.0 }})",
                    color[0], color[1], color[2]
                );
                let mut scene = Scene::empty(Camera::look_at(
                    Vec3::new(0.0, 0.0, 3.0 * scale),
                    Vec3::ZERO,
                    45.0,
                ));
                scene.environment = Vec3::ONE;
                let m = scene.add_material(bare_volume("extreme", &v));
                let sphere = scene.add_mesh(shapes::uv_sphere(24, 12, false));
                scene.add_instance(sphere, m, Affine3A::from_scale(Vec3::splat(scale)));
                // Live constants: one kernel for every case. `render` fails on any
                // non-finite sample.
                let mut s = settings(8, 8, 4);
                s.kernel = KernelKind::General;
                let px = render(&ctx, &scene, s).radiance();
                for p in px {
                    assert!(
                        p.is_finite(),
                        "density {density}, colour {color:?}, g {anisotropy}, scale {scale}: {p}"
                    );
                }
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 24);
}

#[test]
fn absorption_along_a_density_gradient_is_beer_lambert() {
    // A cube of side 1 whose absorption grows linearly through it, 2 × the generated z
    // (0 at the back face, 1 at the front): a ray along the axis crosses an optical depth
    // of ∫₀¹ 2z dz = 1 and keeps e^(-1) per channel (e^(-1/cos θ) at angle θ), which the
    // tracking estimates through a majorant of 2 with null collisions.
    let ctx = gpu();
    let mut scene = Scene::empty(slab_camera());
    scene.environment = Vec3::ONE;
    let gradient = graph_material(
        "gradient",
        "\"coords\": (type: \"texture_coordinate\"),
         \"z\": (type: \"separate_xyz\", inputs: { \"vector\": \"coords.generated\" }),
         \"density\": (type: \"math\", params: { \"operation\": \"multiply\" }, inputs: { \"a\": \"z.z\", \"b\": 2.0 }),
         \"v\": (type: \"volume_absorption\", inputs: { \"color\": (0.0, 0.0, 0.0), \"density\": \"density.value\" }),
         \"out\": (type: \"material_output\", inputs: { \"volume\": \"v.volume\" }),",
    );
    assert_eq!(gradient.volume_majorant(), Some(2.0));
    let m = scene.add_material(gradient);
    let cube = scene.add_mesh(shapes::cube());
    scene.add_instance(cube, m, Affine3A::IDENTITY);
    let (width, height) = (12, 12);
    let px = render(&ctx, &scene, settings(width, height, 256)).radiance();
    let expected: Vec<f32> = pixel_cosines(width, height)
        .iter()
        .map(|c| (-1.0 / c).exp())
        .collect();
    let n = px.len() as f32;
    let want = expected.iter().sum::<f32>() / n;
    for c in 0..3 {
        let values: Vec<f32> = px.iter().map(|p| p[c]).collect();
        let m = values.iter().sum::<f32>() / n;
        let var = values.iter().map(|v| (v - m).powi(2)).sum::<f32>() / (n - 1.0);
        let se = (var / n).sqrt();
        eprintln!("channel {c}: {m} ± {se}, expected {want}");
        assert!(se < 0.002, "standard error {se} too large to test");
        assert!(
            (m - want).abs() < 4.0 * se + 1e-3,
            "channel {c}: mean {m} ± {se}, expected {want}"
        );
    }
}

#[test]
fn a_heterogeneous_volume_needs_bounded_inputs_and_gets_a_majorant() {
    // Noise is within [0, 1], so a density of 3 × noise has a majorant of 3 × the
    // largest extinction per unit density (Principled Volume, colour 0.5: 0.5 + 0.5).
    let text = "(version: 1, name: \"cloud\", nodes: {
        \"noise\": (type: \"noise_texture\"),
        \"density\": (type: \"math\", params: { \"operation\": \"multiply\" }, inputs: { \"a\": \"noise.fac\", \"b\": 3.0 }),
        \"cloud\": (type: \"principled_volume\", inputs: { \"density\": \"density.value\" }),
        \"out\": (type: \"material_output\", inputs: { \"volume\": \"cloud.volume\" }),
    })";
    let (_, graph) = parse_material(text, "cloud.kmat").expect("parses");
    let m = Material::from_graph("cloud", graph).expect("a bounded density compiles");
    assert_eq!(m.volume(), None);
    assert_eq!(m.volume_majorant(), Some(3.0));
    // A position is not bounded: the error names the node whose output has no bound and
    // says how to give it one.
    let text = "(version: 1, name: \"ramp\", nodes: {
        \"coords\": (type: \"texture_coordinate\"),
        \"x\": (type: \"separate_xyz\", inputs: { \"vector\": \"coords.object\" }),
        \"fog\": (type: \"volume_scatter\", inputs: { \"density\": \"x.x\" }),
        \"out\": (type: \"material_output\", inputs: { \"volume\": \"fog.volume\" }),
    })";
    let (_, graph) = parse_material(text, "ramp.kmat").expect("parses");
    let err = Material::from_graph("ramp", graph)
        .expect_err("an unbounded density is refused")
        .to_string();
    assert!(err.contains("\"coords\"") && err.contains("Clamp"), "{err}");
    // Clamped, the same position is bounded.
    let text = "(version: 1, name: \"ramp\", nodes: {
        \"coords\": (type: \"texture_coordinate\"),
        \"x\": (type: \"separate_xyz\", inputs: { \"vector\": \"coords.object\" }),
        \"c\": (type: \"clamp\", inputs: { \"value\": \"x.x\", \"min\": 0.0, \"max\": 5.0 }),
        \"fog\": (type: \"volume_scatter\", inputs: { \"color\": (1.0, 1.0, 1.0), \"density\": \"c.result\" }),
        \"out\": (type: \"material_output\", inputs: { \"volume\": \"fog.volume\" }),
    })";
    let (_, graph) = parse_material(text, "ramp.kmat").expect("parses");
    let m = Material::from_graph("ramp", graph).expect("a clamped density compiles");
    assert_eq!(m.volume_majorant(), Some(5.0));
    // Constant arithmetic feeding a volume is folded first, so it counts as constant.
    let text = "(version: 1, name: \"fog\", nodes: {
        \"half\": (type: \"math\", params: { \"operation\": \"multiply\" }, inputs: { \"a\": 0.5, \"b\": 3.0 }),
        \"fog\": (type: \"volume_scatter\", inputs: { \"density\": \"half.value\" }),
        \"out\": (type: \"material_output\", inputs: { \"volume\": \"fog.volume\" }),
    })";
    let (_, graph) = parse_material(text, "fog.kmat").expect("parses");
    let m = Material::from_graph("fog", graph).expect("constant arithmetic is constant");
    let v = m.volume().expect("a homogeneous volume");
    assert_eq!(v.scattering, [0.8 * 1.5; 3]);
    assert_eq!(m.volume_majorant(), None);
}
