//! Does the view pin the estimate down to the stated accuracy? For each frame of a run, the lower
//! camera's fitness of the estimate and of twelve poses moved from it by the stated accuracy
//! (10 mm along the right camera's x, y and viewing ray, 5° about its x, y and z axes, both
//! signs), and whether the estimate is more than 10 mm or 5° from the truth.
//!
//! `cargo run --release -p evorec-sim --example view_probe -- acq SEED FRAMES` (an acquisition
//! trial's static view, the tracker run here) or `… -- SCENARIO TRACE.csv FIRST LAST STEP` (the
//! estimates of an `evorec run` trace). One line per frame: `wrong F_min(est) max F_min(probe)
//! which`.
mod frames;

use evorec_core::pose::Psi;
use evorec_sim::experiments::acquire::{Case, pose_error, scenario};
use evorec_sim::experiments::experiment::{SimTracker, tracker_config};
use evorec_sim::sim::board::World;
use evorec_sim::sim::scenario::Scenario;
use nalgebra::{Unit, UnitQuaternion, Vector3};

fn probes(e: &Psi) -> Vec<(String, Psi)> {
    let q = e.quaternion_unchecked();
    let t = e.translation();
    let ray = Unit::new_normalize(t);
    let mut out = Vec::new();
    for (name, dir) in [("x", Vector3::x()), ("y", Vector3::y()), ("ray", *ray.as_ref())] {
        for s in [-1.0f32, 1.0] {
            out.push((format!("{name}{s:+}"), Psi::from_parts(&(t + dir * (s * 0.010)), &q)));
        }
    }
    for (name, axis) in [("rx", Vector3::x_axis()), ("ry", Vector3::y_axis()), ("rz", Vector3::z_axis())] {
        for s in [-1.0f32, 1.0] {
            let turn = UnitQuaternion::from_axis_angle(&axis, s * 5f32.to_radians());
            out.push((format!("{name}{s:+}"), Psi::from_parts(&t, &(turn * q))));
        }
    }
    out
}

fn report(
    tracker: &SimTracker,
    frame: &evorec_core::tracker::StereoFrame<'_, evorec_core::image::Rgb565>,
    est: &Psi,
    truth: &Psi,
    k: usize,
) -> anyhow::Result<()> {
    // The scale the status confirms a pose against.
    let scale = tracker.colours().confirming_fitness();
    let lower = |p: &Psi| -> anyhow::Result<f32> {
        let f = tracker.fitness_of(p, frame).map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(f.left.score().min(f.right.score()) / scale)
    };
    let (mm, deg) = pose_error(est, truth);
    // The best probe of the shifts and of the turns.
    let (mut shift, mut turn) = ((f32::MIN, String::new()), (f32::MIN, String::new()));
    for (name, p) in probes(est) {
        let f = lower(&p)?;
        let best = if name.starts_with('r') && name.len() == 4 { &mut turn } else { &mut shift };
        if f > best.0 {
            *best = (f, name);
        }
    }
    println!(
        "{k} {} {:.3} shift {:.3} {} turn {:.3} {} {mm:.1} {deg:.1}",
        u8::from(mm > 10.0 || deg > 5.0),
        lower(est)?,
        shift.0,
        shift.1,
        turn.0,
        turn.1
    );
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("acq") {
        let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(14);
        let n: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(100);
        let s = scenario(seed, Case::Static, false);
        let mut world = World::new(&s)?;
        let mut tracker = SimTracker::new(tracker_config(&s)?).map_err(|e| anyhow::anyhow!("{e}"))?;
        let (w, h) = (s.camera.width, s.camera.height);
        let px = 2 * usize::from(w) * usize::from(h);
        let (mut l, mut r) = (vec![0u8; px], vec![0u8; px]);
        for k in 0..n {
            world.advance_to(k as f64 * s.frame_period_s);
            let frame = frames::rgb565_frame(&mut world, &mut l, &mut r, w, h)?;
            let joints = world.arm().joint_sample();
            let dt = if k == 0 { 0.0 } else { s.frame_period_s as f32 };
            let est = tracker.step(&frame, &joints, dt).map_err(|e| anyhow::anyhow!("{e}"))?;
            if est.status.holds() {
                report(&tracker, &frame, &est.psi, &world.truth(), k)?;
            }
        }
        return Ok(());
    }
    let [_, path, trace, first, last, step] = &args[..] else {
        anyhow::bail!("usage: view_probe acq SEED FRAMES | view_probe SCENARIO TRACE.csv FIRST LAST STEP");
    };
    let (first, last, step): (usize, usize, usize) = (first.parse()?, last.parse()?, step.parse()?);
    let s = Scenario::load(path)?;
    let mut world = World::new(&s)?;
    let tracker = SimTracker::new(tracker_config(&s)?).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut rows = csv::Reader::from_path(trace)?;
    let head = rows.headers()?.clone();
    let col = |name: &str| head.iter().position(|h| h == name).ok_or_else(|| anyhow::anyhow!("no column {name}"));
    let cols: Vec<usize> = ["est_x_mm", "est_y_mm", "est_z_mm", "est_e1", "est_e2", "est_e3", "status"]
        .iter()
        .map(|c| col(c))
        .collect::<Result<_, _>>()?;
    let (w, h) = (s.camera.width, s.camera.height);
    let px = 2 * usize::from(w) * usize::from(h);
    let (mut l, mut r) = (vec![0u8; px], vec![0u8; px]);
    for (i, row) in rows.records().enumerate() {
        let row = row?;
        if i < first || (i - first) % step != 0 {
            continue;
        }
        if i > last {
            break;
        }
        if row.get(cols[6]).is_some_and(|st| st != "tracking" && st != "uncertain") {
            continue;
        }
        world.advance_to(i as f64 * s.frame_period_s);
        let frame = frames::rgb565_frame(&mut world, &mut l, &mut r, w, h)?;
        let v: Vec<f32> = cols[..6].iter().map(|&c| row[c].parse::<f32>()).collect::<Result<_, _>>()?;
        let e = Psi([v[0] * 1e-3, v[1] * 1e-3, v[2] * 1e-3, v[3], v[4], v[5]]);
        report(&tracker, &frame, &e, &world.truth(), i)?;
    }
    Ok(())
}
