//! Fuzz target `sequence_files`: see [`evorec_fuzz::sequence_files`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| evorec_fuzz::sequence_files(data));
