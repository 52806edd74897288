//! The command line's failures: one `error: …` line on stderr naming the file (and field),
//! no backtrace even with `RUST_BACKTRACE=1`, and a non-zero exit status.

use std::path::{Path, PathBuf};
use std::process::Output;

/// Checks the failure and returns its single stderr line.
mod common;
use common::evorec;

fn scratch(name: &str) -> PathBuf {
    common::scratch("cli-errors", name)
}

fn single_error_line(out: &Output) -> String {
    assert!(!out.status.success(), "evorec succeeded: {out:?}");
    assert_eq!(out.status.code(), Some(1), "exit status: {out:?}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "expected exactly one line on stderr, got:\n{stderr}");
    let line = lines[0];
    assert!(line.starts_with("error: "), "{line}");
    assert!(!stderr.contains("backtrace") && !stderr.contains("Caused by"), "{stderr}");
    line.to_owned()
}

/// How often `needle` occurs in `hay`.
fn count(hay: &str, needle: &str) -> usize {
    hay.matches(needle).count()
}

#[test]
fn missing_scenario_file() {
    let dir = scratch("missing");
    let scenario = dir.join("no-such-scenario.toml");
    let out = evorec(&["run", path_str(&scenario), "--out", path_str(&dir.join("out"))]);
    let line = single_error_line(&out);
    assert_eq!(count(&line, path_str(&scenario)), 1, "{line}");
    assert!(line.contains("No such file"), "{line}");
    assert!(!dir.join("out").exists(), "nothing is created before the scenario loads");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_field_in_scenario() {
    let dir = scratch("bad-field");
    let scenario = dir.join("bad.toml");
    let text = "seed = 1\nduration_s = 1.0\n[camera]\nwidth = 0\n";
    std::fs::write(&scenario, text).unwrap_or_else(|e| panic!("{e}"));
    let out = evorec(&["run", path_str(&scenario), "--out", path_str(&dir.join("out"))]);
    let line = single_error_line(&out);
    assert_eq!(count(&line, path_str(&scenario)), 1, "{line}");
    assert_eq!(count(&line, "camera.width"), 1, "the field is named once: {line}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unwritable_output_directory() {
    let dir = scratch("unwritable");
    // A regular file where a directory is needed: fails for every user, root included.
    let blocker = dir.join("a-file");
    std::fs::write(&blocker, "not a directory\n").unwrap_or_else(|e| panic!("{e}"));
    let out_dir = blocker.join("out");
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/smoke.toml");
    let out = evorec(&["run", path_str(&scenario), "--out", path_str(&out_dir)]);
    let line = single_error_line(&out);
    assert_eq!(count(&line, path_str(&out_dir)), 1, "{line}");
    assert!(line.contains("output directory"), "{line}");
    let _ = std::fs::remove_dir_all(&dir);
}

fn path_str(p: &Path) -> &str {
    p.to_str().unwrap_or_else(|| panic!("non-UTF-8 path {}", p.display()))
}
