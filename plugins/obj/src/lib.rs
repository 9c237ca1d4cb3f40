//! Kiln's Wavefront OBJ importer: geometry through `kiln_formats::obj`, the reader the
//! host also loads scene files' OBJ meshes with, and materials from the MTL libraries the
//! file names, converted to `.kmat` graphs ([`mtl`]).
//!
//! Each OBJ object or group (split further where its material changes, as tobj does)
//! becomes one mesh and one instance with the identity transform: OBJ has no scene
//! hierarchy, cameras or lights. Polygons are triangulated as fans; points and lines are
//! skipped. Positions, normals and texture coordinates are passed as written (OBJ's v
//! already points up, as Kiln's); a file Kiln saved comes back with its vertex order,
//! second UV set and colour alpha. A missing MTL library is a warning and its meshes are
//! grey; a mesh without a material gets the host's grey (`u32::MAX`).

pub mod mtl;
pub mod texture;

use std::collections::HashMap;
use std::path::Path;

use kiln_formats::obj::read_obj;
use kiln_plugin_api::{Builder, Importer, Mesh, export_importer};

/// The OBJ importer.
pub struct ObjImport;

/// Column-major identity.
const IDENTITY: [f32; 16] = [
    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
];

impl Importer for ObjImport {
    const NAME: &'static str = "Wavefront OBJ";
    const VERSION: &'static str = env!("CARGO_PKG_VERSION");
    const EXTENSIONS: &'static str = "obj";

    fn import(path: &Path, builder: &mut Builder) -> Result<(), String> {
        let file = read_obj(path)?;
        for w in &file.warnings {
            builder.warn(w);
        }
        let mut material_ids: HashMap<usize, u32> = HashMap::new();
        for mesh in &file.meshes {
            let Some(mesh_id) = builder.add_mesh(&Mesh {
                name: &mesh.name,
                positions: &mesh.positions,
                normals: &mesh.normals,
                uvs: &mesh.uvs,
                uvs1: &mesh.uvs1,
                colors: &mesh.colors,
                indices: mesh.indices.as_flattened(),
                ..Mesh::default()
            }) else {
                // The host said why in a warning.
                continue;
            };
            let material = match mesh.material {
                Some(m) => *material_ids.entry(m).or_insert_with(|| {
                    let converted = mtl::convert(&file.materials[m]);
                    for w in &converted.warnings {
                        builder.warn(w);
                    }
                    builder
                        .add_material(&file.materials[m].name, &converted.kmat)
                        .unwrap_or(u32::MAX)
                }),
                None => u32::MAX,
            };
            builder.add_instance(mesh_id, material, IDENTITY);
        }
        Ok(())
    }
}

export_importer!(ObjImport);
