//! The outliner: the camera, the objects and the lights of the document, as Blender lists
//! them. Click selects, double-click renames, the eye hides and shows, the context menu
//! (right click) renames, duplicates, hides and deletes. Every change is a command on the
//! document.

use egui::{RichText, Ui};

use super::document::{Command, Document, Selection};
use super::node_editor::MaterialDrag;

/// What the outliner keeps between frames: the item being renamed and its text.
#[derive(Default)]
pub struct Outliner {
    renaming: Option<(Selection, String)>,
}

/// What the user asked for in the outliner this frame.
pub enum OutlinerAction {
    Select(Selection),
    Apply(Command),
}

impl Outliner {
    pub fn ui(&mut self, ui: &mut Ui, document: &Document) -> Vec<OutlinerAction> {
        let mut actions = Vec::new();
        egui::ScrollArea::vertical()
            .auto_shrink([false, false])
            .show(ui, |ui| {
                ui.label(RichText::new("Scene").strong());
                self.row(ui, document, Selection::Camera, "📷", &mut actions);
                for i in 0..document.objects().len() {
                    self.row(ui, document, Selection::Object(i), "▣", &mut actions);
                }
                for i in 0..document.lights().len() {
                    self.row(ui, document, Selection::Light(i), "💡", &mut actions);
                }
            });
        actions
    }

    fn row(
        &mut self,
        ui: &mut Ui,
        document: &Document,
        target: Selection,
        icon: &str,
        actions: &mut Vec<OutlinerAction>,
    ) {
        let name = document.name(target).to_owned();
        let visible = document.visible(target);
        ui.horizontal(|ui| {
            ui.add_space(12.0);
            ui.label(icon);
            if let Some((_, text)) = self.renaming.as_mut().filter(|(r, _)| *r == target) {
                let edit = ui.add(egui::TextEdit::singleline(text).desired_width(140.0));
                if !edit.has_focus() && !edit.lost_focus() {
                    edit.request_focus();
                }
                if edit.lost_focus() {
                    let cancelled = ui.input(|i| i.key_pressed(egui::Key::Escape));
                    if !cancelled && *text != name {
                        actions.push(OutlinerAction::Apply(Command::Rename {
                            target,
                            name: text.clone(),
                        }));
                    }
                    self.renaming = None;
                }
                return;
            }
            let selected = document.selection == Some(target);
            let text = if visible {
                RichText::new(&name)
            } else {
                RichText::new(&name).weak()
            };
            let label = ui.selectable_label(selected, text);
            if label.clicked() {
                actions.push(OutlinerAction::Select(target));
            }
            // A material dropped from the node editor's material list.
            if let (Selection::Object(object), Some(dragged)) =
                (target, label.dnd_release_payload::<MaterialDrag>())
            {
                let MaterialDrag(material) = *dragged;
                actions.push(OutlinerAction::Apply(Command::AssignMaterial {
                    object,
                    material,
                }));
            }
            if label.double_clicked() && target != Selection::Camera {
                self.renaming = Some((target, name.clone()));
            }
            if target != Selection::Camera {
                label.context_menu(|ui| {
                    if ui.button("Rename").clicked() {
                        self.renaming = Some((target, name.clone()));
                        ui.close();
                    }
                    if let Some(command) = document.duplicate(target) {
                        if ui.button("Duplicate").clicked() {
                            actions.push(OutlinerAction::Apply(command));
                            ui.close();
                        }
                    }
                    if ui.button(if visible { "Hide" } else { "Show" }).clicked() {
                        actions.push(OutlinerAction::Apply(Command::SetVisible {
                            target,
                            visible: !visible,
                        }));
                        ui.close();
                    }
                    if let Some(command) = document.delete(target) {
                        if ui.button("Delete").clicked() {
                            actions.push(OutlinerAction::Apply(command));
                            ui.close();
                        }
                    }
                });
            }
            if target != Selection::Camera {
                ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                    let eye = if visible { "👁" } else { "—" };
                    let hint = if visible { "Hide" } else { "Show" };
                    let button = ui
                        .add(egui::Button::new(eye).frame(false))
                        .on_hover_text(format!("{hint} {name}"));
                    if button.clicked() {
                        actions.push(OutlinerAction::Apply(Command::SetVisible {
                            target,
                            visible: !visible,
                        }));
                    }
                });
            }
        });
    }
}
