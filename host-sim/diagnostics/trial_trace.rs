//! One run of an acquisition trial as `evorec acquire` runs it (`experiment::run_with_rows`, the
//! trial's scenario and the core's default tuning), frame by frame: status, whether the block is
//! hidden, the fitness of both cameras and the estimate's error (position, orientation modulo the
//! colour symmetry, and per axis). Finds which frames of a trial `acquire.md` counts as
//! `tracking` but wrong.
//!
//! `cargo run --release -p evorec-sim --example trial_trace -- SEED static|a acquire|recovery [LIGHT.toml]`:
//! SEED the trial (`evorec acquire --first-seed SEED --trials 1` runs the same), `a` the motion-A
//! case, `recovery` the run that starts at the true pose and hides the block for a second, LIGHT a
//! `[render]` file as `evorec acquire --light` takes.
use evorec_sim::experiments::acquire::{Case, pose_error, scenario};
use evorec_sim::experiments::experiment;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: trial_trace SEED static|a acquire|recovery [LIGHT.toml]";
    let seed: u64 = args.get(1).and_then(|s| s.parse().ok()).ok_or_else(|| anyhow::anyhow!(usage))?;
    let case = if args.get(2).map(String::as_str) == Some("a") { Case::MotionA } else { Case::Static };
    let recovery = args.get(3).map(String::as_str) == Some("recovery");
    let mut s = scenario(seed, case, recovery);
    s.tracker.0 = evorec_core::tuning::Tuning::DEFAULT;
    if let Some(path) = args.get(4) {
        s.render = evorec_sim::sim::scenario::load_light(std::path::Path::new(path), s.frame_period_s)?;
    }
    let out = experiment::run_with_rows::<8>(&s, || {})?;
    for (k, r) in out.rows.iter().enumerate() {
        let (mm, deg) = pose_error(&r.estimate, &r.truth);
        let axes: Vec<String> = (0..3).map(|i| format!("{:+.1}", 1e3 * (r.estimate.0[i] - r.truth.0[i]))).collect();
        println!(
            "{k:3} {:9} hidden {} F {:.3} (L {:.3} R {:.3}) err {:7.1} mm {:6.1} deg, x y z {} mm",
            r.status.as_str(),
            u8::from(r.hidden),
            r.fitness,
            r.camera_fitness[0],
            r.camera_fitness[1],
            mm,
            deg,
            axes.join(" ")
        );
    }
    Ok(())
}
