//! Wavefront OBJ mesh files as the scene file uses them: reading one into a [`Mesh`]
//! (every shape of the file becomes one mesh) and writing a [`Mesh`] out, which is how
//! saved scenes store their meshes.
//!
//! Kiln writes *aligned* files: vertex `i` has position `v` number `i`, texture
//! coordinate `vt` number `i` and normal `vn` number `i`, so faces read `f 3/3/3 …`; vertex
//! colours follow the position (`v x y z r g b`, the extension most tools read). What OBJ
//! cannot say goes in comment lines other readers skip (as ZBrush's `#MRGB` does):
//! `#kiln uv1 u v` (the second UV set, one line per vertex) and `#kiln alpha a` (colour
//! alpha, one line per vertex, written only when some alpha is not 1). Floats are written
//! with Rust's `Display`, the shortest text that parses back to the same `f32`.
//!
//! Not here: OBJ materials and scene structure, which the OBJ importer plugin
//! (`plugins/obj`) handles; a scene file's `Obj(...)` mesh is geometry only.

use std::path::Path;

use glam::{Vec2, Vec3, Vec4};

use super::Mesh;

/// Loads every shape of an OBJ file into one mesh (materials are ignored for now).
///
/// A file whose vertices are aligned, as Kiln writes them, is read as written (vertex
/// order, unused vertices and the `#kiln` lines kept), so a saved mesh reloads exactly;
/// any other goes through tobj, which numbers vertices by first use in the faces and
/// triangulates polygons as fans.
pub(super) fn load_obj(path: &Path) -> Result<Mesh, String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    if let Some(mesh) = std::str::from_utf8(&bytes).ok().and_then(read_aligned) {
        return Ok(mesh);
    }
    load_with_tobj(path)
}

fn load_with_tobj(path: &Path) -> Result<Mesh, String> {
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
                    .map(|c| Vec4::new(c[0], c[1], c[2], 1.0)),
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

/// Writes `mesh` as an aligned OBJ file (see the module's documentation), atomically.
pub(super) fn write_obj(mesh: &Mesh, path: &Path) -> Result<(), String> {
    kiln_plugin_api::atomic::write_atomically(path, |out| {
        write_aligned(mesh, out).map_err(|e| e.to_string())
    })
}

fn write_aligned(mesh: &Mesh, out: &mut impl std::io::Write) -> std::io::Result<()> {
    writeln!(
        out,
        "# {} (written by Kiln; vertices are aligned)",
        mesh.name
    )?;
    let colors = mesh.colors.len() == mesh.positions.len();
    for (i, p) in mesh.positions.iter().enumerate() {
        match mesh.colors.get(i).filter(|_| colors) {
            Some(c) => writeln!(out, "v {} {} {} {} {} {}", p.x, p.y, p.z, c.x, c.y, c.z)?,
            None => writeln!(out, "v {} {} {}", p.x, p.y, p.z)?,
        }
    }
    if colors && mesh.colors.iter().any(|c| c.w != 1.0) {
        for c in &mesh.colors {
            writeln!(out, "#kiln alpha {}", c.w)?;
        }
    }
    for t in &mesh.uvs {
        writeln!(out, "vt {} {}", t.x, t.y)?;
    }
    for t in &mesh.uvs1 {
        writeln!(out, "#kiln uv1 {} {}", t.x, t.y)?;
    }
    for n in &mesh.normals {
        writeln!(out, "vn {} {} {}", n.x, n.y, n.z)?;
    }
    let (uv, n) = (!mesh.uvs.is_empty(), !mesh.normals.is_empty());
    for t in &mesh.indices {
        let v = |i: u32| {
            let i = u64::from(i) + 1;
            match (uv, n) {
                (true, true) => format!("{i}/{i}/{i}"),
                (true, false) => format!("{i}/{i}"),
                (false, true) => format!("{i}//{i}"),
                (false, false) => format!("{i}"),
            }
        };
        writeln!(out, "f {} {} {}", v(t[0]), v(t[1]), v(t[2]))?;
    }
    Ok(())
}

/// The mesh of an aligned OBJ text, or `None` where the text is anything else (polygons,
/// lines, points, corners whose indices differ, relative indices, attribute counts that do
/// not match the positions, a malformed line): such files are tobj's.
fn read_aligned(text: &str) -> Option<Mesh> {
    fn floats<const N: usize>(words: &[&str]) -> Option<[f32; N]> {
        if words.len() != N {
            return None;
        }
        let mut out = [0.0; N];
        for (o, w) in out.iter_mut().zip(words) {
            *o = w.parse().ok()?;
        }
        Some(out)
    }
    let mut mesh = Mesh::default();
    let mut rgb = Vec::new();
    let mut alpha = Vec::new();
    // Which of (texture coordinate, normal) every corner names; set by the first face.
    let mut corner_form = None;
    let mut corners = Vec::new();
    for line in text.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some((&keyword, args)) = words.split_first() else {
            continue;
        };
        match keyword {
            "v" if args.len() == 6 => {
                let [x, y, z, r, g, b] = floats(args)?;
                mesh.positions.push(Vec3::new(x, y, z));
                rgb.push(Vec3::new(r, g, b));
            }
            "v" => mesh.positions.push(Vec3::from(floats::<3>(args)?)),
            "vt" => mesh.uvs.push(Vec2::from(floats::<2>(args)?)),
            "vn" => mesh.normals.push(Vec3::from(floats::<3>(args)?)),
            "#kiln" => match args.split_first()? {
                (&"uv1", uv) => mesh.uvs1.push(Vec2::from(floats::<2>(uv)?)),
                (&"alpha", a) => alpha.push(floats::<1>(a)?[0]),
                _ => return None,
            },
            "f" => {
                if args.len() != 3 {
                    return None;
                }
                let mut triangle = [0u32; 3];
                for (corner, word) in triangle.iter_mut().zip(args) {
                    let parts: Vec<&str> = word.split('/').collect();
                    let form = match parts.as_slice() {
                        [_] => (false, false),
                        [_, t] => (!t.is_empty(), false),
                        [_, t, _] => (!t.is_empty(), true),
                        _ => return None,
                    };
                    if *corner_form.get_or_insert(form) != form {
                        return None;
                    }
                    let index: u32 = parts[0].parse().ok()?;
                    if index == 0
                        || parts
                            .iter()
                            .skip(1)
                            .any(|p| !p.is_empty() && *p != parts[0])
                    {
                        return None;
                    }
                    *corner = index - 1;
                }
                corners.push(triangle);
            }
            // Grouping and materials carry no geometry.
            "o" | "g" | "s" | "usemtl" | "mtllib" => {}
            _ if keyword.starts_with('#') => {}
            _ => return None,
        }
    }
    let count = mesh.positions.len();
    let (has_uvs, has_normals) = corner_form.unwrap_or((false, false));
    let matches = |n: usize| n == 0 || n == count;
    let (uvs_listed, normals_listed) = (!mesh.uvs.is_empty(), !mesh.normals.is_empty());
    if has_uvs != uvs_listed
        || has_normals != normals_listed
        || !matches(mesh.uvs.len())
        || !matches(mesh.normals.len())
        || !matches(mesh.uvs1.len())
        || !matches(rgb.len())
        || (!alpha.is_empty() && alpha.len() != rgb.len())
    {
        return None;
    }
    mesh.colors = rgb
        .iter()
        .enumerate()
        .map(|(i, c)| c.extend(alpha.get(i).copied().unwrap_or(1.0)))
        .collect();
    mesh.indices = corners;
    Some(mesh)
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
    fn tobj_reads_the_standard_part_of_a_written_file() {
        // Another reader sees the geometry and RGB colours and skips the `#kiln` lines.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.obj");
        let mesh = every_attribute();
        write_obj(&mesh, &path).unwrap();
        let other = load_with_tobj(&path).unwrap();
        assert_eq!(other.indices.len(), 2);
        assert!(other.uvs1.is_empty());
        // tobj numbers vertices by first use: 2, 0, 1.
        assert_eq!(
            other.positions,
            vec![mesh.positions[2], mesh.positions[0], mesh.positions[1]]
        );
        assert_eq!(other.colors[0], mesh.colors[2].truncate().extend(1.0));
    }

    #[test]
    fn unaligned_and_polygon_files_go_through_tobj() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("q.obj");
        // A quad whose corners name different position and texture indices.
        std::fs::write(
            &path,
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\nf 1/2 2/1 3/2 4/1\n",
        )
        .unwrap();
        assert!(read_aligned(&std::fs::read_to_string(&path).unwrap()).is_none());
        let mesh = load_obj(&path).unwrap();
        assert_eq!(mesh.indices.len(), 2, "the quad is two triangles");
        assert_eq!(mesh.uvs.len(), mesh.positions.len());
    }
}
