//! Material node graphs: the data model ([`graph`]), the node library ([`nodes`], with its
//! WGSL in `shaders/nodes/`), the compiler to WGSL ([`compile`]) and the `.kmat` file
//! format ([`load_material`]). Kernel assembly splices compiled materials into the
//! path-tracing kernel through [`materials_wgsl`].

pub mod bounds;
pub mod compile;
pub mod docs;
pub mod graph;
pub mod library;
pub mod nodes;
pub mod texture;

use std::collections::BTreeSet;
use std::path::Path;

use kiln_plugin_api::read::{MAX_FILE_BYTES, read_text_bounded};
use serde::{Deserialize, Serialize};
use thiserror::Error;

pub use compile::{CompiledMaterial, GraphError, MaterialTraits, compile};
pub use graph::{
    Frame, Graph, Group, GroupInterface, GroupSocket, Input, Link, Node, Param, RampStop,
    SocketType, Value,
};

/// The `.kmat` format version this build reads and writes.
pub const MATERIAL_FORMAT_VERSION: u32 = 1;

#[derive(Debug, Error)]
pub enum MaterialFileError {
    // The cause is in the message, not a `source`: a report of the error chain would
    // name it twice.
    #[error("cannot read {path}: {cause}")]
    Io { path: String, cause: std::io::Error },
    #[error("{path}:{line}:{column}: {message}")]
    Syntax {
        path: String,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{path}: {message}")]
    Version { path: String, message: String },
    #[error("cannot save {path}: {message}")]
    Save { path: String, message: String },
}

/// A `.kmat` file: a versioned, named graph (docs/NODES.md describes the format).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialFile {
    pub version: u32,
    #[serde(default)]
    pub name: Option<String>,
    pub nodes: std::collections::BTreeMap<String, Node>,
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub groups: std::collections::BTreeMap<String, Group>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output: Option<String>,
    /// The editor's frames (labelled boxes around nodes); written only when there are any,
    /// so files without frames read and save as before.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub frames: std::collections::BTreeMap<String, Frame>,
}

impl MaterialFile {
    pub fn graph(&self) -> Graph {
        Graph {
            nodes: self.nodes.clone(),
            groups: self.groups.clone(),
            output: self.output.clone(),
            frames: self.frames.clone(),
            interface: None,
        }
    }
}

/// Reads the version first, so a file from another version gets a clear message instead of
/// a complaint about some field.
#[derive(Deserialize)]
struct VersionOnly {
    version: Option<u32>,
}

fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

/// Parses `.kmat` text; `path` is only used in messages.
pub fn parse_material(text: &str, path: &str) -> Result<(String, Graph), MaterialFileError> {
    let syntax = |e: ron::error::SpannedError| MaterialFileError::Syntax {
        path: path.to_owned(),
        line: e.span.start.line,
        column: e.span.start.col,
        message: e.code.to_string(),
    };
    let version = ron_options()
        .from_str::<VersionOnly>(text)
        .map_err(syntax)?
        .version;
    match version {
        Some(MATERIAL_FORMAT_VERSION) => {}
        Some(v) if v > MATERIAL_FORMAT_VERSION => {
            return Err(MaterialFileError::Version {
                path: path.to_owned(),
                message: format!(
                    "written for material format version {v}; this Kiln reads version {MATERIAL_FORMAT_VERSION}: update Kiln"
                ),
            });
        }
        Some(v) => {
            return Err(MaterialFileError::Version {
                path: path.to_owned(),
                message: format!(
                    "material format version {v} is no longer read; save it again from a Kiln that reads it"
                ),
            });
        }
        None => {
            return Err(MaterialFileError::Version {
                path: path.to_owned(),
                message: format!(
                    "no `version:` field (this Kiln reads version {MATERIAL_FORMAT_VERSION})"
                ),
            });
        }
    }
    let file: MaterialFile = ron_options().from_str(text).map_err(syntax)?;
    let name = file.name.clone().unwrap_or_else(|| {
        Path::new(path)
            .file_stem()
            .map_or("material".into(), |s| s.to_string_lossy().into_owned())
    });
    let mut graph = file.graph();
    resolve_files(
        &mut graph,
        Path::new(path).parent().unwrap_or(Path::new("")),
    );
    Ok((name, graph))
}

/// The `.kmat` text of material `name` with `graph`. Deterministic: nodes, inputs,
/// parameters and groups are written in id order and links as `"node.socket"` strings, so
/// an unchanged graph always gives the same bytes (node positions included).
pub fn material_text(name: &str, graph: &Graph) -> Result<String, MaterialFileError> {
    let file = MaterialFile {
        version: MATERIAL_FORMAT_VERSION,
        name: Some(name.to_owned()),
        nodes: graph.nodes.clone(),
        groups: graph.groups.clone(),
        output: graph.output.clone(),
        frames: graph.frames.clone(),
    };
    ron::ser::to_string_pretty(&file, ron::ser::PrettyConfig::default()).map_err(|e| {
        MaterialFileError::Save {
            path: name.to_owned(),
            message: e.to_string(),
        }
    })
}

/// Writes material `name` with `graph` as a `.kmat` file at `path`, atomically.
pub fn save_material(path: &Path, name: &str, graph: &Graph) -> Result<(), MaterialFileError> {
    use std::io::Write as _;
    let text = material_text(name, graph)?;
    kiln_plugin_api::atomic::write_atomically(path, |w| {
        w.write_all(text.as_bytes()).map_err(|e| e.to_string())
    })
    .map_err(|message| MaterialFileError::Save {
        path: path.display().to_string(),
        message,
    })
}

pub fn load_material(path: &Path) -> Result<(String, Graph), MaterialFileError> {
    let text = read_text_bounded(path, MAX_FILE_BYTES).map_err(|cause| MaterialFileError::Io {
        path: path.display().to_string(),
        cause,
    })?;
    parse_material(&text, &path.display().to_string())
}

/// WGSL for a scene's compiled materials: the node-library items they need, each
/// material's function, and the dispatchers the integrator calls:
/// `evaluate_material(id, sp)`, and `evaluate_volume(id, sp)` for heterogeneous volumes
/// inside. Materials not listed read their fixed parameters from the material buffer.
pub fn materials_wgsl(materials: &[(u32, &CompiledMaterial)]) -> Vec<(String, String)> {
    // The integrator reads the material buffer through `material_eval` too.
    let mut roots: BTreeSet<String> = [
        "ShadingPoint",
        "MaterialEval",
        "material_eval",
        "VolumeEval",
        "nd_no_volume",
    ]
    .map(String::from)
    .into();
    for (_, m) in materials {
        roots.extend(m.calls.iter().cloned());
    }
    // (label, WGSL): kernel assembly names the part an error is in.
    let mut parts = vec![(
        "node library items used (shaders/nodes/)".to_owned(),
        library::closure(roots),
    )];
    for (_, m) in materials {
        parts.push((
            format!("material \"{}\" (generated)", m.material),
            m.code.clone(),
        ));
    }
    let mut dispatcher =
        String::from("fn evaluate_material(id: u32, sp: ShadingPoint) -> MaterialEval {\n");
    if !materials.is_empty() {
        dispatcher.push_str("    switch (id) {\n");
        for (id, m) in materials {
            dispatcher.push_str(&format!(
                "        case {id}u: {{ return {}(sp); }}\n",
                m.function
            ));
        }
        dispatcher.push_str("        default: {}\n    }\n");
    }
    dispatcher.push_str("    return material_from_buffer(id, sp);\n}\n");
    // Heterogeneous volumes at points inside (shaders/integrator/media.wgsl).
    dispatcher.push_str("fn evaluate_volume(id: u32, sp: ShadingPoint) -> VolumeEval {\n");
    let volumes: Vec<_> = materials
        .iter()
        .filter_map(|(id, m)| Some((id, m.volume_function.as_ref()?)))
        .collect();
    if !volumes.is_empty() {
        dispatcher.push_str("    switch (id) {\n");
        for (id, function) in volumes {
            dispatcher.push_str(&format!(
                "        case {id}u: {{ return {function}(sp); }}\n"
            ));
        }
        dispatcher.push_str("        default: {}\n    }\n");
    }
    dispatcher.push_str("    return nd_no_volume();\n}\n");
    parts.push(("material dispatcher (generated)".to_owned(), dispatcher));
    parts
}

/// [`crate::shader::lobes::CUTOUT`] for a surface whose alpha is below 1 somewhere
/// (`None`: it varies over the surface), else nothing.
pub fn cutout_lobes(alpha: Option<f32>) -> u32 {
    if alpha.is_none_or(|a| a < 1.0) {
        crate::shader::lobes::CUTOUT
    } else {
        0
    }
}

/// The principled lobes a surface with these weights can reach ([`crate::shader::lobes`]);
/// `None` is a weight that varies over the surface. A thin wall's subsurface is diffuse
/// transmission, not a random walk.
pub fn principled_lobes(
    coat: Option<f32>,
    sheen: Option<f32>,
    metallic: Option<f32>,
    transmission: Option<f32>,
    specular: Option<f32>,
    subsurface: Option<f32>,
    thin_walled: bool,
) -> u32 {
    use crate::shader::lobes;
    let some = |w: Option<f32>| w.is_none_or(|w| w > 0.0);
    let below_one = |w: Option<f32>| w.is_none_or(|w| w < 1.0);
    let mut set = 0;
    if some(coat) {
        set |= lobes::COAT;
    }
    if some(sheen) {
        set |= lobes::SHEEN;
    }
    if some(metallic) {
        set |= lobes::METAL;
    }
    let dielectric = below_one(metallic);
    if dielectric && some(transmission) {
        set |= lobes::GLASS;
    }
    if dielectric && below_one(transmission) {
        set |= lobes::DIFFUSE;
        if some(specular) {
            set |= lobes::SPECULAR;
        }
        if some(subsurface) {
            set |= if thin_walled {
                lobes::TRANSLUCENT
            } else {
                lobes::SUBSURFACE
            };
        }
    }
    set
}

/// Makes the image paths of a graph (as seen from the working directory, as
/// [`resolve_files`] leaves them) relative to the folder `to` a file of it is written
/// in, so that the folder can move with its images; a path on another root stays
/// absolute.
pub fn relative_files(graph: &mut Graph, to: &Path) {
    let Ok(to) = std::path::absolute(to) else {
        return;
    };
    for file in graph.image_files_mut() {
        if file.starts_with("image:") {
            continue;
        }
        let Ok(absolute) = std::path::absolute(file.as_str()) else {
            continue;
        };
        if let Some(relative) = relative_path(&absolute, &to) {
            *file = relative.to_string_lossy().into_owned();
        }
    }
}

/// `path` relative to the folder `base` (both absolute), through `..` where needed;
/// `None` when they share no root.
fn relative_path(path: &Path, base: &Path) -> Option<std::path::PathBuf> {
    use std::path::Component;
    fn normal(p: &Path) -> Vec<Component<'_>> {
        let mut parts: Vec<Component> = Vec::new();
        for c in p.components() {
            match c {
                Component::CurDir => {}
                Component::ParentDir if matches!(parts.last(), Some(Component::Normal(_))) => {
                    parts.pop();
                }
                c => parts.push(c),
            }
        }
        parts
    }
    let (path, base) = (normal(path), normal(base));
    if path.first() != base.first() {
        return None;
    }
    let common = path.iter().zip(&base).take_while(|(a, b)| a == b).count();
    let mut relative = std::path::PathBuf::new();
    for _ in common..base.len() {
        relative.push("..");
    }
    for c in &path[common..] {
        relative.push(c.as_os_str());
    }
    Some(relative)
}

/// Makes image paths of `image_texture` nodes (in the graph and its groups) relative to
/// `base`, the directory of the file the graph came from.
pub fn resolve_files(graph: &mut Graph, base: &Path) {
    for file in graph.image_files_mut() {
        // `image:N` names an image an importer handed over in memory.
        if !file.starts_with("image:") && Path::new(file.as_str()).is_relative() {
            *file = base.join(&*file).to_string_lossy().into_owned();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_climb_out_of_the_base_folder() {
        let rel = |p: &str, b: &str| relative_path(Path::new(p), Path::new(b)).unwrap();
        assert_eq!(rel("/a/b/c.png", "/a/b"), Path::new("c.png"));
        assert_eq!(
            rel("/a/img/c.png", "/a/out/mats"),
            Path::new("../../img/c.png")
        );
        assert_eq!(rel("/a/./x/../c.png", "/a"), Path::new("c.png"));
    }

    #[test]
    fn muted_is_saved_only_when_set_and_reads_back() {
        let mut graph = Graph::default();
        graph.add("value", Node::new("value"));
        let plain = material_text("m", &graph).unwrap();
        assert!(!plain.contains("muted"), "{plain}");
        graph.nodes.get_mut("value").unwrap().muted = true;
        let muted = material_text("m", &graph).unwrap();
        assert!(muted.contains("muted: true"), "{muted}");
        assert_eq!(parse_material(&muted, "m.kmat").unwrap().1, graph);
    }

    #[test]
    fn preview_is_saved_only_when_set_and_reads_back() {
        let mut graph = Graph::default();
        graph.add("value", Node::new("value"));
        let plain = material_text("m", &graph).unwrap();
        assert!(!plain.contains("preview"), "{plain}");
        graph.nodes.get_mut("value").unwrap().preview = true;
        let shown = material_text("m", &graph).unwrap();
        assert!(shown.contains("preview: true"), "{shown}");
        assert_eq!(parse_material(&shown, "m.kmat").unwrap().1, graph);
    }

    #[test]
    fn frames_are_written_only_when_there_are_any_and_read_back() {
        let mut graph = Graph::default();
        graph.add("value", Node::new("value"));
        let plain = material_text("m", &graph).unwrap();
        assert!(!plain.contains("frames"), "{plain}");
        let frame = Frame {
            label: "Values".into(),
            color: [0.2, 0.3, 0.4],
            nodes: vec!["value".into()],
        };
        graph.frames.insert("frame".into(), frame.clone());
        let mut group = Group::default();
        group.frames.insert("inner".into(), frame);
        group.output_position = Some([300.0, 0.0]);
        graph.groups.insert("g".into(), group);
        let framed = material_text("m", &graph).unwrap();
        let read = parse_material(&framed, "m.kmat").unwrap().1;
        assert_eq!(read, graph);
        assert_eq!(
            material_text("m", &read).unwrap(),
            framed,
            "saves byte-identical"
        );
        // Frames are layout: the same computation.
        let mut unframed = graph.clone();
        unframed.frames.clear();
        assert!(graph.same_but_layout(&unframed));
    }

    #[test]
    fn graphs_that_differ_only_in_layout_compute_the_same() {
        let mut graph = Graph::default();
        graph.add("value", Node::new("value"));
        let mut moved = graph.clone();
        moved.nodes.get_mut("value").unwrap().position = Some([10.0, 20.0]);
        assert!(graph.same_but_layout(&moved));
        moved.nodes.get_mut("value").unwrap().preview = true;
        assert!(
            graph.same_but_layout(&moved),
            "a preview shown computes nothing"
        );
        let mut muted = moved.clone();
        muted.nodes.get_mut("value").unwrap().muted = true;
        assert!(!graph.same_but_layout(&muted));
        let mut renamed = graph.clone();
        let node = renamed.nodes.remove("value").unwrap();
        renamed.add("other", node);
        assert!(!graph.same_but_layout(&renamed));
    }
}
