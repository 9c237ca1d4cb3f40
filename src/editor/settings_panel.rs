//! The Render and World tabs of the properties editor, as Blender has them: the render
//! settings the scene file carries (resolution with presets, samples, bounces, seed, view
//! transform, exposure), the editor's own (the viewport's sample limit, export options),
//! the final render's button, progress and export; and the world (its node graph's
//! values, or the environment's colour, map, strength and rotation). Document settings change through commands, like every other edit.

use egui::{DragValue, RichText, Ui};
use glam::Vec3;

use crate::film::tonemap::Tonemap;
use crate::material::nodes::{self, ParamKind, WORLD_OUTPUT};
use crate::material::{Input, Param, SocketType, Value};
use crate::scene::{Quality, WORLD_RESOLUTIONS, World, lookdev};
use crate::shader::sampling::{FilterKind, MAX_FILTER_WIDTH, Sampler};

use super::app::PIXEL_SIZES;
use super::document::{Command, Document, GestureId};
use super::final_render::RenderState;
use super::inspector::{Edit, float_row, gesture, parameter_label, section};
use super::session::ViewportPreferences;

/// Resolution presets (Blender's Format presets, in the order of the list).
pub const RESOLUTION_PRESETS: [(&str, u32, u32); 5] = [
    ("4K UHD", 3840, 2160),
    ("Full HD", 1920, 1080),
    ("HD 720p", 1280, 720),
    ("Square 1080", 1080, 1080),
    ("1080 × 720", 1080, 720),
];

/// The editor's settings that are not part of the document.
pub struct ViewOptions {
    /// The viewport's pixel size and sample limit (kept between sessions).
    pub viewport: ViewportPreferences,
    /// Options for the image writer on export (`bits=16`, `quality=90`, …).
    pub export_options: String,
    /// How the viewport's kernels hold graph materials.
    pub graph_kernels: super::viewport::GraphKernels,
}

/// What the Render tab asks of the app.
pub enum RenderAction {
    Edit(Edit),
    StartRender,
    CancelRender,
    ShowResult,
    Export,
}

/// A row "label  [field]" of a whole-number setting; returns the gesture when it changed.
fn count_row(
    ui: &mut Ui,
    label: &str,
    field: DragValue<'_>,
    tooltip: &str,
) -> Option<Option<GestureId>> {
    let label = ui.label(label);
    let label = if tooltip.is_empty() {
        label
    } else {
        label.on_hover_text(tooltip)
    };
    let r = ui.add(field).labelled_by(label.id);
    ui.end_row();
    r.changed().then(|| gesture(&r))
}

/// A row choosing one of `all` for `value` by its label (`label_of`), Blender's enum
/// menu; returns whether a choice was clicked.
fn choice_row<T: Copy + PartialEq>(
    ui: &mut Ui,
    label: &str,
    tooltip: &str,
    value: &mut T,
    all: &[T],
    label_of: fn(T) -> &'static str,
) -> bool {
    choice_row_with(ui, label, tooltip, value, all, label_of, |_| None)
}

/// [`choice_row`] whose choices `unavailable` names a reason for are shown greyed out,
/// with the reason as their tooltip.
fn choice_row_with<T: Copy + PartialEq>(
    ui: &mut Ui,
    label: &str,
    tooltip: &str,
    value: &mut T,
    all: &[T],
    label_of: fn(T) -> &'static str,
    unavailable: fn(T) -> Option<&'static str>,
) -> bool {
    let label = ui.label(label);
    let label = if tooltip.is_empty() {
        label
    } else {
        label.on_hover_text(tooltip)
    };
    let mut clicked = false;
    egui::ComboBox::from_id_salt(label.id)
        .selected_text(label_of(*value))
        .show_ui(ui, |ui| {
            for &choice in all {
                let why_not = unavailable(choice);
                let option = ui.add_enabled(
                    why_not.is_none(),
                    egui::Button::selectable(*value == choice, label_of(choice)),
                );
                let option = match why_not {
                    Some(why) => option.on_disabled_hover_text(why),
                    None => option,
                };
                if option.clicked() {
                    *value = choice;
                    clicked = true;
                }
            }
        })
        .response
        .labelled_by(label.id);
    ui.end_row();
    clicked
}

/// The Render tab. `render` is the state of the last final render, if any.
pub fn render_tab_ui(
    ui: &mut Ui,
    document: &Document,
    options: &mut ViewOptions,
    render: Option<RenderState>,
) -> Vec<RenderAction> {
    let mut actions = Vec::new();
    let mut settings = document.scene().settings;
    let before = settings;
    let mut changed: Option<Option<GestureId>> = None;
    section(ui, "Format", |ui| {
        let label = ui.label("Preset");
        let current = RESOLUTION_PRESETS
            .iter()
            .find(|(_, w, h)| (*w, *h) == (settings.width, settings.height))
            .map_or("Custom", |(name, _, _)| *name);
        egui::ComboBox::from_id_salt("resolution preset")
            .selected_text(current)
            .show_ui(ui, |ui| {
                for (name, w, h) in RESOLUTION_PRESETS {
                    let text = format!("{name}  ({w}×{h})");
                    if ui
                        .selectable_label((w, h) == (settings.width, settings.height), text)
                        .clicked()
                    {
                        (settings.width, settings.height) = (w, h);
                        changed = Some(None);
                    }
                }
            })
            .response
            .labelled_by(label.id);
        ui.end_row();
        for (name, value) in [
            ("Resolution X", &mut settings.width),
            ("Resolution Y", &mut settings.height),
        ] {
            let field = DragValue::new(value).range(1..=32768).suffix(" px");
            changed = count_row(ui, name, field, "").or(changed);
        }
    });
    section(ui, "Sampling", |ui| {
        let label = ui.label("Quality").on_hover_text(
            "Sets the samples, bounces, clamp, noise threshold and denoiser together, to \
             values measured on Kiln's scenes (docs/BENCHMARKS.md); as kiln render \
             --quality. Editing any of them makes it Custom.",
        );
        egui::ComboBox::from_id_salt("quality preset")
            .selected_text(Quality::of(&settings).map_or("Custom", Quality::label))
            .show_ui(ui, |ui| {
                for q in Quality::ALL {
                    let chosen = Quality::of(&settings) == Some(q);
                    if ui
                        .selectable_label(chosen, q.label())
                        .on_hover_text(q.describe())
                        .clicked()
                    {
                        q.apply(&mut settings);
                        changed = Some(None);
                    }
                }
            })
            .response
            .labelled_by(label.id);
        ui.end_row();
        let samples = DragValue::new(&mut settings.samples_per_pixel).range(1..=1 << 20);
        changed = count_row(ui, "Samples", samples, "").or(changed);
        let bounces = DragValue::new(&mut settings.max_bounces).range(0..=1024);
        changed = count_row(ui, "Max Bounces", bounces, "").or(changed);
        let volume = DragValue::new(&mut settings.max_volume_bounces).range(0..=1024);
        let tooltip = "Scattering events in volumes per path; past them volumes only absorb \
                       (0: no light scattered in volumes). Volume scattering counts against \
                       Max Bounces too.";
        changed = count_row(ui, "Volume Bounces", volume, tooltip).or(changed);
        let seed = DragValue::new(&mut settings.seed);
        let tooltip = "The same seed renders the same image; another gives other noise.";
        changed = count_row(ui, "Seed", seed, tooltip).or(changed);
        let threshold = DragValue::new(&mut settings.noise_threshold)
            .range(0.0..=1.0)
            .speed(0.001)
            .max_decimals(4);
        let tooltip = "Adaptive sampling in final renders: a pixel stops taking samples once \
                       its estimated noise is below this (checked from 16 samples on), so \
                       the samples go where noise remains. 0.01 is clean, 0.05 a preview; \
                       0: off. The viewport samples every pixel.";
        changed = count_row(ui, "Noise Threshold", threshold, tooltip).or(changed);
        let tooltip = "What a final render's image goes through before it is shown and \
                       saved. À-trous: an edge-avoiding filter guided by the albedo, normals \
                       and depth and by each pixel's noise; the image as rendered is kept as \
                       the EXR's noisy layer. Open Image Denoise: Intel's neural denoiser, \
                       in builds with it. The viewport is never denoised.";
        if choice_row_with(
            ui,
            "Denoise",
            tooltip,
            &mut settings.denoiser,
            &crate::scene::Denoiser::ALL,
            crate::scene::Denoiser::label,
            crate::scene::Denoiser::unavailable,
        ) {
            changed = Some(None);
        }
        let tooltip = "Where each path's random numbers come from. Sobol: stratified over a \
                       pixel's samples, less noise at the same samples. Independent: white \
                       noise, for comparison.";
        let sampler = &mut settings.sampling.sampler;
        if choice_row(
            ui,
            "Pattern",
            tooltip,
            sampler,
            &Sampler::ALL,
            Sampler::label,
        ) {
            changed = Some(None);
        }
    });
    section(ui, "Clamping", |ui| {
        for (name, limit, tooltip) in [
            (
                "Direct Light",
                &mut settings.clamp.direct,
                "The most one sample's direct light (scattered at most once) may add, its \
                 colour kept: less noise from small bright lights, darker highlights. 0: off.",
            ),
            (
                "Indirect Light",
                &mut settings.clamp.indirect,
                "The most one sample's indirect light (scattered twice or more) may add: \
                 fewer fireflies from caustics and glossy bounces, darker ones. 0: off.",
            ),
        ] {
            let field = DragValue::new(limit).range(0.0..=1.0e6).speed(0.05);
            changed = count_row(ui, name, field, tooltip).or(changed);
        }
    });
    section(ui, "Volumes", |ui| {
        let resolution =
            DragValue::new(&mut settings.volume_resolution).range(crate::scene::VOLUME_RESOLUTIONS);
        let tooltip = "A volume whose density or colour varies (a graph-driven volume, a \
                       cloud) is baked into a grid with this many points along its object's \
                       longest side: finer keeps more detail, at the cost of memory and of \
                       the bake after every edit of it.";
        changed = count_row(ui, "Grid Resolution", resolution, tooltip).or(changed);
    });
    section(ui, "Film", |ui| {
        let tooltip = "The filter each pixel's samples are drawn from: wider is smoother, \
                       narrower sharper and more aliased.";
        let filter = &mut settings.sampling.filter;
        if choice_row(
            ui,
            "Pixel Filter",
            tooltip,
            &mut filter.kind,
            &FilterKind::ALL,
            FilterKind::label,
        ) {
            changed = Some(None);
        }
        let width = DragValue::new(&mut filter.width)
            .range(0.01..=MAX_FILTER_WIDTH)
            .speed(0.01)
            .suffix(" px");
        changed = count_row(ui, "Filter Width", width, "").or(changed);
    });
    if let Some(gesture) = changed.filter(|_| settings != before) {
        actions.push(RenderAction::Edit(Edit {
            command: Command::SetSettings(settings),
            gesture,
        }));
    }
    let mut view = document.scene().settings.view;
    let mut view_changed: Option<Option<GestureId>> = None;
    section(ui, "Color Management", |ui| {
        let tonemap = &mut view.tonemap;
        if choice_row(
            ui,
            "View Transform",
            "",
            tonemap,
            &Tonemap::ALL,
            Tonemap::label,
        ) {
            view_changed = Some(None);
        }
        if let Some(gesture) = float_row(
            ui,
            "Exposure",
            &mut view.exposure_ev,
            0.05,
            -10.0..=10.0,
            "Stops (EV) applied before the view transform.",
        ) {
            view_changed = Some(gesture);
        }
    });
    if let Some(gesture) = view_changed.filter(|_| view != document.scene().settings.view) {
        actions.push(RenderAction::Edit(Edit {
            command: Command::SetView(view),
            gesture,
        }));
    }
    ui.add_space(8.0);
    render_controls(ui, options, render, &mut actions);
    viewport_section(ui, options);
    actions
}

/// The viewport's own settings (the editor's, not the document's): where it stops
/// sampling and how coarse its pixels are.
fn viewport_section(ui: &mut Ui, options: &mut ViewOptions) {
    section(ui, "Viewport", |ui| {
        let samples = DragValue::new(&mut options.viewport.max_samples).range(1..=1 << 20);
        let tooltip = "Samples per pixel after which the viewport rests.";
        count_row(ui, "Max Samples", samples, tooltip);
        let label = ui.label("Pixel Size").on_hover_text(
            "Screen pixels per viewport pixel along each axis: 2× renders a quarter of \
             the pixels, so the image comes and clears 4 times sooner, blurrier. For slow \
             adapters (a software driver) and large windows. Final renders are not \
             affected.",
        );
        egui::ComboBox::from_id_salt("viewport pixel size")
            .selected_text(format!("{}×", options.viewport.pixel_size))
            .show_ui(ui, |ui| {
                for size in PIXEL_SIZES {
                    ui.selectable_value(&mut options.viewport.pixel_size, size, format!("{size}×"));
                }
            })
            .response
            .labelled_by(label.id);
        ui.end_row();
    });
}

fn render_controls(
    ui: &mut Ui,
    options: &mut ViewOptions,
    render: Option<RenderState>,
    actions: &mut Vec<RenderAction>,
) {
    let running = matches!(
        render,
        Some(RenderState::Preparing | RenderState::Rendering { .. })
    );
    ui.horizontal(|ui| {
        if ui
            .add_enabled(!running, egui::Button::new("Render Image"))
            .on_hover_text("F12")
            .clicked()
        {
            actions.push(RenderAction::StartRender);
        }
        if running && ui.button("Cancel").clicked() {
            actions.push(RenderAction::CancelRender);
        }
    });
    match &render {
        Some(RenderState::Preparing) => {
            ui.add(egui::ProgressBar::new(0.0).text("Preparing the kernel…"));
        }
        Some(RenderState::Rendering { fraction, elapsed }) => {
            let remaining = if *fraction > 0.0 {
                let left = elapsed.as_secs_f64() * (1.0 - fraction) / fraction;
                format!(", {left:.0} s left")
            } else {
                String::new()
            };
            ui.add(
                egui::ProgressBar::new(*fraction as f32)
                    .show_percentage()
                    .text(format!(
                        "{:.0} %  ·  {:.1} s{remaining}",
                        fraction * 100.0,
                        elapsed.as_secs_f64()
                    )),
            );
        }
        Some(RenderState::Finished(result)) => {
            ui.label(format!(
                "Rendered {}×{} at {:.1} spp in {:.2} s{}",
                result.film.width,
                result.film.height,
                result.samples_per_pixel,
                result.elapsed.as_secs_f64(),
                if result.completed { "" } else { " (cancelled)" }
            ));
            ui.horizontal(|ui| {
                if ui.button("Show Render").clicked() {
                    actions.push(RenderAction::ShowResult);
                }
                if ui.button("Export…").clicked() {
                    actions.push(RenderAction::Export);
                }
            });
        }
        Some(RenderState::Failed(message)) => {
            ui.colored_label(
                ui.visuals().error_fg_color,
                format!("Render failed: {message}"),
            );
        }
        None => {}
    }
    ui.horizontal(|ui| {
        let label = ui
            .label("Export options")
            .on_hover_text("PNG: bits=16 · JPEG: quality=90 · EXR: compression=zip|piz|none");
        ui.add(egui::TextEdit::singleline(&mut options.export_options).desired_width(160.0))
            .labelled_by(label.id);
    });
}

/// What the World tab asks of the app.
pub enum WorldAction {
    Edit(Edit),
    LoadMap,
}

/// The World tab: the world's node graph, or the uniform environment and the environment
/// map that replaces it.
pub fn world_tab_ui(ui: &mut Ui, document: &Document) -> Vec<WorldAction> {
    let mut actions = Vec::new();
    let scene = document.scene();
    section(ui, "World Graph", |ui| {
        world_graph_ui(ui, scene.world.as_ref(), &mut actions)
    });
    if scene.world.is_some() {
        ui.weak("The world graph lights the scene; the colour and map below wait unused.");
    }
    section(ui, "Surface", |ui| {
        // Shown as a colour and a strength, as Blender's Background node has them.
        let radiance = scene.environment;
        let strength = radiance.max_element().max(1.0);
        let mut color = (radiance / strength).to_array();
        let mut new_strength = strength;
        let label = ui
            .label("Color")
            .on_hover_text("Linear RGB; shown where no environment map is set.");
        let r = ui.color_edit_button_rgb(&mut color).labelled_by(label.id);
        ui.end_row();
        let mut g = r.changed().then(|| gesture(&r));
        if let Some(gs) = float_row(ui, "Strength", &mut new_strength, 0.01, 0.0..=1e6, "") {
            g = Some(gs);
        }
        if let Some(gesture) = g {
            let value = Vec3::from(color) * new_strength;
            if value != radiance {
                actions.push(WorldAction::Edit(Edit {
                    command: Command::SetEnvironmentColor(value),
                    gesture,
                }));
            }
        }
    });
    section(ui, "Environment Map", |ui| match &scene.environment_map {
        Some(map) => {
            ui.label("Image");
            ui.horizontal(|ui| {
                ui.label(RichText::new(format!("{}×{}", map.width, map.height)).weak());
                if ui.button("Replace…").clicked() {
                    actions.push(WorldAction::LoadMap);
                }
                if ui.button("Remove").clicked() {
                    actions.push(WorldAction::Edit(Edit {
                        command: Command::SetEnvironmentMap(None),
                        gesture: None,
                    }));
                }
            });
            ui.end_row();
            let (mut strength, mut rotation) = (map.strength, map.rotation_degrees);
            let a = float_row(ui, "Map Strength", &mut strength, 0.01, 0.0..=1e6, "");
            let b = float_row(
                ui,
                "Rotation",
                &mut rotation,
                0.5,
                -360.0..=360.0,
                "Degrees about the up (+Y) axis.",
            );
            if let Some(gesture) = a.or(b) {
                actions.push(WorldAction::Edit(Edit {
                    command: Command::SetEnvironmentMapParams {
                        strength,
                        rotation_degrees: rotation,
                    },
                    gesture,
                }));
            }
        }
        None => {
            ui.label("Image");
            if ui.button("Load…").clicked() {
                actions.push(WorldAction::LoadMap);
            }
            ui.end_row();
        }
    });
    actions
}

/// The world graph as Blender's World properties show a world's node tree: each node's
/// unlinked numbers, colours and switches, the output's first, then the bake's
/// resolution. Without a world, a button that makes one of a Sky Texture.
fn world_graph_ui(ui: &mut Ui, world: Option<&World>, actions: &mut Vec<WorldAction>) {
    let set = |world: Option<World>, gesture: Option<GestureId>| {
        WorldAction::Edit(Edit {
            command: Command::SetWorld(world.map(Box::new)),
            gesture,
        })
    };
    let Some(world) = world else {
        ui.label("Graph");
        if ui
            .button("Use Sky Texture")
            .on_hover_text("A clear sky with its sun, as a world graph (docs/NODES.md, World).")
            .clicked()
        {
            actions.push(set(Some(lookdev::world()), None));
        }
        ui.end_row();
        return;
    };
    ui.label("Graph");
    if ui.button("Remove").clicked() {
        actions.push(set(None, None));
    }
    ui.end_row();
    let mut ids: Vec<&String> = world.graph.nodes.keys().collect();
    ids.sort_by_key(|id| (world.graph.nodes[*id].kind != WORLD_OUTPUT, *id));
    for id in ids {
        let node = &world.graph.nodes[id];
        let Some(def) = nodes::find(&node.kind) else {
            continue;
        };
        ui.label(RichText::new(def.label).strong());
        ui.weak(id.as_str());
        ui.end_row();
        for input in &def.inputs {
            if matches!(node.inputs.get(input.name), Some(Input::Link(_))) {
                continue;
            }
            let value = def.constant_input(node, input.name);
            let label = parameter_label(input.name);
            let changed = match (value, input.range) {
                (Some(Value::Float(mut x)), Some(range)) => {
                    let l = ui.label(&label).on_hover_text(input.doc);
                    let r = ui
                        .add(
                            DragValue::new(&mut x)
                                .speed(range.drag_speed())
                                .range(range.min..=range.max)
                                .max_decimals(3),
                        )
                        .labelled_by(l.id);
                    ui.end_row();
                    r.changed().then(|| (Value::Float(x), gesture(&r)))
                }
                (Some(Value::Vec3(mut c)), _) if input.ty == SocketType::Color => {
                    let l = ui.label(&label).on_hover_text(input.doc);
                    let r = ui.color_edit_button_rgb(&mut c).labelled_by(l.id);
                    ui.end_row();
                    r.changed().then(|| (Value::Vec3(c), gesture(&r)))
                }
                _ => None,
            };
            if let Some((value, gesture)) = changed {
                let mut edited = world.clone();
                if let Some(n) = edited.graph.nodes.get_mut(id) {
                    n.inputs.insert(input.name.to_owned(), Input::Value(value));
                }
                actions.push(set(Some(edited), gesture));
            }
        }
        for param in &def.params {
            let ParamKind::Bool(default) = param.kind else {
                continue;
            };
            let mut on = match node.params.get(param.name) {
                Some(Param::Bool(b)) => *b,
                _ => default,
            };
            ui.label(parameter_label(param.name))
                .on_hover_text(param.doc);
            if ui.checkbox(&mut on, "").changed() {
                let mut edited = world.clone();
                if let Some(n) = edited.graph.nodes.get_mut(id) {
                    n.params.insert(param.name.to_owned(), Param::Bool(on));
                }
                actions.push(set(Some(edited), None));
            }
            ui.end_row();
        }
    }
    let mut resolution = world.resolution;
    let l = ui
        .label("Resolution")
        .on_hover_text("Width of the environment map the world is baked into; its height is half.");
    let r = ui
        .add(
            DragValue::new(&mut resolution)
                .range(WORLD_RESOLUTIONS)
                .speed(8.0),
        )
        .labelled_by(l.id);
    ui.end_row();
    if r.changed() {
        let mut edited = world.clone();
        edited.resolution = resolution;
        actions.push(set(Some(edited), gesture(&r)));
    }
}
