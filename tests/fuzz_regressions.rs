//! Every input a fuzz target found a bug with (minimised, in `fuzz/regressions/<target>/`)
//! runs through that target's code here, so the bug stays fixed (docs/RELIABILITY.md).

use std::path::Path;

use kiln_plugin_api::Importer;

// The glTF target is not replayed here (see `TARGETS`).
#[allow(dead_code)]
#[path = "../fuzz/src/lib.rs"]
mod fuzz_targets;

/// A fuzz target's body.
type Target = fn(&[u8]);

/// The targets by the name of their folder in `fuzz/regressions/`. Only one importer crate
/// can be linked into a binary (`fuzz/src/lib.rs`): glTF regressions, once there are any,
/// get a test file of their own.
const TARGETS: [(&str, Target); 3] = [
    ("scene", fuzz_targets::scene),
    ("material", fuzz_targets::material),
    ("obj", |data| {
        fuzz_targets::obj(data, kiln_obj::ObjImport::import)
    }),
];

#[test]
fn every_fuzz_regression_input_passes_its_target() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions");
    let mut checked = 0;
    for (name, target) in TARGETS {
        let Ok(entries) = std::fs::read_dir(root.join(name)) else {
            continue;
        };
        for entry in entries {
            let path = entry.expect("a regression input").path();
            let data = std::fs::read(&path).expect("reading a regression input");
            if std::panic::catch_unwind(|| target(&data)).is_err() {
                panic!("{}: the {name} target panics", path.display());
            }
            checked += 1;
        }
    }
    assert!(checked > 0, "no regression inputs under {}", root.display());
}
