//! The editor's document: the scene being edited plus what the editor knows about it
//! (object names, visibility, the selection, the file it came from), and the one way to
//! change it, [`Document::apply`] with a [`Command`].
//!
//! Every edit goes through a command, so undo/redo, the unsaved-changes state and the
//! viewport's restart all follow from one stream: a command returns its inverse, the
//! history keeps inverses, and each applied command bumps [`Document::revision`], which the
//! viewport compares with what it rendered. Commands that continue one gesture (the
//! frames of one slider drag) merge into a single undo step.
//!
//! What this is not: a view. Panels read the document and build commands; nothing here
//! knows about egui or the GPU.

use std::path::{Path, PathBuf};

use glam::{Affine3A, EulerRot, Quat, Vec3};

use super::graph_edit::GraphEdit;
use crate::material::texture::load_texture;
use crate::material::{Graph, GraphError};
use crate::scene::{
    Camera, EnvironmentMap, Instance, Light, LightObject, Material, Scene, SceneSettings, World,
};
use crate::shader::principled::ParamValue;
use crate::shader::view::ViewSettings;

/// What can be selected.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Selection {
    /// An instance of [`Scene::instances`], by index.
    Object(usize),
    /// A light of [`Scene::lights`], by index.
    Light(usize),
    /// The scene's camera.
    Camera,
}

/// One edit of the document. Applying a command yields its inverse.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    SetTransform {
        object: usize,
        transform: Affine3A,
    },
    /// One principled parameter of a material, by its name in
    /// [`crate::shader::principled::PARAMETERS`].
    SetMaterialParameter {
        material: usize,
        parameter: &'static str,
        value: ParamValue,
    },
    SetLight {
        light: usize,
        value: Light,
    },
    SetCamera(Camera),
    Rename {
        target: Selection,
        name: String,
    },
    SetVisible {
        target: Selection,
        visible: bool,
    },
    /// Removes an object; its mesh stays in the scene (other objects may share it).
    DeleteObject {
        object: usize,
    },
    /// Places an object at index `object` (undoing a delete, or a duplicate at the end).
    InsertObject {
        object: usize,
        instance: Instance,
    },
    DeleteLight {
        light: usize,
    },
    InsertLight {
        light: usize,
        value: LightObject,
    },
    /// An edit of a material's node graph ([`GraphEdit`]). A graph that no longer
    /// compiles is kept as the edited graph with its error, and the material renders as
    /// it last compiled.
    EditGraph {
        material: usize,
        edit: GraphEdit,
    },
    /// An edit of the world's node graph, kept like a material's when it no longer
    /// compiles (the world renders as it last compiled).
    EditWorldGraph(GraphEdit),
    /// Inserts a material at `index` (later materials move up one); `pending` is an
    /// edited graph that did not compile, restored with it.
    AddMaterial {
        index: usize,
        material: Box<Material>,
        pending: Option<Box<(Graph, GraphError)>>,
    },
    /// Replaces a material whole, with the edited graph that did not compile, if any
    /// (what undoes a graph edit of a material that had no graph).
    SetMaterial {
        material: usize,
        value: Box<Material>,
        pending: Option<Box<(Graph, GraphError)>>,
    },
    /// Removes a material no object uses.
    RemoveMaterial {
        index: usize,
    },
    RenameMaterial {
        material: usize,
        name: String,
    },
    /// Gives an object another material.
    AssignMaterial {
        object: usize,
        material: usize,
    },
    /// The render settings the scene file carries (size, samples, bounces, seed, view).
    SetSettings(SceneSettings),
    /// Exposure and view transform alone: the display changes, the samples stay.
    SetView(ViewSettings),
    /// The uniform environment radiance (linear RGB), shown where no map is.
    SetEnvironmentColor(Vec3),
    /// The environment map's strength and rotation (degrees about +Y).
    SetEnvironmentMapParams {
        strength: f32,
        rotation_degrees: f32,
    },
    /// Replaces (or removes) the environment map.
    SetEnvironmentMap(Option<Box<EnvironmentMap>>),
    /// Replaces (or removes) the world graph, which takes the place of the environment's
    /// colour and map while there is one.
    SetWorld(Option<Box<World>>),
    /// Adds the meshes, materials, objects and lights of an imported scene after the
    /// document's own (its objects refer to its own meshes and materials).
    Append(Box<Appended>),
    /// Drops everything past the given counts (the inverse of an append).
    Truncate(Counts),
}

/// What an [`Command::Append`] adds: a scene's contents (its objects and lights named)
/// with the images its materials embed, which they name `image:0`, `image:1`, … in this
/// list (the document renumbers them after its own).
#[derive(Clone, Debug, PartialEq)]
pub struct Appended {
    pub scene: Scene,
    pub images: Vec<(String, std::sync::Arc<Vec<u8>>)>,
}

/// How many meshes, materials, objects, lights and embedded images a document holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Counts {
    pub meshes: usize,
    pub materials: usize,
    pub objects: usize,
    pub lights: usize,
    pub images: usize,
}

impl Command {
    /// What a command changes, for merging the frames of a gesture: two commands with the
    /// same key replace each other's effect.
    fn key(&self) -> (u8, usize, &'static str) {
        match self {
            Command::SetTransform { object, .. } => (0, *object, ""),
            Command::SetMaterialParameter {
                material,
                parameter,
                ..
            } => (1, *material, parameter),
            Command::SetLight { light, .. } => (2, *light, ""),
            Command::SetCamera(_) => (3, 0, ""),
            Command::Rename { .. } => (4, 0, ""),
            Command::SetVisible { .. } => (5, 0, ""),
            Command::SetSettings(_) => (12, 0, ""),
            Command::SetView(_) => (15, 0, ""),
            Command::SetEnvironmentColor(_) => (13, 0, ""),
            Command::SetEnvironmentMapParams { .. } => (14, 0, ""),
            Command::SetWorld(_) => (16, 0, ""),
            Command::EditWorldGraph(edit) => (17, 0, if edit.only_moves() { "move" } else { "" }),
            Command::EditGraph { material, edit } => {
                (6, *material, if edit.only_moves() { "move" } else { "" })
            }
            Command::AddMaterial { .. } => (7, 0, ""),
            Command::SetMaterial { material, .. } => (11, *material, ""),
            Command::RemoveMaterial { .. } => (8, 0, ""),
            Command::RenameMaterial { material, .. } => (9, *material, ""),
            Command::AssignMaterial { object, .. } => (10, *object, ""),
            // Structural edits never merge: each is its own step.
            _ => (u8::MAX, usize::MAX, ""),
        }
    }

    /// Whether the command changes what is rendered (a rename does not, nor does a view
    /// setting: the display pass applies it to the samples already taken).
    pub fn changes_image(&self) -> bool {
        match self {
            Command::Rename { .. } | Command::RenameMaterial { .. } | Command::SetView(_) => false,
            Command::EditGraph { edit, .. } | Command::EditWorldGraph(edit) => edit.changes_image(),
            _ => true,
        }
    }
}

/// Why a command was refused; the document is unchanged.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct CommandError(pub String);

/// Identifies one continuous gesture (a drag of one widget); commands applied under the
/// same open gesture merge into one undo step.
pub type GestureId = u64;

struct Step {
    /// Unique in the document's life; what "saved" refers to.
    id: u64,
    /// Applying these, last first, undoes the step.
    inverses: Vec<Command>,
    key: (u8, usize, &'static str),
    gesture: Option<GestureId>,
}

/// A transform as the inspector shows it: translation, rotation as Euler angles in
/// degrees (about X, then Y, then Z, as the scene file's `rotate`), and scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    pub translation: Vec3,
    pub rotation_degrees: Vec3,
    pub scale: Vec3,
}

impl Trs {
    pub fn from_affine(transform: &Affine3A) -> Self {
        let (scale, rotation, translation) = transform.to_scale_rotation_translation();
        let (z, y, x) = rotation.to_euler(EulerRot::ZYX);
        Self {
            translation,
            rotation_degrees: Vec3::new(x, y, z).map(f32::to_degrees),
            scale,
        }
    }

    pub fn to_affine(self) -> Affine3A {
        let r = self.rotation_degrees.map(f32::to_radians);
        Affine3A::from_scale_rotation_translation(
            self.scale,
            Quat::from_euler(EulerRot::ZYX, r.z, r.y, r.x),
            self.translation,
        )
    }
}

/// Undo steps a document keeps (Blender keeps 32 by default, Photoshop 50): an editing
/// session of hours must not hold every state it passed through. The oldest is dropped
/// first.
pub const UNDO_STEPS: usize = 256;

/// `saved_step` of a document whose saved state is no longer in its undo history.
const SAVED_STATE_DROPPED: u64 = u64::MAX;

/// The environment of a new scene: Blender's grey world, enough to see by and no light.
pub const NEW_SCENE_GREY: f32 = 0.05;

/// The scene being edited with the editor's state of it and its undo history.
pub struct Document {
    /// The objects' and lights' names and visibility live in the scene (saved with it).
    scene: Scene,
    /// Images an importer embedded, written beside the scene when it is saved.
    images: Vec<(String, std::sync::Arc<Vec<u8>>)>,
    pub selection: Option<Selection>,
    /// Edited graphs that do not compile, by material, with the compiler's error; the
    /// scene keeps such a material as it last compiled.
    pending_graphs: std::collections::BTreeMap<usize, (Graph, GraphError)>,
    /// The edited world graph when it does not compile, with the error.
    pending_world: Option<(Graph, GraphError)>,
    path: Option<PathBuf>,
    undo: Vec<Step>,
    redo: Vec<Step>,
    open_gesture: Option<GestureId>,
    revision: u64,
    /// The revision of the rendered content (renames do not count).
    image_revision: u64,
    /// The step on top of the undo stack when the document was read or saved (None: the
    /// empty stack): undoing back to it makes the document clean again.
    saved_step: Option<u64>,
    next_step: u64,
}

impl Document {
    /// A document on `scene`, as read from `path` (None: not saved yet). Objects the file
    /// did not name are named after their mesh, with Blender's `.001` suffixes where a
    /// mesh is placed more than once; lights after their kind ("Point", "Sun").
    pub fn new(
        mut scene: Scene,
        path: Option<PathBuf>,
        images: Vec<(String, std::sync::Arc<Vec<u8>>)>,
    ) -> Self {
        name_unnamed(&mut scene);
        Self {
            scene,
            images,
            selection: None,
            pending_graphs: std::collections::BTreeMap::new(),
            pending_world: None,
            path,
            undo: Vec::new(),
            redo: Vec::new(),
            open_gesture: None,
            revision: 0,
            image_revision: 0,
            saved_step: None,
            next_step: 0,
        }
    }

    /// The scene as edited, hidden items included (what is saved).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The scene as rendered: hidden objects and lights left out.
    pub fn render_scene(&self) -> Scene {
        self.scene.without_hidden()
    }

    /// Maps an instance index of [`Document::render_scene`] back to the document's.
    pub fn object_of_rendered_instance(&self, rendered: usize) -> Option<usize> {
        self.scene
            .instances
            .iter()
            .enumerate()
            .filter(|(_, o)| o.visible)
            .nth(rendered)
            .map(|(i, _)| i)
    }

    pub fn objects(&self) -> &[Instance] {
        &self.scene.instances
    }

    pub fn lights(&self) -> &[LightObject] {
        &self.scene.lights
    }

    pub fn images(&self) -> &[(String, std::sync::Arc<Vec<u8>>)] {
        &self.images
    }

    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// The name shown for a selectable item.
    pub fn name(&self, target: Selection) -> &str {
        match target {
            Selection::Object(i) => self.scene.instances.get(i).map_or("", |o| o.name.as_str()),
            Selection::Light(i) => self.scene.lights.get(i).map_or("", |l| l.name.as_str()),
            Selection::Camera => "Camera",
        }
    }

    /// Whether a selectable item is rendered (the camera always is).
    pub fn visible(&self, target: Selection) -> bool {
        match target {
            Selection::Object(i) => self.scene.instances.get(i).is_some_and(|o| o.visible),
            Selection::Light(i) => self.scene.lights.get(i).is_some_and(|l| l.visible),
            Selection::Camera => true,
        }
    }

    /// How many meshes, materials, objects and lights the document holds.
    pub fn counts(&self) -> Counts {
        Counts {
            meshes: self.scene.meshes.len(),
            materials: self.scene.materials.len(),
            objects: self.scene.instances.len(),
            lights: self.scene.lights.len(),
            images: self.images.len(),
        }
    }

    /// A name not yet taken among the objects and lights, from `base` with Blender's
    /// numeric suffixes (`block` → `block.001`, `block.001` → `block.002`).
    pub fn unique_name(&self, base: &str) -> String {
        free_name(base, |n| self.name_taken(n))
    }

    fn name_taken(&self, name: &str) -> bool {
        self.scene.instances.iter().any(|i| i.name == name)
            || self.scene.lights.iter().any(|l| l.name == name)
    }

    /// The command that duplicates `target` (an object or a light) as a new item at the
    /// end, named after it; None for the camera or a missing item. A duplicated object
    /// shares its mesh with the original, as Blender's linked duplicate does.
    pub fn duplicate(&self, target: Selection) -> Option<Command> {
        match target {
            Selection::Object(i) => {
                let original = self.scene.instances.get(i)?;
                Some(Command::InsertObject {
                    object: self.scene.instances.len(),
                    instance: Instance {
                        name: self.unique_name(&original.name),
                        ..original.clone()
                    },
                })
            }
            Selection::Light(i) => {
                let original = self.scene.lights.get(i)?;
                Some(Command::InsertLight {
                    light: self.scene.lights.len(),
                    value: LightObject {
                        name: self.unique_name(&original.name),
                        ..original.clone()
                    },
                })
            }
            Selection::Camera => None,
        }
    }

    /// The command that deletes `target`; None for the camera.
    pub fn delete(&self, target: Selection) -> Option<Command> {
        match target {
            Selection::Object(object) if object < self.scene.instances.len() => {
                Some(Command::DeleteObject { object })
            }
            Selection::Light(light) if light < self.scene.lights.len() => {
                Some(Command::DeleteLight { light })
            }
            _ => None,
        }
    }

    /// The command that appends `scene` (an import, with the images its materials embed)
    /// to the document, its objects and lights named as a newly opened document would
    /// name them, made unique.
    pub fn append(&self, scene: Scene, images: Vec<(String, std::sync::Arc<Vec<u8>>)>) -> Command {
        let mut scene = scene;
        name_unnamed(&mut scene);
        let mut taken = std::collections::HashSet::new();
        let mut unique = |name: &mut String| {
            *name = free_name(name, |n| self.name_taken(n) || taken.contains(n));
            taken.insert(name.clone());
        };
        for instance in &mut scene.instances {
            unique(&mut instance.name);
        }
        for light in &mut scene.lights {
            unique(&mut light.name);
        }
        Command::Append(Box::new(Appended { scene, images }))
    }

    /// The command that adds a new object with `mesh` at `transform`, with a new default
    /// material of its own (Blender gives a new object none; a grey principled material
    /// renders the same and can be edited at once).
    pub fn add_object(&self, mesh: crate::scene::Mesh, transform: Affine3A) -> Command {
        let mut scene = Scene::empty(self.scene.camera);
        let name = mesh.name.clone();
        let mesh = scene.add_mesh(mesh);
        let material = scene.add_material(crate::scene::Material::with(
            &self.unique_material_name("Material"),
            crate::shader::principled::Principled::default(),
        ));
        scene.add_instance(mesh, material, transform);
        scene.instances[0].name = name;
        self.append(scene, Vec::new())
    }

    /// A material name not yet taken, from `base` with Blender's numeric suffixes.
    pub fn unique_material_name(&self, base: &str) -> String {
        free_name(base, |n| self.scene.materials.iter().any(|m| m.name == n))
    }

    /// The command that adds `light` at the end of the lights, named after its kind.
    pub fn add_light(&self, light: Light) -> Command {
        Command::InsertLight {
            light: self.scene.lights.len(),
            value: LightObject {
                name: self.unique_name(light_kind(&light)),
                ..light.into()
            },
        }
    }

    /// The graph of material `material` as edited: a graph that does not compile, the
    /// material's graph, or for a material of fixed parameters the one-node graph holding
    /// them. `None` when there is no such material.
    pub fn material_graph(&self, material: usize) -> Option<Graph> {
        if let Some((graph, _)) = self.pending_graphs.get(&material) {
            return Some(graph.clone());
        }
        let m = self.scene.materials.get(material)?;
        Some(match &m.graph {
            Some(g) => g.graph.clone(),
            None => crate::scene::graph_from_principled(m),
        })
    }

    /// The world's graph as edited: one that does not compile, or the world's; `None`
    /// without a world.
    pub fn world_graph(&self) -> Option<Graph> {
        if let Some((graph, _)) = &self.pending_world {
            return Some(graph.clone());
        }
        Some(self.scene.world.as_ref()?.graph.clone())
    }

    /// Why the edited world graph does not compile, if it does not.
    pub fn world_error(&self) -> Option<&GraphError> {
        self.pending_world.as_ref().map(|(_, e)| e)
    }

    /// Why material `material`'s edited graph does not compile, if it does not.
    pub fn graph_error(&self, material: usize) -> Option<&GraphError> {
        self.pending_graphs.get(&material).map(|(_, e)| e)
    }

    /// The materials whose edited graph does not compile, with why: a saved file holds
    /// the last graph of each that compiled (a file must load), so saving says so.
    pub fn uncompiled_graphs(&self) -> impl Iterator<Item = (usize, &GraphError)> {
        self.pending_graphs.iter().map(|(&m, (_, e))| (m, e))
    }

    /// Bumped by every applied, undone or redone command.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Bumped by every change to what is rendered.
    pub fn image_revision(&self) -> u64 {
        self.image_revision
    }

    /// Whether the document differs from the file it was last read from or saved to.
    pub fn is_dirty(&self) -> bool {
        self.undo.last().map(|s| s.id) != self.saved_step
    }

    /// Records that the document was written to `path`.
    pub fn mark_saved(&mut self, path: PathBuf) {
        self.path = Some(path);
        self.saved_step = self.undo.last().map(|s| s.id);
    }

    /// Marks the document as differing from any file (a recovered autosave): it stays
    /// dirty until saved.
    pub fn mark_unsaved(&mut self) {
        self.saved_step = Some(SAVED_STATE_DROPPED);
    }

    /// Steps in the undo history (at most [`UNDO_STEPS`]).
    pub fn undo_steps(&self) -> usize {
        self.undo.len()
    }

    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// Applies `command` as a new undo step, or, when `gesture` is the gesture of the last
    /// step and still open, as part of that step (one undo reverts the whole drag).
    pub fn apply(
        &mut self,
        command: Command,
        gesture: Option<GestureId>,
    ) -> Result<(), CommandError> {
        let key = command.key();
        let changes_image = command.changes_image();
        let inverse = self.execute(command)?;
        let merge = gesture.is_some()
            && self.open_gesture == gesture
            && self
                .undo
                .last()
                .is_some_and(|s| s.gesture == gesture && s.key == key);
        self.record(vec![inverse], key, gesture, merge, changes_image);
        Ok(())
    }

    /// Records what was just executed: a new undo step of `inverses`, or with `merge` the
    /// gesture's open step (whose first inverse already restores the state before the
    /// gesture) under a new id, since it now holds more than when it may have been saved.
    fn record(
        &mut self,
        inverses: Vec<Command>,
        key: (u8, usize, &'static str),
        gesture: Option<GestureId>,
        merge: bool,
        changes_image: bool,
    ) {
        let id = self.next_step;
        self.next_step += 1;
        match self.undo.last_mut().filter(|_| merge) {
            Some(step) => step.id = id,
            None => {
                self.undo.push(Step {
                    id,
                    inverses,
                    key,
                    gesture,
                });
                if self.undo.len() > UNDO_STEPS {
                    self.drop_oldest_step();
                }
            }
        }
        self.open_gesture = gesture;
        self.redo.clear();
        self.bump(changes_image);
    }

    /// Applies `commands` in order as one undo step (an import staged with its world and
    /// exposure). A command refused undoes those applied before it: the document is left
    /// as it was.
    pub fn apply_all(&mut self, commands: Vec<Command>) -> Result<(), CommandError> {
        let mut inverses = Vec::with_capacity(commands.len());
        let mut changes_image = false;
        for command in commands {
            changes_image |= command.changes_image();
            match self.execute(command) {
                Ok(inverse) => inverses.push(inverse),
                Err(e) => {
                    for inverse in inverses.into_iter().rev() {
                        if let Err(e) = self.execute(inverse) {
                            tracing::error!("a refused batch did not undo: {e}");
                        }
                    }
                    return Err(e);
                }
            }
        }
        // Its own step: a batch never merges.
        self.record(
            inverses,
            (u8::MAX, usize::MAX, ""),
            None,
            false,
            changes_image,
        );
        Ok(())
    }

    /// Whether nothing lights the scene: no lights, no world graph or environment map, an
    /// environment no brighter than a new scene's grey ([`NEW_SCENE_GREY`]) and no
    /// emissive object (an import into it gets the look-dev default).
    pub fn unlit(&self) -> bool {
        let s = &self.scene;
        s.lights.is_empty()
            && s.world.is_none()
            && s.environment.max_element() <= NEW_SCENE_GREY
            && s.environment_map.is_none()
            && !s
                .instances
                .iter()
                .any(|i| s.materials[i.material].is_emissive())
    }

    /// Forgets the oldest undo step. The state below the stack is then the one that step
    /// led to: the saved state if that step was on top when saving, and otherwise a state
    /// undo can no longer reach.
    fn drop_oldest_step(&mut self) {
        let dropped = self.undo.remove(0);
        self.saved_step = match self.saved_step {
            Some(id) if id == dropped.id => None,
            None => Some(SAVED_STATE_DROPPED),
            kept => kept,
        };
    }

    /// Ends the open gesture: the next command starts a new undo step.
    pub fn end_gesture(&mut self) {
        self.open_gesture = None;
    }

    /// Drops the redo history (after undoing something that was never meant to stay, such
    /// as a cancelled transform tool).
    pub fn forget_redo(&mut self) {
        self.redo.clear();
    }

    /// Reverts the last step; false when there is none.
    pub fn undo(&mut self) -> bool {
        self.transfer(true)
    }

    /// Re-applies the last undone step; false when there is none.
    pub fn redo(&mut self) -> bool {
        self.transfer(false)
    }

    fn transfer(&mut self, undo: bool) -> bool {
        self.open_gesture = None;
        let step = if undo {
            self.undo.pop()
        } else {
            self.redo.pop()
        };
        let Some(step) = step else {
            return false;
        };
        let mut inverses = Vec::with_capacity(step.inverses.len());
        let mut changes_image = false;
        for command in step.inverses.into_iter().rev() {
            changes_image |= command.changes_image();
            // A recorded inverse restores a state the document was in, so it is valid.
            match self.execute(command) {
                Ok(inverse) => inverses.push(inverse),
                Err(e) => {
                    tracing::error!("undo history out of step with the document: {e}");
                    return false;
                }
            }
        }
        let step = Step {
            id: step.id,
            inverses,
            key: step.key,
            gesture: None,
        };
        if undo {
            self.redo.push(step);
        } else {
            self.undo.push(step);
        }
        self.bump(changes_image);
        true
    }

    fn bump(&mut self, changes_image: bool) {
        self.revision += 1;
        if changes_image {
            self.image_revision += 1;
        }
    }

    /// Changes the document; returns the command that reverts the change.
    fn execute(&mut self, command: Command) -> Result<Command, CommandError> {
        let err = |m: String| Err(CommandError(m));
        match command {
            Command::SetTransform { object, transform } => {
                let Some(instance) = self.scene.instances.get_mut(object) else {
                    return err(format!("no object {object}"));
                };
                let det = transform.matrix3.determinant();
                if !transform.is_finite() || det == 0.0 || !det.is_finite() {
                    return err(format!(
                        "the transform of \"{}\" must be finite and invertible (no zero scale)",
                        self.scene.instances[object].name
                    ));
                }
                let old = std::mem::replace(&mut instance.transform, transform);
                Ok(Command::SetTransform {
                    object,
                    transform: old,
                })
            }
            Command::SetMaterialParameter {
                material,
                parameter,
                value,
            } => {
                let Some(m) = self.scene.materials.get_mut(material) else {
                    return err(format!("no material {material}"));
                };
                let Some(old) = m.principled.get(parameter) else {
                    return err(format!("no principled parameter \"{parameter}\""));
                };
                let mut changed = m.principled;
                changed
                    .set(parameter, value)
                    .map_err(|e| CommandError(format!("material \"{}\": {e}", m.name)))?;
                changed
                    .validate()
                    .map_err(|e| CommandError(format!("material \"{}\": {e}", m.name)))?;
                m.principled = changed;
                Ok(Command::SetMaterialParameter {
                    material,
                    parameter,
                    value: old,
                })
            }
            Command::SetLight { light, value } => {
                let Some(slot) = self.scene.lights.get_mut(light) else {
                    return err(format!("no light {light}"));
                };
                value
                    .validate()
                    .map_err(|e| CommandError(format!("{}: {e}", slot.name)))?;
                let old = std::mem::replace(&mut slot.light, value);
                Ok(Command::SetLight { light, value: old })
            }
            Command::SetCamera(camera) => {
                camera.validate().map_err(CommandError)?;
                let old = std::mem::replace(&mut self.scene.camera, camera);
                Ok(Command::SetCamera(old))
            }
            Command::Rename { target, name } => {
                let slot = match target {
                    Selection::Object(i) => self.scene.instances.get_mut(i).map(|o| &mut o.name),
                    Selection::Light(i) => self.scene.lights.get_mut(i).map(|l| &mut l.name),
                    Selection::Camera => return err("the camera cannot be renamed".into()),
                };
                let Some(slot) = slot else {
                    return err(format!("nothing to rename at {target:?}"));
                };
                if name.trim().is_empty() {
                    return err("a name cannot be empty".into());
                }
                let old = std::mem::replace(slot, name);
                Ok(Command::Rename { target, name: old })
            }
            Command::EditGraph { material, edit } => self.edit_graph(material, edit),
            Command::AddMaterial {
                index,
                material,
                pending,
            } => {
                if index > self.scene.materials.len() {
                    return err(format!("no material slot {index}"));
                }
                material.validate().map_err(CommandError)?;
                self.scene.materials.insert(index, *material);
                for instance in &mut self.scene.instances {
                    if instance.material >= index {
                        instance.material += 1;
                    }
                }
                self.pending_graphs = std::mem::take(&mut self.pending_graphs)
                    .into_iter()
                    .map(|(i, p)| (if i >= index { i + 1 } else { i }, p))
                    .collect();
                if let Some(pending) = pending {
                    self.pending_graphs.insert(index, *pending);
                }
                Ok(Command::RemoveMaterial { index })
            }
            Command::SetMaterial {
                material,
                value,
                pending,
            } => {
                let Some(slot) = self.scene.materials.get_mut(material) else {
                    return err(format!("no material {material}"));
                };
                value.validate().map_err(CommandError)?;
                let old = std::mem::replace(slot, *value);
                let old_pending = match pending {
                    Some(p) => self.pending_graphs.insert(material, *p),
                    None => self.pending_graphs.remove(&material),
                };
                Ok(Command::SetMaterial {
                    material,
                    value: Box::new(old),
                    pending: old_pending.map(Box::new),
                })
            }
            Command::RemoveMaterial { index } => {
                let Some(m) = self.scene.materials.get(index) else {
                    return err(format!("no material {index}"));
                };
                if let Some(user) = self
                    .scene
                    .instances
                    .iter()
                    .position(|i| i.material == index)
                {
                    return err(format!(
                        "material \"{}\" is used by \"{}\": assign another material first",
                        m.name, self.scene.instances[user].name
                    ));
                }
                let material = self.scene.materials.remove(index);
                for instance in &mut self.scene.instances {
                    if instance.material > index {
                        instance.material -= 1;
                    }
                }
                let pending = self.pending_graphs.remove(&index).map(Box::new);
                self.pending_graphs = std::mem::take(&mut self.pending_graphs)
                    .into_iter()
                    .map(|(i, p)| (if i > index { i - 1 } else { i }, p))
                    .collect();
                Ok(Command::AddMaterial {
                    index,
                    material: Box::new(material),
                    pending,
                })
            }
            Command::RenameMaterial { material, name } => {
                let Some(m) = self.scene.materials.get_mut(material) else {
                    return err(format!("no material {material}"));
                };
                if name.trim().is_empty() {
                    return err("a name cannot be empty".into());
                }
                let old = std::mem::replace(&mut m.name, name);
                Ok(Command::RenameMaterial {
                    material,
                    name: old,
                })
            }
            Command::AssignMaterial { object, material } => {
                if material >= self.scene.materials.len() {
                    return err(format!("no material {material}"));
                }
                let Some(instance) = self.scene.instances.get_mut(object) else {
                    return err(format!("no object {object}"));
                };
                let old = std::mem::replace(&mut instance.material, material);
                Ok(Command::AssignMaterial {
                    object,
                    material: old,
                })
            }
            Command::SetVisible { target, visible } => {
                let slot = match target {
                    Selection::Object(i) => self.scene.instances.get_mut(i).map(|o| &mut o.visible),
                    Selection::Light(i) => self.scene.lights.get_mut(i).map(|l| &mut l.visible),
                    Selection::Camera => return err("the camera cannot be hidden".into()),
                };
                let Some(slot) = slot else {
                    return err(format!("nothing to hide at {target:?}"));
                };
                let old = std::mem::replace(slot, visible);
                Ok(Command::SetVisible {
                    target,
                    visible: old,
                })
            }
            Command::DeleteObject { object } => {
                if object >= self.scene.instances.len() {
                    return err(format!("no object {object}"));
                }
                self.selection = shifted_selection(self.selection, Selection::Object(object));
                Ok(Command::InsertObject {
                    object,
                    instance: self.scene.instances.remove(object),
                })
            }
            Command::InsertObject { object, instance } => {
                if object > self.scene.instances.len() {
                    return err(format!("cannot insert an object at {object}"));
                }
                if instance.mesh >= self.scene.meshes.len()
                    || instance.material >= self.scene.materials.len()
                {
                    return err(format!(
                        "\"{}\" refers to a mesh or material the scene lacks",
                        instance.name
                    ));
                }
                self.scene.instances.insert(object, instance);
                self.selection = Some(Selection::Object(object));
                Ok(Command::DeleteObject { object })
            }
            Command::DeleteLight { light } => {
                if light >= self.scene.lights.len() {
                    return err(format!("no light {light}"));
                }
                self.selection = shifted_selection(self.selection, Selection::Light(light));
                Ok(Command::InsertLight {
                    light,
                    value: self.scene.lights.remove(light),
                })
            }
            Command::InsertLight { light, value } => {
                if light > self.scene.lights.len() {
                    return err(format!("cannot insert a light at {light}"));
                }
                value
                    .light
                    .validate()
                    .map_err(|e| CommandError(format!("{}: {e}", value.name)))?;
                self.scene.lights.insert(light, value);
                self.selection = Some(Selection::Light(light));
                Ok(Command::DeleteLight { light })
            }
            Command::SetSettings(settings) => {
                settings.validate().map_err(CommandError)?;
                let old = std::mem::replace(&mut self.scene.settings, settings);
                Ok(Command::SetSettings(old))
            }
            Command::SetView(view) => {
                view.validate().map_err(CommandError)?;
                let old = std::mem::replace(&mut self.scene.settings.view, view);
                Ok(Command::SetView(old))
            }
            Command::SetEnvironmentColor(color) => {
                if !color.is_finite() || color.min_element() < 0.0 {
                    return err(format!(
                        "the environment colour must be finite and non-negative, not {color}"
                    ));
                }
                let old = std::mem::replace(&mut self.scene.environment, color);
                Ok(Command::SetEnvironmentColor(old))
            }
            Command::SetEnvironmentMapParams {
                strength,
                rotation_degrees,
            } => {
                let Some(map) = self.scene.environment_map.as_mut() else {
                    return err("the scene has no environment map".into());
                };
                if !strength.is_finite() || strength < 0.0 || !rotation_degrees.is_finite() {
                    return err(format!(
                        "the environment map's strength must be finite and non-negative and its rotation finite (strength {strength}, rotation {rotation_degrees})"
                    ));
                }
                let old = Command::SetEnvironmentMapParams {
                    strength: map.strength,
                    rotation_degrees: map.rotation_degrees,
                };
                map.strength = strength;
                map.rotation_degrees = rotation_degrees;
                Ok(old)
            }
            Command::SetEnvironmentMap(map) => {
                if let Some(map) = &map {
                    map.validate().map_err(CommandError)?;
                }
                let old = std::mem::replace(&mut self.scene.environment_map, map.map(|m| *m));
                Ok(Command::SetEnvironmentMap(old.map(Box::new)))
            }
            Command::SetWorld(world) => {
                if let Some(world) = &world {
                    world.validate().map_err(CommandError)?;
                    world
                        .suns()
                        .map_err(|e| CommandError(format!("the world: {e}")))?;
                }
                let old = std::mem::replace(&mut self.scene.world, world.map(|w| *w));
                self.pending_world = None;
                Ok(Command::SetWorld(old.map(Box::new)))
            }
            Command::EditWorldGraph(edit) => self.edit_world_graph(edit),
            Command::Append(appended) => {
                let Appended { mut scene, images } = *appended;
                scene.validate().map_err(CommandError)?;
                let before = self.counts();
                let (mesh_base, material_base) = (before.meshes, before.materials);
                for material in &mut scene.materials {
                    renumber_embedded_images(material, |i| i + before.images);
                }
                self.images.extend(images);
                self.scene.meshes.extend(scene.meshes);
                self.scene.materials.extend(scene.materials);
                self.scene
                    .instances
                    .extend(scene.instances.into_iter().map(|i| Instance {
                        mesh: i.mesh + mesh_base,
                        material: i.material + material_base,
                        ..i
                    }));
                self.scene.lights.extend(scene.lights);
                Ok(Command::Truncate(before))
            }
            Command::Truncate(counts) => {
                let now = self.counts();
                if counts.meshes > now.meshes
                    || counts.materials > now.materials
                    || counts.objects > now.objects
                    || counts.lights > now.lights
                    || counts.images > now.images
                {
                    return err(format!(
                        "cannot truncate the document to {counts:?}: it holds {now:?}"
                    ));
                }
                let kept = &self.scene.instances[..counts.objects];
                if kept
                    .iter()
                    .any(|i| i.mesh >= counts.meshes || i.material >= counts.materials)
                {
                    return err("a kept object uses a mesh or material that would go".into());
                }
                let mut removed = Scene::empty(self.scene.camera);
                removed.meshes = self.scene.meshes.split_off(counts.meshes);
                removed.materials = self.scene.materials.split_off(counts.materials);
                // Edited graphs of the removed materials go with them.
                self.pending_graphs.retain(|&m, _| m < counts.materials);
                removed.instances = self
                    .scene
                    .instances
                    .split_off(counts.objects)
                    .into_iter()
                    .map(|i| Instance {
                        mesh: i.mesh - counts.meshes.min(i.mesh),
                        material: i.material - counts.materials.min(i.material),
                        ..i
                    })
                    .collect();
                removed.lights = self.scene.lights.split_off(counts.lights);
                let images = self.images.split_off(counts.images);
                for material in &mut removed.materials {
                    renumber_embedded_images(material, |i| i.saturating_sub(counts.images));
                }
                if matches!(self.selection, Some(Selection::Object(i)) if i >= counts.objects)
                    || matches!(self.selection, Some(Selection::Light(i)) if i >= counts.lights)
                {
                    self.selection = None;
                }
                Ok(Command::Append(Box::new(Appended {
                    scene: removed,
                    images,
                })))
            }
        }
    }
}

/// The selection after `removed` is taken out of its list: cleared when it was the
/// selection, moved down one when it came after it in the same list.
fn shifted_selection(selection: Option<Selection>, removed: Selection) -> Option<Selection> {
    match (selection, removed) {
        (Some(s), r) if s == r => None,
        (Some(Selection::Object(i)), Selection::Object(r)) if i > r => {
            Some(Selection::Object(i - 1))
        }
        (Some(Selection::Light(i)), Selection::Light(r)) if i > r => Some(Selection::Light(i - 1)),
        (s, _) => s,
    }
}

impl Document {
    /// Applies a graph edit to material `material`'s edited graph and recompiles it: a
    /// graph that compiles replaces the material; one that does not is kept with its
    /// error beside the material as it last compiled.
    fn edit_world_graph(&mut self, edit: GraphEdit) -> Result<Command, CommandError> {
        let (Some(mut graph), Some(world)) = (self.world_graph(), self.scene.world.as_ref()) else {
            return Err(CommandError("the scene has no world graph".into()));
        };
        let inverse = edit
            .apply(&mut graph)
            .map_err(|e| CommandError(format!("the world: {e}")))?;
        // Images the world already holds are reused rather than read again.
        let known = world.images.clone();
        let load = |file: &str| match known.get(file) {
            Some(image) => Ok((**image).clone()),
            None => load_texture(Path::new(file)),
        };
        let resolution = world.resolution;
        match World::from_graph_with(graph.clone(), &load) {
            Ok(mut compiled) => {
                compiled.resolution = resolution;
                self.scene.world = Some(compiled);
                self.pending_world = None;
            }
            Err(error) => self.pending_world = Some((graph, error)),
        }
        Ok(Command::EditWorldGraph(inverse))
    }

    fn edit_graph(&mut self, material: usize, edit: GraphEdit) -> Result<Command, CommandError> {
        let Some(mut graph) = self.material_graph(material) else {
            return Err(CommandError(format!("no material {material}")));
        };
        let name = self.scene.materials[material].name.clone();
        // A material of fixed parameters becomes a graph material with its first graph
        // edit; undoing that edit gives back the material it was.
        let before = self.scene.materials[material]
            .graph
            .is_none()
            .then(|| Box::new(self.scene.materials[material].clone()));
        let inverse = edit
            .apply(&mut graph)
            .map_err(|e| CommandError(format!("material \"{name}\": {e}")))?;
        // Images the material already holds (an importer's embedded ones among them) are
        // reused rather than read again.
        let known = self.scene.materials[material]
            .graph
            .as_ref()
            .map(|g| g.images.clone())
            .unwrap_or_default();
        let load = |file: &str| match known.get(file) {
            Some(image) => Ok((**image).clone()),
            None => load_texture(Path::new(file)),
        };
        match Material::from_graph_with(&name, graph.clone(), &load) {
            Ok(compiled) => {
                self.scene.materials[material] = compiled;
                self.pending_graphs.remove(&material);
            }
            Err(error) => {
                self.pending_graphs.insert(material, (graph, error));
            }
        }
        Ok(match before {
            Some(value) => Command::SetMaterial {
                material,
                value,
                pending: None,
            },
            None => Command::EditGraph {
                material,
                edit: inverse,
            },
        })
    }
}

/// Names the objects and lights `scene` left unnamed: objects after their mesh, lights
/// after their kind ("Point", "Sun"), made unique with Blender's `.001` suffixes.
fn name_unnamed(scene: &mut Scene) {
    let mut taken: std::collections::HashSet<String> = (scene.instances.iter())
        .map(|i| i.name.clone())
        .chain(scene.lights.iter().map(|l| l.name.clone()))
        .collect();
    let mut name_after = |base: &str| {
        let name = free_name(base, |n| taken.contains(n));
        taken.insert(name.clone());
        name
    };
    for i in 0..scene.instances.len() {
        if scene.instances[i].name.is_empty() {
            let base = &scene.meshes[scene.instances[i].mesh].name;
            let base = if base.is_empty() { "object" } else { base };
            scene.instances[i].name = name_after(base);
        }
    }
    for light in &mut scene.lights {
        if light.name.is_empty() {
            light.name = name_after(light_kind(&light.light));
        }
    }
}

/// `base` if `taken` does not hold it, otherwise the first of its stem and the stem's
/// Blender suffixes (`block.001` → `block`, `block.001`, `block.002`, …) that it does not
/// hold: the one rule for naming objects, lights and materials.
fn free_name(base: &str, taken: impl Fn(&str) -> bool) -> String {
    if !taken(base) {
        return base.to_owned();
    }
    let stem = match base.rsplit_once('.') {
        Some((stem, digits)) if digits.len() == 3 && digits.bytes().all(|b| b.is_ascii_digit()) => {
            stem
        }
        _ => base,
    };
    std::iter::once(stem.to_owned())
        .chain((1..).map(|i| format!("{stem}.{i:03}")))
        .find(|n| !taken(n))
        .expect("some suffix is free")
}

/// Renumbers the embedded images (`image:N`) a material's graph reads, and the decoded
/// images it holds for them, by `renumber`: an import's images keep their own numbering
/// until they join a document's.
fn renumber_embedded_images(material: &mut Material, renumber: impl Fn(usize) -> usize) {
    let Some(graph) = material.graph.as_mut() else {
        return;
    };
    let renamed = |file: &str| {
        let n = file.strip_prefix("image:")?.parse::<usize>().ok()?;
        Some(format!("image:{}", renumber(n)))
    };
    let graph = std::sync::Arc::make_mut(graph);
    for file in graph.graph.image_files_mut() {
        if let Some(new) = renamed(file) {
            *file = new;
        }
    }
    graph.images = std::mem::take(&mut graph.images)
        .into_iter()
        .map(|(file, image)| (renamed(&file).unwrap_or(file), image))
        .collect();
}

/// A light's kind in a word, for names and headings.
pub fn light_kind(light: &Light) -> &'static str {
    match light {
        Light::Point { .. } => "Point",
        Light::Spot { .. } => "Spot",
        Light::Distant { .. } => "Sun",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn document() -> Document {
        let scene = crate::scene::default_scene().expect("the bundled scene loads");
        Document::new(scene, None, Vec::new())
    }

    fn moved(doc: &Document, object: usize, x: f32) -> Command {
        let mut trs = Trs::from_affine(&doc.scene().instances[object].transform);
        trs.translation.x = x;
        Command::SetTransform {
            object,
            transform: trs.to_affine(),
        }
    }

    #[test]
    fn repeated_meshes_get_blender_suffixes() {
        let doc = document();
        let names: Vec<&str> = doc
            .scene()
            .instances
            .iter()
            .map(|o| o.name.as_str())
            .collect();
        assert!(
            names.contains(&"block") && names.contains(&"block.001"),
            "{names:?}"
        );
    }

    #[test]
    fn undo_restores_and_redo_reapplies_a_transform() {
        let mut doc = document();
        let before = doc.scene().instances[6].transform;
        doc.apply(moved(&doc, 6, 10.0), None).unwrap();
        let after = doc.scene().instances[6].transform;
        assert!((after.translation.x - 10.0).abs() < 1e-4);
        assert!(doc.is_dirty());
        assert!(doc.undo());
        assert_eq!(doc.scene().instances[6].transform, before);
        assert!(!doc.is_dirty(), "undone back to the file's state");
        assert!(doc.redo());
        assert!(doc.is_dirty());
        assert_eq!(doc.scene().instances[6].transform, after);
        assert!(!doc.redo(), "nothing left to redo");
    }

    #[test]
    fn the_undo_history_keeps_its_last_steps_and_knows_the_saved_state_is_gone() {
        let mut doc = document();
        let start = doc.scene().instances[6].transform;
        let edits = UNDO_STEPS + 10;
        for step in 1..=edits {
            doc.apply(moved(&doc, 6, step as f32), None).unwrap();
        }
        let mut undone = 0;
        while doc.undo() {
            undone += 1;
        }
        assert_eq!(undone, UNDO_STEPS);
        let oldest_kept = doc.scene().instances[6].transform.translation.x;
        assert_eq!(oldest_kept, (edits - UNDO_STEPS) as f32);
        assert_ne!(doc.scene().instances[6].transform, start);
        assert!(
            doc.is_dirty(),
            "the file's state was dropped from the history, so no undo reaches it"
        );

        // Saved after the first edit: clean again only where that state is.
        let mut doc = document();
        doc.apply(moved(&doc, 6, 1.0), None).unwrap();
        doc.mark_saved(PathBuf::from("saved.kiln"));
        for step in 2..=UNDO_STEPS + 1 {
            doc.apply(moved(&doc, 6, step as f32), None).unwrap();
        }
        while doc.undo() {}
        assert_eq!(doc.scene().instances[6].transform.translation.x, 1.0);
        assert!(!doc.is_dirty(), "back at the saved state below the history");
    }

    #[test]
    fn a_drag_is_one_undo_step_and_a_new_gesture_is_another() {
        let mut doc = document();
        let start = doc.scene().instances[6].transform;
        for x in [1.0, 2.0, 3.0] {
            doc.apply(moved(&doc, 6, x), Some(7)).unwrap();
        }
        doc.end_gesture();
        let after_first = doc.scene().instances[6].transform;
        doc.apply(moved(&doc, 6, 4.0), Some(7)).unwrap();
        assert!(doc.undo());
        assert_eq!(doc.scene().instances[6].transform, after_first);
        assert!(doc.undo());
        assert_eq!(doc.scene().instances[6].transform, start);
        assert!(!doc.can_undo());
    }

    #[test]
    fn an_invalid_edit_is_refused_and_changes_nothing() {
        let mut doc = document();
        let revision = doc.revision();
        let zero_scale = Command::SetTransform {
            object: 0,
            transform: Affine3A::from_scale(Vec3::ZERO),
        };
        assert!(doc.apply(zero_scale, None).is_err());
        let bad_ior = Command::SetMaterialParameter {
            material: 0,
            parameter: "ior",
            value: ParamValue::Float(0.5),
        };
        assert!(doc.apply(bad_ior, None).is_err());
        assert_eq!(doc.revision(), revision);
        assert!(!doc.can_undo() && !doc.is_dirty());
    }

    #[test]
    fn hidden_objects_are_saved_but_not_rendered() {
        let mut doc = document();
        let target = Selection::Object(6);
        doc.apply(
            Command::SetVisible {
                target,
                visible: false,
            },
            None,
        )
        .unwrap();
        assert_eq!(doc.scene().instances.len(), 8);
        assert_eq!(doc.render_scene().instances.len(), 7);
        assert_eq!(doc.object_of_rendered_instance(6), Some(7));
    }

    #[test]
    fn a_rename_marks_the_document_dirty_but_keeps_the_image() {
        let mut doc = document();
        let image = doc.image_revision();
        doc.apply(
            Command::Rename {
                target: Selection::Object(0),
                name: "ground".into(),
            },
            None,
        )
        .unwrap();
        assert_eq!(doc.name(Selection::Object(0)), "ground");
        assert!(doc.is_dirty());
        assert_eq!(doc.image_revision(), image);
    }

    #[test]
    fn delete_and_duplicate_undo_to_the_same_scene() {
        let mut doc = document();
        let (scene, names) = (doc.scene().clone(), doc.objects().to_vec());
        doc.selection = Some(Selection::Object(7));
        doc.apply(doc.delete(Selection::Object(6)).unwrap(), None)
            .unwrap();
        assert_eq!(doc.scene().instances.len(), 7);
        assert_eq!(
            doc.selection,
            Some(Selection::Object(6)),
            "the selection follows its object down"
        );
        let copy = doc.duplicate(Selection::Object(0)).unwrap();
        doc.apply(copy, None).unwrap();
        let last = doc.objects().len() - 1;
        assert_eq!(
            doc.scene().instances[last].mesh,
            doc.scene().instances[0].mesh,
            "a duplicate shares its mesh"
        );
        assert_ne!(doc.objects()[last].name, doc.objects()[0].name);
        let light = doc.duplicate(Selection::Light(0));
        assert!(light.is_none() || doc.apply(light.unwrap(), None).is_ok());
        while doc.undo() {}
        assert_eq!(doc.scene(), &scene);
        assert_eq!(doc.objects(), names);
        assert!(!doc.is_dirty());
    }

    #[test]
    fn unique_names_take_the_next_free_suffix() {
        let doc = document();
        assert_eq!(doc.unique_name("block"), "block.002");
        assert_eq!(doc.unique_name("block.001"), "block.002");
        assert_eq!(doc.unique_name("teapot"), "teapot");
    }

    #[test]
    fn an_append_adds_after_the_document_and_undoes_to_it() {
        let mut doc = document();
        let before = doc.scene().clone();
        let other = crate::scene::default_scene().unwrap();
        let added = other.instances.len();
        doc.apply(doc.append(other.clone(), Vec::new()), None)
            .unwrap();
        let scene = doc.scene();
        assert_eq!(scene.instances.len(), before.instances.len() + added);
        let first = &scene.instances[before.instances.len()];
        assert_eq!(first.mesh, before.meshes.len() + other.instances[0].mesh);
        assert_eq!(
            first.material,
            before.materials.len() + other.instances[0].material
        );
        let names: std::collections::HashSet<&str> = doc
            .scene()
            .instances
            .iter()
            .map(|o| o.name.as_str())
            .collect();
        assert_eq!(names.len(), doc.objects().len(), "names stay unique");
        assert!(doc.undo());
        assert_eq!(doc.scene(), &before);
        assert!(doc.redo());
        assert_eq!(doc.scene().instances.len(), before.instances.len() + added);
    }

    #[test]
    fn a_batch_is_one_undo_step_and_a_refused_one_changes_nothing() {
        let mut doc = document();
        let before = doc.scene().clone();
        let bad = Command::SetEnvironmentColor(Vec3::new(-1.0, 0.0, 0.0));
        let refused = doc.apply_all(vec![
            Command::SetEnvironmentColor(Vec3::splat(0.5)),
            Command::SetWorld(Some(Box::new(crate::scene::lookdev::world()))),
            bad,
        ]);
        assert!(refused.is_err());
        assert_eq!(*doc.scene(), before);
        assert!(!doc.undo(), "a refused batch leaves no step");
        doc.apply_all(vec![
            Command::SetEnvironmentColor(Vec3::splat(0.5)),
            Command::SetWorld(Some(Box::new(crate::scene::lookdev::world()))),
        ])
        .unwrap();
        assert!(doc.scene().world.is_some());
        assert!(doc.undo());
        assert_eq!(*doc.scene(), before, "one undo takes the whole batch back");
        assert!(doc.redo());
        assert_eq!(doc.scene().environment, Vec3::splat(0.5));
    }

    #[test]
    fn settings_and_environment_edits_are_checked_and_undone() {
        let mut doc = document();
        let mut settings = doc.scene().settings;
        settings.width = 0;
        assert!(doc.apply(Command::SetSettings(settings), None).is_err());
        settings.width = 1920;
        doc.apply(Command::SetSettings(settings), None).unwrap();
        assert_eq!(doc.scene().settings.width, 1920);
        let bad = Command::SetEnvironmentColor(Vec3::new(-1.0, 0.0, 0.0));
        assert!(doc.apply(bad, None).is_err());
        doc.apply(Command::SetEnvironmentColor(Vec3::splat(0.5)), None)
            .unwrap();
        assert!(
            doc.apply(
                Command::SetEnvironmentMapParams {
                    strength: 1.0,
                    rotation_degrees: 0.0
                },
                None
            )
            .is_err(),
            "the Cornell box has no map"
        );
        let material = doc.scene().instances[0].material;
        let other = (material + 1) % doc.scene().materials.len();
        doc.apply(
            Command::AssignMaterial {
                object: 0,
                material: other,
            },
            None,
        )
        .unwrap();
        assert!(
            doc.apply(
                Command::AssignMaterial {
                    object: 0,
                    material: 999
                },
                None
            )
            .is_err()
        );
        while doc.undo() {}
        assert_eq!(doc.scene(), &document().scene().clone());
    }

    #[test]
    fn trs_round_trips_the_scene_files_rotation_order() {
        let trs = Trs {
            translation: Vec3::new(1.0, 2.0, 3.0),
            rotation_degrees: Vec3::new(10.0, -16.6, 30.0),
            scale: Vec3::new(2.0, 3.0, 4.0),
        };
        let back = Trs::from_affine(&trs.to_affine());
        assert!((back.translation - trs.translation).abs().max_element() < 1e-4);
        assert!(
            (back.rotation_degrees - trs.rotation_degrees)
                .abs()
                .max_element()
                < 1e-3
        );
        assert!((back.scale - trs.scale).abs().max_element() < 1e-4);
    }

    #[test]
    fn a_graph_edit_that_does_not_compile_keeps_the_last_material_and_undo_restores_it() {
        let mut doc = document();
        let before = doc.scene().materials[0].clone();
        let start = doc.material_graph(0).unwrap();
        // Removing the surface leaves the output without a shader: still compiles (the
        // default surface); removing the output does not.
        let output = start
            .nodes
            .iter()
            .find(|(_, n)| n.kind == "material_output")
            .map(|(id, _)| id.clone())
            .unwrap();
        doc.apply(
            Command::EditGraph {
                material: 0,
                edit: GraphEdit::RemoveNode { id: output },
            },
            None,
        )
        .unwrap();
        let error = doc.graph_error(0).expect("no output is a compile error");
        assert!(!error.message.is_empty());
        let uncompiled: Vec<usize> = doc.uncompiled_graphs().map(|(m, _)| m).collect();
        assert_eq!(uncompiled, [0], "saving warns about this material");
        assert_eq!(
            doc.scene().materials[0],
            before,
            "the last valid material renders"
        );
        assert_ne!(
            doc.material_graph(0).unwrap(),
            start,
            "the edited graph is kept"
        );
        assert!(doc.undo());
        assert!(doc.graph_error(0).is_none());
        assert_eq!(doc.uncompiled_graphs().count(), 0);
        assert_eq!(doc.material_graph(0).unwrap(), start);
        assert_eq!(doc.scene().materials[0], before);
    }

    #[test]
    fn materials_are_added_assigned_renamed_and_removed_with_undo() {
        let mut doc = document();
        let count = doc.scene().materials.len();
        let used = doc.scene().instances[6].material;
        doc.apply(
            Command::AddMaterial {
                index: 0,
                material: Box::new(Material::diffuse("new", Vec3::ONE)),
                pending: None,
            },
            None,
        )
        .unwrap();
        assert_eq!(doc.scene().materials[0].name, "new");
        assert_eq!(
            doc.scene().instances[6].material,
            used + 1,
            "objects keep their material when one is inserted before it"
        );
        let err = doc
            .apply(Command::RemoveMaterial { index: used + 1 }, None)
            .unwrap_err();
        assert!(err.0.contains("used by"), "{err}");
        doc.apply(
            Command::AssignMaterial {
                object: 6,
                material: 0,
            },
            None,
        )
        .unwrap();
        doc.apply(
            Command::RenameMaterial {
                material: 0,
                name: "renamed".into(),
            },
            None,
        )
        .unwrap();
        assert_eq!(doc.scene().materials[0].name, "renamed");
        assert_eq!(doc.scene().instances[6].material, 0);
        while doc.undo() {}
        assert_eq!(doc.scene().materials.len(), count);
        assert_eq!(doc.scene().instances[6].material, used);
        assert!(!doc.is_dirty());
    }
}
