//! Fuzz target `firmware_serve`: see [`evorec_fuzz::firmware_serve`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| evorec_fuzz::firmware_serve(data));
