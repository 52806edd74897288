//! `evorec run`: one scenario on the host, and the run's report (shared with `evorec hil`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use evorec_sim::experiments::closed_loop;
use evorec_sim::experiments::experiment::{self, RunOutput};

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

/// Writes an open-loop run's files and prints its accuracy and hand-over.
pub(super) fn write_open_loop(output: &RunOutput, out: &Path, title: &str, t0: Instant) -> Result<()> {
    experiment::write_outputs(output, out, title)?;
    report(&output.summary.accuracy, t0);
    report_handover(output.summary.handover.as_ref());
    println!("wrote {}", out.display());
    Ok(())
}

/// Writes a closed-loop run's files and prints its accuracy and servo summary.
pub(super) fn write_closed_loop(
    output: &closed_loop::ClosedLoopOutput,
    out: &Path,
    title: &str,
    t0: Instant,
) -> Result<()> {
    closed_loop::write_outputs(output, out, title)?;
    experiment::write_estimate(&output.run, out)?;
    report(&output.run.summary.accuracy, t0);
    report_servo(&output.servo_summary);
    Ok(())
}

fn report(a: &experiment::Accuracy, t0: Instant) {
    println!(
        "{} frames in {:.1} s: F_mean {:.4}, RMS x/y/z {:.2}/{:.2}/{:.2} mm, RMS e1/e2/e3 {:.4}/{:.4}/{:.4}",
        a.rms.frames,
        t0.elapsed().as_secs_f64(),
        a.f_mean,
        a.rms.rms_x_mm,
        a.rms.rms_y_mm,
        a.rms.rms_z_mm,
        a.rms.rms_e1,
        a.rms.rms_e2,
        a.rms.rms_e3
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
        h.at_capture.position_mm(),
        h.held.position_mm(),
        h.predicted.position_mm(),
        h.position_ratio,
        h.at_capture.eps_norm(),
        h.held.eps_norm(),
        h.predicted.eps_norm(),
        h.eps_ratio,
        h.trusted_fraction * 100.0
    );
}

fn report_servo(s: &closed_loop::ServoSummary) {
    println!(
        "servo (t >= {:.1} s): RMS error {:.2} mm / {:.3} deg, spread {:.2} mm / {:.3} deg, {} frames not held, \
         max camera speed {:.3} m/s: {}",
        s.steady_from_s,
        s.rms_err_mm,
        s.rms_err_deg,
        s.spread_mm,
        s.spread_deg,
        s.frames_not_held,
        s.max_camera_speed_m_s,
        s.outcome.as_str()
    );
}
