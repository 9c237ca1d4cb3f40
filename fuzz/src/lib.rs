//! The fuzz targets' bodies, one function per target (`fuzz_targets/` calls them, and
//! `tests/fuzz_regressions.rs` replays every input in `fuzz/regressions/<target>/` through
//! them), and what they share: a scratch folder per process for inputs that importers read
//! by path, and the host checks an import's materials go through.
//!
//! The importer targets take the importer as a function: each importer crate exports the
//! plugin symbol `kiln_plugin_descriptor`, so no binary can link two of them.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use kiln::material::{compile, material_text, materials_wgsl, parse_material};
use kiln::render::kernel::path_tracing_kernel;
use kiln::scene::{Scene, load_scene, parse_scene, save_scene};
use kiln::shader::KernelFeatures;
use kiln_plugin_api::Builder;
use kiln_plugin_api::recording::Recorder;

/// An importer's entry point (`kiln_plugin_api::Importer::import`).
pub type ImportFn = fn(&Path, &mut Builder) -> Result<(), String>;

/// `.kiln` scene text → parse and validate; a scene that loads must also come back equal
/// after saving (when its materials and meshes have distinct non-empty names:
/// `save_scene` renames the others).
pub fn scene(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    // Relative paths resolve in an empty folder: a fuzzed scene reads no file of ours.
    let base = scratch_dir().join("empty");
    let _ = std::fs::create_dir_all(&base);
    let Ok(scene) = parse_scene(text, Path::new("fuzzed.kiln"), &base) else {
        return;
    };
    if !saves_as_is(&scene) {
        return;
    }
    let path = scratch_dir().join("saved/scene.kiln");
    let _ = std::fs::create_dir_all(path.parent().expect("a folder"));
    save_scene(&scene, &path, &[]).unwrap_or_else(|e| panic!("saving a loaded scene: {e}"));
    let again = load_scene(&path).unwrap_or_else(|e| panic!("loading a saved scene: {e}"));
    assert!(again == scene, "the scene changed by saving and loading");
}

fn saves_as_is(scene: &Scene) -> bool {
    fn distinct<'a>(names: impl Iterator<Item = &'a str>) -> bool {
        let mut seen = HashSet::new();
        names.into_iter().all(|n| !n.is_empty() && seen.insert(n))
    }
    distinct(scene.materials.iter().map(|m| m.name.as_str()))
        && distinct(scene.meshes.iter().map(|m| m.name.as_str()))
}

/// `.kmat` text → [`check_material`].
pub fn material(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = check_material("fuzzed", text);
    }
}

/// A `.gltf` or `.glb` file (told apart by its magic, as the importer does) through the
/// glTF importer `importer`.
pub fn gltf(data: &[u8], importer: ImportFn) {
    let path = input_file("input.gltf", data);
    import(&path, importer);
}

/// A Wavefront OBJ file and the MTL library it may name (`mtllib input.mtl`), given as one
/// input split at [`OBJ_MTL_SEPARATOR`], through the OBJ importer `importer`.
pub fn obj(data: &[u8], importer: ImportFn) {
    let (obj, mtl) = split_obj_mtl(data);
    input_file("input.mtl", mtl);
    let path = input_file("input.obj", obj);
    import(&path, importer);
}

/// A folder of this process's own, kept until it exits.
pub fn scratch_dir() -> &'static Path {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    DIR.get_or_init(|| {
        tempfile::Builder::new()
            .prefix("kiln-fuzz-")
            .tempdir()
            .expect("a scratch folder")
    })
    .path()
}

/// `data` written to `name` in the scratch folder.
pub fn input_file(name: &str, data: &[u8]) -> PathBuf {
    let path = scratch_dir().join(name);
    std::fs::write(&path, data).expect("writing the input");
    path
}

/// What Kiln does with a material graph: parse the `.kmat` text, compile it and validate
/// the kernel it is spliced into with naga. Errors are expected; panics are findings. A
/// graph that parses must also survive being written and read back: the text written
/// again is the same (compared as text, where a NaN the parser took equals itself).
pub fn check_material(name: &str, kmat: &str) -> Result<(), String> {
    let (parsed_name, graph) = parse_material(kmat, "fuzz.kmat").map_err(|e| e.to_string())?;
    let text = material_text(&parsed_name, &graph).map_err(|e| e.to_string())?;
    let again = parse_material(&text, "rewritten.kmat")
        .unwrap_or_else(|e| panic!("a written material does not parse: {e}\n{text}"));
    let rewritten = material_text(&again.0, &again.1).map_err(|e| e.to_string())?;
    assert_eq!(rewritten, text, "a written material reads back different");
    let compiled = compile(name, &graph, "material_0").map_err(|e| e.to_string())?;
    let wgsl = materials_wgsl(&[(0, &compiled)]);
    path_tracing_kernel(&KernelFeatures::default(), &wgsl)
        .validate()
        .unwrap_or_else(|e| panic!("a compiled material fails naga validation: {e}\n{kmat}"));
    Ok(())
}

/// Runs a Rust importer on the file at `path` against the recording host, with every
/// material checked as [`check_material`] does. Called directly, not through the C entry
/// point, whose guard would turn a panic into an error the fuzzer never sees.
pub fn import(path: &Path, importer: ImportFn) {
    let mut recorder = Recorder::check_materials(check_material);
    let raw = recorder.scene_builder();
    let mut builder = unsafe { Builder::from_raw(&raw) };
    let _ = importer(path, &mut builder);
    assert!(
        recorder.recorded.violations.is_empty(),
        "the importer broke the host's rules: {:?}",
        recorder.recorded.violations
    );
}

/// The line that separates an `obj` target's OBJ text from its MTL library.
pub const OBJ_MTL_SEPARATOR: &[u8] = b"\n#mtl\n";

/// An `obj` target input as (OBJ, MTL): split at the first [`OBJ_MTL_SEPARATOR`], the MTL
/// empty when there is none.
pub fn split_obj_mtl(data: &[u8]) -> (&[u8], &[u8]) {
    match data
        .windows(OBJ_MTL_SEPARATOR.len())
        .position(|w| w == OBJ_MTL_SEPARATOR)
    {
        Some(at) => (&data[..at], &data[at + OBJ_MTL_SEPARATOR.len()..]),
        None => (data, &[]),
    }
}
