//! Fuzz target: see `luxest_fuzz::sensors`.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luxest_fuzz::sensors(data));
