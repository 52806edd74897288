//! `evorec run` and `evorec hil`: one scenario, on the host or with the firmware under QEMU.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use evorec_firmware::faults::FaultConfig;
use evorec_sim::experiments::closed_loop;
use evorec_sim::experiments::experiment::{self, RunOutput};
use evorec_sim::firmware::hil;
use evorec_sim::output::io;
use evorec_sim::sim::scenario::Scenario;

use super::{OutArgs, Overrides};

#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// Scenario file (TOML).
    scenario: PathBuf,
    #[command(flatten)]
    out: OutArgs,
    #[command(flatten)]
    overrides: Overrides,
}

impl RunArgs {
    pub fn run(self) -> Result<()> {
        let s = self.overrides.load(&self.scenario)?;
        let out = self.out.create()?;
        let t0 = Instant::now();
        if s.servo.is_some() {
            let output = closed_loop::run(&s, &closed_loop::LoopOptions::for_scenario(&s), || {})?;
            let title = format!("{} ({}, closed loop)", self.scenario.display(), s.method().name());
            write_closed_loop(&output, out, &title, t0)?;
            println!("wrote {}", out.display());
            return Ok(());
        }
        let output = experiment::run(&s, || {})?;
        let title = format!("{} ({})", self.scenario.display(), s.method().name());
        write_open_loop(&output, out, &title, t0)
    }
}

#[derive(clap::Args, Debug)]
#[command(mut_arg("out", |a| a.help("Output directory (also holds QEMU's FIFOs and log)")))]
pub struct HilArgs {
    /// Scenario file (TOML).
    scenario: PathBuf,
    #[command(flatten)]
    out: OutArgs,
    /// Firmware ELF (default: $EVOREC_FIRMWARE_ELF, else the workspace's
    /// target/thumbv7em-none-eabihf/release/evorec-firmware).
    #[arg(long)]
    firmware: Option<PathBuf>,
    #[command(flatten)]
    overrides: Overrides,
    /// Link fault injection: the fraction of messages (both directions) that are bit-flipped,
    /// dropped, duplicated, truncated or delayed, e.g. 0.01 for 1 %. Writes `link.json`.
    #[arg(long)]
    faults: Option<f64>,
    /// Seed of the fault injection.
    #[arg(long, default_value_t = 1)]
    fault_seed: u64,
}

impl HilArgs {
    pub fn run(self) -> Result<()> {
        let s = self.overrides.load(&self.scenario)?;
        let out = self.out.create()?;
        let firmware = self.firmware.clone().unwrap_or_else(evorec_firmware::host::default_firmware_path);
        let t0 = Instant::now();
        let faults = self.fault_config()?;
        if s.servo.is_some() {
            return hil_servo(&s, &self.scenario, out, &firmware, faults, t0);
        }
        let (output, link) = hil::run_with_faults(&s, &firmware, &out.join("qemu"), faults, || {})?;
        report_link(&link, out, faults.is_some())?;
        let title = format!("{} ({}, firmware on QEMU)", self.scenario.display(), s.method().name());
        write_open_loop(&output, out, &title, t0)
    }

    /// `--faults` and `--fault-seed`.
    fn fault_config(&self) -> Result<Option<FaultConfig>> {
        match self.faults {
            Some(r) if !(0.0..=1.0).contains(&r) => anyhow::bail!("--faults {r}: a fraction in [0, 1] (0.01 = 1 %)"),
            Some(r) => Ok(Some(FaultConfig::from_rate(r, self.fault_seed))),
            None => Ok(None),
        }
    }
}

/// `evorec hil` on a scenario with `[servo]`: the closed loop on the firmware's estimates
/// (its trace and summary as `evorec run` writes them), then the host's run of the same loop,
/// compared frame by frame (`comparison.json`). On a clean link a difference is an error.
fn hil_servo(
    s: &Scenario,
    scenario: &Path,
    out: &Path,
    firmware: &Path,
    faults: Option<FaultConfig>,
    t0: Instant,
) -> Result<()> {
    let opts = closed_loop::LoopOptions::for_scenario(s);
    let options = hil::options_with_faults(faults);
    let (output, link) = hil::run_closed_loop(s, &opts, firmware, &out.join("qemu"), &options, || {})?;
    report_link(&link, out, faults.is_some())?;
    let title = format!("{} ({}, closed loop, firmware on QEMU)", scenario.display(), s.method().name());
    write_closed_loop(&output, out, &title, t0)?;
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

/// Writes an open-loop run's files and prints its accuracy and hand-over.
fn write_open_loop(output: &RunOutput, out: &Path, title: &str, t0: Instant) -> Result<()> {
    experiment::write_outputs(output, out, title)?;
    report(&output.summary.accuracy, t0);
    report_handover(output.summary.handover.as_ref());
    println!("wrote {}", out.display());
    Ok(())
}

/// Writes a closed-loop run's files and prints its accuracy and servo summary.
fn write_closed_loop(output: &closed_loop::ClosedLoopOutput, out: &Path, title: &str, t0: Instant) -> Result<()> {
    closed_loop::write_outputs(output, out, title)?;
    experiment::write_estimate(&output.run, out)?;
    report(&output.run.summary.accuracy, t0);
    report_servo(&output.servo_summary);
    Ok(())
}

/// With fault injection: prints what the link did and writes `link.json`.
fn report_link(link: &hil::LinkReport, out: &Path, faults: bool) -> Result<()> {
    if faults {
        println!("{}", link.describe());
        io::write_bytes(&out.join("link.json"), link.to_json().as_bytes())?;
    }
    Ok(())
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
