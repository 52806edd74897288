//! The fitness of the true pose and of a run's estimate, frame by frame: for frames FIRST..LAST of
//! a scenario, F (left, right) of the ground truth and of the estimate a run wrote in its
//! `trace.csv` (`est_*` columns), on the simulator's frames as the tracker sees them (the
//! default colour model). It tells a search that misses the fitness's optimum from a fitness
//! whose optimum is not the truth.
//!
//! `[SCAN=1] cargo run --release -p evorec-sim --example truth_fitness -- SCENARIO TRACE.csv FIRST LAST`
//! (`SCAN=1`: also F of the estimate moved along the right and the left camera's viewing ray, ±25 mm)
mod frames;

use evorec_core::pose::Psi;
use evorec_sim::experiments::experiment::{SimTracker, tracker_config};
use evorec_sim::sim::board::World;
use evorec_sim::sim::scenario::Scenario;
use nalgebra::Vector3;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let [_, path, trace, first, last] = &args[..] else {
        anyhow::bail!("usage: truth_fitness SCENARIO TRACE.csv FIRST LAST");
    };
    let (first, last): (usize, usize) = (first.parse()?, last.parse()?);
    let s = Scenario::load(path)?;
    let mut world = World::new(&s)?;
    let rig = *world.rig();
    let tracker = SimTracker::new(tracker_config(&s)?).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut rows = csv::Reader::from_path(trace)?;
    let head = rows.headers()?.clone();
    let col = |name: &str| head.iter().position(|h| h == name).ok_or_else(|| anyhow::anyhow!("no column {name}"));
    let est: Vec<usize> = ["est_x_mm", "est_y_mm", "est_z_mm", "est_e1", "est_e2", "est_e3"]
        .iter()
        .map(|c| col(c))
        .collect::<Result<_, _>>()?;
    let (w, h) = (s.camera.width, s.camera.height);
    let n = usize::from(w) * usize::from(h);
    let (mut l, mut r) = (vec![0u8; 2 * n], vec![0u8; 2 * n]);
    println!("frame t truth_FL truth_FR est_FL est_FR est_err_mm");
    for (i, row) in rows.records().enumerate() {
        let row = row?;
        if i < first {
            continue;
        }
        if i > last {
            break;
        }
        world.advance_to(i as f64 * s.frame_period_s);
        let frame = frames::rgb565_frame(&mut world, &mut l, &mut r, w, h)?;
        let truth = world.truth();
        let v: Vec<f32> = est.iter().map(|&c| row[c].parse::<f32>()).collect::<Result<_, _>>()?;
        let e = Psi([v[0] * 1e-3, v[1] * 1e-3, v[2] * 1e-3, v[3], v[4], v[5]]);
        let err = (e.translation() - truth.translation()).norm() * 1e3;
        let ft = tracker.fitness_of(&truth, &frame).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        let fe = tracker.fitness_of(&e, &frame).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        if std::env::var("SCAN").is_ok() {
            let f = |q: &Psi| tracker.fitness_of(q, &frame).map(|f| f.total).unwrap_or(0.0);
            // Along the ray from each camera's centre (in the right camera's frame) through the
            // estimate's centre, ±25 mm.
            let left_centre = rig.left_from_right.inverse().translation.vector;
            for (name, centre) in [("ray", Vector3::zeros()), ("left ray", left_centre)] {
                let line: Vec<String> = (-25..=25)
                    .step_by(5)
                    .map(|mm| {
                        let d = e.translation() - centre;
                        let p = centre + d * (1.0 + mm as f32 * 1e-3 / d.norm());
                        format!("{mm}:{:.3}", f(&Psi([p.x, p.y, p.z, e.0[3], e.0[4], e.0[5]])))
                    })
                    .collect();
                println!("  est along {name} {}", line.join(" "));
            }
            // Towards the truth in tenths, in every gene, in the position's or in the turn's.
            for (name, genes) in [("est to truth", 0..6), ("position only", 0..3), ("rotation only", 3..6)] {
                let line: Vec<String> = (0..=10)
                    .map(|k| {
                        let a = k as f32 / 10.0;
                        let q = Psi(core::array::from_fn(|g| {
                            if genes.contains(&g) { e.0[g] + a * (truth.0[g] - e.0[g]) } else { e.0[g] }
                        }));
                        format!("{:.3}", f(&q))
                    })
                    .collect();
                println!("  {name} {}", line.join(" "));
            }
        }
        println!(
            "{i} {:.3} {:.3} {:.3} {:.3} {:.3} {err:.1}",
            i as f64 * s.frame_period_s,
            ft.left.score(),
            ft.right.score(),
            fe.left.score(),
            fe.right.score()
        );
    }
    Ok(())
}
