//! Fuzz target: see `luxest_fuzz::ply`.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luxest_fuzz::ply(data));
