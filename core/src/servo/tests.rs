//! Unit tests of the servo law in a kinematic simulation: the camera pose is integrated from
//! the commanded twist, the measurement is the exact relative pose.

use super::*;
use crate::quat;
use nalgebra::Translation3;

const DT: f32 = 0.01;

fn limits() -> ServoLimits {
    ServoLimits { max_speed_m_s: 0.3, max_rot_speed_rad_s: 1.0, max_accel_m_s2: 1.0, max_rot_accel_rad_s2: 3.0 }
}

fn desired() -> Isometry3<f32> {
    Isometry3::translation(0.0, 0.0, 0.6)
}

fn servo(gain: f32, limits: ServoLimits) -> Servo {
    Servo::new(ServoConfig { desired: desired(), gain, limits }).unwrap_or_else(|e| unreachable!("{e}"))
}

fn rot(angle: f32, axis: [f32; 3]) -> UnitQuaternion<f32> {
    quat::from_angle_axis(angle, &Vector3::from(axis)).unwrap_or_else(|e| unreachable!("{e:?}"))
}

/// Moves the camera by a twist given in its own frame for `dt`.
fn integrate(camera: &Isometry3<f32>, twist: &CameraTwist, dt: f32) -> Isometry3<f32> {
    let w = twist.w * dt;
    let angle = math::sqrt(w.dot(&w));
    let r = if angle > 0.0 { rot(angle, [w.x, w.y, w.z]) } else { UnitQuaternion::identity() };
    camera * Isometry3::from_parts(Translation3::from(twist.v * dt), r)
}

fn speed(v: &Vector3<f32>) -> f32 {
    math::sqrt(v.dot(v))
}

struct Run {
    camera: Isometry3<f32>,
    servo: Servo,
    max_v: f32,
    max_w: f32,
    max_dv: f32,
    max_dw: f32,
}

impl Run {
    fn new(servo: Servo, camera: Isometry3<f32>) -> Self {
        Self { camera, servo, max_v: 0.0, max_w: 0.0, max_dv: 0.0, max_dw: 0.0 }
    }

    /// One period against a target at `target` (world) moving with `vel` (world frame);
    /// `tracking = false` withholds the measurement.
    fn step(&mut self, target: &Isometry3<f32>, vel: Option<&CameraTwist>, tracking: bool) -> ServoOutput {
        let pose = self.camera.inverse() * target;
        let r_cw = self.camera.rotation.inverse();
        let target_velocity = match vel {
            Some(v) => CameraTwist { v: r_cw * v.v, w: r_cw * v.w },
            None => CameraTwist::ZERO,
        };
        let input = ServoInput { pose, target_velocity };
        let prev = *self.servo.command();
        let out = self.servo.update(tracking.then_some(&input), DT).unwrap_or_else(|e| unreachable!("{e}"));
        self.max_v = self.max_v.max(speed(&out.command.v));
        self.max_w = self.max_w.max(speed(&out.command.w));
        self.max_dv = self.max_dv.max(speed(&(out.command.v - prev.v)));
        self.max_dw = self.max_dw.max(speed(&(out.command.w - prev.w)));
        self.camera = integrate(&self.camera, &out.command, DT);
        out
    }

    fn error(&self, target: &Isometry3<f32>) -> PoseError {
        PoseError::between(&(self.camera.inverse() * target), &desired())
    }
}

fn start_camera() -> Isometry3<f32> {
    Isometry3::from_parts(Translation3::new(0.08, -0.05, -0.12), rot(0.35, [0.3, 1.0, -0.2]))
}

#[test]
fn converges_on_a_static_target_within_the_limits() {
    let target = Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.6), UnitQuaternion::identity());
    let mut run = Run::new(servo(2.0, limits()), start_camera());
    let e0 = run.error(&target);
    assert!(e0.translation_norm() > 0.1 && e0.rotation_norm() > 0.3);
    for _ in 0..1000 {
        run.step(&target, None, true);
    }
    let e = run.error(&target);
    assert!(e.translation_norm() < 1e-4 && e.rotation_norm() < 1e-4, "{e:?}");
    let l = limits();
    assert!(run.max_v <= l.max_speed_m_s * (1.0 + 1e-6) && run.max_w <= l.max_rot_speed_rad_s * (1.0 + 1e-6));
    assert!(run.max_dv <= l.max_accel_m_s2 * DT * 1.0001 && run.max_dw <= l.max_rot_accel_rad_s2 * DT * 1.0001);
}

#[test]
fn error_decays_at_the_gain_when_the_limits_do_not_bind() {
    let target = desired();
    let camera = Isometry3::translation(0.002, 0.0, 0.0);
    let wide =
        ServoLimits { max_speed_m_s: 10.0, max_rot_speed_rad_s: 10.0, max_accel_m_s2: 1e4, max_rot_accel_rad_s2: 1e4 };
    let mut run = Run::new(servo(2.0, wide), camera);
    for _ in 0..50 {
        run.step(&target, None, true);
    }
    // 0.5 s at λ = 2: e^{-1} of the start (Euler with λdt = 0.02: 0.98^50 = 0.364).
    let ratio = run.error(&target).translation_norm() / 0.002;
    assert!((ratio - 0.98f32.powi(50)).abs() < 1e-3, "{ratio}");
}

#[test]
fn commands_are_clamped_to_the_speed_and_acceleration_limits() {
    let mut s = servo(50.0, limits());
    let far = ServoInput {
        pose: Isometry3::from_parts(Translation3::new(2.0, -1.0, 3.0), rot(2.5, [1.0, 0.0, 0.0])),
        target_velocity: CameraTwist { v: Vector3::new(5.0, 0.0, 0.0), w: Vector3::new(0.0, 4.0, 0.0) },
    };
    let (law, _) = s.law(&far);
    assert!(speed(&law.v) > 1.0 && speed(&law.w) > 1.0);
    let first = s.update(Some(&far), DT).unwrap_or_else(|e| unreachable!("{e}"));
    assert!((speed(&first.command.v) - limits().max_accel_m_s2 * DT).abs() < 1e-6);
    assert!((speed(&first.command.w) - limits().max_rot_accel_rad_s2 * DT).abs() < 1e-6);
    let mut out = first;
    for _ in 0..200 {
        out = s.update(Some(&far), DT).unwrap_or_else(|e| unreachable!("{e}"));
    }
    assert!((speed(&out.command.v) - limits().max_speed_m_s).abs() < 1e-5);
    assert!((speed(&out.command.w) - limits().max_rot_speed_rad_s).abs() < 1e-5);
    // The direction of the clamped command is the law's.
    let cos = out.command.v.dot(&law.v) / (speed(&out.command.v) * speed(&law.v));
    assert!(cos > 0.9999, "{cos}");
}

/// A block moving at 0.1 m/s along the camera's x and turning at 0.2 rad/s about its y.
fn moving_target(t: f32) -> (Isometry3<f32>, CameraTwist) {
    let w = Vector3::new(0.0, 0.2, 0.0);
    let pose = Isometry3::from_parts(Translation3::new(0.1 * t, 0.0, 0.6), rot(0.2 * t, [0.0, 1.0, 0.0]));
    (pose, CameraTwist { v: Vector3::new(0.1, 0.0, 0.0), w })
}

#[test]
fn target_velocity_feedforward_removes_the_lag_on_a_moving_block() {
    for (feed, lagging) in [(true, false), (false, true)] {
        let mut run = Run::new(servo(2.0, limits()), Isometry3::identity());
        for k in 0..800 {
            let (target, vel) = moving_target(k as f32 * DT);
            run.step(&target, feed.then_some(&vel), true);
        }
        let (target, _) = moving_target(800.0 * DT);
        let e = run.error(&target);
        if lagging {
            // A P law lags a ramp by v / λ = 0.05 m (plus the turn's share).
            assert!(e.translation_norm() > 0.03, "{e:?}");
            assert!((e.rotation_norm() - 0.1).abs() < 0.01, "{e:?}");
        } else {
            assert!(e.translation_norm() < 1e-3 && e.rotation_norm() < 1e-3, "{e:?}");
        }
    }
}

#[test]
fn on_loss_it_decelerates_to_a_stop_within_the_limits_and_resumes_without_a_jump() {
    let target = Isometry3::translation(0.5, 0.0, 0.6);
    let mut run = Run::new(servo(4.0, limits()), Isometry3::identity());
    // Get going at the speed limit.
    for _ in 0..60 {
        run.step(&target, None, true);
    }
    let v0 = speed(&run.servo.command().v);
    assert!((v0 - limits().max_speed_m_s).abs() < 1e-5, "{v0}");
    let stop_steps = (v0 / (limits().max_accel_m_s2 * DT)).ceil() as usize;
    let mut last = v0;
    let mut stopped_after = None;
    for k in 0..stop_steps + 20 {
        let out = run.step(&target, None, false);
        let v = speed(&out.command.v);
        assert!(v <= last + 1e-7, "speed rose while stopping");
        assert!(last - v <= limits().max_accel_m_s2 * DT * 1.0001);
        assert!(out.error.is_none());
        last = v;
        if out.mode == ServoMode::Stopped && stopped_after.is_none() {
            stopped_after = Some(k + 1);
        }
        if stopped_after.is_some() {
            assert_eq!(out.mode, ServoMode::Stopped);
        } else {
            assert_eq!(out.mode, ServoMode::Stopping);
        }
    }
    assert_eq!(stopped_after, Some(stop_steps), "stops within max_speed / max_accel");
    // Re-acquired: the command ramps up from rest.
    let out = run.step(&target, None, true);
    assert_eq!(out.mode, ServoMode::Servoing);
    assert!(speed(&out.command.v) <= limits().max_accel_m_s2 * DT * 1.0001);
    for _ in 0..1000 {
        run.step(&target, None, true);
    }
    assert!(run.error(&target).translation_norm() < 1e-4);
    assert!(run.max_dv <= limits().max_accel_m_s2 * DT * 1.0001);
}

#[test]
fn bad_input_is_refused_and_leaves_the_servo_unchanged() {
    let mut s = servo(2.0, limits());
    let good = ServoInput { pose: Isometry3::translation(0.1, 0.0, 0.6), target_velocity: CameraTwist::ZERO };
    let _ = s.update(Some(&good), DT);
    let before = s;
    for dt in [0.0, -0.01, f32::NAN, f32::INFINITY] {
        assert!(matches!(s.update(Some(&good), dt), Err(ServoStepError::BadDt(_))));
    }
    let mut nan = good;
    nan.pose.translation.vector.x = f32::NAN;
    assert_eq!(s.update(Some(&nan), DT), Err(ServoStepError::NonFiniteInput));
    let mut inf = good;
    inf.target_velocity.w.z = f32::INFINITY;
    assert_eq!(s.update(Some(&inf), DT), Err(ServoStepError::NonFiniteInput));
    assert_eq!(s, before);
}

#[test]
fn invalid_configurations_name_the_field() {
    let ok = ServoConfig { desired: desired(), gain: 1.0, limits: limits() };
    assert!(ok.validate().is_ok());
    assert_eq!(Servo::new(ServoConfig { gain: 0.0, ..ok }).err(), Some(ServoConfigError::Gain));
    assert_eq!(Servo::new(ServoConfig { gain: f32::NAN, ..ok }).err(), Some(ServoConfigError::Gain));
    let mut bad = ok;
    bad.limits.max_accel_m_s2 = -1.0;
    assert_eq!(bad.validate(), Err(ServoConfigError::Limit("max_accel_m_s2")));
    bad = ok;
    bad.limits.max_rot_speed_rad_s = f32::INFINITY;
    assert_eq!(bad.validate(), Err(ServoConfigError::Limit("max_rot_speed_rad_s")));
    bad = ok;
    bad.desired.translation.vector.z = f32::NAN;
    assert_eq!(bad.validate(), Err(ServoConfigError::Desired));
}

#[test]
fn pose_error_is_the_desired_camera_seen_from_the_current_one() {
    // The block 0.1 m further right than desired: the camera must move +x by 0.1 m.
    let e = PoseError::between(&Isometry3::translation(0.1, 0.0, 0.6), &desired());
    assert!((e.translation - Vector3::new(0.1, 0.0, 0.0)).norm() < 1e-6);
    assert_eq!(e.rotation_norm(), 0.0);
    // A rotation of 3 rad keeps its angle (no wrap to the long way round).
    let cur = Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.6), rot(3.0, [0.0, 0.0, 1.0]));
    let e = PoseError::between(&cur, &desired());
    assert!((e.rotation_norm() - 3.0).abs() < 1e-5, "{e:?}");
}
