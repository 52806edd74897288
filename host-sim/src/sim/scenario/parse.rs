//! The checks of a scenario file's `[camera]`, `[target]`, `[robot]` and `[servo]` tables
//! after deserialisation: each key against its range, named in every error.

use super::check::{Bound, check_range, check_range_why, float_in, int_in, missing};
use super::raw::{Floats, RawCamera, RawRobot, RawScenario, RawServo, RawTarget};
use super::*;

pub(super) fn parse_camera(r: RawCamera) -> Result<CameraConfig> {
    let d = CameraConfig::default();
    let width = int_in("camera.width", r.width, i64::from(d.width), 16, 4096)?;
    let height = int_in("camera.height", r.height, i64::from(d.height), 16, 4096)?;
    let fx = float_in("camera.fx", r.fx, d.fx, Bound::Open(0.0), 1e5)?;
    let fy = float_in("camera.fy", r.fy, d.fy, Bound::Open(0.0), 1e5)?;
    let cx = r.cx.unwrap_or(d.cx);
    check_range_why("camera.cx", cx, Bound::Closed(0.0), width as f64, " (inside the image width)")?;
    let cy = r.cy.unwrap_or(d.cy);
    check_range_why("camera.cy", cy, Bound::Closed(0.0), height as f64, " (inside the image height)")?;
    let baseline_m = float_in("camera.baseline_m", r.baseline_m, d.baseline_m, Bound::Open(0.0), 1.0)?;
    let noise_std = float_in("camera.noise_std", r.noise_std, d.noise_std, Bound::Closed(0.0), 100.0)?;
    let supersample = int_in("camera.supersample", r.supersample, i64::from(d.supersample), 1, 8)?;
    let samples = (width * height * supersample * supersample) as u64;
    if samples > MAX_SAMPLES_PER_IMAGE {
        return Err(invalid(
            "camera.supersample",
            format!("width·height·supersample² must be ≤ {MAX_SAMPLES_PER_IMAGE}, got {samples}"),
        ));
    }
    Ok(CameraConfig {
        // In range by the checks above.
        width: width as u16,
        height: height as u16,
        fx,
        fy,
        cx,
        cy,
        baseline_m,
        noise_std,
        supersample: supersample as u32,
    })
}

pub(super) fn parse_target(r: RawTarget) -> Result<TargetConfig> {
    let d = TargetConfig::default();
    let size_m = r.size_m.map_or(d.size_m, |f| f.0);
    for (i, x) in size_m.iter().enumerate() {
        check_range(&format!("target.size_m[{i}]"), *x, Bound::Open(0.0), 2.0)?;
    }
    let face_hues_deg = r.face_hues_deg.map_or(d.face_hues_deg, |f| f.0);
    for (i, h) in face_hues_deg.iter().enumerate() {
        if !h.is_finite() || *h < 0.0 || *h >= 360.0 {
            return Err(invalid(format!("target.face_hues_deg[{i}]"), format!("must be in [0, 360), got {h}")));
        }
    }
    let distance_m = float_in("target.distance_m", r.distance_m, d.distance_m, Bound::Open(0.0), 5.0)?;
    let half_diagonal = 0.5 * size_m.iter().map(|x| x * x).sum::<f64>().sqrt();
    if distance_m <= half_diagonal + 0.05 {
        return Err(invalid(
            "target.distance_m",
            format!(
                "must exceed the block's half diagonal plus 0.05 m ({:.4} m), got {distance_m}",
                half_diagonal + 0.05
            ),
        ));
    }
    let amplitude_deg = float_in("target.amplitude_deg", r.amplitude_deg, d.amplitude_deg, Bound::Closed(0.0), 180.0)?;
    let omega_rad_s = float_in("target.omega_rad_s", r.omega_rad_s, d.omega_rad_s, Bound::Closed(0.0), 10.0)?;
    let yaw0_deg = float_in("target.yaw0_deg", r.yaw0_deg, d.yaw0_deg, Bound::Closed(-180.0), 180.0)?;
    let placement = acquisition::parse_placement(r.placement.as_ref())?;
    let base = TargetConfig { size_m, face_hues_deg, distance_m, amplitude_deg, omega_rad_s, yaw0_deg, placement, ..d };
    parse_target_path(&r, base)
}

/// The `[target]` keys of the block's path ([`crate::sim::target_path`]).
fn parse_target_path(r: &RawTarget, base: TargetConfig) -> Result<TargetConfig> {
    let d = TargetConfig::default();
    let conveyor_speed_m_s =
        float_in("target.conveyor_speed_m_s", r.conveyor_speed_m_s, d.conveyor_speed_m_s, Bound::Closed(0.0), 0.3)?;
    if conveyor_speed_m_s != 0.0 && conveyor_speed_m_s < 0.05 {
        return Err(invalid(
            "target.conveyor_speed_m_s",
            format!("must be 0 (off) or in [0.05, 0.3], got {conveyor_speed_m_s}"),
        ));
    }
    let conveyor_travel_m =
        float_in("target.conveyor_travel_m", r.conveyor_travel_m, d.conveyor_travel_m, Bound::Open(0.0), 0.5)?;
    let conveyor_accel_m_s2 =
        float_in("target.conveyor_accel_m_s2", r.conveyor_accel_m_s2, d.conveyor_accel_m_s2, Bound::Open(0.0), 10.0)?;
    let min_accel = 2.0 * conveyor_speed_m_s * conveyor_speed_m_s / conveyor_travel_m;
    if conveyor_accel_m_s2 < min_accel * (1.0 - 1e-9) {
        return Err(invalid(
            "target.conveyor_accel_m_s2",
            format!(
                "must be at least 2·speed²/travel = {min_accel:.4} m/s² to reverse within the travel, got \
                 {conveyor_accel_m_s2}"
            ),
        ));
    }
    let conveyor_dwell_s =
        float_in("target.conveyor_dwell_s", r.conveyor_dwell_s, d.conveyor_dwell_s, Bound::Closed(0.0), 60.0)?;
    let random_amplitude_m =
        float_in("target.random_amplitude_m", r.random_amplitude_m, d.random_amplitude_m, Bound::Closed(0.0), 0.1)?;
    let random_amplitude_deg = float_in(
        "target.random_amplitude_deg",
        r.random_amplitude_deg,
        d.random_amplitude_deg,
        Bound::Closed(0.0),
        30.0,
    )?;
    let random_omega_rad_s =
        float_in("target.random_omega_rad_s", r.random_omega_rad_s, d.random_omega_rad_s, Bound::Open(0.0), 2.0)?;
    if conveyor_speed_m_s > 0.0 && random_amplitude_m > 0.0 {
        return Err(invalid(
            "target.random_amplitude_m",
            "the block follows one path: set conveyor_speed_m_s or random_amplitude_m to 0",
        ));
    }
    let (conveyor_direction, conveyor_direction_frame, conveyor_start) = conveyor_direction(r)?;
    Ok(TargetConfig {
        conveyor_speed_m_s,
        conveyor_travel_m,
        conveyor_accel_m_s2,
        conveyor_dwell_s,
        conveyor_direction,
        conveyor_direction_frame,
        conveyor_start,
        random_amplitude_m,
        random_amplitude_deg,
        random_omega_rad_s,
        ..base
    })
}

/// `[target] conveyor_direction` (normalised), `conveyor_direction_frame` and `conveyor_start`.
fn conveyor_direction(r: &RawTarget) -> Result<([f64; 3], ConveyorFrame, ConveyorStart)> {
    let d = TargetConfig::default();
    let direction = r.conveyor_direction.map_or(d.conveyor_direction, |f| f.0);
    let conveyor_direction = unit_direction(direction).ok_or_else(|| {
        let [x, y, z] = direction;
        invalid("target.conveyor_direction", format!("must be a finite, non-zero vector, got [{x}, {y}, {z}]"))
    })?;
    let conveyor_direction_frame = match r.conveyor_direction_frame.as_deref().unwrap_or("world") {
        "world" => ConveyorFrame::World,
        "camera" => ConveyorFrame::Camera,
        other => {
            return Err(invalid(
                "target.conveyor_direction_frame",
                format!("expected \"world\" or \"camera\", got \"{other}\""),
            ));
        }
    };
    let conveyor_start = match r.conveyor_start.as_deref().unwrap_or("rest") {
        "rest" => ConveyorStart::Rest,
        "moving" => ConveyorStart::Moving,
        other => {
            return Err(invalid("target.conveyor_start", format!("expected \"rest\" or \"moving\", got \"{other}\"")));
        }
    };
    Ok((conveyor_direction, conveyor_direction_frame, conveyor_start))
}

/// `v` as a unit vector: `None` if a component is not finite or all are zero. A vector whose
/// norm is already 1 to within a few ulps is kept as it is, so that a scenario written by
/// [`Scenario::to_toml_string`] reads back bit for bit.
pub(super) fn unit_direction(v: [f64; 3]) -> Option<[f64; 3]> {
    if !v.iter().all(|x| x.is_finite()) {
        return None;
    }
    let largest = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if largest == 0.0 {
        return None;
    }
    let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if (norm - 1.0).abs() <= 8.0 * f64::EPSILON {
        return Some(v);
    }
    // Scaled first so that neither tiny nor huge components under- or overflow.
    let scaled = v.map(|x| x / largest);
    let norm = scaled.iter().map(|x| x * x).sum::<f64>().sqrt();
    Some(scaled.map(|x| x / norm))
}

pub(super) fn parse_robot(r: RawRobot) -> Result<RobotConfig> {
    let d = RobotConfig::default();
    let motion = match r.motion.as_deref().unwrap_or(d.motion.as_str()) {
        "static" => MotionKind::Static,
        "A" => MotionKind::A,
        "B" => MotionKind::B,
        other => {
            return Err(invalid("robot.motion", format!("expected \"static\", \"A\" or \"B\", got \"{other}\"")));
        }
    };
    let omega_rad_s = float_in("robot.omega_rad_s", r.omega_rad_s, d.omega_rad_s, Bound::Closed(0.0), 2.0)?;
    let amplitude_m = float_in("robot.amplitude_m", r.amplitude_m, d.amplitude_m, Bound::Closed(0.0), 0.3)?;
    let amplitude_deg = float_in("robot.amplitude_deg", r.amplitude_deg, d.amplitude_deg, Bound::Closed(0.0), 45.0)?;
    Ok(RobotConfig { motion, omega_rad_s, amplitude_m, amplitude_deg })
}

/// The places that moved into `[tracker]` and `[start]`: an error naming the new place.
pub(super) fn refuse_old_keys(r: &RawScenario) -> Result<()> {
    let moved = [
        ("method", r.method.is_some(), "moved to [tracker] method"),
        ("ga", r.ga.is_some(), "moved to [tracker] ga.* (e.g. ga.population)"),
        ("target_filter", r.target_filter.is_some(), "moved to [tracker] target.* (e.g. target.acceleration_m_s2)"),
    ];
    if let Some((key, _, to)) = moved.iter().find(|(_, given, _)| *given) {
        return Err(invalid(*key, *to));
    }
    let tracker = r.tracker.as_ref().and_then(|t| t.as_table());
    match ["initial", "delay_s"].iter().find(|k| tracker.is_some_and(|t| t.contains_key(**k))) {
        Some(k) => Err(invalid(format!("tracker.{k}"), format!("moved to [start] {k}"))),
        None => Ok(()),
    }
}

pub(super) fn parse_servo(r: Option<RawServo>) -> Result<Option<ServoSection>> {
    let Some(r) = r else { return Ok(None) };
    let Some(desired_t_m) = r.desired_t_m.map(|f| f.0) else { return Err(missing("servo.desired_t_m")) };
    let t_field = "servo.desired_t_m";
    check_range_why(&format!("{t_field}[0]"), desired_t_m[0].abs(), Bound::Closed(0.0), 1.0, " (|x|)")?;
    check_range_why(&format!("{t_field}[1]"), desired_t_m[1].abs(), Bound::Closed(0.0), 1.0, " (|y|)")?;
    check_range_why(&format!("{t_field}[2]"), desired_t_m[2], Bound::Open(0.2), 3.0, " (in front of the camera)")?;
    let desired_q_xyzw = match r.desired_q_xyzw {
        None => None,
        Some(Floats(q)) => {
            let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            if !n.is_finite() || (n - 1.0).abs() > 1e-3 {
                return Err(invalid("servo.desired_q_xyzw", format!("must be a unit quaternion, got norm {n}")));
            }
            Some(q.map(|x| x / n))
        }
    };
    let d = ServoSection::new(desired_t_m);
    let gain = float_in("servo.gain", r.gain, d.gain, Bound::Open(0.0), 50.0)?;
    let max_speed_m_s = float_in("servo.max_speed_m_s", r.max_speed_m_s, d.max_speed_m_s, Bound::Open(0.0), 2.0)?;
    let max_rot_speed_rad_s =
        float_in("servo.max_rot_speed_rad_s", r.max_rot_speed_rad_s, d.max_rot_speed_rad_s, Bound::Open(0.0), 5.0)?;
    let max_accel_m_s2 = float_in("servo.max_accel_m_s2", r.max_accel_m_s2, d.max_accel_m_s2, Bound::Open(0.0), 20.0)?;
    let max_rot_accel_rad_s2 =
        float_in("servo.max_rot_accel_rad_s2", r.max_rot_accel_rad_s2, d.max_rot_accel_rad_s2, Bound::Open(0.0), 50.0)?;
    let delay_frames = int_in("servo.delay_frames", r.delay_frames, i64::from(d.delay_frames), 0, 10)? as u32;
    Ok(Some(ServoSection {
        desired_t_m,
        desired_q_xyzw,
        gain,
        max_speed_m_s,
        max_rot_speed_rad_s,
        max_accel_m_s2,
        max_rot_accel_rad_s2,
        delay_frames,
    }))
}
