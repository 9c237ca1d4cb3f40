//! One import, start to end: read and check the document, load its buffers, walk the
//! scene and hand the host each (mesh, primitive) once, each material once per variant,
//! and an instance per node that uses them.
//!
//! What cannot be represented is reported through `Builder::warn` and skipped; only a
//! file that cannot be read at all (unparseable, a missing buffer, a required extension
//! this importer lacks) fails the import.

use std::collections::HashMap;
use std::path::Path;

use glam::Mat4;
use gltf::json;
use kiln_plugin_api::{Builder, Mesh};

use crate::buffers::Buffers;
use crate::geometry::{self, primitive_name};
use crate::images::{HostImages, ImageCache, NamedImages};
use crate::material::{self, Variant};
use crate::{document, extensions, scene, validate};

/// Vertices and triangles one import hands over (the host's limits).
const MAX_VERTICES: usize = 1 << 26;
const MAX_TRIANGLES: usize = 1 << 26;
/// Schema problems listed in the one warning that reports them.
const PROBLEMS_LISTED: usize = 5;

/// Imports the glTF or GLB file at `path` into `builder`.
pub fn import(path: &Path, builder: &mut Builder) -> Result<(), String> {
    let mut doc = document::read(path)?;
    let mut warnings = Vec::new();
    let problems = document::schema_problems(&mut doc.root);
    if !problems.is_empty() {
        let mut listed = problems[..problems.len().min(PROBLEMS_LISTED)].join("; ");
        if problems.len() > PROBLEMS_LISTED {
            listed.push_str(&format!("; and {} more", problems.len() - PROBLEMS_LISTED));
        }
        warnings.push(format!(
            "the file does not follow the glTF 2.0 schema ({listed}); what can be read is imported"
        ));
    }
    extensions::check(&doc.root, &mut warnings)?;
    if doc.animations > 0 {
        warnings.push(format!(
            "animations are not imported ({} in the file); the scene is shown at rest",
            doc.animations
        ));
    }
    for w in warnings.drain(..) {
        builder.warn(&w);
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = Buffers::load(&doc.root, base, doc.blob.take())?;
    for w in validate::check(&doc, &buffers, base) {
        builder.warn(&w);
    }
    let mut import = SceneImport {
        root: &doc.root,
        buffers: &buffers,
        base,
        builder,
        meshes: HashMap::new(),
        materials: HashMap::new(),
        images: ImageCache::default(),
        vertices: 0,
        triangles: 0,
        camera_set: false,
        counts: Counts::default(),
    };
    import.run();
    Ok(())
}

/// Things reported once per import, with how often they happened.
#[derive(Default)]
struct Counts {
    extra_cameras: usize,
    skinned_nodes: usize,
    morphed_meshes: usize,
    bad_transforms: usize,
}

struct SceneImport<'a, 'b> {
    root: &'a json::Root,
    buffers: &'a Buffers,
    base: &'a Path,
    builder: &'a mut Builder<'b>,
    /// Host mesh id (None: skipped) and whether it has vertex colours, by (mesh, primitive).
    meshes: HashMap<(usize, usize), Option<(u32, bool)>>,
    /// Host material id by (glTF material, vertex colours); `u32::MAX` for the default.
    materials: HashMap<(Option<usize>, bool), u32>,
    images: ImageCache,
    vertices: usize,
    triangles: usize,
    camera_set: bool,
    counts: Counts,
}

impl SceneImport<'_, '_> {
    fn run(&mut self) {
        let root = self.root;
        let mut warnings = Vec::new();
        let roots = scene::root_nodes(root, &mut warnings);
        let mut morphed = vec![false; root.meshes.len()];
        scene::walk(root, &roots, &mut warnings, |node, world| {
            self.visit(node, world, &mut morphed);
        });
        self.counts.morphed_meshes = morphed.iter().filter(|&&m| m).count();
        let c = &self.counts;
        if c.extra_cameras > 0 {
            warnings.push(format!(
                "{} more camera(s) ignored: Kiln renders through the first perspective camera",
                c.extra_cameras
            ));
        }
        if c.skinned_nodes > 0 {
            warnings.push(format!(
                "skinning is not supported: {} skinned node(s) shown in their bind pose",
                c.skinned_nodes
            ));
        }
        if c.morphed_meshes > 0 {
            warnings.push(format!(
                "morph targets are not supported: {} mesh(es) shown in their base shape",
                c.morphed_meshes
            ));
        }
        if c.bad_transforms > 0 {
            warnings.push(format!(
                "{} node(s) with a non-finite transform skipped",
                c.bad_transforms
            ));
        }
        for w in warnings {
            self.builder.warn(&w);
        }
    }

    fn visit(&mut self, index: usize, world: &Mat4, morphed: &mut [bool]) {
        let root = self.root;
        let node = &root.nodes[index];
        if !world.is_finite() {
            self.counts.bad_transforms += 1;
            return;
        }
        if let Some(m) = node.mesh.map(|m| m.value()) {
            match root.meshes.get(m) {
                None => self
                    .builder
                    .warn(&format!("node {index}: mesh {m} does not exist")),
                Some(mesh) => {
                    if node.skin.is_some() {
                        self.counts.skinned_nodes += 1;
                    }
                    if mesh
                        .primitives
                        .iter()
                        .any(|p| p.targets.as_ref().is_some_and(|t| !t.is_empty()))
                    {
                        morphed[m] = true;
                    }
                    for p in 0..mesh.primitives.len() {
                        self.instance(m, p, world);
                    }
                }
            }
        }
        if let Some(c) = node.camera.map(|c| c.value()) {
            if self.camera_set {
                self.counts.extra_cameras += 1;
            } else {
                match scene::camera(root, c, world) {
                    Ok(camera) => {
                        self.builder.set_camera(&camera);
                        self.camera_set = true;
                    }
                    Err(e) => self.builder.warn(&format!("node {index}: {e}; ignored")),
                }
            }
        }
        let light = node
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref());
        if let Some(l) = light {
            match scene::light(root, l.light.value(), world) {
                Ok(light) => {
                    self.builder.add_light(&light);
                }
                Err(e) => self.builder.warn(&format!("node {index}: {e}; ignored")),
            }
        }
    }

    fn instance(&mut self, m: usize, p: usize, world: &Mat4) {
        let Some((mesh, vertex_colors)) = self.mesh(m, p) else {
            return;
        };
        let primitive = &self.root.meshes[m].primitives[p];
        let material = self.material(primitive.material.map(|i| i.value()), vertex_colors);
        self.builder
            .add_instance(mesh, material, world.to_cols_array());
    }

    /// The host id of primitive `p` of mesh `m`, added on first use.
    fn mesh(&mut self, m: usize, p: usize) -> Option<(u32, bool)> {
        if let Some(id) = self.meshes.get(&(m, p)) {
            return *id;
        }
        let name = primitive_name(self.root, m, p);
        let mut warnings = Vec::new();
        let id = match geometry::read_primitive(self.root, self.buffers, m, p, &mut warnings) {
            Err(e) => {
                warnings.push(format!("skipped: {e}"));
                None
            }
            Ok(t)
                if self.vertices + t.positions.len() > MAX_VERTICES
                    || self.triangles + t.indices.len() / 3 > MAX_TRIANGLES =>
            {
                warnings.push(format!(
                    "skipped: the import would exceed {MAX_VERTICES} vertices or {MAX_TRIANGLES} triangles"
                ));
                None
            }
            Ok(t) => {
                let mesh = Mesh {
                    name: &name,
                    positions: &t.positions,
                    normals: &t.normals,
                    uvs: &t.uvs,
                    uvs1: &t.uvs1,
                    tangents: &t.tangents,
                    colors: &t.colors,
                    indices: &t.indices,
                };
                let id = self.builder.add_mesh(&mesh);
                if id.is_some() {
                    self.vertices += t.positions.len();
                    self.triangles += t.indices.len() / 3;
                }
                id.map(|id| (id, !t.colors.is_empty()))
            }
        };
        for w in warnings {
            self.builder.warn(&format!("primitive \"{name}\": {w}"));
        }
        self.meshes.insert((m, p), id);
        id
    }

    /// The host id of glTF material `index` (None: none), `u32::MAX` for the host's grey.
    fn material(&mut self, index: Option<usize>, vertex_colors: bool) -> u32 {
        let index = match index {
            Some(i) if i >= self.root.materials.len() => {
                if !self.materials.contains_key(&(Some(i), vertex_colors)) {
                    self.builder
                        .warn(&format!("material {i} does not exist; the default is used"));
                    self.materials.insert((Some(i), vertex_colors), u32::MAX);
                }
                None
            }
            i => i,
        };
        if index.is_none() && !vertex_colors {
            return u32::MAX;
        }
        if let Some(&id) = self.materials.get(&(index, vertex_colors)) {
            return id;
        }
        let variant = Variant {
            vertex_colors,
            textures: true,
        };
        let (text, warnings) = {
            let mut images = HostImages {
                root: self.root,
                buffers: self.buffers,
                base: self.base,
                builder: &mut *self.builder,
                cache: &mut self.images,
            };
            material::translate(self.root, index, variant, &mut images)
        };
        for w in &warnings {
            self.builder.warn(w);
        }
        let mut id = self.builder.add_material(&text.name, &text.kmat);
        if id.is_none() && text.kmat.contains("image_texture") {
            let plain = Variant {
                textures: false,
                ..variant
            };
            let (text, _) = material::translate(self.root, index, plain, &mut NamedImages);
            id = self.builder.add_material(&text.name, &text.kmat);
            if id.is_some() {
                self.builder.warn(&format!(
                    "material \"{}\": the host could not use its textures; imported without them",
                    text.name
                ));
            }
        }
        let id = id.unwrap_or_else(|| {
            self.builder.warn(&format!(
                "material \"{}\" was refused; the default grey is used",
                text.name
            ));
            u32::MAX
        });
        self.materials.insert((index, vertex_colors), id);
        id
    }
}
