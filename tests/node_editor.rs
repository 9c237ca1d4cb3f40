//! The node editor driven like a user, headless on lavapipe (as tests/editor.rs): add a
//! node through the search menu, draw wires by dragging between pins, edit a value, see a
//! refused wire's reason, undo and redo back and forth, and save and reopen; every socket
//! label of every library node shows whole; edit a colour ramp; pick and drop images.

use egui::accesskit::{self, Role};
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT, Queryable};
use kiln::editor::{EditorApp, ScriptedDialogs, Selection};
use kiln::material::{Graph, Input, Link, Node, Param, RampStop};

#[path = "common/editor_harness.rs"]
mod editor_harness;

use editor_harness::{
    SAMPLE_LIMIT, Setup, assert_standby_returned, start, step_until, step_until_specialised,
};

fn harness(dialogs: ScriptedDialogs) -> Harness<'static, EditorApp> {
    start(Setup {
        dialogs,
        // Wide, so the canvas has room left of the material's nodes for the new one.
        size: egui::vec2(1920.0, 1000.0),
        ..Setup::default()
    })
}

fn steps(harness: &mut Harness<'_, EditorApp>, n: usize) {
    for _ in 0..n {
        harness.step();
    }
}

fn graph(app: &EditorApp) -> Graph {
    let m = app.node_editor().material().expect("a material is shown");
    app.document()
        .material_graph(m)
        .expect("the material exists")
}

fn pin(harness: &Harness<'_, EditorApp>, node: &str, socket: &str, input: bool) -> egui::Pos2 {
    harness
        .state()
        .node_editor()
        .pin_position(node, socket, input)
        .unwrap_or_else(|| panic!("pin {node}.{socket} (input: {input}) is drawn"))
}

/// Drags a wire with the primary button from output `from` to input `to` (node, socket),
/// as a mouse would.
fn drag(harness: &mut Harness<'_, EditorApp>, from: (&str, &str), to: (&str, &str)) {
    let from = pin(harness, from.0, from.1, false);
    let to = pin(harness, to.0, to.1, true);
    mouse_drag(harness, from, to - from);
}

/// Shift+clicks the header of the noise texture node: snarl selects with Shift+click (a
/// plain click only raises the node).
fn select_noise(harness: &mut Harness<'_, EditorApp>) {
    let header = {
        let node_editor = harness.state().node_editor();
        let top = node_editor.node_position("noise_texture").unwrap();
        let left = pin(harness, "noise_texture", "vector", true);
        let right = pin(harness, "noise_texture", "color", false);
        egui::pos2((left.x + right.x) / 2.0, top.y + (right.y - top.y) * 0.3)
    };
    harness.event(egui::Event::PointerMoved(header));
    harness.step();
    for pressed in [true, false] {
        harness.event_modifiers(
            egui::Event::PointerButton {
                pos: header,
                button: egui::PointerButton::Primary,
                pressed,
                modifiers: egui::Modifiers::SHIFT,
            },
            egui::Modifiers::SHIFT,
        );
        harness.step();
    }
    steps(harness, 2);
}

/// Shift+A over the canvas at `at` from its top left (left of the material's nodes),
/// then types `query` into the add menu's search.
fn search_add_menu(harness: &mut Harness<'_, EditorApp>, at: egui::Vec2, query: &str) {
    let canvas = harness.state().node_editor().canvas_rect().unwrap();
    harness.event(egui::Event::PointerMoved(canvas.left_top() + at));
    harness.step();
    harness.key_press_modifiers(egui::Modifiers::SHIFT, egui::Key::A);
    steps(harness, 2);
    harness
        .get_by_role_and_label(Role::TextInput, "Search")
        .type_text(query);
    steps(harness, 2);
}

/// Searches the add menu for `query` at `at` ([`search_add_menu`]) and picks `label`.
fn add_from_menu(harness: &mut Harness<'_, EditorApp>, at: egui::Vec2, query: &str, label: &str) {
    search_add_menu(harness, at, query);
    harness.get_by_label(label).click_accesskit();
    steps(harness, 3);
}

/// An editor showing the red wall's material: of fixed parameters, its two nodes laid
/// out automatically.
fn red_wall_material() -> Harness<'static, EditorApp> {
    let mut harness = harness(ScriptedDialogs::default());
    steps(&mut harness, 2);
    harness.get_by_label("left wall").click();
    steps(&mut harness, 2);
    harness
}

#[test]
fn enter_in_the_add_menu_s_search_adds_the_first_match() {
    let mut harness = red_wall_material();
    let before = graph(harness.state()).nodes.len();
    // The red wall's material is of fixed parameters: its nodes are laid out
    // automatically, and adding one must not move them.
    let drawn = |h: &Harness<'_, EditorApp>| {
        ["surface", "output"].map(|id| h.state().node_editor().node_position(id).unwrap())
    };
    let was = drawn(&harness);
    let panel_edge = |h: &Harness<'_, EditorApp>| h.get_by_label("Outliner").rect().left();
    let edge = panel_edge(&harness);
    let at = egui::vec2(60.0, 60.0);
    search_add_menu(&mut harness, at, "noise");
    // "Noise Texture" and "White Noise Texture" match; Enter takes the first.
    assert!(harness.query_by_label("White Noise Texture").is_some());
    harness.key_press(egui::Key::Enter);
    steps(&mut harness, 3);
    let after = graph(harness.state());
    assert_eq!(after.nodes.len(), before + 1);
    assert!(
        after.nodes.keys().any(|id| id == "noise_texture"),
        "{:?}",
        after.nodes.keys()
    );
    assert!(
        harness.query_by_label("White Noise Texture").is_none(),
        "the menu closed"
    );
    for (a, b) in was.iter().zip(&drawn(&harness)) {
        assert!(a.distance(*b) < 0.5, "a node moved from {a:?} to {b:?}");
    }
    // The inspector beside it now calls the material a graph; its panel keeps its width
    // (a line that does not wrap would widen it and narrow the node editor).
    harness.get_by_label("A node-graph material: its parameters are set by its nodes.");
    let moved = (panel_edge(&harness) - edge).abs();
    assert!(moved < 0.5, "the side panel's edge moved {moved} px");

    // A search that matches nothing says so, and Enter adds nothing.
    search_add_menu(&mut harness, at, "no such node");
    assert!(harness.query_by_label("No node matches.").is_some());
    harness.key_press(egui::Key::Enter);
    steps(&mut harness, 3);
    assert_eq!(graph(harness.state()).nodes.len(), before + 1);
}

#[test]
fn deleting_a_node_of_an_automatically_laid_out_graph_leaves_the_others_in_place() {
    let mut harness = red_wall_material();
    // The red wall's material is of fixed parameters, its two nodes laid out
    // automatically: without the BSDF, the output alone would be laid out again, leftmost.
    let was = harness
        .state()
        .node_editor()
        .node_position("output")
        .unwrap();
    shift_click_node(&mut harness, "surface");
    harness.key_press(egui::Key::X);
    steps(&mut harness, 3);
    assert!(!graph(harness.state()).nodes.contains_key("surface"));
    let now = harness
        .state()
        .node_editor()
        .node_position("output")
        .unwrap();
    assert!(
        was.distance(now) < 0.5,
        "the output moved from {was:?} to {now:?}"
    );
}

/// Presses the primary button at `from`, moves by `by` in steps and releases, as a mouse
/// drag does.
fn mouse_drag(harness: &mut Harness<'_, EditorApp>, from: egui::Pos2, by: egui::Vec2) {
    let button = |pos, pressed| egui::Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: egui::Modifiers::NONE,
    };
    harness.event(egui::Event::PointerMoved(from));
    harness.step();
    harness.event(button(from, true));
    harness.step();
    for i in 1..=12 {
        harness.event(egui::Event::PointerMoved(from + by * (i as f32 / 12.0)));
        harness.step();
    }
    harness.event(button(from + by, false));
    steps(harness, 3);
}

#[test]
fn build_a_graph_in_the_node_editor_then_undo_redo_save_and_reopen() {
    let dir = tempfile::tempdir().unwrap();
    let saved = dir.path().join("nodes.kiln");
    let mut harness = harness(ScriptedDialogs {
        save: vec![saved.clone()].into(),
        ..ScriptedDialogs::default()
    });
    step_until(&mut harness, "the first samples", |app| {
        app.viewport_status()
            .is_some_and(|s| s.samples >= SAMPLE_LIMIT && s.error.is_none())
    });

    // Selecting the short block shows its material's graph.
    harness.get_by_label("block").click();
    steps(&mut harness, 3);
    assert_eq!(
        harness.state().document().selection,
        Some(Selection::Object(6))
    );
    let material = harness.state().node_editor().material().unwrap();
    assert_eq!(
        material,
        harness.state().document().scene().instances[6].material
    );
    let start = graph(harness.state());
    assert!(
        start.nodes.contains_key("surface"),
        "{:?}",
        start.nodes.keys()
    );

    // Shift+A over the canvas (left of the material's nodes) opens the add menu; search
    // and pick the noise texture.
    search_add_menu(&mut harness, egui::vec2(30.0, 40.0), "noise");
    let item = harness.get_by_label("Noise Texture");
    eprintln!("noise menu item at {:?}", item.rect());
    item.click_accesskit();
    steps(&mut harness, 3);
    let added = graph(harness.state());
    assert_eq!(added.nodes["noise_texture"].kind, "noise_texture");
    assert!(added.nodes["noise_texture"].position.is_some());

    // A colour output into the output's shader input is refused, with the reason shown.
    if let Some(path) = std::env::var_os("KILN_NODE_EDITOR_SHOT") {
        // A look at the canvas, for whoever changes its layout.
        harness.render().unwrap().save(path).unwrap();
    }
    let refused = graph(harness.state());
    drag(
        &mut harness,
        ("noise_texture", "color"),
        ("output", "surface"),
    );
    let message = harness
        .state()
        .node_editor()
        .message()
        .expect("a refused wire says why")
        .to_owned();
    assert!(
        message.contains("color") && message.contains("bsdf"),
        "{message}"
    );
    assert!(
        harness.query_by_label(&message).is_some(),
        "shown: {message}"
    );
    assert_eq!(
        graph(harness.state()),
        refused,
        "a refused wire changes nothing"
    );

    // Noise colour → base colour: the material recompiles and the viewport restarts.
    let status = harness.state().viewport_status().unwrap();
    drag(
        &mut harness,
        ("noise_texture", "color"),
        ("surface", "base_color"),
    );
    let connected = graph(harness.state());
    assert_eq!(
        connected.nodes["surface"].inputs["base_color"],
        Input::Link(Link::new("noise_texture", "color")),
        "{:?}",
        harness.state().node_editor().message()
    );
    assert!(harness.state().document().graph_error(material).is_none());
    assert!(
        harness.state().document().scene().materials[material]
            .graph
            .is_some(),
        "the scene renders the graph"
    );
    step_until(&mut harness, "the recompiled material's samples", |app| {
        app.viewport_status().is_some_and(|s| {
            s.restarts > status.restarts
                && s.shown_revision != status.shown_revision
                && s.samples >= SAMPLE_LIMIT
        })
    });

    // The noise scale, set as a screen reader would.
    let status = harness.state().viewport_status().unwrap();
    set_noise_scale(&mut harness, 12.5);
    let scaled = graph(harness.state());
    assert_eq!(
        scaled.nodes["noise_texture"].inputs["scale"],
        Input::from(12.5)
    );
    assert!(harness.state().document().is_dirty());
    step_until(&mut harness, "the rescaled material's samples", |app| {
        app.viewport_status().is_some_and(|s| {
            s.restarts > status.restarts && s.shown_revision != status.shown_revision
        })
    });

    // Undo each step back to the start graph, then redo to the end.
    let mut undos = 0;
    while graph(harness.state()) != start {
        assert!(undos < 10, "undo returns to the start graph");
        harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
        steps(&mut harness, 2);
        undos += 1;
    }
    assert_eq!(undos, 3, "add, connect and scale are one step each");
    for _ in 0..undos {
        harness.key_press_modifiers(
            egui::Modifiers::COMMAND.plus(egui::Modifiers::SHIFT),
            egui::Key::Z,
        );
        steps(&mut harness, 2);
    }
    assert_eq!(graph(harness.state()), scaled);

    // Save, reopen: the same graph, positions included.
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    steps(&mut harness, 2);
    assert!(saved.exists(), "{:?}", harness.state().error());
    assert!(!harness.state().document().is_dirty());
    let first = std::fs::read(&saved).unwrap();
    harness.state_mut().open(saved.clone());
    steps(&mut harness, 2);
    let reopened = harness.state().document().material_graph(material).unwrap();
    assert_eq!(reopened, scaled);
    // Saving the unchanged document again writes the same bytes.
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    steps(&mut harness, 2);
    assert_eq!(std::fs::read(&saved).unwrap(), first);

    // Keyboard over the canvas: Shift+click the noise node's header to select it, Shift+D
    // duplicates it, Ctrl+C / Ctrl+V paste another copy, X deletes the selected node.
    select_noise(&mut harness);
    harness.key_press_modifiers(egui::Modifiers::SHIFT, egui::Key::D);
    steps(&mut harness, 3);
    let duplicated = graph(harness.state());
    assert_eq!(duplicated.nodes["noise_texture_2"].kind, "noise_texture");
    assert_eq!(
        duplicated.nodes["noise_texture_2"].inputs["scale"],
        Input::from(12.5),
        "a duplicate keeps its values"
    );
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::C);
    steps(&mut harness, 2);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::V);
    steps(&mut harness, 3);
    assert!(graph(harness.state()).nodes.contains_key("noise_texture_3"));
    harness.key_press(egui::Key::X);
    steps(&mut harness, 3);
    let deleted = graph(harness.state());
    assert!(!deleted.nodes.contains_key("noise_texture"));
    assert!(
        !deleted.nodes["surface"].inputs.contains_key("base_color"),
        "deleting a node removes its wires"
    );
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    steps(&mut harness, 2);
    assert_eq!(
        graph(harness.state()).nodes["surface"].inputs["base_color"],
        Input::Link(Link::new("noise_texture", "color")),
        "undo restores the node and its wires"
    );
}

#[test]
fn ranges_mute_reroute_and_select_all_on_the_canvas() {
    let mut harness = harness(ScriptedDialogs::default());
    harness.get_by_label("block").click();
    steps(&mut harness, 3);
    add_from_menu(
        &mut harness,
        egui::vec2(30.0, 40.0),
        "noise",
        "Noise Texture",
    );
    let start = graph(harness.state());
    assert_eq!(start.nodes["noise_texture"].kind, "noise_texture");

    // Dragging the noise scale far left stops at its hard minimum, 0.
    let field = harness
        .get_all_by_role_and_label(Role::SpinButton, "scale")
        .find(|n| n.accesskit_node().numeric_value() == Some(5.0))
        .expect("the noise texture's scale field (5 by default)")
        .rect();
    // Accessibility reports the canvas's widgets in canvas coordinates.
    let at = harness
        .state()
        .node_editor()
        .canvas_to_screen(field.center());
    mouse_drag(&mut harness, at, egui::vec2(-600.0, 0.0));
    let dragged = graph(harness.state());
    assert_eq!(
        dragged.nodes["noise_texture"].inputs.get("scale"),
        Some(&Input::from(0.0)),
        "{:?}",
        harness.state().node_editor().message()
    );

    // M mutes the selected node, as one undo step.
    select_noise(&mut harness);
    harness.key_press(egui::Key::M);
    steps(&mut harness, 3);
    assert!(graph(harness.state()).nodes["noise_texture"].muted);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    steps(&mut harness, 2);
    assert_eq!(graph(harness.state()), dragged, "undo unmutes");

    // A selects every node, Alt+A none (snarl's own selection, the noise, included): X
    // then deletes nothing.
    harness.key_press(egui::Key::A);
    steps(&mut harness, 2);
    harness.key_press_modifiers(egui::Modifiers::ALT, egui::Key::A);
    steps(&mut harness, 2);
    harness.key_press(egui::Key::X);
    steps(&mut harness, 3);
    assert_eq!(graph(harness.state()), dragged, "nothing is selected");
    // A then X deletes every node (delete protects none, the output included, as
    // Blender's); undo restores them all.
    harness.key_press(egui::Key::A);
    steps(&mut harness, 2);
    harness.key_press(egui::Key::X);
    steps(&mut harness, 3);
    assert!(
        graph(harness.state()).nodes.is_empty(),
        "{:?}",
        graph(harness.state()).nodes.keys()
    );
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    steps(&mut harness, 3);
    assert_eq!(graph(harness.state()), dragged, "undo restores every node");

    // A reroute from the add menu's Layout entries, wired between the noise and the base
    // colour: the material compiles.
    add_from_menu(&mut harness, egui::vec2(360.0, 60.0), "reroute", "Reroute");
    assert_eq!(graph(harness.state()).nodes["reroute"].kind, "reroute");
    steps(&mut harness, 2);
    drag(
        &mut harness,
        ("noise_texture", "color"),
        ("reroute", "input"),
    );
    drag(
        &mut harness,
        ("reroute", "output"),
        ("surface", "base_color"),
    );
    let rerouted = graph(harness.state());
    assert_eq!(
        rerouted.nodes["surface"].inputs["base_color"],
        Input::Link(Link::new("reroute", "output")),
        "{:?}",
        harness.state().node_editor().message()
    );
    let material = harness.state().node_editor().material().unwrap();
    assert!(harness.state().document().graph_error(material).is_none());
}

/// A small PNG in `dir`.
fn png(dir: &std::path::Path, name: &str) -> std::path::PathBuf {
    let path = dir.join(name);
    image::RgbaImage::from_pixel(2, 2, image::Rgba([200, 100, 50, 255]))
        .save(&path)
        .unwrap();
    path
}

/// Widget `n`'s rectangle in screen points (accessibility reports the canvas's widgets
/// in canvas coordinates).
fn screen_rect(harness: &Harness<'_, EditorApp>, n: &egui_kittest::Node<'_>) -> egui::Rect {
    let node_editor = harness.state().node_editor();
    let r = n.rect();
    egui::Rect::from_min_max(
        node_editor.canvas_to_screen(r.min),
        node_editor.canvas_to_screen(r.max),
    )
}

#[test]
fn every_socket_label_of_every_library_node_shows_whole_beside_its_pin() {
    let dir = tempfile::tempdir().unwrap();
    let image = png(dir.path(), "texture.png");
    let mut all = Graph::default();
    for def in kiln::material::nodes::library() {
        let mut node = Node::new(def.kind);
        // The image and environment textures read a file.
        if def
            .params
            .iter()
            .any(|p| matches!(p.kind, kiln::material::nodes::ParamKind::File))
        {
            node.params.insert(
                "file".into(),
                Param::Text(image.to_string_lossy().into_owned()),
            );
        }
        all.nodes.insert(def.kind.to_owned(), node);
    }
    let mut scene = kiln::scene::default_scene().unwrap();
    scene.materials[0] = kiln::scene::Material::from_graph("every node", all).unwrap();
    let path = dir.path().join("every_node.kiln");
    kiln::scene::save_scene(&scene, &path, &[]).unwrap();

    let mut harness = harness(ScriptedDialogs::default());
    harness.state_mut().open(path);
    steps(&mut harness, 4);
    assert_eq!(harness.state().node_editor().material(), Some(0));

    let mut checked = 0;
    for def in kiln::material::nodes::library() {
        let node = harness
            .state()
            .node_editor()
            .node_rect(def.kind)
            .unwrap_or_else(|| panic!("node {} is drawn", def.kind));
        let sockets = def
            .inputs
            .iter()
            .map(|s| (s.name, true))
            .chain(def.outputs.iter().map(|s| (s.name, false)));
        for (socket, input) in sockets {
            let pin = harness
                .state()
                .node_editor()
                .pin_rect(def.kind, socket, input)
                .unwrap_or_else(|| panic!("pin {}.{socket} is drawn", def.kind));
            // The label of this socket: the one of its name on the pin's row, nearest the
            // pin.
            let label = harness
                .get_all_by_role_and_label(Role::Label, socket)
                .map(|n| screen_rect(&harness, &n))
                .filter(|r| (r.center().y - pin.center().y).abs() < pin.height())
                .min_by(|a, b| {
                    let d = |r: &egui::Rect| (r.center().x - pin.center().x).abs();
                    d(a).total_cmp(&d(b))
                })
                .unwrap_or_else(|| panic!("a label {}.{socket} beside its pin", def.kind));
            assert!(
                node.contains_rect(label),
                "label {}.{socket} at {label:?} lies inside its node at {node:?}",
                def.kind
            );
            let gap = if input {
                label.left() - pin.right()
            } else {
                pin.left() - label.right()
            };
            assert!(
                gap >= 3.0,
                "label {}.{socket} at {label:?} keeps a margin to its pin at {pin:?}: {gap}",
                def.kind
            );
            checked += 1;
        }
    }
    assert!(checked > 100, "{checked} labels");
}

/// The colour ramp's stops on node `node` (None while it has the default ones).
fn stops(app: &EditorApp, node: &str) -> Option<Vec<RampStop>> {
    match graph(app).nodes[node].params.get("stops") {
        Some(Param::Ramp(stops)) => Some(stops.clone()),
        None => None,
        Some(other) => panic!("stops are a ramp: {other:?}"),
    }
}

/// A click with the primary button at `at`.
fn click_at(harness: &mut Harness<'_, EditorApp>, at: egui::Pos2) {
    harness.event(egui::Event::PointerMoved(at));
    harness.step();
    for pressed in [true, false] {
        harness.event(egui::Event::PointerButton {
            pos: at,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::NONE,
        });
        harness.step();
    }
    steps(harness, 2);
}

#[test]
fn a_colour_ramp_takes_stops_added_moved_and_deleted_each_undone_in_one_step() {
    let mut harness = harness(ScriptedDialogs::default());
    harness.get_by_label("block").click();
    steps(&mut harness, 3);
    add_from_menu(&mut harness, egui::vec2(30.0, 40.0), "ramp", "Color Ramp");
    let start = graph(harness.state());
    assert_eq!(start.nodes["color_ramp"].kind, "color_ramp");
    assert_eq!(stops(harness.state(), "color_ramp"), None);

    // A click a quarter along the bar adds a stop there, of the ramp's colour there.
    let bar = screen_rect(&harness, &harness.get_by_label("color ramp"));
    let at = |t: f32| bar.left() + bar.width() * t;
    click_at(&mut harness, egui::pos2(at(0.25), bar.center().y));
    let added = stops(harness.state(), "color_ramp").expect("a stop was added");
    assert_eq!(added.len(), 3, "{added:?}");
    assert!((added[1].position - 0.25).abs() < 0.01, "{added:?}");
    assert!(
        (added[1].color[0] - added[1].position).abs() < 1e-4,
        "black to white: grey as bright as it is far along: {added:?}"
    );

    // Dragging its marker to three quarters moves it there (one undo step).
    let markers = screen_rect(&harness, &harness.get_by_label("color ramp stops"));
    mouse_drag(
        &mut harness,
        egui::pos2(at(added[1].position), markers.center().y),
        egui::vec2(at(0.75) - at(added[1].position), 0.0),
    );
    let moved = stops(harness.state(), "color_ramp").unwrap();
    assert_eq!(moved.len(), 3, "{moved:?}");
    assert!((moved[1].position - 0.75).abs() < 0.01, "{moved:?}");
    assert_eq!(
        moved[1].color, added[1].color,
        "a moved stop keeps its colour"
    );
    assert!(moved.windows(2).all(|w| w[0].position <= w[1].position));

    // Dragged past the end, it stops at 1 and the stops stay sorted.
    mouse_drag(
        &mut harness,
        egui::pos2(at(moved[1].position), markers.center().y),
        egui::vec2(bar.width(), 0.0),
    );
    let clamped = stops(harness.state(), "color_ramp").unwrap();
    assert_eq!(clamped.len(), 3, "{clamped:?}");
    assert!(clamped.windows(2).all(|w| w[0].position <= w[1].position));
    assert_eq!(clamped.iter().filter(|s| s.position == 1.0).count(), 2);
    let undo_once = |harness: &mut Harness<'_, EditorApp>| {
        harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
        steps(harness, 2);
    };
    undo_once(&mut harness);
    assert_eq!(
        stops(harness.state(), "color_ramp").unwrap(),
        moved,
        "one drag, one undo step"
    );

    // A click on the moved stop's marker selects it; the button deletes it.
    click_at(
        &mut harness,
        egui::pos2(at(moved[1].position), markers.center().y),
    );
    harness.get_by_label("Delete stop").click_accesskit();
    steps(&mut harness, 3);
    let deleted = stops(harness.state(), "color_ramp").unwrap();
    assert_eq!(deleted, vec![moved[0].clone(), moved[2].clone()]);

    // Each edit undoes in one step, back to the start.
    undo_once(&mut harness);
    assert_eq!(stops(harness.state(), "color_ramp").unwrap(), moved);
    undo_once(&mut harness);
    assert_eq!(stops(harness.state(), "color_ramp").unwrap(), added);
    undo_once(&mut harness);
    assert_eq!(graph(harness.state()), start);
}

/// A file dropped on the window, as a platform reports it.
#[derive(Debug)]
struct Dropped(std::path::PathBuf);

impl egui::DroppedFile for Dropped {
    fn path(&self) -> &std::path::Path {
        &self.0
    }

    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}

#[test]
fn an_image_texture_reads_a_picked_or_dropped_image_and_shows_a_broken_one_as_its_error() {
    let dir = tempfile::tempdir().unwrap();
    let image = png(dir.path(), "bricks.png");
    let broken = dir.path().join("broken.png");
    std::fs::write(&broken, b"not a png").unwrap();
    let mut harness = harness(ScriptedDialogs {
        image: vec![image.clone(), broken.clone()].into(),
        ..ScriptedDialogs::default()
    });
    harness.get_by_label("block").click();
    steps(&mut harness, 3);
    add_from_menu(
        &mut harness,
        egui::vec2(30.0, 40.0),
        "image",
        "Image Texture",
    );
    drag(
        &mut harness,
        ("image_texture", "color"),
        ("surface", "base_color"),
    );
    let material = harness.state().node_editor().material().unwrap();
    assert_eq!(
        graph(harness.state()).nodes["surface"].inputs["base_color"],
        Input::Link(Link::new("image_texture", "color"))
    );
    assert!(
        harness.state().document().graph_error(material).is_some(),
        "an image texture without a file does not compile"
    );

    // Open… asks the dialogs for an image: the node reads it and the material compiles.
    harness.get_by_label("Open…").click_accesskit();
    steps(&mut harness, 3);
    let file = |app: &EditorApp, node: &str| graph(app).nodes[node].params.get("file").cloned();
    assert_eq!(
        file(harness.state(), "image_texture"),
        Some(Param::Text(image.to_string_lossy().into_owned()))
    );
    assert!(
        harness.state().document().graph_error(material).is_none(),
        "{:?}",
        harness.state().document().graph_error(material)
    );
    assert!(harness.query_by_label("file: bricks.png").is_some());
    let compiled = harness.state().document().scene().materials[material].clone();

    // A file that does not load is the node's error; the graph keeps it and the viewport
    // the last material that compiled.
    harness.get_by_label("Open…").click_accesskit();
    steps(&mut harness, 3);
    assert_eq!(
        file(harness.state(), "image_texture"),
        Some(Param::Text(broken.to_string_lossy().into_owned()))
    );
    let error = harness
        .state()
        .document()
        .graph_error(material)
        .expect("a broken image is an error")
        .clone();
    assert_eq!(error.node.as_deref(), Some("image_texture"), "{error:?}");
    assert!(error.message.contains("broken.png"), "{error:?}");
    assert_eq!(
        harness.state().document().scene().materials[material].graph,
        compiled.graph
    );

    // An image dropped on the canvas becomes an image texture reading it, where it fell.
    let canvas = harness.state().node_editor().canvas_rect().unwrap();
    let at = canvas.left_top() + egui::vec2(60.0, 120.0);
    harness.event(egui::Event::PointerMoved(at));
    harness.step();
    let before = graph(harness.state());
    harness
        .input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(image.clone())));
    // Not an image: not the node editor's.
    harness
        .input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(dir.path().join("notes.txt"))));
    steps(&mut harness, 3);
    let dropped = graph(harness.state());
    assert_eq!(dropped.nodes.len(), before.nodes.len() + 1);
    let node = &dropped.nodes["image_texture_2"];
    assert_eq!(node.kind, "image_texture");
    assert_eq!(
        node.params.get("file"),
        Some(&Param::Text(image.to_string_lossy().into_owned()))
    );
    let drawn = harness
        .state()
        .node_editor()
        .node_position("image_texture_2")
        .unwrap();
    assert!(
        (drawn - at).length() < 1.0,
        "the node's corner is where the file fell: {drawn:?} vs {at:?}"
    );
}

/// A scene file: the Cornell box with its short block made of the bundled marble graph.
fn marble_box(dir: &std::path::Path) -> std::path::PathBuf {
    let mut scene = kiln::scene::default_scene().unwrap();
    let text = std::fs::read_to_string("assets/materials/marble.kmat").unwrap();
    let (_, graph) = kiln::material::parse_material(&text, "marble.kmat").unwrap();
    let block = scene.instances[6].material;
    scene.materials[block] = kiln::scene::Material::from_graph("marble", graph).unwrap();
    let path = dir.join("marble box.kiln");
    kiln::scene::save_scene(&scene, &path, &[]).unwrap();
    path
}

#[test]
fn a_topology_edit_shows_at_once_and_the_specialised_kernel_follows_in_the_background() {
    use kiln::editor::graph_edit::GraphEdit;
    use kiln::editor::viewport::GraphKernels;
    use kiln::editor::{Command, viewport::ViewportStatus};
    use kiln::render::KernelKind;

    let dir = tempfile::tempdir().unwrap();
    let mut harness = start(Setup {
        file: Some(marble_box(dir.path())),
        graph_kernels: GraphKernels::InterpretedThenSpecialized(std::time::Duration::from_millis(
            300,
        )),
        // Enough that the viewport is still accumulating while the compile runs.
        sample_limit: 100_000,
        ..Setup::default()
    });
    let status =
        |h: &Harness<'_, EditorApp>| -> ViewportStatus { h.state().viewport_status().unwrap() };
    // The first image on screen (of the coarse film) is interpreted.
    step_until(&mut harness, "the interpreted first image", |app| {
        app.viewport_status()
            .is_some_and(|s| s.passes >= 1 && s.kernel == Some(KernelKind::Interpreted))
    });
    // Still: the final render's kernel is built in the background while frames keep
    // coming.
    step_until(&mut harness, "the background compile", |app| {
        app.viewport_status().is_some_and(|s| s.compiling)
    });
    let compiling = status(&harness);
    assert!(compiling.passes >= 1, "the interpreted image is on screen");
    let mut frames = 0;
    step_until(&mut harness, "the specialised renderers", |app| {
        frames += 1;
        app.viewport_status().is_some_and(|s| s.compiled_swaps >= 1)
    });
    let compiled = status(&harness);
    assert_eq!(compiled.kernel, Some(KernelKind::Specialized));
    assert!(
        frames > 10,
        "the window kept drawing while the kernel compiled ({frames} frames)"
    );
    assert_eq!(compiled.renderer_builds, compiling.renderer_builds);

    // A topology edit: an invert node between the marble's ramp and its base colour.
    let app = harness.state();
    let material = app.document().scene().instances[6].material;
    let graph = app.document().material_graph(material).unwrap();
    let Input::Link(from) = graph.nodes["surface"].inputs["base_color"].clone() else {
        panic!("marble's base colour is linked");
    };
    let edit = GraphEdit::Batch(vec![
        GraphEdit::AddNode {
            id: "inverted".into(),
            node: Node::new("invert").input("color", Input::Link(from)),
        },
        GraphEdit::connect("inverted", "color", "surface", "base_color"),
    ]);
    let before = status(&harness);
    let posted = std::time::Instant::now();
    harness
        .state_mut()
        .apply_command(Command::EditGraph { material, edit });
    step_until(&mut harness, "the edit's first image", |app| {
        app.viewport_status()
            .is_some_and(|s| s.restarts > before.restarts && s.shown_restart == s.restarts)
    });
    let edited = status(&harness);
    eprintln!(
        "topology edit → first image: {:?} (viewport latency {:?})",
        posted.elapsed(),
        edited.last_edit_latency
    );
    // The specialised kernel, with the graph folded in, cannot take the edit: it went
    // into the interpreted renderers kept aside, which came back without a build.
    assert_standby_returned(&before, &edited, KernelKind::Interpreted);
    // And once still again, the edited graph is compiled in the background too.
    step_until_specialised(&mut harness, "the edited graph compiled", &edited);
    eprintln!(
        "topology edit → specialised renderers swapped in: {:?}",
        posted.elapsed()
    );
}

/// Home over the canvas: the view frames every node.
fn frame_all(harness: &mut Harness<'_, EditorApp>) {
    let canvas = harness.state().node_editor().canvas_rect().unwrap();
    harness.event(egui::Event::PointerMoved(canvas.center()));
    harness.step();
    harness.key_press(egui::Key::Home);
    steps(harness, 3);
}

/// Scrolls the canvas with the mouse wheel, as a user pans, until node `id` is drawn at its
/// centre: Home shows a tall graph from its top, at a scale text can be read at.
fn scroll_into_view(harness: &mut Harness<'_, EditorApp>, id: &str) {
    let canvas = harness.state().node_editor().canvas_rect().unwrap();
    let rect = harness
        .state()
        .node_editor()
        .node_rect(id)
        .unwrap_or_else(|| panic!("node {id} is drawn"));
    harness.event(egui::Event::PointerMoved(canvas.center()));
    harness.step();
    harness.event(egui::Event::MouseWheel {
        unit: egui::MouseWheelUnit::Point,
        delta: canvas.center() - rect.center(),
        phase: egui::TouchPhase::Move,
        modifiers: egui::Modifiers::NONE,
    });
    steps(harness, 10);
    let rect = harness.state().node_editor().node_rect(id).unwrap();
    assert!(
        canvas.contains_rect(rect),
        "node {id} scrolled into the canvas {canvas:?}: {rect:?}"
    );
}

/// Shift+clicks the header of node `id` (snarl adds it to its selection).
fn shift_click_node(harness: &mut Harness<'_, EditorApp>, id: &str) {
    let rect = harness
        .state()
        .node_editor()
        .node_rect(id)
        .unwrap_or_else(|| panic!("node {id} is drawn"));
    let header = egui::pos2(rect.center().x, rect.top() + 10.0);
    harness.event(egui::Event::PointerMoved(header));
    harness.step();
    for pressed in [true, false] {
        harness.event_modifiers(
            egui::Event::PointerButton {
                pos: header,
                button: egui::PointerButton::Primary,
                pressed,
                modifiers: egui::Modifiers::SHIFT,
            },
            egui::Modifiers::SHIFT,
        );
        harness.step();
    }
    steps(harness, 2);
}

/// The material's WGSL up to names: what it computes. The compiler numbers values
/// (`n3`) and helpers (`m_ramp1`) in the order of the flattened node ids, and comments
/// each with its node's path, which grouping changes: such names are renamed by their
/// first appearance and comments dropped.
fn computes(g: &Graph) -> String {
    let code = kiln::material::compile("m", g, "m")
        .unwrap_or_else(|e| panic!("{}", e.message))
        .code;
    let numbered = |word: &str| {
        let stem = word.trim_end_matches(|c: char| c.is_ascii_digit());
        stem.len() < word.len() && (stem == "n" || stem.starts_with("m_"))
    };
    let mut names = std::collections::BTreeMap::new();
    let mut out = String::new();
    for line in code.lines().filter(|l| !l.trim_start().starts_with("//")) {
        let mut word = String::new();
        for c in line.chars().chain(std::iter::once('\n')) {
            if c.is_ascii_alphanumeric() || c == '_' {
                word.push(c);
                continue;
            }
            if numbered(&word) {
                let next = format!("v{}", names.len());
                word = names.entry(word).or_insert(next).clone();
            }
            out.push_str(&word);
            out.push(c);
            word.clear();
        }
    }
    out
}

#[test]
fn group_enter_edit_exit_ungroup_undo_and_a_frame_saved_and_reopened() {
    let dir = tempfile::tempdir().unwrap();
    let saved = dir.path().join("structure.kiln");
    let mut harness = harness(ScriptedDialogs {
        save: vec![saved.clone()].into(),
        ..ScriptedDialogs::default()
    });
    harness.get_by_label("block").click();
    steps(&mut harness, 3);
    let material = harness.state().node_editor().material().unwrap();
    let name = harness.state().document().scene().materials[material]
        .name
        .clone();
    let start = graph(harness.state());
    add_from_menu(
        &mut harness,
        egui::vec2(30.0, 40.0),
        "noise",
        "Noise Texture",
    );
    steps(&mut harness, 2);
    drag(
        &mut harness,
        ("noise_texture", "color"),
        ("surface", "base_color"),
    );
    let connected = graph(harness.state());
    assert_eq!(
        connected.nodes["surface"].inputs["base_color"],
        Input::Link(Link::new("noise_texture", "color"))
    );

    // Ctrl+G on the noise and the BSDF: one group, its instance read by the output.
    shift_click_node(&mut harness, "noise_texture");
    shift_click_node(&mut harness, "surface");
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::G);
    steps(&mut harness, 3);
    let grouped = graph(harness.state());
    let group = grouped.groups.get("NodeGroup").unwrap_or_else(|| {
        panic!(
            "a group is made: {:?} {:?}",
            grouped.groups.keys(),
            harness.state().node_editor().message()
        )
    });
    assert!(group.nodes.contains_key("noise_texture") && group.nodes.contains_key("surface"));
    assert!(!grouped.nodes.contains_key("noise_texture") && !grouped.nodes.contains_key("surface"));
    assert_eq!(grouped.nodes["group"].kind, "group");
    assert_eq!(
        grouped.nodes["output"].inputs["surface"],
        Input::Link(Link::new("group", "bsdf"))
    );
    assert_eq!(computes(&grouped), computes(&connected));
    assert!(harness.state().document().graph_error(material).is_none());

    // Tab on the group node enters it: the breadcrumb names the path, the inner nodes
    // and the group's output node show.
    frame_all(&mut harness);
    scroll_into_view(&mut harness, "group");
    shift_click_node(&mut harness, "group");
    harness.key_press(egui::Key::Tab);
    steps(&mut harness, 3);
    assert_eq!(harness.state().node_editor().group_path(), ["NodeGroup"]);
    harness.get_by_label(&format!("{name} › NodeGroup"));
    harness.get_by_label("Group Output");
    assert!(
        harness
            .state()
            .node_editor()
            .node_rect("noise_texture")
            .is_some()
    );
    if let Some(path) = std::env::var_os("KILN_GROUP_SHOT") {
        // A look inside the group, for whoever changes how groups are drawn.
        harness.render().unwrap().save(path).unwrap();
    }

    // A value inside: the group's node changes.
    set_noise_scale(&mut harness, 12.5);
    let valued = graph(harness.state());
    assert_eq!(
        valued.groups["NodeGroup"].nodes["noise_texture"].inputs["scale"],
        Input::from(12.5)
    );

    // The interface panel adds a float input (and, the group having none, its input
    // node inside).
    harness.get_by_label("Group interface").click();
    steps(&mut harness, 2);
    harness.get_by_label("+ Input").click();
    steps(&mut harness, 2);
    harness.get_by_label("float").click();
    steps(&mut harness, 3);
    let edited = graph(harness.state());
    let group = &edited.groups["NodeGroup"];
    assert_eq!(
        group.inputs.len(),
        1,
        "{:?}",
        harness.state().node_editor().message()
    );
    assert_eq!(group.inputs[0].name, "Value");
    assert_eq!(group.nodes["group_input"].kind, "group_input");
    assert_eq!(edited.nodes["group"].kind, "group");

    // Tab with nothing selected leaves the group.
    frame_all(&mut harness);
    harness.key_press(egui::Key::Tab);
    steps(&mut harness, 3);
    assert!(harness.state().node_editor().group_path().is_empty());
    assert!(
        harness
            .query_by_label(&format!("{name} › NodeGroup"))
            .is_none()
    );

    // Ctrl+Alt+G ungroups: the nodes are back, wired as before, the group gone.
    frame_all(&mut harness);
    scroll_into_view(&mut harness, "group");
    shift_click_node(&mut harness, "group");
    harness.key_press_modifiers(
        egui::Modifiers::COMMAND.plus(egui::Modifiers::ALT),
        egui::Key::G,
    );
    steps(&mut harness, 3);
    let ungrouped = graph(harness.state());
    assert!(
        ungrouped.groups.is_empty(),
        "{:?}",
        harness.state().node_editor().message()
    );
    assert_eq!(
        ungrouped.nodes["output"].inputs["surface"],
        Input::Link(Link::new("surface", "bsdf"))
    );
    assert_eq!(
        ungrouped.nodes["noise_texture"].inputs["scale"],
        Input::from(12.5)
    );
    assert_eq!(computes(&ungrouped), computes(&edited));

    // Each step is one undo: ungroup, input, value, group, wire, node.
    for expected in [&edited, &valued, &grouped, &connected] {
        harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
        steps(&mut harness, 2);
        assert_eq!(&graph(harness.state()), expected);
    }
    for _ in 0..2 {
        harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
        steps(&mut harness, 2);
    }
    assert_eq!(graph(harness.state()), start);

    // Ctrl+J frames the BSDF; dragging the frame's label bar moves it, one undo step.
    frame_all(&mut harness);
    shift_click_node(&mut harness, "surface");
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::J);
    steps(&mut harness, 3);
    let framed = graph(harness.state());
    assert_eq!(framed.frames["frame"].nodes, ["surface"]);
    assert_eq!(framed.frames["frame"].label, "Frame");
    frame_all(&mut harness);
    let bar = harness
        .state()
        .node_editor()
        .frame_bar("frame")
        .expect("the frame's label bar is drawn");
    let surface_before = harness
        .state()
        .node_editor()
        .node_position("surface")
        .unwrap();
    mouse_drag(&mut harness, bar.center(), egui::vec2(80.0, 40.0));
    let moved = graph(harness.state());
    let surface_after = harness
        .state()
        .node_editor()
        .node_position("surface")
        .unwrap();
    assert!(
        (surface_after - surface_before - egui::vec2(80.0, 40.0)).length() < 2.0,
        "{surface_before:?} → {surface_after:?}"
    );
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    steps(&mut harness, 2);
    assert_eq!(
        graph(harness.state()),
        framed,
        "a frame drag is one undo step"
    );
    harness.key_press_modifiers(
        egui::Modifiers::COMMAND.plus(egui::Modifiers::SHIFT),
        egui::Key::Z,
    );
    steps(&mut harness, 2);
    assert_eq!(graph(harness.state()), moved);

    // Saved and reopened, the frame is there; saving again writes the same bytes.
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    steps(&mut harness, 2);
    assert!(saved.exists(), "{:?}", harness.state().error());
    let first = std::fs::read(&saved).unwrap();
    harness.state_mut().open(saved.clone());
    steps(&mut harness, 2);
    let reopened = harness.state().document().material_graph(material).unwrap();
    assert_eq!(reopened, moved);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    steps(&mut harness, 2);
    assert_eq!(std::fs::read(&saved).unwrap(), first);
}

/// Sets the noise texture's scale field (5 by default) to `value`, as a screen reader
/// would, and lets the edit land.
fn set_noise_scale(harness: &mut Harness<'_, EditorApp>, value: f64) {
    let field = harness
        .get_all_by_role_and_label(Role::SpinButton, "scale")
        .find(|n| n.accesskit_node().numeric_value() == Some(5.0))
        .expect("the noise texture's scale field (5 by default)");
    let (target_node, target_tree) = field.accesskit_node().locate();
    harness.event(egui::Event::AccessKitActionRequest(
        accesskit::ActionRequest {
            action: accesskit::Action::SetValue,
            target_node,
            target_tree,
            data: Some(accesskit::ActionData::NumericValue(value)),
        },
    ));
    steps(harness, 3);
}

/// The node editor's World switch shows the world's graph on the same canvas: New World
/// makes one of the environment's colour, a Sky Texture added from the menu and wired into
/// the output lights the viewport (with a sun), and undo takes the wire away.
#[test]
fn the_world_graph_is_edited_on_the_canvas() {
    let mut harness = harness(ScriptedDialogs::default());
    step_until(&mut harness, "the first samples", |app| {
        app.viewport_status()
            .is_some_and(|s| s.samples >= SAMPLE_LIMIT && s.error.is_none())
    });
    harness.get_by_label("World").click();
    steps(&mut harness, 2);
    assert!(harness.state().node_editor().showing_world());
    harness.get_by_label("New World").click();
    steps(&mut harness, 3);
    let world_graph = |app: &EditorApp| app.document().world_graph().expect("a world");
    assert!(world_graph(harness.state()).nodes.contains_key("output"));
    if let Some(path) = std::env::var_os("KILN_WORLD_SHOT") {
        harness.render().unwrap().save(path).unwrap();
    }

    add_from_menu(&mut harness, egui::vec2(30.0, 40.0), "sky", "Sky Texture");
    assert_eq!(
        world_graph(harness.state()).nodes["sky_texture"].kind,
        "sky_texture"
    );
    let restarts = harness.state().viewport_status().unwrap().restarts;
    frame_all(&mut harness);
    let before = world_graph(harness.state());
    drag(&mut harness, ("sky_texture", "color"), ("output", "color"));
    if let Some(path) = std::env::var_os("KILN_WORLD_SHOT") {
        harness.render().unwrap().save(path).unwrap();
    }
    let wired = world_graph(harness.state());
    assert_eq!(
        wired.nodes["output"].inputs.get("color"),
        Some(&Input::Link(Link::new("sky_texture", "color"))),
        "message: {:?}",
        harness.state().node_editor().message()
    );
    let world = harness.state().document().scene().world.clone().unwrap();
    assert_eq!(world.suns().unwrap().len(), 1);
    step_until(&mut harness, "the sky's samples", |app| {
        app.viewport_status().is_some_and(|s| {
            s.restarts > restarts && s.samples >= SAMPLE_LIMIT && s.error.is_none()
        })
    });

    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    steps(&mut harness, 2);
    assert_eq!(world_graph(harness.state()), before);
}
