//! Feedforward of the target's own motion (`Feedforward::OnWithTarget`, eq. 23 in full) on a
//! synthetic sequence: a block sliding sideways in front of a still camera, and one turning in
//! place.

use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::ga::SearchSpace;
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::quat;
use evorec_core::target_motion::{PredictError, TargetVelocity};
use evorec_core::tracker::{Feedforward, JointSample, Tracker, TrackerConfig};
use nalgebra::{Isometry3, Quaternion, UnitQuaternion, Vector3};

mod common;
use common::{frame, median, render};

const DT_US: u64 = 33_000;
const FRAMES: u64 = 100;
/// Lateral speed of the block in the camera frame (m/s), reached after [`RAMP_S`].
const SPEED: f32 = 0.1;
/// The block accelerates uniformly from rest over this time (s).
const RAMP_S: f32 = 1.0;

/// Distance travelled after `t` seconds.
fn travel(t: f32) -> f32 {
    if t < RAMP_S { 0.5 * SPEED * t * t / RAMP_S } else { SPEED * (t - 0.5 * RAMP_S) }
}

fn rig() -> StereoRig {
    let cam = Pinhole::new_checked(800.0, 800.0, 320.0, 240.0, 640, 480).unwrap();
    StereoRig::parallel(cam, 0.1).unwrap()
}

fn truth(k: u64) -> Psi {
    let t = (k * DT_US) as f32 * 1e-6;
    let q = quat::from_angle_axis(0.3, &Vector3::new(0.2, 1.0, 0.1)).unwrap();
    Psi::from_parts(&Vector3::new(-0.15 + travel(t), 0.01, 0.75), &q)
}

/// Turn rate of the turning block (rad/s) about the camera's y axis.
const TURN_RATE: f32 = 0.3;

/// The angle (rad) between the orientations of `a` and `b`, modulo the block's colour symmetry
/// (a half turn about any of its axes).
fn symmetric_angle(a: &Psi, b: &Psi) -> f32 {
    let (qa, qb) = (a.quaternion_unchecked(), b.quaternion_unchecked());
    // The identity and the half turns about the block's x, y and z axes.
    let symmetry = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
    symmetry
        .iter()
        .map(|&[w, x, y, z]| {
            let s = UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z));
            (qa * (qb * s).inverse()).angle()
        })
        .fold(f32::MAX, f32::min)
}

/// The block turning in place at [`TURN_RATE`] from the sliding block's orientation.
fn turning(k: u64) -> Psi {
    let t = (k * DT_US) as f32 * 1e-6;
    let q0 = quat::from_angle_axis(0.3, &Vector3::new(0.2, 1.0, 0.1)).unwrap();
    let turn = quat::from_angle_axis(TURN_RATE * t, &Vector3::y()).unwrap();
    Psi::from_parts(&Vector3::new(0.0, 0.01, 0.75), &(turn * q0))
}

/// Frames at the end over which the filter's velocity is averaged (one frame's is noisy).
const LAST: u64 = 20;

/// Runs the sequence with GA seed `seed`; returns the RMS position error (m) over frames
/// 30.., the tracker, and the filter's mean world velocity and mean angular speed (rad/s) over
/// the last [`LAST`] frames (zero where it has none).
fn run(mode: Feedforward, seed: u64) -> (f32, Tracker, Vector3<f32>, f32) {
    run_on(truth, mode, seed).0
}

/// [`run`] on the poses `truth`, also with the RMS rotation error (rad) over frames 30...
fn run_on(truth: fn(u64) -> Psi, mode: Feedforward, seed: u64) -> ((f32, Tracker, Vector3<f32>, f32), f32) {
    let rig = rig();
    let space = SearchSpace::new_checked([-0.4, -0.4, 0.3], [0.4, 0.4, 1.3]).unwrap();
    let config =
        TrackerConfig::pa10(rig, Block::PAPER, Isometry3::identity(), space).with_seed(seed).with_feedforward(mode);
    let mut tracker: Tracker = Tracker::new(config).unwrap();
    tracker.reset_around(&truth(0), &[0.002, 0.002, 0.002, 0.004, 0.004, 0.004]).unwrap();
    let mut sq = 0.0;
    let mut n = 0;
    let mut v_sum = Vector3::zeros();
    let mut w_sum = 0.0f32;
    let mut rot_sq = 0.0f32;
    for k in 0..FRAMES {
        let (l, r) = render(&rig, &truth(k));
        let frame = frame(&l, &r, 640, 480);
        let joints = JointSample { q: [0.0; 7], qd: [0.0; 7], time_us: k * DT_US };
        let dt = if k == 0 { 0.0 } else { DT_US as f32 * 1e-6 };
        let e = tracker.step(&frame, &joints, dt).unwrap();
        assert_eq!(e.capture_time_us, k * DT_US);
        if k >= 30 {
            sq += (e.psi.translation() - truth(k).translation()).norm_squared();
            let err = symmetric_angle(&e.psi, &truth(k));
            rot_sq += err * err;
            n += 1;
        }
        if k >= FRAMES - LAST {
            v_sum += tracker.target_filter().velocity().map_or(Vector3::zeros(), |v| v.v);
            w_sum += tracker.target_filter().velocity().map_or(0.0, |v| v.w.norm());
        }
    }
    (((sq / n as f32).sqrt(), tracker, v_sum / LAST as f32, w_sum / LAST as f32), (rot_sq / n as f32).sqrt())
}

#[test]
fn target_feedforward_follows_a_sliding_block() {
    // One GA seed's RMS error is a draw (over seeds 1–12 the default's ranged from 1.8 to
    // 19 mm), so the errors are compared as medians over 24 seeds.
    let seeds = 1..=24;
    let rms_ff = median(seeds.clone().map(|s| run(Feedforward::On, s).0).collect());
    let runs: Vec<_> = seeds.map(|s| run(Feedforward::OnWithTarget, s)).collect();
    let rms_target = median(runs.iter().map(|r| r.0).collect());
    eprintln!("medians: FF {rms_ff} m, FF + target {rms_target} m");
    assert!(rms_target < 0.5 * rms_ff, "FF + target {rms_target} m vs FF {rms_ff} m (medians)");
    // Medians over the seeds, measured: FF alone 30.3 mm, FF + target 1.7 mm (the ramp from
    // rest is where it lags).
    assert!(rms_target < 0.008, "FF + target {rms_target} m (median)");
    // The block slides without turning. The GA trades a small turn for a small shift across
    // the view, and a filter that reads it as a turn feeds it to the children; the two copies
    // of the elite moved with and without the turn let the fitness refuse it. Measured, median
    // of the mean angular speed over the last frames: 0.046 rad/s (0.13 without the copies,
    // measured when the model was fed the best individual's orientation). One seed's mean
    // ranges from 0.02 to 0.21 rad/s: a median over eight seeds is too rough a draw for the
    // bound (seeds 1–8 give 0.042 where seeds 1–40 give 0.053), hence 24 seeds.
    let spin = median(runs.iter().map(|r| r.3).collect());
    assert!(spin < 0.06, "the filter reads a turn of {spin} rad/s into a sliding block (median)");

    // The filter has the block's velocity (the camera is the world's flange frame at q = 0, so
    // the world velocity is the camera-frame one rotated by the flange's rotation).
    let cam = evorec_core::kinematics::PA10.forward(&[0.0; 7]);
    let expected = cam.rotation * Vector3::new(SPEED, 0.0, 0.0);
    // One frame's velocity is noisy: the mean over the last frames is tested, per seed, and
    // the median over the seeds across the line of sight (the camera's x and y) and along it,
    // where stereo depth is seven times noisier (measured: x 0.0013 and y 0.0001 m/s below the
    // truth, z 0.0007 above; the seeds range from 0.080 to 0.104 m/s in x).
    let errs: Vec<Vector3<f32>> = runs.iter().map(|r| cam.rotation.inverse() * (r.2 - expected)).collect();
    let err = Vector3::from_fn(|i, _| median(errs.iter().map(|e| e[i]).collect()));
    assert!(err.x.abs() < 0.015 && err.y.abs() < 0.01 && err.z.abs() < 0.03, "median velocity error {err}");
    for (_, tracker, _, _) in &runs {
        let filter = tracker.target_filter();
        assert!(filter.is_trusted());
        // What the next step would shift every individual by: the filter's velocity.
        assert_eq!(tracker.target_feedforward_velocity(), filter.feedforward_velocity());
    }

    // Hand-over: the pose 50 ms after the last capture, 5 mm ahead of the last capture's. The
    // last frame's estimate is one draw (measured: −14.5 to +2.2 mm off in x, median of the
    // magnitudes 1.2 mm), so the median is tested.
    let last = (FRAMES - 1) * DT_US;
    let joints = JointSample { q: [0.0; 7], qd: [0.0; 7], time_us: last };
    let t_out = (last + 50_000) as f32 * 1e-6;
    let expected_x = -0.15 + travel(t_out);
    let off: Vec<f32> = runs
        .iter()
        .map(|(_, tracker, _, _)| {
            let p = tracker.predict(&joints, last + 50_000).unwrap();
            assert!(p.trusted && p.base_time_us == last);
            (p.psi.0[0] - expected_x).abs()
        })
        .collect();
    let off = median(off);
    assert!(off < 0.008, "predicted x off by {off} m (median)");
}

#[test]
fn a_reset_forgets_the_target_motion() {
    let (_, mut tracker, _, _) = run(Feedforward::OnWithTarget, 3);
    assert!(tracker.target_filter().is_trusted());
    tracker.reset_uniform();
    assert!(!tracker.target_filter().has_track());
    let joints = JointSample { q: [0.0; 7], qd: [0.0; 7], time_us: 0 };
    assert_eq!(tracker.target_feedforward_velocity(), TargetVelocity::ZERO);
    assert_eq!(tracker.predict(&joints, 0), Err(PredictError::NoTrack));
}

#[test]
fn target_feedforward_follows_a_turning_block() {
    // The model's turn fed forward follows a block that really turns (the paired test of the
    // turn must not refuse it). Measured, medians over seeds 1–6: rotation error 0.016 rad
    // with the target's motion fed forward against 0.104 rad with the arm's alone (0.054 rad
    // when the model was fed the best individual's orientation instead of the crowd's), the
    // model's turn rate 0.306 rad/s.
    let seeds = 1..=6;
    let ff: Vec<_> = seeds.clone().map(|s| run_on(turning, Feedforward::On, s)).collect();
    let target: Vec<_> = seeds.map(|s| run_on(turning, Feedforward::OnWithTarget, s)).collect();
    let rot_ff = median(ff.iter().map(|r| r.1).collect());
    let rot_target = median(target.iter().map(|r| r.1).collect());
    let rate = median(target.iter().map(|r| r.0.3).collect());
    let rms_target = median(target.iter().map(|r| r.0.0).collect());
    eprintln!(
        "medians: rotation FF {rot_ff} rad, FF + target {rot_target} rad; turn rate {rate} rad/s; position {rms_target} m"
    );
    assert!(rot_target < 0.75 * rot_ff, "FF + target {rot_target} rad vs FF {rot_ff} rad (medians)");
    assert!((rate - TURN_RATE).abs() < 0.1 * TURN_RATE, "the filter's turn rate {rate} rad/s (median)");
}
