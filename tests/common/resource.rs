//! Test resources kept outside the repository: the shared glTF-Validator corpus and the
//! plugin libraries cargo builds beside the test executables. A test that needs one and
//! does not find it fails under CI (where a pass must mean "checked"), and outside CI
//! skips loudly, saying what is missing. Not a fixture loader: the tests read the files.
//!
//! Also compiled into the glTF plugin's tests (`plugins/gltf/tests/common`), by path.

use std::io::Write as _;
use std::path::{Path, PathBuf};

/// Whether the tests run under CI: the `CI` environment variable is set, as CI services
/// set it (`CI=true`), to anything but empty, `0` or `false`.
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !matches!(v.trim(), "" | "0" | "false" | "FALSE"))
}

/// `path` if it exists. Otherwise, under CI, panics naming `what` and `path`; outside CI,
/// prints a skip notice naming them and returns None.
pub fn require(path: &Path, what: &str) -> Option<PathBuf> {
    if path.exists() {
        return Some(path.to_owned());
    }
    if in_ci() {
        panic!(
            "{what} is missing at {} (CI is set, so a missing resource fails the test)",
            path.display()
        );
    }
    // Straight to stderr, not `eprintln!`: the test harness swallows what a passing test
    // prints through the macros, and this notice must be seen.
    let _ = writeln!(
        std::io::stderr(),
        "\n*** SKIPPED: {what} is missing at {}; nothing was checked (under CI=true this fails) ***\n",
        path.display()
    );
    None
}

/// The files below `dir` whose extension is one of `extensions`, sorted. A folder that
/// cannot be read is an error naming it, not an empty list.
pub fn files_with_extensions(dir: &Path, extensions: &[&str]) -> Result<Vec<PathBuf>, String> {
    fn walk(dir: &Path, extensions: &[&str], out: &mut Vec<PathBuf>) -> Result<(), String> {
        let entries =
            std::fs::read_dir(dir).map_err(|e| format!("cannot read {}: {e}", dir.display()))?;
        for entry in entries {
            let path = entry
                .map_err(|e| format!("cannot list {}: {e}", dir.display()))?
                .path();
            if path.is_dir() {
                walk(&path, extensions, out)?;
            } else if path
                .extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| extensions.contains(&e))
            {
                out.push(path);
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(dir, extensions, &mut out)?;
    out.sort();
    Ok(out)
}
