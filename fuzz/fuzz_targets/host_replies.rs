//! Fuzz target `host_replies`: see [`evorec_fuzz::host_replies`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| evorec_fuzz::host_replies(data));
