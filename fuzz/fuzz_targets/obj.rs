//! Fuzz target: see `luxest_fuzz::obj`.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luxest_fuzz::obj(data));
