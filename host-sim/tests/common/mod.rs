//! What the command-line tests share: a scratch directory per test and a run of the binary.

use std::path::PathBuf;
use std::process::{Command, Output};

/// A fresh scratch directory `evorec-<suite>-<pid>-<name>` under the system's temporary one.
pub fn scratch(suite: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("evorec-{suite}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("creating {}: {e}", dir.display()));
    dir
}

/// Runs `evorec ARGS` with backtraces requested (so a printed backtrace would show) and no
/// `RUST_LOG` of the caller's.
pub fn evorec(args: &[&str]) -> Output {
    evorec_env(args, &[])
}

/// [`evorec`] with environment variables set.
#[allow(dead_code)] // not every test binary uses it
pub fn evorec_env(args: &[&str], vars: &[(&str, &str)]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_evorec"))
        .args(args)
        .envs(vars.iter().copied())
        .env("RUST_BACKTRACE", "1")
        .env("RUST_LIB_BACKTRACE", "1")
        .env_remove("RUST_LOG")
        .output()
        .unwrap_or_else(|e| panic!("running evorec: {e}"))
}
