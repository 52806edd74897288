//! Small text helpers shared by the readers' error messages.

/// Collapses a (possibly multi-line) parser message into one line: every run of whitespace,
/// line breaks included, becomes one space.
pub fn one_line(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}
