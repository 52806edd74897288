//! Tests of the target filter.

use super::*;
use crate::kinematics::PA10;

const DT_US: u64 = 33_000;

/// A block moving with `v` and turning with `w` (world) from `p0`, at frame `k`.
fn moving(k: u64, v: Vector3<f32>, w: Vector3<f32>) -> Isometry3<f32> {
    let t = (k * DT_US) as f32 * 1e-6;
    let q0 = quat::from_angle_axis(0.4, &Vector3::new(0.3, 1.0, 0.2)).unwrap();
    Isometry3::from_parts(Translation3::from(Vector3::new(0.8, -0.1, 0.3) + v * t), exp_rotation(&(w * t)) * q0)
}

/// Deterministic pseudo-noise in [−1, 1].
fn noise(k: u64, axis: u64) -> f32 {
    let x = (k.wrapping_mul(2654435761).wrapping_add(axis.wrapping_mul(40503)) % 2001) as f32;
    x / 1000.0 - 1.0
}

fn noisy(iso: Isometry3<f32>, k: u64, amp_m: f32, amp_rad: f32) -> Isometry3<f32> {
    let dp = Vector3::new(noise(k, 1), noise(k, 2), noise(k, 3)) * amp_m;
    let dr = Vector3::new(noise(k, 4), noise(k, 5), noise(k, 6)) * amp_rad;
    Isometry3::from_parts(Translation3::from(iso.translation.vector + dp), exp_rotation(&dr) * iso.rotation)
}

/// Feeds `f` the exact poses of a block moving with `v` and turning with `w`, frames `frames`
/// at fitness 0.95.
fn feed(f: &mut TargetFilter, frames: core::ops::Range<u64>, v: Vector3<f32>, w: Vector3<f32>) {
    for k in frames {
        f.update(&moving(k, v, w), k * DT_US, 0.95);
    }
}

/// A default filter fed 60 frames (0..60) of a block moving with `v` without turning: its
/// velocity is trusted.
fn trusted_filter(v: Vector3<f32>) -> TargetFilter {
    let mut f = TargetFilter::with_defaults();
    feed(&mut f, 0..60, v, Vector3::zeros());
    assert!(f.is_trusted(), "not trusted after 60 frames at {v}");
    f
}

/// A filter made with the defaults changed by `spoil`.
fn spoiled(spoil: impl FnOnce(&mut TargetFilterParams)) -> Result<TargetFilter, FilterParamsError> {
    let mut p = TargetFilterParams::DEFAULT;
    spoil(&mut p);
    TargetFilter::new(p)
}

/// The linear part tuned slow (the first tuning: constant velocity, 3 mm noise, 0.002 m²/s³,
/// trusted at 0.03 m/s, no hold), for comparison with the default's fast one.
const SLOW: TargetFilterParams = TargetFilterParams {
    position_noise_m: 0.003,
    depth_noise_m: 0.003,
    acceleration_psd: 0.002,
    jerk_psd: 0.0,
    initial_accel_sd_m_s2: 0.0,
    acceleration_lead_s: 0.0,
    trusted_speed_sd_m_s: 0.03,
    lost_fitness: 0.5,
    hold_motion: false,
    ..TargetFilterParams::DEFAULT
};

#[test]
fn constant_velocity_is_recovered() {
    let (v, w) = (Vector3::new(0.0, 0.2, -0.05), Vector3::new(0.0, 0.1, 0.5));
    let mut f = TargetFilter::new(SLOW).unwrap();
    let mut trusted_at = None;
    for k in 0..120 {
        let out = f.update(&noisy(moving(k, v, w), k, 0.002, 0.004), k * DT_US, 0.95);
        assert_ne!(out, UpdateOutcome::Lost);
        if trusted_at.is_none() && f.is_trusted() {
            trusted_at = Some(k);
        }
    }
    let k = trusted_at.unwrap();
    assert!(k >= u64::from(TargetFilterParams::DEFAULT.converge_updates), "trusted too early at {k}");
    assert!(k <= 40, "trusted only at {k}");
    let est = f.velocity().unwrap();
    assert!((est.v - v).norm() < 0.01, "v {} vs {}", est.v, v);
    assert!((est.w - w).norm() < 0.05, "w {} vs {}", est.w, w);
}

#[test]
fn not_trusted_before_convergence() {
    let mut f = TargetFilter::with_defaults();
    for k in 0..5 {
        f.update(&moving(k, Vector3::new(0.1, 0.0, 0.0), Vector3::zeros()), k * DT_US, 0.95);
        assert!(!f.is_trusted());
        assert_eq!(f.velocity(), None);
        assert_eq!(f.feedforward_velocity(), TargetVelocity::ZERO);
    }
}

#[test]
fn a_reset_forgets() {
    let v = Vector3::new(0.3, 0.0, 0.0);
    let mut f = trusted_filter(v);
    // A fitness drop means the target is lost.
    assert_eq!(f.update(&moving(60, v, Vector3::zeros()), 60 * DT_US, 0.2), UpdateOutcome::Lost);
    assert!(!f.has_track() && !f.is_trusted());
    assert_eq!(f.velocity_estimate(), None);
    // It starts again from nothing: a still target now reads as still.
    let still = moving(0, Vector3::zeros(), Vector3::zeros());
    for k in 61..120 {
        f.update(&still, k * DT_US, 0.95);
    }
    assert!(f.velocity().unwrap().v.norm() < 1e-3);
    f.reset();
    assert!(!f.has_track());
    assert_eq!(f.update(&still, 200 * DT_US, 0.95), UpdateOutcome::Started);
}

#[test]
fn outliers_are_bounded() {
    let v = Vector3::new(0.0, 0.1, 0.0);
    let mut f = trusted_filter(v);
    let before = f.velocity().unwrap();
    // A wild estimate (half a metre and 90° off) is rejected and changes no velocity.
    let mut wild = moving(60, v, Vector3::zeros());
    wild.translation.vector.x += 0.5;
    wild.rotation = exp_rotation(&Vector3::new(1.57, 0.0, 0.0)) * wild.rotation;
    assert_eq!(f.update(&wild, 60 * DT_US, 0.95), UpdateOutcome::Rejected);
    // (Only the prediction over the frame moves it, by the acceleration state's ~0 · dt.)
    let after = f.velocity_estimate().unwrap();
    assert!((after.v - before.v).norm() < 1e-5 && (after.w - before.w).norm() < 1e-6, "{after:?} vs {before:?}");
    assert!(f.is_trusted(), "a single outlier does not undo convergence");
    // The track resumes.
    for k in 61..80 {
        assert_eq!(f.update(&moving(k, v, Vector3::zeros()), k * DT_US, 0.95), UpdateOutcome::Accepted);
    }
    assert!((f.velocity().unwrap().v - v).norm() < 0.005);
    // A run of outliers restarts the filter at the newest measurement.
    for k in 80..83 {
        let mut m = moving(k, v, Vector3::zeros());
        m.translation.vector.z += 1.0;
        let out = f.update(&m, k * DT_US, 0.95);
        assert!(out == if k < 82 { UpdateOutcome::Rejected } else { UpdateOutcome::Started }, "{k}: {out:?}");
    }
    assert!(!f.is_trusted());
}

#[test]
fn time_gaps_and_bad_input_restart() {
    let mut f = TargetFilter::with_defaults();
    let m = moving(0, Vector3::zeros(), Vector3::zeros());
    assert_eq!(f.update(&m, 1_000_000, 0.9), UpdateOutcome::Started);
    assert_eq!(f.update(&m, 1_033_000, 0.9), UpdateOutcome::Accepted);
    assert_eq!(f.update(&m, 900_000, 0.9), UpdateOutcome::Started, "time ran backwards");
    assert_eq!(f.update(&m, 2_000_000, 0.9), UpdateOutcome::Started, "gap above max_gap_s");
    assert_eq!(f.update(&m, 2_033_000, f32::NAN), UpdateOutcome::Lost);
    let mut bad = m;
    bad.translation.vector.x = f32::INFINITY;
    assert_eq!(f.update(&bad, 2_066_000, 0.9), UpdateOutcome::Lost);
    assert_eq!(spoiled(|p| p.gate_sigma = 0.0), Err(FilterParamsError("gate_sigma")));
    assert_eq!(spoiled(|p| p.significance_sigma = -1.0), Err(FilterParamsError("significance_sigma")));
    assert_eq!(spoiled(|p| p.converge_updates = 0), Err(FilterParamsError("converge_updates")));
}

#[test]
fn deadband_zeroes_slow_motion_only() {
    let mut f = TargetFilter::with_defaults();
    let (v, w) = (Vector3::new(0.005, 0.0, 0.0), Vector3::new(0.0, 0.0, 0.3));
    feed(&mut f, 0..80, v, w);
    let ff = f.feedforward_velocity();
    assert_eq!(ff.v, Vector3::zeros());
    assert!((ff.w - w).norm() < 0.02);
}

#[test]
fn noise_of_a_still_target_is_not_fed_forward_but_slow_real_motion_is() {
    // Estimates of a target at rest with uniform noise of ±1.7 mm (σ 0.98 mm, the filter's
    // 1 mm) and ±0.02 rad: the filter's velocity wanders above the dead bands, but never
    // reaches significance.
    let mut f = TargetFilter::with_defaults();
    let still = Vector3::zeros();
    let mut above_deadband = 0;
    for k in 0..600 {
        f.update(&noisy(moving(k, still, still), k, 0.0017, 0.02), k * DT_US, 0.95);
        if let Some(vel) = f.velocity() {
            above_deadband += usize::from(vel.v.norm() >= TargetFilterParams::DEFAULT.deadband_m_s);
            assert_eq!(f.feedforward_velocity(), TargetVelocity::ZERO, "frame {k}: {vel:?}");
        }
    }
    assert!(above_deadband > 0, "the dead band alone would have let noise through");
    // A conveyor with the same noise is fed forward in every frame once converged, at 0.1 m/s
    // by the fast default, at 0.05 m/s by the slow tuning, and on average at its speed. One
    // frame's fed velocity is noisy (the default's acceleration state, moved on by
    // `acceleration_lead_s`, puts single frames several cm/s off here); the mean over the last
    // 50 frames is within 0.01 m/s.
    for (params, speed) in [(TargetFilterParams::DEFAULT, 0.1), (SLOW, 0.05)] {
        let mut f = TargetFilter::new(params).unwrap();
        let v = Vector3::new(0.0, speed, 0.0);
        let mut sum = Vector3::zeros();
        for k in 0..200 {
            f.update(&noisy(moving(k, v, still), k, 0.0017, 0.02), k * DT_US, 0.95);
            if k >= 150 {
                let fed = f.feedforward_velocity().v;
                assert!(fed != Vector3::zeros(), "{speed}: frame {k} not fed forward");
                sum += fed;
            }
        }
        let mean = sum / 50.0;
        assert!((mean - v).norm() < 0.01, "{speed}: mean fed {mean}");
    }
}

#[test]
fn a_status_other_than_tracking_resets() {
    let v = Vector3::new(0.2, 0.0, 0.0);
    let mut f = TargetFilter::with_defaults();
    for k in 0..60 {
        assert_ne!(f.update_with_status(&moving(k, v, v), k * DT_US, 0.95, Status::Tracking), UpdateOutcome::Lost);
    }
    assert!(f.is_trusted());
    // The tracker lost the block: its estimate (fitness still high, carried along) is no
    // measurement.
    for status in [Status::Lost, Status::Searching] {
        assert_eq!(f.update_with_status(&moving(60, v, v), 60 * DT_US, 0.95, status), UpdateOutcome::Lost);
        assert!(!f.has_track() && f.feedforward_velocity() == TargetVelocity::ZERO);
        assert_eq!(f.last_outcome(), Some(UpdateOutcome::Lost));
    }
    assert_eq!(f.update_with_status(&moving(61, v, v), 61 * DT_US, 0.95, Status::Tracking), UpdateOutcome::Started);
}

#[test]
fn predict_moves_the_target_and_follows_the_camera() {
    let q = [0.1f32, -0.4, 0.3, 1.2, -0.5, 0.7, 0.2];
    let qd = [0.2f32, 0.1, -0.1, 0.05, 0.0, 0.3, -0.2];
    let mount = Isometry3::translation(0.05, 0.0, 0.06);
    let (v, w) = (Vector3::new(0.1, -0.05, 0.0), Vector3::new(0.0, 0.0, 0.4));
    // The whole velocity, also along the line of sight (the default's rule: `depth_is_not_fed_forward`).
    let mut f =
        TargetFilter::new(TargetFilterParams { depth_feedforward: 1.0, ..TargetFilterParams::DEFAULT }).unwrap();
    let no_joints = JointSample { q, qd, time_us: 0 };
    assert_eq!(f.predict(&PA10, &mount, &no_joints, 0), Err(PredictError::NoTrack));
    feed(&mut f, 0..80, v, w);
    let t_capture = 79 * DT_US;
    let t_out = t_capture + 50_000;
    let joints = JointSample { q, qd, time_us: t_capture };
    let p = f.predict(&PA10, &mount, &joints, t_out).unwrap();
    assert!(p.trusted && p.base_time_us == t_capture);
    let tau = 0.05f32;
    let q_out: [f32; 7] = core::array::from_fn(|i| q[i] + qd[i] * tau);
    let cam_out = PA10.forward(&q_out) * mount;
    let truth_world = moving(79, v, w);
    let truth_world = Isometry3::from_parts(
        Translation3::from(truth_world.translation.vector + v * tau),
        exp_rotation(&(w * tau)) * truth_world.rotation,
    );
    let truth = Psi::from_isometry(&(cam_out.inverse() * truth_world));
    for i in 0..6 {
        assert!((p.psi.0[i] - truth.0[i]).abs() < 2e-4, "[{i}] {} vs {}", p.psi.0[i], truth.0[i]);
    }
    let mut nan = joints;
    nan.qd[3] = f32::NAN;
    assert_eq!(f.predict(&PA10, &mount, &nan, t_out), Err(PredictError::NonFiniteJoint));
}

#[test]
fn world_pose_round_trips_through_the_camera() {
    let q = [0.3f32, 0.2, -0.1, 1.0, 0.4, -0.3, 0.5];
    let mount = Isometry3::translation(0.05, 0.0, 0.06);
    let psi = Psi::new([0.02, -0.03, 0.7], [0.1, -0.05, 0.2]);
    let w = world_pose(&PA10, &q, &mount, &psi);
    let cam = PA10.forward(&q) * mount;
    let back = Psi::from_isometry(&(cam.inverse() * w));
    for i in 0..6 {
        assert!((back.0[i] - psi.0[i]).abs() < 1e-5);
    }
    let r = camera_from_world_rotation(&cam);
    assert!((r * (w.translation.vector - cam.translation.vector) - psi.translation()).norm() < 1e-5);
}

#[test]
fn log_and_exp_are_inverse() {
    for phi in [Vector3::new(0.3, -0.2, 0.1), Vector3::new(0.0, 0.0, 2.5), Vector3::new(1e-8, 0.0, 0.0)] {
        let back = log_rotation(&exp_rotation(&phi));
        assert!((back - phi).norm() < 1e-5, "{phi} -> {back}");
    }
}

/// A block on a conveyor along world y: at `speed` until frame 60, then reversing with a
/// half-cosine velocity profile over `reversal_frames`. Its pose and velocity at frame `k`.
fn shuttle(k: u64, speed: f32, reversal_frames: u64) -> (Isometry3<f32>, f32) {
    let dt = DT_US as f32 * 1e-6;
    let vel = |j: u64| -> f32 {
        match j.checked_sub(60) {
            None => speed,
            Some(i) if i < reversal_frames => {
                speed * math::cos(core::f32::consts::PI * i as f32 / reversal_frames as f32)
            }
            Some(_) => -speed,
        }
    };
    let y: f32 = (0..k).map(|j| 0.5 * (vel(j) + vel(j + 1)) * dt).sum();
    let base = moving(0, Vector3::zeros(), Vector3::zeros());
    let pose =
        Isometry3::from_parts(Translation3::from(base.translation.vector + Vector3::new(0.0, y, 0.0)), base.rotation);
    (pose, vel(k))
}

/// The worst error of the fed-forward speed along y (against the mean speed over the next
/// frame) through a reversal at 0.2 m/s over 22
/// frames (0.85 m/s² at its peak), and whether anything was fed forward in every frame from
/// the first trusted one on.
fn reversal_lag(params: TargetFilterParams) -> (f32, bool) {
    let mut f = TargetFilter::new(params).unwrap();
    let (mut worst, mut fed_throughout, mut trusted) = (0.0f32, true, false);
    for k in 0..130 {
        // The feedforward shifts over the next frame: its reference is the mean speed over it.
        let (pose, v0) = shuttle(k, 0.2, 22);
        let v = 0.5 * (v0 + shuttle(k + 1, 0.2, 22).1);
        f.update(&noisy(pose, k, 0.0005, 0.004), k * DT_US, 0.95);
        trusted |= f.is_trusted();
        if trusted && k >= 40 {
            let ff = f.feedforward_velocity().v;
            fed_throughout &= ff != Vector3::zeros();
            worst = worst.max((ff.y - v).abs());
        }
    }
    (worst, fed_throughout)
}

#[test]
fn the_default_follows_a_reversal_the_slow_tuning_lags() {
    let (fast, fed) = reversal_lag(TargetFilterParams::DEFAULT);
    let (slow, slow_fed) = reversal_lag(SLOW);
    let constant_velocity = TargetFilterParams {
        jerk_psd: 0.0,
        initial_accel_sd_m_s2: 0.0,
        acceleration_lead_s: 0.0,
        ..TargetFilterParams::DEFAULT
    };
    let (cv, _) = reversal_lag(constant_velocity);
    assert!(fast < 0.75 * cv, "worst speed error {fast} m/s against {cv} without the acceleration state");
    assert!(fed, "the motion is held through the speed's zero crossing");
    assert!(!slow_fed, "without hold_motion the slow speed around the reversal is not significant");
    assert!(fast < 0.5 * slow, "worst speed error {fast} m/s against the slow tuning's {slow}");
    assert!(fast < 0.06, "worst speed error {fast} m/s");
}

#[test]
fn depth_is_not_fed_forward() {
    let v = Vector3::new(0.1, 0.15, 0.0);
    let f = trusted_filter(v);
    let all = f.feedforward_velocity().v;
    assert!((all - v).norm() < 0.01, "{all}");
    // Seen along world x: the part along the line of sight is dropped, the rest kept.
    let seen = f.feedforward_velocity_seen_along(&Vector3::new(2.0, 0.0, 0.0)).v;
    assert!(seen.x.abs() < 1e-6 && (seen.y - all.y).abs() < 1e-6 && seen.z == all.z, "{seen}");
    // Seen along a slanted sight: along it only what each world axis says in proportion to its
    // share across the sight, `Σ (1 − uᵢ²) vᵢ uᵢ`.
    let u = Vector3::new(0.8, 0.6, 0.0);
    let seen = f.feedforward_velocity_seen_along(&(u * 0.7)).v;
    let across = (1.0 - 0.64) * all.x * 0.8 + (1.0 - 0.36) * all.y * 0.6;
    assert!((seen.dot(&u) - across).abs() < 1e-6, "{seen}");
    assert!((seen - u * seen.dot(&u) - (all - u * all.dot(&u))).norm() < 1e-6, "across the sight all is kept");
    assert_eq!(spoiled(|p| p.depth_feedforward = 1.5), Err(FilterParamsError("depth_feedforward")));
}

#[test]
fn params_errors_name_the_rule_of_their_field() {
    use std::string::ToString;
    type Spoil = fn(&mut TargetFilterParams);
    let cases: [(Spoil, &str); 5] = [
        (|p| p.depth_noise_m = 0.0, "target filter parameter depth_noise_m must be finite and positive"),
        (|p| p.deadband_m_s = -0.1, "target filter parameter deadband_m_s must be finite and non-negative"),
        (|p| p.lost_fitness = f32::NAN, "target filter parameter lost_fitness must be finite and non-negative"),
        (|p| p.depth_feedforward = f32::NAN, "target filter parameter depth_feedforward must be between 0 and 1"),
        (|p| p.max_outliers = 0, "target filter parameter max_outliers must be at least 1"),
    ];
    for (spoil, message) in cases {
        let mut p = TargetFilterParams::DEFAULT;
        spoil(&mut p);
        let err = p.validate().unwrap_err();
        assert_eq!(err.to_string(), message);
        // A filter that refuses the parameters keeps its own.
        let mut f = TargetFilter::with_defaults();
        assert_eq!(f.set_params(p), Err(err));
        assert_eq!(f.params(), &TargetFilterParams::DEFAULT);
    }
}

#[test]
fn a_belt_across_a_slanted_view_keeps_its_motion_in_depth() {
    // A block moving along world y seen along a sight 16° off world x: its motion along the
    // sight (0.2 · sin 16° ≈ 0.055 m/s) is motion of a well-measured axis and is fed forward.
    let v = Vector3::new(0.0, 0.2, 0.0);
    let f = trusted_filter(v);
    let u = Vector3::new(0.96, 0.28, 0.0);
    let seen = f.feedforward_velocity_seen_along(&u).v;
    let all = f.feedforward_velocity().v;
    assert!(seen.dot(&u) > 0.9 * all.dot(&u) && all.dot(&u) > 0.05, "{seen} of {all}");
}

/// The fed-forward angular velocity over `frames` frames of a block whose orientation is
/// `turn(k)` (world rotation vector from `moving`'s start) with ±`jitter` rad of noise, seen
/// with fitness 0.99: the RMS of its error against the true rate `rate(k)` from frame 40 on,
/// and the last one.
fn angular_feed(
    params: TargetFilterParams,
    frames: u64,
    jitter: f32,
    turn: impl Fn(u64) -> Vector3<f32>,
    rate: impl Fn(u64) -> Vector3<f32>,
) -> (f32, Vector3<f32>) {
    let mut f = TargetFilter::new(params).unwrap();
    let (mut sum, mut n, mut last) = (0.0, 0, Vector3::zeros());
    for k in 0..frames {
        let base = moving(0, Vector3::zeros(), Vector3::zeros());
        let pose = Isometry3::from_parts(base.translation, exp_rotation(&turn(k)) * base.rotation);
        f.update(&noisy(pose, k, 0.0005, jitter), k * DT_US, 0.99);
        last = f.feedforward_velocity().w;
        if k >= 40 {
            sum += (last - rate(k)).norm_squared();
            n += 1;
        }
    }
    (math::sqrt(sum / n as f32), last)
}

const FAST_ONLY: TargetFilterParams =
    TargetFilterParams { slow_angular_acceleration_psd: 0.0, ..TargetFilterParams::DEFAULT };

#[test]
fn a_steady_slow_turn_is_fed_forward_by_the_slow_model() {
    // The iiwa-rotate sample: a block turning at 0.03 rad/s, estimates jittering by a few mrad.
    let w = Vector3::new(0.0, -0.023, -0.019);
    let dt = DT_US as f32 * 1e-6;
    let turn = |k: u64| w * (k as f32 * dt);
    let (rms, last) = angular_feed(TargetFilterParams::DEFAULT, 300, 0.005, turn, |_| w);
    assert!((last - w).norm() < 0.006, "fed forward {last} for {w}");
    assert!(rms < 0.012, "RMS error of the fed-forward rate {rms} rad/s");
    // The fast model alone (σ_ω ≈ 0.05 rad/s) never finds it significant.
    let (_, fast) = angular_feed(FAST_ONLY, 300, 0.005, turn, |_| w);
    assert_eq!(fast, Vector3::zeros());
    // A block at rest with the same jitter is not turned.
    let (rest, _) = angular_feed(TargetFilterParams::DEFAULT, 300, 0.005, |_| Vector3::zeros(), |_| Vector3::zeros());
    assert!(rest < 1e-3, "a still block fed forward at {rest} rad/s RMS");
}

#[test]
fn an_oscillating_yaw_is_not_lagged_by_the_slow_model() {
    // The target grid's fast yaw: ±15° at ω_o = 1 and 0.5 rad/s, estimates jittering by 5 mrad.
    // The slow model would lag it by a large part of its 0.26 rad/s peak rate; it restarts
    // while the fast model sees the turn, so the fed-forward rate is no worse than the fast
    // model's alone.
    let dt = DT_US as f32 * 1e-6;
    let axis = Vector3::new(0.0, 0.0, 1.0);
    for omega in [1.0f32, 0.5] {
        let amp = 15f32.to_radians();
        let turn = |k: u64| axis * (amp * math::sin(omega * k as f32 * dt));
        let rate = |k: u64| axis * (amp * omega * math::cos(omega * k as f32 * dt));
        let (both, _) = angular_feed(TargetFilterParams::DEFAULT, 600, 0.005, turn, rate);
        let (fast, _) = angular_feed(FAST_ONLY, 600, 0.005, turn, rate);
        assert!(both <= 1.05 * fast, "ω_o {omega}: RMS rate error {both} rad/s against the fast model's {fast}");
        assert!(both < 0.5 * amp * omega, "ω_o {omega}: RMS rate error {both} rad/s");
    }
}

#[test]
fn a_poorly_seen_block_does_not_teach_the_slow_model() {
    // The same steady turn at fitness 0.9 (below `slow_min_fitness`): nothing of the slow
    // model is fed forward, as with the fast model alone.
    let w = Vector3::new(0.0, -0.023, -0.019);
    let mut f = TargetFilter::with_defaults();
    for k in 0..300u64 {
        let base = moving(0, Vector3::zeros(), Vector3::zeros());
        let pose =
            Isometry3::from_parts(base.translation, exp_rotation(&(w * (k * DT_US) as f32 * 1e-6)) * base.rotation);
        f.update(&noisy(pose, k, 0.0005, 0.005), k * DT_US, 0.9);
    }
    assert_eq!(f.feedforward_velocity().w, Vector3::zeros());
}

/// The angular velocity fed forward after 120 frames of a block moving with `v` and turning
/// with `w`, and whether its linear velocity is fed forward then.
fn angular_while_moving(params: TargetFilterParams, v: Vector3<f32>, w: Vector3<f32>) -> (Vector3<f32>, bool) {
    let mut f = TargetFilter::new(params).unwrap();
    for k in 0..120u64 {
        f.update(&noisy(moving(k, v, w), k, 0.0005, 0.004), k * DT_US, 0.9);
    }
    let ff = f.feedforward_velocity();
    (ff.w, ff.v != Vector3::zeros())
}

#[test]
fn a_moving_block_gets_no_fast_angular_feedforward() {
    let v = Vector3::new(0.0, 0.2, 0.0);
    let w = Vector3::new(0.0, 0.0, 0.3);
    let unmuted = TargetFilterParams { linear_motion_mutes_angular: false, ..TargetFilterParams::DEFAULT };
    let (fed, moves) = angular_while_moving(unmuted, v, w);
    assert!(moves && (fed - w).norm() < 0.1, "without the mute the turn {w} is fed forward as {fed}");
    let (muted, moves) = angular_while_moving(TargetFilterParams::DEFAULT, v, w);
    assert!(moves, "the linear motion is still fed forward");
    assert_eq!(muted, Vector3::zeros(), "the fast angular model is muted while the block moves");
    // A block turning in place keeps its angular feedforward.
    let (still, moves) = angular_while_moving(TargetFilterParams::DEFAULT, Vector3::zeros(), w);
    assert!(!moves && (still - w).norm() < 0.1, "a turn in place {w} is fed forward as {still}");
}

/// The by-name tables list every field of [`TargetFilterParams`] once (checked against the
/// derived `Debug`, which names them all), and each entry reads and writes its own field.
#[test]
fn the_field_tables_cover_every_parameter_once() {
    use std::string::{String, ToString};
    use std::vec::Vec;
    let debug = std::format!("{:?}", TargetFilterParams::DEFAULT);
    let inner = debug.trim_start_matches("TargetFilterParams { ").trim_end_matches(" }");
    let mut declared: Vec<String> =
        inner.split(", ").map(|kv| kv.split(':').next().unwrap_or("").to_string()).collect();
    let reals = TargetFilterParams::REAL_FIELDS.iter().map(|f| f.name);
    let counts = TargetFilterParams::COUNT_FIELDS.iter().map(|f| f.name);
    let flags = TargetFilterParams::FLAG_FIELDS.iter().map(|f| f.name);
    let mut listed: Vec<String> = reals.chain(counts).chain(flags).map(ToString::to_string).collect();
    declared.sort();
    listed.sort();
    assert_eq!(listed, declared);
    assert_eq!(listed.len(), 27);
    let d = TargetFilterParams::DEFAULT;
    for f in TargetFilterParams::REAL_FIELDS {
        let mut p = d;
        (f.set)(&mut p, (f.get)(&d) + 0.5);
        assert_eq!((f.get)(&p), (f.get)(&d) + 0.5, "{}", f.name);
        assert!(std::format!("{p:?}").contains(&std::format!("{}: {:?}", f.name, (f.get)(&d) + 0.5)), "{}", f.name);
    }
    for f in TargetFilterParams::COUNT_FIELDS {
        let mut p = d;
        (f.set)(&mut p, 777);
        assert!(std::format!("{p:?}").contains(&std::format!("{}: 777", f.name)), "{}", f.name);
    }
    for f in TargetFilterParams::FLAG_FIELDS {
        let mut p = d;
        (f.set)(&mut p, !(f.get)(&d));
        assert!(std::format!("{p:?}").contains(&std::format!("{}: {}", f.name, !(f.get)(&d))), "{}", f.name);
    }
}
