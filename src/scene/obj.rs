//! Wavefront OBJ mesh files as the scene file uses them: reading one into a [`Mesh`]
//! (every shape of the file becomes one mesh) and writing a [`Mesh`] out.
//!
//! Not here: OBJ materials and scene structure, which the OBJ importer plugin
//! (`plugins/obj`) handles; a scene file's `Obj(...)` mesh is geometry only.

use std::path::Path;

use glam::{Vec2, Vec3};

use super::Mesh;

/// Loads every shape of an OBJ file into one mesh (materials are ignored for now).
pub(super) fn load_obj(path: &Path) -> Result<Mesh, String> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj(path, &options).map_err(|e| e.to_string())?;
    let mut mesh = Mesh::default();
    let mut all_have_normals = true;
    let mut all_have_uvs = true;
    let mut all_have_colors = true;
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        let count = m.positions.len() / 3;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        all_have_normals &= m.normals.len() == count * 3;
        all_have_uvs &= m.texcoords.len() == count * 2;
        if all_have_normals {
            mesh.normals.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|n| Vec3::new(n[0], n[1], n[2])),
            );
        }
        if all_have_uvs {
            mesh.uvs
                .extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], t[1])));
        }
        // Colours after the position (`v x y z r g b`), an extension many tools write.
        all_have_colors &= m.vertex_color.len() == count * 3;
        if all_have_colors {
            mesh.colors.extend(
                m.vertex_color
                    .chunks_exact(3)
                    .map(|c| glam::Vec4::new(c[0], c[1], c[2], 1.0)),
            );
        }
        mesh.indices.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    if !all_have_normals {
        mesh.normals.clear();
    }
    if !all_have_uvs {
        mesh.uvs.clear();
    }
    if !all_have_colors {
        mesh.colors.clear();
    }
    Ok(mesh)
}

/// A mesh as an OBJ file (positions, UVs, normals, triangles).
pub(super) fn write_obj(mesh: &crate::scene::Mesh, path: &Path) -> std::io::Result<()> {
    use std::io::Write;
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(out, "# {} (written by Kiln)", mesh.name)?;
    for (i, p) in mesh.positions.iter().enumerate() {
        match mesh.colors.get(i) {
            Some(c) => writeln!(out, "v {} {} {} {} {} {}", p.x, p.y, p.z, c.x, c.y, c.z)?,
            None => writeln!(out, "v {} {} {}", p.x, p.y, p.z)?,
        }
    }
    for t in &mesh.uvs {
        writeln!(out, "vt {} {}", t.x, t.y)?;
    }
    for n in &mesh.normals {
        writeln!(out, "vn {} {} {}", n.x, n.y, n.z)?;
    }
    let (uv, n) = (!mesh.uvs.is_empty(), !mesh.normals.is_empty());
    for t in &mesh.indices {
        let v = |i: u32| {
            let i = i + 1;
            match (uv, n) {
                (true, true) => format!("{i}/{i}/{i}"),
                (true, false) => format!("{i}/{i}"),
                (false, true) => format!("{i}//{i}"),
                (false, false) => format!("{i}"),
            }
        };
        writeln!(out, "f {} {} {}", v(t[0]), v(t[1]), v(t[2]))?;
    }
    out.flush()
}
