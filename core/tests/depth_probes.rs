//! The depth probes of `Feedforward::OnWithTarget`: children placed along the best pose's
//! viewing ray, and a block that comes towards the cameras followed in depth.

use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::ga::SearchSpace;
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::quat;
use evorec_core::tracker::{DEPTH_PROBE_DISPARITY_PX, DEPTH_PROBES, Feedforward, JointSample, Tracker, TrackerConfig};
use nalgebra::{Isometry3, Vector3};

mod common;
use common::{frame, median, render};

const DT_US: u64 = 33_000;
const FOCAL_PX: f32 = 800.0;
const BASELINE_M: f32 = 0.1;

fn rig() -> StereoRig {
    let cam = Pinhole::new_checked(FOCAL_PX, FOCAL_PX, 320.0, 240.0, 640, 480).unwrap();
    StereoRig::parallel(cam, BASELINE_M).unwrap()
}

fn tracker(seed: u64, start: &Psi, mode: Feedforward) -> Tracker {
    let space = SearchSpace::new_checked([-0.4, -0.4, 0.3], [0.4, 0.4, 1.3]).unwrap();
    let config =
        TrackerConfig::pa10(rig(), Block::PAPER, Isometry3::identity(), space).with_seed(seed).with_feedforward(mode);
    let mut tracker: Tracker = Tracker::new(config).unwrap();
    tracker.reset_around(start, &[0.002, 0.002, 0.002, 0.004, 0.004, 0.004]).unwrap();
    tracker
}

/// The block at `z` m on the right camera's optical axis, turned so that three faces show.
fn block_at(z: f32) -> Psi {
    let q = quat::from_angle_axis(0.3, &Vector3::new(0.2, 1.0, 0.1)).unwrap();
    Psi::from_parts(&Vector3::new(0.01, -0.01, z), &q)
}

/// After a generation, the children just before the immigrants are the best pose (the elite,
/// index 0 after breeding) moved along its viewing ray to the depths whose disparity differs
/// by ±k px; in `Feedforward::On` (the paper's method) they are ordinary children.
#[test]
fn the_probes_line_the_best_poses_viewing_ray() {
    let truth = block_at(0.7);
    let (l, r) = render(&rig(), &truth);
    let frame = frame(&l, &r, 640, 480);
    for mode in [Feedforward::OnWithTarget, Feedforward::On] {
        let mut t = tracker(5, &truth, mode);
        let mut last = None;
        for k in 0..3u64 {
            let joints = JointSample { q: [0.0; 7], qd: [0.0; 7], time_us: k * DT_US };
            let dt = if k == 0 { 0.0 } else { DT_US as f32 * 1e-6 };
            last = Some(t.step(&frame, &joints, dt).unwrap());
        }
        // Held: the probes are bred while the block is held, confirmed or not.
        assert!(last.unwrap().status.holds());
        let best = t.population()[0];
        let end = t.population().len() - t.config().tuning.ga.immigrants;
        let z = best.0[2];
        let unit = z * z / (FOCAL_PX * BASELINE_M);
        let mut probes = 0;
        for (j, k) in DEPTH_PROBE_DISPARITY_PX.iter().enumerate() {
            for (s, sign) in [1.0f32, -1.0].iter().enumerate() {
                let ind = t.population()[end - DEPTH_PROBES + 2 * j + s];
                let scale = 1.0 + sign * k * unit / z;
                let on_ray = (0..3).all(|i| (ind.0[i] - best.0[i] * scale).abs() < 1e-6);
                let same_turn = (3..6).all(|i| ind.0[i] == best.0[i]);
                if on_ray && same_turn {
                    probes += 1;
                }
            }
        }
        let expected = if mode == Feedforward::OnWithTarget { DEPTH_PROBES } else { 0 };
        assert_eq!(probes, expected, "{mode:?}");
    }
}

/// RMS depth error (m) over frames 30.. of a block coming straight at the cameras at 0.1 m/s
/// (0.85 m to 0.52 m in 100 frames).
fn approach_rms_z(mode: Feedforward, seed: u64) -> f32 {
    let truth = |k: u64| block_at(0.85 - 0.1 * (k * DT_US) as f32 * 1e-6);
    let rig = rig();
    let mut t = tracker(seed, &truth(0), mode);
    let (mut sq, mut n) = (0.0, 0);
    for k in 0..100u64 {
        let (l, r) = render(&rig, &truth(k));
        let joints = JointSample { q: [0.0; 7], qd: [0.0; 7], time_us: k * DT_US };
        let dt = if k == 0 { 0.0 } else { DT_US as f32 * 1e-6 };
        let e = t.step(&frame(&l, &r, 640, 480), &joints, dt).unwrap();
        if k >= 30 {
            sq += (e.psi.0[2] - truth(k).0[2]).powi(2);
            n += 1;
        }
    }
    (sq / n as f32).sqrt()
}

#[test]
fn a_block_coming_towards_the_cameras_is_followed_in_depth() {
    let seeds = 1..=8;
    let ff = median(seeds.clone().map(|s| approach_rms_z(Feedforward::On, s)).collect());
    let target = median(seeds.map(|s| approach_rms_z(Feedforward::OnWithTarget, s)).collect());
    eprintln!("median RMS z: FF {ff} m, FF + target {target} m");
    // Measured, seeds 1–8: FF 183 mm (lost), FF + target 5.5 mm, and 11.7 mm without the
    // probes. The exactly rendered edges leave the fitness flat over several millimetres of
    // depth at 0.5–0.85 m, so the estimate wanders within that.
    assert!(target < 0.008, "FF + target: median RMS z {target} m");
    assert!(target < 0.1 * ff, "FF + target {target} m vs FF {ff} m");
}
