//! Fuzz target: see `luxest_fuzz::ies`.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luxest_fuzz::ies(data));
