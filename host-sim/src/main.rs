//! evorec CLI.
fn main() {}
