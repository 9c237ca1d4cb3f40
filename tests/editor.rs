//! The editor driven like a user, headless on lavapipe: egui_kittest runs the real
//! `EditorApp` (eframe with the wgpu backend, the renderer on the same device) and clicks,
//! types and presses keys. The viewport accumulates on a worker thread and stops at a
//! small sample limit, so the tests step frames until it reports what they wait for.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use egui::accesskit::{self, Role};
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT, Queryable};
use glam::Vec3;
use kiln::editor::{EditorApp, EditorOptions, ScriptedDialogs, Selection};
use kiln::plugin::PluginHost;

const SAMPLE_LIMIT: u32 = 2;
/// Building the viewport's kernel on lavapipe takes seconds on a busy machine.
const WAIT: Duration = Duration::from_secs(240);

fn harness(dialogs: ScriptedDialogs) -> Harness<'static, EditorApp> {
    harness_with(dialogs, PluginHost::default())
}

fn harness_with(dialogs: ScriptedDialogs, plugins: PluginHost) -> Harness<'static, EditorApp> {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: set before any thread of this test starts a device.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    Harness::builder()
        .with_size(egui::vec2(1280.0, 800.0))
        .wgpu_setup(kiln::editor::wgpu_setup(true))
        .build_eframe(move |cc| {
            EditorApp::new(
                cc,
                EditorOptions {
                    file: None,
                    dialogs: Box::new(dialogs),
                    plugins,
                    sample_limit: SAMPLE_LIMIT,
                },
            )
        })
}

/// Steps frames until `done` holds; fails naming `what` after [`WAIT`].
fn step_until(harness: &mut Harness<'_, EditorApp>, what: &str, done: impl Fn(&EditorApp) -> bool) {
    let start = Instant::now();
    while !done(harness.state()) {
        assert!(
            start.elapsed() < WAIT,
            "timed out waiting for {what}; viewport error: {:?}",
            harness.state().viewport_status().and_then(|s| s.error)
        );
        harness.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    harness.step();
}

fn samples_done(app: &EditorApp) -> bool {
    app.viewport_status()
        .is_some_and(|s| s.samples >= SAMPLE_LIMIT && s.error.is_none())
}

/// Sets the `axis`-th field (0 = X) of the inspector row `row` as a screen reader would.
fn set_field(harness: &mut Harness<'_, EditorApp>, row: &str, axis: usize, value: f64) {
    let fields: Vec<_> = harness
        .get_all_by_role_and_label(Role::SpinButton, row)
        .collect();
    assert_eq!(fields.len(), 3, "the {row} row has X, Y and Z");
    let (target_node, target_tree) = fields[axis].accesskit_node().locate();
    harness.event(egui::Event::AccessKitActionRequest(
        accesskit::ActionRequest {
            action: accesskit::Action::SetValue,
            target_node,
            target_tree,
            data: Some(accesskit::ActionData::NumericValue(value)),
        },
    ));
    harness.step();
    harness.step();
}

#[test]
fn a_transform_edit_restarts_accumulation_without_compiling_and_undo_restores_it() {
    let mut harness = harness(ScriptedDialogs::default());
    step_until(&mut harness, "the first samples", samples_done);
    let gpu = harness.state().gpu().expect("a wgpu device").clone();
    let compiled = gpu.pipelines_compiled();
    let status = harness.state().viewport_status().unwrap();
    assert!(
        status.size[0] > 100 && status.size[1] > 100,
        "{:?}",
        status.size
    );

    // Select the short block in the outliner and move it in the inspector.
    harness.get_by_label("block").click();
    harness.step();
    assert_eq!(
        harness.state().document().selection,
        Some(Selection::Object(6))
    );
    let before = harness.state().document().scene().instances[6].transform;
    set_field(&mut harness, "Location", 0, 250.0);
    let moved = harness.state().document().scene().instances[6].transform;
    assert!((moved.translation.x - 250.0).abs() < 1e-3, "{moved:?}");
    assert!((moved.translation.y - before.translation.y).abs() < 1e-3);

    let restarts = status.restarts;
    let revision = harness.state().viewport_status().unwrap().shown_revision;
    step_until(&mut harness, "the moved block's samples", |app| {
        app.viewport_status().is_some_and(|s| {
            s.restarts > restarts && s.shown_revision != revision && s.samples >= SAMPLE_LIMIT
        })
    });
    assert_eq!(
        gpu.pipelines_compiled(),
        compiled,
        "a transform edit must not compile a kernel"
    );
    let edited = harness.state().viewport_status().unwrap();
    assert!(
        edited.instance_uploads > status.instance_uploads,
        "the transform was not written into the instance buffer"
    );
    assert_eq!(
        (edited.renderer_builds, edited.kernel_builds),
        (status.renderer_builds, status.kernel_builds),
        "a transform edit builds no renderer and no kernel"
    );
    assert_eq!(edited.material_updates, status.material_updates);

    // Ctrl+Z puts the block back.
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.step();
    assert_eq!(
        harness.state().document().scene().instances[6].transform,
        before
    );
    assert!(!harness.state().document().is_dirty());
    // Ctrl+Shift+Z moves it again.
    harness.key_press_modifiers(
        egui::Modifiers::COMMAND.plus(egui::Modifiers::SHIFT),
        egui::Key::Z,
    );
    harness.step();
    assert_eq!(
        harness.state().document().scene().instances[6].transform,
        moved
    );
}

#[test]
fn clicking_the_viewport_selects_the_object_under_the_pointer() {
    let mut harness = harness(ScriptedDialogs::default());
    step_until(&mut harness, "the first samples", samples_done);
    let rect = harness
        .state()
        .viewport_rect()
        .expect("the viewport was laid out");
    let view = *harness.state().view();
    // Where the tall block's centre appears in the viewport.
    let centre: Vec3 = harness.state().document().scene().instances[7]
        .transform
        .translation
        .into();
    let (right, up, forward) = view.frame();
    let tan_half = (view.fov_y_degrees.to_radians() * 0.5).tan();
    let rel = centre - view.position;
    let z = rel.dot(forward);
    let x = rel.dot(right) / z / (tan_half * rect.width() / rect.height());
    let y = rel.dot(up) / z / tan_half;
    let pos = egui::pos2(
        rect.left() + (x + 1.0) * 0.5 * rect.width(),
        rect.top() + (1.0 - y) * 0.5 * rect.height(),
    );
    for pressed in [true, false] {
        harness.event(egui::Event::PointerMoved(pos));
        harness.event(egui::Event::PointerButton {
            pos,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::NONE,
        });
        harness.step();
    }
    harness.step();
    assert_eq!(
        harness.state().document().selection,
        Some(Selection::Object(7))
    );
    // The inspector shows the selected object under its name, beside the outliner's row.
    assert_eq!(harness.query_all_by_label("block.001").count(), 2);
}

#[test]
fn save_reopen_gives_the_same_document_and_unsaved_changes_prompt() {
    let dir = tempfile::tempdir().unwrap();
    let path: PathBuf = dir.path().join("edited.kiln");
    let mut dialogs = ScriptedDialogs::default();
    dialogs.save.push_back(path.clone());
    dialogs.open.push_back(path.clone());
    dialogs.open.push_back(path.clone());
    let mut harness = harness(dialogs);
    harness.step();

    harness.get_by_label("block.001").click();
    harness.step();
    set_field(&mut harness, "Scale", 1, 200.0);
    assert!(harness.state().document().is_dirty());
    let edited = harness.state().document().scene().clone();

    // Ctrl+S on a document without a file asks where, then writes it.
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    harness.step();
    assert!(path.is_file(), "nothing written at {}", path.display());
    assert!(!harness.state().document().is_dirty());
    assert_eq!(harness.state().document().path(), Some(path.as_path()));

    // Ctrl+O reopens it (no prompt: nothing unsaved) and gives the same scene.
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::O);
    harness.step();
    assert!(!harness.state().is_prompting());
    assert_eq!(*harness.state().document().scene(), edited);

    // An unsaved edit makes Ctrl+O ask first; Cancel keeps the document as it is.
    harness
        .query_all_by_label("block.001")
        .next()
        .unwrap()
        .click();
    harness.step();
    set_field(&mut harness, "Location", 2, 100.0);
    let unsaved = harness.state().document().scene().clone();
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::O);
    harness.step();
    assert!(harness.state().is_prompting());
    assert!(harness.query_by_label("Unsaved changes").is_some());
    harness.get_by_label("Cancel").click();
    harness.step();
    assert!(!harness.state().is_prompting());
    assert_eq!(*harness.state().document().scene(), unsaved);

    // Don't Save goes on to open the file, dropping the edit.
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::O);
    harness.step();
    harness.get_by_label("Don't Save").click();
    harness.step();
    assert_eq!(*harness.state().document().scene(), edited);
    assert!(!harness.state().document().is_dirty());
}

#[test]
fn a_file_that_fails_to_open_is_reported_and_the_document_kept() {
    let dir = tempfile::tempdir().unwrap();
    let broken = dir.path().join("broken.kiln");
    std::fs::write(&broken, "( version: 1, camera: ").unwrap();
    let mut dialogs = ScriptedDialogs::default();
    dialogs.open.push_back(broken.clone());
    let mut harness = harness(dialogs);
    harness.step();
    let scene = harness.state().document().scene().clone();
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::O);
    harness.step();
    harness.step();
    let error = harness
        .state()
        .error()
        .expect("the failure is shown")
        .to_owned();
    assert!(error.contains("broken.kiln"), "{error}");
    assert!(harness.query_by_label("Error").is_some());
    assert_eq!(*harness.state().document().scene(), scene);
}

#[test]
fn a_gltf_opens_through_the_importer_plugin_and_saves_as_a_kiln_scene() {
    // The bundled plugins, as `cargo build` left them next to the test executable.
    let exe = std::env::current_exe().unwrap();
    let mut plugins = PluginHost::default();
    plugins.load_dir(exe.parent().unwrap(), true);
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("quad.glb");
    kiln::bench::write_glb(&kiln::scene::shapes::quad(), &glb).unwrap();
    let saved = dir.path().join("quad.kiln");
    let mut dialogs = ScriptedDialogs::default();
    dialogs.open.push_back(glb);
    dialogs.save.push_back(saved.clone());
    let mut harness = harness_with(dialogs, plugins);
    harness.step();

    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::O);
    harness.step();
    assert_eq!(harness.state().error(), None);
    let imported = harness.state().document().scene().clone();
    assert_eq!(imported.triangle_count(), 2, "the quad's two triangles");
    // An imported file is not a Kiln scene: saving asks where, then writes one.
    assert_eq!(harness.state().document().path(), None);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    harness.step();
    assert_eq!(harness.state().document().path(), Some(saved.as_path()));
    assert_eq!(kiln::scene::load_scene(&saved).unwrap(), imported);
}
