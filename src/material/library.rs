//! The WGSL node library (`shaders/nodes/`), split into top-level items so a kernel
//! includes only the functions its materials call and what those call in turn.

use std::collections::{BTreeSet, HashMap};
use std::sync::OnceLock;

use crate::shader::ShaderFile;

macro_rules! node_file {
    ($path:literal) => {
        ShaderFile {
            path: concat!("shaders/nodes/", $path),
            source: include_str!(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/shaders/nodes/",
                $path
            )),
        }
    };
}

/// The node library's files.
pub const NODE_FILES: &[ShaderFile] = &[
    node_file!("inputs.wgsl"),
    node_file!("hash.wgsl"),
    node_file!("math.wgsl"),
    node_file!("color.wgsl"),
    node_file!("textures.wgsl"),
    node_file!("image.wgsl"),
    node_file!("sky.wgsl"),
    node_file!("volume.wgsl"),
];

/// One top-level declaration (function, struct or constant) with the comment above it.
#[derive(Debug)]
pub struct Item {
    pub name: String,
    pub file: &'static str,
    pub text: String,
    /// Identifiers the item mentions.
    uses: BTreeSet<String>,
}

pub fn items() -> &'static [Item] {
    static ITEMS: OnceLock<Vec<Item>> = OnceLock::new();
    ITEMS.get_or_init(|| {
        NODE_FILES
            .iter()
            .flat_map(|f| split(f.path, f.source))
            .collect()
    })
}

fn identifiers(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut word = String::new();
    for c in text.chars().chain([' ']) {
        if c.is_ascii_alphanumeric() || c == '_' {
            word.push(c);
        } else if !word.is_empty() {
            if !word.starts_with(|c: char| c.is_ascii_digit()) {
                out.insert(std::mem::take(&mut word));
            }
            word.clear();
        }
    }
    out
}

/// Splits a WGSL file into items: each starts at a line beginning `fn `, `struct ` or
/// `const ` and ends where its braces close (or, for a constant, at its `;`).
fn split(file: &'static str, source: &str) -> Vec<Item> {
    let mut items = Vec::new();
    let mut comment = String::new();
    let mut current: Option<(String, String, i32)> = None;
    for line in source.lines() {
        if let Some((name, text, depth)) = current.as_mut() {
            text.push_str(line);
            text.push('\n');
            let code = line.split("//").next().unwrap_or("");
            *depth += code.matches('{').count() as i32 - code.matches('}').count() as i32;
            let done = *depth <= 0 && (code.contains('}') || code.trim_end().ends_with(';'));
            if done {
                let text = std::mem::take(text);
                let body: String = text
                    .lines()
                    .map(|l| l.split("//").next().unwrap_or(""))
                    .collect::<Vec<_>>()
                    .join("\n");
                let mut uses = identifiers(&body);
                uses.remove(name.as_str());
                items.push(Item {
                    name: std::mem::take(name),
                    file,
                    text,
                    uses,
                });
                current = None;
            }
            continue;
        }
        let keyword = ["fn ", "struct ", "const "]
            .into_iter()
            .find(|k| line.starts_with(k));
        match keyword {
            Some(k) => {
                let name: String = line[k.len()..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                let code = line.split("//").next().unwrap_or("");
                let depth = code.matches('{').count() as i32 - code.matches('}').count() as i32;
                let text = format!("{comment}{line}\n");
                comment.clear();
                let single = depth == 0 && (code.contains('}') || code.trim_end().ends_with(';'));
                if single {
                    let mut uses = identifiers(code);
                    uses.remove(&name);
                    items.push(Item {
                        name,
                        file,
                        text,
                        uses,
                    });
                } else {
                    current = Some((name, text, depth));
                }
            }
            None if line.starts_with("//") => {
                comment.push_str(line);
                comment.push('\n');
            }
            None => comment.clear(),
        }
    }
    items
}

/// The items `roots` need, in library order, as WGSL.
pub fn closure(roots: impl IntoIterator<Item = String>) -> String {
    let items = items();
    let by_name: HashMap<&str, usize> = items
        .iter()
        .enumerate()
        .map(|(i, it)| (it.name.as_str(), i))
        .collect();
    let mut needed = vec![false; items.len()];
    let mut stack: Vec<usize> = roots
        .into_iter()
        .filter_map(|r| by_name.get(r.as_str()).copied())
        .collect();
    while let Some(i) = stack.pop() {
        if needed[i] {
            continue;
        }
        needed[i] = true;
        for u in &items[i].uses {
            if let Some(&j) = by_name.get(u.as_str()) {
                if !needed[j] {
                    stack.push(j);
                }
            }
        }
    }
    let mut out = String::new();
    for (i, item) in items.iter().enumerate() {
        if needed[i] {
            out.push_str(&item.text);
            out.push('\n');
        }
    }
    out
}
