//! The user documentation stays what it is meant to be: a README of at most 300 lines, no work
//! session numbering ("session 12", any case) in the README, `CHANGELOG.md` or `docs/*.md`, and
//! every `docs/…` path the README names exists (links and figures included). The README's test
//! command is the one `.ci/run` runs.

use std::path::{Path, PathBuf};

/// Largest README, in lines.
const README_MAX_LINES: usize = 300;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The user documents: README, CHANGELOG and every Markdown file directly in `docs/`.
fn documents() -> Vec<PathBuf> {
    let root = root();
    let mut files = vec![root.join("README.md"), root.join("CHANGELOG.md")];
    let docs = std::fs::read_dir(root.join("docs")).expect("docs/ exists");
    let mut md: Vec<PathBuf> =
        docs.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.extension().is_some_and(|x| x == "md")).collect();
    md.sort();
    files.extend(md);
    files
}

/// Byte offsets of "session" followed by white space and a digit (case-insensitive), i.e. the
/// regex `(?i)session\s+\d`.
fn session_numbers(text: &str) -> Vec<usize> {
    let lower = text.to_ascii_lowercase();
    let bytes = lower.as_bytes();
    let mut hits = Vec::new();
    let mut from = 0;
    while let Some(i) = lower.get(from..).and_then(|rest| rest.find("session")).map(|i| i + from) {
        let mut j = i + "session".len();
        let spaces = j;
        while bytes.get(j).is_some_and(u8::is_ascii_whitespace) {
            j += 1;
        }
        if j > spaces && bytes.get(j).is_some_and(u8::is_ascii_digit) {
            hits.push(i);
        }
        from = i + 1;
    }
    hits
}

/// Every `docs/…` path named in `text` (up to the first character that cannot be in a path),
/// with a `#fragment` removed.
fn docs_paths(text: &str) -> Vec<String> {
    let mut paths = Vec::new();
    let mut from = 0;
    while let Some(i) = text.get(from..).and_then(|rest| rest.find("docs/")).map(|i| i + from) {
        let preceded_by_word = text
            .get(..i)
            .and_then(|s| s.chars().next_back())
            .is_some_and(|c| c.is_alphanumeric() || "/._-".contains(c));
        let end = text
            .get(i..)
            .and_then(|s| s.find(|c: char| !(c.is_alphanumeric() || "/._-".contains(c))))
            .map_or(text.len(), |n| i + n);
        let path = text.get(i..end).unwrap_or_default().trim_end_matches('.');
        if !preceded_by_word && path.len() > "docs/".len() {
            paths.push(path.to_string());
        }
        from = end.max(i + 1);
    }
    paths
}

#[test]
fn readme_is_at_most_300_lines() {
    let n = read(&root().join("README.md")).lines().count();
    assert!(n <= README_MAX_LINES, "README.md has {n} lines, at most {README_MAX_LINES}");
}

#[test]
fn no_session_numbers_in_the_documentation() {
    let mut found = Vec::new();
    for path in documents() {
        let text = read(&path);
        for i in session_numbers(&text) {
            let line = text.get(..i).map_or(0, |s| s.lines().count().max(1));
            found.push(format!("{}:{line}", path.display()));
        }
    }
    assert!(found.is_empty(), "work session numbers in the documentation: {found:?}");
}

#[test]
fn every_docs_path_the_readme_names_exists() {
    let root = root();
    let readme = read(&root.join("README.md"));
    let paths = docs_paths(&readme);
    assert!(paths.len() >= 5, "the README links docs/ (found {paths:?})");
    let missing: Vec<&String> = paths.iter().filter(|p| !root.join(p.as_str()).exists()).collect();
    assert!(missing.is_empty(), "README.md names missing files: {missing:?}");
    assert!(root.join("CHANGELOG.md").exists(), "CHANGELOG.md exists");
}

#[test]
fn the_readme_test_command_is_what_ci_runs() {
    let root = root();
    let readme = read(&root.join("README.md"));
    let ci = read(&root.join(".ci/run"));
    assert!(readme.contains("```sh\nscripts/test.sh\n```"), "the README shows `scripts/test.sh` as the test command");
    assert!(ci.lines().any(|l| l.trim() == "scripts/test.sh"), ".ci/run calls scripts/test.sh");
}

#[test]
fn the_scanners_find_what_they_should() {
    assert_eq!(session_numbers("Session 12 and session\n3, not sessions 4 or session x"), vec![0, 15]);
    assert_eq!(
        docs_paths("see [x](docs/method.md#a), `docs/figures/a.png`. hil-stubs/docs/b.md"),
        vec!["docs/method.md".to_string(), "docs/figures/a.png".to_string()]
    );
}
