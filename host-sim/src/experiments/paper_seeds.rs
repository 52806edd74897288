//! Seed sweeps over the paper grid (`evorec paper --seeds A..B`): each cell of one method run
//! once per GA seed, for comparisons that a single seed cannot carry (the spread between seeds
//! is about 10 %). Writes `cells_A_B.csv`, one row per cell and seed, the table that
//! `scripts/compare_seeds.py` compares.

use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};

use anyhow::Result;

use crate::experiments::experiment::{self, Accuracy};
use crate::experiments::paper::{Cell, OMEGAS, scenario_of};
use crate::experiments::truth::WrongTracking;
use crate::sim::motion::MotionKind;
use crate::sim::scenario::Scenario;
use evorec_core::tuning::Feedforward;

/// Columns of `cells_A_B.csv`.
pub const COLUMNS: [&str; 12] = [
    "motion",
    "omega",
    "seed",
    "F",
    "x_mm",
    "y_mm",
    "z_mm",
    "e1",
    "e2",
    "e3",
    "tracking_wrong_fraction",
    "longest_wrong_tracking_frames",
];

/// The cells of a sweep of `method`: motion A at every ω of the paper, motion B at ω > 0
/// (motion B at rest is motion A at rest).
pub fn cells(method: Feedforward) -> Vec<Cell> {
    let a = OMEGAS.iter().map(|&omega| Cell { motion: MotionKind::A, method, omega });
    let b = OMEGAS.iter().filter(|w| **w > 0.0).map(|&omega| Cell { motion: MotionKind::B, method, omega });
    a.chain(b).collect()
}

/// Parses a cell `MOTION:OMEGA` (e.g. `A:0.25`, `b:1`), which must be one of [`cells`]'s.
///
/// # Errors
/// The message for a malformed or unknown cell.
pub fn parse_cell(text: &str) -> Result<(MotionKind, f64), String> {
    let (m, w) = text.split_once(':').ok_or_else(|| format!("`{text}` is not MOTION:OMEGA (e.g. A:0.25)"))?;
    let omega: f64 = w.trim().parse().map_err(|_| format!("`{text}` is not MOTION:OMEGA (e.g. A:0.25)"))?;
    let motion = match m.trim() {
        "A" | "a" => MotionKind::A,
        "B" | "b" => MotionKind::B,
        _ => return Err(format!("`{text}`: the motion is A or B")),
    };
    let known = cells(Feedforward::On).iter().any(|c| c.motion == motion && c.omega == omega);
    if !known {
        return Err(format!("`{text}` is not a cell of the sweep (A at ω = 0, 0.125, 0.25, 0.5, 1; B at ω > 0)"));
    }
    Ok((motion, omega))
}

/// Parses a seed range `A..B` (both included, A ≤ B) or a single seed `N`.
///
/// # Errors
/// The message for a malformed or empty range.
pub fn parse_seeds(text: &str) -> Result<RangeInclusive<u64>, String> {
    let seed =
        |s: &str| {
            s.trim().parse::<u64>().ok().filter(|n| *n <= i64::MAX as u64).ok_or_else(|| {
                format!("`{text}`: expected FIRST..LAST (both included) or one seed, each in 0 ..= 2^63−1")
            })
        };
    let (first, last) = match text.split_once("..") {
        Some((a, b)) => (seed(a)?, seed(b.strip_prefix('=').unwrap_or(b))?),
        None => (seed(text)?, seed(text)?),
    };
    if first > last {
        return Err(format!("`{text}`: the first seed is larger than the last"));
    }
    Ok(first..=last)
}

/// One run of a sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeedRun {
    /// The cell.
    pub cell: Cell,
    /// The GA's (and the renderer's) seed.
    pub seed: u64,
    /// Its accuracy.
    pub accuracy: Accuracy,
    /// How often its `tracking` was wrong.
    pub wrong_tracking: WrongTracking,
}

/// Runs every cell once per seed (in parallel, seed by seed in the order of `cells`), each
/// with `base`'s camera and target and the seed replaced, writes each run's outputs under
/// `out/runs/` and the table `out/cells_FIRST_LAST.csv`; returns the runs and the table's path.
///
/// # Errors
/// Any run's or file's error.
pub fn run(
    cells: &[Cell],
    seeds: RangeInclusive<u64>,
    base: &Scenario,
    out: &Path,
    show_progress: bool,
) -> Result<(Vec<SeedRun>, PathBuf)> {
    let jobs: Vec<(u64, Cell)> = seeds.clone().flat_map(|seed| cells.iter().map(move |c| (seed, *c))).collect();
    let scenario = |seed: u64, cell: &Cell| scenario_of(&Scenario { seed, ..*base }, cell);
    let frames = |(seed, cell): &(u64, Cell)| u64::from(crate::sim::board::frame_total(&scenario(*seed, cell)));
    let runs = crate::experiments::grid::run_cells(&jobs, frames, show_progress, |(seed, cell), tick| {
        let output = experiment::run(&scenario(*seed, cell), tick)?;
        let title =
            format!("motion {} / {} / ω = {} rad/s / seed {seed}", cell.motion_name(), cell.method_name(), cell.omega);
        experiment::write_outputs(&output, &out.join("runs").join(format!("{}_s{seed}", cell.slug())), &title)?;
        let summary = &output.summary;
        Ok(SeedRun { cell: *cell, seed: *seed, accuracy: summary.accuracy, wrong_tracking: summary.wrong_tracking })
    })?;
    let path = out.join(format!("cells_{}_{}.csv", seeds.start(), seeds.end()));
    crate::output::io::write_csv(&path, &COLUMNS, &runs.iter().map(record).collect::<Vec<_>>())?;
    Ok((runs, path))
}

/// One row of the table: motion, ω, seed, then F̄ and the RMS errors in `%g` style with six
/// significant digits, the fraction of the tracking frames that were wrong (`%g`) and the
/// longest run of them.
pub fn record(r: &SeedRun) -> Vec<String> {
    let a = &r.accuracy;
    let mut rec = vec![r.cell.motion_name().to_owned(), format!("{}", r.cell.omega), r.seed.to_string()];
    rec.extend(
        [a.f_mean, a.rms.rms_x_mm, a.rms.rms_y_mm, a.rms.rms_z_mm, a.rms.rms_e1, a.rms.rms_e2, a.rms.rms_e3].map(g6),
    );
    rec.push(g6(r.wrong_tracking.tracking_wrong_fraction));
    rec.push(r.wrong_tracking.longest_wrong_tracking_frames.to_string());
    rec
}

/// `v` with six significant digits, as C's and Python's `%g`: fixed notation for decimal
/// exponents −4 ..= 5, scientific otherwise, trailing zeros removed.
pub fn g6(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let sci = format!("{v:.5e}");
    let (mantissa, exp) = sci.split_once('e').unwrap_or((&sci, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let trim = |s: &str| {
        if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_owned() } else { s.to_owned() }
    };
    if (-4..6).contains(&exp) {
        trim(&format!("{v:.*}", (5 - exp) as usize))
    } else {
        format!("{}e{}{:02}", trim(mantissa), if exp < 0 { '-' } else { '+' }, exp.abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::truth::Rms;

    #[test]
    fn g6_matches_percent_g() {
        // Python: ['%.6g' % v for v in ...]
        let cases = [
            (0.997_411_234_5, "0.997411"),
            (1.794_561_2, "1.79456"),
            (43.204_999, "43.205"),
            (0.001_234_567_8, "0.00123457"),
            (0.000_012_345_678, "1.23457e-05"),
            (123_456.7, "123457"),
            (1_234_567.0, "1.23457e+06"),
            (2.0, "2"),
            (0.1, "0.1"),
            (9.999_999, "10"),
            (-0.5, "-0.5"),
            (0.0, "0"),
        ];
        for (v, want) in cases {
            assert_eq!(g6(v), want, "{v}");
        }
    }

    #[test]
    fn the_sweep_has_nine_cells_and_parses_the_script_s_cells() {
        let names: Vec<String> =
            cells(Feedforward::On).iter().map(|c| format!("{}:{}", c.motion_name(), c.omega)).collect();
        assert_eq!(names, ["A:0", "A:0.125", "A:0.25", "A:0.5", "A:1", "B:0.125", "B:0.25", "B:0.5", "B:1"]);
        assert_eq!(parse_cell("A:0.25"), Ok((MotionKind::A, 0.25)));
        assert_eq!(parse_cell("b:1"), Ok((MotionKind::B, 1.0)));
        assert!(parse_cell("B:0").is_err() && parse_cell("A:0.3").is_err() && parse_cell("A0").is_err());
        assert_eq!(parse_seeds("1..20"), Ok(1..=20));
        assert_eq!(parse_seeds("7"), Ok(7..=7));
        assert_eq!(parse_seeds("3..=4"), Ok(3..=4));
        assert!(
            parse_seeds("5..4").is_err() && parse_seeds("x").is_err() && parse_seeds("1..9223372036854775808").is_err()
        );
    }

    #[test]
    fn a_row_is_the_script_s() {
        let cell = Cell { motion: MotionKind::B, method: Feedforward::On, omega: 0.125 };
        let rms = Rms {
            rms_x_mm: 0.362_514_9,
            rms_y_mm: 0.41,
            rms_z_mm: 1.98,
            rms_e1: 0.001_187_65,
            rms_e2: 0.003_2,
            rms_e3: 0.000_012_3,
            mean_x_mm: 0.0,
            mean_y_mm: 0.0,
            mean_z_mm: 0.0,
            rotation: None,
            frames: 2182,
        };
        let accuracy = Accuracy { f_mean: 0.998_4, rms };
        let wrong_tracking = WrongTracking {
            tracking_frames: 2000,
            tracking_wrong_frames: 25,
            tracking_wrong_fraction: 0.0125,
            longest_wrong_tracking_frames: 7,
            uncertain_frames: 150,
            uncertain_wrong_frames: 30,
        };
        let rec = record(&SeedRun { cell, seed: 4, accuracy, wrong_tracking });
        assert_eq!(rec.join(","), "B,0.125,4,0.9984,0.362515,0.41,1.98,0.00118765,0.0032,1.23e-05,0.0125,7");
        let run = |motion, omega| SeedRun { cell: Cell { motion, omega, ..cell }, seed: 1, accuracy, wrong_tracking };
        let (a0, a1) = (record(&run(MotionKind::A, 0.0)), record(&run(MotionKind::A, 1.0)));
        assert_eq!((a0[1].as_str(), a1[1].as_str()), ("0", "1"));
    }
}
