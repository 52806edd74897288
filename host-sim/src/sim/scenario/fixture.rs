//! The small scene the tests share: the arm swaying at the firmware's 160×120 frames.

use super::Scenario;

/// `scenarios/hil_motion_a_ff.toml`: motion A with motion feedforward at the firmware's
/// 160×120 frames, 72 s.
pub const HIL_MOTION_A_FF: &str = include_str!("../../../../scenarios/hil_motion_a_ff.toml");

/// [`HIL_MOTION_A_FF`] cut to `duration_s`.
///
/// # Panics
/// Never for a positive `duration_s` up to 72 s (the file is a valid scenario).
pub fn hil_motion_a_ff(duration_s: f64) -> Scenario {
    let mut s = Scenario::from_toml_str(HIL_MOTION_A_FF).unwrap_or_else(|e| panic!("{e}"));
    s.duration_s = duration_s;
    s
}

/// [`hil_motion_a_ff`] cut to `duration_s`, its arm swaying at `ω = 0.5` rad/s (fast enough for
/// the feedforward to matter within a few seconds): the one short 160×120 scene of the tests
/// that run, export or track a scenario.
///
/// # Panics
/// Never for a positive `duration_s` up to 72 s (the file is a valid scenario).
pub fn sway_160x120(duration_s: f64) -> Scenario {
    let mut s = hil_motion_a_ff(duration_s);
    s.robot.omega_rad_s = 0.5;
    s
}
