//! Fuzz target: see `luxest_fuzz::scene_info`.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luxest_fuzz::scene_info(data));
