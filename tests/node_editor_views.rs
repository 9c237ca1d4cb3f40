//! How the node editor looks and how fast it draws: a snapshot of the bundled marble
//! material's graph (its automatic layout), and the frame time of a 200-node graph (a
//! measurement printed for docs/BENCHMARKS.md, not a pass/fail threshold).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use kiln::editor::{Command, EditorApp, ScriptedDialogs};

#[path = "common/editor_harness.rs"]
mod editor_harness;

use editor_harness::{Setup, start};

/// Pixels that may differ from the snapshot: text antialiasing on another CPU.
const SNAPSHOT_FAILED_PIXELS: usize = 200;

/// A scene of one quad whose material is `material` (a `.kmat` file or inline graph RON),
/// written in `dir`.
fn scene_with(dir: &Path, material: &str) -> PathBuf {
    let path = dir.join("graph.kiln");
    let text = format!(
        r#"(
    version: 1,
    render: (width: 64, height: 64),
    camera: (position: (0, 0, 3), look_at: (0, 0, 0), projection: Perspective(fov_y: 40)),
    environment: (0.8, 0.8, 0.8),
    materials: {{ "shown": {material} }},
    meshes: {{ "quad": Quad }},
    instances: [(name: "quad", mesh: "quad", material: "shown", transform: (rotate: (90, 0, 0)))],
)"#
    );
    std::fs::write(&path, text).unwrap();
    path
}

/// The editor on `path` in a window wide enough for the marble's five nodes side by side
/// at the canvas's smallest framing scale.
fn open(path: PathBuf) -> Harness<'static, EditorApp> {
    let mut harness = start(Setup {
        dialogs: ScriptedDialogs::default(),
        file: Some(path),
        size: egui::vec2(2400.0, 1000.0),
        ..Setup::default()
    });
    harness.step();
    harness.get_by_label("quad").click();
    harness.step();
    harness
}

#[test]
fn the_marble_graph_matches_its_snapshot() {
    let dir = tempfile::tempdir().unwrap();
    let marble = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/materials/marble.kmat");
    let mut harness = open(scene_with(
        dir.path(),
        &format!("(graph_file: {:?})", marble.display().to_string()),
    ));
    // Let the node editor frame the graph.
    for _ in 0..10 {
        harness.step();
    }
    let canvas = harness
        .state()
        .node_editor()
        .canvas_rect()
        .expect("the canvas was drawn");
    let image = harness.render().expect("the window renders");
    let ppp = harness.ctx.pixels_per_point();
    let px = |v: f32| (v * ppp).round() as u32;
    let crop = image::imageops::crop_imm(
        &image,
        px(canvas.left()),
        px(canvas.top()),
        px(canvas.width()),
        px(canvas.height()),
    )
    .to_image();
    egui_kittest::image_snapshot_options(
        &crop,
        "node_editor_marble",
        &egui_kittest::SnapshotOptions::new().max_failed_pixels(SNAPSHOT_FAILED_PIXELS),
    );
}

#[test]
fn frame_time_with_200_nodes() {
    // A chain of 199 math nodes into the base colour: node 0 adds 0.01 to a constant,
    // each next one to the previous.
    let mut nodes = String::new();
    for i in 0..199 {
        let input = if i == 0 {
            "0.2".to_owned()
        } else {
            format!("\"m{}.value\"", i - 1)
        };
        nodes.push_str(&format!(
            "\"m{i}\": (type: \"math\", params: {{ \"operation\": \"add\" }}, inputs: {{ \"a\": {input}, \"b\": 0.001 }}),\n"
        ));
    }
    let graph = format!(
        "(graph: (nodes: {{ {nodes} \"surface\": (type: \"principled_bsdf\", inputs: {{ \"roughness\": \"m198.value\" }}), \"out\": (type: \"material_output\", inputs: {{ \"surface\": \"surface.bsdf\" }}) }}))"
    );
    let dir = tempfile::tempdir().unwrap();
    let mut harness = open(scene_with(dir.path(), &graph));
    let shown = harness
        .state()
        .node_editor()
        .material()
        .and_then(|m| harness.state().document().material_graph(m))
        .expect("the graph is shown");
    assert_eq!(
        shown.nodes.len(),
        201,
        "199 math nodes, the BSDF and the output"
    );
    // Frames of the canvas with every node drawn (zoomed out to frame all), and while a
    // value changes (each change rebuilds the canvas from the document).
    let mut idle = Vec::new();
    for _ in 0..20 {
        let start = Instant::now();
        harness.step();
        idle.push(start.elapsed());
    }
    let mut editing = Vec::new();
    for i in 0..10 {
        let material = harness.state().node_editor().material().unwrap();
        let command = Command::EditGraph {
            material,
            edit: kiln::editor::graph_edit::GraphEdit::SetInput {
                node: "m0".into(),
                input: "b".into(),
                value: Some(kiln::material::Input::Value(kiln::material::Value::Float(
                    0.001 * i as f32,
                ))),
            },
        };
        let start = Instant::now();
        harness.state_mut().apply_command(command);
        harness.step();
        editing.push(start.elapsed());
    }
    let median = |mut v: Vec<Duration>| {
        v.sort();
        v[v.len() / 2]
    };
    println!(
        "node editor with {} nodes: frame {:?} (median of 20), frame after a value edit {:?} (median of 10)",
        shown.nodes.len(),
        median(idle),
        median(editing)
    );
}
