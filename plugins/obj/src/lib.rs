//! Kiln's Wavefront OBJ importer: geometry through `tobj`, materials from the MTL
//! libraries the file names, converted to `.kmat` graphs ([`mtl`]).
//!
//! Each OBJ object or group (split further where its material changes, as tobj does)
//! becomes one mesh and one instance with the identity transform: OBJ has no scene
//! hierarchy, cameras or lights. Polygons are triangulated as fans; points and lines are
//! skipped. Positions, normals and texture coordinates are passed as written (OBJ's v
//! already points up, as Kiln's). A missing MTL library is a warning and its meshes are
//! grey; a mesh without a material gets the host's grey (`u32::MAX`).

pub mod mtl;
pub mod texture;

use std::cell::RefCell;
use std::collections::HashMap;
use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use kiln_plugin_api::{Builder, Importer, Mesh, export_importer};

/// The OBJ importer.
pub struct ObjImport;

/// Column-major identity.
const IDENTITY: [f32; 16] = [
    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
];

/// Groups of `n` floats, or `None` (with a warning) if `data` does not hold one group
/// per vertex.
fn per_vertex<const N: usize>(
    data: &[f32],
    vertices: usize,
    what: &str,
    mesh: &str,
    builder: &mut Builder,
) -> Option<Vec<[f32; N]>> {
    if data.is_empty() {
        return None;
    }
    if data.len() != vertices * N {
        builder.warn(&format!(
            "object \"{mesh}\": {what} are given for only some vertices; dropped"
        ));
        return None;
    }
    Some(
        data.chunks_exact(N)
            .map(|c| std::array::from_fn(|i| c[i]))
            .collect(),
    )
}

impl Importer for ObjImport {
    const NAME: &'static str = "Wavefront OBJ";
    const VERSION: &'static str = env!("CARGO_PKG_VERSION");
    const EXTENSIONS: &'static str = "obj";

    fn import(path: &Path, builder: &mut Builder) -> Result<(), String> {
        let file = File::open(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let dir = path.parent().unwrap_or(Path::new(""));
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
        let (models, materials) =
            tobj::load_obj_buf(&mut BufReader::new(file), &options, |library| {
                let full = dir.join(library);
                tobj::load_mtl(&full).or_else(|e| {
                    let reason = match std::fs::metadata(&full) {
                        Err(io) => io.to_string(),
                        Ok(_) => e.to_string(),
                    };
                    library_warnings.borrow_mut().push(format!(
                        "material library {} not loaded ({reason}); its materials are grey",
                        full.display()
                    ));
                    // An empty library: the file's other libraries still load.
                    tobj::load_mtl_buf(&mut &b""[..])
                })
            })
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        for w in library_warnings.into_inner() {
            builder.warn(&w);
        }
        // Every library either loaded or was replaced by an empty one above.
        let materials = materials.unwrap_or_default();

        if models.iter().all(|m| m.mesh.indices.is_empty()) {
            return Err(format!("{} holds no faces", path.display()));
        }

        let mut material_ids: HashMap<usize, u32> = HashMap::new();
        for (index, model) in models.iter().enumerate() {
            let mesh = &model.mesh;
            let name = if model.name.is_empty() {
                format!("object {index}")
            } else {
                model.name.clone()
            };
            if mesh.indices.is_empty() {
                builder.warn(&format!(
                    "object \"{name}\" has no faces (points and lines are not rendered)"
                ));
                continue;
            }
            let positions: Vec<[f32; 3]> = mesh
                .positions
                .chunks_exact(3)
                .map(|p| [p[0], p[1], p[2]])
                .collect();
            let n = positions.len();
            let normals = per_vertex::<3>(&mesh.normals, n, "normals", &name, builder);
            let uvs = per_vertex::<2>(&mesh.texcoords, n, "texture coordinates", &name, builder);
            let colors: Option<Vec<[f32; 4]>> =
                per_vertex::<3>(&mesh.vertex_color, n, "vertex colours", &name, builder)
                    .map(|c| c.into_iter().map(|[r, g, b]| [r, g, b, 1.0]).collect());
            let Some(mesh_id) = builder.add_mesh(&Mesh {
                name: &name,
                positions: &positions,
                normals: normals.as_deref().unwrap_or_default(),
                uvs: uvs.as_deref().unwrap_or_default(),
                colors: colors.as_deref().unwrap_or_default(),
                indices: &mesh.indices,
                ..Mesh::default()
            }) else {
                // The host said why in a warning.
                continue;
            };
            let material = match mesh.material_id {
                Some(m) if m < materials.len() => *material_ids.entry(m).or_insert_with(|| {
                    let converted = mtl::convert(&materials[m]);
                    for w in &converted.warnings {
                        builder.warn(w);
                    }
                    builder
                        .add_material(&materials[m].name, &converted.kmat)
                        .unwrap_or(u32::MAX)
                }),
                _ => u32::MAX,
            };
            builder.add_instance(mesh_id, material, IDENTITY);
        }
        Ok(())
    }
}

export_importer!(ObjImport);
