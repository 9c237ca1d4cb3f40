//! The Khronos glTF-Validator test corpus (372 files, most deliberately broken): every
//! file must import or fail with a message, never panic, hang or hand the host data it
//! would refuse; every material graph made from the corpus's valid files must compile.

mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;

use common::resource;

/// A guard against hangs, not a performance assertion (timings belong in the benchmarks):
/// the largest corpus file imports in milliseconds, so a minute without an answer is stuck.
const HANG_GUARD: Duration = Duration::from_secs(60);

/// The corpus as stored holds 372 .gltf/.glb files, each with its validator report, 129 of
/// them without errors. Fewer means the corpus is incomplete and the tests check less than
/// they say.
const MIN_CORPUS_FILES: usize = 372;
const MIN_VALID_FILES: usize = 129;
/// The material graphs the valid files translate to, as measured on the stored corpus.
const MIN_MATERIAL_GRAPHS: usize = 261;

/// Files the validator finds no error in that the importer refuses, by path below the
/// corpus, each with the reason. Every other valid file must import; a listed file that
/// imports fails the test too, so the list cannot go stale.
/// None at present: the last one, `base/data/buffer/non_relative_uri.gltf` (an unused
/// buffer at an http: URL), imports since unreachable buffers fail only where they are read.
const REFUSED_VALID_FILES: &[(&str, &str)] = &[];

/// The corpus folder and its .gltf/.glb files; None (a loud skip) when it is missing
/// outside CI.
fn corpus() -> Option<(PathBuf, Vec<PathBuf>)> {
    let dir = resource::require(
        Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/corpus/gltf-validator/test"
        )),
        "the glTF-Validator corpus",
    )?;
    let paths =
        resource::files_with_extensions(&dir, &["gltf", "glb"]).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        paths.len() >= MIN_CORPUS_FILES,
        "only {} .gltf/.glb files under {}, expected at least {MIN_CORPUS_FILES}",
        paths.len(),
        dir.display()
    );
    Some((dir, paths))
}

/// Whether the validator's report for `path` lists no errors; an error naming the report
/// when it is missing or unparsable.
fn valid(path: &Path) -> Result<bool, String> {
    let mut report = path.as_os_str().to_owned();
    report.push(".report.json");
    let report = PathBuf::from(report);
    let bytes = std::fs::read(&report)
        .map_err(|e| format!("no validator report {}: {e}", report.display()))?;
    let json = gltf::json::deserialize::from_slice::<gltf::json::Value>(&bytes)
        .map_err(|e| format!("unparsable validator report {}: {e}", report.display()))?;
    let errors = json
        .pointer("/issues/numErrors")
        .and_then(|v| v.as_u64())
        .ok_or_else(|| format!("no issues.numErrors in {}", report.display()))?;
    Ok(errors == 0)
}

/// `path` below the corpus folder, with forward slashes: how [`REFUSED_VALID_FILES`]
/// names it.
fn name(dir: &Path, path: &Path) -> String {
    path.strip_prefix(dir)
        .expect("found below the corpus")
        .to_string_lossy()
        .replace('\\', "/")
}

#[test]
fn every_corpus_file_imports_or_fails_cleanly() {
    let Some((dir, paths)) = corpus() else {
        return;
    };
    let (mut ok, mut ok_warned, mut refused, mut valid_files) = (0, 0, 0, 0);
    let mut failures = Vec::new();
    let mut slow = Vec::new();
    let mut slowest = (Duration::ZERO, String::new());
    for path in &paths {
        let name = name(&dir, path);
        let (result, recorded, elapsed) = match common::import_with_timeout(path, HANG_GUARD) {
            Ok(answer) => answer,
            Err(e) => {
                failures.push(format!("{name}: {e}"));
                continue;
            }
        };
        if elapsed > slowest.0 {
            slowest = (elapsed, name.clone());
        }
        if elapsed > Duration::from_secs(1) {
            slow.push(format!("{name}: {elapsed:?}"));
        }
        let valid = match valid(path) {
            Ok(valid) => valid,
            Err(e) => {
                failures.push(format!("{name}: {e}"));
                continue;
            }
        };
        valid_files += usize::from(valid);
        let listed = REFUSED_VALID_FILES.iter().any(|(f, _)| *f == name);
        match &result {
            Err(e) if e.contains("panicked") => failures.push(format!("{name}: {e}")),
            Err(e) if e.is_empty() => failures.push(format!("{name}: refused without a message")),
            Err(e) if valid && !listed => {
                failures.push(format!("{name}: valid, but refused: {e}"));
            }
            Err(_) => refused += 1,
            Ok(()) if listed => failures.push(format!(
                "{name}: imports, but REFUSED_VALID_FILES says it is refused; remove it there"
            )),
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
        "{} files ({valid_files} valid): {ok} imported cleanly, {ok_warned} with warnings, {refused} refused; slower than 1 s: {slow:?}; slowest {} in {:?}",
        paths.len(),
        slowest.1,
        slowest.0
    );
    for (listed, _) in REFUSED_VALID_FILES {
        if !paths.iter().any(|p| p.ends_with(listed)) {
            failures.push(format!(
                "{listed}: in REFUSED_VALID_FILES but not in the corpus"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
    assert!(
        valid_files >= MIN_VALID_FILES,
        "only {valid_files} files the validator finds valid, expected at least {MIN_VALID_FILES}"
    );
}

#[test]
fn every_material_of_the_valid_corpus_files_compiles() {
    let Some((dir, paths)) = corpus() else {
        return;
    };
    let mut failures = Vec::new();
    let mut checked = 0;
    for path in &paths {
        let name = name(&dir, path);
        match valid(path) {
            Ok(true) => {}
            Ok(false) => continue,
            Err(e) => {
                failures.push(format!("{name}: {e}"));
                continue;
            }
        }
        let texts = match kiln_gltf::material_texts(path) {
            Ok(texts) => texts,
            // Listed with its reason; the import test checks the list is current.
            Err(_) if REFUSED_VALID_FILES.iter().any(|(f, _)| *f == name) => continue,
            Err(e) => {
                failures.push(format!("{name}: valid, but not translated: {e}"));
                continue;
            }
        };
        for (material, kmat) in texts {
            checked += 1;
            if let Err(e) = common::compile_kmat(&material, &kmat) {
                failures.push(format!("{name}: {material}: {e}"));
            }
        }
    }
    eprintln!("{checked} material graphs compiled");
    assert!(failures.is_empty(), "{failures:#?}");
    assert!(
        checked >= MIN_MATERIAL_GRAPHS,
        "only {checked} graphs checked, expected at least {MIN_MATERIAL_GRAPHS}"
    );
}
