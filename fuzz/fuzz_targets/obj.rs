//! The `obj` target: `kiln_fuzz::obj` with the OBJ importer (docs/RELIABILITY.md).
#![no_main]

use kiln_plugin_api::Importer;

libfuzzer_sys::fuzz_target!(|data: &[u8]| kiln_fuzz::obj(data, kiln_obj::ObjImport::import));
