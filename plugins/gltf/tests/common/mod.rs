//! The test host: the importer driven through its C ABI by `kiln_plugin_api`'s recording
//! host, which checks what it adds as strictly as Kiln's host does — material graphs are
//! parsed and compiled by `kiln::material`, meshes must be whole and in range.

#![allow(dead_code)] // each test file uses a different part

use std::path::Path;
use std::sync::mpsc;
use std::time::{Duration, Instant};

pub use kiln_plugin_api::recording::Recorded;
use kiln_plugin_api::recording::Recorder;

/// Finding resources outside the repository (fails under CI when one is missing): the
/// workspace's own test helper, shared by path rather than copied.
#[path = "../../../../tests/common/resource.rs"]
pub mod resource;

/// Parses and compiles `kmat` as Kiln's host does; the error if it does not compile.
pub fn compile_kmat(name: &str, kmat: &str) -> Result<(), String> {
    let (_, graph) =
        kiln::material::parse_material(kmat, "test.gltf").map_err(|e| format!("{e}\n{kmat}"))?;
    kiln::material::compile(name, &graph, "material").map_err(|e| format!("{e}\n{kmat}"))?;
    Ok(())
}

/// Imports `path` through the plugin's exported C entry point, compiling every material.
pub fn import(path: &Path) -> (Result<(), String>, Recorded) {
    let descriptor = unsafe { &*kiln_gltf::kiln_plugin_descriptor() };
    Recorder::check_materials(compile_kmat).import(descriptor, path)
}

/// [`import`] on another thread, with the time it took; an error saying whether it did not
/// finish within `limit` or the thread panicked.
pub fn import_with_timeout(
    path: &Path,
    limit: Duration,
) -> Result<(Result<(), String>, Recorded, Duration), String> {
    let (tx, rx) = mpsc::channel();
    let path = path.to_owned();
    std::thread::spawn(move || {
        let start = Instant::now();
        let (result, recorded) = import(&path);
        let _ = tx.send((result, recorded, start.elapsed()));
    });
    rx.recv_timeout(limit).map_err(|e| match e {
        mpsc::RecvTimeoutError::Timeout => format!("no result within {limit:?}"),
        mpsc::RecvTimeoutError::Disconnected => "the importing thread panicked".to_owned(),
    })
}

/// A scratch folder of its own for files a test writes, removed when dropped.
pub fn scratch_dir() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("kiln-gltf-test-")
        .tempdir()
        .expect("temp dir")
}
