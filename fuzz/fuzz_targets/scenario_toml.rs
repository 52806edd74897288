//! Fuzz target `scenario_toml`: see [`evorec_fuzz::scenario_toml`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| evorec_fuzz::scenario_toml(data));
