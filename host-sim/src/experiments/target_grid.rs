//! `evorec paper --grid target`: the block's own motion beyond the paper, under
//! motion A at ω = [`ROBOT_OMEGA`] rad/s, for the base scenario's duration (72 s by default):
//! a conveyor along world y at [`SPEEDS`] (with the
//! paper's yaw oscillation `ω_o = 0.125` rad/s), and faster yaw oscillations `ω_o` ∈
//! [`OMEGAS_O`] without conveyor; then a conveyor along the right camera's optical
//! axis at [`DEPTH_SPEEDS`], "approach" (first run towards the cameras) and "recede" (away),
//! started at full speed in the middle of its [`DEPTH_TRAVEL_M`] travel (the tracker starts on a
//! moving block); each with "1-step GA + FF" and "1-step GA + FF + target". Per
//! run also the hand-over one `[start] delay_s` after capture ([`crate::sim::board::Handover`]).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;

use crate::experiments::experiment::{self, Summary};
use crate::experiments::paper::DURATION_S;
use crate::sim::motion::MotionKind;
use crate::sim::scenario::{ConveyorFrame, ConveyorStart, Scenario, WORLD_Y};
use evorec_core::tuning::Feedforward;

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

/// Speeds of the conveyors along the optical axis, [`Belt::Approach`] and [`Belt::Recede`]
/// (m/s).
pub const DEPTH_SPEEDS: [f64; 3] = [0.05, 0.1, 0.2];

/// Travel of the conveyors along the optical axis (m): the block centre, 0.7 m ahead of the
/// stereo pair, shuttles between 0.6 and 0.8 m deep.
pub const DEPTH_TRAVEL_M: f64 = 0.2;

/// Which way a cell's conveyor runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Belt {
    /// Along world y (across the view), from rest at its −y end (the grid's first belts).
    AcrossY,
    /// Along the right camera's optical axis at `t = 0` (camera frame `[0, 0, −1]`), started
    /// at full speed in the middle of its travel towards the cameras.
    Approach,
    /// The same belt started away from the cameras (camera frame `[0, 0, 1]`).
    Recede,
}

impl Belt {
    /// The name in the tables and run directories.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::AcrossY => "y",
            Self::Approach => "approach",
            Self::Recede => "recede",
        }
    }

    /// `[target] conveyor_direction` (in [`Belt::frame`]).
    pub fn direction(self) -> [f64; 3] {
        match self {
            Self::AcrossY => WORLD_Y,
            Self::Approach => [0.0, 0.0, -1.0],
            Self::Recede => [0.0, 0.0, 1.0],
        }
    }

    /// `[target] conveyor_direction_frame`.
    pub fn frame(self) -> ConveyorFrame {
        match self {
            Self::AcrossY => ConveyorFrame::World,
            Self::Approach | Self::Recede => ConveyorFrame::Camera,
        }
    }

    /// `[target] conveyor_start`.
    pub fn start(self) -> ConveyorStart {
        match self {
            Self::AcrossY => ConveyorStart::Rest,
            Self::Approach | Self::Recede => ConveyorStart::Moving,
        }
    }

    /// `[target] conveyor_travel_m`.
    pub fn travel_m(self) -> f64 {
        match self {
            Self::AcrossY => TRAVEL_M,
            Self::Approach | Self::Recede => DEPTH_TRAVEL_M,
        }
    }
}

/// One cell: a conveyor (its direction, and speed, 0 = none) and a yaw frequency `ω_o`, and a
/// method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cell {
    /// Which way the conveyor runs.
    pub belt: Belt,
    /// Conveyor speed (m/s), 0 = none.
    pub speed_m_s: f64,
    /// Yaw oscillation frequency `ω_o` (rad/s).
    pub omega_o: f64,
    /// FF or FF + target.
    pub method: Feedforward,
}

impl Cell {
    /// Directory name of the cell's run.
    pub fn slug(&self) -> String {
        let belt = match self.belt {
            Belt::AcrossY => String::new(),
            b => format!("_{}", b.as_str()),
        };
        format!("target_{}{belt}_v{}_wo{}", self.method.name().replace('+', "_"), self.speed_m_s, self.omega_o)
    }

    /// The conveyor's name in the tables: its [`Belt::as_str`], "–" without one.
    pub fn belt_name(&self) -> &'static str {
        if self.speed_m_s > 0.0 { self.belt.as_str() } else { "–" }
    }

    /// The method's name in the tables.
    pub fn method_name(&self) -> &'static str {
        crate::experiments::paper::Cell { motion: MotionKind::A, method: self.method, omega: ROBOT_OMEGA }.method_name()
    }
}

/// The grid: [`SPEEDS`] across y at [`PAPER_OMEGA_O`], then the other [`OMEGAS_O`] without
/// conveyor, then [`Belt::Approach`] and [`Belt::Recede`] at [`DEPTH_SPEEDS`] and
/// [`PAPER_OMEGA_O`]; each with FF and FF + target.
pub fn grid() -> Vec<Cell> {
    let mut conditions: Vec<(Belt, f64, f64)> = SPEEDS.iter().map(|&v| (Belt::AcrossY, v, PAPER_OMEGA_O)).collect();
    conditions.extend(OMEGAS_O.iter().filter(|&&w| w != PAPER_OMEGA_O).map(|&w| (Belt::AcrossY, 0.0, w)));
    for belt in [Belt::Approach, Belt::Recede] {
        conditions.extend(DEPTH_SPEEDS.iter().map(|&v| (belt, v, PAPER_OMEGA_O)));
    }
    let mut cells = Vec::new();
    for (belt, speed_m_s, omega_o) in conditions {
        for method in [Feedforward::On, Feedforward::OnWithTarget] {
            cells.push(Cell { belt, speed_m_s, omega_o, method });
        }
    }
    cells
}

/// The scenario of a cell (the base scenario's duration, seed, camera): motion A at
/// [`ROBOT_OMEGA`], the cell's [`Belt`] over its [`Belt::travel_m`] with reversals at
/// max(0.5, 2v²/travel) m/s².
pub fn scenario_of(base: &Scenario, cell: &Cell) -> Scenario {
    let mut s = *base;
    s.set_method(cell.method);
    s.robot.motion = MotionKind::A;
    s.robot.omega_rad_s = ROBOT_OMEGA;
    s.target.omega_rad_s = cell.omega_o;
    s.target.conveyor_speed_m_s = cell.speed_m_s;
    let travel = cell.belt.travel_m();
    s.target.conveyor_travel_m = travel;
    let v = cell.speed_m_s;
    s.target.conveyor_accel_m_s2 = (2.0 * v * v / travel).max(0.5);
    s.target.conveyor_direction = cell.belt.direction();
    s.target.conveyor_direction_frame = cell.belt.frame();
    s.target.conveyor_start = cell.belt.start();
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
    let frames = |c: &Cell| u64::from(crate::sim::board::frame_total(&scenario_of(base, c)));
    let results = crate::experiments::grid::run_cells(cells, frames, show_progress, |cell, tick| {
        let output = experiment::run(&scenario_of(base, cell), tick)?;
        let belt = match cell.belt {
            Belt::AcrossY => String::new(),
            b => format!(" ({})", b.as_str()),
        };
        let title = format!(
            "motion A ω = {ROBOT_OMEGA} / {} / conveyor {} m/s{belt}, ω_o = {} rad/s",
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
pub const COLUMNS: [&str; 18] = [
    "conveyor_m_s",
    "conveyor_dir",
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
    let (f_mean, a) = (s.accuracy.f_mean, &s.accuracy.rms);
    let tracking = s.status.tracking as f64 / a.frames.max(1) as f64;
    let (delay, cap, held, pred, rp, re) = match &s.handover {
        Some(h) => (
            h.delay_s,
            h.at_capture.position_mm(),
            h.held.position_mm(),
            h.predicted.position_mm(),
            h.position_ratio,
            h.eps_ratio,
        ),
        None => (f64::NAN, f64::NAN, f64::NAN, f64::NAN, f64::NAN, f64::NAN),
    };
    [f_mean, a.rms_x_mm, a.rms_y_mm, a.rms_z_mm, a.rms_e1, a.rms_e2, a.rms_e3, tracking, delay, cap, held, pred, rp, re]
}

/// Writes `target_table.csv` and `target_table.md`.
///
/// # Errors
/// I/O errors.
pub fn write_tables(results: &[(Cell, Summary)], out: &Path) -> Result<()> {
    let records: Vec<Vec<String>> = results
        .iter()
        .map(|(cell, summary)| {
            let mut rec = vec![
                format!("{}", cell.speed_m_s),
                cell.belt_name().to_owned(),
                format!("{}", cell.omega_o),
                cell.method_name().to_owned(),
            ];
            rec.extend(values(summary).iter().map(|v| format!("{v:.6}")));
            rec
        })
        .collect();
    crate::output::io::write_table(out, "target_table", &COLUMNS, &records, &markdown(results))
}

/// The grid as a Markdown table.
pub fn markdown(results: &[(Cell, Summary)]) -> String {
    let mut s = String::new();
    let depth = results.first().map_or(0.7, |(_, s)| s.scenario.target.distance_m);
    let _ = writeln!(
        s,
        "Motion A at ω = {ROBOT_OMEGA} rad/s, {} s per run. Conveyor y: along world y over {TRAVEL_M} m, from \
         rest; approach / recede: along the right camera's optical axis over {DEPTH_TRAVEL_M} m (block centre \
         {:.2}–{:.2} m deep), started at full speed in its middle towards / away from the cameras. ω_o: the \
         block's yaw oscillation (±15°). Hand-over (frames reported as tracking): RMS position error at \
         capture, of the estimate held until the output time, and of the core's prediction for it; ratio = \
         predicted / at capture.\n",
        results.first().map_or(DURATION_S, |(_, s)| s.scenario.duration_s),
        depth - 0.5 * DEPTH_TRAVEL_M,
        depth + 0.5 * DEPTH_TRAVEL_M,
    );
    let _ = writeln!(
        s,
        "| conveyor m/s | direction | ω_o rad/s | method | F̄ | RMS x mm | RMS y mm | RMS z mm | RMS ε₁ | RMS ε₂ | RMS ε₃ | \
         tracking | capture mm | held mm | predicted mm | ratio pos | ratio ε |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for (cell, summary) in results {
        let v = values(summary);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.4} | {:.2} | {:.2} | {:.2} | {:.4} | {:.4} | {:.4} | {:.0} % | {:.2} | {:.2} | {:.2} | \
             {:.2} | {:.2} |",
            cell.speed_m_s,
            cell.belt_name(),
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
    use nalgebra::Vector3;

    use super::*;
    use crate::sim::target_path::{self, TargetPath};

    #[test]
    fn grid_covers_the_issue_s_speeds_and_yaw_rates_with_both_methods() {
        let cells = grid();
        assert_eq!(cells.len(), 2 * (SPEEDS.len() + OMEGAS_O.len() - 1 + 2 * DEPTH_SPEEDS.len()));
        for v in SPEEDS {
            for m in [Feedforward::On, Feedforward::OnWithTarget] {
                assert!(cells.contains(&Cell { belt: Belt::AcrossY, speed_m_s: v, omega_o: PAPER_OMEGA_O, method: m }));
            }
        }
        for w in [0.5, 1.0] {
            assert!(cells.iter().any(|c| c.speed_m_s == 0.0 && c.omega_o == w));
        }
        let base = Scenario::new(1, 1.0, Feedforward::Off);
        for c in &cells {
            let s = scenario_of(&base, c);
            let text = s.to_toml_string().unwrap_or_else(|e| unreachable!("{e}"));
            // Every cell is a valid scenario (the conveyor can reverse within its travel).
            let back = Scenario::from_toml_str(&text).unwrap_or_else(|e| unreachable!("{c:?}: {e}"));
            assert_eq!(back, s);
            assert_eq!((s.robot.motion, s.robot.omega_rad_s, s.method()), (MotionKind::A, ROBOT_OMEGA, c.method));
        }
    }

    fn depth_cells() -> Vec<Cell> {
        grid().into_iter().filter(|c| c.belt != Belt::AcrossY).collect()
    }

    #[test]
    fn the_issue_s_cells_keep_their_slugs_and_scenarios() {
        let cells = grid();
        // The belts across y come first, with their names and scenarios unchanged.
        let old: Vec<&Cell> = cells.iter().take(2 * (SPEEDS.len() + OMEGAS_O.len() - 1)).collect();
        assert!(old.iter().all(|c| c.belt == Belt::AcrossY));
        assert_eq!(old[6].slug(), "target_ff_v0.2_wo0.125");
        assert_eq!(old[7].slug(), "target_ff_target_v0.2_wo0.125");
        let base = Scenario::new(1, 1.0, Feedforward::Off);
        let s = scenario_of(&base, old[7]);
        assert_eq!(
            (s.target.conveyor_travel_m, s.target.conveyor_direction, s.target.conveyor_start),
            (TRAVEL_M, WORLD_Y, ConveyorStart::Rest)
        );
        assert_eq!(s.target.conveyor_direction_frame, ConveyorFrame::World);
        // The depth cells: both belts at every speed with both methods, moving at t = 0.
        let depth = depth_cells();
        assert_eq!(depth.len(), 2 * 2 * DEPTH_SPEEDS.len());
        for belt in [Belt::Approach, Belt::Recede] {
            for v in DEPTH_SPEEDS {
                for m in [Feedforward::On, Feedforward::OnWithTarget] {
                    let c = Cell { belt, speed_m_s: v, omega_o: PAPER_OMEGA_O, method: m };
                    assert!(depth.contains(&c), "{c:?}");
                }
            }
        }
        let c = depth
            .iter()
            .find(|c| c.belt == Belt::Recede && c.speed_m_s == 0.1 && c.method == Feedforward::OnWithTarget);
        assert_eq!(c.map(Cell::slug).as_deref(), Some("target_ff_target_recede_v0.1_wo0.125"));
    }

    #[test]
    fn depth_belts_run_along_the_optical_axis_from_the_middle_at_full_speed() {
        let base = Scenario::new(1, 72.0, Feedforward::On);
        let cam = crate::sim::motion::initial_camera_pose(base.camera.baseline_m);
        for c in depth_cells() {
            let s = scenario_of(&base, &c);
            let path = TargetPath::from_scenario(&s);
            let motion = crate::sim::board::target_motion(&s);
            // In Σ_CR at t = 0: at the middle of the travel, moving along ∓z at the cell's speed.
            let v_cam = cam.rotation.inverse() * path.offset(0.0).velocity;
            let sign = if c.belt == Belt::Approach { -1.0 } else { 1.0 };
            assert!((v_cam - Vector3::new(0.0, 0.0, sign * c.speed_m_s)).norm() < 1e-12, "{c:?}: {v_cam}");
            assert!(path.offset(0.0).position.norm() < 1e-12);
            // Over the run the centre stays within travel/2 of its start, along that axis.
            for k in 0..=720 {
                let t = 0.1 * f64::from(k);
                let p = cam.inverse() * target_path::target_pose(&motion, &path, t).translation.vector;
                let p0 = cam.inverse() * motion.centre.coords;
                let d = p - p0;
                assert!(d.x.abs() < 1e-12 && d.y.abs() < 1e-12, "{c:?} t={t}: {d}");
                assert!(d.z.abs() <= 0.5 * DEPTH_TRAVEL_M + 1e-12, "{c:?} t={t}: {d}");
            }
        }
    }

    /// The smallest distance (pixels) of a block corner (or, with `centre`, of the block centre)
    /// from the border of either image, every 50 ms of the scenario's run along the scripted
    /// flange motion (the arm follows it within a fraction of a millimetre); negative outside.
    fn worst_margin_px(s: &Scenario, centre: bool) -> f64 {
        let c = &s.camera;
        let block = crate::sim::board::block(s);
        let (path, motion) = (TargetPath::from_scenario(s), crate::sim::board::target_motion(s));
        let (flange, mount) =
            (crate::sim::board::flange_trajectory(s), crate::sim::motion::flange_to_camera_f64(c.baseline_m));
        let points: Vec<Vector3<f64>> = if centre {
            vec![Vector3::zeros()]
        } else {
            block.corners().iter().map(|p| p.coords.cast::<f64>()).collect()
        };
        let mut worst = f64::INFINITY;
        for k in 0..=(s.duration_s / 0.05) as u32 {
            let t = 0.05 * f64::from(k);
            let cam = flange.setpoint(t).pose * mount;
            let pose = cam.inverse() * target_path::target_pose(&motion, &path, t);
            for p in &points {
                let q = pose * nalgebra::Point3::from(*p);
                // Right camera, and the left one a baseline along −x (its origin at −baseline).
                for dx in [0.0, c.baseline_m] {
                    let (u, v) = (c.fx * (q.x + dx) / q.z + c.cx, c.fy * q.y / q.z + c.cy);
                    worst = worst.min(u.min(v).min(f64::from(c.width) - u).min(f64::from(c.height) - v));
                }
            }
        }
        worst
    }

    #[test]
    fn depth_belts_keep_the_block_in_view_as_the_belts_across_y_do() {
        // Motion A's ±0.1 m sway already takes a corner of the block out of an image now and
        // then on the belts across y (about 90 px at 0.1 m/s and faster); the depth belts
        // over 0.2 m keep the block centre well inside both images and lose less of the block.
        let base = Scenario::new(1, 72.0, Feedforward::On);
        let across = Cell { belt: Belt::AcrossY, speed_m_s: 0.2, omega_o: PAPER_OMEGA_O, method: Feedforward::On };
        let across_corner = worst_margin_px(&scenario_of(&base, &across), false);
        assert!(across_corner < -50.0, "{across_corner}");
        for c in depth_cells().into_iter().filter(|c| c.method == Feedforward::On) {
            let s = scenario_of(&base, &c);
            let (corner, centre) = (worst_margin_px(&s, false), worst_margin_px(&s, true));
            assert!(centre > 100.0, "{c:?}: the centre comes within {centre:.1} px of an image border");
            assert!(corner > across_corner, "{c:?}: a corner {:.1} px outside an image", -corner);
        }
    }

    #[test]
    fn shipped_approach_and_recede_scenarios_are_the_grid_s_0_1_m_s_cells() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
        let base = Scenario::new(1, 20.0, Feedforward::On);
        for (file, belt) in [("approach_ff_target.toml", Belt::Approach), ("recede_ff_target.toml", Belt::Recede)] {
            let s = Scenario::load(dir.join(file)).unwrap_or_else(|e| unreachable!("{e}"));
            let cell = Cell { belt, speed_m_s: 0.1, omega_o: PAPER_OMEGA_O, method: Feedforward::OnWithTarget };
            assert_eq!(s, scenario_of(&base, &cell), "{file}");
        }
    }
}
