//! Checks of images: exactly one of `uri` and `bufferView` (ONE_OF_MISMATCH), a
//! `mimeType` for buffer views (UNSATISFIED_DEPENDENCY), no byteStride on their views
//! (in [`super::structure`]), URIs that parse (INVALID_URI) and resolve (IO_ERROR), the
//! declared MIME type against the content (IMAGE_MIME_TYPE_INVALID, INVALID_URI), types
//! that need an extension the file does not use (IMAGE_NON_ENABLED_MIME_TYPE), and PNG
//! and JPEG headers that end early or are malformed (IMAGE_UNEXPECTED_EOS,
//! IMAGE_DATA_INVALID). Content Kiln does not recognise is not an error here (the
//! validator only notes it); the importer reports it where a texture uses the image.

use std::borrow::Cow;
use std::io::Read;
use std::path::Path;

use gltf::json;

use super::structure::{data_uri_header, media_type};
use super::{MAX_IMAGE_BYTES, MAX_IMAGE_FILE_BYTES, Report};
use crate::buffers::{Buffers, Uri, parse_uri};
use crate::images::image_name;

/// Formats told by their first bytes, with their MIME type.
const FORMATS: [(&[u8], &str); 4] = [
    (b"\x89PNG\r\n\x1a\n", "image/png"),
    (b"\xFF\xD8\xFF", "image/jpeg"),
    (b"\xABKTX 20\xBB\r\n\x1a\n", "image/ktx2"),
    (b"DDS ", "image/vnd-ms.dds"),
];

/// The MIME type of the content, if its first bytes are of a known format.
fn sniff(head: &[u8]) -> Option<&'static str> {
    if head.starts_with(b"RIFF") && head.get(8..12) == Some(b"WEBP") {
        return Some("image/webp");
    }
    FORMATS
        .iter()
        .find(|(magic, _)| head.starts_with(magic))
        .map(|(_, mime)| *mime)
}

/// The extension a MIME type needs, `Ok(None)` for core types, `Err` for types no glTF
/// image may have.
fn extension_for(mime: &str) -> Result<Option<&'static str>, ()> {
    match mime {
        "image/png" | "image/jpeg" => Ok(None),
        "image/webp" => Ok(Some("EXT_texture_webp")),
        "image/ktx2" => Ok(Some("KHR_texture_basisu")),
        "image/vnd-ms.dds" => Ok(Some("MSFT_texture_dds")),
        "image/avif" => Ok(Some("EXT_texture_avif")),
        _ => Err(()),
    }
}

/// Problems of the header of a PNG or JPEG stream. `complete`: `bytes` is the whole
/// stream (not a prefix), so running out of bytes is the stream's fault.
fn header_problem(mime: &str, bytes: &[u8], complete: bool) -> Option<String> {
    match mime {
        "image/png" => {
            // Signature, then the IHDR chunk: length 13, type, 13 bytes, CRC.
            if bytes.len() < 33 {
                return complete.then(|| "the PNG ends before its header (IHDR) does".to_owned());
            }
            if bytes[8..12] != [0, 0, 0, 13] || &bytes[12..16] != b"IHDR" {
                return Some("the PNG does not start with a valid IHDR chunk".to_owned());
            }
            None
        }
        "image/jpeg" => jpeg_problem(bytes, complete),
        _ => None,
    }
}

/// Walks a JPEG's marker segments up to its frame header (SOFn).
fn jpeg_problem(bytes: &[u8], complete: bool) -> Option<String> {
    let eos = || complete.then(|| "the JPEG ends before its frame header".to_owned());
    let mut at = 2;
    loop {
        // Markers: 0xFF, any fill 0xFF bytes, then the marker code.
        if at >= bytes.len() {
            return eos();
        }
        if bytes[at] != 0xFF {
            return Some(format!(
                "the JPEG has no marker where one must be (byte {at})"
            ));
        }
        while at < bytes.len() && bytes[at] == 0xFF {
            at += 1;
        }
        let Some(&code) = bytes.get(at) else {
            return eos();
        };
        at += 1;
        match code {
            // Standalone markers: TEM, RSTn.
            0x01 | 0xD0..=0xD7 => continue,
            0xD8 | 0xD9 | 0xDA | 0x00 => {
                return Some(format!(
                    "the JPEG has marker 0x{code:02X} before its frame header"
                ));
            }
            _ => {}
        }
        let Some(length) = bytes.get(at..at + 2) else {
            return eos();
        };
        let length = usize::from(u16::from_be_bytes([length[0], length[1]]));
        if length < 2 {
            return Some(format!(
                "the JPEG has a marker segment of invalid length {length}"
            ));
        }
        // SOF0–SOF15 except DHT (C4), JPG (C8) and DAC (CC): the frame header.
        if matches!(code, 0xC0..=0xCF) && !matches!(code, 0xC4 | 0xC8 | 0xCC) {
            return if at + length <= bytes.len() || !complete {
                None
            } else {
                eos()
            };
        }
        at += length;
    }
}

/// The first bytes of an external image (up to [`MAX_IMAGE_BYTES`], and what is left of
/// `budget`, which it spends) and whether they are the whole file.
fn read_head(path: &Path, budget: &mut u64) -> std::io::Result<(Vec<u8>, bool)> {
    let (file, size) = kiln_plugin_api::read::open_regular(path)?;
    let mut head = Vec::new();
    file.take(MAX_IMAGE_BYTES.min(*budget))
        .read_to_end(&mut head)?;
    *budget = budget.saturating_sub(head.len() as u64);
    let complete = size <= head.len() as u64;
    Ok((head, complete))
}

pub fn check(root: &json::Root, buffers: &Buffers, base: &Path, report: &mut Report) {
    let used = |e: &str| root.extensions_used.iter().any(|u| u == e);
    let mut budget = MAX_IMAGE_FILE_BYTES;
    for (i, image) in root.images.iter().enumerate() {
        let mut problems = Vec::new();
        let declared = image.mime_type.as_ref().map(|m| m.0.as_str());
        match (&image.uri, image.buffer_view) {
            (Some(_), Some(_)) => problems.push("it has both a uri and a bufferView".to_owned()),
            (None, None) => problems.push("it has neither a uri nor a bufferView".to_owned()),
            (None, Some(_)) if declared.is_none() => {
                problems.push("it is stored in a buffer view but has no mimeType".to_owned())
            }
            _ => {}
        }
        // The content, whether it is all of it, and the MIME type a data URI declares.
        let mut content: Option<(Cow<[u8]>, bool)> = None;
        let mut uri_type: Option<String> = None;
        if let Some(uri) = &image.uri {
            if let Some(header) = data_uri_header(uri) {
                match media_type(header) {
                    Ok(t) if !t.is_empty() => uri_type = Some(t.to_owned()),
                    Ok(_) => {}
                    Err(e) => problems.push(format!("its data URI is malformed: {e}")),
                }
            }
            match parse_uri(uri) {
                Err(e) => problems.push(format!("its URI is {e}")),
                Ok(Uri::Data(bytes)) => content = Some((Cow::Owned(bytes), true)),
                Ok(Uri::Relative(relative)) => {
                    if relative.is_empty() || relative.starts_with(':') {
                        problems.push(format!("its URI \"{uri}\" is not a valid URI"));
                    } else {
                        let path = base.join(&relative);
                        match read_head(&path, &mut budget) {
                            Ok((head, complete)) => content = Some((Cow::Owned(head), complete)),
                            Err(e) => problems
                                .push(format!("the file \"{relative}\" cannot be read ({e})")),
                        }
                    }
                }
                Ok(Uri::Unsupported(_)) => {}
            }
        } else if let Some(view) = image.buffer_view {
            if let Ok((bytes, _)) = buffers.view(root, view.value()) {
                content = Some((Cow::Borrowed(bytes), true));
            }
        }
        let sniffed = content.as_ref().and_then(|(bytes, _)| sniff(bytes));
        for (what, mime) in [
            ("its data URI", uri_type.as_deref()),
            ("its mimeType", declared),
        ] {
            let Some(mime) = mime else {
                continue;
            };
            match extension_for(mime) {
                Err(()) if sniffed.is_none() => problems.push(format!(
                    "{what} declares \"{mime}\", not an image type glTF allows"
                )),
                Ok(Some(extension)) if !used(extension) => problems.push(format!(
                    "{what} declares \"{mime}\", which needs the extension {extension}, not used by the file"
                )),
                _ => {}
            }
            if let Some(found) = sniffed.filter(|&s| s != mime) {
                problems.push(format!(
                    "{what} declares \"{mime}\" but the data is {found}"
                ));
            }
        }
        if let Some(found) = sniffed {
            if uri_type.is_none() && declared.is_none() {
                if let Ok(Some(extension)) = extension_for(found) {
                    if !used(extension) {
                        problems.push(format!(
                            "it is {found}, which needs the extension {extension}, not used by the file"
                        ));
                    }
                }
            }
            if let Some((bytes, complete)) = &content {
                if let Some(p) = header_problem(found, bytes, *complete) {
                    problems.push(p);
                }
            }
        }
        if !problems.is_empty() {
            report.add(format!("{}: {}", image_name(root, i), problems.join("; ")));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truncated_and_malformed_headers_are_found() {
        let png = b"\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR";
        assert!(header_problem("image/png", png, true).is_some());
        assert!(header_problem("image/png", png, false).is_none());
        let bad_jpeg = b"\xFF\xD8\xFF\x00\x00\x00\x00\x00";
        assert!(header_problem("image/jpeg", bad_jpeg, true).is_some());
        let zero_length = b"\xFF\xD8\xFF\xE0\x00\x00";
        let p = header_problem("image/jpeg", zero_length, true).expect("invalid length");
        assert!(p.contains("length 0"), "{p}");
        // SOI, APP0 of 4 bytes, SOF0 of 11 bytes.
        let mut good = b"\xFF\xD8\xFF\xE0\x00\x04ab\xFF\xC0\x00\x0b".to_vec();
        good.extend_from_slice(&[8, 0, 1, 0, 1, 1, 1, 0x11, 0]);
        assert_eq!(header_problem("image/jpeg", &good, true), None);
        assert!(header_problem("image/jpeg", &good[..10], true).is_some());
        assert_eq!(sniff(b"RIFF\0\0\0\0WEBPVP8 "), Some("image/webp"));
        assert_eq!(sniff(b"GIF89a"), None);
    }
}
