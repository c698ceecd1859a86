//! Fuzz target: see `luxest_fuzz::gltf`.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luxest_fuzz::gltf(data));
