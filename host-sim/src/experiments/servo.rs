//! `evorec servo`: the closed-loop experiments. The block on a conveyor (several speeds) or
//! turning, the loop run with each recognition method, over a grid of servo gains and
//! processing delays; per run the servo error over time, per cell its RMS, and a stability map
//! (gain × delay per method: converged / oscillating / diverged / lost).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use plotters::prelude::*;
use serde::Serialize;

use crate::experiments::closed_loop::{self, LoopOptions, Outcome, ServoSummary};
use crate::output::io;
use crate::output::plot::{FONT, draw_err, ensure_font, render_png};
use crate::sim::board::frame_total;
use crate::sim::scenario::{Scenario, ServoSection, TrackerTable};
use crate::sim::target_path::Conveyor;
use evorec_core::tuning::Feedforward;

/// What the block does.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum TargetCase {
    /// On a conveyor along world `y` at this speed (m/s); 0 = at rest.
    Conveyor {
        /// Belt speed (m/s).
        speed_m_s: f64,
    },
    /// Turning about the vertical (yaw oscillation, ±15° at this angular frequency).
    Rotating {
        /// `ω_o` (rad/s).
        omega_rad_s: f64,
    },
}

impl TargetCase {
    /// A short name for tables and directories.
    pub fn name(&self) -> String {
        match self {
            Self::Conveyor { speed_m_s } => format!("conveyor {speed_m_s} m/s"),
            Self::Rotating { omega_rad_s } => format!("rotating {omega_rad_s} rad/s"),
        }
    }

    fn slug(&self) -> String {
        match self {
            Self::Conveyor { speed_m_s } => format!("conveyor_{speed_m_s}"),
            Self::Rotating { omega_rad_s } => format!("rotating_{omega_rad_s}"),
        }
    }
}

/// The grid of `evorec servo`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GridSettings {
    /// Simulated seconds per run.
    pub duration_s: f64,
    /// Image width (height = 3/4 of it; fx = fy = 1.25 · width).
    pub width: u16,
    /// Target cases.
    pub targets: Vec<TargetCase>,
    /// Servo gains `λ` (1/s).
    pub gains: Vec<f64>,
    /// Processing delays (frame periods).
    pub delays: Vec<u32>,
    /// Desired block centre in `Σ_CR` (m).
    pub desired_t_m: [f64; 3],
    /// Conveyor travel (m) and reversal acceleration (m/s²).
    pub conveyor_travel_m: f64,
    /// Reversal acceleration (m/s²).
    pub conveyor_accel_m_s2: f64,
    /// Seed of every run.
    pub seed: u64,
    /// The tracker's tuning in every cell (`--config`; each cell's method replaces its `method`).
    #[serde(skip_serializing_if = "TrackerTable::is_default")]
    pub tracker: TrackerTable,
}

impl Default for GridSettings {
    /// 10 s runs at 320×240; conveyor 0, 0.05, 0.1, 0.2 m/s and turning at 0.5 rad/s; gains
    /// 1, 2, 4, 8 /s; delays 0–3 frames; the block brought to 0.6 m.
    fn default() -> Self {
        Self {
            duration_s: 10.0,
            width: 320,
            targets: vec![
                TargetCase::Conveyor { speed_m_s: 0.0 },
                TargetCase::Conveyor { speed_m_s: 0.05 },
                TargetCase::Conveyor { speed_m_s: 0.1 },
                TargetCase::Conveyor { speed_m_s: 0.2 },
                TargetCase::Rotating { omega_rad_s: 0.5 },
            ],
            gains: vec![1.0, 2.0, 4.0, 8.0],
            delays: vec![0, 1, 2, 3],
            desired_t_m: [-0.05, 0.0, 0.6],
            conveyor_travel_m: 1.0,
            conveyor_accel_m_s2: 0.5,
            seed: 1,
            tracker: TrackerTable::default(),
        }
    }
}

/// One run of the grid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Cell {
    /// The block's motion.
    pub target: TargetCase,
    /// Recognition method.
    #[serde(with = "crate::sim::scenario::feedforward_name")]
    pub method: Feedforward,
    /// Servo gain (1/s).
    pub gain: f64,
    /// Processing delay (frame periods).
    pub delay_frames: u32,
}

impl Cell {
    fn slug(&self) -> String {
        format!("{}_{}_g{}_d{}", self.target.slug(), self.method.name().replace('+', "_"), self.gain, self.delay_frames)
    }
}

/// The cells of a grid, target-major.
pub fn cells(g: &GridSettings) -> Vec<Cell> {
    let mut out = Vec::new();
    for &target in &g.targets {
        for method in Feedforward::ALL {
            for &gain in &g.gains {
                for &delay_frames in &g.delays {
                    out.push(Cell { target, method, gain, delay_frames });
                }
            }
        }
    }
    out
}

/// The scenario and loop options of a cell.
pub fn scenario_of(g: &GridSettings, cell: &Cell) -> (Scenario, LoopOptions) {
    let mut s = Scenario::new(g.seed, g.duration_s, cell.method);
    s.tracker = g.tracker;
    s.set_method(cell.method);
    let w = g.width;
    s.camera.width = w;
    s.camera.height = w / 4 * 3;
    s.camera.fx = 1.25 * f64::from(w);
    s.camera.fy = s.camera.fx;
    s.camera.cx = 0.5 * f64::from(w);
    s.camera.cy = 0.5 * f64::from(s.camera.height);
    s.camera.supersample = 2;
    let mut opts = LoopOptions {
        occlusion: None,
        conveyor: None,
        feedforward: Some(cell.method),
        target_velocity: cell.method == Feedforward::OnWithTarget,
    };
    match cell.target {
        TargetCase::Conveyor { speed_m_s } => {
            s.target.omega_rad_s = 0.0;
            if speed_m_s > 0.0 {
                opts.conveyor = Some(Conveyor::along_world_y(speed_m_s, g.conveyor_travel_m, g.conveyor_accel_m_s2));
            }
        }
        TargetCase::Rotating { omega_rad_s } => s.target.omega_rad_s = omega_rad_s,
    }
    s.servo =
        Some(ServoSection { gain: cell.gain, delay_frames: cell.delay_frames, ..ServoSection::new(g.desired_t_m) });
    (s, opts)
}

/// Runs the grid in parallel with a progress bar; writes `servo_table.csv`, `servo_table.md`,
/// `stability_<target>.png`, `settings.json` and `runs/<cell>/servo_error.csv` into `out`.
///
/// # Errors
/// Any run's or file's error.
pub fn run_grid(g: &GridSettings, out: &Path, show_progress: bool) -> Result<Vec<(Cell, ServoSummary)>> {
    let cells = cells(g);
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    crate::output::io::write_json(&out.join("settings.json"), g)?;
    let frames = |c: &Cell| u64::from(frame_total(&scenario_of(g, c).0));
    let results = crate::experiments::grid::run_cells(&cells, frames, show_progress, |cell, tick| {
        let (s, opts) = scenario_of(g, cell);
        let output = closed_loop::run(&s, &opts, tick)?;
        write_error_series(&output.servo, &out.join("runs").join(cell.slug()))?;
        Ok((*cell, output.servo_summary))
    })?;
    write_tables(&results, out)?;
    for target in &g.targets {
        stability_map(&results, g, target, &out.join(format!("stability_{}.png", target.slug())))?;
    }
    Ok(results)
}

fn write_error_series(rows: &[closed_loop::ServoRow], dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)?;
    let records: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                format!("{:.3}", r.t),
                format!("{:.4}", r.error.translation_norm() * 1e3),
                format!("{:.4}", r.error.rotation_norm().to_degrees()),
                u8::from(r.held).to_string(),
                format!("{:.5}", r.camera_speed_m_s),
                format!("{:.4}", r.tracker_error_m * 1e3),
            ]
        })
        .collect();
    let columns = ["t", "servo_err_mm", "servo_err_deg", "held", "camera_speed_m_s", "tracker_err_mm"];
    io::write_csv(&dir.join("servo_error.csv"), &columns, &records)
}

/// Columns of `servo_table.csv`.
pub const COLUMNS: [&str; 12] = [
    "target",
    "method",
    "gain",
    "delay_frames",
    "rms_err_mm",
    "rms_err_deg",
    "max_err_mm",
    "spread_mm",
    "spread_deg",
    "frames_not_held",
    "max_camera_speed_m_s",
    "outcome",
];

fn fields(c: &Cell, s: &ServoSummary) -> [String; 12] {
    [
        c.target.name(),
        c.method.name().to_owned(),
        format!("{}", c.gain),
        c.delay_frames.to_string(),
        format!("{:.2}", s.rms_err_mm),
        format!("{:.3}", s.rms_err_deg),
        format!("{:.2}", s.max_err_mm),
        format!("{:.2}", s.spread_mm),
        format!("{:.3}", s.spread_deg),
        s.frames_not_held.to_string(),
        format!("{:.3}", s.max_camera_speed_m_s),
        s.outcome.as_str().to_owned(),
    ]
}

/// Writes `servo_table.csv` and `servo_table.md` (every cell, then converged cells per
/// target and method).
///
/// # Errors
/// I/O errors.
pub fn write_tables(results: &[(Cell, ServoSummary)], out: &Path) -> Result<()> {
    let records: Vec<Vec<String>> = results.iter().map(|(c, s)| fields(c, s).to_vec()).collect();
    io::write_table(out, "servo_table", &COLUMNS, &records, &markdown(results))
}

/// The tables as Markdown: converged cells per target and method, then every cell.
pub fn markdown(results: &[(Cell, ServoSummary)]) -> String {
    let mut md = String::from(
        "| target | method | converged | oscillating | diverged | lost |\n|---|---|---:|---:|---:|---:|\n",
    );
    let mut targets: Vec<TargetCase> = Vec::new();
    for (c, _) in results {
        if !targets.contains(&c.target) {
            targets.push(c.target);
        }
    }
    for t in &targets {
        for m in Feedforward::ALL {
            let count =
                |o: Outcome| results.iter().filter(|(c, s)| c.target == *t && c.method == m && s.outcome == o).count();
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} |",
                t.name(),
                m.name(),
                count(Outcome::Converged),
                count(Outcome::Oscillating),
                count(Outcome::Diverged),
                count(Outcome::Lost)
            );
        }
    }
    md.push_str("\n| ");
    md.push_str(&COLUMNS.join(" | "));
    md.push_str(" |\n|");
    md.push_str(&"---|".repeat(COLUMNS.len()));
    md.push('\n');
    for (c, s) in results {
        let _ = writeln!(md, "| {} |", fields(c, s).join(" | "));
    }
    md
}

fn outcome_colour(o: Outcome) -> RGBColor {
    match o {
        Outcome::Converged => RGBColor(80, 170, 90),
        Outcome::Oscillating => RGBColor(240, 190, 60),
        Outcome::Diverged => RGBColor(210, 70, 60),
        Outcome::Lost => RGBColor(110, 110, 110),
    }
}

/// The stability map of one target case: one panel per method, delay across, gain up, each
/// cell coloured by its outcome and labelled with its RMS servo error (mm).
///
/// # Errors
/// Drawing or I/O errors.
pub fn stability_map(
    results: &[(Cell, ServoSummary)],
    g: &GridSettings,
    target: &TargetCase,
    path: &Path,
) -> Result<()> {
    ensure_font()?;
    let (nx, ny) = (g.delays.len(), g.gains.len());
    render_png(path, (1200, 480), |root| {
        let title =
            format!("stability map, {} (green converged, yellow oscillating, red diverged, grey lost)", target.name());
        let body = root.titled(&title, (FONT, 20)).map_err(draw_err)?;
        for (area, m) in body.split_evenly((1, 3)).iter().zip(Feedforward::ALL) {
            let mut chart = ChartBuilder::on(area)
                .caption(m.name(), (FONT, 18))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(50)
                .build_cartesian_2d(0.0..nx as f64, 0.0..ny as f64)
                .map_err(draw_err)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_desc("delay (frames), increasing →")
                .y_desc("gain, increasing →")
                .x_labels(0)
                .y_labels(0)
                .label_style((FONT, 14))
                .draw()
                .map_err(draw_err)?;
            for (c, s) in results.iter().filter(|(c, _)| c.target == *target && c.method == m) {
                let (Some(i), Some(j)) =
                    (g.delays.iter().position(|d| *d == c.delay_frames), g.gains.iter().position(|v| *v == c.gain))
                else {
                    continue;
                };
                let (x, y) = (i as f64, j as f64);
                chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(x + 0.03, y + 0.03), (x + 0.97, y + 0.97)],
                        outcome_colour(s.outcome).filled(),
                    )))
                    .map_err(draw_err)?;
                for (text, dy) in [
                    (format!("λ {} /s, {} fr", c.gain, c.delay_frames), 0.75),
                    (format!("{:.1} mm", s.rms_err_mm), 0.45),
                ] {
                    chart
                        .draw_series(std::iter::once(Text::new(text, (x + 0.12, y + dy), (FONT, 13).into_font())))
                        .map_err(draw_err)?;
                }
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_cell_runs_the_grids_tuning() {
        let mut g = GridSettings::default();
        g.tracker.0.target.image_noise_px = 0.75;
        for cell in cells(&g) {
            let s = scenario_of(&g, &cell).0;
            assert_eq!(s.tuning().target, g.tracker.0.target);
            assert_eq!(s.method(), cell.method);
        }
        let json = serde_json::to_string(&g).unwrap_or_default();
        assert!(json.contains("\"target.image_noise_px\":0.75"), "{json}");
        let plain = serde_json::to_string(&GridSettings::default()).unwrap_or_default();
        assert!(!plain.contains("tracker"), "{plain}");
    }
}
