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
        let err = ((0..3).map(|k| (e.0[k] - truth.0[k]).powi(2)).sum::<f32>()).sqrt() * 1e3;
        let ft = tracker.fitness_of(&truth, &frame).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        let fe = tracker.fitness_of(&e, &frame).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        if std::env::var("SCAN").is_ok() {
            let line: Vec<String> = (-25..=25)
                .step_by(5)
                .map(|mm| {
                    let q = e.scaled_along_ray(1.0 + mm as f32 * 1e-3 / e.0[2]);
                    let f = tracker.fitness_of(&q, &frame).map(|f| f.total).unwrap_or(0.0);
                    format!("{mm}:{f:.3}")
                })
                .collect();
            println!("  est along ray {}", line.join(" "));
            let c = rig.left_from_right.inverse().translation.vector;
            let line: Vec<String> = (-25..=25)
                .step_by(5)
                .map(|mm| {
                    let mut q = e;
                    let d = e.translation() - c;
                    let p = c + d * (1.0 + mm as f32 * 1e-3 / d.norm());
                    q.0[0] = p.x;
                    q.0[1] = p.y;
                    q.0[2] = p.z;
                    let f = tracker.fitness_of(&q, &frame).map(|f| f.total).unwrap_or(0.0);
                    format!("{mm}:{f:.3}")
                })
                .collect();
            println!("  est along left ray {}", line.join(" "));
            let line: Vec<String> = (0..=10)
                .map(|k| {
                    let a = k as f32 / 10.0;
                    let q = Psi(core::array::from_fn(|g| e.0[g] + a * (truth.0[g] - e.0[g])));
                    let f = tracker.fitness_of(&q, &frame).map(|f| f.total).unwrap_or(0.0);
                    format!("{f:.3}")
                })
                .collect();
            println!("  est to truth {}", line.join(" "));
            for (name, genes) in [("position only", 0..3), ("rotation only", 3..6)] {
                let line: Vec<String> = (0..=10)
                    .map(|k| {
                        let a = k as f32 / 10.0;
                        let q = Psi(core::array::from_fn(|g| {
                            if genes.contains(&g) { e.0[g] + a * (truth.0[g] - e.0[g]) } else { e.0[g] }
                        }));
                        let f = tracker.fitness_of(&q, &frame).map(|f| f.total).unwrap_or(0.0);
                        format!("{f:.3}")
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
