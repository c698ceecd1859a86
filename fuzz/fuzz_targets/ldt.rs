//! Fuzz target: see `luxest_fuzz::ldt`.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luxest_fuzz::ldt(data));
