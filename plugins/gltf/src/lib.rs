//! Kiln's glTF 2.0 importer plugin (`.gltf`, `.glb`): meshes, metallic-roughness
//! materials and their common extensions as material graphs, the node hierarchy,
//! the first perspective camera and KHR_lights_punctual lights.
//!
//! Data flow: [`document`] reads the container and JSON, [`extensions`] decides whether
//! the file can be imported at all, [`buffers`] loads the bytes, [`scene`] walks the
//! nodes, [`geometry`] (through [`accessor`]) turns primitives into triangle lists and
//! [`material`] (through [`texture`], [`images`] and `kiln_plugin_api::kmat`) turns materials into
//! `.kmat` graphs; [`import`] drives them and talks to the host. [`validate`] checks the
//! file against the rules parsing does not enforce and reports what breaks them.
//!
//! Not imported: animations, skins and morph targets (rest pose), orthographic cameras,
//! UV sets past the second (TEXCOORD_0 and TEXCOORD_1 are), points and lines, and extensions outside [`extensions::HANDLED`]
//! (reported, or refused when the file requires them). Every read of the file is
//! bounds-checked: broken files give warnings or an error, never a panic.

pub mod accessor;
pub mod buffers;
pub mod document;
pub mod extensions;
pub mod geometry;
pub mod images;
pub mod import;
pub mod material;
pub mod scene;
pub mod texture;
pub mod validate;

use std::path::Path;

use kiln_plugin_api::{Builder, Importer};

/// The importer the plugin exports.
pub struct GltfImporter;

impl Importer for GltfImporter {
    const NAME: &'static str = "glTF 2.0";
    const VERSION: &'static str = env!("CARGO_PKG_VERSION");
    const EXTENSIONS: &'static str = "gltf,glb";

    fn import(path: &Path, builder: &mut Builder) -> Result<(), String> {
        import::import(path, builder)
    }
}

kiln_plugin_api::export_importer!(GltfImporter);

/// Every material of the file at `path` as `(name, .kmat text)`, without a host: each
/// glTF material with and without vertex colours, then the vertex-colour default.
/// Images are named `image:N` by glTF image index and not loaded. For tools and tests
/// that check the generated graphs.
pub fn material_texts(path: &Path) -> Result<Vec<(String, String)>, String> {
    let mut doc = document::read(path)?;
    document::schema_problems(&mut doc.root);
    let root = &doc.root;
    let mut out = Vec::new();
    let indices = (0..root.materials.len()).map(Some).chain([None]);
    for index in indices {
        for vertex_colors in [false, true] {
            let variant = material::Variant {
                vertex_colors,
                textures: true,
            };
            let (text, _) = material::translate(root, index, variant, &mut images::NamedImages);
            out.push((text.name, text.kmat));
            if index.is_none() {
                break;
            }
        }
    }
    Ok(out)
}
