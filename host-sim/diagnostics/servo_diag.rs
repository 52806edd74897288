//! Per-axis tracker error of one closed-loop servo cell (conveyor, ff+target), frame by frame.
//! `cargo run --release -p evorec-sim --example servo_diag -- SEED GAIN [SPEED] [FRAMES]`
use evorec_core::tuning::Feedforward;
use evorec_sim::experiments::closed_loop;
use evorec_sim::experiments::servo::{Cell, GridSettings, TargetCase, scenario_of};

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let seed: u64 = a.get(1).map_or(Ok(1), |s| s.parse())?;
    let gain: f64 = a.get(2).map_or(Ok(2.0), |s| s.parse())?;
    let speed: f64 = a.get(3).map_or(Ok(0.1), |s| s.parse())?;
    let frames: usize = a.get(4).map_or(Ok(60), |s| s.parse())?;
    let g = GridSettings { seed, ..GridSettings::default() };
    let cell = Cell {
        target: TargetCase::Conveyor { speed_m_s: speed },
        method: Feedforward::OnWithTarget,
        gain,
        delay_frames: 1,
    };
    let (s, opts) = scenario_of(&g, &cell);
    let out = closed_loop::run(&s, &opts, || {})?;
    println!("t dx dy dz(mm) de1 de2 de3 tz F status");
    for r in out.run.rows.iter().take(frames) {
        let (e, t) = (r.estimate.0, r.truth.0);
        println!(
            "{:.3} {:7.2} {:7.2} {:7.2} {:8.4} {:8.4} {:8.4} {:.3} {:.3} {:?}",
            r.t,
            1e3 * (e[0] - t[0]),
            1e3 * (e[1] - t[1]),
            1e3 * (e[2] - t[2]),
            e[3] - t[3],
            e[4] - t[4],
            e[5] - t[5],
            t[2],
            r.fitness,
            r.status
        );
    }
    println!("{:?}", out.servo_summary.outcome);
    Ok(())
}
