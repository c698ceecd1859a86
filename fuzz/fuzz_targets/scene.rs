//! Fuzz target: see `luxest_fuzz::scene`.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luxest_fuzz::scene(data));
