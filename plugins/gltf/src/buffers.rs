//! The bytes behind a document: buffers loaded from data URIs, files next to the `.gltf`
//! or the GLB's binary chunk, and bounds-checked slices of their buffer views.
//!
//! Buffers are loaded eagerly and a buffer whose file is missing or unreadable fails the
//! import with its name: a missing `.bin` is a broken file, not a detail to render around.
//! A URI with a scheme this importer does not fetch (`http:`, …) is not an error until a
//! buffer view reads it. Images are not loaded here (see `images`).

use std::path::Path;

use base64::Engine;
use gltf::json;

use crate::document::{MAX_FILE_BYTES, read_file};

/// The loaded buffers, in document order, each cut to its declared `byteLength`.
pub struct Buffers {
    /// Per buffer, its bytes or why it has none. A buffer without bytes is an error only
    /// where a buffer view reads it, so a file that declares an unreachable buffer it never
    /// uses still imports (the glTF-Validator finds such files valid).
    data: Vec<Result<Vec<u8>, String>>,
}

/// Where a URI points.
pub enum Uri<'a> {
    /// `data:...`, decoded.
    Data(Vec<u8>),
    /// A path relative to the glTF file (percent-decoded).
    Relative(String),
    /// A scheme this importer does not fetch (`http:`, …).
    Unsupported(&'a str),
}

/// Classifies and, for data URIs, decodes `uri`.
pub fn parse_uri(uri: &str) -> Result<Uri<'_>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (header, payload) = rest
            .split_once(',')
            .ok_or_else(|| "a data URI without a ','".to_owned())?;
        if header.ends_with(";base64") {
            // Padding is optional in practice; whitespace is not allowed but appears.
            let cleaned: String = payload
                .chars()
                .filter(|c| !c.is_ascii_whitespace())
                .collect();
            let engine = base64::engine::GeneralPurpose::new(
                &base64::alphabet::STANDARD,
                base64::engine::GeneralPurposeConfig::new()
                    .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent),
            );
            return engine
                .decode(cleaned.as_bytes())
                .map(Uri::Data)
                .map_err(|e| format!("a data URI with invalid base64: {e}"));
        }
        return Ok(Uri::Data(percent_decode(payload)));
    }
    // RFC 3986: a scheme is letters, digits, '+', '-', '.' before the first ':', and
    // starts with a letter. A drive letter (`C:`) is one letter: treat it as a path.
    if let Some((scheme, _)) = uri.split_once(':') {
        let is_scheme = scheme.len() > 1
            && scheme.starts_with(|c: char| c.is_ascii_alphabetic())
            && scheme
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c));
        if is_scheme {
            return Ok(Uri::Unsupported(scheme));
        }
    }
    let decoded = percent_decode(uri);
    Ok(Uri::Relative(
        String::from_utf8_lossy(&decoded).into_owned(),
    ))
}

/// `%XX` escapes decoded; malformed escapes are kept as written.
pub fn percent_decode(s: &str) -> Vec<u8> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    out
}

impl Buffers {
    /// Loads every buffer of `root`; external files are resolved against `base`.
    pub fn load(root: &json::Root, base: &Path, mut blob: Option<Vec<u8>>) -> Result<Self, String> {
        let mut data = Vec::with_capacity(root.buffers.len());
        for (i, buffer) in root.buffers.iter().enumerate() {
            let name = buffer.name.as_deref().map_or_else(
                || format!("buffer {i}"),
                |n| format!("buffer {i} (\"{n}\")"),
            );
            let mut bytes = match &buffer.uri {
                None => match blob.take() {
                    Some(blob) => blob,
                    None => {
                        data.push(Err("no URI, no GLB binary chunk".to_owned()));
                        continue;
                    }
                },
                Some(uri) => match parse_uri(uri).map_err(|e| format!("{name}: {e}"))? {
                    Uri::Data(bytes) => bytes,
                    Uri::Relative(relative) => {
                        let path = base.join(&relative);
                        if !path.is_file() {
                            return Err(format!(
                                "{name}: the file \"{relative}\" was not found (looked for {})",
                                path.display()
                            ));
                        }
                        read_file(&path).map_err(|e| format!("{name}: {e}"))?
                    }
                    Uri::Unsupported(scheme) => {
                        data.push(Err(format!(
                            "its \"{scheme}:\" URI is not fetched (only relative paths and data URIs are read)"
                        )));
                        continue;
                    }
                },
            };
            let length = buffer.byte_length.0;
            if (bytes.len() as u64) < length {
                return Err(format!(
                    "{name} holds {} bytes, fewer than its byteLength of {length}",
                    bytes.len()
                ));
            }
            // Bytes past byteLength (GLB padding) are not part of the buffer.
            bytes.truncate(length.min(MAX_FILE_BYTES) as usize);
            data.push(Ok(bytes));
        }
        Ok(Self { data })
    }

    /// Whether buffer `index` has bytes (it exists and was given a URI or the GLB chunk).
    pub fn has_data(&self, index: usize) -> bool {
        matches!(self.data.get(index), Some(Ok(_)))
    }

    /// The bytes of buffer view `index`, and its stride if it declares one.
    pub fn view(&self, root: &json::Root, index: usize) -> Result<(&[u8], Option<usize>), String> {
        let view = root
            .buffer_views
            .get(index)
            .ok_or_else(|| format!("buffer view {index} does not exist"))?;
        let buffer = view.buffer.value();
        let data = self
            .data
            .get(buffer)
            .ok_or_else(|| format!("buffer view {index}: buffer {buffer} does not exist"))?
            .as_ref()
            .map_err(|why| format!("buffer view {index}: buffer {buffer} has no data: {why}"))?;
        let offset = view.byte_offset.map_or(0, |o| o.0);
        let length = view.byte_length.0;
        let end = offset
            .checked_add(length)
            .filter(|&e| e <= data.len() as u64);
        let Some(end) = end else {
            return Err(format!(
                "buffer view {index} (offset {offset}, length {length}) does not fit in buffer {buffer} of {} bytes",
                data.len()
            ));
        };
        let stride = view.byte_stride.map(|s| s.0);
        Ok((&data[offset as usize..end as usize], stride))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_uris_decode_with_and_without_padding() {
        let Ok(Uri::Data(d)) = parse_uri("data:application/octet-stream;base64,AAECAw==") else {
            panic!("not decoded");
        };
        assert_eq!(d, [0, 1, 2, 3]);
        let Ok(Uri::Data(d)) = parse_uri("data:application/octet-stream;base64,AAECAw") else {
            panic!("not decoded");
        };
        assert_eq!(d, [0, 1, 2, 3]);
        assert!(parse_uri("data:application/octet-stream;base64,@@@").is_err());
    }

    #[test]
    fn relative_uris_are_percent_decoded_and_schemes_refused() {
        let Ok(Uri::Relative(p)) = parse_uri("my%20model.bin") else {
            panic!("not relative");
        };
        assert_eq!(p, "my model.bin");
        assert!(matches!(
            parse_uri("https://example.com/a.bin"),
            Ok(Uri::Unsupported("https"))
        ));
        assert!(matches!(parse_uri("C:model.bin"), Ok(Uri::Relative(_))));
        assert_eq!(percent_decode("100%"), b"100%");
        assert_eq!(percent_decode("%zz%4"), b"%zz%4");
    }
}
