//! `evorec run --seed N` and `evorec hil --seed N`: the scenario's seed replaced, exactly as
//! if the file said `seed = N` (for seed sweeps such as `scripts/target_seeds.sh`); and the
//! estimates and rotation error both write, as `evorec track` does.

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
        "seed = {seed}\nduration_s = 0.3\n[tracker]\nmethod = \"ff+target\"\n[target]\nconveyor_speed_m_s = 0.1\n\
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

/// The poses of an `estimate.tum`: one line per frame of `trace.csv`, in its order.
fn check_estimate_tum(dir: &std::path::Path) {
    let read = |f: &str| std::fs::read_to_string(dir.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
    let tum = read("estimate.tum");
    let poses: Vec<Vec<f64>> = tum
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split_whitespace().map(|w| w.parse().unwrap_or_else(|e| panic!("{l}: {e}"))).collect())
        .collect();
    let trace = read("trace.csv");
    assert_eq!(poses.len(), trace.lines().count() - 1, "{tum}");
    for (pose, row) in poses.iter().zip(trace.lines().skip(1)) {
        assert_eq!(pose.len(), 8);
        let q = pose[4..].iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!((q - 1.0).abs() < 1e-6, "{pose:?}");
        let t: f64 = row.split(',').next().and_then(|t| t.parse().ok()).unwrap_or(f64::NAN);
        assert!((pose[0] - t).abs() < 1e-3, "{pose:?} against {row}");
        let est_x_mm: f64 = row.split(',').nth(21).and_then(|x| x.parse().ok()).unwrap_or(f64::NAN);
        assert!((pose[1] * 1e3 - est_x_mm).abs() < 1e-3, "{pose:?} against {row}");
    }
    let summary: serde_json::Value = serde_json::from_str(&read("summary.json")).unwrap_or_else(|e| panic!("{e}"));
    let rms = summary["rms_rot_deg"].as_f64().unwrap_or_else(|| panic!("no rms_rot_deg: {summary}"));
    let max = summary["max_rot_deg"].as_f64().unwrap_or_else(|| panic!("no max_rot_deg: {summary}"));
    assert!(rms > 0.0 && rms <= max && max < 10.0, "{rms} {max}");
}

#[test]
fn run_writes_the_estimates_and_the_rotation_error() {
    let dir = scratch("estimate");
    let file = dir.join("s.toml");
    std::fs::write(&file, scenario(1)).unwrap_or_else(|e| panic!("{e}"));
    let out = dir.join("out");
    let o = evorec(&["run", path_str(&file), "--out", path_str(&out)]);
    assert!(o.status.success(), "{o:?}");
    check_estimate_tum(&out);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `evorec hil --seed`: QEMU and the firmware (built first, as the workspace's HIL tests do;
/// `EVOREC_SKIP_HIL=1` skips this test).
#[test]
fn hil_seed_flag_overrides_the_scenario_s_seed() {
    if std::env::var_os("EVOREC_SKIP_HIL").is_some_and(|v| v == "1") {
        println!("hil_seed_flag_overrides_the_scenario_s_seed skipped: EVOREC_SKIP_HIL=1");
        return;
    }
    let firmware =
        evorec_firmware::host::build_firmware(evorec_firmware::BoardProfile::M4).unwrap_or_else(|e| panic!("{e}"));
    let dir = scratch("hil");
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios/hil_motion_a_ff.toml"))
        .unwrap_or_else(|e| panic!("{e}"));
    let short = text.replacen("duration_s = 72.0", "duration_s = 1.0", 1);
    assert_ne!(short, text, "the scenario's duration line moved");
    let (one, three) = (dir.join("one.toml"), dir.join("three.toml"));
    std::fs::write(&one, &short).unwrap_or_else(|e| panic!("{e}"));
    std::fs::write(&three, short.replacen("seed = 1\n", "seed = 3\n", 1)).unwrap_or_else(|e| panic!("{e}"));
    let hil = |file: &PathBuf, out: &str, extra: &[&str]| {
        let out = dir.join(out);
        let mut args = vec!["hil", path_str(file), "--out", path_str(&out), "--firmware", path_str(&firmware)];
        args.extend_from_slice(extra);
        let o = evorec(&args);
        assert!(o.status.success(), "{o:?}");
        let read = |f: &str| std::fs::read(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        (read("summary.json"), read("trace.csv"), out)
    };
    let flagged = hil(&one, "flagged", &["--seed", "3"]);
    let file = hil(&three, "file", &[]);
    assert_eq!((&flagged.0, &flagged.1), (&file.0, &file.1), "--seed 3 runs as seed = 3 in the file");
    assert_ne!(flagged.1, hil(&one, "plain", &[]).1, "another seed, another run");
    check_estimate_tum(&flagged.2);
    let _ = std::fs::remove_dir_all(&dir);
}
