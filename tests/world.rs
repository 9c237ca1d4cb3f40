//! Worlds: node graphs for the environment, baked into maps, with the Sky Texture's sun
//! a light of its own. The sky against published atmospheric values (Bucholtz's Rayleigh
//! optical depth, Kasten and Young's air mass), the sun's irradiance on a horizontal
//! plane against their closed form through the whole renderer, graph worlds against the
//! constant environment and environment maps they stand for, a furnace under a graph
//! world, and the look-dev default's exposure against its bake.

mod common;

use std::f32::consts::PI;

use common::{fresh_gpu, furnace_render, furnace_scene, gpu, mean, render, settings};
use glam::{Affine3A, Vec3};
use kiln::material::{Graph, Input, Link, Node, Param, Value};
use kiln::render::environment_cdf::luminance;
use kiln::render::world_bake::{Environment, bake_world, lookdev_exposure};
use kiln::render::{RenderControl, Renderer};
use kiln::scene::{Camera, EnvironmentMap, Light, Material, Scene, World, lookdev, shapes};
use std::sync::Arc;

/// A world of one Sky Texture into the output, its sun at `elevation` degrees, with
/// these amounts of air, dust and ozone.
fn sky(elevation: f32, [air, dust, ozone]: [f32; 3], disc: bool) -> World {
    let mut graph = Graph::default();
    graph.add(
        "sky",
        Node::new("sky_texture")
            .input("sun_elevation", Input::Value(Value::Float(elevation)))
            .input("air", Input::Value(Value::Float(air)))
            .input("dust", Input::Value(Value::Float(dust)))
            .input("ozone", Input::Value(Value::Float(ozone)))
            .param("sun_disc", Param::Bool(disc)),
    );
    graph.add(
        "out",
        Node::new("world_output").input("color", Input::Link(Link::new("sky", "color"))),
    );
    let mut world = World::from_graph(graph).expect("the sky world compiles");
    world.resolution = 64;
    world
}

/// The editor's window device on a CPU adapter hands its compiles to a second device
/// (`GpuContext::rehearse_compiles_on`): a world's bake runs there, and gives the same
/// map as on a device of its own.
#[test]
fn a_world_bakes_on_the_rehearsal_device_where_there_is_one() {
    let map = |baked: kiln::render::world_bake::BakedWorld| match baked.environment {
        Environment::Map(map) => map,
        Environment::Constant(c) => panic!("a sky bakes into a map, not {c}"),
    };
    // Devices of their own: the window's gets a rehearsal, and both count compiles.
    let window = fresh_gpu();
    let background = window.sibling().expect("a second device on the adapter");
    window.rehearse_compiles_on(Arc::clone(&background));
    // A world no other test bakes, so that the last bake's memory does not serve it.
    let mut world = sky(20.0, [1.0, 1.0, 1.0], false);
    world.resolution = 32;
    let rehearsed = map(bake_world(&window, &world).unwrap_or_else(|e| panic!("{e}")));
    if window.info.device_type == wgpu::DeviceType::Cpu {
        assert_eq!(
            window.pipelines_compiled(),
            0,
            "the window's device compiled the bake"
        );
        assert!(background.pipelines_compiled() >= 1);
    } else {
        assert!(
            window.pipelines_compiled() >= 1,
            "nothing is rehearsed on a GPU"
        );
    }
    // The same world baked again on a device without a rehearsal, once another world has
    // taken the last bake's place.
    let plain = fresh_gpu();
    let mut other = world.clone();
    other.resolution = 16;
    bake_world(&plain, &other).unwrap_or_else(|e| panic!("{e}"));
    let direct = map(bake_world(&plain, &world).unwrap_or_else(|e| panic!("{e}")));
    assert_eq!((rehearsed.width, rehearsed.height), (32, 16));
    assert!(
        rehearsed.texels == direct.texels,
        "the two devices' maps differ"
    );
}

/// The luminance of the irradiance of `world`'s one sun, on a surface facing it.
fn sun_irradiance(world: &World) -> f32 {
    let baked = bake_world(&gpu(), world).unwrap_or_else(|e| panic!("{e}"));
    match baked.suns.as_slice() {
        [sun] => match sun.light {
            Light::Distant { irradiance, .. } => luminance(irradiance),
            _ => unreachable!("a sun is a distant light"),
        },
        suns => panic!("{} suns", suns.len()),
    }
}

/// Rayleigh optical depth of the US standard atmosphere at `um` micrometres, from sea
/// level (Bucholtz 1995, "Rayleigh-scattering calculations for the terrestrial
/// atmosphere", Applied Optics 34(15), eq. 8 with the coefficients of its Table 5 for
/// λ > 0.5 µm).
fn bucholtz_optical_depth(um: f32) -> f32 {
    let (a, b, c, d) = (0.00864, 3.916, 0.074, 0.050);
    a * um.powf(-(b + c * um + d / um))
}

/// Relative optical air mass at `zenith` degrees (Kasten and Young 1989, "Revised optical
/// air mass tables and approximation formula", Applied Optics 28(22)).
fn kasten_young_air_mass(zenith: f32) -> f32 {
    1.0 / (zenith.to_radians().cos() + 0.50572 * (96.07995 - zenith).powf(-1.6364))
}

/// The sun seen through air alone keeps exp(−τ m) of its light: the optical depth of
/// Bucholtz's tables at the luminance's effective wavelength (555 nm) and Kasten and
/// Young's air mass, within 1% at the zenith and 30° up.
#[test]
fn the_sun_through_clear_air_keeps_what_published_optical_depths_say() {
    let above = sun_irradiance(&sky(90.0, [0.0, 0.0, 0.0], true));
    // The black body at 5778 K scaled to 1361 W/m², weighted by ȳ: about 1.6.
    assert!((1.4..1.9).contains(&above), "above the atmosphere: {above}");
    for elevation in [90.0, 30.0] {
        let through = sun_irradiance(&sky(elevation, [1.0, 0.0, 0.0], true));
        let m = kasten_young_air_mass(90.0 - elevation);
        let expected = (-bucholtz_optical_depth(0.555) * m).exp();
        let kept = through / above;
        eprintln!("sun {elevation}° up: keeps {kept:.4}, published {expected:.4}");
        assert!(
            (kept / expected - 1.0).abs() < 0.01,
            "sun {elevation}° up: keeps {kept}, published {expected} (air mass {m})"
        );
    }
    // Dust and ozone take more; a sun below the horizon gives nothing.
    let hazy = sun_irradiance(&sky(30.0, [1.0, 1.0, 1.0], true));
    let clear = sun_irradiance(&sky(30.0, [1.0, 0.0, 0.0], true));
    assert!(hazy < clear * 0.95, "hazy {hazy}, clear {clear}");
    assert_eq!(sun_irradiance(&sky(-5.0, [1.0, 1.0, 1.0], true)), 0.0);
}

/// The texel of `map` that direction `d` reads.
fn texel(map: &EnvironmentMap, d: Vec3) -> Vec3 {
    let d = d.normalize();
    let u = (d.x.atan2(-d.z) / (2.0 * PI) + 0.5).fract();
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    let x = ((u * map.width as f32) as u32).min(map.width - 1);
    let y = ((v * map.height as f32) as u32).min(map.height - 1);
    map.texels[(y * map.width + x) as usize]
}

/// `world` baked into its map and suns.
fn bake(world: &World) -> (EnvironmentMap, Vec<kiln::scene::LightObject>) {
    let baked = bake_world(&gpu(), world).unwrap_or_else(|e| panic!("{e}"));
    match baked.environment {
        Environment::Map(map) => (map, baked.suns),
        Environment::Constant(c) => panic!("a sky bakes into a map, not {c}"),
    }
}

/// A clear sky is blue overhead and brighter toward the sun than away from it. Below the
/// horizon lies its ground, a matte surface the sun lights: with the default albedo 0.3
/// it shows about 0.3/π of the sun's irradiance on it (within 25%: the haze in front
/// adds and takes some), and with albedo 0 only the haze, darker than the zenith.
#[test]
fn the_sky_is_blue_and_brightest_toward_the_sun_over_a_lit_ground() {
    let world = sky(30.0, [1.0, 1.0, 1.0], true);
    let (map, suns) = bake(&world);
    let zenith = texel(&map, Vec3::Y);
    assert!(
        zenith.z > zenith.y && zenith.y > zenith.x,
        "the zenith is {zenith}, not blue"
    );
    // The sun stands toward −Z (rotation 0), 30° up.
    let toward = luminance(texel(&map, Vec3::new(0.0, 0.4, -1.0)));
    let away = luminance(texel(&map, Vec3::new(0.0, 0.4, 1.0)));
    assert!(toward > 2.0 * away, "toward the sun {toward}, away {away}");

    let below = Vec3::new(1.0, -1.0, 0.0);
    let Light::Distant { irradiance, .. } = suns[0].light else {
        unreachable!("a sun is a distant light")
    };
    let ground = 0.3 / PI * luminance(irradiance) * 30f32.to_radians().sin();
    let seen = luminance(texel(&map, below));
    assert!(
        (seen / ground - 1.0).abs() < 0.25,
        "the ground shows {seen}; 0.3/π of the sun's irradiance on it is {ground}"
    );
    let mut black = world.clone();
    black
        .graph
        .nodes
        .get_mut("sky")
        .unwrap()
        .inputs
        .insert("ground_albedo".into(), Input::Value(Value::Float(0.0)));
    let (map, _) = bake(&black);
    let haze = luminance(texel(&map, below));
    assert!(
        haze < 0.5 * luminance(zenith),
        "over a black ground the haze is {haze}, the zenith {zenith}"
    );
}

/// A white horizontal plane seen from above: the sun adds (1/π) E cos θ to its radiance,
/// with E the sun's irradiance through the atmosphere, from Bucholtz's optical depth and
/// Kasten and Young's air mass, within 2%: the sky node, the bake and the renderer's sun
/// light together.
#[test]
fn the_sun_lights_a_horizontal_plane_as_the_closed_form_says() {
    let ctx = gpu();
    let elevation = 40.0f32;
    let above = sun_irradiance(&sky(90.0, [0.0, 0.0, 0.0], true));
    let radiance = |disc: bool| {
        let mut scene = Scene::empty(Camera::look_at(Vec3::new(0.0, 1.0, 0.0), Vec3::ZERO, 20.0));
        scene.camera.up = Vec3::Z;
        scene.world = Some(sky(elevation, [1.0, 0.0, 0.0], disc));
        let white = scene.add_material(Material::diffuse("white", Vec3::ONE));
        let plane = scene.add_mesh(shapes::quad());
        scene.add_instance(
            plane,
            white,
            Affine3A::from_scale(Vec3::new(50.0, 1.0, 50.0)),
        );
        luminance(mean(&render(&ctx, &scene, settings(16, 16, 64)).radiance()))
    };
    let sun = radiance(true) - radiance(false);
    let zenith = 90.0 - elevation;
    let e = above
        * (-bucholtz_optical_depth(0.555) * kasten_young_air_mass(zenith)).exp()
        * zenith.to_radians().cos();
    let expected = e / PI;
    eprintln!("the sun adds {sun:.4} to the plane's radiance; the closed form {expected:.4}");
    assert!(
        (sun / expected - 1.0).abs() < 0.02,
        "the sun adds {sun} to the plane; the closed form says {expected}"
    );
}

/// A world whose colour comes through a link bakes into a map of that colour, which
/// renders like the constant environment (the same colour, its exact path): relative RMSE
/// at the noise level; a world with nothing linked keeps the constant path.
#[test]
fn a_constant_world_renders_like_the_constant_environment() {
    let ctx = gpu();
    let colour = [0.6, 0.8, 1.0];
    let mut graph = Graph::default();
    graph.add(
        "rgb",
        Node::new("rgb").input("color", Input::Value(Value::Vec3(colour))),
    );
    graph.add(
        "out",
        Node::new("world_output")
            .input("color", Input::Link(Link::new("rgb", "color")))
            .input("strength", Input::Value(Value::Float(0.5))),
    );
    let mut linked = World::from_graph(graph).expect("compiles");
    linked.resolution = 32;
    let baked = bake_world(&ctx, &linked).expect("bake");
    let Environment::Map(map) = &baked.environment else {
        panic!("a linked colour bakes into a map")
    };
    let expected = Vec3::from(colour) * 0.5;
    assert!(
        map.texels
            .iter()
            .all(|t| (*t - expected).abs().max_element() < 1e-6),
        "the map is not {expected} everywhere"
    );
    let constant = bake_world(&ctx, &World::constant(expected)).expect("bake");
    assert_eq!(constant.environment, Environment::Constant(expected));

    // The noise level: two renders of the constant environment with other seeds differ
    // by it; the world's render differs from one of them by no more (×1.25), and their
    // means agree within 1%.
    let mut scene = furnace_scene(0.5, 0.0);
    scene.environment = expected;
    let with_seed = |scene: &Scene, seed: u32| {
        let mut s = settings(24, 24, 64);
        s.seed = seed;
        render(&ctx, scene, s).radiance()
    };
    let reference = with_seed(&scene, 1);
    let other = with_seed(&scene, 2);
    scene.environment = Vec3::ZERO;
    scene.world = Some(linked);
    let world = with_seed(&scene, 3);
    let level = luminance(mean(&reference)) as f64;
    let (noise, difference) = (
        common::rmse(&other, &reference) / level,
        common::rmse(&world, &reference) / level,
    );
    eprintln!("relative RMSE: world {difference:.4}, noise level {noise:.4}");
    assert!(
        difference < 1.25 * noise,
        "the world differs by a relative RMSE of {difference}, the noise is {noise}"
    );
    let (a, b) = (mean(&reference), mean(&world));
    assert!(
        ((a - b) / a).abs().max_element() < 0.01,
        "constant environment {a}, world {b}"
    );
}

/// A white sphere under a world graph (a linked colour, so baked and sampled as a map)
/// reflects the world's radiance times its albedo: a furnace, with and without light
/// sampling.
#[test]
fn a_furnace_under_a_world_graph_returns_the_albedo() {
    let ctx = gpu();
    let mut graph = Graph::default();
    graph.add(
        "rgb",
        Node::new("rgb").input("color", Input::Value(Value::Vec3([1.0; 3]))),
    );
    graph.add(
        "out",
        Node::new("world_output").input("color", Input::Link(Link::new("rgb", "color"))),
    );
    let mut world = World::from_graph(graph).expect("compiles");
    world.resolution = 16;
    let mut scene = furnace_scene(0.8, 0.0);
    scene.world = Some(world);
    for light_sampling in [false, true] {
        let mut s = settings(24, 24, 128);
        s.light_sampling = light_sampling;
        let (_, on_sphere) = furnace_render(&ctx, &scene, s);
        let m = mean(&on_sphere);
        assert!(
            (m - Vec3::splat(0.8)).abs().max_element() < 0.01,
            "light sampling {light_sampling}: {m}"
        );
    }
}

/// An Environment Texture world at the image's own resolution, read by nearest texel,
/// bakes into the image's texels exactly: the world renders as the environment map does.
#[test]
fn an_image_world_bakes_into_the_image() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sky.exr");
    let (w, h) = (32u32, 16u32);
    let mut image = image::Rgb32FImage::new(w, h);
    for (x, y, p) in image.enumerate_pixels_mut() {
        let bright = if (10..13).contains(&x) && (4..6).contains(&y) {
            50.0
        } else {
            1.0
        };
        *p = image::Rgb([
            bright * (0.1 + x as f32 / w as f32),
            bright * 0.3,
            bright * (0.2 + y as f32 / h as f32),
        ]);
    }
    image.save(&path).unwrap();
    let mut graph = Graph::default();
    graph.add(
        "image",
        Node::new("environment_texture")
            .param("file", Param::Text(path.to_string_lossy().into_owned()))
            .param("interpolation", Param::Text("closest".into())),
    );
    graph.add(
        "out",
        Node::new("world_output").input("color", Input::Link(Link::new("image", "color"))),
    );
    let mut world = World::from_graph(graph).expect("compiles");
    world.resolution = w;
    let baked = bake_world(&gpu(), &world).expect("bake");
    let Environment::Map(map) = baked.environment else {
        panic!("an image world bakes into a map")
    };
    let loaded = EnvironmentMap::load(&path).expect("loads");
    assert_eq!((map.width, map.height), (loaded.width, loaded.height));
    for (i, (a, b)) in map.texels.iter().zip(&loaded.texels).enumerate() {
        assert!(
            (*a - *b).abs().max_element() <= 1e-3 * b.max_element(),
            "texel {i}: baked {a}, image {b}"
        );
    }
}

/// The look-dev default's exposure is the one its sky's bake gives (an 18% grey ground
/// at 0.18), within 0.05 stop.
#[test]
fn the_lookdev_exposure_is_its_skys() {
    let baked = bake_world(&gpu(), &lookdev::world()).expect("bake");
    let measured = lookdev_exposure(&baked);
    assert!(
        (measured - lookdev::EXPOSURE_EV).abs() < 0.05,
        "the look-dev sky's bake gives {measured} EV; lookdev::EXPOSURE_EV is {}",
        lookdev::EXPOSURE_EV
    );
}

/// Where world point `p` lands in a `width` × `height` image of `camera` (pixels from the
/// top left).
fn project(camera: &Camera, p: Vec3, width: u32, height: u32) -> (f32, f32) {
    let (right, up, forward) = camera.frame();
    let v = p - camera.position;
    let tan_half = (camera.fov_y_degrees.to_radians() * 0.5).tan();
    let aspect = width as f32 / height as f32;
    let z = v.dot(forward);
    let x = v.dot(right) / (z * tan_half * aspect);
    let y = -v.dot(up) / (z * tan_half);
    (
        (x + 1.0) * 0.5 * width as f32,
        (y + 1.0) * 0.5 * height as f32,
    )
}

/// A model imported without lights or camera (a ball, from a binary glTF) gets the
/// look-dev default: the image's mean lies in a sane range at the chosen exposure, the
/// model is centred and fills most of the frame's height, and its shadow is visible on
/// the ground (darker than the ground beside it by half).
#[test]
fn an_import_without_lights_or_camera_gets_the_lookdev_default() {
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("ball.glb");
    kiln::bench::write_glb(&shapes::uv_sphere(48, 24, true), &glb).unwrap();
    let plugins = common::bundled_plugins();
    let imported = plugins.import(&glb).expect("imports");
    assert!(!imported.has_lights && !imported.has_camera);
    let mut scene = imported.scene;
    lookdev::add_ground(&mut scene, lookdev::Ground::Plane);
    let (width, height) = (96u32, 64u32);
    let ctx = gpu();
    let luminances = |scene: &Scene| -> Vec<f32> {
        render(&ctx, scene, settings(width, height, 64))
            .radiance()
            .iter()
            .map(|c| luminance(*c) * scene.settings.view.exposure_ev.exp2())
            .collect()
    };
    let lit = luminances(&scene);
    let image_mean = lit.iter().sum::<f32>() / lit.len() as f32;
    assert!(
        (0.1..0.6).contains(&image_mean),
        "the exposed image's mean luminance is {image_mean}"
    );

    // Where the ball is: black in a white world, on no ground.
    let mut mask = scene.clone();
    mask.world = None;
    mask.environment = Vec3::ONE;
    mask.instances.retain(|i| i.name != "ground");
    for m in &mut mask.materials {
        *m = Material::diffuse("black", Vec3::ZERO);
    }
    mask.settings.view.exposure_ev = 0.0;
    let covered: Vec<(f32, f32)> = luminances(&mask)
        .iter()
        .enumerate()
        .filter(|(_, l)| **l < 0.5)
        .map(|(i, _)| {
            (
                (i as u32 % width) as f32 + 0.5,
                (i as u32 / width) as f32 + 0.5,
            )
        })
        .collect();
    let n = covered.len() as f32;
    let centre = covered
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.0 / n, a.1 + p.1 / n));
    assert!(
        (centre.0 / width as f32 - 0.5).abs() < 0.05
            && (centre.1 / height as f32 - 0.5).abs() < 0.05,
        "the model's centre is at {centre:?} in a {width}x{height} image"
    );
    let (top, bottom) = covered
        .iter()
        .fold((f32::MAX, f32::MIN), |a, p| (a.0.min(p.1), a.1.max(p.1)));
    let fill = (bottom - top + 1.0) / height as f32;
    assert!(
        (0.7..0.9).contains(&fill),
        "the model spans {fill} of the frame's height, not about {}",
        lookdev::FRAME_FILL
    );

    // The shadow of the ball's centre on the ground, and the ground as far on the sun's
    // side: the first is in shadow, the second lit.
    let sun = lookdev::world().suns().unwrap()[0].direction;
    let (lo, hi) = mask.bounds().unwrap();
    let c = (lo + hi) * 0.5;
    let shadow = c - sun * ((c.y - lo.y) / sun.y);
    let beside = Vec3::new(2.0 * c.x - shadow.x, lo.y, 2.0 * c.z - shadow.z);
    let at = |p: Vec3| {
        let (x, y) = project(&scene.camera, p, width, height);
        assert!(
            (0.0..width as f32).contains(&x) && (0.0..height as f32).contains(&y),
            "{p} is out of view at ({x}, {y})"
        );
        lit[y as usize * width as usize + x as usize]
    };
    let (dark, light) = (at(shadow), at(beside));
    eprintln!(
        "look-dev: mean {image_mean:.3}, centre {centre:?}, fill {fill:.3}, shadow {dark:.3} beside {light:.3}"
    );
    assert!(
        dark < 0.5 * light,
        "the ground in the ball's shadow is {dark}, beside it {light}"
    );
}

/// A ball imported from glTF with `--ground catcher`'s ground under it, rendered at
/// 96×64 with AOVs: the renderer, and the pixels of the ball, its shadow, the ground far
/// from it and the sky.
fn catcher_render(ball_alpha: f32) -> (Scene, Renderer, [usize; 4]) {
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("ball.glb");
    kiln::bench::write_glb(&shapes::uv_sphere(48, 24, true), &glb).unwrap();
    let mut scene = common::bundled_plugins()
        .import(&glb)
        .expect("imports")
        .scene;
    lookdev::add_ground(&mut scene, lookdev::Ground::Catcher);
    let material = scene.instances[0].material;
    scene.materials[material].principled.alpha = ball_alpha;
    let (width, height) = (96u32, 64u32);
    let mut s = settings(width, height, 64);
    s.aovs = true;
    let mut renderer = Renderer::new(gpu(), &scene, s).expect("renderer");
    renderer
        .render(0..64, RenderControl::default())
        .expect("render");
    let at = |p: Vec3| {
        let (x, y) = project(&scene.camera, p, width, height);
        y as usize * width as usize + x as usize
    };
    let sun = lookdev::world().suns().unwrap()[0].direction;
    // The ball's bounds (the scene's include the ground).
    let ball = &scene.instances[0];
    let (lo, hi) = scene.meshes[ball.mesh]
        .positions
        .iter()
        .map(|p| ball.transform.transform_point3(*p))
        .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| (lo.min(p), hi.max(p)));
    let c = (lo + hi) * 0.5;
    let shadow = at(c - sun * ((c.y - lo.y) / sun.y));
    let far = at(Vec3::new(
        c.x - 3.0 * (hi.x - lo.x),
        lo.y,
        c.z + 0.5 * (hi.z - lo.z),
    ));
    let sky = 0; // the top-left pixel looks above the horizon
    let pixels = [at(c), shadow, far, sky];
    (scene, renderer, pixels)
}

fn alpha_aov(renderer: &Renderer) -> Vec<f32> {
    renderer
        .read_aovs()
        .expect("aovs")
        .expect("asked for")
        .alpha
}

/// `--ground catcher`: the ground is a shadow catcher, so the camera sees the ball, the
/// ball's shadow as alpha (a shadow's opacity: the share of light the ball blocks) and a
/// transparent background; the export's alpha is that coverage, its colour black there.
#[test]
fn a_shadow_catcher_keeps_the_shadow_as_alpha_over_a_transparent_background() {
    let (scene, renderer, [ball, shadow, far, sky]) = catcher_render(1.0);
    assert!(renderer.transparent());
    let radiance = renderer.read_film().expect("film").radiance();
    let alpha = alpha_aov(&renderer);
    eprintln!(
        "catcher: alpha ball {:.3}, shadow {:.3}, far ground {:.3}, sky {:.3}",
        alpha[ball], alpha[shadow], alpha[far], alpha[sky]
    );
    assert!(alpha[ball] > 0.99, "the ball's alpha is {}", alpha[ball]);
    assert!(
        alpha[shadow] > 0.6,
        "the shadow's alpha is {}",
        alpha[shadow]
    );
    assert!(
        alpha[far] < 0.15,
        "the far ground's alpha is {}",
        alpha[far]
    );
    assert_eq!(alpha[sky], 0.0);
    for i in [shadow, far, sky] {
        assert_eq!(radiance[i], Vec3::ZERO, "pixel {i} has colour");
    }
    let export =
        kiln::render::export_film(&renderer, scene.settings.view, kiln::scene::Denoiser::None)
            .expect("export");
    for i in [ball, shadow, far, sky] {
        assert_eq!(export.radiance[4 * i + 3], alpha[i].clamp(0.0, 1.0));
    }
}

/// A half-transparent ball casts a lighter shadow on a catcher: light crosses its two
/// surfaces at ½ each, so the catcher keeps ¾ of the opaque ball's shadow.
#[test]
fn a_cutout_casts_a_partial_shadow_on_a_shadow_catcher() {
    let (_, opaque, [_, shadow, _, _]) = catcher_render(1.0);
    let (_, half, _) = catcher_render(0.5);
    let (opaque, half) = (alpha_aov(&opaque)[shadow], alpha_aov(&half)[shadow]);
    eprintln!("catcher shadow: opaque ball {opaque:.3}, half-transparent ball {half:.3}");
    // 64 samples of the sky and sun: the ratio is uncertain by a few per cent.
    assert!(
        (half / opaque - 0.75).abs() < 0.1,
        "the half-transparent ball's shadow is {half}, the opaque ball's {opaque}"
    );
}
