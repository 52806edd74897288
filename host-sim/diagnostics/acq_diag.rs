//! Diagnostics of one acquisition trial: per frame, the seed's and the estimate's errors.
//! `cargo run --release -p evorec-sim --example acq_diag -- SEED [a] [FRAMES] [timing|-] [LIGHT.toml]`:
//! SEED the trial, `a` for the motion-A case, LIGHT a `[render]` file as `evorec acquire --light` takes.
//! With `BANDS=1` in the environment, every frame also prints the learnt hue bands, the expected
//! fitness, and the true pose's and the estimate's fitness counts through the table after the step;
//! with `AXES=1`, the estimate's error per axis and the learnt silhouette shift.
use evorec_core::acquire;
use evorec_sim::experiments::acquire::{Case, pose_error, scenario};
use evorec_sim::experiments::experiment::{SimTracker, tracker_config};
use evorec_sim::sim::board::World;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let seed: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(3);
    let case = if args.get(2).map(String::as_str) == Some("a") { Case::MotionA } else { Case::Static };
    let frames: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(60);
    let timing = args.get(4).map(String::as_str) == Some("timing");
    let mut s = scenario(seed, case, false);
    // The tuning `evorec acquire` gives every trial: the core's defaults.
    s.tracker.0 = evorec_core::tuning::Tuning::DEFAULT;
    // An optional fifth argument: a light file, as `evorec acquire --light` takes.
    if let Some(path) = args.get(5) {
        s.render = evorec_sim::sim::scenario::load_light(std::path::Path::new(path), s.frame_period_s)?;
    }
    let mut world = World::new(&s)?;
    let mut tracker = SimTracker::new(tracker_config(&s)?).map_err(|e| anyhow::anyhow!("{e}"))?;
    let cfg = *tracker.config();
    let half = tracker.model().half_size();
    let n = usize::from(s.camera.width) * usize::from(s.camera.height);
    let (mut l, mut r) = (vec![0u8; 2 * n], vec![0u8; 2 * n]);
    for k in 0..frames {
        let t = k as f64 * s.frame_period_s;
        world.advance_to(t);
        // RGB565, as the simulated board delivers (and `evorec acquire` runs on).
        let images = world.render();
        evorec_sim::sim::render::rgb565_into(&images.left, &mut l);
        evorec_sim::sim::render::rgb565_into(&images.right, &mut r);
        let (cw, ch) = (s.camera.width, s.camera.height);
        let frame = evorec_core::tracker::StereoFrame {
            left: evorec_core::image::Rgb565Image::new_checked(&l[..], cw, ch)?,
            right: evorec_core::image::Rgb565Image::new_checked(&r[..], cw, ch)?,
        };
        let truth = world.truth();
        let (bl, br) = tracker.blobs_of(&frame).map_err(|e| anyhow::anyhow!("{e}"))?;
        let hh = [half.x, half.y, half.z];
        let seed_pose = acquire::seed_pose(&cfg.rig, &hh, &bl, &br, cfg.tuning.acquire.min_face_hits);
        let raw_err = seed_pose.and_then(|sp| sp.psi()).map(|p| pose_error(&p, &truth));
        let seed_pose = seed_pose.map(|sp| {
            let m = acquire::Measured {
                rig: &cfg.rig,
                half: &hh,
                left: &bl,
                right: &br,
                stride: cfg.tuning.acquire.scan_stride,
                min_hits: cfg.tuning.acquire.min_face_hits,
            };
            acquire::refine(&m, &sp)
        });
        let seed_err = seed_pose.and_then(|sp| sp.psi()).map(|p| pose_error(&p, &truth));
        let f_truth = tracker.fitness_of(&truth, &frame).map_err(|e| anyhow::anyhow!("{e}"))?.total;
        let joints = world.arm().joint_sample();
        if timing {
            // Host time of one generation forced into each status on this frame (the state is
            // restored by cloning), min over repetitions.
            for status in evorec_core::status::Status::ALL {
                let mut best = f64::MAX;
                for _ in 0..200 {
                    let mut c = tracker.clone();
                    c.set_status(status);
                    let t0 = std::time::Instant::now();
                    let _ = std::hint::black_box(c.step(&frame, &joints, 0.033));
                    best = best.min(t0.elapsed().as_secs_f64());
                }
                println!("frame {k}: {:9} {:.1} us per generation (min of 200)", status.as_str(), best * 1e6);
            }
        }
        let dt = if k == 0 { 0.0 } else { s.frame_period_s as f32 };
        let est = tracker.step(&frame, &joints, dt).map_err(|e| anyhow::anyhow!("{e}"))?;
        let (mm, deg) = pose_error(&est.psi, &truth);
        if std::env::var_os("AXES").is_some() {
            let d: Vec<String> = (0..3).map(|i| format!("{:+.1}", 1e3 * (est.psi.0[i] - truth.0[i]))).collect();
            println!(
                "    error x y z (mm) {} at z {:.3} m; edge shift {:+.3} px",
                d.join(" "),
                truth.0[2],
                tracker.edge_shift_px()
            );
        }
        if std::env::var_os("BANDS").is_some() {
            let m = tracker.colours();
            let ft = tracker.fitness_of(&truth, &frame).map_err(|e| anyhow::anyhow!("{e}"))?;
            let fe = tracker.fitness_of(&est.psi, &frame).map_err(|e| anyhow::anyhow!("{e}"))?;
            let bands: Vec<String> =
                m.bands().iter().map(|b| format!("{}±{}", 2 * u16::from(b.centre), 2 * u16::from(b.half))).collect();
            println!(
                "    expected {:.3} bands {} | truth now {:.3} ({:?} {:?}) est now {:.3} ({:?} {:?})",
                m.expected_fitness(),
                bands.join(" "),
                ft.total,
                ft.left,
                ft.right,
                fe.total,
                fe.left,
                fe.right
            );
        }
        println!(
            "{k:3} F {:.3} (truth {:.3}) {:9} err {:6.1} mm {:6.1} deg | raw {:?} seed faces {:?} err {:?} | hits L {:?} R {:?}",
            est.fitness,
            f_truth,
            est.status.as_str(),
            mm,
            deg,
            raw_err.map(|(a, b)| (a.round(), b.round())),
            seed_pose.map(|s| (s.faces, s.free_axis)),
            seed_err.map(|(a, b)| (a.round(), b.round())),
            bl.count,
            br.count
        );
    }
    Ok(())
}
