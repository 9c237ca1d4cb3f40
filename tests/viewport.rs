//! The viewport's worker applies each edit the cheapest way: a transform or a light is
//! written into the renderer in place (no renderer, no kernel built), and an edit that
//! needs a new kernel is built on another thread while the old renderer keeps
//! accumulating its image, then swapped in. Prints how long each edit took to show
//! (`cargo test --test viewport -- --nocapture`; docs/BENCHMARKS.md).

use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{Affine3A, Vec3};
use kiln::editor::viewport::{GraphKernels, Target, ViewportRenderer, ViewportStatus};
use kiln::material::{Input, Value};
use kiln::render::GpuContext;
use kiln::scene::{self, Light, Material, Scene};

/// Building a kernel on lavapipe takes seconds on a busy machine.
const WAIT: Duration = Duration::from_secs(240);

fn target(scene: Scene, revision: u64, size: [u32; 2]) -> Target {
    Target {
        camera: scene.camera,
        scene: Arc::new(scene),
        scene_revision: revision,
        size,
        // Never reached: the viewport keeps accumulating.
        sample_limit: 1 << 20,
        view: Default::default(),
        // Graph edits here measure compiled kernels (value edits in place, structure
        // compiled): tests/node_editor.rs measures interpreted ones.
        graphs: GraphKernels::Compiled,
    }
}

fn wait_for(
    viewport: &ViewportRenderer,
    what: &str,
    done: impl Fn(&ViewportStatus) -> bool,
) -> ViewportStatus {
    let start = Instant::now();
    loop {
        let status = viewport.status();
        assert!(status.error.is_none(), "{what}: {:?}", status.error);
        if done(&status) {
            return status;
        }
        assert!(start.elapsed() < WAIT, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// Posts `scene` as `revision` and waits for its first image; returns the status then
/// and the time from posting to that image.
fn edit(
    viewport: &mut ViewportRenderer,
    scene: Scene,
    revision: u64,
    size: [u32; 2],
    what: &str,
) -> (ViewportStatus, Duration) {
    let posted = Instant::now();
    viewport.post(target(scene, revision, size));
    let status = wait_for(viewport, what, |s| {
        s.shown_revision == Some(revision) && s.shown_restart == s.restarts
    });
    (status, posted.elapsed())
}

fn median(mut times: Vec<Duration>) -> Duration {
    times.sort();
    times[times.len() / 2]
}

#[test]
fn edits_are_applied_in_place_and_new_kernels_are_built_in_the_background() {
    edits_at([64, 48]);
}

/// The same at the editor's default viewport size (950×754 in a 1280×800 window), where the
/// worker keeps a coarse film beside the full one and the first image after an edit is
/// the coarse film's: both layers must take edits in place. Its printed times are the
/// numbers in docs/BENCHMARKS.md.
#[test]
fn edits_at_the_default_viewport_size_update_both_films_in_place() {
    edits_at([950, 754]);
}

fn edits_at(size: [u32; 2]) {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: set before any thread of this test starts a device.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    let ctx = GpuContext::new(None).unwrap_or_else(|e| panic!("a GPU adapter: {e}"));
    let mut viewport = ViewportRenderer::new(Arc::clone(&ctx), || {});
    let mut scene = scene::default_scene().expect("bundled scene");
    scene.add_light(Light::Point {
        position: Vec3::new(278.0, 400.0, 200.0),
        intensity: Vec3::splat(2.0e4),
        radius: 0.0,
    });
    let (first, first_time) = edit(&mut viewport, scene.clone(), 1, size, "the first image");
    assert_eq!(first.renderer_builds, 1);

    // Each kind of edit a few times over, for a median.
    const REPEATS: u64 = 5;
    let mut revision = 1;
    let mut status = first.clone();

    // A transform: the instances are written, nothing is built.
    let mut transform_times = Vec::new();
    for i in 0..REPEATS {
        let step = if i % 2 == 0 { -50.0 } else { 40.0 };
        scene.instances[7].transform =
            Affine3A::from_translation(Vec3::new(step, 0.0, 30.0)) * scene.instances[7].transform;
        revision += 1;
        let (moved, time) = edit(
            &mut viewport,
            scene.clone(),
            revision,
            size,
            "the moved block",
        );
        assert!(moved.restarts > status.restarts);
        status = moved;
        transform_times.push(time);
    }
    assert_eq!(status.instance_uploads, first.instance_uploads + REPEATS);
    assert_eq!(
        (status.renderer_builds, status.kernel_builds),
        (first.renderer_builds, first.kernel_builds),
        "a transform edit built a renderer or a kernel"
    );

    // A light: its buffers are written, nothing is built.
    let mut light_times = Vec::new();
    let lit_before = status.clone();
    for i in 0..REPEATS {
        scene.lights[0].light = Light::Point {
            position: Vec3::new(200.0 + 10.0 * i as f32, 350.0, 150.0),
            intensity: Vec3::new(4.0e4, 2.0e4, 1.0e4),
            radius: 10.0,
        };
        revision += 1;
        let (lit, time) = edit(
            &mut viewport,
            scene.clone(),
            revision,
            size,
            "the new light",
        );
        status = lit;
        light_times.push(time);
    }
    assert_eq!(status.light_updates, lit_before.light_updates + REPEATS);
    assert_eq!(status.renderer_builds, first.renderer_builds);

    // A camera move: nothing is written but the camera.
    let mut camera_times = Vec::new();
    let mut camera = scene.camera;
    for _ in 0..REPEATS {
        camera.position += Vec3::new(4.0, 0.0, 0.0);
        let mut moved = target(scene.clone(), revision, size);
        moved.camera = camera;
        let restarts = status.restarts;
        let posted = Instant::now();
        viewport.post(moved);
        status = wait_for(&viewport, "the moved camera", |s| {
            s.restarts > restarts && s.shown_restart == s.restarts
        });
        camera_times.push(posted.elapsed());
    }
    assert_eq!(status.renderer_builds, first.renderer_builds);
    let turned = status;

    // A graph material: a new kernel, built while the old image keeps accumulating.
    let marble = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/materials/marble.kmat");
    let (name, graph) = kiln::material::load_material(&marble).expect("marble.kmat");
    scene.materials[0] = Material::from_graph(&name, graph).expect("a graph material");
    let before = viewport.status();
    let posted = Instant::now();
    revision += 1;
    viewport.post(target(scene.clone(), revision, size));
    // Passes of the old image completed while the new renderer was being built.
    let mut passes_meanwhile = 0;
    let rebuilt = loop {
        let s = viewport.status();
        assert!(s.error.is_none(), "the kernel edit: {:?}", s.error);
        if s.shown_revision == Some(revision) {
            break s;
        }
        if s.building.is_some() && s.shown_revision == Some(revision - 1) {
            passes_meanwhile = s.passes - before.passes;
        }
        assert!(
            posted.elapsed() < WAIT,
            "timed out waiting for the graph material's image"
        );
        std::thread::sleep(Duration::from_millis(2));
    };
    let kernel_time = posted.elapsed();
    assert_eq!(rebuilt.renderer_builds, turned.renderer_builds + 1);
    assert!(
        rebuilt.kernel_builds > turned.kernel_builds,
        "the graph material compiled no kernel"
    );
    assert!(rebuilt.building.is_none());
    if size[0] * size[1] <= 64 * 48 {
        // A compile takes far longer than a pass of this small image.
        assert!(
            passes_meanwhile > 2,
            "the old image stopped while the kernel was built ({passes_meanwhile} passes)"
        );
    }

    // A value of the graph (the veins' scale, as a node-editor slider sets it): the
    // viewport's kernel reads graph constants from its parameter buffer, so the edit is
    // a write, not a kernel.
    let mut value_times = Vec::new();
    status = rebuilt.clone();
    for i in 0..REPEATS {
        let graph_material = scene.materials[0].graph.as_ref().expect("the marble graph");
        let mut graph = graph_material.graph.clone();
        graph.nodes.get_mut("veins").expect("veins").inputs.insert(
            "scale".into(),
            Input::Value(Value::Float(1.5 + 0.5 * i as f32)),
        );
        scene.materials[0] = Material::from_graph(&name, graph).expect("still compiles");
        revision += 1;
        let (edited, time) = edit(
            &mut viewport,
            scene.clone(),
            revision,
            size,
            "the new scale",
        );
        assert!(edited.restarts > status.restarts, "accumulation restarted");
        status = edited;
        value_times.push(time);
    }
    assert_eq!(
        status.material_updates,
        rebuilt.material_updates + REPEATS,
        "each value edit was written in place"
    );
    assert_eq!(
        (status.renderer_builds, status.kernel_builds),
        (rebuilt.renderer_builds, rebuilt.kernel_builds),
        "a graph value edit built a renderer or a kernel"
    );

    println!(
        "viewport {}x{} on {}: first image {first_time:?}; edit to first image, median of \
         {REPEATS}: transform {:?}, light {:?}, camera {:?}, graph value {:?}; new kernel \
         {kernel_time:?} ({passes_meanwhile} passes of the old image meanwhile)",
        size[0],
        size[1],
        ctx.describe(),
        median(transform_times),
        median(light_times),
        median(camera_times),
        median(value_times),
    );
}
