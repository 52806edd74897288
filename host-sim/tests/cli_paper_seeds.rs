//! `evorec paper --seeds FIRST..LAST`: the sweep's table `cells_FIRST_LAST.csv`, one row per
//! seed and cell with the columns `scripts/compare_seeds.py` reads, each row the run's summary.

use std::path::Path;

mod common;
use common::evorec;

fn path_str(p: &Path) -> &str {
    p.to_str().unwrap_or_else(|| panic!("non-UTF-8 path {}", p.display()))
}

#[test]
fn seeds_write_one_row_per_seed_and_cell() {
    let dir = common::scratch("cli-paper-seeds", "table");
    let o = evorec(&["-q", "paper", "--seeds", "3..4", "--cells", "B:1,A:0", "--out", path_str(&dir)]);
    assert!(o.status.success(), "{o:?}");
    let table = std::fs::read_to_string(dir.join("cells_3_4.csv")).unwrap_or_else(|e| panic!("{e}"));
    let lines: Vec<&str> = table.lines().collect();
    assert_eq!(
        lines[0],
        "motion,omega,seed,F,x_mm,y_mm,z_mm,e1,e2,e3,tracking_wrong_fraction,longest_wrong_tracking_frames"
    );
    let keys: Vec<String> = lines[1..].iter().map(|l| l.split(',').take(3).collect::<Vec<_>>().join(",")).collect();
    assert_eq!(keys, ["B,1,3", "A,0,3", "B,1,4", "A,0,4"], "seed by seed, the cells in --cells' order");
    let summary = std::fs::read_to_string(dir.join("runs/B_ff_w1_s4/summary.json")).unwrap_or_else(|e| panic!("{e}"));
    let summary: serde_json::Value = serde_json::from_str(&summary).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(summary["scenario"]["seed"], 4);
    assert_eq!(summary["scenario"]["tracker"]["method"], "ff");
    let row: Vec<f64> = lines[3].split(',').skip(3).map(|v| v.parse().unwrap_or(f64::NAN)).collect();
    let keys = [
        "F_mean",
        "rms_x_mm",
        "rms_y_mm",
        "rms_z_mm",
        "rms_e1",
        "rms_e2",
        "rms_e3",
        "tracking_wrong_fraction",
        "longest_wrong_tracking_frames",
    ];
    assert_eq!(row.len(), keys.len());
    for (value, key) in row.iter().zip(keys) {
        let want = summary[key].as_f64().unwrap_or(f64::NAN);
        assert!((value - want).abs() <= 1e-5 * want.abs() + 1e-9, "{key}: {value} against {want}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_seed_ranges_and_cells_are_refused() {
    let dir = common::scratch("cli-paper-seeds", "refused");
    let out = path_str(&dir);
    for args in [
        &["paper", "--seeds", "4..3", "--out", out][..],
        &["paper", "--seeds", "1..2", "--cells", "B:0", "--out", out],
        &["paper", "--seeds", "1..2", "--cells", "A:0.3", "--out", out],
        &["paper", "--cells", "A:0", "--out", out],
        &["paper", "--seeds", "1..2", "--grid", "target", "--out", out],
    ] {
        let o = evorec(args);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert_eq!(std::fs::read_dir(&dir).map(|d| d.count()).unwrap_or(0), 0, "{args:?} wrote into {out}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
