//! `evorec paper --grid target`: the block's own motion beyond the paper, under
//! motion A at ω = [`ROBOT_OMEGA`] rad/s, for the base scenario's duration (72 s by default):
//! a conveyor at [`SPEEDS`] (with the
//! paper's yaw oscillation `ω_o = 0.125` rad/s), and faster yaw oscillations `ω_o` ∈
//! [`OMEGAS_O`] without conveyor; each with "1-step GA + FF" and "1-step GA + FF + target". Per
//! run also the hand-over one `[tracker] delay_s` after capture ([`crate::sim::Handover`]).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;

use crate::experiment::{self, Summary};
use crate::motion::MotionKind;
use crate::paper::DURATION_S;
use crate::scenario::{Method, Scenario};

/// Conveyor speeds (m/s).
pub const SPEEDS: [f64; 5] = [0.0, 0.05, 0.1, 0.2, 0.3];

/// Yaw oscillation frequencies `ω_o` (rad/s); 0.125 is the paper's.
pub const OMEGAS_O: [f64; 3] = [0.125, 0.5, 1.0];

/// The paper's `ω_o` (rad/s), used with the conveyor.
pub const PAPER_OMEGA_O: f64 = 0.125;

/// Motion A's frequency (rad/s).
pub const ROBOT_OMEGA: f64 = 0.5;

/// Conveyor shuttle length (m).
pub const TRAVEL_M: f64 = 0.15;

/// One cell: a conveyor speed (0 = none) and a yaw frequency `ω_o`, and a method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cell {
    /// Conveyor speed (m/s), 0 = none.
    pub speed_m_s: f64,
    /// Yaw oscillation frequency `ω_o` (rad/s).
    pub omega_o: f64,
    /// FF or FF + target.
    pub method: Method,
}

impl Cell {
    /// Directory name of the cell's run.
    pub fn slug(&self) -> String {
        format!("target_{}_v{}_wo{}", self.method.as_str().replace('+', "_"), self.speed_m_s, self.omega_o)
    }

    /// The method's name in the tables.
    pub fn method_name(&self) -> &'static str {
        crate::paper::Cell { motion: MotionKind::A, method: self.method, omega: ROBOT_OMEGA }.method_name()
    }
}

/// The grid: [`SPEEDS`] at [`PAPER_OMEGA_O`], then the other [`OMEGAS_O`] without conveyor;
/// each with FF and FF + target.
pub fn grid() -> Vec<Cell> {
    let mut conditions: Vec<(f64, f64)> = SPEEDS.iter().map(|&v| (v, PAPER_OMEGA_O)).collect();
    conditions.extend(OMEGAS_O.iter().filter(|&&w| w != PAPER_OMEGA_O).map(|&w| (0.0, w)));
    let mut cells = Vec::new();
    for (speed_m_s, omega_o) in conditions {
        for method in [Method::Ff, Method::FfTarget] {
            cells.push(Cell { speed_m_s, omega_o, method });
        }
    }
    cells
}

/// The scenario of a cell (the base scenario's duration, seed, camera): motion A at [`ROBOT_OMEGA`], the conveyor over [`TRAVEL_M`] with
/// reversals at max(0.5, 2v²/travel) m/s².
pub fn scenario_of(base: &Scenario, cell: &Cell) -> Scenario {
    let mut s = *base;
    s.method = cell.method;
    s.robot.motion = MotionKind::A;
    s.robot.omega_rad_s = ROBOT_OMEGA;
    s.target.omega_rad_s = cell.omega_o;
    s.target.conveyor_speed_m_s = cell.speed_m_s;
    s.target.conveyor_travel_m = TRAVEL_M;
    let v = cell.speed_m_s;
    s.target.conveyor_accel_m_s2 = (2.0 * v * v / TRAVEL_M).max(0.5);
    s.target.random_amplitude_m = 0.0;
    s
}

/// Results of the grid, in the order of the cells run.
pub type Results = Vec<(Cell, Summary)>;

/// Runs `cells` (e.g. [`grid`]) and writes `out/runs/target_*`, `target_table.csv` and
/// `target_table.md`.
///
/// # Errors
/// Any run's or any file's error.
pub fn run_grid(cells: &[Cell], base: &Scenario, out: &Path, show_progress: bool) -> Result<Results> {
    let frames = |c: &Cell| u64::from(crate::sim::frame_total(&scenario_of(base, c)));
    let results = crate::grid::run_cells(cells, frames, show_progress, |cell, tick| {
        let output = experiment::run(&scenario_of(base, cell), tick)?;
        let title = format!(
            "motion A ω = {ROBOT_OMEGA} / {} / conveyor {} m/s, ω_o = {} rad/s",
            cell.method_name(),
            cell.speed_m_s,
            cell.omega_o
        );
        experiment::write_outputs(&output, &out.join("runs").join(cell.slug()), &title)?;
        Ok((*cell, output.summary))
    })?;
    write_tables(&results, out)?;
    Ok(results)
}

/// Column names of `target_table.csv`.
pub const COLUMNS: [&str; 17] = [
    "conveyor_m_s",
    "omega_o_rad_s",
    "method",
    "F_mean",
    "rms_x_mm",
    "rms_y_mm",
    "rms_z_mm",
    "rms_e1",
    "rms_e2",
    "rms_e3",
    "tracking_fraction",
    "delay_s",
    "capture_pos_mm",
    "out_held_pos_mm",
    "out_pred_pos_mm",
    "pred_over_capture_pos",
    "pred_over_capture_eps",
];

fn values(s: &Summary) -> [f64; 14] {
    let a = &s.accuracy;
    let tracking = s.status.tracking as f64 / a.frames.max(1) as f64;
    let (delay, cap, held, pred, rp, re) = match &s.handover {
        Some(h) => (
            h.delay_s,
            h.at_capture.rms_position_mm,
            h.held.rms_position_mm,
            h.predicted.rms_position_mm,
            h.position_ratio,
            h.eps_ratio,
        ),
        None => (f64::NAN, f64::NAN, f64::NAN, f64::NAN, f64::NAN, f64::NAN),
    };
    [
        a.f_mean, a.rms_x_mm, a.rms_y_mm, a.rms_z_mm, a.rms_e1, a.rms_e2, a.rms_e3, tracking, delay, cap, held, pred,
        rp, re,
    ]
}

/// Writes `target_table.csv` and `target_table.md`.
///
/// # Errors
/// I/O errors.
pub fn write_tables(results: &[(Cell, Summary)], out: &Path) -> Result<()> {
    let records: Vec<Vec<String>> = results
        .iter()
        .map(|(cell, summary)| {
            let mut rec =
                vec![format!("{}", cell.speed_m_s), format!("{}", cell.omega_o), cell.method_name().to_owned()];
            rec.extend(values(summary).iter().map(|v| format!("{v:.6}")));
            rec
        })
        .collect();
    crate::io::write_table(out, "target_table", &COLUMNS, &records, &markdown(results))
}

/// The grid as a Markdown table.
pub fn markdown(results: &[(Cell, Summary)]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Motion A at ω = {ROBOT_OMEGA} rad/s, {} s per run. Conveyor along world y over {TRAVEL_M} m; \
         ω_o: the block's yaw oscillation (±15°). Hand-over (frames reported as tracking): RMS position error at \
         capture, of the estimate held until the output time, and of the core's prediction for it; ratio = \
         predicted / at capture.\n",
        results.first().map_or(DURATION_S, |(_, s)| s.scenario.duration_s)
    );
    let _ = writeln!(
        s,
        "| conveyor m/s | ω_o rad/s | method | F̄ | RMS x mm | RMS y mm | RMS z mm | RMS ε₁ | RMS ε₂ | RMS ε₃ | \
         tracking | capture mm | held mm | predicted mm | ratio pos | ratio ε |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for (cell, summary) in results {
        let v = values(summary);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.4} | {:.2} | {:.2} | {:.2} | {:.4} | {:.4} | {:.4} | {:.0} % | {:.2} | {:.2} | {:.2} | \
             {:.2} | {:.2} |",
            cell.speed_m_s,
            cell.omega_o,
            cell.method_name(),
            v[0],
            v[1],
            v[2],
            v[3],
            v[4],
            v[5],
            v[6],
            v[7] * 100.0,
            v[9],
            v[10],
            v[11],
            v[12],
            v[13]
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_covers_the_issue_s_speeds_and_yaw_rates_with_both_methods() {
        let cells = grid();
        assert_eq!(cells.len(), 2 * (SPEEDS.len() + OMEGAS_O.len() - 1));
        for v in SPEEDS {
            for m in [Method::Ff, Method::FfTarget] {
                assert!(cells.contains(&Cell { speed_m_s: v, omega_o: PAPER_OMEGA_O, method: m }));
            }
        }
        for w in [0.5, 1.0] {
            assert!(cells.iter().any(|c| c.speed_m_s == 0.0 && c.omega_o == w));
        }
        let base = Scenario::new(1, 1.0, Method::Ga);
        for c in &cells {
            let s = scenario_of(&base, c);
            let text = s.to_toml_string().unwrap_or_else(|e| unreachable!("{e}"));
            // Every cell is a valid scenario (the conveyor can reverse within its travel).
            let back = Scenario::from_toml_str(&text).unwrap_or_else(|e| unreachable!("{c:?}: {e}"));
            assert_eq!(back, s);
            assert_eq!((s.robot.motion, s.robot.omega_rad_s, s.method), (MotionKind::A, ROBOT_OMEGA, c.method));
        }
    }
}
