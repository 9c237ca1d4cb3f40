//! Mesh primitives as triangle lists: attributes decoded (`accessor`), strips and fans
//! unrolled, non-indexed primitives indexed, UVs flipped to Kiln's v-up convention and
//! indices checked against the vertex count, so the host receives only meshes it accepts.
//!
//! Points and lines are not surfaces and are skipped; morph targets and skins are left
//! in their rest pose (reported by the scene walk).

use gltf::json;
use gltf::json::mesh::{Mode, Semantic};
use gltf::json::validation::Checked;

use crate::accessor::{self, Element};
use crate::buffers::Buffers;

/// One primitive, ready for `Builder::add_mesh`. Optional attributes are empty if absent.
#[derive(Default)]
pub struct Triangles {
    pub name: String,
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub uvs: Vec<[f32; 2]>,
    pub uvs1: Vec<[f32; 2]>,
    pub tangents: Vec<[f32; 4]>,
    pub colors: Vec<[f32; 4]>,
    pub indices: Vec<u32>,
}

/// The name messages use for primitive `p` of mesh `m`.
pub fn primitive_name(root: &json::Root, m: usize, p: usize) -> String {
    let mesh = root.meshes.get(m);
    let base = mesh
        .and_then(|mesh| mesh.name.clone())
        .unwrap_or_else(|| format!("mesh {m}"));
    if mesh.is_some_and(|mesh| mesh.primitives.len() > 1) {
        format!("{base} #{p}")
    } else {
        base
    }
}

fn attribute(primitive: &json::mesh::Primitive, semantic: Semantic) -> Option<usize> {
    primitive
        .attributes
        .get(&Checked::Valid(semantic))
        .map(|i| i.value())
}

/// An optional attribute: empty (with a warning) if it cannot be read or its count
/// differs from the positions'.
fn optional<T: Element>(
    root: &json::Root,
    buffers: &Buffers,
    index: Option<usize>,
    what: &str,
    vertices: usize,
    warnings: &mut Vec<String>,
) -> Vec<T> {
    let Some(index) = index else {
        return Vec::new();
    };
    match accessor::read::<T>(root, buffers, index) {
        Ok(v) if v.len() == vertices => v,
        Ok(v) => {
            warnings.push(format!(
                "{what} has {} entries for {vertices} vertices; left out",
                v.len()
            ));
            Vec::new()
        }
        Err(e) => {
            warnings.push(format!("{what} left out: {e}"));
            Vec::new()
        }
    }
}

/// Reads primitive `p` of mesh `m`. `Err` says why it is skipped; warnings are about
/// what was left out of an otherwise usable primitive.
pub fn read_primitive(
    root: &json::Root,
    buffers: &Buffers,
    m: usize,
    p: usize,
    warnings: &mut Vec<String>,
) -> Result<Triangles, String> {
    let primitive = root
        .meshes
        .get(m)
        .and_then(|mesh| mesh.primitives.get(p))
        .ok_or_else(|| "does not exist".to_owned())?;
    let mode = match primitive.mode {
        Checked::Valid(mode) => mode,
        Checked::Invalid => return Err("has an invalid mode".into()),
    };
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        return Err(format!("is made of {mode:?}, not triangles"));
    }
    let position = attribute(primitive, Semantic::Positions)
        .ok_or_else(|| "has no POSITION attribute".to_owned())?;
    let positions: Vec<[f32; 3]> =
        accessor::read(root, buffers, position).map_err(|e| format!("POSITION: {e}"))?;
    let n = positions.len();
    if n == 0 {
        return Err("has no vertices".into());
    }
    let mut mesh = Triangles {
        positions,
        ..Triangles::default()
    };
    mesh.normals = optional(
        root,
        buffers,
        attribute(primitive, Semantic::Normals),
        "NORMAL",
        n,
        warnings,
    );
    mesh.tangents = optional(
        root,
        buffers,
        attribute(primitive, Semantic::Tangents),
        "TANGENT",
        n,
        warnings,
    );
    // glTF's v runs down the image; Kiln's, like Blender's, up.
    let uv_set = |set: u32, name: &str, warnings: &mut Vec<String>| {
        optional::<[f32; 2]>(
            root,
            buffers,
            attribute(primitive, Semantic::TexCoords(set)),
            name,
            n,
            warnings,
        )
        .into_iter()
        .map(|[u, v]| [u, 1.0 - v])
        .collect()
    };
    mesh.uvs = uv_set(0, "TEXCOORD_0", warnings);
    mesh.uvs1 = uv_set(1, "TEXCOORD_1", warnings);
    if let Some(color) = attribute(primitive, Semantic::Colors(0)) {
        mesh.colors = match accessor::components(root, color) {
            Some(3) => optional::<[f32; 3]>(root, buffers, Some(color), "COLOR_0", n, warnings)
                .into_iter()
                .map(|[r, g, b]| [r, g, b, 1.0])
                .collect(),
            _ => optional(root, buffers, Some(color), "COLOR_0", n, warnings),
        };
    }
    let indices = match primitive.indices {
        Some(i) => {
            accessor::read::<u32>(root, buffers, i.value()).map_err(|e| format!("indices: {e}"))?
        }
        None => (0..n as u32).collect(),
    };
    mesh.indices = triangulate(mode, indices, warnings);
    if mesh.indices.is_empty() {
        return Err("has no triangles".into());
    }
    if let Some(&bad) = mesh.indices.iter().find(|&&i| i as usize >= n) {
        return Err(format!("index {bad} is out of range for {n} vertices"));
    }
    Ok(mesh)
}

/// Triangle-list indices for `mode` (glTF 2.0 §3.7.2.1's definitions of strips and fans).
fn triangulate(mode: Mode, indices: Vec<u32>, warnings: &mut Vec<String>) -> Vec<u32> {
    match mode {
        Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
            .flat_map(|i| {
                let (a, b, c) = (indices[i], indices[i + 1], indices[i + 2]);
                if i % 2 == 0 { [a, b, c] } else { [a, c, b] }
            })
            .collect(),
        Mode::TriangleFan => (1..indices.len().saturating_sub(1))
            .flat_map(|i| [indices[i], indices[i + 1], indices[0]])
            .collect(),
        _ => {
            let mut indices = indices;
            let extra = indices.len() % 3;
            if extra != 0 {
                warnings.push(format!(
                    "{} indices is not a whole number of triangles; the last {extra} dropped",
                    indices.len()
                ));
                indices.truncate(indices.len() - extra);
            }
            indices
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_alternate_winding_and_fans_share_the_first_vertex() {
        let mut w = Vec::new();
        assert_eq!(
            triangulate(Mode::TriangleStrip, vec![0, 1, 2, 3, 4], &mut w),
            vec![0, 1, 2, 1, 3, 2, 2, 3, 4]
        );
        assert_eq!(
            triangulate(Mode::TriangleFan, vec![0, 1, 2, 3], &mut w),
            vec![1, 2, 0, 2, 3, 0]
        );
        assert!(triangulate(Mode::TriangleStrip, vec![0, 1], &mut w).is_empty());
        assert!(w.is_empty());
        assert_eq!(
            triangulate(Mode::Triangles, vec![0, 1, 2, 3], &mut w),
            vec![0, 1, 2]
        );
        assert_eq!(w.len(), 1);
    }
}
