//! Rules of the code base that no compiler checks, read from the source itself.

use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn the_library_never_prints() {
    // The library reports through return values, `tracing` and writers its callers pass;
    // only the binary (src/main.rs) owns the terminal.
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    assert!(files.len() > 20, "only {} source files found", files.len());
    let mut offences = Vec::new();
    for file in files.iter().filter(|f| !f.ends_with("src/main.rs")) {
        let text = std::fs::read_to_string(file).unwrap();
        for (i, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            if ["println!", "eprintln!", "print!", "eprint!", "dbg!"]
                .iter()
                .any(|m| code.contains(m))
            {
                offences.push(format!("{}:{}: {}", file.display(), i + 1, line.trim()));
            }
        }
    }
    assert!(
        offences.is_empty(),
        "the library prints:\n{}",
        offences.join("\n")
    );
}

/// The library's layers, bottom to top: a module may use the ones before it and none
/// after (docs/ARCHITECTURE.md explains each). `bench` drives everything, like the binary.
const LAYERS: [&str; 11] = [
    "limits", "shader", "material", "scene", "accel", "film", "render", "farm", "plugin", "bench",
    "editor",
];

/// The top-level modules `text` names through `crate::`, outside comments:
/// `crate::scene::Scene` and `crate::{scene::Scene, film}` alike.
fn crate_modules_used(text: &str) -> Vec<String> {
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let mut used = Vec::new();
    for line in text.lines() {
        let code = line.split("//").next().unwrap_or("");
        for (at, _) in code.match_indices("crate::") {
            let rest = &code[at + "crate::".len()..];
            if let Some(group) = rest.strip_prefix('{') {
                // Only the group's top-level names are modules of the crate.
                let mut depth = 0;
                let mut start = true;
                for (i, c) in group.char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' if depth == 0 => break,
                        '}' => depth -= 1,
                        ',' if depth == 0 => start = true,
                        c if start && !c.is_whitespace() => {
                            start = false;
                            used.push(ident(&group[i..]));
                        }
                        _ => {}
                    }
                }
            } else {
                used.push(ident(rest));
            }
        }
    }
    used
}

#[test]
fn the_dependency_reader_sees_paths_groups_and_ignores_comments() {
    let text = "use crate::scene::Scene;\n\
                use crate::{film::Film, render::{self, Renderer}};\n\
                let x = crate::accel::build(); // crate::plugin in a comment\n\
                /// [`crate::bench`] in a doc comment\n";
    assert_eq!(
        crate_modules_used(text),
        ["scene", "film", "render", "accel"]
    );
}

#[test]
fn layers_point_one_way() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    let modules: Vec<&str> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("pub mod ")?.strip_suffix(';'))
        .collect();
    let mut sorted_layers = LAYERS.to_vec();
    sorted_layers.sort();
    let mut sorted_modules = modules.clone();
    sorted_modules.sort();
    assert_eq!(
        sorted_modules, sorted_layers,
        "every module of lib.rs has a place in LAYERS (and docs/ARCHITECTURE.md)"
    );

    let mut offences = Vec::new();
    for (level, module) in LAYERS.iter().enumerate() {
        let mut files = Vec::new();
        let dir = src.join(module);
        if dir.is_dir() {
            rust_files(&dir, &mut files);
        } else {
            files.push(src.join(format!("{module}.rs")));
        }
        for file in files {
            let text = std::fs::read_to_string(&file).unwrap();
            for used in crate_modules_used(&text) {
                let Some(used_level) = LAYERS.iter().position(|l| *l == used) else {
                    offences.push(format!("{}: crate::{used} is no layer", file.display()));
                    continue;
                };
                if used_level > level {
                    offences.push(format!(
                        "{}: the {module} layer uses crate::{used}, a layer above it",
                        file.display()
                    ));
                }
            }
        }
    }
    assert!(offences.is_empty(), "{}", offences.join("\n"));
}
