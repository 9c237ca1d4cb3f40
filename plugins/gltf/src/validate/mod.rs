//! Checks of a file against the rules of glTF 2.0 (and of the extensions this importer
//! knows) that parsing does not enforce, so that a broken file is never imported in
//! silence. They follow the Khronos glTF-Validator's errors, whose codes the comments
//! name: what the validator calls an error is reported here as a warning that says which
//! object is wrong and how; what it calls a warning or a hint is not reported.
//!
//! Nothing here changes what is imported: the readers are bounds-checked on their own and
//! the checks only read. They are bounded: accessor values are scanned up to
//! [`MAX_ELEMENTS_SCANNED`] per accessor (a warning about an accessor says when its check
//! stopped early) and [`MAX_VALUES_SCANNED`] per file (accessors past it are skipped,
//! which is said only next to other value problems: on a large valid file it would be
//! noise), image files are read up to [`MAX_IMAGE_BYTES`] each and
//! [`MAX_IMAGE_FILE_BYTES`] in all, and at most [`MAX_WARNINGS`] warnings are listed.
//!
//! - [`raw`]: what only the JSON text shows (empty arrays, extension objects and their
//!   declarations, values out of their schema ranges in materials and lights).
//! - [`structure`]: buffers, buffer views, accessors, meshes, nodes, scenes, skins and
//!   cameras, from their JSON properties.
//! - [`data`]: accessor values (NaN and infinities, min/max, unit vectors, indices,
//!   inverse bind matrices).
//! - [`image_data`]: images (URIs, MIME types against content, truncated headers).

mod data;
mod image_data;
mod raw;
mod structure;

use std::path::Path;

use gltf::json;
use gltf::json::validation::Checked;

use crate::buffers::Buffers;
use crate::document::Document;

/// Elements of one accessor whose values are checked.
pub const MAX_ELEMENTS_SCANNED: u64 = 1 << 22;
/// Components (numbers) checked over the whole file.
pub const MAX_VALUES_SCANNED: u64 = 1 << 26;
/// Bytes of an external image file read to check its header.
pub const MAX_IMAGE_BYTES: u64 = 1 << 22;
/// Bytes of external image files read in all.
pub const MAX_IMAGE_FILE_BYTES: u64 = 1 << 26;
/// Warnings listed; the rest are counted in one more.
pub const MAX_WARNINGS: usize = 40;

/// The problems found in `doc`, one warning per kind of problem and object.
pub fn check(doc: &Document, buffers: &Buffers, base: &Path) -> Vec<String> {
    let mut report = Report::default();
    for p in &doc.container_problems {
        report.add(p.clone());
    }
    let uses = Uses::new(&doc.root);
    raw::check(&doc.raw, &doc.root, &mut report);
    structure::check(&doc.root, &doc.raw, doc.glb, buffers, &uses, &mut report);
    data::check(&doc.root, buffers, &uses, &mut report);
    image_data::check(&doc.root, buffers, base, &mut report);
    report.finish()
}

/// The warnings found so far, capped at [`MAX_WARNINGS`].
#[derive(Default)]
pub struct Report {
    warnings: Vec<String>,
    unlisted: usize,
}

impl Report {
    pub fn add(&mut self, warning: impl Into<String>) {
        if self.warnings.len() < MAX_WARNINGS {
            self.warnings.push(warning.into());
        } else {
            self.unlisted += 1;
        }
    }

    fn finish(mut self) -> Vec<String> {
        if self.unlisted > 0 {
            self.warnings.push(format!(
                "{} more problems of the kinds above are not listed",
                self.unlisted
            ));
        }
        self.warnings
    }
}

/// How messages name object `index` of a kind: `mesh 2 ("Cube")`.
pub fn named(kind: &str, index: usize, name: Option<&str>) -> String {
    match name.map(str::trim).filter(|n| !n.is_empty()) {
        Some(n) => {
            let short: String = n.chars().take(48).collect();
            let ellipsis = if short.len() < n.len() { "…" } else { "" };
            format!("{kind} {index} (\"{short}{ellipsis}\")")
        }
        None => format!("{kind} {index}"),
    }
}

/// `items` joined with ", ", at most `limit` of them, then "and N more".
pub fn list<T: std::fmt::Display>(items: &[T], limit: usize) -> String {
    let mut s = items
        .iter()
        .take(limit)
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(", ");
    if items.len() > limit {
        s.push_str(&format!(" and {} more", items.len() - limit));
    }
    s
}

/// What an accessor is used for.
#[derive(Clone, Copy, Default)]
pub struct Roles {
    pub position: bool,
    pub normal: bool,
    pub tangent: bool,
    pub color: bool,
    pub indices: bool,
    pub inverse_bind_matrices: bool,
    /// A vertex attribute or morph target of some primitive.
    pub vertex: bool,
}

/// What a buffer view's bytes are used for.
#[derive(Clone, Copy, Default)]
pub struct ViewRoles {
    pub vertex: bool,
    pub index: bool,
    pub image: bool,
    pub sparse: bool,
    pub inverse_bind_matrices: bool,
}

/// The uses of accessors and buffer views, gathered once from meshes, skins, sparse
/// accessors and images.
pub struct Uses {
    /// The first use of each accessor, as messages name it ("POSITION of mesh 0").
    pub accessor_label: Vec<Option<String>>,
    pub accessor_roles: Vec<Roles>,
    /// For an indices accessor: the fewest vertices among the primitives it indexes.
    pub index_limit: Vec<Option<u64>>,
    pub view_roles: Vec<ViewRoles>,
    /// The distinct accessors that read each buffer view as vertex attributes, sorted.
    pub view_vertex_accessors: Vec<Vec<usize>>,
}

impl Uses {
    fn new(root: &json::Root) -> Self {
        let accessors = root.accessors.len();
        let views = root.buffer_views.len();
        let mut uses = Self {
            accessor_label: vec![None; accessors],
            accessor_roles: vec![Roles::default(); accessors],
            index_limit: vec![None; accessors],
            view_roles: vec![ViewRoles::default(); views],
            view_vertex_accessors: vec![Vec::new(); views],
        };
        let view_of = |a: usize| {
            root.accessors
                .get(a)
                .and_then(|a| a.buffer_view)
                .map(|v| v.value())
                .filter(|&v| v < views)
        };
        for (m, mesh) in root.meshes.iter().enumerate() {
            let mesh_name = named("mesh", m, mesh.name.as_deref());
            for primitive in &mesh.primitives {
                let mut vertices: Option<u64> = None;
                for (semantic, a) in &primitive.attributes {
                    let a = a.value();
                    if a >= accessors {
                        continue;
                    }
                    vertices = Some(vertices.map_or(root.accessors[a].count.0, |v| {
                        v.min(root.accessors[a].count.0)
                    }));
                    uses.label(a, || format!("{} of {mesh_name}", semantic.to_string()));
                    let roles = &mut uses.accessor_roles[a];
                    roles.vertex = true;
                    match semantic {
                        Checked::Valid(json::mesh::Semantic::Positions) => roles.position = true,
                        Checked::Valid(json::mesh::Semantic::Normals) => roles.normal = true,
                        Checked::Valid(json::mesh::Semantic::Tangents) => roles.tangent = true,
                        Checked::Valid(json::mesh::Semantic::Colors(_)) => roles.color = true,
                        _ => {}
                    }
                    if let Some(v) = view_of(a) {
                        uses.view_roles[v].vertex = true;
                        uses.view_vertex_accessors[v].push(a);
                    }
                }
                for target in primitive.targets.iter().flatten() {
                    let attributes = [
                        ("POSITION", target.positions),
                        ("NORMAL", target.normals),
                        ("TANGENT", target.tangents),
                    ];
                    for (semantic, a) in attributes {
                        let Some(a) = a.map(|a| a.value()).filter(|&a| a < accessors) else {
                            continue;
                        };
                        uses.label(a, || format!("morph target {semantic} of {mesh_name}"));
                        uses.accessor_roles[a].vertex = true;
                        if let Some(v) = view_of(a) {
                            uses.view_roles[v].vertex = true;
                            uses.view_vertex_accessors[v].push(a);
                        }
                    }
                }
                if let Some(a) = primitive
                    .indices
                    .map(|a| a.value())
                    .filter(|&a| a < accessors)
                {
                    uses.label(a, || format!("indices of {mesh_name}"));
                    uses.accessor_roles[a].indices = true;
                    if let Some(n) = vertices {
                        uses.index_limit[a] = Some(uses.index_limit[a].map_or(n, |l| l.min(n)));
                    }
                    if let Some(v) = view_of(a) {
                        uses.view_roles[v].index = true;
                    }
                }
            }
        }
        for (s, skin) in root.skins.iter().enumerate() {
            let Some(a) = skin
                .inverse_bind_matrices
                .map(|a| a.value())
                .filter(|&a| a < accessors)
            else {
                continue;
            };
            let skin_name = named("skin", s, skin.name.as_deref());
            uses.label(a, || format!("inverse bind matrices of {skin_name}"));
            uses.accessor_roles[a].inverse_bind_matrices = true;
            if let Some(v) = view_of(a) {
                uses.view_roles[v].inverse_bind_matrices = true;
            }
        }
        for accessor in &root.accessors {
            if let Some(sparse) = &accessor.sparse {
                for v in [
                    sparse.indices.buffer_view.value(),
                    sparse.values.buffer_view.value(),
                ] {
                    if let Some(roles) = uses.view_roles.get_mut(v) {
                        roles.sparse = true;
                    }
                }
            }
        }
        for accessors in &mut uses.view_vertex_accessors {
            accessors.sort_unstable();
            accessors.dedup();
        }
        for image in &root.images {
            if let Some(roles) = image
                .buffer_view
                .and_then(|v| uses.view_roles.get_mut(v.value()))
            {
                roles.image = true;
            }
        }
        uses
    }

    fn label(&mut self, accessor: usize, label: impl FnOnce() -> String) {
        if self.accessor_label[accessor].is_none() {
            self.accessor_label[accessor] = Some(label());
        }
    }

    /// How messages name accessor `index`: `accessor 3 (POSITION of mesh 0)`.
    pub fn accessor(&self, root: &json::Root, index: usize) -> String {
        let name = named(
            "accessor",
            index,
            root.accessors.get(index).and_then(|a| a.name.as_deref()),
        );
        match self.accessor_label.get(index).and_then(Option::as_ref) {
            Some(label) => format!("{name} ({label})"),
            None => name,
        }
    }
}
