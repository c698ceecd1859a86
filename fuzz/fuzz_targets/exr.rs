//! Fuzz target: see `luxest_fuzz::exr`.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luxest_fuzz::exr(data));
