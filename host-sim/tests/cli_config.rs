//! `evorec config` and `--config FILE`: the printed defaults given back with `--config` run
//! exactly as without them, a changed value changes the run, an unknown key is named with its
//! file, and every run's `config.toml` reproduces it.

use std::path::{Path, PathBuf};

mod common;
use common::evorec;

fn path_str(p: &Path) -> &str {
    p.to_str().unwrap_or_else(|| panic!("non-UTF-8 path {}", p.display()))
}

/// A short motion A run at 160x120 with every tuning default (`ff+target`).
fn scenario() -> String {
    let mut s = evorec_sim::sim::scenario::fixture::sway_160x120(0.5);
    s.seed = 2;
    s.tracker.0 = evorec_core::tuning::Tuning::DEFAULT;
    s.to_toml_string().unwrap_or_else(|e| panic!("{e}"))
}

fn run(dir: &Path, out: &str, extra: &[&str]) -> Vec<u8> {
    let scenario = dir.join("scenario.toml");
    let out = dir.join(out);
    let mut args = vec!["run", path_str(&scenario), "--out", path_str(&out)];
    args.extend_from_slice(extra);
    let o = evorec(&args);
    assert!(o.status.success(), "{o:?}");
    std::fs::read(out.join("trace.csv")).unwrap_or_else(|e| panic!("trace.csv: {e}"))
}

#[test]
fn the_printed_defaults_reproduce_the_run_and_a_changed_value_changes_it() {
    let dir: PathBuf = common::scratch("cli-config", "run");
    std::fs::write(dir.join("scenario.toml"), scenario()).unwrap_or_else(|e| panic!("{e}"));
    let o = evorec(&["config"]);
    assert!(o.status.success(), "{o:?}");
    let defaults = String::from_utf8(o.stdout).unwrap_or_else(|e| panic!("{e}"));
    assert!(defaults.starts_with("[tracker]\n# "), "{defaults}");
    assert!(defaults.contains("\nga.mutation_prob = 0.9\n"), "{defaults}");
    let config = dir.join("c.toml");
    std::fs::write(&config, &defaults).unwrap_or_else(|e| panic!("{e}"));

    let plain = run(&dir, "plain", &[]);
    assert_eq!(run(&dir, "with", &["--config", path_str(&config)]), plain);
    let written = std::fs::read_to_string(dir.join("plain/config.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(written, defaults, "the run's config.toml is its full tuning");

    let changed = dir.join("changed.toml");
    let text = defaults.replace("ga.mutation_prob = 0.9", "ga.mutation_prob = 0.5");
    std::fs::write(&changed, text).unwrap_or_else(|e| panic!("{e}"));
    let other = run(&dir, "changed", &["--config", path_str(&changed)]);
    assert_ne!(other, plain, "ga.mutation_prob changed nothing");
    let again = dir.join("changed/config.toml");
    assert_eq!(run(&dir, "again", &["--config", path_str(&again)]), other, "config.toml reproduces the run");

    let o = evorec(&["config", path_str(&dir.join("scenario.toml")), "--config", path_str(&changed)]);
    assert!(o.status.success(), "{o:?}");
    assert!(String::from_utf8_lossy(&o.stdout).contains("\nga.mutation_prob = 0.5\n"));

    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "[tracker]\nga.mutaton_prob = 0.5\n").unwrap_or_else(|e| panic!("{e}"));
    let o = evorec(&[
        "run",
        path_str(&dir.join("scenario.toml")),
        "--out",
        path_str(&dir.join("bad")),
        "--config",
        path_str(&bad),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.toml") && err.contains("tracker.ga.mutaton_prob: unknown key"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
