//! Wavefront OBJ geometry, read the same way by Kiln's host (the meshes a `.kiln` scene
//! references) and by the OBJ importer plugin (`kiln-obj`), and written the way saved
//! scenes store their meshes.
//!
//! Kiln writes *aligned* files: one mesh without materials in which vertex `i` has
//! position `v` number `i`, texture coordinate `vt` number `i` and normal `vn` number
//! `i`, so faces read `f 3/3/3 …`; vertex colours follow the position
//! (`v x y z r g b`, the extension most tools read). What OBJ cannot say goes in comment
//! lines other readers skip (as ZBrush's `#MRGB` does): `#kiln uv1 u v` (the second UV
//! set, one line per vertex) and `#kiln alpha a` (colour alpha, one line per vertex,
//! written only when some alpha is not 1). Floats are written with Rust's `Display`, the
//! shortest text that parses back to the same `f32`.
//!
//! [`read_obj`] reads an aligned file as written (vertex order, unused vertices and the
//! `#kiln` lines kept), so a saved mesh reloads exactly. Any other file (objects, groups,
//! materials, polygons, corners whose indices differ) goes through tobj: one mesh per
//! object or group, split further where the material changes, vertices numbered by first
//! use in the faces, polygons triangulated as fans, points and lines skipped.
//!
//! Not here: turning MTL materials into Kiln's (the plugin's `mtl` module) and building a
//! scene from the meshes (the host's scene loader, the plugin's builder calls).

use std::cell::RefCell;
use std::path::Path;

use kiln_plugin_api::read::{MAX_FILE_BYTES, read_bounded};

/// An MTL material, as tobj parses it.
pub use tobj::Material;

/// The name tobj gives geometry before any `o` or `g` statement; an aligned file's mesh
/// has it too.
pub const UNNAMED_OBJECT: &str = "unnamed_object";

/// One mesh of an OBJ file. Each attribute is given for every vertex or is empty.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjMesh {
    /// The object or group name (`object N` for an empty one).
    pub name: String,
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub uvs: Vec<[f32; 2]>,
    /// The second UV set (`#kiln uv1` lines of an aligned file).
    pub uvs1: Vec<[f32; 2]>,
    /// RGBA; alpha from `#kiln alpha` lines of an aligned file, else 1.
    pub colors: Vec<[f32; 4]>,
    pub indices: Vec<[u32; 3]>,
    /// Index into [`ObjFile::materials`].
    pub material: Option<usize>,
}

/// An OBJ file's meshes and materials.
#[derive(Clone, Debug, Default)]
pub struct ObjFile {
    /// Every object with at least one face, in file order.
    pub meshes: Vec<ObjMesh>,
    /// The materials of every MTL library the file names that could be read.
    pub materials: Vec<Material>,
    /// What was left out: material libraries that could not be read, attributes given
    /// for only some vertices of an object, objects without faces.
    pub warnings: Vec<String>,
}

/// Reads an OBJ file (see the module's documentation for aligned files and the rest).
/// MTL libraries are read relative to the file's folder; one that cannot be read is a
/// warning. A file that cannot be read or parsed, or holds no faces, is an error naming
/// `path`.
pub fn read_obj(path: &Path) -> Result<ObjFile, String> {
    let fail = |message: String| format!("cannot read {}: {message}", path.display());
    let bytes = read_bounded(path, MAX_FILE_BYTES).map_err(|e| fail(e.to_string()))?;
    let file = match std::str::from_utf8(&bytes).ok().and_then(read_aligned) {
        Some(mesh) => ObjFile {
            meshes: vec![mesh],
            ..ObjFile::default()
        },
        None => read_with_tobj(&bytes, path.parent().unwrap_or(Path::new(""))).map_err(fail)?,
    };
    if file.meshes.iter().all(|m| m.indices.is_empty()) {
        return Err(format!("{} holds no faces", path.display()));
    }
    Ok(file)
}

/// Groups of `N` floats, or `None` (with a warning) if `data` does not hold one group
/// per vertex.
fn per_vertex<const N: usize>(
    data: &[f32],
    vertices: usize,
    what: &str,
    mesh: &str,
    warnings: &mut Vec<String>,
) -> Vec<[f32; N]> {
    if data.is_empty() {
        return Vec::new();
    }
    if data.len() != vertices * N {
        warnings.push(format!(
            "object \"{mesh}\": {what} are given for only some vertices; dropped"
        ));
        return Vec::new();
    }
    data.chunks_exact(N)
        .map(|c| std::array::from_fn(|i| c[i]))
        .collect()
}

/// The colour statements of MTL text (`Ka`, `Kd`, `Ks`, `Ke`) as tobj can read them: it
/// panics on fewer than three numbers. One number is the grey the MTL specification makes
/// of it (`Kd 0.5` is `Kd 0.5 0.5 0.5`); none or two are dropped with a warning naming
/// the line. Lines are split as tobj splits them (at `\n`, each checked as UTF-8 on its
/// own: tobj reads the lines before one that is not, then fails), and the others are
/// passed on unchanged.
fn colours_tobj_reads(bytes: &[u8], library: &Path, warnings: &mut Vec<String>) -> Vec<u8> {
    let mut fixed = Vec::with_capacity(bytes.len());
    for (number, line) in bytes.split(|&b| b == b'\n').enumerate() {
        if number > 0 {
            fixed.push(b'\n');
        }
        let Ok(text) = std::str::from_utf8(line) else {
            fixed.extend_from_slice(line);
            continue;
        };
        let mut words = text.split_whitespace();
        let keyword = words.next();
        let values: Vec<&str> = words.take(3).collect();
        match (keyword, values.as_slice()) {
            (Some(k @ ("Ka" | "Kd" | "Ks" | "Ke")), [grey]) => {
                fixed.extend_from_slice(format!("{k} {grey} {grey} {grey}").as_bytes());
            }
            (Some("Ka" | "Kd" | "Ks" | "Ke"), [] | [_, _]) => warnings.push(format!(
                "material library {} line {}: \"{}\" needs one number or three (r g b); ignored",
                library.display(),
                number + 1,
                text.trim(),
            )),
            _ => fixed.extend_from_slice(line),
        }
    }
    fixed
}

/// Checks every vertex index of the faces, lines and points against the vertices, texture
/// coordinates and normals that exist, before tobj sees them: it turns a relative index
/// reaching before the first element, or an absolute one past the last, into an index
/// whose arithmetic overflows. Errors name the line, as tobj's do not. Lines that are not
/// UTF-8 or whose indices are not numbers are left to tobj, which refuses them.
fn check_indices(bytes: &[u8]) -> Result<(), String> {
    const KINDS: [(&str, &str); 3] = [
        ("v", "vertex"),
        ("vt", "texture coordinate"),
        ("vn", "normal"),
    ];
    let lines = || {
        bytes
            .split(|&b| b == b'\n')
            .enumerate()
            .filter_map(|(n, line)| Some((n + 1, std::str::from_utf8(line).ok()?)))
    };
    let count = |line: &str, totals: &mut [usize; 3]| {
        let keyword = line.split_whitespace().next();
        if let Some(kind) = KINDS.iter().position(|(k, _)| Some(*k) == keyword) {
            totals[kind] += 1;
        }
    };
    let mut totals = [0; 3];
    for (_, line) in lines() {
        count(line, &mut totals);
    }
    let mut so_far = [0; 3];
    for (number, line) in lines() {
        count(line, &mut so_far);
        let mut words = line.split_whitespace();
        if !matches!(words.next(), Some("f" | "l" | "p")) {
            continue;
        }
        for corner in words {
            for (kind, index) in corner.split('/').enumerate().take(3) {
                let Ok(index) = index.parse::<isize>() else {
                    continue;
                };
                let (available, reachable) = if index < 0 {
                    (so_far[kind], index.unsigned_abs() <= so_far[kind])
                } else {
                    (
                        totals[kind],
                        index != 0 && index.unsigned_abs() <= totals[kind],
                    )
                };
                if !reachable {
                    return Err(format!(
                        "line {number}: index {index} refers to no {} (the file has {available}{})",
                        KINDS[kind].1,
                        if index < 0 { " before this line" } else { "" },
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Any OBJ text, through tobj; `dir` is where its MTL libraries are looked for.
fn read_with_tobj(bytes: &[u8], dir: &Path) -> Result<ObjFile, String> {
    check_indices(bytes)?;
    // tobj's optional features add fields; another crate of the build may turn them on.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // tobj takes the library loader as `Fn`.
    let library_warnings = RefCell::new(Vec::new());
    let (models, materials) = tobj::load_obj_buf(&mut &bytes[..], &options, |library| {
        let full = dir.join(library);
        let loaded = read_bounded(&full, MAX_FILE_BYTES)
            .map_err(|e| e.to_string())
            .and_then(|bytes| {
                let mut warnings = library_warnings.borrow_mut();
                let text = colours_tobj_reads(&bytes, &full, &mut warnings);
                tobj::load_mtl_buf(&mut text.as_slice()).map_err(|e| e.to_string())
            });
        loaded.or_else(|reason| {
            library_warnings.borrow_mut().push(format!(
                "material library {} not loaded ({reason}); its materials are grey",
                full.display()
            ));
            // An empty library: the file's other libraries still load.
            tobj::load_mtl_buf(&mut &b""[..])
        })
    })
    .map_err(|e| e.to_string())?;
    let mut file = ObjFile {
        // Every library either loaded or was replaced by an empty one above.
        materials: materials.unwrap_or_default(),
        warnings: library_warnings.into_inner(),
        ..ObjFile::default()
    };
    for (index, model) in models.into_iter().enumerate() {
        let m = model.mesh;
        let name = if model.name.is_empty() {
            format!("object {index}")
        } else {
            model.name
        };
        if m.indices.is_empty() {
            file.warnings.push(format!(
                "object \"{name}\" has no faces (points and lines are not rendered)"
            ));
            continue;
        }
        let positions: Vec<[f32; 3]> = m
            .positions
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2]])
            .collect();
        let n = positions.len();
        let warnings = &mut file.warnings;
        let normals = per_vertex::<3>(&m.normals, n, "normals", &name, warnings);
        let uvs = per_vertex::<2>(&m.texcoords, n, "texture coordinates", &name, warnings);
        let colors = per_vertex::<3>(&m.vertex_color, n, "vertex colours", &name, warnings)
            .into_iter()
            .map(|[r, g, b]| [r, g, b, 1.0])
            .collect();
        file.meshes.push(ObjMesh {
            name,
            positions,
            normals,
            uvs,
            uvs1: Vec::new(),
            colors,
            indices: m
                .indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
            material: m.material_id.filter(|&id| id < file.materials.len()),
        });
    }
    Ok(file)
}

/// The mesh of an aligned OBJ text, or `None` where the text is anything else (objects,
/// groups, materials, polygons, lines, points, corners whose indices differ, relative
/// indices, attribute counts that do not match the positions, a malformed line): such
/// files are tobj's.
fn read_aligned(text: &str) -> Option<ObjMesh> {
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
    let mut mesh = ObjMesh {
        name: UNNAMED_OBJECT.to_owned(),
        ..ObjMesh::default()
    };
    let mut rgb = Vec::new();
    let mut alpha = Vec::new();
    // Which of (texture coordinate, normal) every corner names; set by the first face.
    let mut corner_form = None;
    for line in text.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some((&keyword, args)) = words.split_first() else {
            continue;
        };
        match keyword {
            "v" if args.len() == 6 => {
                let [x, y, z, r, g, b] = floats(args)?;
                mesh.positions.push([x, y, z]);
                rgb.push([r, g, b]);
            }
            "v" => mesh.positions.push(floats::<3>(args)?),
            "vt" => mesh.uvs.push(floats::<2>(args)?),
            "vn" => mesh.normals.push(floats::<3>(args)?),
            "#kiln" => match args.split_first()? {
                (&"uv1", uv) => mesh.uvs1.push(floats::<2>(uv)?),
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
                mesh.indices.push(triangle);
            }
            // Smoothing groups carry nothing Kiln reads.
            "s" => {}
            _ if keyword.starts_with('#') => {}
            // Objects, groups and materials (`o`, `g`, `usemtl`, `mtllib`) split the
            // file into meshes: tobj's.
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
        || mesh.indices.iter().flatten().any(|&i| i as usize >= count)
    {
        return None;
    }
    mesh.colors = rgb
        .iter()
        .enumerate()
        .map(|(i, &[r, g, b])| [r, g, b, alpha.get(i).copied().unwrap_or(1.0)])
        .collect();
    Some(mesh)
}

/// Writes `mesh` as an aligned OBJ file (see the module's documentation), atomically;
/// its name goes in the header comment, its material nowhere.
pub fn write_obj(mesh: &ObjMesh, path: &Path) -> Result<(), String> {
    kiln_plugin_api::atomic::write_atomically(path, |out| {
        write_aligned(mesh, out).map_err(|e| e.to_string())
    })
}

fn write_aligned(mesh: &ObjMesh, out: &mut impl std::io::Write) -> std::io::Result<()> {
    writeln!(
        out,
        "# {} (written by Kiln; vertices are aligned)",
        mesh.name
    )?;
    let colors = mesh.colors.len() == mesh.positions.len();
    for (i, [x, y, z]) in mesh.positions.iter().enumerate() {
        match mesh.colors.get(i).filter(|_| colors) {
            Some([r, g, b, _]) => writeln!(out, "v {x} {y} {z} {r} {g} {b}")?,
            None => writeln!(out, "v {x} {y} {z}")?,
        }
    }
    if colors && mesh.colors.iter().any(|c| c[3] != 1.0) {
        for c in &mesh.colors {
            writeln!(out, "#kiln alpha {}", c[3])?;
        }
    }
    for [u, v] in &mesh.uvs {
        writeln!(out, "vt {u} {v}")?;
    }
    for [u, v] in &mesh.uvs1 {
        writeln!(out, "#kiln uv1 {u} {v}")?;
    }
    for [x, y, z] in &mesh.normals {
        writeln!(out, "vn {x} {y} {z}")?;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A mesh whose faces use its vertices out of order, with one vertex no face uses and
    /// every attribute, including those OBJ has no statement for.
    fn every_attribute() -> ObjMesh {
        ObjMesh {
            name: UNNAMED_OBJECT.into(),
            positions: vec![
                [0.1, -0.0, 1e-7],
                [1.0, 2.5, -3.25],
                [0.3, 1e20, 7.0],
                [5.0, 5.0, 5.0],
            ],
            normals: vec![
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [0.0, 0.0, -1.0],
            ],
            uvs: vec![[0.1, 0.2], [1.0, 1.0], [0.0, 0.0], [0.7, 1.0 / 3.0]],
            uvs1: vec![[0.9, 0.8], [0.0, 0.0], [1.0, 1.0], [1.0 / 7.0, 2.0]],
            colors: vec![
                [1.0, 0.0, 0.0, 0.5],
                [1.0; 4],
                [0.2, 0.4, 0.6, 0.0],
                [0.1, 0.1, 0.1, 1.0],
            ],
            indices: vec![[2, 0, 1], [1, 2, 2]],
            material: None,
        }
    }

    fn read_back(mesh: &ObjMesh) -> ObjMesh {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.obj");
        write_obj(mesh, &path).unwrap();
        let mut file = read_obj(&path).unwrap();
        assert_eq!(file.meshes.len(), 1);
        assert!(file.warnings.is_empty(), "{:?}", file.warnings);
        file.meshes.remove(0)
    }

    /// Found by fuzzing (fuzz/regressions/obj/): tobj panicked on a colour statement with
    /// fewer than three numbers.
    #[test]
    fn mtl_colours_with_one_number_are_grey_and_with_two_are_dropped_with_a_warning() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("m.mtl"),
            b"newmtl grey\nKd 0.25\nnewmtl odd\nKd 0.5 0.5\nKs\nKe 1 2 3\n",
        )
        .unwrap();
        let obj = "mtllib m.mtl\nusemtl odd\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        let file = read_with_tobj(obj.as_bytes(), dir.path()).unwrap();
        let [grey, odd] = file.materials.as_slice() else {
            panic!("two materials: {:?}", file.materials);
        };
        assert_eq!(grey.diffuse, Some([0.25; 3]));
        assert_eq!((odd.diffuse, odd.specular), (None, None));
        assert_eq!(odd.emissive, Some([1.0, 2.0, 3.0]));
        assert_eq!(file.warnings.len(), 2, "{:?}", file.warnings);
        assert!(
            file.warnings[0].contains("line 4: \"Kd 0.5 0.5\" needs one number or three"),
            "{}",
            file.warnings[0]
        );
        assert!(
            file.warnings[1].contains("line 5: \"Ks\""),
            "{}",
            file.warnings[1]
        );
    }

    /// Found by fuzzing too: a line that is not UTF-8 after the bad colour. tobj parses
    /// the lines before it, then refuses the library.
    #[test]
    fn a_bad_colour_before_a_line_that_is_not_utf8_does_not_panic() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("m.mtl"), b"newmtl a\nKd 0.5 0.5\n\xff\n").unwrap();
        let file = read_with_tobj(b"mtllib m.mtl\nv 0 0 0\n", dir.path()).unwrap();
        assert!(file.materials.is_empty());
        assert!(
            file.warnings.iter().any(|w| w.contains("not loaded")),
            "{:?}",
            file.warnings
        );
    }

    /// Found by fuzzing (fuzz/regressions/obj/): a relative index before the first texture
    /// coordinate overflowed tobj's index arithmetic.
    #[test]
    fn face_indices_that_reach_no_element_are_refused_naming_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let refused = |obj: &str| read_with_tobj(obj.as_bytes(), dir.path()).unwrap_err();
        let v = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n";
        assert_eq!(
            refused(&format!("{v}f 1/-3 2/1 3/1\n")),
            "line 5: index -3 refers to no texture coordinate (the file has 1 before this line)"
        );
        assert_eq!(
            refused(&format!("{v}f 1 2 4\n")),
            "line 5: index 4 refers to no vertex (the file has 3)"
        );
        assert!(refused(&format!("{v}f 0 1 2\n")).contains("index 0 refers to no vertex"));
        assert!(refused(&format!("{v}f 1//9223372036854775807 2 3\n")).contains("no normal"));
        // Relative and forward absolute indices that exist are read.
        let file = read_with_tobj(
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nf 1 2 4\nv 1 1 0\n",
            dir.path(),
        )
        .unwrap();
        assert_eq!(file.meshes[0].indices.len(), 2);
    }

    #[test]
    fn written_mesh_reads_back_exactly() {
        let mesh = every_attribute();
        assert_eq!(read_back(&mesh), mesh);
    }

    #[test]
    fn written_mesh_without_optional_attributes_reads_back_exactly() {
        let mut mesh = every_attribute();
        mesh.uvs.clear();
        mesh.normals.clear();
        assert_eq!(read_back(&mesh), mesh);
        mesh.colors.clear();
        mesh.uvs1.clear();
        assert_eq!(read_back(&mesh), mesh);
    }

    #[test]
    fn tobj_reads_the_standard_part_of_a_written_file() {
        // Another reader sees the geometry and RGB colours and skips the `#kiln` lines.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.obj");
        let mesh = every_attribute();
        write_obj(&mesh, &path).unwrap();
        let other = read_with_tobj(&std::fs::read(&path).unwrap(), dir.path()).unwrap();
        let other = &other.meshes[0];
        assert_eq!(other.indices.len(), 2);
        assert!(other.uvs1.is_empty());
        // tobj numbers vertices by first use: 2, 0, 1.
        assert_eq!(
            other.positions,
            vec![mesh.positions[2], mesh.positions[0], mesh.positions[1]]
        );
        let [r, g, b, _] = mesh.colors[2];
        assert_eq!(other.colors[0], [r, g, b, 1.0]);
    }

    #[test]
    fn unaligned_polygon_and_material_files_go_through_tobj() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("q.obj");
        // A quad whose corners name different position and texture indices.
        let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\nf 1/2 2/1 3/2 4/1\n";
        std::fs::write(&path, quad).unwrap();
        assert!(read_aligned(quad).is_none());
        let file = read_obj(&path).unwrap();
        let mesh = &file.meshes[0];
        assert_eq!(mesh.indices.len(), 2, "the quad is two triangles");
        assert_eq!(mesh.uvs.len(), mesh.positions.len());
        // Aligned indices, but two objects with materials: one mesh each.
        let objects =
            "mtllib none.mtl\no a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\no b\nf 3 2 1\n";
        assert!(read_aligned(objects).is_none());
        std::fs::write(&path, objects).unwrap();
        let file = read_obj(&path).unwrap();
        let names: Vec<&str> = file.meshes.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["a", "b"]);
        assert!(
            file.warnings.iter().any(|w| w.contains("none.mtl")),
            "{:?}",
            file.warnings
        );
    }

    #[test]
    fn files_without_faces_are_errors_naming_them() {
        let dir = tempfile::tempdir().unwrap();
        for (name, text) in [("empty.obj", ""), ("points.obj", "v 0 0 0\np 1\n")] {
            let path = dir.path().join(name);
            std::fs::write(&path, text).unwrap();
            let e = read_obj(&path).unwrap_err();
            assert!(e.contains(name) && e.contains("no faces"), "{e}");
        }
        let e = read_obj(&dir.path().join("missing.obj")).unwrap_err();
        assert!(e.contains("missing.obj"), "{e}");
    }
}
