//! `evorec servo`: the closed-loop visual servoing grid.

use std::time::Instant;

use anyhow::Result;
use evorec_core::tuning::Tuning;
use evorec_sim::experiments::servo;
use evorec_sim::sim::scenario::TrackerTable;

use super::{ConfigArg, OutArgs};

#[derive(clap::Args, Debug)]
pub struct ServoArgs {
    #[command(flatten)]
    out: OutArgs,
    /// Simulated seconds per run.
    #[arg(long, default_value_t = 10.0)]
    duration: f64,
    /// Servo gains (1/s), comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1.0, 2.0, 4.0, 8.0])]
    gains: Vec<f64>,
    /// Processing delays (frame periods), comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [0, 1, 2, 3])]
    delays: Vec<u32>,
    /// Conveyor speeds (m/s), comma-separated (the turning block is always added).
    #[arg(long, value_delimiter = ',', default_values_t = [0.0, 0.05, 0.1, 0.2])]
    speeds: Vec<f64>,
    /// Seed of every run's scenario (GA and renderer noise): one closed-loop run per cell
    /// is a single draw, so compare grids over several seeds.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The tuning of every cell (each cell's method replaces the file's `method`).
    #[command(flatten)]
    config: ConfigArg,
}

impl ServoArgs {
    pub fn run(self, progress: bool) -> Result<()> {
        let g = self.settings()?;
        let t0 = Instant::now();
        let results = servo::run_grid(&g, &self.out.out, progress)?;
        println!("{}", servo::markdown(&results).split("\n\n").next().unwrap_or_default());
        println!("{} runs in {:.1} s; wrote {}", results.len(), t0.elapsed().as_secs_f64(), self.out.out.display());
        Ok(())
    }

    /// The grid's settings, the flags checked.
    fn settings(&self) -> Result<servo::GridSettings> {
        let duration = self.duration;
        anyhow::ensure!(duration > 0.0 && duration <= 3600.0, "--duration: must be in (0, 3600], got {duration}");
        anyhow::ensure!(self.gains.iter().all(|g| *g > 0.0 && *g <= 50.0), "--gains: each must be in (0, 50]");
        anyhow::ensure!(self.delays.iter().all(|d| *d <= 10), "--delays: each must be in 0..=10");
        anyhow::ensure!(self.speeds.iter().all(|v| (0.0..=0.3).contains(v)), "--speeds: each must be in [0, 0.3]");
        let mut g = servo::GridSettings {
            duration_s: duration,
            gains: self.gains.clone(),
            delays: self.delays.clone(),
            seed: self.seed,
            ..servo::GridSettings::default()
        };
        g.targets = self.speeds.iter().map(|&speed_m_s| servo::TargetCase::Conveyor { speed_m_s }).collect();
        g.targets.push(servo::TargetCase::Rotating { omega_rad_s: 0.5 });
        g.tracker = TrackerTable(self.config.over(Tuning::DEFAULT)?);
        Ok(g)
    }
}
