//! Fuzz target: see `luxest_fuzz::texture_exr`.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luxest_fuzz::texture_exr(data));
