//! `evorec hil`: one scenario with the tracker in the firmware under QEMU.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use evorec_firmware::faults::FaultConfig;
use evorec_sim::experiments::closed_loop;
use evorec_sim::firmware::hil;
use evorec_sim::output::io;
use evorec_sim::sim::scenario::Scenario;

use super::run::{write_closed_loop, write_open_loop};
use super::{OutArgs, Overrides};

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

/// With fault injection: prints what the link did and writes `link.json`.
fn report_link(link: &hil::LinkReport, out: &Path, faults: bool) -> Result<()> {
    if faults {
        println!("{}", link.describe());
        io::write_bytes(&out.join("link.json"), link.to_json().as_bytes())?;
    }
    Ok(())
}
