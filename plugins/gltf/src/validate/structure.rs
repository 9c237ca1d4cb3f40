//! Checks of objects from their JSON properties: buffers and buffer views (lengths,
//! strides, targets), accessors (alignment, lengths, sparse counts), mesh primitives
//! (attribute counts and formats, morph targets), nodes (transforms, hierarchy), scenes,
//! skins and cameras. Accessor values are [`super::data`]'s.

use glam::{Mat3, Mat4, Quat};
use gltf::json;
use gltf::json::Value;
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::buffer::Target;
use gltf::json::mesh::Semantic;
use gltf::json::validation::Checked;

use super::data::Layout;
use super::{Report, Uses, list, named};
use crate::buffers::Buffers;

pub fn check(
    root: &json::Root,
    raw: &Value,
    glb: bool,
    buffers: &Buffers,
    uses: &Uses,
    report: &mut Report,
) {
    buffer_objects(root, raw, glb, buffers, report);
    buffer_views(root, uses, report);
    accessors(root, uses, report);
    meshes(root, report);
    nodes(root, report);
    skins(root, report);
    cameras(root, report);
}

/// Buffers: a zero byteLength (VALUE_NOT_IN_RANGE), a data URI that is malformed
/// (INVALID_URI) or not of a buffer's media type (BUFFER_DATA_URI_MIME_TYPE_INVALID), and
/// in a GLB a buffer without URI that no binary chunk fills (BUFFER_MISSING_GLB_DATA).
fn buffer_objects(
    root: &json::Root,
    raw: &Value,
    glb: bool,
    buffers: &Buffers,
    report: &mut Report,
) {
    for (i, buffer) in root.buffers.iter().enumerate() {
        let name = named("buffer", i, buffer.name.as_deref());
        let declared = raw
            .get("buffers")
            .and_then(|b| b.get(i))
            .is_some_and(|b| b.get("byteLength").is_some());
        if declared && buffer.byte_length.0 == 0 {
            report.add(format!(
                "{name}: byteLength is 0 (a buffer holds at least 1 byte)"
            ));
        }
        match &buffer.uri {
            Some(uri) => {
                if let Some(header) = data_uri_header(uri) {
                    match media_type(header) {
                        Err(e) => report.add(format!("{name}: its data URI is malformed: {e}")),
                        Ok(t) if t != "application/octet-stream" && t != "application/gltf-buffer" => {
                            report.add(format!(
                                "{name}: its data URI has the media type \"{t}\"; a buffer's is application/octet-stream or application/gltf-buffer"
                            ))
                        }
                        Ok(_) => {}
                    }
                }
            }
            // Later buffers without a URI are placeholders, which the spec allows.
            None if glb && i == 0 && !buffers.has_data(0) => report.add(format!(
                "{name} has no URI and the GLB has no binary chunk to hold its data"
            )),
            None => {}
        }
    }
}

/// The header of a data URI (between `data:` and the comma).
pub fn data_uri_header(uri: &str) -> Option<&str> {
    uri.strip_prefix("data:")
        .map(|rest| rest.split_once(',').map_or(rest, |(h, _)| h))
}

/// The media type of a data URI header (`type/subtype[;attr=value]*[;base64]`); an error
/// for an empty parameter or one without a value.
pub fn media_type(header: &str) -> Result<&str, String> {
    let mut parts = header.split(';');
    let media = parts.next().unwrap_or("");
    let params: Vec<&str> = parts.collect();
    for (k, p) in params.iter().enumerate() {
        let last = k + 1 == params.len();
        if last && *p == "base64" {
            continue;
        }
        if p.is_empty() || !p.contains('=') {
            return Err(format!(
                "the parameter \"{p}\" in \"{header}\" is not attribute=value"
            ));
        }
    }
    if !media.is_empty() && media.split('/').count() != 2 {
        return Err(format!("\"{media}\" is not a media type"));
    }
    Ok(media)
}

/// Buffer views: zero length (VALUE_NOT_IN_RANGE), past their buffer
/// (BUFFER_VIEW_TOO_LONG), byteStride not a multiple of 4 (VALUE_MULTIPLE_OF), larger
/// than the view (BUFFER_VIEW_TOO_BIG_BYTE_STRIDE) or given where only vertex data may
/// have one (BUFFER_VIEW_INVALID_BYTE_STRIDE, MESH_PRIMITIVE_INDICES_ACCESSOR_WITH_BYTESTRIDE,
/// IMAGE_BUFFER_VIEW_WITH_BYTESTRIDE, SKIN_IBM_ACCESSOR_WITH_BYTESTRIDE), used both as
/// vertex and index data or against its target (BUFFER_VIEW_TARGET_OVERRIDE), and shared
/// by vertex accessors without a stride (MESH_PRIMITIVE_ACCESSOR_WITHOUT_BYTESTRIDE).
fn buffer_views(root: &json::Root, uses: &Uses, report: &mut Report) {
    for (i, view) in root.buffer_views.iter().enumerate() {
        let mut problems = Vec::new();
        let length = view.byte_length.0;
        let offset = view.byte_offset.map_or(0, |o| o.0);
        if length == 0 {
            problems.push("byteLength is 0".to_owned());
        }
        let b = view.buffer.value();
        if let Some(buffer) = root.buffers.get(b) {
            if offset
                .checked_add(length)
                .is_none_or(|end| end > buffer.byte_length.0)
            {
                problems.push(format!(
                    "offset {offset} + length {length} runs past the {} bytes of buffer {b}",
                    buffer.byte_length.0
                ));
            }
        }
        let roles = uses.view_roles.get(i).copied().unwrap_or_default();
        let target = match view.target {
            Some(Checked::Valid(Target::ArrayBuffer)) => Some(Target::ArrayBuffer),
            Some(Checked::Valid(Target::ElementArrayBuffer)) => Some(Target::ElementArrayBuffer),
            _ => None,
        };
        if let Some(stride) = view.byte_stride.map(|s| s.0) {
            if stride % 4 != 0 {
                problems.push(format!("byteStride {stride} is not a multiple of 4"));
            }
            if stride as u64 > length && length > 0 {
                problems.push(format!(
                    "byteStride {stride} is larger than the view's {length} bytes"
                ));
            }
            let mut not_vertex = Vec::new();
            if target == Some(Target::ElementArrayBuffer) {
                not_vertex.push("its target is ELEMENT_ARRAY_BUFFER");
            }
            if roles.index {
                not_vertex.push("it holds indices");
            }
            if roles.sparse {
                not_vertex.push("it holds sparse accessor data");
            }
            if roles.image {
                not_vertex.push("it holds an image");
            }
            if roles.inverse_bind_matrices {
                not_vertex.push("it holds inverse bind matrices");
            }
            if !not_vertex.is_empty() {
                problems.push(format!(
                    "it has a byteStride, which only vertex data may have, but {}",
                    not_vertex.join(" and ")
                ));
            }
        } else if uses.view_vertex_accessors[i].len() > 1 {
            problems.push(format!(
                "accessors {} read vertex attributes from it, which requires a byteStride",
                list(&uses.view_vertex_accessors[i], 4)
            ));
        }
        let vertex = roles.vertex || target == Some(Target::ArrayBuffer);
        let index = roles.index || target == Some(Target::ElementArrayBuffer);
        if vertex && index {
            let how = match target {
                Some(Target::ArrayBuffer) => "its target is ARRAY_BUFFER but it holds indices",
                Some(Target::ElementArrayBuffer) => {
                    "its target is ELEMENT_ARRAY_BUFFER but it holds vertex attributes"
                }
                None => "it holds both vertex attributes and indices",
            };
            problems.push(how.to_owned());
        }
        if roles.image && (roles.vertex || roles.index) {
            problems.push("it holds both an image and mesh data".to_owned());
        }
        if !problems.is_empty() {
            report.add(format!(
                "{}: {}",
                named("buffer view", i, view.name.as_deref()),
                problems.join("; ")
            ));
        }
    }
}

/// Accessors: byteOffset without bufferView (UNSATISFIED_DEPENDENCY), count 0,
/// `normalized` on floats or 32-bit integers (ACCESSOR_NORMALIZED_INVALID), misaligned
/// offsets (ACCESSOR_OFFSET_ALIGNMENT, ACCESSOR_TOTAL_OFFSET_ALIGNMENT,
/// ACCESSOR_MATRIX_ALIGNMENT, MESH_PRIMITIVE_ACCESSOR_UNALIGNED), a stride smaller than an
/// element (ACCESSOR_SMALL_BYTESTRIDE), data past the view (ACCESSOR_TOO_LONG), min/max
/// of the wrong length, and sparse storage that does not fit (ACCESSOR_SPARSE_COUNT_OUT_OF_RANGE).
fn accessors(root: &json::Root, uses: &Uses, report: &mut Report) {
    for (i, accessor) in root.accessors.iter().enumerate() {
        let mut problems = Vec::new();
        let offset = accessor.byte_offset.map(|o| o.0);
        let view_index = accessor.buffer_view.map(|v| v.value());
        if view_index.is_none() && offset.is_some() {
            problems.push("it has a byteOffset but no bufferView".to_owned());
        }
        let count = accessor.count.0;
        if count == 0 {
            problems.push("count is 0".to_owned());
        }
        let Some(layout) = Layout::of(accessor) else {
            // Invalid componentType or type: reported with the schema problems.
            push(report, uses, root, i, problems);
            continue;
        };
        if accessor.normalized
            && matches!(layout.component, ComponentType::F32 | ComponentType::U32)
        {
            problems.push(format!(
                "it is normalized, which only 8- and 16-bit integers may be ({:?})",
                layout.component
            ));
        }
        for (key, value) in [("min", &accessor.min), ("max", &accessor.max)] {
            if let Some(v) = value {
                let ok = v.as_array().is_some_and(|a| {
                    a.len() == layout.components && a.iter().all(Value::is_number)
                });
                if !ok {
                    problems.push(format!(
                        "{key} is not an array of {} numbers",
                        layout.components
                    ));
                }
            }
        }
        let offset = offset.unwrap_or(0);
        let size = layout.component_size as u64;
        if layout.is_matrix() && offset % 4 != 0 {
            problems.push(format!(
                "byteOffset {offset} of a matrix accessor is not a multiple of 4"
            ));
        } else if offset % size != 0 {
            problems.push(format!(
                "byteOffset {offset} is not a multiple of its component size {size}"
            ));
        }
        if let Some(view) = view_index.and_then(|v| root.buffer_views.get(v)) {
            let v = view_index.unwrap_or(0);
            let view_offset = view.byte_offset.map_or(0, |o| o.0);
            let total = view_offset.saturating_add(offset);
            if total % size != 0 && offset % size == 0 {
                problems.push(format!(
                    "its data starts at byte {total} of the buffer, not a multiple of its component size {size}"
                ));
            }
            let stride = view.byte_stride.map(|s| s.0 as u64);
            if let Some(s) = stride.filter(|&s| s < layout.element_length as u64) {
                problems.push(format!(
                    "buffer view {v}'s byteStride {s} is smaller than an element ({} bytes)",
                    layout.element_length
                ));
            }
            let stride = stride.unwrap_or(layout.default_stride as u64);
            let length = layout.byte_length(count, stride);
            let fits = offset
                .checked_add(length)
                .is_some_and(|end| end <= view.byte_length.0);
            if !fits {
                problems.push(format!(
                    "{count} elements from byteOffset {offset} ({length} bytes) do not fit in buffer view {v} of {} bytes",
                    view.byte_length.0
                ));
            }
            let roles = uses.accessor_roles.get(i).copied().unwrap_or_default();
            if roles.vertex && (total % 4 != 0 || stride % 4 != 0) {
                problems.push(
                    "as vertex attribute data its start and stride must be multiples of 4 bytes"
                        .to_owned(),
                );
            }
        }
        if let Some(sparse) = &accessor.sparse {
            let n = sparse.count.0;
            if n == 0 {
                problems.push("sparse.count is 0".to_owned());
            }
            if n > count {
                problems.push(format!(
                    "sparse.count {n} is more than the accessor's {count} elements"
                ));
            }
            let index_size = match sparse.indices.component_type {
                Checked::Valid(json::accessor::IndexComponentType(c)) => c.size() as u64,
                Checked::Invalid => 4,
            };
            let parts = [
                (
                    "indices",
                    sparse.indices.buffer_view.value(),
                    sparse.indices.byte_offset.0,
                    index_size,
                    index_size,
                ),
                (
                    "values",
                    sparse.values.buffer_view.value(),
                    sparse.values.byte_offset.0,
                    size,
                    size * layout.components as u64,
                ),
            ];
            for (what, v, at, align, element) in parts {
                let Some(view) = root.buffer_views.get(v) else {
                    continue;
                };
                let total = view.byte_offset.map_or(0, |o| o.0).saturating_add(at);
                if total % align != 0 {
                    problems.push(format!(
                        "sparse {what} start at byte {total} of the buffer, not a multiple of {align}"
                    ));
                }
                let fits = element
                    .checked_mul(n)
                    .and_then(|l| l.checked_add(at))
                    .is_some_and(|end| end <= view.byte_length.0);
                if !fits {
                    problems.push(format!(
                        "{n} sparse {what} from byteOffset {at} do not fit in buffer view {v}"
                    ));
                }
            }
        }
        push(report, uses, root, i, problems);
    }
}

fn push(report: &mut Report, uses: &Uses, root: &json::Root, i: usize, problems: Vec<String>) {
    if !problems.is_empty() {
        report.add(format!(
            "{}: {}",
            uses.accessor(root, i),
            problems.join("; ")
        ));
    }
}

fn semantic_name(s: &Checked<Semantic>) -> String {
    s.to_string()
}

/// Mesh primitives: attribute accessors of different counts
/// (MESH_PRIMITIVE_UNEQUAL_ACCESSOR_COUNT), UNSIGNED_INT attributes
/// (MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_UNSIGNED_INT), indices that are not unsigned
/// integer scalars (MESH_PRIMITIVE_INDICES_ACCESSOR_INVALID_FORMAT), unpaired JOINTS and
/// WEIGHTS (MESH_PRIMITIVE_JOINTS_WEIGHTS_MISMATCH), and morph targets: without a base
/// attribute, of another count, POSITION without bounds, a different number per primitive,
/// or a weights array of another length (MESH_PRIMITIVE_MORPH_TARGET_*,
/// MESH_PRIMITIVE_POSITION_ACCESSOR_WITHOUT_BOUNDS, MESH_PRIMITIVES_UNEQUAL_TARGETS_COUNT,
/// MESH_INVALID_WEIGHTS_COUNT).
fn meshes(root: &json::Root, report: &mut Report) {
    let accessor = |i: usize| root.accessors.get(i);
    for (m, mesh) in root.meshes.iter().enumerate() {
        let mesh_name = named("mesh", m, mesh.name.as_deref());
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let mut problems = Vec::new();
            let counts: Vec<(String, u64)> = primitive
                .attributes
                .iter()
                .filter_map(|(s, a)| accessor(a.value()).map(|a| (semantic_name(s), a.count.0)))
                .collect();
            if let Some((_, first)) = counts.first() {
                if counts.iter().any(|(_, c)| c != first) {
                    let each: Vec<String> =
                        counts.iter().map(|(s, c)| format!("{s} {c}")).collect();
                    problems.push(format!(
                        "its attributes have different counts ({})",
                        list(&each, 6)
                    ));
                }
            }
            let uint: Vec<String> = primitive
                .attributes
                .iter()
                .filter(|(_, a)| {
                    accessor(a.value()).is_some_and(|a| {
                        matches!(
                            a.component_type,
                            Checked::Valid(json::accessor::GenericComponentType(
                                ComponentType::U32
                            ))
                        )
                    })
                })
                .map(|(s, _)| semantic_name(s))
                .collect();
            if !uint.is_empty() {
                problems.push(format!(
                    "attribute(s) {} use UNSIGNED_INT, which attributes may not",
                    list(&uint, 4)
                ));
            }
            if let Some(a) = primitive.indices.and_then(|i| accessor(i.value())) {
                let ok = a.type_ == Checked::Valid(Type::Scalar)
                    && matches!(
                        a.component_type,
                        Checked::Valid(json::accessor::GenericComponentType(
                            ComponentType::U8 | ComponentType::U16 | ComponentType::U32
                        ))
                    );
                if !ok {
                    problems.push(
                        "its indices accessor is not a SCALAR of UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT"
                            .to_owned(),
                    );
                }
            }
            let sets = |f: fn(&Semantic) -> Option<u32>| -> Vec<u32> {
                primitive
                    .attributes
                    .keys()
                    .filter_map(|s| match s {
                        Checked::Valid(s) => f(s),
                        Checked::Invalid => None,
                    })
                    .collect()
            };
            let joints = sets(|s| match s {
                Semantic::Joints(n) => Some(*n),
                _ => None,
            });
            let weights = sets(|s| match s {
                Semantic::Weights(n) => Some(*n),
                _ => None,
            });
            if joints.len() != weights.len() {
                problems.push(format!(
                    "it has {} JOINTS attribute(s) but {} WEIGHTS",
                    joints.len(),
                    weights.len()
                ));
            }
            for (t, target) in primitive.targets.iter().flatten().enumerate() {
                let attributes = [
                    ("POSITION", target.positions, Semantic::Positions),
                    ("NORMAL", target.normals, Semantic::Normals),
                    ("TANGENT", target.tangents, Semantic::Tangents),
                ];
                for (name, a, semantic) in attributes {
                    let Some(a) = a.map(|a| a.value()) else {
                        continue;
                    };
                    let base = primitive.attributes.get(&Checked::Valid(semantic));
                    match base.and_then(|b| accessor(b.value())) {
                        None if base.is_none() => problems.push(format!(
                            "morph target {t} has {name} but the primitive has no {name} attribute"
                        )),
                        None => {}
                        Some(base) => {
                            if let Some(acc) = accessor(a) {
                                if acc.count.0 != base.count.0 {
                                    problems.push(format!(
                                        "morph target {t}'s {name} has {} elements, the base attribute {}",
                                        acc.count.0, base.count.0
                                    ));
                                }
                            }
                        }
                    }
                    if name == "POSITION" {
                        if let Some(acc) = accessor(a) {
                            if acc.min.is_none() || acc.max.is_none() {
                                problems.push(format!(
                                    "morph target {t}'s POSITION (accessor {a}) has no min and max, which POSITION accessors must have"
                                ));
                            }
                        }
                    }
                }
            }
            if !problems.is_empty() {
                report.add(format!(
                    "{mesh_name} primitive {p}: {}",
                    problems.join("; ")
                ));
            }
        }
        let targets: Vec<usize> = mesh
            .primitives
            .iter()
            .map(|p| p.targets.as_ref().map_or(0, Vec::len))
            .collect();
        if targets.iter().any(|&t| t != targets[0]) {
            report.add(format!(
                "{mesh_name}: its primitives have different numbers of morph targets ({})",
                list(&targets, 8)
            ));
        }
        if let (Some(weights), Some(&t)) = (&mesh.weights, targets.first()) {
            if weights.len() != t {
                report.add(format!(
                    "{mesh_name}: {} default weights for {t} morph target(s)",
                    weights.len()
                ));
            }
        }
    }
}

/// Whether `m` (column-major) is a translation · rotation · scale: its last row is
/// (0, 0, 0, 1) and recomposing its decomposition gives it back (no shear, no projection).
pub fn decomposable(m: &[f32; 16]) -> bool {
    if m[3] != 0.0 || m[7] != 0.0 || m[11] != 0.0 || m[15] != 1.0 {
        return false;
    }
    let mat = Mat4::from_cols_array(m);
    let det = Mat3::from_mat4(mat).determinant();
    if !mat.is_finite() || det == 0.0 || !det.is_finite() {
        return false;
    }
    let (s, r, t) = mat.to_scale_rotation_translation();
    let back = Mat4::from_scale_rotation_translation(s, r, t).to_cols_array();
    let magnitude = m.iter().fold(1.0f32, |a, v| a.max(v.abs()));
    back.iter()
        .zip(m)
        .all(|(a, b)| (a - b).abs() <= 1e-4 * magnitude)
}

/// Nodes: matrix together with TRS (NODE_MATRIX_TRS), a matrix that is not a TRS
/// (NODE_MATRIX_NON_TRS), a rotation that is not a unit quaternion (ROTATION_NON_UNIT), a
/// skin or weights without a mesh (UNSATISFIED_DEPENDENCY); the hierarchy: nodes with
/// several parents (NODE_PARENT_OVERRIDE), cycles (NODE_LOOP) and scene nodes that are
/// children (SCENE_NON_ROOT_NODE).
fn nodes(root: &json::Root, report: &mut Report) {
    let n = root.nodes.len();
    for (i, node) in root.nodes.iter().enumerate() {
        let mut problems = Vec::new();
        if let Some(m) = &node.matrix {
            if node.translation.is_some() || node.rotation.is_some() || node.scale.is_some() {
                problems.push(
                    "it has both a matrix and translation/rotation/scale; the matrix is used"
                        .to_owned(),
                );
            }
            if !decomposable(m) {
                problems.push(
                    "its matrix is not a translation · rotation · scale (it shears or projects)"
                        .to_owned(),
                );
            }
        }
        if let Some(r) = &node.rotation {
            let length = Quat::from_array(r.0).length();
            if length.is_nan() || (length - 1.0).abs() > 0.00769 {
                problems.push(format!(
                    "its rotation {:?} is not a unit quaternion (length {length})",
                    r.0
                ));
            }
        }
        if node.skin.is_some() && node.mesh.is_none() {
            problems.push("it has a skin but no mesh".to_owned());
        }
        if node.weights.is_some() && node.mesh.is_none() {
            problems.push("it has morph weights but no mesh".to_owned());
        }
        if !problems.is_empty() {
            report.add(format!(
                "{}: {}",
                named("node", i, node.name.as_deref()),
                problems.join("; ")
            ));
        }
    }
    let parents = parents(root);
    let several: Vec<usize> = (0..n).filter(|&c| parents[c].len() > 1).collect();
    if !several.is_empty() {
        report.add(format!(
            "node(s) {} are children of more than one node; the hierarchy must be a tree",
            list(&several, 6)
        ));
    }
    let looped = cycles(root);
    if !looped.is_empty() {
        report.add(format!(
            "the node hierarchy has a cycle (through node(s) {}); it must be a tree",
            list(&looped, 6)
        ));
    }
    for (s, scene) in root.scenes.iter().enumerate() {
        let children: Vec<usize> = scene
            .nodes
            .iter()
            .map(|i| i.value())
            .filter(|&i| parents.get(i).is_some_and(|p| !p.is_empty()))
            .collect();
        if !children.is_empty() {
            report.add(format!(
                "{}: node(s) {} are listed as roots but are children of other nodes",
                named("scene", s, scene.name.as_deref()),
                list(&children, 6)
            ));
        }
    }
}

/// The distinct parents of each node, lowest index first.
fn parents(root: &json::Root) -> Vec<Vec<usize>> {
    let mut parents = vec![Vec::new(); root.nodes.len()];
    for (p, node) in root.nodes.iter().enumerate() {
        for c in node.children.iter().flatten() {
            if let Some(list) = parents.get_mut(c.value()) {
                list.push(p);
            }
        }
    }
    for list in &mut parents {
        list.dedup();
    }
    parents
}

/// Nodes on cycles of the hierarchy (the first [`CYCLE_NODES_LISTED`] found), from a
/// depth-first walk of the children: each edge back to a node on the current path closes
/// a cycle made of the path from that node on.
fn cycles(root: &json::Root) -> Vec<usize> {
    let n = root.nodes.len();
    // 0: not visited, 1: on the current path, 2: done.
    let mut state = vec![0u8; n];
    let mut closing = Vec::new();
    for start in 0..n {
        if state[start] != 0 {
            continue;
        }
        let mut stack: Vec<(usize, usize)> = vec![(start, 0)];
        state[start] = 1;
        while let Some(&mut (node, ref mut next)) = stack.last_mut() {
            let children = root.nodes[node].children.as_deref().unwrap_or(&[]);
            if let Some(child) = children.get(*next) {
                *next += 1;
                let c = child.value();
                match state.get(c) {
                    Some(0) => {
                        state[c] = 1;
                        stack.push((c, 0));
                    }
                    Some(1) if closing.len() < CYCLE_NODES_LISTED => {
                        let from = stack.iter().rposition(|&(n, _)| n == c).unwrap_or(0);
                        for &(n, _) in &stack[from..] {
                            if !closing.contains(&n) {
                                closing.push(n);
                            }
                        }
                    }
                    _ => {}
                }
            } else {
                state[node] = 2;
                stack.pop();
            }
        }
    }
    closing.sort_unstable();
    closing
}

/// Nodes on cycles that [`cycles`] collects.
const CYCLE_NODES_LISTED: usize = 16;

/// The hierarchy as a forest, each node under its first parent (several parents are
/// reported by [`nodes`]), with depth-first entry and exit times that tell ancestors in
/// constant time. Nodes on cycles are reachable from no root and have no times.
struct Forest {
    /// The root of each node's tree (itself for roots and nodes on cycles).
    top: Vec<usize>,
    enter: Vec<usize>,
    exit: Vec<usize>,
}

impl Forest {
    fn new(parents: &[Vec<usize>]) -> Self {
        let n = parents.len();
        let mut children = vec![Vec::new(); n];
        let mut roots = Vec::new();
        for (c, p) in parents.iter().enumerate() {
            match p.first() {
                Some(&p) => children[p].push(c),
                None => roots.push(c),
            }
        }
        let mut forest = Self {
            top: (0..n).collect(),
            enter: vec![usize::MAX; n],
            exit: vec![usize::MAX; n],
        };
        let mut clock = 0;
        for &r in &roots {
            forest.enter[r] = clock;
            clock += 1;
            let mut stack = vec![(r, 0usize)];
            while let Some(&mut (node, ref mut next)) = stack.last_mut() {
                if let Some(&c) = children[node].get(*next) {
                    *next += 1;
                    forest.enter[c] = clock;
                    clock += 1;
                    forest.top[c] = r;
                    stack.push((c, 0));
                } else {
                    forest.exit[node] = clock;
                    clock += 1;
                    stack.pop();
                }
            }
        }
        forest
    }

    /// Whether `a` is `b` or an ancestor of `b`.
    fn holds(&self, a: usize, b: usize) -> bool {
        a == b
            || (self.enter[a] != usize::MAX
                && self.enter[b] != usize::MAX
                && self.enter[a] <= self.enter[b]
                && self.exit[b] <= self.exit[a])
    }
}

/// Skins (ignored by Kiln, which shows the bind pose, but reported): inverse bind matrices
/// that are not MAT4 floats (SKIN_IBM_INVALID_FORMAT) or fewer than the joints
/// (INVALID_IBM_ACCESSOR_COUNT), joints without a common root (SKIN_NO_COMMON_ROOT), a
/// skeleton that is not one (SKIN_SKELETON_INVALID).
fn skins(root: &json::Root, report: &mut Report) {
    if root.skins.is_empty() {
        return;
    }
    let forest = Forest::new(&parents(root));
    for (s, skin) in root.skins.iter().enumerate() {
        let mut problems = Vec::new();
        let joints: Vec<usize> = skin
            .joints
            .iter()
            .map(|j| j.value())
            .filter(|&j| j < root.nodes.len())
            .collect();
        if let Some(a) = skin.inverse_bind_matrices.map(|a| a.value()) {
            if let Some(accessor) = root.accessors.get(a) {
                let format_ok = accessor.type_ == Checked::Valid(Type::Mat4)
                    && matches!(
                        accessor.component_type,
                        Checked::Valid(json::accessor::GenericComponentType(ComponentType::F32))
                    );
                if !format_ok {
                    problems.push(format!(
                        "its inverse bind matrices (accessor {a}) are not MAT4 floats"
                    ));
                }
                if accessor.count.0 < skin.joints.len() as u64 {
                    problems.push(format!(
                        "{} inverse bind matrices for {} joints",
                        accessor.count.0,
                        skin.joints.len()
                    ));
                }
            }
        }
        if joints
            .iter()
            .any(|&j| forest.top[j] != forest.top[joints[0]])
        {
            problems.push("its joints do not share a common root".to_owned());
        } else if let Some(skeleton) = skin.skeleton.map(|s| s.value()) {
            if skeleton < root.nodes.len() && !joints.iter().all(|&j| forest.holds(skeleton, j)) {
                problems.push(format!(
                    "its skeleton node {skeleton} is not an ancestor of all its joints"
                ));
            }
        }
        if !problems.is_empty() {
            report.add(format!(
                "{} (skins are not imported): {}",
                named("skin", s, skin.name.as_deref()),
                problems.join("; ")
            ));
        }
    }
}

/// `a > b`; false if either is NaN, so that `!greater` also catches NaN.
fn greater(a: f32, b: f32) -> bool {
    a > b
}

/// Cameras: not exactly one projection (ONE_OF_MISMATCH), and projection values out of
/// range: yfov, aspectRatio, znear, zfar ≤ znear (CAMERA_ZFAR_LEQUAL_ZNEAR), a zero
/// xmag or ymag (CAMERA_XMAG_YMAG_ZERO).
fn cameras(root: &json::Root, report: &mut Report) {
    use json::camera::Type as CameraType;
    for (c, camera) in root.cameras.iter().enumerate() {
        let mut problems = Vec::new();
        match (&camera.perspective, &camera.orthographic) {
            (Some(_), Some(_)) => {
                problems.push("it has both a perspective and an orthographic projection".to_owned())
            }
            (None, None) => problems.push("it has no projection".to_owned()),
            (Some(_), None) if camera.type_ == Checked::Valid(CameraType::Orthographic) => problems
                .push("its type is orthographic but it has a perspective projection".to_owned()),
            (None, Some(_)) if camera.type_ == Checked::Valid(CameraType::Perspective) => problems
                .push("its type is perspective but it has an orthographic projection".to_owned()),
            _ => {}
        }
        if let Some(p) = &camera.perspective {
            if !greater(p.yfov, 0.0) {
                problems.push(format!("yfov {} is not positive", p.yfov));
            }
            if let Some(a) = p.aspect_ratio.filter(|&a| !greater(a, 0.0)) {
                problems.push(format!("aspectRatio {a} is not positive"));
            }
            if !greater(p.znear, 0.0) {
                problems.push(format!("znear {} is not positive", p.znear));
            }
            if let Some(f) = p.zfar.filter(|&f| !greater(f, p.znear)) {
                problems.push(format!("zfar {f} is not greater than znear {}", p.znear));
            }
        }
        if let Some(o) = &camera.orthographic {
            if o.xmag == 0.0 || o.ymag == 0.0 {
                problems.push(format!(
                    "xmag {} and ymag {} must not be zero",
                    o.xmag, o.ymag
                ));
            }
            if o.znear.is_nan() || o.znear < 0.0 {
                problems.push(format!("znear {} is negative", o.znear));
            }
            if !greater(o.zfar, o.znear) {
                problems.push(format!(
                    "zfar {} is not greater than znear {}",
                    o.zfar, o.znear
                ));
            }
        }
        if !problems.is_empty() {
            report.add(format!(
                "{}: {}",
                named("camera", c, camera.name.as_deref()),
                problems.join("; ")
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trs_matrices_decompose_and_sheared_ones_do_not() {
        let trs = Mat4::from_scale_rotation_translation(
            glam::Vec3::new(2.0, 3.0, -1.0),
            Quat::from_rotation_y(0.7),
            glam::Vec3::new(1.0, 2.0, 3.0),
        );
        assert!(decomposable(&trs.to_cols_array()));
        assert!(decomposable(&Mat4::IDENTITY.to_cols_array()));
        let mut sheared = Mat4::IDENTITY.to_cols_array();
        sheared[4] = 0.5;
        assert!(!decomposable(&sheared));
        assert!(!decomposable(&[1.0; 16]));
        assert!(!decomposable(&[0.0; 16]));
    }

    #[test]
    fn data_uri_media_types() {
        assert_eq!(
            media_type("application/octet-stream;base64"),
            Ok("application/octet-stream")
        );
        assert!(media_type("application/octet-stream;;base64").is_err());
        assert_eq!(media_type("image/png;charset=x;base64"), Ok("image/png"));
        assert_eq!(data_uri_header("data:a/b;base64,AAAA"), Some("a/b;base64"));
        assert_eq!(data_uri_header("x.bin"), None);
    }
}
