//! Support for the workspace-level tests in `tests/tests/`.

use std::fmt;

/// A test failure that prints its message as is (with a build or install hint), so a missing
/// firmware image or QEMU reads as an instruction rather than a debug dump.
pub struct Failure(pub String);

impl fmt::Debug for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl<E: fmt::Display> From<E> for Failure {
    fn from(e: E) -> Self {
        Self(e.to_string())
    }
}

/// A [`Failure`] with a message.
pub fn fail(msg: impl Into<String>) -> Failure {
    Failure(msg.into())
}

/// Whether the HIL tests are to be skipped (`EVOREC_SKIP_HIL=1`, as the tests' docs say);
/// when they are, says so on stdout, naming `test`.
pub fn hil_skipped(test: &str) -> bool {
    let skip = std::env::var_os("EVOREC_SKIP_HIL").is_some_and(|v| v == "1");
    if skip {
        println!("{test} skipped: EVOREC_SKIP_HIL=1");
    }
    skip
}
