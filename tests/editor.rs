//! The editor driven like a user, headless on lavapipe: egui_kittest runs the real
//! `EditorApp` (eframe with the wgpu backend, the renderer on the same device) and clicks,
//! types and presses keys. The viewport accumulates on a worker thread and stops at a
//! small sample limit, so the tests step frames until it reports what they wait for.

use std::path::{Path, PathBuf};
use std::time::Duration;

use egui::accesskit::{self, Role};
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT, Queryable};
use glam::Vec3;
use kiln::editor::final_render::RenderState;
use kiln::editor::session::{SessionStore, ViewportPreferences};
use kiln::editor::{EditorApp, ScriptedDialogs, Selection};
use kiln::film::tonemap::Tonemap;
use kiln::plugin::PluginHost;
use kiln::shader::sampling::{FilterKind, PixelFilter, Sampler, Sampling};

#[path = "common/editor_harness.rs"]
mod editor_harness;

use editor_harness::{
    PIXEL_SIZE, SAMPLE_LIMIT, Setup, assert_standby_returned, bundled_plugins, quad_glb, start,
    step_until, step_until_specialised,
};

fn harness(dialogs: ScriptedDialogs) -> Harness<'static, EditorApp> {
    start(Setup {
        dialogs,
        ..Setup::default()
    })
}

fn harness_with(dialogs: ScriptedDialogs, plugins: PluginHost) -> Harness<'static, EditorApp> {
    start(Setup {
        dialogs,
        plugins,
        ..Setup::default()
    })
}

fn samples_done(app: &EditorApp) -> bool {
    app.viewport_status()
        .is_some_and(|s| s.samples >= SAMPLE_LIMIT && s.error.is_none())
}

/// Sets the `axis`-th field (0 = X) of the inspector row `row` as a screen reader would.
fn set_field(harness: &mut Harness<'_, EditorApp>, row: &str, axis: usize, value: f64) {
    let count = harness
        .get_all_by_role_and_label(Role::SpinButton, row)
        .count();
    assert_eq!(count, 3, "the {row} row has X, Y and Z");
    set_nth_field(harness, row, axis, value);
}

/// Sets the one numeric field labelled `label`.
fn set_value(harness: &mut Harness<'_, EditorApp>, label: &str, value: f64) {
    let count = harness
        .get_all_by_role_and_label(Role::SpinButton, label)
        .count();
    assert_eq!(count, 1, "one field is labelled {label}");
    set_nth_field(harness, label, 0, value);
}

fn set_nth_field(harness: &mut Harness<'_, EditorApp>, label: &str, index: usize, value: f64) {
    let fields: Vec<_> = harness
        .get_all_by_role_and_label(Role::SpinButton, label)
        .collect();
    let (target_node, target_tree) = fields[index].accesskit_node().locate();
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

/// Once the scene is still, the viewport samples with the final render's specialised
/// kernel. An edit that kernel takes in place stays on it; one that needs another lobe goes
/// into the general renderers it replaced, which come back at once, without a build, and
/// are replaced again once the scene is still.
#[test]
fn a_still_viewport_samples_with_the_specialised_kernel_and_edits_need_no_build() {
    use kiln::editor::Command;
    use kiln::editor::viewport::{GraphKernels, ViewportStatus};
    use kiln::render::KernelKind;
    use kiln::shader::principled::ParamValue;

    let mut harness = start(Setup {
        graph_kernels: GraphKernels::InterpretedThenSpecialized(Duration::from_millis(300)),
        // Still accumulating throughout.
        sample_limit: 100_000,
        ..Setup::default()
    });
    let status =
        |h: &Harness<'_, EditorApp>| -> ViewportStatus { h.state().viewport_status().unwrap() };
    let shown = |after: u64| {
        move |app: &EditorApp| {
            app.viewport_status().is_some_and(|s| {
                s.restarts > after && s.shown_restart == s.restarts && s.samples >= 2
            })
        }
    };
    // The Cornell box has no graphs: the general kernel first, then the specialised one.
    step_until(&mut harness, "the general kernel's image", |app| {
        app.viewport_status()
            .is_some_and(|s| s.samples >= 2 && s.kernel == Some(KernelKind::General))
    });
    let general = status(&harness);
    step_until(&mut harness, "the specialised renderers", |app| {
        app.viewport_status()
            .is_some_and(|s| s.compiled_swaps >= 1 && s.samples >= 4)
    });
    let still = status(&harness);
    assert_eq!(still.kernel, Some(KernelKind::Specialized));
    assert_eq!(still.renderer_builds, general.renderer_builds);
    eprintln!(
        "viewport samples/s: general kernel {:.0}, specialised {:.0}",
        general.samples_per_second(),
        still.samples_per_second()
    );

    // A transform edit: written into the specialised renderers in place.
    let mut transform = harness.state().document().scene().instances[6].transform;
    transform.translation.x += 20.0;
    harness.state_mut().apply_command(Command::SetTransform {
        object: 6,
        transform,
    });
    step_until(&mut harness, "the moved block", shown(still.restarts));
    let moved = status(&harness);
    assert_eq!(moved.kernel, Some(KernelKind::Specialized));
    assert!(moved.instance_uploads > still.instance_uploads);
    assert_eq!(
        (moved.renderer_builds, moved.standby_returns),
        (still.renderer_builds, still.standby_returns)
    );

    // A metallic white: a lobe the specialised kernel lacks. The general renderers take
    // both edits (they were kept before the move) and come back.
    let white = harness
        .state()
        .document()
        .scene()
        .materials
        .iter()
        .position(|m| m.name == "white")
        .unwrap();
    harness
        .state_mut()
        .apply_command(Command::SetMaterialParameter {
            material: white,
            parameter: "metallic",
            value: ParamValue::Float(1.0),
        });
    step_until(&mut harness, "the metallic walls", shown(moved.restarts));
    let metallic = status(&harness);
    assert_standby_returned(&moved, &metallic, KernelKind::General);

    // Still again: a specialised kernel with the conductor lobe.
    let again = step_until_specialised(&mut harness, "the specialised renderers again", &metallic);
    assert!(
        again.kernel_builds > metallic.kernel_builds,
        "a kernel with the new lobe"
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
    let pos = on_screen(&harness, 7, rect);
    for pressed in [true, false] {
        pointer(&mut harness, pos, Some(pressed));
    }
    harness.step();
    assert_eq!(
        harness.state().document().selection,
        Some(Selection::Object(7))
    );
    // The inspector shows the selected object under its name, beside the outliner's row.
    assert_eq!(harness.query_all_by_label("block.001").count(), 2);
}

/// Where the centre of object `object` appears in the viewport `rect`.
fn on_screen(harness: &Harness<'_, EditorApp>, object: usize, rect: egui::Rect) -> egui::Pos2 {
    let view = *harness.state().view();
    let centre: Vec3 = harness.state().document().scene().instances[object]
        .transform
        .translation
        .into();
    let (right, up, forward) = view.frame();
    let tan_half = (view.fov_y_degrees.to_radians() * 0.5).tan();
    let rel = centre - view.position;
    let z = rel.dot(forward);
    let x = rel.dot(right) / z / (tan_half * rect.width() / rect.height());
    let y = rel.dot(up) / z / tan_half;
    egui::pos2(
        rect.left() + (x + 1.0) * 0.5 * rect.width(),
        rect.top() + (1.0 - y) * 0.5 * rect.height(),
    )
}

/// Drags with the primary button from `from` to `to` in a few frames.
fn drag(harness: &mut Harness<'_, EditorApp>, from: egui::Pos2, to: egui::Pos2) {
    pointer(harness, from, Some(true));
    for t in [0.1, 0.5, 1.0] {
        pointer(harness, from + (to - from) * t, None);
    }
    pointer(harness, to, Some(false));
    harness.step();
}

#[test]
fn a_new_material_keeps_the_node_editor_s_height() {
    let mut harness = harness(ScriptedDialogs::default());
    harness.step();
    let bar = harness.get_by_label("✚ Drag").rect().center().y;
    let viewport = harness.state().viewport_rect().unwrap();
    let materials = harness.state().document().scene().materials.len();

    harness.get_by_label("New").click();
    for _ in 0..3 {
        harness.step();
    }
    assert_eq!(
        harness.state().document().scene().materials.len(),
        materials + 1
    );
    assert_eq!(harness.state().node_editor().material(), Some(materials));
    // The frame that picks the new material draws no canvas (the document holds it from
    // the next one); the panel must not shrink to that frame.
    let moved = (harness.get_by_label("✚ Drag").rect().center().y - bar).abs();
    assert!(moved < 1.0, "the node editor's bar moved {moved} px");
    assert_eq!(harness.state().viewport_rect().unwrap(), viewport);
}

#[test]
fn a_material_dragged_onto_an_object_in_the_outliner_or_the_viewport_is_assigned() {
    let mut harness = harness(ScriptedDialogs::default());
    harness.step();
    // Selecting the left wall shows its material, red, in the node editor's list.
    harness.get_by_label("left wall").click();
    harness.step();
    let red = 1;
    assert_eq!(harness.state().node_editor().material(), Some(red));
    assert!(harness.query_by_label("fixed parameters").is_some());
    let stats = harness.state().node_editor().stats().cloned();
    assert!(
        matches!(stats, Some(Ok(s)) if s.wgsl_bytes > 0),
        "the editor measures the graph's compile: {stats:?}"
    );

    let chip = harness.get_by_label("✚ Drag").rect().center();
    let row = harness.get_by_label("block").rect().center();
    drag(&mut harness, chip, row);
    assert_eq!(
        harness.state().document().scene().instances[6].material,
        red
    );
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.step();
    assert_eq!(harness.state().document().scene().instances[6].material, 0);

    let rect = harness.state().viewport_rect().unwrap();
    let tall_block = on_screen(&harness, 7, rect);
    let chip = harness.get_by_label("✚ Drag").rect().center();
    drag(&mut harness, chip, tall_block);
    assert_eq!(
        harness.state().document().scene().instances[7].material,
        red
    );
}

#[test]
fn material_thumbnails_show_each_material_on_a_sphere_and_follow_its_edits() {
    let mut harness = start(Setup {
        thumbnails: true,
        ..Setup::default()
    });
    let thumbnail = |app: &EditorApp, i: usize| -> Option<egui::ColorImage> {
        let material = &app.document().scene().materials[i];
        app.thumbnails()?.image(i, material).cloned()
    };
    let started = std::time::Instant::now();
    step_until(&mut harness, "a thumbnail of every material", |app| {
        (0..4).all(|i| thumbnail(app, i).is_some())
    });
    println!("4 thumbnails in {:?}", started.elapsed());
    let (white, red, green) = (0, 1, 2);
    let centre = |image: &egui::ColorImage| image[(32, 34)];
    let corner = |image: &egui::ColorImage| image[(1, 1)];
    let [w, r, g] = [white, red, green].map(|i| thumbnail(harness.state(), i).unwrap());
    // The sphere takes its material's colour; around it is the same sky.
    assert!(centre(&r).r() > 2 * centre(&r).g(), "red: {:?}", centre(&r));
    assert!(centre(&g).g() > centre(&g).r(), "green: {:?}", centre(&g));
    assert!(
        centre(&w).r().abs_diff(centre(&w).g()) < 40,
        "white: {:?}",
        centre(&w)
    );
    assert_eq!(
        corner(&r),
        corner(&g),
        "the sky is the same behind every sphere"
    );
    assert_eq!(harness.state().thumbnails().unwrap().error(), None);

    // An edit of the red material (made metallic in the inspector) makes its thumbnail
    // stale until it is rendered again, differently.
    harness.get_by_label("left wall").click();
    harness.step();
    set_value(&mut harness, "Metallic", 1.0);
    assert!(
        thumbnail(harness.state(), red).is_none(),
        "stale after the edit"
    );
    let edited = std::time::Instant::now();
    step_until(&mut harness, "the edited material's thumbnail", |app| {
        thumbnail(app, red).is_some()
    });
    println!("the edited material's thumbnail in {:?}", edited.elapsed());
    let metal = thumbnail(harness.state(), red).unwrap();
    assert_ne!(metal.pixels, r.pixels, "the thumbnail shows the edit");
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

/// Whether the last frame asked the window to close.
fn asked_to_close(harness: &Harness<'_, EditorApp>) -> bool {
    harness
        .output()
        .viewport_output
        .values()
        .any(|v| v.commands.contains(&egui::ViewportCommand::Close))
}

/// Presses Ctrl+Q (Cmd+Q on a Mac) and says whether the frame that saw it asked the
/// window to close; then releases the keys. (`key_press_modifiers` would step past that
/// frame: it runs one frame per event.)
fn press_quit(harness: &mut Harness<'_, EditorApp>) -> bool {
    let key = |pressed| egui::Event::Key {
        key: egui::Key::Q,
        physical_key: None,
        pressed,
        repeat: false,
        modifiers: egui::Modifiers::COMMAND,
    };
    harness.event(egui::Event::ModifiersChanged(egui::Modifiers::COMMAND));
    harness.event(key(true));
    harness.step();
    let closing = asked_to_close(harness);
    harness.event(key(false));
    harness.event(egui::Event::ModifiersChanged(egui::Modifiers::NONE));
    harness.step();
    closing
}

#[test]
fn ctrl_q_quits_and_asks_first_about_unsaved_changes() {
    let mut harness = harness(ScriptedDialogs::default());
    harness.step();
    assert!(!asked_to_close(&harness));

    // Nothing unsaved: Ctrl+Q closes the window at once.
    assert!(press_quit(&mut harness));
    assert!(!harness.state().is_prompting());

    // An unsaved edit: Ctrl+Q asks first, and Cancel keeps the window and the edit.
    harness.get_by_label("block.001").click();
    harness.step();
    set_field(&mut harness, "Scale", 1, 200.0);
    assert!(!press_quit(&mut harness));
    assert!(harness.state().is_prompting());
    assert!(harness.query_by_label("Unsaved changes").is_some());
    harness.get_by_label("Cancel").click();
    harness.step();
    assert!(!asked_to_close(&harness));
    assert!(!harness.state().is_prompting());
    assert!(harness.state().document().is_dirty());

    // Don't Save closes it (the click's last frame, its release, is where it acts).
    assert!(!press_quit(&mut harness));
    harness.get_by_label("Don't Save").click();
    harness.step();
    assert!(asked_to_close(&harness));
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
    let plugins = bundled_plugins();
    let dir = tempfile::tempdir().unwrap();
    let glb = quad_glb(dir.path());
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
    // The quad brings no lights: the look-dev default stands it on a ground (two more).
    assert_eq!(
        imported.triangle_count(),
        4,
        "the quad's two triangles and the ground's"
    );
    assert!(imported.world.is_some() && imported.instances[1].name == "ground");
    // An imported file is not a Kiln scene: saving asks where, then writes one.
    assert_eq!(harness.state().document().path(), None);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    harness.step();
    assert_eq!(harness.state().document().path(), Some(saved.as_path()));
    assert_eq!(kiln::scene::load_scene(&saved).unwrap(), imported);
}

#[test]
fn render_image_runs_in_the_background_and_exports_the_result() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("render.png");
    let mut dialogs = ScriptedDialogs::default();
    dialogs.export.push_back(png.clone());
    // Tall enough for the whole Render tab and the render's buttons below it.
    let mut harness = start(Setup {
        dialogs,
        size: egui::vec2(1280.0, 1100.0),
        ..Setup::default()
    });
    harness.step();

    // The Render tab sets the document's render settings, one undo step each.
    harness.get_by_label("📷 Render").click();
    harness.step();
    set_value(&mut harness, "Resolution X", 48.0);
    set_value(&mut harness, "Resolution Y", 32.0);
    set_value(&mut harness, "Samples", 3.0);
    set_value(&mut harness, "Grid Resolution", 64.0);
    let settings = harness.state().document().scene().settings;
    assert_eq!(
        (settings.width, settings.height, settings.samples_per_pixel),
        (48, 32, 3)
    );
    assert_eq!(settings.volume_resolution, 64, "Volumes > Grid Resolution");
    // The firefly clamp, as Cycles' Light Paths > Clamping: off until set.
    assert_eq!(settings.clamp, kiln::scene::Clamp::default());
    set_value(&mut harness, "Indirect Light", 10.0);
    let clamp = harness.state().document().scene().settings.clamp;
    assert_eq!((clamp.direct, clamp.indirect), (0.0, 10.0), "Clamping");
    // The pixel filter and the sampling pattern, as Cycles' Film and Sampling panels.
    set_value(&mut harness, "Filter Width", 2.5);
    for (combo, choice) in [("Pixel Filter", "Gaussian"), ("Pattern", "Independent")] {
        harness.get_by_role_and_label(Role::ComboBox, combo).click();
        harness.step();
        harness.step();
        harness.get_by_label(choice).click();
        harness.step();
        harness.step();
    }
    let sampling = harness.state().document().scene().settings.sampling;
    assert_eq!(
        sampling,
        Sampling {
            sampler: Sampler::Independent,
            filter: PixelFilter {
                kind: FilterKind::Gaussian,
                width: 2.5
            },
        }
    );
    assert!(harness.query_by_label("Render Image").is_some());

    // F12 renders in the background; frames keep coming meanwhile.
    harness.key_press(egui::Key::F12);
    harness.step();
    assert!(harness.state().render_state().is_some(), "a render started");
    step_until(&mut harness, "the final render", |app| {
        matches!(app.render_state(), Some(RenderState::Finished(_)))
    });
    let Some(RenderState::Finished(result)) = harness.state().render_state() else {
        unreachable!()
    };
    assert_eq!((result.film.width, result.film.height), (48, 32));
    assert!(result.completed);
    assert!((result.samples_per_pixel - 3.0).abs() < 1e-9);
    // The Cornell box is lit: the result is not black.
    let mean = result.film.radiance.iter().sum::<f32>() / result.film.radiance.len() as f32;
    assert!(mean > 0.01, "mean radiance {mean}");

    // Export… writes it through the image writers.
    harness
        .query_all_by_label("Export…")
        .next()
        .expect("an Export button")
        .click();
    harness.step();
    assert_eq!(harness.state().error(), None);
    let image = image::open(&png).expect("a PNG was written");
    assert_eq!((image.width(), image.height()), (48, 32));
}

/// The editor on the Cornell box, tall enough for the Render tab's view settings and their
/// menu below the sampling and denoising rows (and the World tab's sky), saving to `path`,
/// once the viewport shows its first samples.
fn tall_editor_saving_to(path: &Path) -> Harness<'static, EditorApp> {
    let mut dialogs = ScriptedDialogs::default();
    dialogs.save.push_back(path.to_owned());
    let mut harness = start(Setup {
        dialogs,
        size: egui::vec2(1280.0, 1100.0),
        ..Setup::default()
    });
    step_until(&mut harness, "the first samples", samples_done);
    harness
}

#[test]
fn view_settings_change_the_display_not_the_samples_and_are_saved_with_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("looks.kiln");
    let mut harness = tall_editor_saving_to(&path);
    let restarts = harness.state().viewport_status().unwrap().restarts;
    harness.get_by_label("📷 Render").click();
    harness.step();

    // Exposure and view transform: one undo step each, and the samples stay.
    set_value(&mut harness, "Exposure", 1.5);
    harness
        .get_by_role_and_label(Role::ComboBox, "View Transform")
        .click();
    harness.step();
    harness.step();
    harness.get_by_label("ACES").click();
    harness.step();
    harness.step();
    let view = harness.state().document().scene().settings.view;
    assert_eq!((view.exposure_ev, view.tonemap), (1.5, Tonemap::Aces));
    for _ in 0..3 {
        harness.step();
    }
    let status = harness.state().viewport_status().unwrap();
    assert_eq!(status.restarts, restarts, "a view change keeps the samples");
    assert!(status.samples >= SAMPLE_LIMIT);

    // The seed is a render setting: it restarts accumulation with other noise.
    set_value(&mut harness, "Seed", 7.0);
    assert_eq!(harness.state().document().scene().settings.seed, 7);
    step_until(&mut harness, "a restart for the new seed", |app| {
        app.viewport_status().is_some_and(|s| s.restarts > restarts)
    });

    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.step();
    assert_eq!(harness.state().document().scene().settings.seed, 0);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.step();
    assert_eq!(
        harness.state().document().scene().settings.view.tonemap,
        Tonemap::Agx
    );
    for _ in 0..2 {
        harness.key_press_modifiers(
            egui::Modifiers::COMMAND | egui::Modifiers::SHIFT,
            egui::Key::Z,
        );
        harness.step();
    }
    let settings = harness.state().document().scene().settings;
    assert_eq!((settings.seed, settings.view), (7, view));

    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    harness.step();
    assert_eq!(kiln::scene::load_scene(&path).unwrap().settings, settings);
}

#[test]
fn duplicate_and_delete_are_undoable_and_a_duplicate_shares_its_mesh() {
    let mut harness = harness(ScriptedDialogs::default());
    harness.step();
    let start = harness.state().document().scene().clone();
    harness.get_by_label("block").click();
    harness.step();
    harness.key_press_modifiers(egui::Modifiers::SHIFT, egui::Key::D);
    harness.step();
    let doc = harness.state().document();
    let copy = doc.objects().len() - 1;
    assert_eq!(doc.objects().len(), start.instances.len() + 1);
    assert_eq!(doc.objects()[copy].name, "block.002");
    let (copy_instance, original) = (&doc.scene().instances[copy], &doc.scene().instances[6]);
    assert_eq!(
        (
            copy_instance.mesh,
            copy_instance.material,
            copy_instance.transform
        ),
        (original.mesh, original.material, original.transform)
    );
    assert_eq!(doc.scene().meshes.len(), start.meshes.len(), "no new mesh");
    assert_eq!(doc.selection, Some(Selection::Object(copy)));
    // The outliner's context menu duplicates too.
    harness.get_by_label("block.001").click_secondary();
    harness.step();
    harness.step();
    // The context menu's entry, beside the outliner (the node editor's material list
    // has a Duplicate button too).
    let panel_left = harness.state().viewport_rect().unwrap().right();
    harness
        .query_all_by_label("Duplicate")
        .find(|n| {
            n.accesskit_node()
                .bounding_box()
                .is_some_and(|b| b.x0 as f32 > panel_left)
        })
        .expect("the outliner's context menu")
        .click();
    harness.step();
    harness.step();
    let count = harness.state().document().objects().len();
    assert_eq!(count, start.instances.len() + 2);
    assert_eq!(
        harness
            .state()
            .document()
            .name(Selection::Object(count - 1)),
        "block.003"
    );
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.step();
    harness.get_by_label("block.002").click();
    harness.step();
    // X deletes the selection (the copy).
    harness.key_press(egui::Key::X);
    harness.step();
    assert_eq!(
        harness.state().document().scene().instances.len(),
        start.instances.len()
    );
    assert_eq!(harness.state().document().selection, None);
    for _ in 0..2 {
        harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
        harness.step();
    }
    assert_eq!(*harness.state().document().scene(), start);
}

#[test]
fn an_import_adds_to_the_scene_as_one_undo_step() {
    let plugins = bundled_plugins();
    let dir = tempfile::tempdir().unwrap();
    let glb = quad_glb(dir.path());
    let mut dialogs = ScriptedDialogs::default();
    dialogs.import.push_back(glb);
    let mut harness = harness_with(dialogs, plugins);
    harness.step();
    let start = harness.state().document().scene().clone();
    import_through_the_menu(&mut harness);
    let scene = harness.state().document().scene().clone();
    assert_eq!(scene.instances.len(), start.instances.len() + 1);
    assert_eq!(scene.triangle_count(), start.triangle_count() + 2);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.step();
    assert_eq!(*harness.state().document().scene(), start);
}

/// The material list's Import Materials… adds a MaterialX file's materials as one undo step (one
/// whose image is missing keeps its graph, with the error, and the import says which
/// file); Export Material… writes the shown material, which reads back as the same graph.
#[test]
fn the_material_list_imports_and_exports_materialx() {
    let dir = tempfile::tempdir().unwrap();
    let brass = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/corpus/materialx/StandardSurface/standard_surface_brass_tiled.mtlx");
    let gold = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/corpus/materialx/StandardSurface/standard_surface_gold.mtlx");
    let out = dir.path().join("gold.mtlx");
    let mut dialogs = ScriptedDialogs::default();
    dialogs.material_import.push_back(brass.clone());
    dialogs.material_import.push_back(gold);
    dialogs.material_import.push_back(brass);
    dialogs.material_export.push_back(out.clone());
    let mut harness = harness_with(dialogs, bundled_plugins());
    harness.step();
    let start = harness.state().document().scene().clone();
    let before = start.materials.len();

    harness.get_by_label("Import Materials…").click();
    harness.step();
    let app = harness.state();
    assert_eq!(app.error(), None);
    let materials = &app.document().scene().materials;
    assert_eq!(materials.len(), before + 1);
    assert_eq!(materials[before].name, "Tiled_Brass");
    // Its images are not in the corpus: the graph is kept, with the error naming one.
    let error = app
        .document()
        .graph_error(before)
        .expect("the missing image's error");
    assert!(error.to_string().contains("brass_"), "{error}");
    let (title, text) = app.notice().expect("the warnings are shown");
    assert!(
        title.contains("warnings") && text.contains("brass_color.jpg"),
        "{text}"
    );
    harness.step();
    harness.get_by_label("OK").click();
    harness.step();
    harness.step();
    assert_eq!(harness.state().notice(), None);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.step();
    assert_eq!(*harness.state().document().scene(), start);

    harness.get_by_label("Import Materials…").click();
    harness.step();
    let app = harness.state();
    assert_eq!((app.error(), app.notice()), (None, None));
    let shown = app.document().material_graph(before).unwrap();
    assert_eq!(app.document().scene().materials[before].name, "Gold");
    harness.get_by_label("Export Material…").click();
    harness.step();
    assert_eq!(harness.state().error(), None);
    let back = bundled_plugins().import_materials(&out).unwrap().materials;
    assert_eq!(back.len(), 1);
    assert_eq!(back[0].0, "Gold");
    let principled = |g: &kiln::material::Graph| {
        g.nodes
            .values()
            .find(|n| n.kind == "principled_bsdf")
            .map(|n| n.inputs.clone())
    };
    assert_eq!(principled(&back[0].1), principled(&shown));

    // A graph that does not compile (its images are missing) is not exported, as `kiln
    // material export` refuses one: no dialog, an error naming it.
    harness.get_by_label("Import Materials…").click();
    harness.step();
    harness.get_by_label("OK").click();
    harness.step();
    harness.get_by_label("Export Material…").click();
    harness.step();
    let error = harness.state().error().expect("the export is refused");
    assert!(
        error.contains("cannot export Tiled_Brass: its graph does not compile"),
        "{error}"
    );
}

/// File ▸ Import… (the dialog answers with the file queued), which must succeed.
fn import_through_the_menu(harness: &mut Harness<'_, EditorApp>) {
    harness.get_by_label("File").click();
    harness.step();
    harness.get_by_label("Import…").click();
    harness.step();
    assert_eq!(harness.state().error(), None);
}

/// A model without lights imported into a new (unlit) scene is staged as `kiln edit
/// model.glb` opens one: the sky world, the look-dev exposure and a ground under it, in
/// the same undo step as the import.
#[test]
fn an_import_into_an_unlit_scene_gets_the_lookdev_default_in_one_undo_step() {
    let dir = tempfile::tempdir().unwrap();
    let mut dialogs = ScriptedDialogs::default();
    dialogs.import.push_back(quad_glb(dir.path()));
    let mut harness = harness_with(dialogs, bundled_plugins());
    harness.step();
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::N);
    harness.step();
    let empty = harness.state().document().scene().clone();
    assert!(harness.state().document().unlit());
    import_through_the_menu(&mut harness);
    let scene = harness.state().document().scene().clone();
    assert!(scene.world.is_some());
    assert_eq!(
        scene.settings.view.exposure_ev,
        kiln::scene::lookdev::EXPOSURE_EV
    );
    assert_eq!(scene.instances.len(), 2, "the quad and its ground");
    assert_eq!(scene.instances[1].name, "ground");
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.step();
    assert_eq!(*harness.state().document().scene(), empty);
}

#[test]
fn an_autosave_left_by_a_crash_is_offered_and_recovered() {
    let state = tempfile::tempdir().unwrap();
    // What a crashed editor leaves: an autosave of an edited Cornell box in a folder
    // named after a process that no longer runs.
    let mut edited = kiln::scene::default_scene().unwrap();
    edited.environment = Vec3::new(0.1, 0.2, 0.3);
    let store = SessionStore::new(state.path().to_owned());
    store.autosave(&edited, &[], None).unwrap();
    let recovery = state.path().join("recovery");
    std::fs::rename(
        recovery.join(std::process::id().to_string()),
        recovery.join(u32::MAX.to_string()),
    )
    .unwrap();

    let mut harness = start(Setup {
        state_dir: Some(state.path().to_owned()),
        autosave_every: Duration::ZERO,
        ..Setup::default()
    });
    harness.step();
    assert!(harness.state().offered_recovery().is_some());
    assert!(harness.query_by_label("Recover unsaved work?").is_some());
    harness.get_by_label("Recover").click();
    harness.step();
    assert_eq!(
        harness.state().document().scene().environment,
        edited.environment
    );
    assert!(
        harness.state().document().is_dirty(),
        "recovered work is unsaved"
    );
    assert!(store.recovery().is_none(), "the offered autosave is gone");

    // This session autosaves its own unsaved work (every frame, as configured here).
    step_until(&mut harness, "an autosave", |_| {
        recovery
            .join(std::process::id().to_string())
            .join("autosave.kiln")
            .is_file()
    });
}

#[test]
fn new_asks_about_unsaved_changes_and_starts_an_empty_scene() {
    let mut harness = harness(ScriptedDialogs::default());
    harness.step();
    harness.get_by_label("block").click();
    harness.step();
    harness.key_press(egui::Key::X);
    harness.step();
    assert!(harness.state().document().is_dirty());
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::N);
    harness.step();
    assert!(harness.state().is_prompting());
    harness.get_by_label("Don't Save").click();
    harness.step();
    let scene = harness.state().document().scene();
    assert!(scene.instances.is_empty() && scene.lights.is_empty());
    assert!(!harness.state().document().is_dirty());
    assert_eq!(harness.state().document().path(), None);
}

/// Pixels that may differ from the snapshot beyond kittest's colour tolerance (0.6, in
/// squared YIQ distance): none. The viewport shows a fixed sample count of a deterministic
/// render, so the window is the same image on every run on the same adapter.
const SNAPSHOT_FAILED_PIXELS: usize = 0;

#[test]
fn the_main_window_matches_its_snapshot() {
    // The viewport as a user first sees it: a pixel per pixel.
    let mut harness = start(Setup {
        pixel_size: 1,
        ..Setup::default()
    });
    harness.get_by_label("block").click();
    step_until(&mut harness, "the first samples", samples_done);
    // Let the node editor's framing and the last texture update settle.
    for _ in 0..10 {
        harness.step();
    }
    let image = harness.render().expect("the window renders");
    // The status line (samples per second, elapsed time) differs from run to run: the
    // snapshot (menu, viewport, properties, node editor) stops above it.
    let ppp = harness.ctx.pixels_per_point();
    let status = harness.state().status_rect().unwrap();
    let height = (status.top() * ppp).floor() as u32;
    let window = image::imageops::crop_imm(&image, 0, 0, image.width(), height).to_image();
    egui_kittest::image_snapshot_options(
        &window,
        "editor_main_window",
        &egui_kittest::SnapshotOptions::new().max_failed_pixels(SNAPSHOT_FAILED_PIXELS),
    );
}

fn pointer(harness: &mut Harness<'_, EditorApp>, pos: egui::Pos2, button: Option<bool>) {
    harness.event(egui::Event::PointerMoved(pos));
    if let Some(pressed) = button {
        harness.event(egui::Event::PointerButton {
            pos,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::NONE,
        });
    }
    harness.step();
}

#[test]
fn g_x_moves_the_selection_along_x_in_one_step_and_esc_cancels_a_rotation() {
    let mut harness = harness(ScriptedDialogs::default());
    harness.step();
    harness.get_by_label("block").click();
    harness.step();
    let rect = harness.state().viewport_rect().unwrap();
    let start = harness.state().document().scene().instances[6].transform;
    let centre = rect.center();
    pointer(&mut harness, centre, None);
    harness.key_press(egui::Key::G);
    harness.step();
    harness.key_press(egui::Key::X);
    harness.step();
    for dx in [20.0, 40.0, 60.0] {
        pointer(&mut harness, centre + egui::vec2(dx, 15.0), None);
    }
    let moved = harness.state().document().scene().instances[6].transform;
    assert!(
        (moved.translation.x - start.translation.x).abs() > 1.0,
        "{moved:?}"
    );
    assert!((moved.translation.y - start.translation.y).abs() < 1e-3);
    assert!((moved.translation.z - start.translation.z).abs() < 1e-3);
    assert_eq!(moved.matrix3, start.matrix3);
    // A click confirms; the whole move is one undo step.
    pointer(&mut harness, centre + egui::vec2(60.0, 15.0), Some(true));
    pointer(&mut harness, centre + egui::vec2(60.0, 15.0), Some(false));
    assert_eq!(
        harness.state().document().selection,
        Some(Selection::Object(6)),
        "the confirming click does not select"
    );
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.step();
    assert_eq!(
        harness.state().document().scene().instances[6].transform,
        start
    );
    assert!(!harness.state().document().can_undo());

    // R turns the object with the mouse; Esc puts it back and leaves no history.
    pointer(&mut harness, centre + egui::vec2(80.0, 0.0), None);
    harness.key_press(egui::Key::R);
    harness.step();
    pointer(&mut harness, centre + egui::vec2(0.0, -80.0), None);
    assert_ne!(
        harness.state().document().scene().instances[6].transform,
        start
    );
    harness.key_press(egui::Key::Escape);
    harness.step();
    assert_eq!(
        harness.state().document().scene().instances[6].transform,
        start
    );
    assert!(!harness.state().document().can_undo() && !harness.state().document().can_redo());
}

/// The editor with the short block selected (and the toolbar's `tool`, if given): the
/// block's transform and the viewport's projection, for grabbing gizmo handles.
fn block_selected(
    tool: Option<&str>,
) -> (
    Harness<'static, EditorApp>,
    glam::Affine3A,
    kiln::editor::gizmo::ViewProjection,
) {
    let mut harness = harness(ScriptedDialogs::default());
    harness.step();
    harness.get_by_label("block").click();
    harness.step();
    if let Some(tool) = tool {
        harness.get_by_label(tool).click();
        harness.step();
    }
    let start = harness.state().document().scene().instances[6].transform;
    let view = kiln::editor::gizmo::ViewProjection {
        camera: *harness.state().view(),
        rect: harness.state().viewport_rect().unwrap(),
    };
    (harness, start, view)
}

#[test]
fn dragging_the_gizmos_y_arrow_moves_the_selection_up() {
    let (mut harness, start, view) = block_selected(None);
    let arrows =
        kiln::editor::gizmo::arrows(&view, &start, kiln::editor::gizmo::Orientation::Global)
            .expect("the block is in front of the camera");
    let (a, b) = arrows[1];
    let grab = a + (b - a) * 0.6;
    pointer(&mut harness, grab, None);
    pointer(&mut harness, grab, Some(true));
    for dy in [-10.0, -25.0, -40.0] {
        pointer(&mut harness, grab + egui::vec2(5.0, dy), None);
    }
    pointer(&mut harness, grab + egui::vec2(5.0, -40.0), Some(false));
    let moved = harness.state().document().scene().instances[6].transform;
    assert!(moved.translation.y > start.translation.y + 1.0, "{moved:?}");
    assert!((moved.translation.x - start.translation.x).abs() < 1e-3);
    assert!((moved.translation.z - start.translation.z).abs() < 1e-3);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.step();
    assert_eq!(
        harness.state().document().scene().instances[6].transform,
        start,
        "one drag, one undo step"
    );
}

#[test]
fn a_new_scene_gets_objects_and_lights_from_the_add_menu() {
    let mut harness = harness(ScriptedDialogs::default());
    harness.step();
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::N);
    harness.step();
    assert!(harness.state().document().scene().instances.is_empty());
    harness.get_by_label("Add").click();
    harness.step();
    harness.get_by_label("Cube").click();
    harness.step();
    harness.get_by_label("Add").click();
    harness.step();
    harness.get_by_label("Sun").click();
    harness.step();
    let scene = harness.state().document().scene().clone();
    assert_eq!(scene.instances.len(), 1);
    assert_eq!(scene.instances[0].name, "Cube");
    assert_eq!(
        scene.materials.len(),
        1,
        "the cube has a material of its own"
    );
    assert_eq!(scene.lights.len(), 1);
    assert_eq!(harness.state().document().name(Selection::Light(0)), "Sun");
    // The cube sits at the view's pivot, in front of the camera.
    let view = *harness.state().view();
    assert!((Vec3::from(scene.instances[0].transform.translation) - view.look_at).length() < 1e-4);

    // Shift+A over the viewport opens the same menu at the pointer.
    let rect = harness.state().viewport_rect().unwrap();
    pointer(&mut harness, rect.center(), None);
    harness.key_press_modifiers(egui::Modifiers::SHIFT, egui::Key::A);
    harness.step();
    harness.get_by_label("UV Sphere").click();
    harness.step();
    assert_eq!(harness.state().document().scene().instances.len(), 2);

    // Each addition is one undo step.
    for _ in 0..3 {
        harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
        harness.step();
    }
    let scene = harness.state().document().scene();
    assert!(scene.instances.is_empty() && scene.lights.is_empty() && scene.materials.is_empty());
}

#[test]
fn the_rotate_gizmo_turns_the_selection_about_the_grabbed_ring() {
    let (mut harness, start, view) = block_selected(Some("⟳ Rotate"));
    let rings = kiln::editor::gizmo::rings(&view, &start, kiln::editor::gizmo::Orientation::Global)
        .unwrap();
    // The Y ring's point farthest to the right of the origin, away from the others.
    let grab = *rings[1].iter().max_by(|a, b| a.x.total_cmp(&b.x)).unwrap();
    assert_eq!(kiln::editor::gizmo::ring_at(&rings, grab, 8.0), Some(1));
    pointer(&mut harness, grab, None);
    pointer(&mut harness, grab, Some(true));
    for dy in [10.0, 25.0, 40.0] {
        pointer(&mut harness, grab + egui::vec2(0.0, dy), None);
    }
    pointer(&mut harness, grab + egui::vec2(0.0, 40.0), Some(false));
    let turned = harness.state().document().scene().instances[6].transform;
    assert_eq!(turned.translation, start.translation);
    assert_ne!(turned.matrix3, start.matrix3);
    // About Y only: the object's up axis keeps its direction.
    let up = |t: &glam::Affine3A| t.matrix3.y_axis.normalize();
    assert!((up(&turned) - up(&start)).length() < 1e-4);
}

/// Opens the Render tab and picks `choice` from the menu labelled `menu`.
fn choose_in_render_tab(harness: &mut Harness<'_, EditorApp>, menu: &str, choice: &str) {
    harness.get_by_label("📷 Render").click();
    harness.step();
    harness.get_by_role_and_label(Role::ComboBox, menu).click();
    harness.step();
    harness.step();
    harness.get_by_label(choice).click();
    harness.step();
}

#[test]
fn a_quality_preset_sets_its_settings_in_one_undo_step() {
    let mut harness = start(Setup {
        size: egui::vec2(1280.0, 1100.0),
        ..Setup::default()
    });
    harness.step();
    let before = harness.state().document().scene().settings;
    choose_in_render_tab(&mut harness, "Quality", "Draft");
    harness.step();
    let s = harness.state().document().scene().settings;
    let draft = kiln::scene::Quality::Draft.settings();
    assert_eq!(
        kiln::scene::Quality::of(&s),
        Some(kiln::scene::Quality::Draft)
    );
    assert_eq!(
        (s.samples_per_pixel, s.max_bounces, s.clamp, s.denoiser),
        (
            draft.samples_per_pixel,
            draft.max_bounces,
            draft.clamp,
            draft.denoiser
        )
    );
    // The rest stays, and one undo takes the whole preset back.
    assert_eq!(
        (s.width, s.seed, s.view),
        (before.width, before.seed, before.view)
    );
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.step();
    assert_eq!(harness.state().document().scene().settings, before);
}

/// On a software driver a kernel compiles inside its first submission, and the window,
/// whose frames are submissions to the same device, waited for it (a minute with a cold
/// shader cache). `kiln edit` compiles each of the viewport's kernels on the background
/// device first, so that the window's device finds it in the driver's cache.
#[test]
fn the_viewports_kernels_compile_on_the_background_device_first() {
    let mut harness = start(Setup {
        rehearse_compiles: true,
        ..Setup::default()
    });
    step_until(&mut harness, "the first samples", samples_done);
    let app = harness.state();
    let (window, background) = (app.gpu().unwrap(), app.background_gpu().unwrap());
    assert!(window.device != background.device, "one device for both");
    if window.info.device_type == wgpu::DeviceType::Cpu {
        // Thumbnails are off: what the background device compiled, it compiled for the
        // viewport.
        assert!(
            background.pipelines_compiled() >= window.pipelines_compiled(),
            "the background device compiled {} pipelines, the window's {}",
            background.pipelines_compiled(),
            window.pipelines_compiled()
        );
        // ... and does not keep them: the driver's cache has the machine code.
        assert_eq!(background.pipelines_cached(), 0);
    } else {
        // Other drivers compile outside submissions: nothing is rehearsed.
        assert_eq!(background.pipelines_compiled(), 0);
    }
    assert!(window.pipelines_compiled() >= 1);
}

#[test]
fn the_viewport_renders_one_pixel_per_pixel_size_squared_of_the_window() {
    // Tall enough that the Render tab's last section, the viewport's, is on screen.
    let state = tempfile::tempdir().unwrap();
    let mut harness = start(Setup {
        size: egui::vec2(1280.0, 1600.0),
        state_dir: Some(state.path().to_owned()),
        ..Setup::default()
    });
    step_until(&mut harness, "the first samples", samples_done);
    let ppp = harness.ctx.pixels_per_point();
    let expected = |app: &EditorApp, pixel_size: f32| {
        let rect = app.viewport_rect().unwrap();
        [rect.width(), rect.height()].map(|v| (v * ppp / pixel_size).round() as u32)
    };
    let status = harness.state().viewport_status().unwrap();
    assert_eq!(status.size, expected(harness.state(), PIXEL_SIZE as f32));
    let revision = harness.state().document().revision();

    choose_in_render_tab(&mut harness, "Pixel Size", "2×");
    step_until(&mut harness, "the image at 2× pixels", |app| {
        app.viewport_status()
            .is_some_and(|s| s.size == expected(app, 2.0) && s.samples >= SAMPLE_LIMIT)
    });
    harness.step();
    assert!(
        harness.query_by_label_contains("at 2× pixels").is_some(),
        "the status line says the pixel size"
    );
    // A view option: the document does not change.
    assert_eq!(harness.state().document().revision(), revision);
    assert!(!harness.state().document().is_dirty());
    // A preference: the next editor starts with it.
    let kept = SessionStore::new(state.path().to_owned()).viewport_preferences();
    assert_eq!(
        kept,
        ViewportPreferences {
            pixel_size: 2,
            max_samples: SAMPLE_LIMIT
        }
    );
}

/// The World tab makes a sky world in one step, edits its sun as a value like any other
/// (one undo step, and the viewport renders the new world), and the world is saved with
/// the scene.
#[test]
fn the_world_tab_makes_and_edits_a_sky_and_saves_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sky.kiln");
    let mut harness = tall_editor_saving_to(&path);
    harness.get_by_label("🌐 World").click();
    harness.step();
    harness.get_by_label("Use Sky Texture").click();
    harness.step();
    harness.step();
    let sky_elevation = |app: &EditorApp| -> Option<f32> {
        let world = app.document().scene().world.as_ref()?;
        match world.graph.nodes["sky"].inputs.get("sun_elevation") {
            Some(kiln::material::Input::Value(kiln::material::Value::Float(e))) => Some(*e),
            _ => None,
        }
    };
    assert_eq!(
        sky_elevation(harness.state()),
        Some(kiln::scene::lookdev::SUN_ELEVATION)
    );
    let restarts = harness.state().viewport_status().unwrap().restarts;
    set_value(&mut harness, "Sun Elevation", 10.0);
    assert_eq!(sky_elevation(harness.state()), Some(10.0));
    step_until(&mut harness, "the new world's samples", |app| {
        app.viewport_status().is_some_and(|s| {
            s.restarts > restarts && s.samples >= SAMPLE_LIMIT && s.error.is_none()
        })
    });

    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.step();
    assert_eq!(
        sky_elevation(harness.state()),
        Some(kiln::scene::lookdev::SUN_ELEVATION)
    );
    harness.key_press_modifiers(
        egui::Modifiers::COMMAND | egui::Modifiers::SHIFT,
        egui::Key::Z,
    );
    harness.step();
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    harness.step();
    let saved = kiln::scene::load_scene(&path).unwrap();
    assert_eq!(saved.world, harness.state().document().scene().world);
    assert!(saved.world.is_some());
}

/// Device losses the editor handed over, as `kiln edit`'s answer would receive them.
type Handovers = std::sync::Arc<std::sync::Mutex<Vec<kiln::editor::DeviceLost>>>;

/// An editor on the bundled scene, its session state in `state`, whose block has been
/// moved to x = `x` and not saved; and the device losses it hands over.
fn editor_with_an_unsaved_move(state: &Path, x: f64) -> (Harness<'static, EditorApp>, Handovers) {
    let calls = Handovers::default();
    let record = std::sync::Arc::clone(&calls);
    let mut harness = start(Setup {
        state_dir: Some(state.to_owned()),
        on_device_lost: Box::new(move |lost| record.lock().unwrap().push(lost)),
        ..Setup::default()
    });
    step_until(&mut harness, "the first samples", samples_done);
    harness.get_by_label("block").click();
    harness.step();
    set_field(&mut harness, "Location", 0, x);
    assert!(harness.state().document().is_dirty());
    (harness, calls)
}

/// The scene this process's editor left in the recovery autosave under `state`.
fn recovered(state: &Path) -> kiln::scene::Scene {
    let autosave = state
        .join("recovery")
        .join(std::process::id().to_string())
        .join("autosave.kiln");
    kiln::scene::load_scene(&autosave).unwrap()
}

/// A GPU device lost under the editor (destroyed here): the unsaved change is written to
/// the recovery autosave at once, the editor hands over once (`kiln edit` starts a new
/// editor on a new device) and draws nothing more; the new editor says why it started.
#[test]
fn a_lost_device_autosaves_the_document_and_hands_over_once() {
    let state = tempfile::tempdir().unwrap();
    let (mut harness, calls) = editor_with_an_unsaved_move(state.path(), 250.0);
    let moved = harness.state().document().scene().instances[6].transform;
    let gpu = harness.state().gpu().expect("a wgpu device").clone();
    gpu.device.destroy();
    // wgpu says so once the work submitted before finishes (seconds under load).
    let handed_over = std::sync::Arc::clone(&calls);
    step_until(&mut harness, "the handover", |_| {
        !handed_over.lock().unwrap().is_empty()
    });
    for _ in 0..5 {
        harness.step();
    }
    let calls = calls.lock().unwrap().clone();
    assert_eq!(calls.len(), 1, "{calls:?}");
    assert!(
        calls[0].reason.contains("destroyed") && calls[0].autosaved && calls[0].file.is_none(),
        "{calls:?}"
    );
    assert_eq!(recovered(state.path()).instances[6].transform, moved);
    assert!(
        harness
            .query_by_label_contains("The GPU device was lost")
            .is_some()
    );

    let harness = start(Setup {
        restarted_after_device_loss: Some("the device was destroyed".into()),
        ..Setup::default()
    });
    assert!(
        harness
            .query_by_label_contains("so Kiln started the editor again")
            .is_some()
    );
}

/// A device lost while egui draws a frame, after the editor's check at the frame's start:
/// egui's renderer panics (it cannot make its buffers), and the editor, dropped as the
/// panic unwinds, still writes the edit to the recovery autosave and hands over.
#[test]
fn a_device_lost_while_egui_draws_still_autosaves_and_hands_over() {
    let state = tempfile::tempdir().unwrap();
    let (mut harness, calls) = editor_with_an_unsaved_move(state.path(), -125.0);
    let moved = harness.state().document().scene().instances[6].transform;
    let gpu = harness.state().gpu().expect("a wgpu device").clone();
    // The frame's shapes are made; the device goes before they are drawn.
    harness.step();
    gpu.device.destroy();
    let drawn = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| harness.render()));
    assert!(
        !matches!(drawn, Ok(Ok(_))),
        "egui drew on a destroyed device"
    );
    assert!(calls.lock().unwrap().is_empty(), "no frame checked yet");
    drop(harness);
    let calls = calls.lock().unwrap().clone();
    assert_eq!(calls.len(), 1, "{calls:?}");
    assert!(
        calls[0].reason.contains("destroyed") && calls[0].autosaved,
        "{calls:?}"
    );
    assert_eq!(recovered(state.path()).instances[6].transform, moved);
}
