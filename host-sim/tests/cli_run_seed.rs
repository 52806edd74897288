//! `evorec run --seed N`: the scenario's seed replaced, exactly as if the file said `seed = N`
//! (for seed sweeps such as `scripts/target_seeds.sh`).

use std::path::PathBuf;

mod common;
use common::evorec;

fn scratch(name: &str) -> PathBuf {
    common::scratch("cli-run-seed", name)
}

fn path_str(p: &std::path::Path) -> &str {
    p.to_str().unwrap_or_else(|| panic!("non-UTF-8 path {}", p.display()))
}

/// A short run of the approaching belt (camera-frame direction, moving start).
fn scenario(seed: u64) -> String {
    format!(
        "seed = {seed}\nduration_s = 0.3\nmethod = \"ff+target\"\n[target]\nconveyor_speed_m_s = 0.1\n\
         conveyor_direction = [0, 0, -1]\nconveyor_direction_frame = \"camera\"\nconveyor_start = \"moving\"\n\
         [robot]\nmotion = \"A\"\nomega_rad_s = 0.5\n"
    )
}

#[test]
fn seed_flag_overrides_the_scenario_s_seed() {
    let dir = scratch("override");
    let (one, three) = (dir.join("one.toml"), dir.join("three.toml"));
    std::fs::write(&one, scenario(1)).unwrap_or_else(|e| panic!("{e}"));
    std::fs::write(&three, scenario(3)).unwrap_or_else(|e| panic!("{e}"));
    let run = |file: &PathBuf, out: &str, extra: &[&str]| {
        let out = dir.join(out);
        let mut args = vec!["run", path_str(file), "--out", path_str(&out)];
        args.extend_from_slice(extra);
        let o = evorec(&args);
        assert!(o.status.success(), "{o:?}");
        let read = |f: &str| std::fs::read(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        (read("summary.json"), read("trace.csv"))
    };
    let flagged = run(&one, "flagged", &["--seed", "3"]);
    assert_eq!(flagged, run(&three, "file", &[]), "--seed 3 runs as seed = 3 in the file");
    assert_ne!(flagged.1, run(&one, "plain", &[]).1, "another seed, another run");
    let summary = String::from_utf8_lossy(&flagged.0).into_owned();
    assert!(summary.contains("\"seed\": 3") && summary.contains("\"conveyor_start\": \"moving\""), "{summary}");

    let o = evorec(&["run", path_str(&one), "--out", path_str(&dir.join("bad")), "--seed", "-1"]);
    assert!(!o.status.success());
    let o = evorec(&["run", path_str(&one), "--out", path_str(&dir.join("bad")), "--seed", "9223372036854775808"]);
    assert!(!o.status.success(), "above 2^63 - 1, which a scenario file cannot hold either");
    let _ = std::fs::remove_dir_all(&dir);
}
