//! The Khronos glTF-Validator test corpus (372 files, most deliberately broken): every
//! file must import or fail with a message, never panic, hang or hand the host data it
//! would refuse; every material graph made from the corpus's valid files must compile.

mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;

/// Per-file limit: the largest corpus file imports in milliseconds.
const LIMIT: Duration = Duration::from_secs(5);

fn corpus() -> Option<PathBuf> {
    let dir = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/corpus/gltf-validator/test"
    ));
    dir.is_dir().then(|| dir.to_owned())
}

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            files(&path, out);
        } else if matches!(
            path.extension().and_then(|e| e.to_str()),
            Some("gltf" | "glb")
        ) {
            out.push(path);
        }
    }
}

/// Whether the validator's report for `path` lists no errors.
fn valid(path: &Path) -> bool {
    let mut report = path.as_os_str().to_owned();
    report.push(".report.json");
    let Ok(bytes) = std::fs::read(&report) else {
        return false;
    };
    let Ok(json) = gltf::json::deserialize::from_slice::<gltf::json::Value>(&bytes) else {
        return false;
    };
    json.pointer("/issues/numErrors").and_then(|v| v.as_u64()) == Some(0)
}

#[test]
fn every_corpus_file_imports_or_fails_cleanly() {
    let Some(dir) = corpus() else {
        eprintln!("skipped: the glTF-Validator corpus is not in shared/corpus");
        return;
    };
    let mut paths = Vec::new();
    files(&dir, &mut paths);
    assert!(paths.len() > 300, "only {} corpus files found", paths.len());
    let (mut ok, mut ok_warned, mut refused) = (0, 0, 0);
    let mut failures = Vec::new();
    let mut slow = Vec::new();
    let mut slowest = (Duration::ZERO, String::new());
    for path in &paths {
        let name = path
            .strip_prefix(&dir)
            .unwrap_or(path)
            .display()
            .to_string();
        let Some((result, recorded, elapsed)) = common::import_with_timeout(path, LIMIT) else {
            failures.push(format!("{name}: no result within {LIMIT:?}"));
            continue;
        };
        if elapsed > slowest.0 {
            slowest = (elapsed, name.clone());
        }
        if elapsed > Duration::from_secs(1) {
            slow.push(format!("{name}: {elapsed:?}"));
        }
        match &result {
            Err(e) if e.contains("panicked") => failures.push(format!("{name}: {e}")),
            // A file the validator finds no error in is refused only for an extension
            // it requires that this importer lacks, or data it keeps on the web.
            Err(e)
                if valid(path)
                    && !e.contains("requires the glTF extension")
                    && !e.contains("URIs are not supported") =>
            {
                failures.push(format!("{name}: valid, but refused: {e}"));
            }
            Err(_) => refused += 1,
            Ok(()) if recorded.warnings.is_empty() => ok += 1,
            Ok(()) => ok_warned += 1,
        }
        for v in &recorded.violations {
            failures.push(format!("{name}: sent data the host refuses: {v}"));
        }
        if std::env::var_os("KILN_GLTF_CORPUS_LOG").is_some() {
            match &result {
                Ok(()) => eprintln!("OK   {name}: {:?}", recorded.warnings),
                Err(e) => eprintln!("ERR  {name}: {e}"),
            }
        }
    }
    eprintln!(
        "{} files: {ok} imported cleanly, {ok_warned} with warnings, {refused} refused; slower than 1 s: {slow:?}; slowest {} in {:?}",
        paths.len(),
        slowest.1,
        slowest.0
    );
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn every_material_of_the_valid_corpus_files_compiles() {
    let Some(dir) = corpus() else {
        eprintln!("skipped: the glTF-Validator corpus is not in shared/corpus");
        return;
    };
    let mut paths = Vec::new();
    files(&dir, &mut paths);
    let mut failures = Vec::new();
    let mut checked = 0;
    for path in paths.iter().filter(|p| valid(p)) {
        let Ok(texts) = kiln_gltf::material_texts(path) else {
            continue;
        };
        for (name, kmat) in texts {
            checked += 1;
            if let Err(e) = common::compile_kmat(&name, &kmat) {
                failures.push(format!("{}: {name}: {e}", path.display()));
            }
        }
    }
    eprintln!("{checked} material graphs compiled");
    assert!(checked > 50, "only {checked} graphs checked");
    assert!(failures.is_empty(), "{failures:#?}");
}
