//! The `scene` target: `kiln_fuzz::scene` (docs/RELIABILITY.md).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| kiln_fuzz::scene(data));
