//! White-furnace tests: in a uniform environment, a closed object of albedo 1 is invisible,
//! and a convex object of albedo a reflects exactly a times the environment. Run with BSDF
//! sampling alone and with next-event estimation + MIS, which must agree.

mod common;

use common::{furnace_render, furnace_scene, gpu, mean, render, settings};
use glam::{Affine3A, Vec3};
use kiln::scene::{Camera, Material, Scene, shapes};
use kiln::shader::principled::Principled;

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
    let wall = scene.add_material(Material::emitter("emitter", Vec3::ONE));
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

/// The furnace for a principled material: a faceted sphere of it in a uniform environment
/// of radiance 1. Returns the image's mean and the mean over pixels fully on the sphere.
fn principled_furnace(material: Material, light_sampling: bool, spp: u32) -> (f32, f32) {
    let (image, on_sphere) = principled_furnace_pixels(material, light_sampling, spp);
    (image, mean(&on_sphere).x)
}

/// [`principled_furnace`]'s image mean and the pixels fully on the sphere.
fn principled_furnace_pixels(
    material: Material,
    light_sampling: bool,
    spp: u32,
) -> (f32, Vec<Vec3>) {
    let ctx = gpu();
    let mut scene = furnace_scene(0.5, 1.0);
    scene.materials[0] = Material {
        name: "test".into(),
        ..material
    };
    let mut s = settings(SIZE, SIZE, spp);
    s.light_sampling = light_sampling;
    // Unbounded, as scenes are by default: a furnace returns all its light only without
    // a bounce limit. At 64 bounces smooth glass lost 0.1 % (paths caught inside the
    // faceted sphere), more than four standard errors once Russian roulette stopped
    // cutting paths inside glass short (survives_roulette's eta_scale).
    s.max_bounces = 1024;
    let (px, on_sphere) = furnace_render(&ctx, &scene, s);
    (mean(&px).x, on_sphere)
}

/// The standard error of the mean of the pixels' red channel, from their spread: a bound
/// on the Monte Carlo error of the mean where every pixel has the same expectation.
fn standard_error_of_mean(pixels: &[Vec3]) -> f32 {
    let n = pixels.len() as f32;
    let m = mean(pixels).x;
    let variance = pixels.iter().map(|p| (p.x - m).powi(2)).sum::<f32>() / (n - 1.0);
    (variance / n).sqrt()
}

/// The mean over the sphere of `material`'s furnace at 256 spp and its standard error,
/// which must be small enough (< 0.0025) for four of them to bound a percent.
fn sphere_mean_and_error(name: &str, material: &Material, light_sampling: bool) -> (f32, f32) {
    let (_, pixels) = principled_furnace_pixels(material.clone(), light_sampling, 256);
    let (m, se) = (mean(&pixels).x, standard_error_of_mean(&pixels));
    eprintln!("{name}, light sampling {light_sampling}: mean {m}, standard error {se}");
    assert!(
        se < 0.0025,
        "{name} (light sampling {light_sampling}): standard error {se} too large to test"
    );
    (m, se)
}

fn white() -> Material {
    Material {
        principled: Principled {
            base_color: Vec3::ONE,
            specular_color: Vec3::ONE,
            ..Principled::default()
        },
        ..Material::default()
    }
}

#[test]
fn furnace_smooth_layers_of_white_reflect_one_within_four_standard_errors() {
    // Smooth glass, smooth white metal, a smooth coat over white diffuse, thin walls:
    // no energy is lost or created, so the sphere reads exactly 1 up to Monte Carlo noise.
    let cases = [
        (
            "smooth glass",
            Material {
                principled: Principled {
                    transmission_weight: 1.0,
                    roughness: 0.0,
                    ..white().principled
                },
                ..white()
            },
        ),
        (
            "smooth white metal",
            Material {
                principled: Principled {
                    metallic: 1.0,
                    roughness: 0.0,
                    ..white().principled
                },
                ..white()
            },
        ),
        (
            "smooth coat over white diffuse",
            Material {
                principled: Principled {
                    coat_weight: 1.0,
                    coat_roughness: 0.0,
                    specular_weight: 0.0,
                    ..white().principled
                },
                ..white()
            },
        ),
        (
            "thin-walled glass",
            Material {
                principled: Principled {
                    transmission_weight: 1.0,
                    roughness: 0.0,
                    thin_walled: true,
                    ..white().principled
                },
                ..white()
            },
        ),
        (
            // Diffuse reflection and diffuse transmission through the wall, white.
            "translucent thin wall",
            Material {
                principled: Principled {
                    subsurface_weight: 0.5,
                    specular_weight: 0.0,
                    thin_walled: true,
                    ..white().principled
                },
                ..white()
            },
        ),
    ];
    for (name, material) in cases {
        for light_sampling in [false, true] {
            // With BSDF sampling alone each bounce picks a lobe in proportion to its share
            // of the energy and weights it f cos / pdf = 1; what noise remains comes from
            // Russian roulette (which ends 5% of paths past the third bounce and weights the
            // rest by 1/0.95) and, with next-event estimation, from MIS-weighted sums. Both
            // are exact in expectation, and every pixel's expectation is 1, so the pixels'
            // spread is noise alone: the sphere's mean must be 1 within four standard
            // errors of the mean (a false alarm once in ~16000 runs), and those errors
            // must be small enough for that to mean something (4 SE < 0.01).
            let (m, se) = sphere_mean_and_error(name, &material, light_sampling);
            assert!(
                (m - 1.0).abs() < 4.0 * se + 1e-5,
                "{name} (light sampling {light_sampling}): mean {m}, standard error {se}"
            );
        }
    }
}

#[test]
fn furnace_white_metal_stays_white_at_every_roughness() {
    // Multiple-scattering compensation returns the energy single-scattering GGX loses
    // (0.89 at roughness 0.5 without it, measured on this sphere).
    for roughness in [0.25, 0.5, 0.75, 1.0] {
        let material = Material {
            principled: Principled {
                metallic: 1.0,
                roughness,
                ..white().principled
            },
            ..white()
        };
        let (_, on_sphere) = principled_furnace(material, true, 256);
        eprintln!("white metal, roughness {roughness}: {on_sphere}");
        assert!(
            (on_sphere - 1.0).abs() < 0.03,
            "roughness {roughness}: {on_sphere}"
        );
    }
}

#[test]
fn furnace_white_glass_stays_white_at_every_roughness() {
    // Rough glass is scaled by its tabulated energy albedo (Turquin 2019); without it this
    // sphere measured 0.81 (solid) and 0.78 (thin-walled) at roughness 0.5.
    for thin_walled in [false, true] {
        for roughness in [0.25, 0.5, 0.75, 1.0] {
            let material = Material {
                principled: Principled {
                    transmission_weight: 1.0,
                    roughness,
                    thin_walled,
                    ..white().principled
                },
                ..white()
            };
            let (_, on_sphere) = principled_furnace(material, true, 256);
            eprintln!("white glass, thin {thin_walled}, roughness {roughness}: {on_sphere}");
            assert!(
                (on_sphere - 1.0).abs() < 0.03,
                "thin {thin_walled}, roughness {roughness}: {on_sphere}"
            );
        }
    }
}

#[test]
fn furnace_rough_layers_of_white_lose_little_and_never_gain() {
    // Each case's expectation, bounded per configuration: within four standard errors of
    // the mean (see `furnace_smooth_layers_of_white_reflect_one_within_four_standard_errors`) plus 0.005
    // for what the tabulated albedos (16² and 8² entries, interpolated) leave, with
    // BSDF sampling and with next-event estimation alike.
    //
    // Rough white metal is compensated for multiple scattering (Kulla & Conty 2017) and
    // rough Oren–Nayar diffuse is energy-preserving (EON), so both are exactly white: 1.
    // Uncompensated GGX measured 0.89 here, which this bound fails. Sheen over diffuse
    // scales the base by the sheen's albedo, which loses nothing either. A rough specular
    // layer or coat over a diffuse base loses what albedo scaling cannot return (the light
    // the base sends back up and the layer reflects down again): 0.990 measured on this
    // sphere at roughness 0.5 and IOR 1.5 (the coat and the specular layer are the same
    // lobe, so the two agree to the bit), and never more than 1.
    let cases = [
        (
            "rough white metal",
            Material {
                principled: Principled {
                    metallic: 1.0,
                    roughness: 0.5,
                    ..white().principled
                },
                ..white()
            },
            1.0,
        ),
        (
            "white plastic",
            Material {
                principled: Principled {
                    roughness: 0.5,
                    ..white().principled
                },
                ..white()
            },
            0.990,
        ),
        (
            "rough (Oren–Nayar) white diffuse",
            Material {
                principled: Principled {
                    diffuse_roughness: 1.0,
                    specular_weight: 0.0,
                    ..white().principled
                },
                ..white()
            },
            1.0,
        ),
        (
            "sheen over white diffuse",
            Material {
                principled: Principled {
                    sheen_weight: 1.0,
                    specular_weight: 0.0,
                    ..white().principled
                },
                ..white()
            },
            1.0,
        ),
        (
            "rough coat over white diffuse",
            Material {
                principled: Principled {
                    coat_weight: 1.0,
                    coat_roughness: 0.5,
                    specular_weight: 0.0,
                    ..white().principled
                },
                ..white()
            },
            0.990,
        ),
    ];
    for (name, material, expected) in cases {
        for light_sampling in [false, true] {
            let (m, se) = sphere_mean_and_error(name, &material, light_sampling);
            let bound = 4.0 * se + 0.005;
            assert!(
                m <= 1.0 + 4.0 * se,
                "{name} (light sampling {light_sampling}) creates energy: {m} ± {se}"
            );
            assert!(
                (m - expected).abs() < bound,
                "{name} (light sampling {light_sampling}): {m}, expected {expected} ± {bound}"
            );
        }
    }
}

/// The mean over the sphere of each channel of `material`'s furnace, with its standard
/// error, at `spp` samples per pixel.
fn sphere_channel_means(
    name: &str,
    material: &Material,
    light_sampling: bool,
    spp: u32,
) -> [(f32, f32); 3] {
    let (_, pixels) = principled_furnace_pixels(material.clone(), light_sampling, spp);
    std::array::from_fn(|c| {
        let channel: Vec<Vec3> = pixels.iter().map(|p| Vec3::splat(p[c])).collect();
        let (m, se) = (mean(&channel).x, standard_error_of_mean(&channel));
        eprintln!(
            "{name}, light sampling {light_sampling}, channel {c}: mean {m}, standard error {se}"
        );
        assert!(
            se < 0.004,
            "{name} (light sampling {light_sampling}): standard error {se} too large to test"
        );
        (m, se)
    })
}

/// `entry_ior` is the subsurface IOR (the walk's refractive entry), `ior` the boundary's.
fn white_subsurface(
    radius: Vec3,
    scale: f32,
    anisotropy: f32,
    ior: f32,
    entry_ior: f32,
) -> Material {
    Material {
        principled: Principled {
            subsurface_weight: 1.0,
            subsurface_radius: radius,
            subsurface_scale: scale,
            subsurface_anisotropy: anisotropy,
            subsurface_ior: entry_ior,
            ior,
            roughness: 0.0,
            ..white().principled
        },
        ..white()
    }
}

#[test]
fn furnace_white_subsurface_is_one_in_every_channel() {
    // A white base colour maps to a medium that absorbs nothing (albedo exactly 1), so
    // whatever enters the sphere leaves it again: the sphere reads 1, whether its
    // boundary reflects nothing (IOR 1, index-matched) or is a smooth dielectric, and in
    // every channel when the radius differs per channel (sampled by MIS over the
    // channels). Radii are the sphere's size, so walks end well within their step bound.
    let cases = [
        (
            "index-matched",
            white_subsurface(Vec3::ONE, 0.5, 0.0, 1.0, 1.01),
        ),
        (
            "behind a smooth dielectric, entry IOR 3.8",
            white_subsurface(Vec3::ONE, 0.5, 0.0, 1.5, 3.8),
        ),
        (
            "chromatic radius, forward scattering",
            white_subsurface(Vec3::new(1.0, 0.5, 0.25), 1.0, 0.7, 1.5, 1.4),
        ),
    ];
    for (name, material) in cases {
        // Per-channel free flights make chromatic walks noisier.
        let spp = if name.starts_with("chromatic") {
            1024
        } else {
            256
        };
        for light_sampling in [false, true] {
            for (c, (m, se)) in sphere_channel_means(name, &material, light_sampling, spp)
                .into_iter()
                .enumerate()
            {
                assert!(
                    (m - 1.0).abs() < 4.0 * se + 1e-4,
                    "{name} (light sampling {light_sampling}) channel {c}: mean {m}, standard error {se}"
                );
            }
        }
    }
}

#[test]
fn subsurface_stays_finite_at_parameter_extremes() {
    let ctx = gpu();
    let mut checked = 0;
    for radius in [0.0, 1e-6, 1.0, 1e6] {
        for scale in [1e-4, 1e4] {
            // The entry IOR beyond Cycles' range on both sides (clamped to [1.01, 3.8]).
            for (base, anisotropy, entry_ior) in
                [(0.0, 0.0, 1.0), (1.0, 1.0, 3.8), (0.5, 0.999, 100.0)]
            {
                let mut scene = furnace_scene(0.5, 1.0);
                scene.materials[0] = Material {
                    name: "extreme".into(),
                    principled: Principled {
                        base_color: Vec3::splat(base),
                        subsurface_weight: 1.0,
                        subsurface_radius: Vec3::new(radius, radius * 0.5, radius * 0.1),
                        subsurface_scale: scale,
                        subsurface_anisotropy: anisotropy,
                        subsurface_ior: entry_ior,
                        ..Principled::default()
                    },
                    ..Material::default()
                };
                // `render` fails on any non-finite sample.
                let px = render(&ctx, &scene, settings(8, 8, 4)).radiance();
                for p in px {
                    assert!(
                        p.is_finite() && p.max_element() < 20.0,
                        "radius {radius}, scale {scale}, base {base}, g {anisotropy}, IOR {entry_ior}: {p}"
                    );
                }
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 24);
}
