//! `evorec servo`, `timing`, `export`, `acquire` and `render`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use evorec_core::tuning::{Feedforward, Tuning};
use evorec_sim::experiments::servo;
use evorec_sim::output::frame;
use evorec_sim::rig::export;
use evorec_sim::sim::render::Light;
use evorec_sim::sim::scenario::{Scenario, TrackerTable, load_light};

use super::{ConfigArg, OutArgs, load};

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

#[derive(clap::Args, Debug)]
pub struct TimingArgs {
    #[command(flatten)]
    out: OutArgs,
    /// Board profile: `m4` (Cortex-M4F, STM32F4 at 168 MHz, 160×120) or `m7` (Cortex-M7,
    /// STM32H743 at 480 MHz, 320×240).
    #[arg(long, default_value = "m4", value_parser = ["m4", "m7"])]
    profile: String,
}

impl TimingArgs {
    pub fn run(self) -> Result<()> {
        let board = evorec_sim::firmware::timing::Board::by_name(&self.profile)
            .ok_or_else(|| anyhow::anyhow!("--profile {}: expected m4 or m7", self.profile))?;
        evorec_sim::firmware::timing::run(self.out.create()?, board)
    }
}

#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// Scenario file (TOML).
    scenario: PathBuf,
    /// Sequence directory to create (must not exist or be empty).
    #[arg(long)]
    out: PathBuf,
}

impl ExportArgs {
    pub fn run(self, progress: bool) -> Result<()> {
        let s = load(&self.scenario)?;
        let name = self.scenario.file_stem().map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        let bar = progress
            .then(|| evorec_sim::output::logging::progress_bar(u64::from(evorec_sim::sim::board::frame_total(&s))));
        let stats = export::export(&s, &name, &self.out, bar.clone())?;
        if let Some(b) = bar {
            b.finish_and_clear();
        }
        println!("wrote {} ({} frames, {} joint samples)", self.out.display(), stats.frames, stats.joint_samples);
        Ok(())
    }
}

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

#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scenario file (TOML).
    scenario: PathBuf,
    /// Frame index (frame n is captured at n · frame_period_s).
    #[arg(long, default_value_t = 0)]
    frame: u32,
    #[command(flatten)]
    out: OutArgs,
}

impl RenderArgs {
    pub fn run(self) -> Result<()> {
        let s = load(&self.scenario)?;
        let files = frame::render_frame(&s, self.frame, self.out.create()?).context("rendering")?;
        for f in files {
            println!("wrote {}", f.display());
        }
        Ok(())
    }
}

#[derive(clap::Args, Debug)]
pub struct ConfigArgs {
    /// A scenario whose `[tracker]` table to print (default: the core's defaults).
    scenario: Option<PathBuf>,
    #[command(flatten)]
    config: ConfigArg,
}

impl ConfigArgs {
    pub fn run(self) -> Result<()> {
        let base = match &self.scenario {
            Some(path) => *load(path)?.tuning(),
            None => Tuning::DEFAULT,
        };
        print!("{}", TrackerTable(self.config.over(base)?).to_toml());
        Ok(())
    }
}
