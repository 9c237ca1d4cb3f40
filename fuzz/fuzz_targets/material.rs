//! The `material` target: `kiln_fuzz::material` (docs/RELIABILITY.md).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| kiln_fuzz::material(data));
