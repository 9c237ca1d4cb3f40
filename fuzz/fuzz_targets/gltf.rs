//! The `gltf` target: `kiln_fuzz::gltf` with the glTF importer (docs/RELIABILITY.md).
#![no_main]

use kiln_plugin_api::Importer;

libfuzzer_sys::fuzz_target!(|data: &[u8]| kiln_fuzz::gltf(data, kiln_gltf::GltfImporter::import));
