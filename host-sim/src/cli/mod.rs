//! The command line: one [`clap::Args`] struct per subcommand, each with its `run`, and the
//! arguments they share.
//!
//! Layer `cli`, on top of the library's layers (see the crate doc of `evorec_sim`): the
//! `evorec` binary's own modules, which may use every layer; no layer uses them.

mod acquire;
mod colours;
mod config;
mod export;
mod hil;
mod import;
mod paper;
mod render;
mod rig;
mod run;
mod servo;
mod timing;
mod track;

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::{Parser, Subcommand};
use evorec_core::tuning::{Feedforward, Tuning};
use evorec_sim::output::io;
use evorec_sim::sim::scenario::{Scenario, with_config_file};

/// On-line evolutionary 3D pose recognition: PA-10 hand-eye stereo simulator.
#[derive(Parser, Debug)]
#[command(version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
    /// More log output (-v info, -vv debug, -vvv trace); `RUST_LOG` overrides.
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    pub verbose: u8,
    /// Only errors in the log, and no progress bar.
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    pub quiet: bool,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Run one scenario: writes DIR/trace.csv, DIR/estimate.tum (TUM format), DIR/summary.json
    /// (with the rotation error) and plots.
    Run(run::RunArgs),
    /// The paper's experiment: motions A and B × ω ∈ {0, 0.125, 0.25, 0.5, 1.0} × (GA, GA + FF,
    /// GA + FF + target), 72 s each, in parallel; writes DIR/paper_table.csv, DIR/paper_table.md
    /// and DIR/runs/. `--grid target` runs the grid over the block's own motion instead
    /// (DIR/target_table.*), `--grid both` both.
    Paper(paper::PaperArgs),
    /// Run one scenario with the tracker in the firmware under QEMU (the scenario must render
    /// the firmware's 160x120 frames); writes the same files as `run`. Builds nothing: build
    /// the firmware first (`cd hil-stubs && cargo build --release`).
    Hil(hil::HilArgs),
    /// Closed-loop experiments (position-based visual servoing from the tracker's estimates):
    /// conveyor 0/0.05/0.1/0.2 m/s and turning block × (ga, ff, ff+target) × gains × delays,
    /// in parallel; writes DIR/servo_table.csv, DIR/servo_table.md, DIR/stability_*.png and
    /// DIR/runs/*/servo_error.csv.
    Servo(servo::ServoArgs),
    /// Worst-case timing and memory per GA generation on the board: runs the timing firmware
    /// under QEMU with -icount and writes DIR/timing.json and DIR/timing.md. Builds nothing:
    /// build the firmware first (`cd hil-stubs && cargo build --release`; for `--profile m7`
    /// `cd hil-stubs && CARGO_TARGET_DIR=../target/m7 cargo build --release --features m7`).
    Timing(timing::TimingArgs),
    /// Track a recorded stereo sequence (`evorec-seq/1` directory) or a ROS 2 bag (with
    /// `--rig`): writes DIR/trace.csv, DIR/estimate.tum (TUM format), DIR/summary.json, plots
    /// and `DIR/overlay_<N>.png`, and for a bag DIR/estimate.mcap + DIR/metadata.yaml, which
    /// make DIR a rosbag2 bag (pose with covariance, status, /tf, marker, velocity; names from
    /// the rig file's output table). Nothing is written unless the whole sequence was tracked.
    Track(track::TrackArgs),
    /// Write a ROS 2 bag (MCAP storage: a bag directory or one .mcap file) as a recorded sequence
    /// (`evorec-seq/1`): images paired by stamp, joint states by name, transforms from tf, the URDF
    /// from the bag or the rig file. Nothing is written at OUT unless the whole bag was read.
    Import(import::ImportArgs),
    /// Draft a rig file (`evorec-rig/1`) from a ROS 2 bag: topics by message type, the camera
    /// frames from the images, the base link from the URDF and the flange from /tf_static.
    /// Keys the bag leaves open are written as "TODO" with the candidates; the block's
    /// `[target]` section is written commented out, to fill in.
    Rig(rig::RigArgs),
    /// Write a simulator scenario as a recorded sequence (`evorec-seq/1`): the PA-10's URDF,
    /// camera_info YAMLs, PNGs, joints at 1 kHz, ground truth, sequence.toml with the initial
    /// pose; `evorec track SEQ` then reads it back.
    Export(export::ExportArgs),
    /// Acquisition statistics: N random block poses (seeds FIRST_SEED..), each from an unknown
    /// start and through a 1 s occlusion, static arm and motion A at 0.5 rad/s with FF, in
    /// parallel; writes DIR/acquire.json, DIR/acquire.md and DIR/acquire_cdf.png.
    Acquire(acquire::AcquireArgs),
    /// Render one frame of a scenario: left/right PNGs, the same with the projected search
    /// model at the true pose drawn over them, and frame.json with the geometry.
    Render(render::RenderArgs),
    /// The block's face colours as the cameras of a recorded sequence or a ROS 2 bag see them:
    /// tracks from the first frame to `--frames` past `--frame` (a frame showing the block),
    /// prints each face's measured hue and band, and writes them as a `[target]` table
    /// (`--out`, default colours.toml) for sequence.toml or the rig file. Tracking does not
    /// need it: the tracker learns the colours by itself.
    Colours(colours::ColoursArgs),
    /// Print the tracker's tuning as a `[tracker]` TOML table, every field with its unit and
    /// meaning: the defaults, or a scenario's (and a `--config` file's) effective values. Give
    /// the file to `run`, `hil`, `track`, `servo` or `acquire` with `--config FILE`.
    Config(config::ConfigArgs),
}

impl Command {
    /// Runs the subcommand; `progress` shows progress bars (not `--quiet`).
    pub fn run(self, progress: bool) -> Result<()> {
        match self {
            Self::Run(a) => a.run(),
            Self::Paper(a) => a.run(progress),
            Self::Hil(a) => a.run(),
            Self::Servo(a) => a.run(progress),
            Self::Timing(a) => a.run(),
            Self::Track(a) => a.run(progress),
            Self::Import(a) => a.run(progress),
            Self::Rig(a) => a.run(),
            Self::Export(a) => a.run(progress),
            Self::Acquire(a) => a.run(progress),
            Self::Render(a) => a.run(),
            Self::Config(a) => a.run(),
            Self::Colours(a) => a.run(progress),
        }
    }
}

/// `--out DIR`: the output directory of the subcommands that write several files into one.
#[derive(clap::Args, Debug, Clone)]
pub struct OutArgs {
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

impl OutArgs {
    /// Creates the output directory before the work ([`io::create_out_dir`]).
    pub fn create(&self) -> Result<&Path> {
        io::create_out_dir(&self.out)?;
        Ok(&self.out)
    }
}

/// `--config FILE`: the tracker's tuning from a file, the one declaration of the option for
/// every subcommand that takes it (`#[command(flatten)]`).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ConfigArg {
    /// A TOML file holding a `[tracker]` table (as `evorec config` prints it, or a run's
    /// `config.toml`): its keys replace the tuning the command starts from (the scenario's or
    /// the defaults); options such as `--method` replace its keys.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
}

impl ConfigArg {
    /// The file, if given.
    pub fn path(&self) -> Option<&Path> {
        self.config.as_deref()
    }

    /// `base` with the file's keys, if a file is given.
    pub fn over(&self, base: Tuning) -> Result<Tuning> {
        Ok(with_config_file(base, self.path())?)
    }
}

/// `--config`, `--method` and `--seed` of the subcommands that run one scenario file (`run`,
/// `hil`).
#[derive(clap::Args, Debug, Clone)]
pub struct Overrides {
    #[command(flatten)]
    pub config: ConfigArg,
    /// Override the scenario's method: ga, ff or ff+target.
    #[arg(long, value_parser = str::parse::<Feedforward>)]
    pub method: Option<Feedforward>,
    /// Override the scenario's seed (GA and image noise), 0 ..= 2^63−1: for seed sweeps.
    #[arg(long, value_parser = clap::value_parser!(u64).range(0..=i64::MAX as u64))]
    pub seed: Option<u64>,
}

impl Overrides {
    /// The scenario file `path` with the overrides applied: the configuration file's keys,
    /// then `--method`, then `--seed`.
    pub fn load(&self, path: &Path) -> Result<Scenario> {
        let mut s = load(path)?;
        s.tracker.0 = self.config.over(*s.tuning())?;
        if let Some(m) = self.method {
            s.set_method(m);
        }
        s.seed = self.seed.unwrap_or(s.seed);
        Ok(s)
    }
}

/// A scenario file.
pub fn load(path: &Path) -> Result<Scenario> {
    Ok(Scenario::load(path)?)
}
