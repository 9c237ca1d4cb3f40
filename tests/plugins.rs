//! The plugin host against purpose-built plugins: the C example exporter (proving the
//! header works from C), and broken ones — wrong ABI version, no descriptor, not a
//! library, an importer that fails, one that panics, and run out of process one that
//! crashes and one that hangs. Kiln reports each and keeps going.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use assert_cmd::cargo::CommandCargoExt;
use kiln::plugin::{Isolation, PluginHost, PluginKind};

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

/// An importer built against ABI version 1, whose descriptor ends before version 2's
/// material functions: the host still loads it and reads nothing past its end.
const VERSION_1_IMPORTER: &str = r#"
#include "kiln_plugin.h"
typedef struct V1Descriptor {
    uint32_t abi_version; uint32_t kind; const char *name; const char *version;
    const char *extensions; KilnImportFn import; KilnExportFn export_;
} V1Descriptor;
static int32_t import(const char *path, const KilnSceneBuilder *b, KilnErrorBuffer *e) {
    (void)path; (void)b; (void)e; return KILN_STATUS_OK;
}
static const V1Descriptor D = { 1u, KILN_KIND_IMPORTER, "old", "1", "old", import, 0 };
const V1Descriptor *kiln_plugin_descriptor(void) { return &D; }
"#;

/// The smallest material format in C (docs/PLUGINS.md): reads a `.cmat` file holding
/// an RGB colour into a principled material, and writes a material's name.
const C_MATERIAL_FORMAT: &str = r#"
#include <stdio.h>
#include "kiln_plugin.h"
static int32_t import_material(const char *path, const KilnMaterialSink *sink, KilnErrorBuffer *e) {
    float r, g, b;
    FILE *f = fopen(path, "r");
    if (!f || fscanf(f, "%f %f %f", &r, &g, &b) != 3) {
        if (f) fclose(f);
        snprintf(e->data, e->capacity, "%s holds no colour", path);
        return KILN_STATUS_ERROR;
    }
    fclose(f);
    char kmat[512];
    snprintf(kmat, sizeof kmat,
        "(version: 1, nodes: {"
        " \"s\": (type: \"principled_bsdf\", inputs: { \"base_color\": (%f, %f, %f) }),"
        " \"out\": (type: \"material_output\", inputs: { \"surface\": \"s.bsdf\" }) })",
        r, g, b);
    if (sink->add_material(sink->ctx, "painted", kmat) == KILN_INVALID_ID) {
        snprintf(e->data, e->capacity, "Kiln refused the material");
        return KILN_STATUS_ERROR;
    }
    sink->warn(sink->ctx, "colours only");
    return KILN_STATUS_OK;
}
static int32_t export_material(const char *path, const char *name, const char *kmat,
                               const char *library, KilnErrorBuffer *e) {
    (void)kmat; (void)library;
    FILE *f = fopen(path, "w");
    if (!f) { snprintf(e->data, e->capacity, "cannot write %s", path); return KILN_STATUS_ERROR; }
    fprintf(f, "%s\n", name);
    fclose(f);
    return KILN_STATUS_OK;
}
static const KilnPluginDescriptor D = {
    KILN_ABI_VERSION, KILN_KIND_MATERIAL, "colour", "1", "cmat", 0, 0, import_material, export_material,
};
const KilnPluginDescriptor *kiln_plugin_descriptor(void) { return &D; }
"#;

#[test]
fn version_1_plugins_load_and_c_material_formats_work() {
    let dir = tempfile::tempdir().unwrap();
    compile_c(dir.path(), "old", VERSION_1_IMPORTER);
    compile_c(dir.path(), "colour", C_MATERIAL_FORMAT);
    let mut host = PluginHost::default();
    host.load_dir(dir.path(), false);
    assert!(host.rejected.is_empty(), "{:?}", host.rejected);
    assert!(host.handles(PluginKind::Importer, Path::new("x.old")));
    assert!(host.handles(PluginKind::Material, Path::new("x.cmat")));

    let file = dir.path().join("red.cmat");
    std::fs::write(&file, "0.8 0.1 0.1\n").unwrap();
    let imported = host.import_materials(&file).unwrap();
    assert_eq!(imported.warnings, ["colours only"]);
    let (name, graph) = &imported.materials[0];
    assert_eq!(name, "painted");
    kiln::material::compile(name, graph, "m").unwrap();
    let out = dir.path().join("back.cmat");
    host.export_material(&out, name, graph).unwrap();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "painted\n");

    // Through the CLI, and a bad file is an error naming it.
    let folder = dir.path().join("mats");
    let plugin_dir = dir.path().to_str().unwrap();
    let (code, out, err) = kiln(&[
        "--plugin-dir",
        plugin_dir,
        "material",
        "import",
        file.to_str().unwrap(),
        "-o",
        folder.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("painted.kmat") && err.contains("warning: colours only"),
        "{out}{err}"
    );
    assert!(folder.join("painted.kmat").is_file());
    let empty = dir.path().join("empty.cmat");
    std::fs::write(&empty, "").unwrap();
    let (code, _, err) = kiln(&[
        "--plugin-dir",
        plugin_dir,
        "material",
        "import",
        empty.to_str().unwrap(),
        "-o",
        folder.to_str().unwrap(),
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("empty.cmat holds no colour"), "{err}");
}

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

/// A C importer that dereferences a null pointer.
const CRASHING_IMPORTER: &str = r#"
#include "kiln_plugin.h"
static int32_t import(const char *path, const KilnSceneBuilder *b, KilnErrorBuffer *e) {
    (void)path; (void)e;
    b->warn(b->ctx, "about to crash");
    volatile int *p = 0;
    return *p;
}
static const KilnPluginDescriptor D = { KILN_ABI_VERSION, KILN_KIND_IMPORTER, "crashing", "1", "crash", import, 0 };
const KilnPluginDescriptor *kiln_plugin_descriptor(void) { return &D; }
"#;

/// A C importer that never returns.
const HANGING_IMPORTER: &str = r#"
#include "kiln_plugin.h"
static int32_t import(const char *path, const KilnSceneBuilder *b, KilnErrorBuffer *e) {
    (void)path; (void)b; (void)e;
    volatile unsigned long spin = 0;
    for (;;) spin++;
    return KILN_STATUS_OK;
}
static const KilnPluginDescriptor D = { KILN_ABI_VERSION, KILN_KIND_IMPORTER, "hanging", "1", "hang", import, 0 };
const KilnPluginDescriptor *kiln_plugin_descriptor(void) { return &D; }
"#;

/// A host whose importers run in the `kiln` worker, with the plugins of `dir`.
fn isolated_host(dir: &Path, timeout: Duration) -> PluginHost {
    let mut host = PluginHost::discover(&[dir.to_owned()]);
    host.isolate_importers(Isolation {
        exe: assert_cmd::cargo::cargo_bin("kiln"),
        plugin_dirs: vec![dir.to_owned()],
        timeout,
    });
    host
}

/// Isolated, an importer that segfaults or hangs fails its import with a message that
/// says so (the hang within its time limit), the host keeps running, and a good importer
/// still works after them, its refusals reported as in process.
#[test]
fn isolated_importers_that_crash_or_hang_fail_their_import_and_kiln_keeps_running() {
    let dir = tempfile::tempdir().unwrap();
    compile_c(dir.path(), "crashing", CRASHING_IMPORTER);
    compile_c(dir.path(), "hanging", HANGING_IMPORTER);
    compile_c(dir.path(), "failing", FAILING_IMPORTER);
    compile_c(dir.path(), "triangle", TRIANGLE_IMPORTER);
    let host = isolated_host(dir.path(), Duration::from_secs(3));
    let error = |file: &str| {
        host.import(Path::new(file))
            .map(|_| ())
            .unwrap_err()
            .to_string()
    };
    let e = error("model.crash");
    assert!(
        e.contains("crashing failed on model.crash: it crashed (SIGSEGV, signal 11)"),
        "{e}"
    );
    let start = Instant::now();
    let e = error("model.hang");
    assert!(
        e.contains("hanging failed on model.hang: it did not finish within 3 s"),
        "{e}"
    );
    // The worker was stopped at its limit, not waited for (a generous guard for a loaded
    // machine, not a timing).
    assert!(start.elapsed() < Duration::from_secs(30));
    // The plugin's own error comes through as it would in process.
    let e = error("model.fail");
    assert!(
        e.contains("failing failed on model.fail: cannot make sense of model.fail"),
        "{e}"
    );
    let imported = host.import(Path::new("anything.tri")).unwrap();
    let mut in_process = PluginHost::default();
    in_process.load_dir(dir.path(), false);
    let expected = in_process.import(Path::new("anything.tri")).unwrap();
    assert_eq!(imported.scene, expected.scene);
    assert_eq!(imported.warnings, expected.warnings);
    assert!(
        imported
            .warnings
            .iter()
            .any(|w| w.contains("index 7 is out of range for 3 vertices")),
        "{:?}",
        imported.warnings
    );

    // Through the CLI: a message and exit code 1, however the plugin ends.
    for (file, says) in [
        ("model.crash", "it crashed (SIGSEGV"),
        ("model.hang", "did not finish within 1 s"),
    ] {
        let (code, _, err) = kiln(&[
            "render",
            file,
            "-q",
            "--isolate-importers",
            "--import-timeout",
            "1",
            "--plugin-dir",
            dir.path().to_str().unwrap(),
        ]);
        assert_eq!(code, 1, "{err}");
        assert!(err.contains(says), "{err}");
    }
}

/// Plugins load only from the documented places: a library in the current folder is
/// never loaded, even one a scene sits beside.
#[test]
fn a_plugin_in_the_current_folder_is_not_loaded() {
    let dir = tempfile::tempdir().unwrap();
    compile_c(dir.path(), "crashing", CRASHING_IMPORTER);
    let out = Command::cargo_bin("kiln")
        .unwrap()
        .arg("plugins")
        .current_dir(dir.path())
        .output()
        .unwrap();
    let listed = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success());
    assert!(!listed.contains("crashing"), "{listed}");
    assert!(listed.contains("(importer; .gltf, .glb)"), "{listed}");
}
