//! glTF images handed to the host: embedded ones (buffer view or data URI) through
//! `add_image`, named `image:N` in graphs; external files by their path relative to the
//! glTF file, which the host resolves.
//!
//! Each image is resolved once. Its first bytes are checked against the formats the host
//! decodes, so an unreadable image costs the textures that use it rather than, when the
//! host refuses the graph, every texture of the material.

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use gltf::json;
use kiln_plugin_api::Builder;

use crate::buffers::{Buffers, Uri, parse_uri};
use crate::texture::ImageFiles;

/// What the host's image decoder reads, told by the first bytes.
fn check_format(head: &[u8]) -> Result<(), String> {
    const KNOWN: [&[u8]; 5] = [
        b"\x89PNG\r\n\x1a\n",
        b"\xFF\xD8\xFF",
        b"\x76\x2F\x31\x01", // OpenEXR
        b"#?RADIANCE",
        b"#?RGBE",
    ];
    if KNOWN.iter().any(|magic| head.starts_with(magic)) {
        return Ok(());
    }
    let what = if head.starts_with(b"RIFF") && head.get(8..12) == Some(b"WEBP") {
        "a WebP image"
    } else if head.starts_with(b"\xABKTX") {
        "a KTX image (KHR_texture_basisu)"
    } else if head.starts_with(b"DDS ") {
        "a DDS image"
    } else {
        "not an image format Kiln reads"
    };
    Err(format!("{what} (Kiln reads PNG, JPEG, EXR and HDR)"))
}

/// Images resolved so far, by glTF image index.
#[derive(Default)]
pub struct ImageCache {
    files: HashMap<usize, Option<String>>,
}

/// [`ImageFiles`] for a real import: embedded images go to the host.
pub struct HostImages<'a, 'b> {
    pub root: &'a json::Root,
    pub buffers: &'a Buffers,
    pub base: &'a Path,
    pub builder: &'a mut Builder<'b>,
    pub cache: &'a mut ImageCache,
}

impl HostImages<'_, '_> {
    fn embed(&mut self, name: &str, bytes: &[u8]) -> Result<String, String> {
        check_format(bytes)?;
        let id = self
            .builder
            .add_image(name, bytes)
            .ok_or_else(|| "the host refused it".to_owned())?;
        Ok(format!("image:{id}"))
    }

    fn resolve(&mut self, index: usize, name: &str) -> Result<String, String> {
        let image = self
            .root
            .images
            .get(index)
            .ok_or_else(|| "does not exist".to_owned())?;
        if let Some(view) = image.buffer_view {
            let (bytes, _) = self.buffers.view(self.root, view.value())?;
            return self.embed(name, bytes);
        }
        let uri = image
            .uri
            .as_deref()
            .ok_or_else(|| "has neither a URI nor a buffer view".to_owned())?;
        match parse_uri(uri)? {
            Uri::Data(bytes) => self.embed(name, &bytes),
            Uri::Relative(relative) => {
                let path = self.base.join(&relative);
                let mut head = Vec::with_capacity(16);
                kiln_plugin_api::read::open_regular(&path)
                    .and_then(|(f, _)| f.take(16).read_to_end(&mut head))
                    .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
                check_format(&head)?;
                Ok(relative)
            }
            Uri::Unsupported(scheme) => Err(format!(
                "\"{scheme}:\" URIs are not supported (only relative paths and data URIs)"
            )),
        }
    }
}

impl ImageFiles for HostImages<'_, '_> {
    fn file(&mut self, index: usize) -> Option<String> {
        if let Some(file) = self.cache.files.get(&index) {
            return file.clone();
        }
        let name = image_name(self.root, index);
        let file = match self.resolve(index, &name) {
            Ok(file) => Some(file),
            Err(e) => {
                self.builder
                    .warn(&format!("{name}: {e}; textures using it are left out"));
                None
            }
        };
        self.cache.files.insert(index, file.clone());
        file
    }
}

/// How messages name image `index`.
pub fn image_name(root: &json::Root, index: usize) -> String {
    let image = root.images.get(index);
    match image.and_then(|i| i.name.as_deref().or(i.uri.as_deref())) {
        Some(n) if !n.starts_with("data:") => format!("image {index} (\"{n}\")"),
        _ => format!("image {index}"),
    }
}

/// [`ImageFiles`] that names image N `image:N` without loading anything: for
/// translating materials without a host ([`crate::material_texts`]).
pub struct NamedImages;

impl ImageFiles for NamedImages {
    fn file(&mut self, index: usize) -> Option<String> {
        Some(format!("image:{index}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_and_jpeg_are_recognised_and_webp_named() {
        assert!(check_format(b"\x89PNG\r\n\x1a\n....").is_ok());
        assert!(check_format(b"\xFF\xD8\xFF\xE0").is_ok());
        let e = check_format(b"RIFF\0\0\0\0WEBPVP8 ").expect_err("not decoded by Kiln");
        assert!(e.contains("WebP"), "{e}");
        assert!(check_format(b"").is_err());
    }
}
