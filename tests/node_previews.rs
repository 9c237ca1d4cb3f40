//! Node previews driven like a user, headless on lavapipe (as tests/node_editor.rs): the
//! eye in a node's header shows its output as an image under it (a noise varies, a value
//! is flat at its value), the toggle undoes and is saved; Ctrl+Shift+click on a node
//! shows its output in the viewport until cleared, without touching the document.

use std::time::Instant;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use kiln::editor::graph_edit::GraphEdit;
use kiln::editor::{Command, EditorApp, ScriptedDialogs};
use kiln::material::{Graph, Input, Value};

#[path = "common/editor_harness.rs"]
mod editor_harness;

use editor_harness::{SAMPLE_LIMIT, Setup, start, step_until};

/// The eye in a node's header.
const PREVIEW_ICON: &str = "👁";

fn harness(dialogs: ScriptedDialogs) -> Harness<'static, EditorApp> {
    start(Setup {
        dialogs,
        size: egui::vec2(1920.0, 1000.0),
        ..Setup::default()
    })
}

fn steps(harness: &mut Harness<'_, EditorApp>, n: usize) {
    for _ in 0..n {
        harness.step();
    }
}

fn material(app: &EditorApp) -> usize {
    app.node_editor().material().expect("a material is shown")
}

fn graph(app: &EditorApp) -> Graph {
    app.document()
        .material_graph(material(app))
        .expect("the material exists")
}

/// A click with the primary button at `at`, with `modifiers` held.
fn click_at(harness: &mut Harness<'_, EditorApp>, at: egui::Pos2, modifiers: egui::Modifiers) {
    harness.event(egui::Event::PointerMoved(at));
    harness.step();
    for pressed in [true, false] {
        harness.event_modifiers(
            egui::Event::PointerButton {
                pos: at,
                button: egui::PointerButton::Primary,
                pressed,
                modifiers,
            },
            modifiers,
        );
        harness.step();
    }
    steps(harness, 2);
}

/// Shift+A over the canvas at `at` from its top left, search `query`, pick `label`.
fn add_from_menu(harness: &mut Harness<'_, EditorApp>, at: egui::Vec2, query: &str, label: &str) {
    let canvas = harness.state().node_editor().canvas_rect().unwrap();
    harness.event(egui::Event::PointerMoved(canvas.left_top() + at));
    harness.step();
    harness.key_press_modifiers(egui::Modifiers::SHIFT, egui::Key::A);
    steps(harness, 2);
    harness
        .get_by_role_and_label(egui::accesskit::Role::TextInput, "Search")
        .type_text(query);
    steps(harness, 2);
    harness.get_by_label(label).click_accesskit();
    steps(harness, 3);
}

/// Clicks the preview toggle in node `node`'s header (accessibility reports the canvas's
/// widgets in canvas coordinates).
fn toggle_preview(harness: &mut Harness<'_, EditorApp>, node: &str) {
    let at = {
        let editor = harness.state().node_editor();
        let frame = editor
            .node_rect(node)
            .unwrap_or_else(|| panic!("node {node} is drawn"));
        harness
            .query_all_by_label(PREVIEW_ICON)
            .map(|n| {
                let r = n.rect();
                egui::Rect::from_min_max(
                    editor.canvas_to_screen(r.min),
                    editor.canvas_to_screen(r.max),
                )
            })
            .find(|r| frame.contains(r.center()))
            .unwrap_or_else(|| panic!("node {node} has a preview toggle"))
            .center()
    };
    click_at(harness, at, egui::Modifiers::NONE);
}

/// The pixels of node `node`'s preview once it shows the graph as it is now.
fn wait_for_preview(harness: &mut Harness<'_, EditorApp>, node: &str) -> egui::ColorImage {
    let start = Instant::now();
    step_until(harness, &format!("the preview of {node}"), |app| {
        app.node_previews()
            .expect("previews are made")
            .image(material(app), node, &graph(app))
            .is_some()
    });
    let app = harness.state();
    let took = app.node_previews().unwrap().took(material(app), node);
    // For docs/BENCHMARKS.md: toggle to image as the test sees it (frames included), and
    // the worker's share (compile, kernel, evaluation).
    eprintln!(
        "preview of {node}: {:.2} s from the toggle, worker {:.2} s",
        start.elapsed().as_secs_f64(),
        took.unwrap_or_default().as_secs_f64()
    );
    app.node_previews()
        .unwrap()
        .image(material(app), node, &graph(app))
        .unwrap()
        .clone()
}

/// The fully covered pixels of a preview (the sphere, not its outline or the corners).
fn sphere_pixels(image: &egui::ColorImage) -> Vec<[u8; 4]> {
    image
        .pixels
        .iter()
        .filter(|p| p.a() == 255)
        .map(|p| p.to_srgba_unmultiplied())
        .collect()
}

#[test]
fn a_preview_shows_a_nodes_output_under_it_toggles_with_undo_and_is_saved() {
    let dir = tempfile::tempdir().unwrap();
    let saved = dir.path().join("previews.kiln");
    let mut harness = harness(ScriptedDialogs {
        save: vec![saved.clone()].into(),
        ..ScriptedDialogs::default()
    });
    step_until(&mut harness, "the first samples", |app| {
        app.viewport_status()
            .is_some_and(|s| s.samples >= SAMPLE_LIMIT && s.error.is_none())
    });
    harness.get_by_label("block").click();
    steps(&mut harness, 3);
    add_from_menu(
        &mut harness,
        egui::vec2(30.0, 40.0),
        "noise",
        "Noise Texture",
    );
    // The value right of the noise, at the canvas's top.
    let right_of_noise = {
        let editor = harness.state().node_editor();
        let noise = editor.node_rect("noise_texture").unwrap();
        egui::vec2(
            noise.right() - editor.canvas_rect().unwrap().left() + 30.0,
            40.0,
        )
    };
    add_from_menu(&mut harness, right_of_noise, "value", "Value");
    let before = graph(harness.state());
    assert!(before.nodes.contains_key("noise_texture") && before.nodes.contains_key("value"));
    let value_height = harness
        .state()
        .node_editor()
        .node_rect("value")
        .unwrap()
        .height();

    // The eye on the noise: an image under the node whose pixels vary. The viewport's
    // image does not change with it.
    let image_revision = harness.state().document().image_revision();
    toggle_preview(&mut harness, "noise_texture");
    assert!(graph(harness.state()).nodes["noise_texture"].preview);
    assert_eq!(harness.state().document().image_revision(), image_revision);
    assert!(
        graph(harness.state()).same_but_layout(&before),
        "a preview changes nothing the material computes"
    );
    let noise = wait_for_preview(&mut harness, "noise_texture");
    assert_eq!(noise.size, [96, 96]);
    let pixels = sphere_pixels(&noise);
    assert!(pixels.len() > 4000, "{} pixels on the sphere", pixels.len());
    let (low, high) = pixels
        .iter()
        .fold((255, 0), |(lo, hi), p| (p[0].min(lo), p[0].max(hi)));
    assert!(
        high - low > 60,
        "a noise preview varies: its grey spans {low}..{high}"
    );
    assert!(
        pixels.iter().any(|p| p[0].abs_diff(p[1]) > 20),
        "the noise's first output, its colour, is shown in colour"
    );

    // The value node (0.5 by default): flat at sRGB(0.5) = 0.7354 · 255 = 187.5, ± 1.5
    // for rounding.
    toggle_preview(&mut harness, "value");
    let value = wait_for_preview(&mut harness, "value");
    let want = (1.055 * 0.5f32.powf(1.0 / 2.4) - 0.055) * 255.0;
    for p in sphere_pixels(&value) {
        for c in &p[..3] {
            assert!(
                (*c as f32 - want).abs() <= 1.5,
                "a value preview is flat at {want}: {p:?}"
            );
        }
    }
    steps(&mut harness, 3);
    let shown_height = harness
        .state()
        .node_editor()
        .node_rect("value")
        .unwrap()
        .height();
    // The canvas is zoomed to fit the graph: 96 points of canvas are fewer on screen.
    let zoom = {
        let editor = harness.state().node_editor();
        editor.canvas_to_screen(egui::pos2(1.0, 0.0)).x
            - editor.canvas_to_screen(egui::Pos2::ZERO).x
    };
    assert!(
        shown_height >= value_height + 90.0 * zoom,
        "the 96-point image sits under the node (zoom {zoom}): {value_height} → {shown_height}"
    );

    // Undo takes the toggle back (and the image away); redo shows it again at once, the
    // graph being the one it was made of.
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    steps(&mut harness, 4);
    assert!(!graph(harness.state()).nodes["value"].preview);
    let hidden_height = harness
        .state()
        .node_editor()
        .node_rect("value")
        .unwrap()
        .height();
    assert!(
        shown_height - hidden_height >= 90.0 * zoom,
        "toggled off, the image is gone: {shown_height} → {hidden_height}"
    );
    harness.key_press_modifiers(
        egui::Modifiers::COMMAND.plus(egui::Modifiers::SHIFT),
        egui::Key::Z,
    );
    steps(&mut harness, 3);
    assert!(graph(harness.state()).nodes["value"].preview);
    let app = harness.state();
    assert!(
        app.node_previews()
            .unwrap()
            .image(material(app), "value", &graph(app))
            .is_some()
    );

    // A new value: the preview is stale until it renders again, then flat at the new one.
    let m = material(harness.state());
    harness.state_mut().apply_command(Command::EditGraph {
        material: m,
        edit: GraphEdit::SetInput {
            node: "value".into(),
            input: "value".into(),
            value: Some(Input::Value(Value::Float(0.2))),
        },
    });
    steps(&mut harness, 2);
    let value = wait_for_preview(&mut harness, "value");
    let want = (1.055 * 0.2f32.powf(1.0 / 2.4) - 0.055) * 255.0;
    let p = sphere_pixels(&value)[0];
    assert!((p[0] as f32 - want).abs() <= 1.5, "{p:?} vs {want}");

    // A shader: the block's surface on a sphere lit from the upper left, so its upper
    // left is brighter than its lower right.
    toggle_preview(&mut harness, "surface");
    let surface = wait_for_preview(&mut harness, "surface");
    let luma = |x: usize, y: usize| {
        let p = surface.pixels[y * 96 + x];
        assert_eq!(p.a(), 255, "({x}, {y}) is on the sphere");
        p.r() as u32 + p.g() as u32 + p.b() as u32
    };
    let (lit, unlit) = (luma(32, 30), luma(66, 68));
    assert!(
        lit > unlit + 90,
        "a shader's preview is shaded: upper left {lit}, lower right {unlit}"
    );

    // The noise's eye again: off.
    toggle_preview(&mut harness, "noise_texture");
    assert!(!graph(harness.state()).nodes["noise_texture"].preview);

    // Saved with the graph, only where on.
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    steps(&mut harness, 2);
    assert!(saved.exists(), "{:?}", harness.state().error());
    let text = std::fs::read_to_string(&saved).unwrap();
    assert_eq!(text.matches("preview: true").count(), 2, "{text}");
    let shown = graph(harness.state());
    harness.state_mut().open(saved.clone());
    steps(&mut harness, 2);
    let reopened = harness.state().document().material_graph(m).unwrap();
    assert_eq!(reopened, shown);
    assert!(reopened.nodes["value"].preview && !reopened.nodes["noise_texture"].preview);
    assert!(reopened.nodes["surface"].preview);
}

/// The viewport's pixel at its centre (the short block), as the window shows it.
fn viewport_centre(harness: &mut Harness<'_, EditorApp>) -> [u8; 3] {
    let rect = harness.state().viewport_rect().unwrap();
    let ppp = harness.ctx.pixels_per_point();
    let image = harness.render().expect("the window renders");
    let at = rect.center() * ppp;
    let p = image.get_pixel(at.x as u32, at.y as u32);
    [p[0], p[1], p[2]]
}

fn wait_for_image(harness: &mut Harness<'_, EditorApp>, what: &str) {
    let before = harness.state().viewport_status().unwrap().shown_revision;
    step_until(harness, what, |app| {
        app.viewport_status().is_some_and(|s| {
            s.shown_revision != before && s.samples >= SAMPLE_LIMIT && s.building.is_none()
        })
    });
    steps(harness, 3);
}

/// Red well above green and blue: the scene's view transform may desaturate a pure red
/// (AgX shows linear (1, 0, 0) as about sRGB (221, 56, 56)).
fn red_dominant(pixel: [u8; 3]) -> bool {
    let [r, g, b] = pixel.map(i32::from);
    r > 150 && r > 2 * g.max(b) + 40
}

#[test]
fn ctrl_shift_click_previews_a_node_in_the_viewport_until_cleared() {
    let mut harness = harness(ScriptedDialogs::default());
    step_until(&mut harness, "the first samples", |app| {
        app.viewport_status()
            .is_some_and(|s| s.samples >= SAMPLE_LIMIT && s.error.is_none())
    });
    harness.get_by_label("block").click();
    steps(&mut harness, 3);
    add_from_menu(&mut harness, egui::vec2(30.0, 40.0), "rgb", "RGB");
    let m = material(harness.state());
    harness.state_mut().apply_command(Command::EditGraph {
        material: m,
        edit: GraphEdit::SetInput {
            node: "rgb".into(),
            input: "color".into(),
            value: Some(Input::Value(Value::Vec3([1.0, 0.0, 0.0]))),
        },
    });
    steps(&mut harness, 2);
    wait_for_image(&mut harness, "the material with its new node");
    let plain = viewport_centre(&mut harness);
    assert!(!red_dominant(plain), "the block is not red: {plain:?}");
    let revision = harness.state().document().revision();
    let scene = harness.state().document().render_scene();

    // Ctrl+Shift+click on the RGB node's header: the block shows pure red.
    let header = {
        let r = harness.state().node_editor().node_rect("rgb").unwrap();
        egui::pos2(r.center().x, r.top() + 8.0)
    };
    let ctrl_shift = egui::Modifiers::COMMAND.plus(egui::Modifiers::SHIFT);
    click_at(&mut harness, header, ctrl_shift);
    let preview = harness.state().node_editor().viewport_preview().cloned();
    assert_eq!(
        preview.as_ref().map(|p| (p.node.as_str(), p.output)),
        Some(("rgb", 0)),
        "{preview:?}"
    );
    assert!(
        harness.query_by_label("🗙 Clear preview").is_some(),
        "a banner says what the viewport shows"
    );
    wait_for_image(&mut harness, "the previewed node");
    let red = viewport_centre(&mut harness);
    assert!(red_dominant(red), "the block shows the RGB node: {red:?}");
    // A view state: no command, no change to the document or what final renders take.
    assert_eq!(harness.state().document().revision(), revision);
    assert_eq!(harness.state().document().render_scene(), scene);

    // The banner's button clears it: the material again.
    harness.get_by_label("🗙 Clear preview").click();
    steps(&mut harness, 2);
    assert!(harness.state().node_editor().viewport_preview().is_none());
    wait_for_image(&mut harness, "the material again");
    let back = viewport_centre(&mut harness);
    for (a, b) in back.iter().zip(&plain) {
        assert!(
            a.abs_diff(*b) <= 8,
            "back to the material: {back:?} vs {plain:?}"
        );
    }

    // Esc and Ctrl+Shift+click on empty canvas clear it too.
    click_at(&mut harness, header, ctrl_shift);
    assert!(harness.state().node_editor().viewport_preview().is_some());
    harness.key_press(egui::Key::Escape);
    steps(&mut harness, 2);
    assert!(harness.state().node_editor().viewport_preview().is_none());
    click_at(&mut harness, header, ctrl_shift);
    assert!(harness.state().node_editor().viewport_preview().is_some());
    let canvas = harness.state().node_editor().canvas_rect().unwrap();
    let empty = canvas.left_bottom() + egui::vec2(12.0, -12.0);
    assert!(
        !["rgb", "surface", "output"]
            .iter()
            .filter_map(|n| harness.state().node_editor().node_rect(n))
            .any(|r| r.contains(empty)),
        "{empty:?} is empty canvas"
    );
    click_at(&mut harness, empty, ctrl_shift);
    assert!(harness.state().node_editor().viewport_preview().is_none());
    assert_eq!(harness.state().document().revision(), revision);
}
