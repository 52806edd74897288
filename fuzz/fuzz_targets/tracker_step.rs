//! Fuzz target `tracker_step`: see [`evorec_fuzz::tracker_step`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| evorec_fuzz::tracker_step(data));
