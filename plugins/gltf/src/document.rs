//! Reading a `.gltf` or `.glb` file into the JSON model (`gltf::json::Root`) and the GLB's
//! binary chunk, and checking it against the schema.
//!
//! The GLB container is parsed here rather than by the `gltf` crate, whose reader
//! subtracts before it compares (a header length under 12 panics). The JSON goes through
//! a generic value first, so that what the importer ignores (animations) cannot fail it
//! and gltf-json's few demands beyond the spec are met ([`relax`]). Schema violations
//! are reported as one warning and the import goes on: every later read is
//! bounds-checked, so a broken reference costs the object that holds it, not the file.
//! This module does not read buffers or accessors (see `buffers` and `accessor`).

use std::path::Path;

use gltf::json;
use gltf::json::validation::{Checked, Validate};

/// Files (and external buffers) larger than this are refused.
pub use kiln_plugin_api::read::MAX_FILE_BYTES;
use kiln_plugin_api::read::read_bounded;

/// A parsed file: the JSON document and the GLB binary chunk, if any.
pub struct Document {
    pub root: json::Root,
    pub blob: Option<Vec<u8>>,
    /// Animations in the file (not imported; removed before parsing the rest).
    pub animations: usize,
    /// The JSON as written (integers written as `1.0` made integers), before anything
    /// was removed or filled in: for the checks that need what the JSON model drops
    /// (empty arrays, extension objects in any place).
    pub raw: json::Value,
    /// Whether the file is a GLB container.
    pub glb: bool,
    /// Problems of the container or the JSON text that parsing tolerated (a byte-order
    /// mark, a chunk length that is not a multiple of 4).
    pub container_problems: Vec<String>,
}

/// Reads `path`, which may be either JSON glTF or binary GLB (told apart by the magic).
pub fn read(path: &Path) -> Result<Document, String> {
    let bytes = read_file(path)?;
    parse(&bytes)
}

/// Reads a whole regular file of at most [`MAX_FILE_BYTES`].
pub fn read_file(path: &Path) -> Result<Vec<u8>, String> {
    read_bounded(path, MAX_FILE_BYTES).map_err(|e| format!("cannot read {}: {e}", path.display()))
}

/// Parses the bytes of a `.gltf` or `.glb` file.
pub fn parse(bytes: &[u8]) -> Result<Document, String> {
    let glb = bytes.starts_with(b"glTF");
    let mut container_problems = Vec::new();
    let (json_bytes, blob) = if glb {
        let (json_bytes, blob) = split(bytes, &mut container_problems)?;
        (json_bytes, blob.map(<[u8]>::to_vec))
    } else {
        (bytes, None)
    };
    // A UTF-8 byte-order mark is forbidden by the spec but written by some tools, as is
    // a GLB JSON chunk padded with NULs instead of spaces.
    let json_bytes = match json_bytes.strip_prefix(b"\xEF\xBB\xBF") {
        Some(rest) => {
            container_problems.push(
                "the JSON starts with a UTF-8 byte-order mark, which glTF forbids".to_owned(),
            );
            rest
        }
        None => json_bytes,
    };
    let end = json_bytes
        .iter()
        .rposition(|&b| b != 0)
        .map_or(0, |i| i + 1);
    let json_bytes = &json_bytes[..end];
    let mut value: json::Value = json::deserialize::from_slice(json_bytes)
        .map_err(|e| format!("not a valid JSON document: {e}"))?;
    check_version(&value)?;
    integral_floats(&mut value);
    let raw = value.clone();
    let animations = relax(&mut value);
    let root: json::Root = json::deserialize::from_value(value)
        .map_err(|e| format!("not a valid glTF document: {e}"))?;
    Ok(Document {
        root,
        blob,
        animations,
        raw,
        glb,
        container_problems,
    })
}

fn check_version(value: &json::Value) -> Result<(), String> {
    let Some(version) = value
        .pointer("/asset/version")
        .and_then(json::Value::as_str)
    else {
        return Err("not a glTF document: no asset.version".into());
    };
    let major = version.split('.').next().unwrap_or("");
    if major != "2" {
        return Err(format!(
            "glTF version \"{version}\" is not supported (this importer reads glTF 2.x)"
        ));
    }
    Ok(())
}

/// Integers written with a fraction (`1.0`), which JSON and the validator accept and
/// serde's integer fields do not, rewritten as integers. serde_json's recursion limit
/// bounds the depth.
fn integral_floats(value: &mut json::Value) {
    match value {
        json::Value::Number(n) if n.is_f64() => {
            let f = n.as_f64().unwrap_or(f64::NAN);
            if f.fract() == 0.0 && f.abs() < 9.0e15 {
                *value = if f >= 0.0 {
                    json::Value::from(f as u64)
                } else {
                    json::Value::from(f as i64)
                };
            }
        }
        json::Value::Array(items) => items.iter_mut().for_each(integral_floats),
        json::Value::Object(fields) => fields.values_mut().for_each(integral_floats),
        _ => {}
    }
}

/// Removes what this importer does not read and gltf-json parses more strictly than
/// the spec (animations: KHR_animation_pointer channels have no `node`), and fills in
/// what the spec makes optional but gltf-json requires (a scene's `nodes`; integers
/// written as `1.0` are rewritten by [`integral_floats`] first). Returns the number of
/// animations removed.
fn relax(value: &mut json::Value) -> usize {
    let Some(object) = value.as_object_mut() else {
        return 0;
    };
    let animations = match object.remove("animations") {
        Some(json::Value::Array(a)) => a.len(),
        _ => 0,
    };
    if let Some(json::Value::Array(scenes)) = object.get_mut("scenes") {
        for scene in scenes.iter_mut().filter_map(json::Value::as_object_mut) {
            scene
                .entry("nodes")
                .or_insert_with(|| json::Value::Array(Vec::new()));
        }
    }
    animations
}

fn le_u32(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// Splits a GLB (glTF 2.0 spec §4.4) into its JSON chunk and optional BIN chunk.
/// Chunks of other types are skipped, as the spec asks.
pub fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    split(bytes, &mut Vec::new())
}

/// [`split_glb`], noting in `problems` what it tolerates (unaligned chunk lengths).
fn split<'a>(
    bytes: &'a [u8],
    problems: &mut Vec<String>,
) -> Result<(&'a [u8], Option<&'a [u8]>), String> {
    let header = |what: &str| format!("not a valid GLB file: {what}");
    let version = le_u32(bytes, 4).ok_or_else(|| header("truncated header"))?;
    if version != 2 {
        return Err(format!(
            "GLB container version {version} is not supported (version 2 only)"
        ));
    }
    let length = le_u32(bytes, 8).ok_or_else(|| header("truncated header"))? as usize;
    if length < 12 || length > bytes.len() {
        return Err(header(&format!(
            "the header gives a length of {length} bytes; the file has {}",
            bytes.len()
        )));
    }
    let data = &bytes[..length];
    let mut at = 12;
    let mut json = None;
    let mut bin = None;
    let mut index = 0;
    while at < data.len() {
        let (Some(chunk_length), Some(kind)) = (le_u32(data, at), le_u32(data, at + 4)) else {
            return Err(header(&format!("chunk {index} has a truncated header")));
        };
        let start = at + 8;
        let end = start
            .checked_add(chunk_length as usize)
            .filter(|&end| end <= data.len())
            .ok_or_else(|| {
                header(&format!(
                    "chunk {index} claims {chunk_length} bytes past the end of the file"
                ))
            })?;
        let chunk = &data[start..end];
        if chunk_length % 4 != 0 {
            problems.push(format!(
                "the GLB's chunk {index} is {chunk_length} bytes long, not a multiple of 4 as the spec requires"
            ));
        }
        match (index, kind) {
            (0, CHUNK_JSON) => json = Some(chunk),
            (0, _) => return Err(header("the first chunk is not JSON")),
            (1, CHUNK_BIN) => bin = Some(chunk),
            (_, CHUNK_JSON) => return Err(header("more than one JSON chunk")),
            (_, CHUNK_BIN) => return Err(header("a BIN chunk that is not the second chunk")),
            _ => {}
        }
        // Chunks are padded to 4 bytes; a missing final padding is tolerated.
        at = end.saturating_add(3) & !3;
        index += 1;
    }
    let json = json.ok_or_else(|| header("no JSON chunk"))?;
    Ok((json, bin))
}

/// Schema violations, as `path: problem` lines. Unsupported entries of
/// `extensionsRequired` are left to `extensions::check`, which knows what this importer
/// handles (the `gltf` crate only knows the extensions it parses).
pub fn schema_problems(root: &mut json::Root) -> Vec<String> {
    let mut problems = Vec::new();
    // gltf-json's primitive check indexes `accessors` with the POSITION index unchecked:
    // drop dangling POSITION references first (the primitive is then reported and skipped).
    let accessor_count = root.accessors.len();
    for (m, mesh) in root.meshes.iter_mut().enumerate() {
        for (p, primitive) in mesh.primitives.iter_mut().enumerate() {
            let key = Checked::Valid(json::mesh::Semantic::Positions);
            let dangling = primitive.attributes.get(&key).map(|i| i.value());
            if let Some(index) = dangling.filter(|&i| i >= accessor_count) {
                problems.push(format!(
                    "meshes[{m}].primitives[{p}].attributes.POSITION: accessor {index} does not exist"
                ));
                primitive.attributes.remove(&key);
            }
        }
    }
    let root = &*root;
    root.validate(root, json::Path::new, &mut |path, error| {
        let path = path();
        let p = path.as_str();
        let unsupported_required = matches!(error, json::validation::Error::Unsupported)
            && p.starts_with("extensionsRequired");
        // gltf-json requires these; the spec does not (an accessor without a buffer view
        // is zeros, a texture's source may come from an extension).
        let optional = matches!(error, json::validation::Error::Missing)
            && ((p.starts_with("accessors[") && p.ends_with("].bufferView"))
                || (p.starts_with("textures[") && p.ends_with("].source")));
        if !unsupported_required && !optional {
            problems.push(format!("{path}: {error}"));
        }
    });
    problems
}

#[cfg(test)]
mod tests {
    use super::*;

    fn glb(chunks: &[(u32, &[u8])], length_delta: i64) -> Vec<u8> {
        let mut body = Vec::new();
        for (kind, data) in chunks {
            body.extend_from_slice(&(data.len() as u32).to_le_bytes());
            body.extend_from_slice(&kind.to_le_bytes());
            body.extend_from_slice(data);
            while body.len() % 4 != 0 {
                body.push(b' ');
            }
        }
        let mut out = b"glTF".to_vec();
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&((12 + body.len()) as i64 + length_delta).to_le_bytes()[..4]);
        out.extend_from_slice(&body);
        out
    }

    #[test]
    fn glb_chunks_are_split_and_unknown_chunks_skipped() {
        let json = br#"{"asset":{"version":"2.0"}}"#;
        let bytes = glb(&[(CHUNK_JSON, json), (CHUNK_BIN, b"abcd"), (7, b"xx")], 0);
        let (j, b) = split_glb(&bytes).expect("valid GLB");
        assert_eq!(j, json);
        assert_eq!(b, Some(&b"abcd"[..]));
        assert!(parse(&bytes).is_ok());
    }

    #[test]
    fn glb_with_lying_lengths_is_an_error_not_a_panic() {
        let json = br#"{"asset":{"version":"2.0"}}"#;
        let good = glb(&[(CHUNK_JSON, json)], 0);
        assert!(split_glb(&glb(&[(CHUNK_JSON, json)], 4)).is_err());
        assert!(split_glb(&glb(&[(CHUNK_JSON, json)], -100)).is_err());
        let mut huge_chunk = good.clone();
        huge_chunk[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(split_glb(&huge_chunk).is_err());
        for n in 0..good.len() {
            let _ = parse(&good[..n]);
        }
    }

    #[test]
    fn glb_whose_first_chunk_is_binary_is_refused() {
        let bytes = glb(&[(CHUNK_BIN, b"abcd")], 0);
        assert!(split_glb(&bytes).is_err());
    }

    #[test]
    fn gltf_1_is_refused_with_its_version() {
        let e = parse(br#"{"asset":{"version":"1.0"}}"#)
            .err()
            .expect("refused");
        assert!(e.contains("1.0"), "{e}");
    }
}
