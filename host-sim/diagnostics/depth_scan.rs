//! The fitness around the true pose of one simulated frame: the true pose moved along the right
//! camera's viewing ray (depth) and along the camera's x axis, from −20 to +20 mm in 0.5 mm steps.
//! Shows how sharply the fitness resolves each axis, and where its peak is.
//!
//! `cargo run --release -p evorec-sim --example depth_scan -- SCENARIO [TIME_S]`
use evorec_sim::experiments::experiment::{SimTracker, tracker_config};
use evorec_sim::sim::board::World;
use evorec_sim::sim::scenario::Scenario;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        anyhow::bail!("usage: depth_scan SCENARIO [TIME_S]");
    };
    let s = Scenario::load(path)?;
    let t: f64 = args.get(2).and_then(|v| v.parse().ok()).unwrap_or(0.0);
    let mut world = World::new(&s)?;
    let tracker = SimTracker::new(tracker_config(&s)?).map_err(|e| anyhow::anyhow!("{e}"))?;
    let n = usize::from(s.camera.width) * usize::from(s.camera.height);
    let (mut l, mut r) = (vec![0u8; n], vec![0u8; n]);
    world.advance_to(t);
    let frame = world.render().hue_frame(&mut l, &mut r)?;
    let truth = world.truth();
    println!("truth {:?}", truth.0);
    for k in -40..=40 {
        let d = k as f32 * 0.0005;
        let p = truth.scaled_along_ray(1.0 + d / truth.0[2]);
        let fz = tracker.fitness_of(&p, &frame).map_err(|e| anyhow::anyhow!("{e}"))?.total;
        let mut q = truth;
        q.0[0] += d;
        let fx = tracker.fitness_of(&q, &frame).map_err(|e| anyhow::anyhow!("{e}"))?.total;
        println!("{:6.1} mm  depth F {:.4}  x F {:.4}", d * 1000.0, fz, fx);
    }
    Ok(())
}
