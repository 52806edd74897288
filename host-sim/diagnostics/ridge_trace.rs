//! One acquisition trial as `evorec acquire` runs it, frame by frame with the tracker's own view
//! of it: status, both cameras' fitness of the elite, the colour model's expected and confirming
//! fitness (the status's scales), the learnt silhouette shift, the true pose's fitness, and the
//! estimate's error. Every `EVERY` frames (default 20) it also prints the lower camera's fitness
//! along the straight path from the estimate to the true pose (eleven poses: position linear,
//! orientation slerped to the truth's nearest colour-symmetric twin), which shows whether a wrong
//! estimate sits in a separate peak or on a ridge that rises towards the truth; the same path
//! moving only the orientation and only the position shows whether one part alone climbs, and
//! both poses are printed as ψ (right camera frame) for a closer look at the geometry.
//!
//! `cargo run --release -p evorec-sim --example ridge_trace -- SEED CASE [LIGHT.toml|-] [EVERY]`
//! with CASE `static` or `a` (the trial's acquisition run, from an unknown pose) or `static+occluded`
//! or `a+occluded` (its recovery run: from the known start pose, through the 1 s occlusion);
//! `-`: the flat default light, to give EVERY without a light file.
use evorec_core::StereoFrame;
use evorec_core::board::{CameraController, Error as _, ErrorKind};
use evorec_core::image::{Image, Rgb565};
use evorec_core::pose::Psi;
use evorec_sim::experiments::acquire::{Case, pose_error, scenario};
use evorec_sim::experiments::experiment::{Population, SimTracker, isometry_of, scenario_tracker};
use evorec_sim::experiments::truth::{aligned_truth, colour_symmetries};
use evorec_sim::sim::board::{SimBoard, World, image_bytes};
use nalgebra::UnitQuaternion;

/// Which parts of the pose a path moves.
#[derive(Clone, Copy)]
enum Moves {
    Both,
    Turn,
    Position,
}

/// The lower camera's fitness at each of eleven poses from `from` to the position of `to` and
/// the orientation `q1` (the twin of `to`'s nearest `from` under the block's colour
/// symmetries), moving what `moves` says and keeping the rest of `from`.
fn path(
    tracker: &SimTracker,
    (from, to, q1): (&Psi, &Psi, &UnitQuaternion<f32>),
    moves: Moves,
    frame: &StereoFrame<'_, Rgb565>,
) -> String {
    let q0 = from.quaternion_unchecked();
    let (t0, t1) = (from.translation(), to.translation());
    (0..=10)
        .map(|i| {
            let s = i as f32 / 10.0;
            let (st, sq) = match moves {
                Moves::Both => (s, s),
                Moves::Turn => (0.0, s),
                Moves::Position => (s, 0.0),
            };
            let t = t0 * (1.0 - st) + t1 * st;
            let p = Psi::from_parts(&t, &q0.try_slerp(q1, sq, 1e-6).unwrap_or(q0));
            tracker.fitness_of(&p, frame).map_or(f32::NAN, |f| f.left.score().min(f.right.score()))
        })
        .map(|f| format!("{f:.3}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: ridge_trace SEED static|a[+occluded] [LIGHT.toml|-] [EVERY]";
    let seed: u64 = args.get(1).and_then(|s| s.parse().ok()).ok_or_else(|| anyhow::anyhow!(usage))?;
    let (case, recovery) = match args.get(2).map(String::as_str) {
        Some("static") => (Case::Static, false),
        Some("a") => (Case::MotionA, false),
        Some("static+occluded") => (Case::Static, true),
        Some("a+occluded") => (Case::MotionA, true),
        _ => anyhow::bail!(usage),
    };
    let every: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(20).max(1);
    let mut s = scenario(seed, case, recovery);
    s.tracker.0 = evorec_core::tuning::Tuning::DEFAULT;
    if let Some(light) = args.get(3).filter(|l| l.as_str() != "-") {
        s.render = evorec_sim::sim::scenario::load_light(std::path::Path::new(light), s.frame_period_s)?;
    }
    let mut board = SimBoard::new(World::new(&s)?)?;
    // The recovery run starts from the known pose, as `evorec acquire` runs it.
    let population = if recovery { Population::Around(board.start_pose()) } else { Population::Uniform };
    let mut tracker = scenario_tracker::<8>(&s, population)?;
    let symmetries = colour_symmetries(&s.target.face_hues_deg.map(|h| h as f32));
    let n = image_bytes(&s);
    let (mut left, mut right) = (vec![0u8; n], vec![0u8; n]);
    let mut last: Option<u64> = None;
    for k in 0.. {
        let info = match board.next_frame(&mut left, &mut right) {
            Ok(info) => info,
            Err(e) if e.kind() == ErrorKind::EndOfStream => break,
            Err(e) => anyhow::bail!("simulated board: {e:?}"),
        };
        let joints = board.joint_sample().map_err(|e| anyhow::anyhow!("simulated board: {e:?}"))?;
        let dt_s = last.map_or(0.0, |t0| info.capture_time_us.saturating_sub(t0) as f32 * 1e-6);
        last = Some(info.capture_time_us);
        let frame = StereoFrame {
            left: Image::<_, Rgb565>::new_checked(&left[..], info.width, info.height)?,
            right: Image::<_, Rgb565>::new_checked(&right[..], info.width, info.height)?,
        };
        let e = tracker.step(&frame, &joints, dt_s).map_err(|e| anyhow::anyhow!("frame {k}: {e}"))?;
        board.publish(&info, &e).map_err(|e| anyhow::anyhow!("simulated board: {e:?}"))?;
        let truth = board.rows().last().map(|r| r.truth).ok_or_else(|| anyhow::anyhow!("no row"))?;
        let (mm, deg) = pose_error(&e.psi, &truth);
        let c = tracker.colours();
        let t = tracker.fitness_of(&truth, &frame)?;
        println!(
            "{k:3} {:9} F {:.3} (L {:.3} R {:.3}) expected {:.3} confirming {:.3} shift {:+.3} px truth {:.3} (L {:.3} R {:.3}) err {:6.1} mm {:5.1} deg z {:+.1} mm",
            e.status.as_str(),
            e.fitness,
            e.camera_fitness[0],
            e.camera_fitness[1],
            c.expected_fitness(),
            c.confirming_fitness(),
            tracker.edge_shift_px(),
            t.total,
            t.left.score(),
            t.right.score(),
            mm,
            deg,
            1e3 * (e.psi.0[2] - truth.0[2])
        );
        if k % every == 0 {
            println!("    psi estimate {:?} truth {:?}", e.psi.0, truth.0);
            let (twin, _) = aligned_truth(&isometry_of(&e.psi), &isometry_of(&truth), &symmetries);
            let q1: UnitQuaternion<f32> = twin.rotation.cast();
            for (what, moves) in
                [("estimate to truth", Moves::Both), ("turn only", Moves::Turn), ("position only", Moves::Position)]
            {
                let f = path(&tracker, (&e.psi, &truth, &q1), moves, &frame);
                println!("    {what:17}, lower camera: {f}");
            }
        }
    }
    Ok(())
}
