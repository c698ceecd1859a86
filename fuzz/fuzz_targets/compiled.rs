//! Fuzz target: see `luxest_fuzz::compiled`.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luxest_fuzz::compiled(data));
