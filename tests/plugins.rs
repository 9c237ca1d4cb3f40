//! The plugin host against purpose-built plugins: the C example exporter (proving the
//! header works from C), and broken ones — wrong ABI version, no descriptor, not a
//! library, an importer that fails, one that panics. Kiln reports each and keeps going.

use std::path::{Path, PathBuf};
use std::process::Command;

use assert_cmd::cargo::CommandCargoExt;
use kiln::plugin::{PluginHost, PluginKind};

const API_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/plugins/api");

/// Compiles C source into a shared library `name` in `dir` with the system C compiler.
fn compile_c(dir: &Path, name: &str, source: &str) -> PathBuf {
    let src = dir.join(format!("{name}.c"));
    std::fs::write(&src, source).unwrap();
    let lib = dir.join(format!("lib{name}.so"));
    let out = Command::new("cc")
        .args(["-shared", "-fPIC", "-O1", "-I", API_DIR, "-o"])
        .arg(&lib)
        .arg(&src)
        .output()
        .expect("a C compiler (cc) is installed");
    assert!(
        out.status.success(),
        "cc failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    lib
}

fn kiln(args: &[&str]) -> (i32, String, String) {
    let out = Command::cargo_bin("kiln")
        .unwrap()
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

const WRONG_ABI: &str = r#"
#include "kiln_plugin.h"
static const KilnPluginDescriptor D = { 999u, KILN_KIND_EXPORTER, "future", "9", "fut", 0, 0 };
const KilnPluginDescriptor *kiln_plugin_descriptor(void) { return &D; }
"#;

const NO_SYMBOL: &str = "int not_a_plugin(void) { return 42; }\n";

const FAILING_IMPORTER: &str = r#"
#include <stdio.h>
#include "kiln_plugin.h"
static int32_t import(const char *path, const KilnSceneBuilder *b, KilnErrorBuffer *e) {
    b->warn(b->ctx, "looked at the file");
    snprintf(e->data, e->capacity, "cannot make sense of %s", path);
    return KILN_STATUS_ERROR;
}
static const KilnPluginDescriptor D = { KILN_ABI_VERSION, KILN_KIND_IMPORTER, "failing", "1", "fail", import, 0 };
const KilnPluginDescriptor *kiln_plugin_descriptor(void) { return &D; }
"#;

/// A C importer that hands over one triangle, with a bad mesh (index out of range) that
/// the host must refuse.
const TRIANGLE_IMPORTER: &str = r#"
#include "kiln_plugin.h"
static int32_t import(const char *path, const KilnSceneBuilder *b, KilnErrorBuffer *e) {
    (void)path; (void)e;
    float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t good[3] = {0, 1, 2}, bad[3] = {0, 1, 7};
    KilnMeshData m = {"tri", 3, p, 0, 0, 0, 0, 0, good, 3};
    uint32_t mesh = b->add_mesh(b->ctx, &m);
    m.indices = bad;
    if (b->add_mesh(b->ctx, &m) != KILN_INVALID_ID) return KILN_STATUS_ERROR;
    float id[16] = {1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1};
    b->add_instance(b->ctx, mesh, KILN_INVALID_ID, (const float (*)[16])id);
    return KILN_STATUS_OK;
}
static const KilnPluginDescriptor D = { KILN_ABI_VERSION, KILN_KIND_IMPORTER, "triangle", "1", "tri", import, 0 };
const KilnPluginDescriptor *kiln_plugin_descriptor(void) { return &D; }
"#;

/// The panicking Rust plugin (plugins/test-panic), built by cargo as a dev-dependency.
fn panicking_plugin() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let deps = exe.parent().unwrap();
    let lib = deps.join("libpanicking_test_plugin.so");
    assert!(lib.exists(), "{} was not built", lib.display());
    lib
}

#[test]
fn broken_plugins_are_refused_with_their_reason_and_good_ones_load() {
    let dir = tempfile::tempdir().unwrap();
    compile_c(dir.path(), "wrong_abi", WRONG_ABI);
    compile_c(dir.path(), "no_symbol", NO_SYMBOL);
    compile_c(dir.path(), "failing", FAILING_IMPORTER);
    std::fs::write(dir.path().join("libgarbage.so"), b"not an ELF file").unwrap();
    let mut host = PluginHost::default();
    host.load_dir(dir.path(), false);
    let reason = |name: &str| {
        host.rejected
            .iter()
            .find(|r| r.path.file_name().unwrap().to_str().unwrap().contains(name))
            .map(|r| r.reason.clone())
            .unwrap_or_else(|| panic!("{name} was not refused"))
    };
    assert!(
        reason("wrong_abi").contains("ABI version 999"),
        "{}",
        reason("wrong_abi")
    );
    assert!(
        reason("no_symbol").contains("no kiln_plugin_descriptor"),
        "{}",
        reason("no_symbol")
    );
    assert!(
        reason("garbage").contains("cannot load"),
        "{}",
        reason("garbage")
    );
    let loaded: Vec<_> = host.plugins().map(|p| p.name.clone()).collect();
    assert_eq!(loaded, ["failing"]);

    // The CLI says the same.
    let (code, out, _) = kiln(&["plugins", "--plugin-dir", dir.path().to_str().unwrap()]);
    assert_eq!(code, 0);
    assert!(out.contains("failing 1 (importer; .fail)"), "{out}");
    assert!(
        out.contains("libwrong_abi.so: plugin ABI version 999"),
        "{out}"
    );
}

#[test]
fn a_failing_or_panicking_importer_is_an_error_and_the_host_keeps_running() {
    let dir = tempfile::tempdir().unwrap();
    compile_c(dir.path(), "failing", FAILING_IMPORTER);
    compile_c(dir.path(), "triangle", TRIANGLE_IMPORTER);
    let mut host = PluginHost::default();
    host.load_dir(dir.path(), false);
    host.load_file(&panicking_plugin()).unwrap();

    let e = host
        .import(Path::new("model.fail"))
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("failing failed on model.fail: cannot make sense of model.fail"),
        "{e}"
    );
    let e = host
        .import(Path::new("model.panic"))
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("the plugin panicked at plugins/test-panic/src/lib.rs:"),
        "{e}"
    );
    assert!(
        e.contains("deliberate panic while importing model.panic"),
        "{e}"
    );
    // Still running: another import works, with the bad mesh refused and reported.
    let imported = host.import(Path::new("anything.tri")).unwrap();
    assert_eq!(imported.scene.meshes.len(), 1);
    assert_eq!(imported.scene.instances.len(), 1);
    assert!(
        imported
            .warnings
            .iter()
            .any(|w| w.contains("index 7 is out of range for 3 vertices")),
        "{:?}",
        imported.warnings
    );
    let e = host
        .import(Path::new("x.unknown"))
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no importer plugin handles \".unknown\""), "{e}");

    // Through the CLI: one message, exit code 1, no crash.
    let copy = tempfile::tempdir().unwrap();
    std::fs::copy(
        panicking_plugin(),
        copy.path().join("libpanicking_test_plugin.so"),
    )
    .unwrap();
    let (code, _, err) = kiln(&[
        "render",
        "model.panic",
        "-q",
        "--plugin-dir",
        copy.path().to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("the plugin panicked"), "{err}");
    assert!(!err.contains("RUST_BACKTRACE"), "{err}");
}

#[test]
fn the_c_example_exporter_writes_a_ppm() {
    let dir = tempfile::tempdir().unwrap();
    let source = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/plugins/example-c/ppm_exporter.c"
    ))
    .unwrap();
    compile_c(dir.path(), "kiln_ppm", &source);
    let out = dir.path().join("cornell.ppm");
    let (code, _, err) = kiln(&[
        "render",
        "--size",
        "16x12",
        "--spp",
        "2",
        "-q",
        "-o",
        out.to_str().unwrap(),
        "--plugin-dir",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let bytes = std::fs::read(&out).unwrap();
    let header = b"P6\n16 12\n255\n";
    assert!(
        bytes.starts_with(header),
        "{:?}",
        &bytes[..16.min(bytes.len())]
    );
    assert_eq!(bytes.len(), header.len() + 16 * 12 * 3);
    assert!(
        bytes[header.len()..].iter().any(|&b| b > 0),
        "an all-black image"
    );
    let host = {
        let mut h = PluginHost::default();
        h.load_dir(dir.path(), false);
        h
    };
    assert!(host.handles(PluginKind::Exporter, Path::new("x.PPM")));
}
