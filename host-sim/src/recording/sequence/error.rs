//! The one error type of the sequence reader: what was wrong, in which file, at which line and
//! field.

use std::fmt;
use std::path::{Path, PathBuf};

/// A bad sequence input: one message naming the file and, where it applies, the line and the
/// field. Displayed on one line as `FILE:LINE: FIELD: MESSAGE`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SequenceError {
    /// The file at fault.
    pub file: PathBuf,
    /// 1-based line in that file, when the error is about one line.
    pub line: Option<u64>,
    /// The field (TOML/YAML key, CSV column) at fault, when the error is about one field.
    pub field: Option<String>,
    /// What is wrong.
    pub message: String,
}

impl SequenceError {
    /// An error about a whole file.
    pub fn file(file: impl AsRef<Path>, message: impl Into<String>) -> Self {
        Self { file: file.as_ref().to_path_buf(), line: None, field: None, message: one_line(&message.into()) }
    }

    /// Adds the line.
    #[must_use]
    pub fn at_line(mut self, line: u64) -> Self {
        self.line = Some(line);
        self
    }

    /// Adds the field.
    #[must_use]
    pub fn in_field(mut self, field: impl Into<String>) -> Self {
        self.field = Some(field.into());
        self
    }
}

impl fmt::Display for SequenceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        if let Some(field) = &self.field {
            write!(f, ": {field}")?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for SequenceError {}

pub use crate::recording::text::one_line;

/// Shorthand for results of the reader.
pub type Result<T> = std::result::Result<T, SequenceError>;
