//! The OBJ files of a scene file's `Obj(...)` meshes, through the reader and writer the
//! OBJ importer plugin uses (`kiln_formats::obj`, which documents the format): reading
//! one into a [`Mesh`] (every object of the file becomes part of one mesh) and writing a
//! [`Mesh`] out, which is how saved scenes store their meshes. A mesh Kiln wrote reads
//! back exactly, vertex order and all.
//!
//! Not here: OBJ materials and scene structure, which the OBJ importer plugin
//! (`plugins/obj`) handles; a scene file's `Obj(...)` mesh is geometry only.

use std::path::Path;

use glam::{Vec2, Vec3, Vec4};
use kiln_formats::obj::{ObjMesh, read_obj};

use super::Mesh;

/// Loads every object of an OBJ file into one mesh (materials are ignored). An attribute
/// is kept only where every object has it for every vertex.
pub(super) fn load_obj(path: &Path) -> Result<Mesh, String> {
    let file = read_obj(path)?;
    let all = |has: fn(&ObjMesh) -> bool| file.meshes.iter().all(has);
    let (normals, uvs, uvs1, colors) = (
        all(|m| !m.normals.is_empty()),
        all(|m| !m.uvs.is_empty()),
        all(|m| !m.uvs1.is_empty()),
        all(|m| !m.colors.is_empty()),
    );
    let mut mesh = Mesh::default();
    for m in &file.meshes {
        let base = mesh.positions.len() as u32;
        mesh.positions
            .extend(m.positions.iter().map(|&p| Vec3::from(p)));
        if normals {
            mesh.normals
                .extend(m.normals.iter().map(|&n| Vec3::from(n)));
        }
        if uvs {
            mesh.uvs.extend(m.uvs.iter().map(|&t| Vec2::from(t)));
        }
        if uvs1 {
            mesh.uvs1.extend(m.uvs1.iter().map(|&t| Vec2::from(t)));
        }
        if colors {
            mesh.colors.extend(m.colors.iter().map(|&c| Vec4::from(c)));
        }
        mesh.indices
            .extend(m.indices.iter().map(|t| t.map(|i| base + i)));
    }
    Ok(mesh)
}

/// Writes `mesh` as an aligned OBJ file, atomically.
pub(super) fn write_obj(mesh: &Mesh, path: &Path) -> Result<(), String> {
    let obj = ObjMesh {
        name: mesh.name.clone(),
        positions: mesh.positions.iter().map(|p| p.to_array()).collect(),
        normals: mesh.normals.iter().map(|n| n.to_array()).collect(),
        uvs: mesh.uvs.iter().map(|t| t.to_array()).collect(),
        uvs1: mesh.uvs1.iter().map(|t| t.to_array()).collect(),
        colors: mesh.colors.iter().map(|c| c.to_array()).collect(),
        indices: mesh.indices.clone(),
        material: None,
    };
    kiln_formats::obj::write_obj(&obj, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mesh whose faces use its vertices out of order, with one vertex no face uses and
    /// every attribute, including those OBJ has no statement for.
    fn every_attribute() -> Mesh {
        Mesh {
            name: "all".into(),
            positions: vec![
                Vec3::new(0.1, -0.0, 1e-7),
                Vec3::new(1.0, 2.5, -3.25),
                Vec3::new(0.3, 1e20, 7.0),
                Vec3::new(5.0, 5.0, 5.0),
            ],
            normals: vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::NEG_Z],
            uvs: vec![
                Vec2::new(0.1, 0.2),
                Vec2::ONE,
                Vec2::ZERO,
                Vec2::new(0.7, 1.0 / 3.0),
            ],
            uvs1: vec![
                Vec2::new(0.9, 0.8),
                Vec2::ZERO,
                Vec2::ONE,
                Vec2::new(1.0 / 7.0, 2.0),
            ],
            colors: vec![
                Vec4::new(1.0, 0.0, 0.0, 0.5),
                Vec4::ONE,
                Vec4::new(0.2, 0.4, 0.6, 0.0),
                Vec4::new(0.1, 0.1, 0.1, 1.0),
            ],
            indices: vec![[2, 0, 1], [1, 2, 2]],
        }
    }

    #[test]
    fn written_mesh_reads_back_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.obj");
        let mesh = every_attribute();
        write_obj(&mesh, &path).unwrap();
        let back = load_obj(&path).unwrap();
        assert_eq!(
            back,
            Mesh {
                name: String::new(),
                ..mesh
            }
        );
    }

    #[test]
    fn written_mesh_without_optional_attributes_reads_back_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.obj");
        let mut mesh = every_attribute();
        mesh.name.clear();
        mesh.uvs.clear();
        mesh.normals.clear();
        write_obj(&mesh, &path).unwrap();
        assert_eq!(load_obj(&path).unwrap(), mesh);
        mesh.colors.clear();
        mesh.uvs1.clear();
        write_obj(&mesh, &path).unwrap();
        assert_eq!(load_obj(&path).unwrap(), mesh);
    }

    #[test]
    fn objects_merge_into_one_mesh_keeping_only_attributes_all_of_them_have() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("two.obj");
        // Object a has texture coordinates, object b none.
        std::fs::write(
            &path,
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
             o a\nf 1/1 2/2 3/3\no b\nf 2 4 3\n",
        )
        .unwrap();
        let mesh = load_obj(&path).unwrap();
        assert_eq!(mesh.positions.len(), 6);
        assert_eq!(mesh.indices, vec![[0, 1, 2], [3, 4, 5]]);
        assert_eq!(mesh.positions[3], Vec3::X);
        assert!(mesh.uvs.is_empty());
    }
}
