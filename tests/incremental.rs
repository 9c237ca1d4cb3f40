//! Edits written into a built renderer (`Renderer::update`) give the film, bit for bit,
//! of a renderer built afresh for the edited scene, without building a kernel; what
//! cannot be written in place is refused and leaves the renderer as it was. The
//! interactive pacing (small tiles, statistics once a pass) renders the same bits as the
//! final one.

mod common;

use std::sync::Arc;

use common::{fresh_gpu, gpu, settings};
use glam::{Affine3A, Quat, Vec3};
use kiln::film::Film;
use kiln::material::graph::{Input, Value};
use kiln::material::parse_material;
use kiln::render::materials::scene_materials;
use kiln::render::{
    GpuContext, KernelKind, Pacing, RenderControl, RenderSettings, Renderer, UpdateError, Updated,
};
use kiln::scene::{self, Light, Material, Scene};
use kiln::shader::sampling::Sampler;

const SIZE: u32 = 48;
const SAMPLES: u32 = 6;

/// The Cornell box with a point light added, so that every kind of edit has a target.
fn scene() -> Scene {
    let mut s = scene::default_scene().expect("bundled scene");
    s.add_light(Light::Point {
        position: Vec3::new(278.0, 400.0, 200.0),
        intensity: Vec3::splat(2.0e4),
        radius: 0.0,
    });
    s
}

fn render_settings(specialize: bool) -> RenderSettings {
    RenderSettings {
        kernel: if specialize {
            KernelKind::Specialized
        } else {
            KernelKind::General
        },
        max_bounces: 4,
        ..settings(SIZE, SIZE, SAMPLES)
    }
}

fn film(renderer: &mut Renderer) -> Film {
    let stats = renderer
        .render(0..SAMPLES, RenderControl::default())
        .expect("render");
    assert!(stats.completed);
    renderer.read_film().expect("film")
}

fn fresh(ctx: &Arc<GpuContext>, scene: &Scene, s: RenderSettings) -> Film {
    film(&mut Renderer::new(Arc::clone(ctx), scene, s).expect("renderer"))
}

/// Builds a renderer for `old`, renders it, updates it to `new` and renders again;
/// checks the result against a renderer built for `new` and that no kernel was
/// compiled for the update. Returns what the update wrote.
fn check_update(old: &Scene, new: &Scene, specialize: bool) -> Updated {
    // A device of its own: it counts the kernels compiled.
    let ctx = fresh_gpu();
    let s = RenderSettings {
        volume_resolution: old.settings.volume_resolution,
        ..render_settings(specialize)
    };
    let mut renderer = Renderer::new(Arc::clone(&ctx), old, s).expect("renderer");
    let before = film(&mut renderer);
    let compiled = ctx.pipelines_compiled();
    let updated = renderer.update(old, new).expect("an in-place update");
    renderer.clear_film();
    let after = film(&mut renderer);
    assert_eq!(
        ctx.pipelines_compiled(),
        compiled,
        "an in-place update compiled a kernel"
    );
    assert!(after != before, "the edit did not change the image");
    // An edit of the scene's sampling is the renderer's from then on.
    let sampling = if old.settings.sampling != new.settings.sampling {
        new.settings.sampling
    } else {
        s.sampling
    };
    assert!(
        after == fresh(&ctx, new, RenderSettings { sampling, ..s }),
        "the updated renderer's film differs from a fresh renderer's ({updated:?})"
    );
    updated
}

#[test]
fn a_transform_edit_rebuilds_only_the_instances() {
    let old = scene();
    let mut new = old.clone();
    // The tall block, turned and moved.
    let t = &mut new.instances[7].transform;
    *t = Affine3A::from_translation(Vec3::new(-60.0, 0.0, 40.0))
        * *t
        * Affine3A::from_quat(Quat::from_rotation_y(0.4));
    for specialize in [false, true] {
        let updated = check_update(&old, &new, specialize);
        assert!(updated.instances && !updated.materials, "{updated:?}");
    }
}

#[test]
fn moving_an_emitter_moves_its_light() {
    let old = scene();
    let mut new = old.clone();
    // The ceiling light (instance 5) lowered and shifted: its emissive triangles and the
    // light selection follow it.
    new.instances[5].transform = Affine3A::from_translation(Vec3::new(60.0, -150.0, 0.0));
    let updated = check_update(&old, &new, true);
    assert!(updated.instances && updated.lights, "{updated:?}");
}

#[test]
fn a_light_edit_writes_the_light_distribution() {
    let old = scene();
    let mut new = old.clone();
    new.lights[0].light = Light::Point {
        position: Vec3::new(150.0, 300.0, 120.0),
        intensity: Vec3::new(6.0e4, 2.0e4, 1.0e4),
        radius: 20.0,
    };
    new.environment = Vec3::new(0.05, 0.06, 0.08);
    let updated = check_update(&old, &new, false);
    assert!(updated.lights && !updated.instances, "{updated:?}");
}

/// The editor's kernel draws with the sampler `Params.sampler` names, so another sampler
/// is a parameter there.
#[test]
fn the_editors_kernel_takes_another_sampler_in_place() {
    let old = scene();
    let mut new = old.clone();
    new.settings.sampling.sampler = Sampler::Independent;
    let updated = check_update(&old, &new, false);
    assert!(updated.sampling && !updated.lights, "{updated:?}");
}

#[test]
fn a_material_parameter_edit_writes_the_materials_and_emission() {
    let old = scene();
    let mut new = old.clone();
    // The white walls turn blue; the light's emission changes colour and strength.
    new.materials[0].principled.base_color = Vec3::new(0.2, 0.3, 0.7);
    let light = new
        .materials
        .iter_mut()
        .find(|m| m.is_emissive())
        .expect("an emissive material");
    light.principled.emission_strength *= 0.5;
    light.principled.emission_color = Vec3::new(1.0, 0.5, 0.25);
    for specialize in [false, true] {
        let updated = check_update(&old, &new, specialize);
        assert!(updated.materials && updated.lights, "{updated:?}");
    }
}

/// The Cornell box with its white walls made of the bundled marble graph, whose vein
/// scale is `scale`.
fn marble_scene(scale: f32) -> Scene {
    let mut s = scene();
    let text = std::fs::read_to_string("assets/materials/marble.kmat").expect("marble.kmat");
    let (_, mut graph) = parse_material(&text, "marble.kmat").expect("marble parses");
    let veins = graph.nodes.get_mut("veins").expect("the veins node");
    veins
        .inputs
        .insert("scale".into(), Input::Value(Value::Float(scale)));
    s.materials[0] = Material::from_graph("marble", graph).expect("marble compiles");
    s
}

#[test]
fn live_constants_keep_a_graphs_code_when_only_its_values_change() {
    let (a, b) = (marble_scene(1.2), marble_scene(3.5));
    let live = |s: &Scene| scene_materials(s, KernelKind::General).expect("compiles");
    let inline = |s: &Scene| scene_materials(s, KernelKind::Specialized).expect("compiles");
    assert_eq!(live(&a).wgsl, live(&b).wgsl, "live code depends on a value");
    assert_ne!(live(&a).parameters, live(&b).parameters);
    assert!(
        live(&a).parameters.iter().any(|p| p[0] == 1.2),
        "the scale is a parameter"
    );
    assert_ne!(
        inline(&a).wgsl,
        inline(&b).wgsl,
        "inline code holds the value"
    );
    assert!(inline(&a).parameters.is_empty());
}

#[test]
fn a_graph_value_edit_writes_parameters_in_the_editors_kernel_and_renders_as_inline() {
    let (old, new) = (marble_scene(1.2), marble_scene(3.5));
    // The unspecialised kernel (the viewport's) takes the edit in place, and its image
    // is a fresh renderer's, bit for bit.
    let updated = check_update(&old, &new, false);
    assert!(updated.materials, "{updated:?}");
    // The specialised kernel folds the value into its code: the same edit needs a kernel.
    let ctx = gpu();
    let mut specialised =
        Renderer::new(Arc::clone(&ctx), &old, render_settings(true)).expect("renderer");
    assert!(
        matches!(
            specialised.update(&old, &new),
            Err(UpdateError::NeedsRebuild { kernel: true, .. })
        ),
        "a specialised kernel holds the graph's values"
    );
    // Live and inline constants give the same image up to float rounding: the driver
    // compiles arithmetic on literals differently (folds, contracts) from arithmetic on
    // loaded values, which changes low bits and sends a few paths elsewhere. Measured:
    // relative RMSE 1.8e-3 at 6 samples (lavapipe), where the edit itself changes the
    // image by far more; a wrong parameter would show as the edit's size.
    let radiance = |s: &Scene, specialize: bool| -> Vec<f64> {
        fresh(&ctx, s, render_settings(specialize))
            .sums
            .iter()
            .flat_map(|s| [s[0] / s[3], s[1] / s[3], s[2] / s[3]])
            .collect()
    };
    let relative_rmse = |a: &[f64], b: &[f64]| {
        let mean = b.iter().sum::<f64>() / b.len() as f64;
        let squares: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
        (squares / a.len() as f64).sqrt() / mean
    };
    let inline = radiance(&new, true);
    let error = relative_rmse(&radiance(&new, false), &inline);
    let edit = relative_rmse(&radiance(&old, true), &inline);
    assert!(
        error < 5e-3 && error * 10.0 < edit,
        "live and inline images differ: relative RMSE {error} (the edit's own: {edit})"
    );
}

#[test]
fn edits_that_need_a_new_renderer_are_refused_and_change_nothing() {
    let ctx = gpu();
    let old = scene();
    let s = render_settings(true);
    let mut renderer = Renderer::new(Arc::clone(&ctx), &old, s).expect("renderer");
    let original = film(&mut renderer);

    let mut added = old.clone();
    added.instances.push(added.instances[6].clone());
    let mut remeshed = old.clone();
    remeshed.meshes[0].positions[0].y += 10.0;
    let mut metal = old.clone();
    // A metal lobe the specialised (matte) kernel leaves out: a new kernel.
    metal.materials[0].principled.metallic = 1.0;
    let mut invalid = old.clone();
    invalid.instances[0].material = 99;
    // Lights at infinity, which the kernel of a scene without them leaves out.
    let mut sky = old.clone();
    sky.environment = Vec3::new(0.05, 0.06, 0.08);
    // The specialised kernel has its sampler compiled in.
    let mut sampler = old.clone();
    sampler.settings.sampling.sampler = Sampler::Independent;

    for (what, new, kernel) in [
        ("an added instance", &added, Some(false)),
        ("a changed mesh", &remeshed, Some(false)),
        ("a new lobe", &metal, Some(true)),
        ("a sky", &sky, Some(true)),
        ("another sampler", &sampler, Some(true)),
        ("an invalid scene", &invalid, None),
    ] {
        match (renderer.update(&old, new), kernel) {
            (Err(UpdateError::NeedsRebuild { kernel: k, .. }), Some(expected)) => {
                assert_eq!(k, expected, "{what}: whether a kernel is needed");
            }
            (Err(UpdateError::Render(_)), None) => {}
            (other, _) => panic!("{what}: {other:?}"),
        }
    }
    renderer.clear_film();
    assert!(
        film(&mut renderer) == original,
        "a refused edit changed the renderer"
    );
}

/// The editor's kernel takes cut-outs from the scene (`lobes::FROM_SCENE`): shadows
/// through them evaluate materials, which a scene without them should not pay for. The
/// first alpha below 1 needs a new kernel; edits of it below 1 are written in place.
#[test]
fn the_editors_kernel_gains_cutouts_with_a_new_kernel() {
    let old = scene();
    let mut cut = old.clone();
    cut.materials[0].principled.alpha = 0.5;
    let mut renderer = Renderer::new(gpu(), &old, render_settings(false)).expect("renderer");
    assert!(
        matches!(
            renderer.update(&old, &cut),
            Err(UpdateError::NeedsRebuild { kernel: true, .. })
        ),
        "a first cut-out in the editor's kernel"
    );
    let mut cut_more = cut.clone();
    cut_more.materials[0].principled.alpha = 0.25;
    let updated = check_update(&cut, &cut_more, false);
    assert!(updated.materials, "{updated:?}");
}

#[test]
fn interactive_pacing_renders_the_same_bits() {
    let ctx = gpu();
    let s = render_settings(false);
    let final_film = fresh(&ctx, &scene(), s);
    let mut renderer = Renderer::new(Arc::clone(&ctx), &scene(), s).expect("renderer");
    // A budget far below any dispatch shrinks the tiles to the smallest size, which cuts
    // the 48-pixel image unevenly.
    renderer.set_pacing(Pacing::Interactive { budget_us: 1 });
    for sample in 0..SAMPLES {
        let stats = renderer
            .render(sample..sample + 1, RenderControl::default())
            .expect("render");
        assert!(stats.completed);
        assert!(stats.rays > 0, "the pass's statistics were read");
    }
    assert!(renderer.tile_size() < SIZE, "{}", renderer.tile_size());
    assert!(renderer.read_film().expect("film") == final_film);
}

/// The Cornell box with a cloud in it: a sphere holding a volume whose density is noise on
/// the world position, `density` per unit at most (a heterogeneous volume, baked into a
/// grid at `resolution` points).
fn cloud_scene(density: f32, resolution: u32) -> Scene {
    let mut s = scene();
    let text = format!(
        "(version: 1, name: \"cloud\", nodes: {{
            \"geometry\": (type: \"geometry\"),
            \"noise\": (type: \"noise_texture\", inputs: {{ \"vector\": \"geometry.position\", \"scale\": 0.02 }}),
            \"density\": (type: \"math\", params: {{ \"operation\": \"multiply\" }}, inputs: {{ \"a\": \"noise.fac\", \"b\": {density:?} }}),
            \"v\": (type: \"volume_scatter\", inputs: {{ \"color\": (0.9, 0.7, 0.5), \"density\": \"density.value\" }}),
            \"out\": (type: \"material_output\", inputs: {{ \"volume\": \"v.volume\" }}),
        }})"
    );
    let (_, graph) = parse_material(&text, "cloud").expect("the cloud parses");
    let cloud = s.add_material(Material::from_graph("cloud", graph).expect("the cloud compiles"));
    let sphere = s.add_mesh(kiln::scene::shapes::uv_sphere(24, 12, false));
    s.add_instance(
        sphere,
        cloud,
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(120.0),
            Quat::IDENTITY,
            Vec3::new(278.0, 200.0, 280.0),
        ),
    );
    s.settings.volume_resolution = resolution;
    s
}

#[test]
fn edits_of_a_baked_volume_bake_it_again_and_render_as_a_fresh_renderer() {
    // The editor's kernel (live constants): a value edit of the volume's graph is a
    // parameter write and a bake, and so is a move (the density reads the world
    // position). Either way the film is a fresh renderer's, bit for bit, and no kernel
    // is compiled.
    let old = cloud_scene(0.02, 32);
    let denser = cloud_scene(0.05, 32);
    let updated = check_update(&old, &denser, false);
    assert!(updated.materials, "{updated:?}");
    let mut moved = old.clone();
    let cloud = moved.instances.len() - 1;
    moved.instances[cloud].transform =
        Affine3A::from_translation(Vec3::new(-60.0, 40.0, 0.0)) * moved.instances[cloud].transform;
    let updated = check_update(&old, &moved, false);
    assert!(updated.instances && !updated.materials, "{updated:?}");
    // Another resolution lays the grid out anew: a new renderer, the same kernel.
    let ctx = gpu();
    let s = RenderSettings {
        volume_resolution: 32,
        ..render_settings(false)
    };
    let mut renderer = Renderer::new(Arc::clone(&ctx), &old, s).expect("renderer");
    let finer = cloud_scene(0.02, 48);
    match renderer.update(&old, &finer) {
        Err(UpdateError::NeedsRebuild { kernel: false, .. }) => {}
        other => panic!("a resolution edit: {other:?}"),
    }
}
