//! Fuzz target: see `luxest_fuzz::peer`.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luxest_fuzz::peer(data));
