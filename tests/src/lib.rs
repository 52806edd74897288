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
