//! A scene's materials as the kernel takes them: the graph materials compiled to WGSL
//! functions behind one dispatcher, and the table of the images they read.

use crate::material::compile::{Constants, compile_with};
use crate::material::texture::TextureTable;
use crate::material::{CompiledMaterial, GraphError, materials_wgsl};
use crate::scene::Scene;
use crate::shader::bindings::MATERIAL_PARAMS;

/// A scene's graph materials compiled for a kernel.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneMaterials {
    /// [`materials_wgsl`](crate::material::materials_wgsl): the graph materials,
    /// numbered by their index, behind one dispatcher.
    pub wgsl: Vec<(String, String)>,
    /// With live constants, the `material_params` buffer's contents (empty otherwise).
    pub parameters: Vec<[f32; 4]>,
}

/// Compiles the scene's graph materials. With `live` their constants are read from the
/// parameter buffer ([`Constants::Live`]), so that edits of values keep the code: the
/// editor's viewport; otherwise they are folded into it: final renders. Live constants
/// that would not fit the buffer ([`MATERIAL_PARAMS`]) are compiled inline.
pub fn scene_materials(scene: &Scene, live: bool) -> Result<SceneMaterials, GraphError> {
    let materials = compile_scene_materials(scene, live)?;
    if materials.parameters.len() > MATERIAL_PARAMS {
        return compile_scene_materials(scene, false);
    }
    Ok(materials)
}

fn compile_scene_materials(scene: &Scene, live: bool) -> Result<SceneMaterials, GraphError> {
    let mut textures = scene_textures(scene).index;
    let mut compiled = Vec::new();
    let mut parameters = Vec::new();
    for (i, m) in scene.materials.iter().enumerate() {
        if let Some(g) = &m.graph {
            let constants = if live {
                Constants::Live {
                    base: parameters.len() as u32,
                }
            } else {
                Constants::Inline
            };
            let function = format!("material_{i}");
            let material = compile_with(&m.name, &g.graph, &function, &mut textures, constants)?;
            parameters.extend_from_slice(&material.parameters);
            compiled.push((i as u32, material));
        }
    }
    let list: Vec<(u32, &CompiledMaterial)> = compiled.iter().map(|(i, c)| (*i, c)).collect();
    Ok(SceneMaterials {
        wgsl: materials_wgsl(&list),
        parameters,
    })
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
