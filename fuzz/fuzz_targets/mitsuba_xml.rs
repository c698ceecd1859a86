//! Fuzz target: see `luxest_fuzz::mitsuba_xml`.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luxest_fuzz::mitsuba_xml(data));
