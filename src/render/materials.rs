//! A scene's materials as the kernel takes them: the graph materials compiled to WGSL
//! functions behind one dispatcher, and the table of the images they read.

use crate::material::compile::compile_with_textures;
use crate::material::texture::TextureTable;
use crate::material::{CompiledMaterial, GraphError, materials_wgsl};
use crate::scene::Scene;

/// [`materials_wgsl`](crate::material::materials_wgsl) for a scene: its graph materials compiled, numbered by their index.
pub fn scene_materials_wgsl(scene: &Scene) -> Result<Vec<(String, String)>, GraphError> {
    let mut textures = scene_textures(scene).index;
    let mut compiled = Vec::new();
    for (i, m) in scene.materials.iter().enumerate() {
        if let Some(g) = &m.graph {
            compiled.push((
                i as u32,
                compile_with_textures(&m.name, &g.graph, &format!("material_{i}"), &mut textures)?,
            ));
        }
    }
    let list: Vec<(u32, &CompiledMaterial)> = compiled.iter().map(|(i, c)| (*i, c)).collect();
    Ok(materials_wgsl(&list))
}

/// The images of a scene's graph materials, indexed in material order.
pub fn scene_textures(scene: &Scene) -> TextureTable {
    let mut table = TextureTable::default();
    for m in &scene.materials {
        let Some(g) = &m.graph else { continue };
        for (file, image) in &g.images {
            if !table.index.contains_key(file) {
                table.index.insert(file.clone(), table.images.len() as u32);
                table.images.push(std::sync::Arc::clone(image));
            }
        }
    }
    table
}
