//! `evorec acquire`: acquisition statistics over trials.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use evorec_core::tuning::{Feedforward, Tuning};
use evorec_sim::sim::render::Light;
use evorec_sim::sim::scenario::{Scenario, load_light};

use super::{ConfigArg, OutArgs};

#[derive(clap::Args, Debug)]
pub struct AcquireArgs {
    /// Trials per case.
    #[arg(long, default_value_t = 100)]
    trials: usize,
    /// First seed.
    #[arg(long, default_value_t = 1)]
    first_seed: u64,
    /// Points per sample row of the tracker (5, 6, 7 or 8).
    #[arg(long, default_value_t = evorec_sim::experiments::acquire::DEFAULT_POINTS)]
    points: usize,
    #[command(flatten)]
    out: OutArgs,
    /// The tuning of every trial (default: the core's defaults).
    #[command(flatten)]
    config: ConfigArg,
    /// A TOML file holding a `[render]` table (a scenario's keys, e.g.
    /// scenarios/light/camera_like.toml): the light every trial is rendered under (default:
    /// the flat light).
    #[arg(long, value_name = "FILE")]
    light: Option<PathBuf>,
}

impl AcquireArgs {
    pub fn run(self, progress: bool) -> Result<()> {
        let t0 = Instant::now();
        let out = &self.out.out;
        let tuning = self.config.over(Tuning::DEFAULT)?;
        let frame_period_s = Scenario::new(0, 1.0, Feedforward::On).frame_period_s;
        let light = match &self.light {
            Some(path) => load_light(path, frame_period_s)?,
            None => Light::default(),
        };
        let report = evorec_sim::experiments::acquire::run(
            self.trials,
            self.first_seed,
            self.points,
            &tuning,
            &light,
            out,
            progress,
        )?;
        println!("{}", evorec_sim::experiments::acquire::markdown(&report));
        println!("{} trials per case in {:.1} s; wrote {}", self.trials, t0.elapsed().as_secs_f64(), out.display());
        Ok(())
    }
}
