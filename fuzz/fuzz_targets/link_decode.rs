//! Fuzz target `link_decode`: see [`evorec_fuzz::link_decode`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| evorec_fuzz::link_decode(data));
