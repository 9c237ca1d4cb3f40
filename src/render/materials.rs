//! A scene's materials as the kernel takes them: the graph materials compiled to WGSL
//! functions behind one dispatcher, or as programs for the interpreter, and the table of
//! the images they read.

use super::renderer::KernelKind;
use crate::material::compile::{
    Constants, ProgramError, compile_program, compile_with, interpreter,
};
use crate::material::library;
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
    /// With live constants or programs, the `material_params` buffer's contents (empty
    /// otherwise).
    pub parameters: Vec<[f32; 4]>,
}

/// Compiles the scene's graph materials for a kernel of kind `kernel`:
///
/// - [`KernelKind::Specialized`]: constants folded into the code (final renders);
/// - [`KernelKind::General`]: constants read from the parameter buffer
///   ([`Constants::Live`]), so that value edits keep the code; live constants that would
///   not fit the buffer ([`MATERIAL_PARAMS`]) are compiled inline;
/// - [`KernelKind::Interpreted`]: the graphs as programs in the parameter buffer, run by
///   the interpreter ([`interpreter`]), so that no graph edit changes the code; a scene
///   whose programs the interpreter cannot run, or that would not fit the buffer, is
///   compiled as for [`KernelKind::General`].
pub fn scene_materials(scene: &Scene, kernel: KernelKind) -> Result<SceneMaterials, GraphError> {
    match kernel {
        KernelKind::Specialized => compile_scene_materials(scene, false),
        KernelKind::General => {
            let materials = compile_scene_materials(scene, true)?;
            if materials.parameters.len() > MATERIAL_PARAMS {
                return compile_scene_materials(scene, false);
            }
            Ok(materials)
        }
        KernelKind::Interpreted => match interpreted_scene_materials(scene) {
            Ok(materials) => Ok(materials),
            Err(ProgramError::Graph(e)) => Err(e),
            Err(ProgramError::Unsupported { .. }) => scene_materials(scene, KernelKind::General),
        },
    }
}

/// Whether the interpreter runs the scene's graphs ([`KernelKind::Interpreted`] does not
/// fall back to compiled code for it).
pub fn interprets(scene: &Scene) -> bool {
    interpreted_scene_materials(scene).is_ok()
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

/// The scene's graphs as programs, laid out in the parameter buffer: a header (the
/// material count, then per material the word its program starts at, 0 for none, and the
/// element its constants start at), the programs' words four to an element, then their
/// constants. The WGSL is the interpreter, whatever the graphs.
fn interpreted_scene_materials(scene: &Scene) -> Result<SceneMaterials, ProgramError> {
    let mut textures = scene_textures(scene).index;
    let mut programs = Vec::new();
    for (i, m) in scene.materials.iter().enumerate() {
        if let Some(g) = &m.graph {
            programs.push((i, compile_program(&m.name, &g.graph, &mut textures)?));
        }
    }
    let count = scene.materials.len();
    let mut header = vec![0u32; 1 + 2 * count];
    header[0] = count as u32;
    let mut words = Vec::new();
    let code_words = header.len() + programs.iter().map(|(_, p)| p.words.len()).sum::<usize>();
    let mut constant = code_words.div_ceil(4);
    for (i, program) in &programs {
        header[1 + 2 * i] = (header.len() + words.len()) as u32;
        header[2 + 2 * i] = constant as u32;
        words.extend_from_slice(&program.words);
        constant += program.constants.len();
    }
    if constant > MATERIAL_PARAMS {
        return Err(ProgramError::Unsupported {
            material: scene.materials[programs[0].0].name.clone(),
            reason: format!(
                "the scene's programs need {constant} elements of the parameter buffer, \
                 which has {MATERIAL_PARAMS}"
            ),
        });
    }
    // Integers below 2^24 are exact as f32.
    let mut as_floats: Vec<f32> = header.iter().chain(&words).map(|&w| w as f32).collect();
    as_floats.resize(code_words.div_ceil(4) * 4, 0.0);
    let mut parameters: Vec<[f32; 4]> = as_floats
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    for (_, program) in &programs {
        parameters.extend_from_slice(&program.constants);
    }
    Ok(SceneMaterials {
        wgsl: interpreter_wgsl(!textures.is_empty()),
        parameters,
    })
}

/// The interpreter and a dispatcher that runs each graph material's program.
fn interpreter_wgsl(textures: bool) -> Vec<(String, String)> {
    let interpreter = interpreter(textures);
    let roots = [
        "ShadingPoint",
        "MaterialEval",
        "material_eval",
        "VolumeEval",
        "nd_no_volume",
    ]
    .map(String::from)
    .into_iter()
    .chain(interpreter.calls.iter().cloned());
    vec![
        (
            "node library items used (shaders/nodes/)".to_owned(),
            library::closure(roots),
        ),
        (
            "material interpreter (generated)".to_owned(),
            interpreter.code.clone(),
        ),
        (
            "material dispatcher (generated)".to_owned(),
            "fn evaluate_material(id: u32, sp: ShadingPoint) -> MaterialEval {
    if (id < nd_word(0u)) {
        let start = nd_word(1u + 2u * id);
        if (start != 0u) {
            return nd_interpret(start, nd_word(2u + 2u * id), sp);
        }
    }
    return material_from_buffer(id, sp);
}
// The interpreted graph computes its volume with its surface.
fn evaluate_volume(id: u32, sp: ShadingPoint) -> VolumeEval {
    return evaluate_material(id, sp).volume;
}
"
            .to_owned(),
        ),
    ]
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
