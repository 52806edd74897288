//! The paper's experiment grid (§5, Fig. 17 and Fig. 24): motions A and B, robot frequency
//! ω ∈ {0, 0.125, 0.25, 0.5, 1.0} rad/s, with and without feedforward, and beyond the paper
//! with the feedforward of the target's own motion too ("1-step GA + FF + target"),
//! 72 s each, and the comparison with the published tables. The grid over the target's own
//! motions is [`crate::experiments::target_grid`].

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;

use crate::experiments::experiment::{self, Accuracy};
use crate::sim::motion::MotionKind;
use crate::sim::scenario::Scenario;
use evorec_core::tuning::Feedforward;

/// Robot frequencies of the grid (rad/s).
pub const OMEGAS: [f64; 5] = [0.0, 0.125, 0.25, 0.5, 1.0];

/// Duration of each run (s), as in the paper.
pub const DURATION_S: f64 = 72.0;

/// One published row of Fig. 17 / Fig. 24 (`None` = not published).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Published {
    /// "A" or "B".
    pub motion: &'static str,
    /// Feedforward on.
    pub ff: bool,
    /// ω (rad/s).
    pub omega: f64,
    /// F̄, RMS x, y, z (mm), RMS ε₁, ε₂, ε₃.
    pub values: [Option<f64>; 7],
}

/// The published numbers (`shared/paper/paper_tables.csv`, from Fig. 17 and Fig. 24; the
/// paper's OCR lost the ε₃ column of the plain GA rows).
pub const PUBLISHED: [Published; 14] = {
    const fn p(motion: &'static str, ff: bool, omega: f64, v: [f64; 6], e3: Option<f64>) -> Published {
        Published {
            motion,
            ff,
            omega,
            values: [Some(v[0]), Some(v[1]), Some(v[2]), Some(v[3]), Some(v[4]), Some(v[5]), e3],
        }
    }
    [
        p("A", false, 0.0, [0.9625, 1.238529, 3.963243, 5.544477, 0.011146, 0.015599], None),
        p("A", false, 0.125, [0.7047, 15.43175, 18.58162, 25.84152, 0.018499, 0.041138], None),
        p("A", false, 0.25, [0.5794, 16.53167, 26.21253, 36.72746, 0.021081, 0.054877], None),
        p("A", false, 0.5, [0.4378, 30.21539, 32.96989, 44.76831, 0.059064, 0.123591], None),
        p("A", true, 0.125, [0.9473, 2.128153, 6.43577, 6.873411, 0.000485, 0.00952], Some(0.014976)),
        p("A", true, 0.25, [0.9556, 1.316153, 2.329284, 3.128897, 0.001283, 0.013151], Some(0.018944)),
        p("A", true, 0.5, [0.9590, 1.923763, 3.173726, 4.313114, 0.00084, 0.013249], Some(0.013401)),
        p("B", false, 0.0, [0.9525, 1.238529, 3.963243, 5.544477, 0.011146, 0.015599], None),
        p("B", false, 0.125, [0.7445, 7.084036, 15.10137, 21.11374, 0.025746, 0.073936], None),
        p("B", false, 0.25, [0.8089, 12.50464, 19.43937, 26.54229, 0.030625, 0.106551], None),
        p("B", false, 0.5, [0.3987, 15.94141, 24.79264, 33.70501, 0.089354, 0.118325], None),
        p("B", true, 0.125, [0.9556, 1.212835, 5.841326, 3.082948, 0.006454, 0.016637], Some(0.017566)),
        p("B", true, 0.25, [0.9682, 2.475826, 3.708801, 4.88349, 0.012079, 0.02126], Some(0.012186)),
        p("B", true, 0.5, [0.9443, 2.069171, 5.811863, 4.00924, 0.008623, 0.024202], Some(0.013883)),
    ]
};

/// One cell of the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cell {
    /// Motion A or B.
    pub motion: MotionKind,
    /// Feedforward.
    pub method: Feedforward,
    /// ω (rad/s).
    pub omega: f64,
}

impl Cell {
    /// "A" / "B".
    pub fn motion_name(&self) -> &'static str {
        self.motion.as_str()
    }

    /// The method's name in the paper's tables.
    pub fn method_name(&self) -> &'static str {
        match self.method {
            Feedforward::Off => "1-step GA",
            Feedforward::On => "1-step GA + FF",
            Feedforward::OnWithTarget => "1-step GA + FF + target",
        }
    }

    /// Directory name of the cell's run.
    pub fn slug(&self) -> String {
        format!("{}_{}_w{}", self.motion_name(), self.method.name().replace('+', "_"), self.omega)
    }

    /// The published row of this cell, if any.
    pub fn published(&self) -> Option<&'static Published> {
        let ff = match self.method {
            Feedforward::Off => false,
            Feedforward::On => true,
            Feedforward::OnWithTarget => return None,
        };
        PUBLISHED.iter().find(|p| p.motion == self.motion_name() && p.ff == ff && p.omega == self.omega)
    }
}

/// The full grid: A and B × [`OMEGAS`] × (GA, GA + FF, GA + FF + target).
pub fn grid() -> Vec<Cell> {
    let mut cells = Vec::new();
    for motion in [MotionKind::A, MotionKind::B] {
        for method in Feedforward::ALL {
            for omega in OMEGAS {
                cells.push(Cell { motion, method, omega });
            }
        }
    }
    cells
}

/// The scenario of a cell, from a base scenario (camera, target, seed).
pub fn scenario_of(base: &Scenario, cell: &Cell) -> Scenario {
    let mut s = *base;
    s.duration_s = DURATION_S;
    s.set_method(cell.method);
    s.robot.motion = cell.motion;
    s.robot.omega_rad_s = cell.omega;
    s
}

/// Results of the grid, in [`grid`] order.
pub type GridResults = Vec<(Cell, Accuracy)>;

/// Runs every cell (in parallel over the cores, with a progress bar over all frames) and
/// writes each run's outputs under `out/runs/`, then `paper_table.csv` and `paper_table.md`.
///
/// # Errors
/// Any run's or any file's error.
pub fn run_grid(base: &Scenario, out: &Path, show_progress: bool) -> Result<GridResults> {
    run_grid_of(&grid(), base, out, show_progress)
}

/// [`run_grid`] over some of the grid's cells (e.g. one method's), in the order given.
///
/// # Errors
/// Any run's or any file's error.
pub fn run_grid_of(cells: &[Cell], base: &Scenario, out: &Path, show_progress: bool) -> Result<GridResults> {
    let frames = |c: &Cell| u64::from(crate::sim::board::frame_total(&scenario_of(base, c)));
    let results = crate::experiments::grid::run_cells(cells, frames, show_progress, |cell, tick| {
        let output = experiment::run(&scenario_of(base, cell), tick)?;
        let title = format!("motion {} / {} / ω = {} rad/s", cell.motion_name(), cell.method_name(), cell.omega);
        experiment::write_outputs(&output, &out.join("runs").join(cell.slug()), &title)?;
        Ok((*cell, output.summary.accuracy))
    })?;
    write_tables(&results, out)?;
    Ok(results)
}

fn values(a: &Accuracy) -> [f64; 7] {
    [a.f_mean, a.rms.rms_x_mm, a.rms.rms_y_mm, a.rms.rms_z_mm, a.rms.rms_e1, a.rms.rms_e2, a.rms.rms_e3]
}

/// Column names of the tables (those of `paper_tables.csv`).
pub const COLUMNS: [&str; 10] =
    ["motion", "method", "omega_rad_s", "F_mean", "rms_x_mm", "rms_y_mm", "rms_z_mm", "rms_e1", "rms_e2", "rms_e3"];

/// Writes `paper_table.csv` and `paper_table.md`.
///
/// # Errors
/// I/O errors.
pub fn write_tables(results: &[(Cell, Accuracy)], out: &Path) -> Result<()> {
    let records: Vec<Vec<String>> = results
        .iter()
        .map(|(cell, acc)| {
            let mut rec = vec![cell.motion_name().to_owned(), cell.method_name().to_owned(), format!("{}", cell.omega)];
            rec.extend(
                values(acc).iter().enumerate().map(|(i, v)| if i == 0 { format!("{v:.4}") } else { format!("{v:.6}") }),
            );
            rec
        })
        .collect();
    crate::output::io::write_table(out, "paper_table", &COLUMNS, &records, &markdown(results))
}

/// The comparison table: every cell as "ours (paper)".
pub fn markdown(results: &[(Cell, Accuracy)]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Each cell: **ours** (published). Published values: Fig. 17 (motion A) and Fig. 24 (motion B); — = not published.\n"
    );
    let _ =
        writeln!(s, "| motion | method | ω rad/s | F̄ | RMS x mm | RMS y mm | RMS z mm | RMS ε₁ | RMS ε₂ | RMS ε₃ |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
    for (cell, acc) in results {
        let ours = values(acc);
        let theirs = cell.published().map(|p| p.values).unwrap_or([None; 7]);
        let _ = write!(s, "| {} | {} | {} |", cell.motion_name(), cell.method_name(), cell.omega);
        for (i, (o, t)) in ours.iter().zip(theirs.iter()).enumerate() {
            let fmt = |v: f64| {
                if i == 0 {
                    format!("{v:.4}")
                } else if i <= 3 {
                    format!("{v:.2}")
                } else {
                    format!("{v:.4}")
                }
            };
            let pub_s = t.map(fmt).unwrap_or_else(|| "—".to_owned());
            let _ = write!(s, " **{}** ({}) |", fmt(*o), pub_s);
        }
        s.push('\n');
    }
    s
}
