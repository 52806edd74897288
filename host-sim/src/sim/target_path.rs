//! The block's own path in the world, beyond the paper's slow yaw oscillation.
//!
//! The paper's target turns about the vertical axis through its fixed centre
//! ([`crate::sim::motion::TargetMotion`]). On top of that, the centre (and the orientation) can
//! follow a [`TargetPath`] (scenario keys `[target] conveyor_*` and `random_*`):
//!
//! - [`TargetPath::Conveyor`]: a part on a conveyor along a unit direction `u` (by default
//!   world `y`, across the view; `[target] conveyor_direction`, given in the world or in the
//!   right camera's frame at `t = 0`), starting at rest at `−u·travel/2`, accelerating to
//!   `speed`, and reversing smoothly at each end (half-cosine velocity profiles with peak
//!   acceleration `accel`), back and forth, so it stays in view; or (`conveyor_start =
//!   "moving"`) already at full speed along `+u` in the middle of its travel at `t = 0`;
//! - [`TargetPath::Random`]: a seeded random smooth motion, each position axis and each angle
//!   a sum of [`RANDOM_COMPONENTS`] sinusoids, zero at `t = 0` (an object in a person's hand).
//!
//! [`target_pose`] and [`target_twist`] combine the paper's motion with the path; twists are
//! analytic derivatives of the poses (checked by finite differences in the tests).

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use crate::sim::motion::{TargetMotion, Twist};
use crate::sim::scenario::{ConveyorFrame, ConveyorStart, Scenario};

/// Number of sinusoids per axis of [`TargetPath::Random`].
pub const RANDOM_COMPONENTS: usize = 3;

/// One sinusoid `a (sin(ω t + φ) − sin φ)` (zero at `t = 0`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sinusoid {
    /// Amplitude.
    pub amplitude: f64,
    /// Angular frequency (rad/s).
    pub omega: f64,
    /// Phase (rad).
    pub phase: f64,
}

impl Sinusoid {
    fn value(&self, t: f64) -> f64 {
        self.amplitude * ((self.omega * t + self.phase).sin() - self.phase.sin())
    }

    fn rate(&self, t: f64) -> f64 {
        self.amplitude * self.omega * (self.omega * t + self.phase).cos()
    }
}

/// The block centre's own path, on top of the paper's yaw oscillation.
// One value per world, copied rarely: the size difference of the variants does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TargetPath {
    /// The centre stays where it is (the paper).
    Fixed,
    /// A conveyor along its [`Conveyor::direction`] (see the module docs).
    Conveyor {
        /// The shuttle.
        conveyor: Conveyor,
        /// The conveyor's own time at `t = 0` (s): 0 starts at rest at the −direction end,
        /// [`Conveyor::middle_time`] in the middle at full speed towards +direction.
        start_s: f64,
    },
    /// A seeded random smooth motion: each position axis and each rotation angle (about world
    /// `z`, then `y`, then `x`) is a sum of [`RANDOM_COMPONENTS`] sinusoids, zero at `t = 0`,
    /// bounded by twice the configured amplitude.
    Random {
        /// Position offsets along world x, y, z (m).
        position: [[Sinusoid; RANDOM_COMPONENTS]; 3],
        /// Angles about world z, y, x (rad).
        angles: [[Sinusoid; RANDOM_COMPONENTS]; 3],
    },
}

/// A conveyor along the unit vector `direction` (world) shuttling back and forth over
/// `travel_m`: straight runs at `speed_m_s`, reversals with half-cosine velocity profiles of
/// peak acceleration `accel_m_s2` (a real shuttle's finite deceleration at each end), and a
/// rest of `dwell_s` at each end (a belt that stops and starts again). Its own clock starts at
/// rest at the `−direction` end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Conveyor {
    /// Direction of travel (world, unit): [`Conveyor::WORLD_Y`] unless configured.
    pub direction: Vector3<f64>,
    /// Speed of the straight runs (m/s).
    pub speed_m_s: f64,
    /// Length of the shuttle (m).
    pub travel_m: f64,
    /// Peak acceleration of the reversals (m/s²).
    pub accel_m_s2: f64,
    /// Rest at each end before the next run (s).
    pub dwell_s: f64,
}

impl Conveyor {
    /// The default direction of travel: world `y` (across the view).
    pub const WORLD_Y: Vector3<f64> = Vector3::new(0.0, 1.0, 0.0);

    /// A conveyor along world `y` ([`Conveyor::WORLD_Y`]).
    pub fn along_world_y(speed_m_s: f64, travel_m: f64, accel_m_s2: f64) -> Self {
        Self { direction: Self::WORLD_Y, speed_m_s, travel_m, accel_m_s2, dwell_s: 0.0 }
    }

    /// `(t_r, d_r, straight, half)`: duration and distance of a whole reversal's half-cosine
    /// (rest → speed takes `t_r/2` over `d_r`), length of the straight run, and the time from
    /// leaving one end to leaving the other (the rest included).
    fn profile(&self) -> (f64, f64, f64, f64) {
        use std::f64::consts::PI;
        let (v, a) = (self.speed_m_s, self.accel_m_s2);
        let t_r = PI * v / a;
        let d_r = v * t_r / PI;
        let straight = (self.travel_m - 2.0 * d_r).max(0.0);
        (t_r, d_r, straight, t_r + straight / v + self.dwell_s)
    }

    /// Position (relative to the shuttle's middle) and velocity along [`Conveyor::direction`]
    /// at the conveyor's own time `t`.
    pub fn state(&self, t: f64) -> (f64, f64) {
        use std::f64::consts::PI;
        let (t_r, d_r, straight, half) = self.profile();
        let v = self.speed_m_s;
        let u = t.rem_euclid(2.0 * half);
        let (s, out) = if u < half { (u, true) } else { (u - half, false) };
        if s < self.dwell_s {
            return if out { (-0.5 * self.travel_m, 0.0) } else { (0.5 * self.travel_m, 0.0) };
        }
        let s = s - self.dwell_s;
        let (y, vy) = if s < 0.5 * t_r {
            (d_r * (1.0 - (PI * s / t_r).cos()), v * (PI * s / t_r).sin())
        } else if s < 0.5 * t_r + straight / v {
            (d_r + v * (s - 0.5 * t_r), v)
        } else {
            let s2 = s - 0.5 * t_r - straight / v;
            (d_r + straight + d_r * (PI * s2 / t_r).sin(), v * (PI * s2 / t_r).cos())
        };
        // Out (0 → travel) and back (travel → 0), centred on the shuttle's middle.
        if out { (y - 0.5 * self.travel_m, vy) } else { (0.5 * self.travel_m - y, -vy) }
    }

    /// Displacement from the shuttle's middle and velocity (world) at the conveyor's own
    /// time `t`: [`Conveyor::state`] along [`Conveyor::direction`].
    pub fn offset(&self, t: f64) -> (Vector3<f64>, Vector3<f64>) {
        let (s, v) = self.state(t);
        (self.direction * s, self.direction * v)
    }

    /// The conveyor's time at which it first passes the middle of its travel (at full speed
    /// towards +direction: on a straight run, or at the peak of the reversals' profile when
    /// the travel has none).
    pub fn middle_time(&self) -> f64 {
        self.dwell_s + 0.5 * (self.profile().3 - self.dwell_s)
    }

    /// Seconds the conveyor has run at constant speed at its own time `t` (0 while it
    /// accelerates or reverses).
    pub fn steady_for(&self, t: f64) -> f64 {
        let (t_r, _, straight, half) = self.profile();
        let s = t.rem_euclid(half) - self.dwell_s - 0.5 * t_r;
        if s >= 0.0 && s < straight / self.speed_m_s { s } else { 0.0 }
    }
}

/// The pose offset of a [`TargetPath`] at one time and its derivative.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathOffset {
    /// Displacement of the centre (world, m).
    pub position: Vector3<f64>,
    /// Its velocity (m/s).
    pub velocity: Vector3<f64>,
    /// Rotation about the centre, applied on the left of the paper's orientation.
    pub rotation: UnitQuaternion<f64>,
    /// Its angular velocity (world, rad/s).
    pub angular_velocity: Vector3<f64>,
}

impl PathOffset {
    /// No offset.
    pub fn none() -> Self {
        Self {
            position: Vector3::zeros(),
            velocity: Vector3::zeros(),
            rotation: UnitQuaternion::identity(),
            angular_velocity: Vector3::zeros(),
        }
    }
}

impl TargetPath {
    /// The path of a scenario's `[target]` (the random one seeded by the scenario's seed).
    /// A conveyor's direction given in the camera frame is turned into the world once, here,
    /// with the right camera's orientation at `t = 0` ([`conveyor_direction_world`]).
    pub fn from_scenario(s: &Scenario) -> Self {
        let t = &s.target;
        if t.conveyor_speed_m_s > 0.0 {
            let conveyor = Conveyor {
                direction: conveyor_direction_world(s),
                speed_m_s: t.conveyor_speed_m_s,
                travel_m: t.conveyor_travel_m,
                accel_m_s2: t.conveyor_accel_m_s2,
                dwell_s: t.conveyor_dwell_s,
            };
            let start_s = match t.conveyor_start {
                ConveyorStart::Rest => 0.0,
                ConveyorStart::Moving => conveyor.middle_time(),
            };
            return Self::Conveyor { conveyor, start_s };
        }
        if t.random_amplitude_m > 0.0 {
            return Self::random(
                s.seed,
                t.random_amplitude_m,
                t.random_amplitude_deg.to_radians(),
                t.random_omega_rad_s,
            );
        }
        Self::Fixed
    }

    /// A random path from `seed`: per axis, the component amplitudes sum to `amplitude_m` (or
    /// `amplitude_rad`), frequencies are uniform in `[0.2, 1]·max_omega`, phases uniform.
    pub fn random(seed: u64, amplitude_m: f64, amplitude_rad: f64, max_omega: f64) -> Self {
        use rand_core::{Rng, SeedableRng};
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x7A26_E70D);
        let mut unit = move || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        let mut axis = |amp: f64| -> [Sinusoid; RANDOM_COMPONENTS] {
            let weights: [f64; RANDOM_COMPONENTS] = core::array::from_fn(|_| 0.2 + unit());
            let total: f64 = weights.iter().sum();
            core::array::from_fn(|i| Sinusoid {
                amplitude: amp * weights[i] / total,
                omega: max_omega * (0.2 + 0.8 * unit()),
                phase: std::f64::consts::TAU * unit(),
            })
        };
        let position = [axis(amplitude_m), axis(amplitude_m), axis(amplitude_m)];
        let angles = [axis(amplitude_rad), axis(amplitude_rad), axis(amplitude_rad)];
        Self::Random { position, angles }
    }

    /// Seconds the block has moved at constant velocity at `t` (only a conveyor's straight
    /// runs count; 0 for every other path, which has none).
    pub fn steady_for(&self, t: f64) -> f64 {
        match *self {
            Self::Conveyor { conveyor, start_s } => conveyor.steady_for(start_s + t),
            Self::Fixed | Self::Random { .. } => 0.0,
        }
    }

    /// The offset at time `t` (s).
    pub fn offset(&self, t: f64) -> PathOffset {
        match *self {
            Self::Fixed => PathOffset::none(),
            Self::Conveyor { conveyor, start_s } => {
                let (position, velocity) = conveyor.offset(start_s + t);
                PathOffset { position, velocity, ..PathOffset::none() }
            }
            Self::Random { position, angles } => random_offset(&position, &angles, t),
        }
    }
}

/// A scenario's `[target] conveyor_direction` in the world (unit): as given with
/// `conveyor_direction_frame = "world"`; with `"camera"`, turned by the right camera's
/// orientation at `t = 0` ([`crate::sim::motion::initial_camera_pose`]; the flange starts there for
/// every motion), so `[0, 0, −1]` runs along its optical axis towards the cameras.
pub fn conveyor_direction_world(s: &Scenario) -> Vector3<f64> {
    let d = Vector3::from(s.target.conveyor_direction);
    match s.target.conveyor_direction_frame {
        ConveyorFrame::World => d,
        ConveyorFrame::Camera => crate::sim::motion::initial_camera_pose(s.camera.baseline_m).rotation * d,
    }
}

fn random_offset(
    position: &[[Sinusoid; RANDOM_COMPONENTS]; 3],
    angles: &[[Sinusoid; RANDOM_COMPONENTS]; 3],
    t: f64,
) -> PathOffset {
    let sum = |c: &[Sinusoid; RANDOM_COMPONENTS]| c.iter().map(|s| s.value(t)).sum::<f64>();
    let rate = |c: &[Sinusoid; RANDOM_COMPONENTS]| c.iter().map(|s| s.rate(t)).sum::<f64>();
    let p = Vector3::new(sum(&position[0]), sum(&position[1]), sum(&position[2]));
    let v = Vector3::new(rate(&position[0]), rate(&position[1]), rate(&position[2]));
    let (a, b, c) = (sum(&angles[0]), sum(&angles[1]), sum(&angles[2]));
    let (ad, bd, cd) = (rate(&angles[0]), rate(&angles[1]), rate(&angles[2]));
    let rz = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a);
    let ry = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), b);
    let rx = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), c);
    let w = Vector3::z() * ad + rz * (Vector3::y() * bd) + rz * ry * (Vector3::x() * cd);
    PathOffset { position: p, velocity: v, rotation: rz * ry * rx, angular_velocity: w }
}

/// `^W T_M(t)` with the block's path: the paper's turning block displaced by the path's offset
/// and turned about its centre by the path's rotation.
pub fn target_pose(motion: &TargetMotion, path: &TargetPath, t: f64) -> Isometry3<f64> {
    let base = motion.target_world_pose(t);
    let off = path.offset(t);
    Isometry3::from_parts(Translation3::from(base.translation.vector + off.position), off.rotation * base.rotation)
}

/// The twist of [`target_pose`] (velocity of the centre and angular velocity, world).
pub fn target_twist(motion: &TargetMotion, path: &TargetPath, t: f64) -> Twist {
    let base = motion.target_world_twist(t);
    let off = path.offset(t);
    Twist { v: base.v + off.velocity, w: off.angular_velocity + off.rotation * base.w }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::motion::{target_centre, target_rest_rotation};

    fn check_path_twist(path: &TargetPath) {
        let m = TargetMotion {
            centre: target_centre(0.1, 0.7),
            yaw0_rad: 25f64.to_radians(),
            amplitude_rad: 15f64.to_radians(),
            omega_rad_s: 0.5,
            rest: target_rest_rotation(),
        };
        let h = 1e-6;
        for k in 0..80 {
            let t = 0.173 * k as f64;
            let tw = target_twist(&m, path, t);
            let (pp, pm) = (target_pose(&m, path, t + h), target_pose(&m, path, t - h));
            let v = (pp.translation.vector - pm.translation.vector) / (2.0 * h);
            let w = (pp.rotation * pm.rotation.inverse()).scaled_axis() / (2.0 * h);
            assert!((v - tw.v).norm() < 1e-6, "t={t}: v {v} vs {}", tw.v);
            assert!((w - tw.w).norm() < 1e-6, "t={t}: w {w} vs {}", tw.w);
        }
    }

    #[test]
    fn target_path_twists_are_derivatives() {
        check_path_twist(&TargetPath::Fixed);
        let c = Conveyor::along_world_y(0.2, 0.2, 0.5);
        check_path_twist(&TargetPath::Conveyor { conveyor: c, start_s: 0.0 });
        check_path_twist(&TargetPath::Conveyor { conveyor: c, start_s: c.middle_time() });
        let c = Conveyor::along_world_y(0.3, 0.2, 0.9);
        check_path_twist(&TargetPath::Conveyor { conveyor: c, start_s: 0.0 });
        // A slanted belt, from rest and already moving; and one with no straight run.
        let slant = Vector3::new(0.6, -0.3, 0.5).normalize();
        let c = Conveyor { direction: slant, ..Conveyor::along_world_y(0.15, 0.25, 0.4) };
        check_path_twist(&TargetPath::Conveyor { conveyor: c, start_s: 0.0 });
        check_path_twist(&TargetPath::Conveyor { conveyor: c, start_s: c.middle_time() });
        let c = Conveyor { direction: -slant, ..Conveyor::along_world_y(0.2, 0.05, 10.0) };
        check_path_twist(&TargetPath::Conveyor { conveyor: c, start_s: c.middle_time() });
        check_path_twist(&TargetPath::random(7, 0.05, 10f64.to_radians(), 1.0));
        // A belt that stops at each end and starts again.
        let c = Conveyor { dwell_s: 0.7, ..Conveyor::along_world_y(0.2, 0.3, 1.6) };
        check_path_twist(&TargetPath::Conveyor { conveyor: c, start_s: 0.0 });
        check_path_twist(&TargetPath::Conveyor { conveyor: c, start_s: c.middle_time() });
    }

    #[test]
    fn conveyor_with_a_dwell_rests_at_each_end_then_starts_within_its_acceleration() {
        // 0.2 m/s reached within 0.2 s (peak 1.6 m/s², half-cosine of π·0.2/1.6 = 0.39 s).
        let c = Conveyor { dwell_s: 1.0, ..Conveyor::along_world_y(0.2, 0.3, 1.6) };
        let path = TargetPath::Conveyor { conveyor: c, start_s: 0.0 };
        let (mut rest, mut lo, mut hi) = (0usize, 0.0f64, 0.0f64);
        let dt = 1e-3;
        // Two round trips: four rests of 1 s each.
        let period = 2.0 * c.profile().3;
        let n = (2.0 * period / dt) as usize;
        for k in 0..n {
            let o = path.offset(k as f64 * dt);
            rest += usize::from(o.velocity.y == 0.0);
            lo = lo.min(o.position.y);
            hi = hi.max(o.position.y);
        }
        assert!((rest as f64 * dt - 4.0).abs() < 0.01, "rested {} s", rest as f64 * dt);
        assert!((lo + 0.15).abs() < 1e-9 && (hi - 0.15).abs() < 1e-6, "{lo}..{hi}");
        let o = path.offset(1.0 + 0.2);
        assert!(o.velocity.y > 0.19, "0.2 s after the start: {} m/s", o.velocity.y);
        // The middle of the travel is passed at full speed.
        let m = TargetPath::Conveyor { conveyor: c, start_s: c.middle_time() }.offset(0.0);
        assert!(m.position.y.abs() < 1e-9 && (m.velocity.y - 0.2).abs() < 1e-9, "{m:?}");
    }

    #[test]
    fn conveyor_moves_along_its_direction_only() {
        let u = Vector3::new(1.0, 2.0, -2.0) / 3.0;
        let c = Conveyor { direction: u, ..Conveyor::along_world_y(0.1, 0.2, 0.5) };
        let path = TargetPath::Conveyor { conveyor: c, start_s: c.middle_time() };
        for k in 0..400 {
            let t = 0.05 * k as f64;
            let o = path.offset(t);
            let (s, v) = c.state(c.middle_time() + t);
            assert!((o.position - u * s).norm() < 1e-15 && (o.velocity - u * v).norm() < 1e-15, "t={t}");
            assert!(o.position.cross(&u).norm() < 1e-15 && o.velocity.cross(&u).norm() < 1e-15);
            assert!(o.position.norm() <= 0.1 + 1e-12);
        }
        // Moving start: in the middle, at full speed along +u.
        let o = path.offset(0.0);
        assert!(o.position.norm() < 1e-12 && (o.velocity - 0.1 * u).norm() < 1e-12, "{o:?}");
        // At rest: at the −u end, still.
        let o = TargetPath::Conveyor { conveyor: c, start_s: 0.0 }.offset(0.0);
        assert!((o.position + 0.1 * u).norm() < 1e-12 && o.velocity == Vector3::zeros(), "{o:?}");
    }

    #[test]
    fn scenario_sets_the_conveyor_s_direction_frame_and_start() {
        use crate::sim::scenario::{ConveyorFrame, ConveyorStart};
        use evorec_core::tuning::Feedforward;
        let mut s = Scenario::new(1, 10.0, Feedforward::OnWithTarget);
        s.target.conveyor_speed_m_s = 0.1;
        let Some((c, start)) = conveyor_of(&TargetPath::from_scenario(&s)) else { unreachable!() };
        assert_eq!((c.direction, start), (Conveyor::WORLD_Y, 0.0));
        s.target.conveyor_start = ConveyorStart::Moving;
        s.target.conveyor_direction = [0.0, 0.0, -1.0];
        s.target.conveyor_direction_frame = ConveyorFrame::Camera;
        let Some((c, start)) = conveyor_of(&TargetPath::from_scenario(&s)) else { unreachable!() };
        assert_eq!(start, c.middle_time());
        // Towards the right camera along its optical axis at t = 0.
        let cam = crate::sim::motion::initial_camera_pose(s.camera.baseline_m);
        assert!((c.direction + cam.rotation * Vector3::z()).norm() < 1e-15, "{}", c.direction);
        let tilt = crate::sim::motion::CAMERA_TILT_DEG.to_radians();
        assert!((c.direction - Vector3::new(-tilt.cos(), 0.0, tilt.sin())).norm() < 1e-15);
        // The same direction given in the world.
        s.target.conveyor_direction_frame = ConveyorFrame::World;
        let Some((c, _)) = conveyor_of(&TargetPath::from_scenario(&s)) else { unreachable!() };
        assert_eq!(c.direction, Vector3::new(0.0, 0.0, -1.0));
    }

    fn conveyor_of(path: &TargetPath) -> Option<(Conveyor, f64)> {
        match *path {
            TargetPath::Conveyor { conveyor, start_s } => Some((conveyor, start_s)),
            _ => None,
        }
    }

    #[test]
    fn conveyor_shuttles_within_its_travel_at_its_speed() {
        let conveyor = Conveyor::along_world_y(0.2, 0.2, 0.5);
        let path = TargetPath::Conveyor { conveyor, start_s: 0.0 };
        let (mut lo, mut hi, mut vmax, mut amax): (f64, f64, f64, f64) = (0.0, 0.0, 0.0, 0.0);
        let dt = 1e-3;
        for k in 0..20_000 {
            let t = k as f64 * dt;
            let o = path.offset(t);
            assert_eq!((o.position.x, o.position.z, o.velocity.x), (0.0, 0.0, 0.0));
            lo = lo.min(o.position.y);
            hi = hi.max(o.position.y);
            vmax = vmax.max(o.velocity.y.abs());
            amax = amax.max((path.offset(t + dt).velocity.y - o.velocity.y).abs() / dt);
        }
        assert!((lo + 0.1).abs() < 1e-9 && (hi - 0.1).abs() < 1e-6, "{lo}..{hi}");
        assert!((vmax - 0.2).abs() < 1e-9);
        assert!(amax <= 0.5 + 1e-3, "peak acceleration {amax}");
        let o = path.offset(0.0);
        assert!((o.position.y + 0.1).abs() < 1e-12 && o.velocity.y == 0.0, "starts at rest at one end");
    }

    #[test]
    fn conveyor_started_in_the_middle_runs_steadily_until_its_reversal() {
        // 1 m of travel at 0.2 m/s, reversing at 0.5 m/s²: 0.08 m to stop, 4.2 s of straight run.
        let c = Conveyor::along_world_y(0.2, 1.0, 0.5);
        let path = TargetPath::Conveyor { conveyor: c, start_s: c.middle_time() };
        let o = path.offset(0.0);
        assert!(o.position.y.abs() < 1e-12 && (o.velocity.y - 0.2).abs() < 1e-12, "{o:?}");
        let straight_s = (1.0 - 2.0 * 0.08) / 0.2;
        assert!((path.steady_for(0.0) - 0.5 * straight_s).abs() < 1e-9);
        assert!((path.steady_for(1.0) - 0.5 * straight_s - 1.0).abs() < 1e-9);
        // Reversing at the +y end: not steady, slower; steady again on the way back.
        let end = 0.5 * straight_s + 0.5 * std::f64::consts::PI * 0.2 / 0.5;
        assert_eq!(path.steady_for(end), 0.0);
        assert!(path.offset(end).velocity.y.abs() < 1e-9 && (path.offset(end).position.y - 0.5).abs() < 1e-9);
        let back = end + 0.5 * std::f64::consts::PI * 0.2 / 0.5 + 0.3;
        assert!((path.steady_for(back) - 0.3).abs() < 1e-9 && (path.offset(back).velocity.y + 0.2).abs() < 1e-9);
        assert_eq!(TargetPath::Fixed.steady_for(3.0), 0.0);
    }

    #[test]
    fn random_path_is_seeded_bounded_and_starts_at_rest_pose() {
        let a = TargetPath::random(3, 0.05, 0.2, 1.0);
        assert_eq!(a, TargetPath::random(3, 0.05, 0.2, 1.0));
        assert_ne!(a, TargetPath::random(4, 0.05, 0.2, 1.0));
        let o = a.offset(0.0);
        assert!(o.position.norm() < 1e-15 && o.rotation.angle() < 1e-15);
        for k in 0..2000 {
            let o = a.offset(0.05 * k as f64);
            assert!(o.position.iter().all(|p| p.abs() <= 0.1 + 1e-12));
        }
    }
}
