//! The hand-written walk of a scenario file's `[camera]`, `[target]`, `[robot]` and `[servo]`
//! tables: each key checked against its range, named in every error.

use super::*;

pub(super) fn parse_camera(s: &Section<'_>) -> Result<CameraConfig> {
    s.check_keys(&["width", "height", "fx", "fy", "cx", "cy", "baseline_m", "noise_std", "supersample"])?;
    let d = CameraConfig::default();
    let width = s.int_in("width", i64::from(d.width), 16, 4096)?;
    let height = s.int_in("height", i64::from(d.height), 16, 4096)?;
    let fx = s.float_in("fx", d.fx, Bound::Open(0.0), 1e5)?;
    let fy = s.float_in("fy", d.fy, Bound::Open(0.0), 1e5)?;
    let cx = s.float("cx", Some(d.cx))?;
    check_range_why(&s.path("cx"), cx, Bound::Closed(0.0), width as f64, " (inside the image width)")?;
    let cy = s.float("cy", Some(d.cy))?;
    check_range_why(&s.path("cy"), cy, Bound::Closed(0.0), height as f64, " (inside the image height)")?;
    let baseline_m = s.float_in("baseline_m", d.baseline_m, Bound::Open(0.0), 1.0)?;
    let noise_std = s.float_in("noise_std", d.noise_std, Bound::Closed(0.0), 100.0)?;
    let supersample = s.int_in("supersample", i64::from(d.supersample), 1, 8)?;
    let samples = (width * height * supersample * supersample) as u64;
    if samples > MAX_SAMPLES_PER_IMAGE {
        return Err(invalid(
            s.path("supersample"),
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

pub(super) fn parse_target(s: &Section<'_>) -> Result<TargetConfig> {
    s.check_keys(&[
        "size_m",
        "face_hues_deg",
        "distance_m",
        "amplitude_deg",
        "omega_rad_s",
        "yaw0_deg",
        "placement",
        "conveyor_speed_m_s",
        "conveyor_travel_m",
        "conveyor_accel_m_s2",
        "conveyor_dwell_s",
        "conveyor_direction",
        "conveyor_direction_frame",
        "conveyor_start",
        "random_amplitude_m",
        "random_amplitude_deg",
        "random_omega_rad_s",
    ])?;
    let d = TargetConfig::default();
    let size_m: [f64; 3] = s.floats("size_m", d.size_m)?;
    for (i, x) in size_m.iter().enumerate() {
        check_range(&format!("{}[{i}]", s.path("size_m")), *x, Bound::Open(0.0), 2.0)?;
    }
    let face_hues_deg: [f64; 6] = s.floats("face_hues_deg", d.face_hues_deg)?;
    for (i, h) in face_hues_deg.iter().enumerate() {
        let field = format!("{}[{i}]", s.path("face_hues_deg"));
        if !h.is_finite() || *h < 0.0 || *h >= 360.0 {
            return Err(invalid(field, format!("must be in [0, 360), got {h}")));
        }
    }
    let distance_m = s.float_in("distance_m", d.distance_m, Bound::Open(0.0), 5.0)?;
    let half_diagonal = 0.5 * size_m.iter().map(|x| x * x).sum::<f64>().sqrt();
    if distance_m <= half_diagonal + 0.05 {
        return Err(invalid(
            s.path("distance_m"),
            format!(
                "must exceed the block's half diagonal plus 0.05 m ({:.4} m), got {distance_m}",
                half_diagonal + 0.05
            ),
        ));
    }
    let amplitude_deg = s.float_in("amplitude_deg", d.amplitude_deg, Bound::Closed(0.0), 180.0)?;
    let omega_rad_s = s.float_in("omega_rad_s", d.omega_rad_s, Bound::Closed(0.0), 10.0)?;
    let yaw0_deg = s.float_in("yaw0_deg", d.yaw0_deg, Bound::Closed(-180.0), 180.0)?;
    let placement = acquisition::parse_placement(s.get("placement"))?;
    let base = TargetConfig { size_m, face_hues_deg, distance_m, amplitude_deg, omega_rad_s, yaw0_deg, placement, ..d };
    parse_target_path(s, base)
}

/// The `[target]` keys of the block's path ([`crate::sim::target_path`]).
pub(super) fn parse_target_path(s: &Section<'_>, base: TargetConfig) -> Result<TargetConfig> {
    let d = TargetConfig::default();
    let conveyor_speed_m_s = s.float_in("conveyor_speed_m_s", d.conveyor_speed_m_s, Bound::Closed(0.0), 0.3)?;
    if conveyor_speed_m_s != 0.0 && conveyor_speed_m_s < 0.05 {
        return Err(invalid(
            s.path("conveyor_speed_m_s"),
            format!("must be 0 (off) or in [0.05, 0.3], got {conveyor_speed_m_s}"),
        ));
    }
    let conveyor_travel_m = s.float_in("conveyor_travel_m", d.conveyor_travel_m, Bound::Open(0.0), 0.5)?;
    let conveyor_accel_m_s2 = s.float_in("conveyor_accel_m_s2", d.conveyor_accel_m_s2, Bound::Open(0.0), 10.0)?;
    let min_accel = 2.0 * conveyor_speed_m_s * conveyor_speed_m_s / conveyor_travel_m;
    if conveyor_accel_m_s2 < min_accel * (1.0 - 1e-9) {
        return Err(invalid(
            s.path("conveyor_accel_m_s2"),
            format!(
                "must be at least 2·speed²/travel = {min_accel:.4} m/s² to reverse within the travel, got \
                 {conveyor_accel_m_s2}"
            ),
        ));
    }
    let conveyor_dwell_s = s.float_in("conveyor_dwell_s", d.conveyor_dwell_s, Bound::Closed(0.0), 60.0)?;
    let random_amplitude_m = s.float_in("random_amplitude_m", d.random_amplitude_m, Bound::Closed(0.0), 0.1)?;
    let random_amplitude_deg = s.float_in("random_amplitude_deg", d.random_amplitude_deg, Bound::Closed(0.0), 30.0)?;
    let random_omega_rad_s = s.float_in("random_omega_rad_s", d.random_omega_rad_s, Bound::Open(0.0), 2.0)?;
    if conveyor_speed_m_s > 0.0 && random_amplitude_m > 0.0 {
        return Err(invalid(
            s.path("random_amplitude_m"),
            "the block follows one path: set conveyor_speed_m_s or random_amplitude_m to 0",
        ));
    }
    let direction = s.floats("conveyor_direction", d.conveyor_direction)?;
    let conveyor_direction = unit_direction(direction).ok_or_else(|| {
        let [x, y, z] = direction;
        invalid(s.path("conveyor_direction"), format!("must be a finite, non-zero vector, got [{x}, {y}, {z}]"))
    })?;
    let conveyor_direction_frame = match s.string("conveyor_direction_frame", Some("world"))?.as_str() {
        "world" => ConveyorFrame::World,
        "camera" => ConveyorFrame::Camera,
        other => {
            return Err(invalid(
                s.path("conveyor_direction_frame"),
                format!("expected \"world\" or \"camera\", got \"{other}\""),
            ));
        }
    };
    let conveyor_start = match s.string("conveyor_start", Some("rest"))?.as_str() {
        "rest" => ConveyorStart::Rest,
        "moving" => ConveyorStart::Moving,
        other => {
            return Err(invalid(s.path("conveyor_start"), format!("expected \"rest\" or \"moving\", got \"{other}\"")));
        }
    };
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

pub(super) fn parse_robot(s: &Section<'_>) -> Result<RobotConfig> {
    s.check_keys(&["motion", "omega_rad_s", "amplitude_m", "amplitude_deg"])?;
    let d = RobotConfig::default();
    let motion = match s.string("motion", Some(d.motion.as_str()))?.as_str() {
        "static" => MotionKind::Static,
        "A" => MotionKind::A,
        "B" => MotionKind::B,
        other => {
            return Err(invalid(s.path("motion"), format!("expected \"static\", \"A\" or \"B\", got \"{other}\"")));
        }
    };
    let omega_rad_s = s.float_in("omega_rad_s", d.omega_rad_s, Bound::Closed(0.0), 2.0)?;
    let amplitude_m = s.float_in("amplitude_m", d.amplitude_m, Bound::Closed(0.0), 0.3)?;
    let amplitude_deg = s.float_in("amplitude_deg", d.amplitude_deg, Bound::Closed(0.0), 45.0)?;
    Ok(RobotConfig { motion, omega_rad_s, amplitude_m, amplitude_deg })
}

/// The places that moved into `[tracker]` and `[start]`: an error naming the new place.
pub(super) fn refuse_old_keys(table: &Table) -> Result<()> {
    let moved = [
        ("method", "moved to [tracker] method"),
        ("ga", "moved to [tracker] ga.* (e.g. ga.population)"),
        ("target_filter", "moved to [tracker] target.* (e.g. target.acceleration_m_s2)"),
    ];
    if let Some((key, to)) = moved.iter().find(|(k, _)| table.contains_key(*k)) {
        return Err(invalid(*key, *to));
    }
    let tracker = table.get("tracker").and_then(|t| t.as_table());
    match ["initial", "delay_s"].iter().find(|k| tracker.is_some_and(|t| t.contains_key(**k))) {
        Some(k) => Err(invalid(format!("tracker.{k}"), format!("moved to [start] {k}"))),
        None => Ok(()),
    }
}

pub(super) fn parse_servo(s: &Section<'_>) -> Result<Option<ServoSection>> {
    if s.table.is_none() {
        return Ok(None);
    }
    s.check_keys(&[
        "desired_t_m",
        "desired_q_xyzw",
        "gain",
        "max_speed_m_s",
        "max_rot_speed_rad_s",
        "max_accel_m_s2",
        "max_rot_accel_rad_s2",
        "delay_frames",
    ])?;
    if s.get("desired_t_m").is_none() {
        return Err(s.missing("desired_t_m"));
    }
    let desired_t_m: [f64; 3] = s.floats("desired_t_m", [0.0; 3])?;
    let t_field = s.path("desired_t_m");
    check_range_why(&format!("{t_field}[0]"), desired_t_m[0].abs(), Bound::Closed(0.0), 1.0, " (|x|)")?;
    check_range_why(&format!("{t_field}[1]"), desired_t_m[1].abs(), Bound::Closed(0.0), 1.0, " (|y|)")?;
    check_range_why(&format!("{t_field}[2]"), desired_t_m[2], Bound::Open(0.2), 3.0, " (in front of the camera)")?;
    let desired_q_xyzw = match s.get("desired_q_xyzw") {
        None => None,
        Some(_) => {
            let q: [f64; 4] = s.floats("desired_q_xyzw", [0.0; 4])?;
            let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            if !n.is_finite() || (n - 1.0).abs() > 1e-3 {
                return Err(invalid(s.path("desired_q_xyzw"), format!("must be a unit quaternion, got norm {n}")));
            }
            Some(q.map(|x| x / n))
        }
    };
    let d = ServoSection::new(desired_t_m);
    let gain = s.float_in("gain", d.gain, Bound::Open(0.0), 50.0)?;
    let max_speed_m_s = s.float_in("max_speed_m_s", d.max_speed_m_s, Bound::Open(0.0), 2.0)?;
    let max_rot_speed_rad_s = s.float_in("max_rot_speed_rad_s", d.max_rot_speed_rad_s, Bound::Open(0.0), 5.0)?;
    let max_accel_m_s2 = s.float_in("max_accel_m_s2", d.max_accel_m_s2, Bound::Open(0.0), 20.0)?;
    let max_rot_accel_rad_s2 = s.float_in("max_rot_accel_rad_s2", d.max_rot_accel_rad_s2, Bound::Open(0.0), 50.0)?;
    let delay_frames = s.int_in("delay_frames", i64::from(d.delay_frames), 0, 10)? as u32;
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
