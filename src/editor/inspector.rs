//! The inspector (Blender's Properties editor) for the selection: an object's transform and
//! its material, a light's parameters, or the camera's. Each field edits a copy and turns
//! a change into a [`Command`]; a drag of a field is one gesture, so it undoes in one step.
//!
//! The material section is driven by the principled parameter table
//! ([`PARAMETERS`]): every parameter appears, with its range and documentation, without
//! this file naming any.

use egui::{DragValue, Response, RichText, Ui};
use glam::Vec3;

use crate::scene::{Camera, Light};
use crate::shader::principled::{Kind, PARAMETERS, ParamValue, Parameter, Range};

use super::document::{Command, Document, GestureId, Selection, Trs, light_kind};

/// A command the inspector asks for, with the gesture it belongs to.
pub struct Edit {
    pub command: Command,
    pub gesture: Option<GestureId>,
}

/// What else the inspector can ask of the app.
pub enum InspectorAction {
    Edit(Edit),
    /// Make the scene camera the viewport's view (Blender: View ▸ Cameras ▸ Active Camera).
    LookThroughCamera,
    /// Set the scene camera from the viewport's view (Blender: Align Active Camera to View).
    CameraFromView,
}

/// The gesture a changed widget belongs to: its drag, or none for a typed value.
pub(super) fn gesture(response: &Response) -> Option<GestureId> {
    response.dragged().then(|| response.id.value())
}

/// A row "label  [x] [y] [z]"; returns the gesture when a component changed. The three
/// fields carry the row's label for accessibility (tests find them by it).
pub(super) fn vec3_row(
    ui: &mut Ui,
    label: &str,
    value: &mut Vec3,
    speed: f64,
    range: std::ops::RangeInclusive<f32>,
    suffix: &str,
) -> Option<Option<GestureId>> {
    let mut changed = None;
    let label = ui.label(label);
    ui.horizontal(|ui| {
        for (axis, v) in
            ["X ", "Y ", "Z "]
                .into_iter()
                .zip([&mut value.x, &mut value.y, &mut value.z])
        {
            let r = ui
                .add(
                    DragValue::new(v)
                        .prefix(axis)
                        .suffix(suffix)
                        .speed(speed)
                        .range(range.clone())
                        .max_decimals(3),
                )
                .labelled_by(label.id);
            if r.changed() {
                changed = Some(gesture(&r));
            }
        }
    });
    ui.end_row();
    changed
}

/// A row "label  [value]"; returns the gesture when the value changed.
pub(super) fn float_row(
    ui: &mut Ui,
    label: &str,
    value: &mut f32,
    speed: f64,
    range: std::ops::RangeInclusive<f32>,
    tooltip: &str,
) -> Option<Option<GestureId>> {
    let label = ui.label(label);
    let label = if tooltip.is_empty() {
        label
    } else {
        label.on_hover_text(tooltip)
    };
    let r = ui
        .add(
            DragValue::new(value)
                .speed(speed)
                .range(range)
                .max_decimals(3),
        )
        .labelled_by(label.id);
    ui.end_row();
    r.changed().then(|| gesture(&r))
}

/// Blender's label for a parameter: `base_color` → "Base Color".
pub fn parameter_label(name: &str) -> String {
    name.split('_')
        .map(|w| {
            if w == "ior" {
                return "IOR".to_owned();
            }
            let mut c = w.chars();
            c.next()
                .map(|f| f.to_uppercase().chain(c).collect())
                .unwrap_or_default()
        })
        .collect::<Vec<String>>()
        .join(" ")
}

fn range_of(p: &Parameter) -> std::ops::RangeInclusive<f32> {
    match p.range {
        Range::Unit | Range::Flag => 0.0..=1.0,
        Range::NonNegative => 0.0..=f32::MAX,
        Range::Ior => 1.0..=100.0,
        Range::Finite => f32::MIN..=f32::MAX,
    }
}

/// Shows the inspector for the document's selection.
pub fn inspector_ui(ui: &mut Ui, document: &Document, view: &Camera) -> Vec<InspectorAction> {
    let mut actions = Vec::new();
    egui::ScrollArea::vertical()
        .auto_shrink([false, false])
        .show(ui, |ui| match document.selection {
            None => {
                ui.weak("Nothing selected. Click an object in the viewport or the outliner.");
            }
            Some(Selection::Object(i)) => object_ui(ui, document, i, &mut actions),
            Some(Selection::Light(i)) => light_ui(ui, document, i, &mut actions),
            Some(Selection::Camera) => camera_ui(ui, document, view, &mut actions),
        });
    actions
}

/// A titled part of the inspector, open until the user folds it.
fn heading(ui: &mut Ui, title: &str, body: impl FnOnce(&mut Ui)) {
    egui::CollapsingHeader::new(RichText::new(title).strong())
        .default_open(true)
        .show(ui, body);
}

/// A [`heading`] over rows of a label and its value.
pub(super) fn section(ui: &mut Ui, title: &str, body: impl FnOnce(&mut Ui)) {
    heading(ui, title, |ui| {
        egui::Grid::new(title)
            .num_columns(2)
            .spacing([8.0, 4.0])
            .striped(false)
            .show(ui, body);
    });
}

fn object_ui(ui: &mut Ui, document: &Document, object: usize, actions: &mut Vec<InspectorAction>) {
    let scene = document.scene();
    let Some(instance) = scene.instances.get(object) else {
        return;
    };
    ui.heading(document.name(Selection::Object(object)));
    let mesh = &scene.meshes[instance.mesh];
    ui.weak(format!(
        "Mesh \"{}\": {} triangles",
        mesh.name,
        mesh.indices.len()
    ));
    let mut trs = Trs::from_affine(&instance.transform);
    let before = trs;
    let mut changed = None;
    section(ui, "Transform", |ui| {
        let rows = [
            ("Location", &mut trs.translation, 0.1, ""),
            ("Rotation", &mut trs.rotation_degrees, 0.5, "°"),
            ("Scale", &mut trs.scale, 0.01, ""),
        ];
        for (label, value, speed, suffix) in rows {
            let row = vec3_row(ui, label, value, speed, f32::MIN..=f32::MAX, suffix);
            changed = changed.or(row);
        }
    });
    if let Some(gesture) = changed.filter(|_| trs != before) {
        actions.push(InspectorAction::Edit(Edit {
            command: Command::SetTransform {
                object,
                transform: trs.to_affine(),
            },
            gesture,
        }));
    }
    ui.add_space(6.0);
    ui.horizontal(|ui| {
        let label = ui.label("Material");
        let mut chosen = instance.material;
        egui::ComboBox::from_id_salt(("material of", object))
            .selected_text(
                scene
                    .materials
                    .get(chosen)
                    .map_or("(none)", |m| m.name.as_str()),
            )
            .show_ui(ui, |ui| {
                for (i, m) in scene.materials.iter().enumerate() {
                    ui.selectable_value(&mut chosen, i, &m.name);
                }
            })
            .response
            .labelled_by(label.id);
        if chosen != instance.material {
            actions.push(InspectorAction::Edit(Edit {
                command: Command::AssignMaterial {
                    object,
                    material: chosen,
                },
                gesture: None,
            }));
        }
    });
    material_ui(ui, document, instance.material, actions);
}

fn material_ui(
    ui: &mut Ui,
    document: &Document,
    material: usize,
    actions: &mut Vec<InspectorAction>,
) {
    let scene = document.scene();
    let Some(m) = scene.materials.get(material) else {
        return;
    };
    let users = scene
        .instances
        .iter()
        .filter(|i| i.material == material)
        .count();
    let title = format!("Material: {}", m.name);
    ui.add_space(6.0);
    if m.graph.is_some() {
        // Not a `section`: text in a grid cell does not wrap, and would widen the panel
        // (and narrow the node editor beside it) to its length.
        heading(ui, &title, |ui| {
            let note = "A node-graph material: its parameters are set by its nodes.";
            ui.add(egui::Label::new(RichText::new(note).weak()).wrap());
        });
        return;
    }
    if users > 1 {
        ui.weak(format!("Shared by {users} objects"));
    }
    let principled = m.principled;
    section(ui, &title, |ui| {
        for p in &PARAMETERS {
            let Some(value) = principled.get(p.name) else {
                continue;
            };
            let label_text = parameter_label(p.name);
            let mut edit = |value: ParamValue, gesture: Option<GestureId>| {
                actions.push(InspectorAction::Edit(Edit {
                    command: Command::SetMaterialParameter {
                        material,
                        parameter: p.name,
                        value,
                    },
                    gesture,
                }));
            };
            match (p.kind, value) {
                (Kind::Float, ParamValue::Float(mut x)) => {
                    let speed = if p.range == Range::Unit { 0.005 } else { 0.01 };
                    if let Some(g) = float_row(ui, &label_text, &mut x, speed, range_of(p), p.doc) {
                        edit(ParamValue::Float(x), g);
                    }
                }
                (Kind::Color, ParamValue::Color(c)) if p.range == Range::Unit => {
                    let label = ui.label(&label_text).on_hover_text(p.doc);
                    let mut rgb = c.to_array();
                    let r = ui.color_edit_button_rgb(&mut rgb).labelled_by(label.id);
                    ui.end_row();
                    if r.changed() {
                        edit(ParamValue::Color(Vec3::from(rgb)), gesture(&r));
                    }
                }
                (Kind::Color, ParamValue::Color(mut c)) => {
                    // Unbounded colours (emission) take numbers, not a picker.
                    ui.label(&label_text).on_hover_text(p.doc);
                    ui.end_row();
                    if let Some(g) = vec3_row(ui, "", &mut c, 0.01, range_of(p), "") {
                        edit(ParamValue::Color(c), g);
                    }
                }
                (Kind::Bool, ParamValue::Bool(mut b)) => {
                    ui.label(&label_text).on_hover_text(p.doc);
                    let r = ui.checkbox(&mut b, "");
                    ui.end_row();
                    if r.changed() {
                        edit(ParamValue::Bool(b), None);
                    }
                }
                _ => {}
            }
        }
    });
}

/// `light` as a light of another kind (`"Point"`, `"Spot"`, `"Sun"`), keeping what the
/// two share: position, strength and size between point and spot lights; a sun shines
/// the way a spot pointed, with unit irradiance.
fn convert_light(light: &Light, kind: &str) -> Light {
    let (position, direction, intensity, radius) = match *light {
        Light::Point {
            position,
            intensity,
            radius,
        } => (position, Vec3::NEG_Y, intensity, radius),
        Light::Spot {
            position,
            direction,
            intensity,
            radius,
            ..
        } => (position, direction, intensity, radius),
        Light::Distant {
            direction,
            irradiance,
            ..
        } => (
            Vec3::ZERO - direction * 10.0,
            direction,
            irradiance * 100.0,
            0.0,
        ),
    };
    match kind {
        "Point" => Light::Point {
            position,
            intensity,
            radius,
        },
        "Spot" => Light::Spot {
            position,
            direction,
            intensity,
            cone_angle: 30.0,
            blend: 0.15,
            radius,
        },
        _ => Light::Distant {
            direction,
            irradiance: Vec3::ONE,
            angular_diameter: 0.53,
        },
    }
}

fn light_ui(ui: &mut Ui, document: &Document, index: usize, actions: &mut Vec<InspectorAction>) {
    let Some(light) = document.lights().get(index).map(|l| &l.light) else {
        return;
    };
    ui.heading(document.name(Selection::Light(index)));
    ui.horizontal(|ui| {
        let label = ui.label("Type");
        let mut kind = light_kind(light);
        egui::ComboBox::from_id_salt(("light type", index))
            .selected_text(kind)
            .show_ui(ui, |ui| {
                for k in ["Point", "Spot", "Sun"] {
                    ui.selectable_value(&mut kind, k, k);
                }
            })
            .response
            .labelled_by(label.id);
        if kind != light_kind(light) {
            actions.push(InspectorAction::Edit(Edit {
                command: Command::SetLight {
                    light: index,
                    value: convert_light(light, kind),
                },
                gesture: None,
            }));
        }
    });
    let mut value = light.clone();
    let mut changed: Option<Option<GestureId>> = None;
    section(ui, &format!("{} light", light_kind(light)), |ui| {
        let any = f32::MIN..=f32::MAX;
        let non_negative = 0.0..=f32::MAX;
        match &mut value {
            Light::Point {
                position,
                intensity,
                radius,
            } => {
                changed = changed.or(vec3_row(ui, "Position", position, 0.1, any.clone(), ""));
                changed = changed.or(vec3_row(
                    ui,
                    "Intensity (W/sr)",
                    intensity,
                    0.1,
                    non_negative.clone(),
                    "",
                ));
                changed = changed.or(float_row(
                    ui,
                    "Radius",
                    radius,
                    0.01,
                    non_negative,
                    "A sphere light of this radius; 0 is a point.",
                ));
            }
            Light::Spot {
                position,
                direction,
                intensity,
                cone_angle,
                blend,
                radius,
            } => {
                changed = changed.or(vec3_row(ui, "Position", position, 0.1, any.clone(), ""));
                changed = changed.or(vec3_row(ui, "Direction", direction, 0.01, any, ""));
                changed = changed.or(vec3_row(
                    ui,
                    "Intensity (W/sr)",
                    intensity,
                    0.1,
                    non_negative.clone(),
                    "",
                ));
                changed = changed.or(float_row(
                    ui,
                    "Cone angle (°)",
                    cone_angle,
                    0.2,
                    0.01..=180.0,
                    "Half-angle of the cone.",
                ));
                changed = changed.or(float_row(
                    ui,
                    "Blend",
                    blend,
                    0.005,
                    0.0..=1.0,
                    "Softness of the cone's edge.",
                ));
                changed = changed.or(float_row(ui, "Radius", radius, 0.01, non_negative, ""));
            }
            Light::Distant {
                direction,
                irradiance,
                angular_diameter,
            } => {
                changed = changed.or(vec3_row(ui, "Direction", direction, 0.01, any, ""));
                changed = changed.or(vec3_row(
                    ui,
                    "Irradiance (W/m²)",
                    irradiance,
                    0.1,
                    non_negative,
                    "",
                ));
                changed = changed.or(float_row(
                    ui,
                    "Angle (°)",
                    angular_diameter,
                    0.05,
                    0.0..=89.9,
                    "Angular diameter of the sun's disk.",
                ));
            }
        }
    });
    if let Some(gesture) = changed.filter(|_| value != *light) {
        actions.push(InspectorAction::Edit(Edit {
            command: Command::SetLight {
                light: index,
                value,
            },
            gesture,
        }));
    }
}

fn camera_ui(ui: &mut Ui, document: &Document, view: &Camera, actions: &mut Vec<InspectorAction>) {
    let camera = document.scene().camera;
    ui.heading("Camera");
    let mut value = camera;
    let mut changed: Option<Option<GestureId>> = None;
    section(ui, "Camera", |ui| {
        let any = f32::MIN..=f32::MAX;
        changed = changed.or(vec3_row(
            ui,
            "Position",
            &mut value.position,
            0.1,
            any.clone(),
            "",
        ));
        changed = changed.or(vec3_row(ui, "Look at", &mut value.look_at, 0.1, any, ""));
        changed = changed.or(float_row(
            ui,
            "Field of view (°)",
            &mut value.fov_y_degrees,
            0.1,
            1.0..=179.0,
            "Vertical field of view.",
        ));
    });
    section(ui, "Depth of field", |ui| {
        changed = changed.or(float_row(
            ui,
            "Aperture radius",
            &mut value.aperture_radius,
            0.01,
            0.0..=f32::MAX,
            "Radius of the lens; 0 is a pinhole (everything sharp).",
        ));
        changed = changed.or(float_row(
            ui,
            "Focus distance",
            &mut value.focus_distance,
            0.1,
            0.0..=f32::MAX,
            "Distance that is in sharp focus.",
        ));
    });
    if let Some(gesture) = changed.filter(|_| value != camera) {
        actions.push(InspectorAction::Edit(Edit {
            command: Command::SetCamera(value),
            gesture,
        }));
    }
    ui.add_space(6.0);
    ui.horizontal(|ui| {
        if ui
            .button("Look through camera")
            .on_hover_text("Show the scene camera's view in the viewport (Numpad 0)")
            .clicked()
        {
            actions.push(InspectorAction::LookThroughCamera);
        }
        if ui
            .add_enabled(*view != camera, egui::Button::new("Camera from view"))
            .on_hover_text("Move the scene camera to the viewport's view (Ctrl+Alt+Numpad 0)")
            .clicked()
        {
            actions.push(InspectorAction::CameraFromView);
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameter_labels_read_like_blenders() {
        assert_eq!(parameter_label("base_color"), "Base Color");
        assert_eq!(parameter_label("coat_ior"), "Coat IOR");
        assert_eq!(parameter_label("thin_walled"), "Thin Walled");
    }
}
