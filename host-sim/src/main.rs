//! `evorec`: the host simulator's command line.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
use evorec_sim::scenario::{Method, Scenario};
use evorec_sim::sequence::Sequence;
use evorec_sim::{bag, closed_loop, experiment, export, frame, hil, io, paper, servo, target_grid, track};

/// On-line evolutionary 3D pose recognition: PA-10 hand-eye stereo simulator.
#[derive(Parser, Debug)]
#[command(version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// More log output (-v info, -vv debug, -vvv trace); `RUST_LOG` overrides.
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    verbose: u8,
    /// Only errors in the log, and no progress bar.
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    quiet: bool,
}

/// `evorec track --pixels`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum TrackPixels {
    /// The PNG's own 8-bit RGB.
    Rgb888,
    /// Truncated to RGB565 first (the board's sensor format).
    Rgb565,
}

impl From<TrackPixels> for track::Pixels {
    fn from(p: TrackPixels) -> Self {
        match p {
            TrackPixels::Rgb888 => Self::Rgb888,
            TrackPixels::Rgb565 => Self::Rgb565,
        }
    }
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
        /// Override the scenario's method: ga, ff or ff+target.
        #[arg(long, value_parser = Method::parse)]
        method: Option<Method>,
        /// Override the scenario's seed (GA and image noise), 0 ..= 2^63−1: for seed sweeps.
        #[arg(long, value_parser = clap::value_parser!(u64).range(0..=i64::MAX as u64))]
        seed: Option<u64>,
    },
    /// The paper's experiment: motions A and B × ω ∈ {0, 0.125, 0.25, 0.5, 1.0} × (GA, GA + FF,
    /// GA + FF + target), 72 s each, in parallel; writes DIR/paper_table.csv, DIR/paper_table.md
    /// and DIR/runs/. `--grid target` runs the grid over the block's own motion instead
    /// (DIR/target_table.*), `--grid both` both.
    Paper {
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Scenario whose camera, target and seed the grid uses (default: built-in defaults,
        /// seed 1, 72 s); the target grid also takes its duration (the paper's is 72 s).
        #[arg(long)]
        base: Option<PathBuf>,
        /// Which grid: the paper's, the one over the block's own motion, or both.
        #[arg(long, value_enum, default_value_t = Grid::Paper)]
        grid: Grid,
        /// Run only this method's cells (ga, ff or ff+target; the target grid has ff and
        /// ff+target).
        #[arg(long, value_parser = Method::parse)]
        method: Option<Method>,
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
        /// Override the scenario's method: ga, ff or ff+target.
        #[arg(long, value_parser = Method::parse)]
        method: Option<Method>,
        /// Link fault injection: the fraction of messages (both directions) that are bit-flipped,
        /// dropped, duplicated, truncated or delayed, e.g. 0.01 for 1 %. Writes `link.json`.
        #[arg(long)]
        faults: Option<f64>,
        /// Seed of the fault injection.
        #[arg(long, default_value_t = 1)]
        fault_seed: u64,
    },
    /// Closed-loop experiments (position-based visual servoing from the tracker's estimates):
    /// conveyor 0/0.05/0.1/0.2 m/s and turning block × (ga, ff, ff+target) × gains × delays,
    /// in parallel; writes DIR/servo_table.csv, DIR/servo_table.md, DIR/stability_*.png and
    /// DIR/runs/*/servo_error.csv.
    Servo {
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
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
        /// A TOML file holding a `[target_filter]` table (as in a scenario): the "ff+target"
        /// filter's tuning in every cell (default: the core's defaults).
        #[arg(long, value_name = "FILE")]
        target_filter: Option<PathBuf>,
    },
    /// Worst-case timing and memory per GA generation on the board: runs the timing firmware
    /// under QEMU with -icount and writes DIR/timing.json and DIR/timing.md. Builds nothing:
    /// build the firmware first (`cd hil-stubs && cargo build --release`; for `--profile m7`
    /// `cd hil-stubs && CARGO_TARGET_DIR=../target/m7 cargo build --release --features m7`).
    Timing {
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Board profile: `m4` (Cortex-M4F, STM32F4 at 168 MHz, 160×120) or `m7` (Cortex-M7,
        /// STM32H743 at 480 MHz, 320×240).
        #[arg(long, default_value = "m4", value_parser = ["m4", "m7"])]
        profile: String,
    },
    /// Track a recorded stereo sequence (`evorec-seq/1` directory) or a ROS 2 bag (with
    /// `--rig`): writes DIR/trace.csv, DIR/estimate.tum (TUM format), DIR/summary.json, plots
    /// and `DIR/overlay_<N>.png`, and for a bag DIR/estimate.mcap (the poses as
    /// geometry_msgs/PoseStamped, status and fitness). Nothing is written unless the whole
    /// sequence was tracked.
    Track {
        /// Sequence directory (holds sequence.toml), or a ROS 2 bag (directory or .mcap file).
        seq: PathBuf,
        /// The rig file (`evorec-rig/1`) of a bag: its topics, frames and block.
        #[arg(long)]
        rig: Option<PathBuf>,
        /// Largest stamp difference of a bag's stereo pair in ms (default: a quarter of the
        /// frame period).
        #[arg(long, requires = "rig")]
        pair_tolerance_ms: Option<f64>,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Plain 1-step GA (no motion feedforward; the same as `--method ga`).
        #[arg(long, conflicts_with = "method")]
        no_ff: bool,
        /// `ga` (plain 1-step GA), `ff` (+ the arm's motion fed forward) or `ff+target` (+ the
        /// target's own motion, estimated from past estimates, fed forward too; the default: a
        /// recorded target may move, and on a still one nothing significant is fed forward).
        #[arg(long, value_enum, default_value_t = Method::FfTarget)]
        method: Method,
        /// Seed of the GA.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// GA population size (16 up to the compiled capacity, 64: room for the acquisition's seeded and idle individuals).
        #[arg(long)]
        population: Option<usize>,
        /// Sample points per row of the surface-strips model (5, 6, 7 or 8; default the core's
        /// `DEFAULT_GRID`).
        #[arg(long)]
        points_per_row: Option<usize>,
        /// Track only the first N frames.
        #[arg(long)]
        frames: Option<usize>,
        /// Pixels the tracker reads: `rgb888` (the PNG's own colour) or `rgb565` (truncated
        /// first, as a board's camera sensor delivers them: what the firmware would see).
        #[arg(long, value_enum, default_value_t = TrackPixels::Rgb888)]
        pixels: TrackPixels,
        /// Frame indices (frames.csv `index`) to draw the model at its estimate over, e.g. 0,90.
        #[arg(long, value_delimiter = ',')]
        overlay: Vec<u64>,
        /// A TOML file holding a `[target_filter]` table (as in a scenario): the tuning of the
        /// target-velocity filter that `ff+target` feeds forward (default: the core's).
        #[arg(long, value_name = "FILE")]
        target_filter: Option<PathBuf>,
    },
    /// Write a ROS 2 bag (MCAP storage: a bag directory or one .mcap file) as a recorded sequence
    /// (`evorec-seq/1`): images paired by stamp, joint states by name, transforms from tf, the URDF
    /// from the bag or the rig file. Nothing is written at OUT unless the whole bag was read.
    Import {
        /// The bag.
        bag: PathBuf,
        /// The rig file (`evorec-rig/1`): topics, frames and the block.
        #[arg(long)]
        rig: PathBuf,
        /// Sequence directory to create (must not exist or be empty).
        #[arg(long)]
        out: PathBuf,
        /// Largest stamp difference of a stereo pair in ms (default: a quarter of the frame
        /// period).
        #[arg(long)]
        pair_tolerance_ms: Option<f64>,
    },
    /// Write a simulator scenario as a recorded sequence (`evorec-seq/1`): the PA-10's URDF,
    /// camera_info YAMLs, PNGs, joints at 1 kHz, ground truth, sequence.toml with the initial
    /// pose; `evorec track SEQ` then reads it back.
    Export {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Sequence directory to create (must not exist or be empty).
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
        /// Points per sample row of the tracker (5, 6, 7 or 8).
        #[arg(long, default_value_t = evorec_sim::acquire::DEFAULT_POINTS)]
        points: usize,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
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

/// The grids of `evorec paper`.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
enum Grid {
    /// The paper's grid (motions A/B × ω × GA, FF, FF + target).
    Paper,
    /// The block's own motion (conveyor speeds, ω_o) under motion A at 0.5 rad/s.
    Target,
    /// Both.
    Both,
}

fn load(path: &Path) -> Result<Scenario> {
    Ok(Scenario::load(path)?)
}

/// [`load`] with the method overridden if `method` is given.
fn load_with(path: &Path, method: Option<Method>) -> Result<Scenario> {
    let mut s = load(path)?;
    if let Some(m) = method {
        s.method = m;
    }
    Ok(s)
}

fn report_handover(h: Option<&experiment::HandoverSummary>) {
    let Some(h) = h else { return };
    println!(
        "hand-over {:.3} s after capture ({} tracked frames): RMS position at capture {:.2} mm, held {:.2} mm, \
         predicted {:.2} mm (ratio {:.2}); RMS ε at capture {:.4}, held {:.4}, predicted {:.4} (ratio {:.2}); \
         target velocity trusted in {:.0} %",
        h.delay_s,
        h.frames,
        h.at_capture.rms_position_mm,
        h.held.rms_position_mm,
        h.predicted.rms_position_mm,
        h.position_ratio,
        h.at_capture.rms_eps_norm,
        h.held.rms_eps_norm,
        h.predicted.rms_eps_norm,
        h.eps_ratio,
        h.trusted_fraction * 100.0
    );
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

/// Runs the command; on failure prints ONE line `error: …` (the error chain, de-duplicated: see
/// [`error_line`]) to stderr and exits with status 1. No backtrace is printed: `anyhow`'s
/// `Debug` output (which `fn main() -> Result` would use) is not involved.
fn main() -> ExitCode {
    let cli = Cli::parse();
    evorec_sim::logging::init(evorec_sim::logging::level(cli.verbose, cli.quiet));
    match execute(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", error_line(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes joined by `": "`, leaving out every cause whose text the line
/// already holds (a wrapper such as `ScenarioError::InFile` prints its source in its own message).
fn error_line(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

fn track_sequence(dir: &Path, out: &Path, opts: &track::TrackOptions) -> Result<()> {
    let seq = Sequence::load(dir)?;
    let t0 = Instant::now();
    let output = track::run(&seq, opts)?;
    let ev = track::output::evaluate(&seq, &output);
    track::output::write_all(&seq, &output, &ev, out)?;
    print_track(&ev.summary, t0, out);
    Ok(())
}

/// `evorec track BAG --rig RIG`: the bag read (first pass), tracked while its images stream
/// (second pass); the outputs of a sequence plus `estimate.mcap`.
fn track_bag(
    path: &Path,
    rig: &Path,
    out: &Path,
    opts: &track::TrackOptions,
    bag_opts: &bag::BagOptions,
) -> Result<()> {
    let t0 = Instant::now();
    let rig = bag::Rig::load(rig)?;
    let b = bag::load(path, &rig, bag_opts, path)?;
    b.report.log();
    let ev = bag::track::track_and_write(&b, opts, out)?;
    println!("{}", b.report.describe());
    print_track(&ev.summary, t0, out);
    Ok(())
}

fn import_bag(path: &Path, rig: &Path, out: &Path, bag_opts: &bag::BagOptions, progress: bool) -> Result<()> {
    let t0 = Instant::now();
    let rig = bag::Rig::load(rig)?;
    let b = bag::load(path, &rig, bag_opts, out)?;
    b.report.log();
    let bar = progress.then(|| evorec_sim::logging::progress_bar(b.pairs.len() as u64));
    bag::import::import(&b, out, bar.as_ref())?;
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let secs = t0.elapsed().as_secs_f64();
    println!("{}", b.report.describe());
    println!(
        "imported {} frame pairs in {secs:.1} s ({:.0} pairs/s); wrote {}",
        b.pairs.len(),
        b.pairs.len() as f64 / secs.max(1e-9),
        out.display()
    );
    Ok(())
}

fn print_track(s: &track::output::TrackSummary, t0: Instant, out: &Path) {
    print!(
        "{} frames in {:.1} s ({:.0} frames/s): F_mean {:.4}",
        s.frames,
        t0.elapsed().as_secs_f64(),
        s.frames_per_s,
        s.f_mean
    );
    if let Some(a) = &s.all {
        print!(
            ", RMS x/y/z {:.2}/{:.2}/{:.2} mm, RMS rotation {:.2} deg (max {:.2})",
            a.rms_x_mm, a.rms_y_mm, a.rms_z_mm, a.rms_rot_deg, a.max_rot_deg
        );
        match s.within_from_frame {
            Some(f) => print!(", within 10 mm/5 deg from frame {f}"),
            None => print!(", never stays within 10 mm/5 deg"),
        }
    }
    println!("\nwrote {}", out.display());
}

fn report_servo(s: &closed_loop::ServoSummary) {
    println!(
        "servo (t >= {:.1} s): RMS error {:.2} mm / {:.3} deg, spread {:.2} mm / {:.3} deg, {} frames not tracking, \
         max camera speed {:.3} m/s: {}",
        s.steady_from_s,
        s.rms_err_mm,
        s.rms_err_deg,
        s.spread_mm,
        s.spread_deg,
        s.frames_not_tracking,
        s.max_camera_speed_m_s,
        s.outcome.as_str()
    );
}

/// With fault injection: prints what the link did and writes `link.json`.
fn report_link(link: &hil::LinkReport, out: &Path, faults: bool) -> Result<()> {
    if faults {
        println!("{}", link.describe());
        std::fs::write(out.join("link.json"), link.to_json())
            .with_context(|| format!("write {}", out.join("link.json").display()))?;
    }
    Ok(())
}

/// `evorec hil` on a scenario with `[servo]`: the closed loop on the firmware's estimates
/// (its trace and summary as `evorec run` writes them), then the host's run of the same loop,
/// compared frame by frame (`comparison.json`). On a clean link a difference is an error.
fn hil_servo(
    s: &Scenario,
    scenario: &Path,
    out: &Path,
    firmware: &Path,
    faults: Option<evorec_firmware::faults::FaultConfig>,
    t0: Instant,
) -> Result<()> {
    let opts = closed_loop::LoopOptions::for_scenario(s);
    let options = hil::options_with_faults(faults);
    let (output, link) = hil::run_closed_loop(s, &opts, firmware, &out.join("qemu"), &options, || {})?;
    report_link(&link, out, faults.is_some())?;
    let title = format!("{} ({}, closed loop, firmware on QEMU)", scenario.display(), s.method.as_str());
    closed_loop::write_outputs(&output, out, &title)?;
    report(&output.run.summary.accuracy, t0);
    report_servo(&output.servo_summary);
    let t1 = Instant::now();
    let host = closed_loop::run(s, &opts, || {})?;
    let comparison = closed_loop::compare(&output, &host);
    println!("{} (host run {:.1} s)", comparison.describe(), t1.elapsed().as_secs_f64());
    io::write_json(&out.join("comparison.json"), &comparison)?;
    println!("wrote {}", out.display());
    if faults.is_none() && !comparison.identical() {
        anyhow::bail!("the firmware's closed loop differs from the host's on a clean link (see comparison.json)");
    }
    Ok(())
}

fn execute(cli: Cli) -> Result<()> {
    let quiet = cli.quiet;
    match cli.command {
        Command::Run { scenario, out, method, seed } => {
            let mut s = load_with(&scenario, method)?;
            s.seed = seed.unwrap_or(s.seed);
            io::create_out_dir(&out)?;
            let t0 = Instant::now();
            if s.servo.is_some() {
                let output = closed_loop::run(&s, &closed_loop::LoopOptions::for_scenario(&s), || {})?;
                let title = format!("{} ({}, closed loop)", scenario.display(), s.method.as_str());
                closed_loop::write_outputs(&output, &out, &title)?;
                report(&output.run.summary.accuracy, t0);
                report_servo(&output.servo_summary);
                println!("wrote {}", out.display());
                return Ok(());
            }
            let output = experiment::run(&s, || {})?;
            let title = format!("{} ({})", scenario.display(), s.method.as_str());
            experiment::write_outputs(&output, &out, &title)?;
            report(&output.summary.accuracy, t0);
            report_handover(output.summary.handover.as_ref());
            println!("wrote {}", out.display());
        }
        Command::Paper { out, base, grid, method } => {
            let base = match base {
                Some(p) => load(&p)?,
                None => Scenario::new(1, paper::DURATION_S, Method::Ff),
            };
            io::create_out_dir(&out)?;
            let t0 = Instant::now();
            let wanted = |m: Method| method.is_none_or(|w| w == m);
            let mut runs = 0;
            if grid != Grid::Target {
                let cells: Vec<_> = paper::grid().into_iter().filter(|c| wanted(c.method)).collect();
                let results = paper::run_grid_of(&cells, &base, &out, !quiet)?;
                println!("{}", paper::markdown(&results));
                runs += results.len();
            }
            if grid != Grid::Paper {
                let cells: Vec<_> = target_grid::grid().into_iter().filter(|c| wanted(c.method)).collect();
                let results = target_grid::run_grid(&cells, &base, &out, !quiet)?;
                println!("{}", target_grid::markdown(&results));
                runs += results.len();
            }
            println!("{runs} runs in {:.1} s; wrote {}", t0.elapsed().as_secs_f64(), out.display());
        }
        Command::Hil { scenario, out, firmware, method, faults, fault_seed } => {
            let s = load_with(&scenario, method)?;
            io::create_out_dir(&out)?;
            let firmware = firmware.unwrap_or_else(evorec_firmware::host::default_firmware_path);
            let t0 = Instant::now();
            let faults = match faults {
                Some(r) if !(0.0..=1.0).contains(&r) => {
                    anyhow::bail!("--faults {r}: a fraction in [0, 1] (0.01 = 1 %)")
                }
                Some(r) => Some(evorec_firmware::faults::FaultConfig::from_rate(r, fault_seed)),
                None => None,
            };
            if s.servo.is_some() {
                return hil_servo(&s, &scenario, &out, &firmware, faults, t0);
            }
            let (output, link) = hil::run_with_faults(&s, &firmware, &out.join("qemu"), faults, || {})?;
            report_link(&link, &out, faults.is_some())?;
            let title = format!("{} ({}, firmware on QEMU)", scenario.display(), s.method.as_str());
            experiment::write_outputs(&output, &out, &title)?;
            report(&output.summary.accuracy, t0);
            report_handover(output.summary.handover.as_ref());
            println!("wrote {}", out.display());
        }
        Command::Track {
            seq,
            rig,
            pair_tolerance_ms,
            out,
            no_ff,
            method,
            seed,
            population,
            points_per_row,
            frames,
            pixels,
            overlay,
            target_filter,
        } => {
            let target_filter = match target_filter {
                Some(path) => evorec_sim::scenario::TargetFilterSection::load(&path)?,
                None => evorec_sim::scenario::TargetFilterSection::default(),
            };
            let opts = track::TrackOptions {
                feedforward: if no_ff { Method::Ga } else { method }.into(),
                seed,
                population,
                points_per_row,
                frames,
                overlay: overlay.into_iter().collect(),
                progress: !quiet,
                pixels: pixels.into(),
                target_filter: target_filter.0,
            };
            let bag_opts = bag::BagOptions { pair_tolerance_ms };
            match rig {
                Some(rig) => track_bag(&seq, &rig, &out, &opts, &bag_opts)?,
                None if bag::scan::is_bag(&seq) => {
                    anyhow::bail!("{}: is a ROS 2 bag: give its rig file with --rig RIG.toml", seq.display())
                }
                None => track_sequence(&seq, &out, &opts)?,
            }
        }
        Command::Import { bag: path, rig, out, pair_tolerance_ms } => {
            import_bag(&path, &rig, &out, &bag::BagOptions { pair_tolerance_ms }, !quiet)?;
        }
        Command::Export { scenario, out } => {
            let s = load(&scenario)?;
            let name = scenario.file_stem().map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            let bar = (!quiet).then(|| evorec_sim::logging::progress_bar(u64::from(evorec_sim::sim::frame_total(&s))));
            let stats = export::export(&s, &name, &out, bar.clone())?;
            if let Some(b) = bar {
                b.finish_and_clear();
            }
            println!("wrote {} ({} frames, {} joint samples)", out.display(), stats.frames, stats.joint_samples);
        }
        Command::Servo { out, duration, gains, delays, speeds, seed, target_filter } => {
            anyhow::ensure!(duration > 0.0 && duration <= 3600.0, "--duration: must be in (0, 3600], got {duration}");
            anyhow::ensure!(gains.iter().all(|g| *g > 0.0 && *g <= 50.0), "--gains: each must be in (0, 50]");
            anyhow::ensure!(delays.iter().all(|d| *d <= 10), "--delays: each must be in 0..=10");
            anyhow::ensure!(speeds.iter().all(|v| (0.0..=0.3).contains(v)), "--speeds: each must be in [0, 0.3]");
            let mut g =
                servo::GridSettings { duration_s: duration, gains, delays, seed, ..servo::GridSettings::default() };
            g.targets = speeds.iter().map(|&speed_m_s| servo::TargetCase::Conveyor { speed_m_s }).collect();
            g.targets.push(servo::TargetCase::Rotating { omega_rad_s: 0.5 });
            if let Some(path) = target_filter {
                g.target_filter = evorec_sim::scenario::TargetFilterSection::load(&path)?;
            }
            let t0 = Instant::now();
            let results = servo::run_grid(&g, &out, !quiet)?;
            println!("{}", servo::markdown(&results).split("\n\n").next().unwrap_or_default());
            println!("{} runs in {:.1} s; wrote {}", results.len(), t0.elapsed().as_secs_f64(), out.display());
        }
        Command::Acquire { trials, first_seed, points, out } => {
            let t0 = Instant::now();
            let report = evorec_sim::acquire::run(trials, first_seed, points, &out, !quiet)?;
            println!("{}", evorec_sim::acquire::markdown(&report));
            println!("{} trials per case in {:.1} s; wrote {}", trials, t0.elapsed().as_secs_f64(), out.display());
        }
        Command::Timing { out, profile } => {
            let board = evorec_sim::timing::Board::by_name(&profile)
                .ok_or_else(|| anyhow::anyhow!("--profile {profile}: expected m4 or m7"))?;
            io::create_out_dir(&out)?;
            evorec_sim::timing::run(&out, board)?;
        }
        Command::Render { scenario, frame: n, out } => {
            let s = load(&scenario)?;
            io::create_out_dir(&out)?;
            let files = frame::render_frame(&s, n, &out).context("rendering")?;
            for f in files {
                println!("wrote {}", f.display());
            }
        }
    }
    Ok(())
}
