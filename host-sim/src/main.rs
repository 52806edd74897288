//! `evorec`: the host simulator's command line.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use evorec_sim::scenario::{Method, Scenario};
use evorec_sim::{experiment, frame, hil, paper};

/// On-line evolutionary 3D pose recognition: PA-10 hand-eye stereo simulator.
#[derive(Parser, Debug)]
#[command(version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run one scenario: writes DIR/trace.csv, DIR/summary.json and plots.
    Run {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
    },
    /// The paper's experiment: motions A and B × ω ∈ {0, 0.125, 0.25, 0.5, 1.0} × (GA, GA + FF),
    /// 72 s each, in parallel; writes DIR/paper_table.csv, DIR/paper_table.md and DIR/runs/.
    Paper {
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Scenario whose camera, target and seed the grid uses (default: built-in defaults,
        /// seed 1).
        #[arg(long)]
        base: Option<PathBuf>,
        /// Hide the progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Run one scenario with the tracker in the firmware under QEMU (the scenario must render
    /// the firmware's 160x120 frames); writes the same files as `run`. Builds nothing: build
    /// the firmware first (`cd hil-stubs && cargo build --release`).
    Hil {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Output directory (also holds QEMU's FIFOs and log).
        #[arg(long)]
        out: PathBuf,
        /// Firmware ELF (default: $EVOREC_FIRMWARE_ELF, else the workspace's
        /// target/thumbv7em-none-eabihf/release/evorec-firmware).
        #[arg(long)]
        firmware: Option<PathBuf>,
    },
    /// Worst-case timing and memory per GA generation on the Cortex-M4: runs the timing
    /// firmware under QEMU with -icount and writes DIR/timing.json and DIR/timing.md. Builds
    /// nothing: build the firmware first (`cd hil-stubs && cargo build --release`).
    Timing {
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
    },
    /// Acquisition statistics: N random block poses (seeds FIRST_SEED..), each from an unknown
    /// start and through a 1 s occlusion, static arm and motion A at 0.5 rad/s with FF, in
    /// parallel; writes DIR/acquire.json, DIR/acquire.md and DIR/acquire_cdf.png.
    Acquire {
        /// Trials per case.
        #[arg(long, default_value_t = 100)]
        trials: usize,
        /// First seed.
        #[arg(long, default_value_t = 1)]
        first_seed: u64,
        /// Points per sample row of the tracker (5 or 8).
        #[arg(long, default_value_t = evorec_sim::acquire::DEFAULT_POINTS)]
        points: usize,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Hide the progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Render one frame of a scenario: left/right PNGs, the same with the projected search
    /// model at the true pose drawn over them, and frame.json with the geometry.
    Render {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Frame index (frame n is captured at n · frame_period_s).
        #[arg(long, default_value_t = 0)]
        frame: u32,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
    },
}

fn load(path: &Path) -> Result<Scenario> {
    Ok(Scenario::load(path)?)
}

fn report(a: &experiment::Accuracy, t0: Instant) {
    println!(
        "{} frames in {:.1} s: F_mean {:.4}, RMS x/y/z {:.2}/{:.2}/{:.2} mm, RMS e1/e2/e3 {:.4}/{:.4}/{:.4}",
        a.frames,
        t0.elapsed().as_secs_f64(),
        a.f_mean,
        a.rms_x_mm,
        a.rms_y_mm,
        a.rms_z_mm,
        a.rms_e1,
        a.rms_e2,
        a.rms_e3
    );
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Run { scenario, out } => {
            let s = load(&scenario)?;
            let t0 = Instant::now();
            let output = experiment::run(&s, || {})?;
            let title = format!("{} ({})", scenario.display(), s.method.as_str());
            experiment::write_outputs(&output, &out, &title)?;
            report(&output.summary.accuracy, t0);
            println!("wrote {}", out.display());
        }
        Command::Paper { out, base, quiet } => {
            let base = match base {
                Some(p) => load(&p)?,
                None => Scenario::new(1, paper::DURATION_S, Method::Ff),
            };
            let t0 = Instant::now();
            let results = paper::run_grid(&base, &out, !quiet)?;
            println!("{}", paper::markdown(&results));
            println!("{} runs in {:.1} s; wrote {}", results.len(), t0.elapsed().as_secs_f64(), out.display());
        }
        Command::Hil { scenario, out, firmware } => {
            let s = load(&scenario)?;
            let firmware = firmware.unwrap_or_else(evorec_firmware::host::default_firmware_path);
            let t0 = Instant::now();
            let output = hil::run(&s, &firmware, &out.join("qemu"), || {})?;
            let title = format!("{} ({}, firmware on QEMU)", scenario.display(), s.method.as_str());
            experiment::write_outputs(&output, &out, &title)?;
            report(&output.summary.accuracy, t0);
            println!("wrote {}", out.display());
        }
        Command::Acquire { trials, first_seed, points, out, quiet } => {
            let t0 = Instant::now();
            let report = evorec_sim::acquire::run(trials, first_seed, points, &out, !quiet)?;
            println!("{}", evorec_sim::acquire::markdown(&report));
            println!("{} trials per case in {:.1} s; wrote {}", trials, t0.elapsed().as_secs_f64(), out.display());
        }
        Command::Timing { out } => {
            evorec_sim::timing::run(&out)?;
        }
        Command::Render { scenario, frame: n, out } => {
            let s = load(&scenario)?;
            let files = frame::render_frame(&s, n, &out).context("rendering")?;
            for f in files {
                println!("wrote {}", f.display());
            }
        }
    }
    Ok(())
}
