//! Experiment geometry and the scripted motions of the flange and of the target.
//!
//! All poses are in the world frame `Σ_W`, which is the PA-10 base frame (`z` up). Time `t` is
//! in seconds from the start of the run.
//!
//! ## Fixed geometry
//! - The right camera `Σ_CR` sits on the flange at `[+baseline/2, 0, 0.05]` m (flange
//!   coordinates) with the flange's orientation, see [`flange_to_camera`].
//! - At `t = 0` the flange is at [`FLANGE_START_M`] with orientation
//!   [`initial_camera_rotation`]: the optical axis looks along world `+x`, tilted down by
//!   [`CAMERA_TILT_DEG`].
//! - The target centre is `c = p_mid0 + d·z_c` ([`target_centre`]): `d` metres along the stereo
//!   rig's eye-line (the optical axis of a camera midway between the two) at `t = 0`.
//!
//! ## Motions
//! - [`MotionKind::Static`]: the flange stays at its initial pose `e0`.
//! - [`MotionKind::A`] (paper eq. 39): `y_d(t) = y_e0 + a·sin(ωt)`, all else constant.
//! - [`MotionKind::B`] (paper eq. 42–47): `θ(t) = −a·sin(ωt)`; the flange orbits the vertical
//!   world axis through `c`: `p_d = c + Rz(θ)(p_e0 − c)`, `R_d = Rz(θ)·R_e0`, so the camera
//!   keeps its distance to `c` and the rig's eye-line keeps passing through `c` (the paper
//!   says the eye-line of `Σ_CR`; with a parallel stereo pair we aim the pair's midline, so
//!   that both cameras keep the target in view).
//! - The target (paper eq. 37–38): `R_WM(t) = Rz(θ_o(t))·Rz(yaw0)·M0`, `θ_o = a_o·sin(ω_o t)`,
//!   where [`target_rest_rotation`] `M0` stands the block upright with its axes along the
//!   untilted camera's (so its pose in `Σ_CR` is a small rotation, as in the paper, and ε
//!   errors read as in the paper: 0.008 ≈ 1°),
//!   centre fixed at `c` ([`TargetMotion`]).
//!
//! `ω = 0` makes every motion static. Twists are analytic derivatives of the poses.

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Downward tilt `φ` of the optical axis at `t = 0` (degrees).
pub const CAMERA_TILT_DEG: f64 = 20.0;

/// Height of the right camera's origin above the flange, along the flange `z` axis (m).
pub const CAMERA_MOUNT_OFFSET_M: f64 = 0.05;

/// `^H T_CR` in f64: the right camera frame is the flange frame translated by
/// `[+baseline/2, 0, 0.05]` m (flange coordinates), with the same orientation (optical axis =
/// flange `z`).
pub fn flange_to_camera_f64(baseline_m: f64) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::new(0.5 * baseline_m, 0.0, CAMERA_MOUNT_OFFSET_M), UnitQuaternion::identity())
}

/// `^H T_CR` as the core's f32 isometry (see [`flange_to_camera_f64`]); pass it to
/// `evorec_core::feedforward` and to the tracker configuration.
pub fn flange_to_camera(baseline_m: f64) -> Isometry3<f32> {
    flange_to_camera_f64(baseline_m).cast::<f32>()
}

/// Flange position `p_e0` at `t = 0` (world, metres).
pub const FLANGE_START_M: [f64; 3] = [0.45, 0.0, 0.75];

/// The initial camera (and flange) orientation `R_WC0`, columns `x_c, y_c, z_c` in world
/// coordinates: `z_c = (cos φ, 0, −sin φ)`, `y_c = (−sin φ, 0, −cos φ)`, `x_c = (0, −1, 0)`.
pub fn initial_camera_rotation() -> Rotation3<f64> {
    let (s, c) = CAMERA_TILT_DEG.to_radians().sin_cos();
    let x = Vector3::new(0.0, -1.0, 0.0);
    let y = Vector3::new(-s, 0.0, -c);
    let z = Vector3::new(c, 0.0, -s);
    Rotation3::from_basis_unchecked(&[x, y, z])
}

/// The flange pose `e0` at `t = 0` (position [`FLANGE_START_M`], orientation
/// [`initial_camera_rotation`], since the camera mount does not rotate).
pub fn initial_flange_pose() -> Isometry3<f64> {
    let [x, y, z] = FLANGE_START_M;
    Isometry3::from_parts(Translation3::new(x, y, z), UnitQuaternion::from_rotation_matrix(&initial_camera_rotation()))
}

/// The right camera's world pose `^W T_CR` at `t = 0`.
pub fn initial_camera_pose(baseline_m: f64) -> Isometry3<f64> {
    initial_flange_pose() * flange_to_camera_f64(baseline_m)
}

/// The target centre `c = p_mid0 + d·z_c`: `d` metres ahead of the midpoint between the two
/// cameras at `t = 0` (the stereo rig's eye-line), so each camera sees it half a baseline off
/// its optical axis and the lateral sway of motion A keeps it inside both images.
pub fn target_centre(baseline_m: f64, distance_m: f64) -> Point3<f64> {
    let cam = initial_camera_pose(baseline_m);
    let (x_c, z_c) = (cam.rotation * Vector3::x(), cam.rotation * Vector3::z());
    Point3::from(cam.translation.vector - x_c * (0.5 * baseline_m) + z_c * distance_m)
}

/// A velocity screw in world coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Twist {
    /// Linear velocity of the reference point (m/s, world frame).
    pub v: Vector3<f64>,
    /// Angular velocity (rad/s, world frame).
    pub w: Vector3<f64>,
}

impl Twist {
    /// No motion.
    pub fn zero() -> Self {
        Self { v: Vector3::zeros(), w: Vector3::zeros() }
    }
}

/// A desired flange pose together with its time derivative.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlangeSetpoint {
    /// Desired flange pose `^W T_H,d(t)`.
    pub pose: Isometry3<f64>,
    /// Desired flange twist (velocity of the flange origin and angular velocity, world).
    pub twist: Twist,
}

/// Which motion the flange performs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum MotionKind {
    /// The flange holds its initial pose.
    #[serde(rename = "static")]
    Static,
    /// Motion A: sinusoidal translation along world `y` (paper eq. 39).
    A,
    /// Motion B: sinusoidal orbit about the vertical axis through the target centre
    /// (paper eq. 42–47).
    B,
}

impl MotionKind {
    /// The spelling used in scenario files: `"static"`, `"A"` or `"B"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Static => "static",
            Self::A => "A",
            Self::B => "B",
        }
    }
}

/// The scripted flange motion, evaluated analytically at any time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlangeTrajectory {
    /// Motion type.
    pub kind: MotionKind,
    /// Flange pose at `t = 0` (`e0`).
    pub start: Isometry3<f64>,
    /// Point on the vertical orbit axis of motion B (the target centre `c`).
    pub orbit_centre: Point3<f64>,
    /// Angular frequency `ω` (rad/s); 0 means static.
    pub omega_rad_s: f64,
    /// Motion A amplitude along world `y` (m).
    pub amplitude_m: f64,
    /// Motion B orbit amplitude (rad).
    pub amplitude_rad: f64,
}

impl FlangeTrajectory {
    /// A flange motion of `kind` starting at [`initial_flange_pose`], orbiting (motion B) the
    /// vertical axis through `orbit_centre`.
    pub fn new(
        kind: MotionKind,
        omega_rad_s: f64,
        amplitude_m: f64,
        amplitude_rad: f64,
        orbit_centre: Point3<f64>,
    ) -> Self {
        Self { kind, start: initial_flange_pose(), orbit_centre, omega_rad_s, amplitude_m, amplitude_rad }
    }

    /// Desired flange pose and twist at time `t` (s).
    pub fn setpoint(&self, t: f64) -> FlangeSetpoint {
        let w = self.omega_rad_s;
        if w == 0.0 {
            return FlangeSetpoint { pose: self.start, twist: Twist::zero() };
        }
        let (s, c) = (w * t).sin_cos();
        match self.kind {
            MotionKind::Static => FlangeSetpoint { pose: self.start, twist: Twist::zero() },
            MotionKind::A => {
                let mut pose = self.start;
                pose.translation.vector.y += self.amplitude_m * s;
                let v = Vector3::new(0.0, self.amplitude_m * w * c, 0.0);
                FlangeSetpoint { pose, twist: Twist { v, w: Vector3::zeros() } }
            }
            MotionKind::B => {
                // Clockwise seen from above while the target's own yaw (eq. 37) starts
                // counter-clockwise: with the same sign and ω = ω_o the two would cancel and the
                // target would stand still in Σ_CR (the paper's results show it does not).
                let theta = -self.amplitude_rad * s;
                let theta_dot = -self.amplitude_rad * w * c;
                let rz = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), theta);
                let arm = rz * (self.start.translation.vector - self.orbit_centre.coords);
                let pose =
                    Isometry3::from_parts(Translation3::from(self.orbit_centre.coords + arm), rz * self.start.rotation);
                let omega = Vector3::new(0.0, 0.0, theta_dot);
                FlangeSetpoint { pose, twist: Twist { v: omega.cross(&arm), w: omega } }
            }
        }
    }
}

/// `M0`: the block's rest orientation in the world. Model axes go to the axes of the camera
/// before its tilt: `x_M → −y_W` (image right), `y_M → −z_W` (image down, so the block's
/// 150 mm edge is vertical), `z_M → +x_W` (away from the camera). At `t = 0` the camera then
/// sees the block's −z face (blue) head-on, its top (−y, green) under the camera's tilt and,
/// with `yaw0`, one ±x side (red), and `^CR Q_M` is within ~20° of the identity.
pub fn target_rest_rotation() -> UnitQuaternion<f64> {
    let m = Matrix3::new(0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, -1.0, 0.0);
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m))
}

/// The target's scripted rotation about the vertical axis through its fixed centre
/// (paper eq. 37–38): `R_WM(t) = Rz(a·sin(ω t))·Rz(yaw0)·M0` ([`target_rest_rotation`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetMotion {
    /// Target centre `c` (world, m), fixed.
    pub centre: Point3<f64>,
    /// Initial yaw `yaw0` about world `z` (rad).
    pub yaw0_rad: f64,
    /// Oscillation amplitude (rad).
    pub amplitude_rad: f64,
    /// Oscillation angular frequency `ω_o` (rad/s); 0 means static.
    pub omega_rad_s: f64,
    /// Orientation before the yaws: [`target_rest_rotation`], or the random pose's.
    pub rest: UnitQuaternion<f64>,
}

impl TargetMotion {
    /// The yaw `θ_o(t)` added to `yaw0` (rad).
    pub fn theta(&self, t: f64) -> f64 {
        self.amplitude_rad * (self.omega_rad_s * t).sin()
    }

    /// `^W T_M(t)`: the target frame (centred on the block) in world coordinates.
    pub fn target_world_pose(&self, t: f64) -> Isometry3<f64> {
        let yaw = self.theta(t) + self.yaw0_rad;
        Isometry3::from_parts(
            Translation3::from(self.centre.coords),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw) * self.rest,
        )
    }

    /// The target's twist at time `t` (velocity of its centre, zero, and angular velocity).
    pub fn target_world_twist(&self, t: f64) -> Twist {
        let rate = self.amplitude_rad * self.omega_rad_s * (self.omega_rad_s * t).cos();
        Twist { v: Vector3::zeros(), w: Vector3::new(0.0, 0.0, rate) }
    }
}

/// The default geometry's trajectory (baseline 0.1 m, 0.7 m, ±0.1 m, ±15°) for tests.
#[cfg(test)]
pub(crate) fn test_trajectory(kind: MotionKind, omega: f64) -> FlangeTrajectory {
    FlangeTrajectory::new(kind, omega, 0.1, 15f64.to_radians(), target_centre(0.1, 0.7))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn traj(kind: MotionKind, omega: f64) -> FlangeTrajectory {
        test_trajectory(kind, omega)
    }

    #[test]
    fn initial_rotation_is_proper_and_matches_spec() {
        let r = initial_camera_rotation().into_inner();
        assert!((r.transpose() * r - nalgebra::Matrix3::identity()).abs().max() < 1e-15);
        assert!((r.determinant() - 1.0).abs() < 1e-15);
        let phi = 20f64.to_radians();
        let z = r.column(2);
        assert!((z[0] - phi.cos()).abs() < 1e-15 && z[1] == 0.0 && (z[2] + phi.sin()).abs() < 1e-15);
    }

    #[test]
    fn target_centre_is_on_the_initial_eye_line() {
        let cam = initial_camera_pose(0.1);
        let c = target_centre(0.1, 0.7);
        let in_cam = cam.inverse_transform_point(&c);
        assert!((in_cam.x + 0.05).abs() < 1e-12 && in_cam.y.abs() < 1e-12);
        assert!((in_cam.z - 0.7).abs() < 1e-12);
        // Right camera origin: p_e0 + b/2·x_c + 0.05·z_c.
        let p = cam.translation.vector;
        let phi = 20f64.to_radians();
        assert!((p - Vector3::new(0.45 + 0.05 * phi.cos(), -0.05, 0.75 - 0.05 * phi.sin())).norm() < 1e-12);
    }

    /// Central finite differences of the pose against the analytic twist.
    fn check_twist(tr: &FlangeTrajectory) {
        let h = 1e-6;
        for k in 0..50 {
            let t = 0.37 * k as f64;
            let sp = tr.setpoint(t);
            let (pp, pm) = (tr.setpoint(t + h).pose, tr.setpoint(t - h).pose);
            let v = (pp.translation.vector - pm.translation.vector) / (2.0 * h);
            let w = (pp.rotation * pm.rotation.inverse()).scaled_axis() / (2.0 * h);
            assert!((v - sp.twist.v).norm() < 1e-7, "v {v} vs {}", sp.twist.v);
            assert!((w - sp.twist.w).norm() < 1e-7, "w {w} vs {}", sp.twist.w);
        }
    }

    #[test]
    fn twists_are_derivatives_of_poses() {
        for kind in [MotionKind::Static, MotionKind::A, MotionKind::B] {
            check_twist(&traj(kind, 1.0));
            check_twist(&traj(kind, 0.125));
        }
    }

    #[test]
    fn motion_a_moves_only_y() {
        let tr = traj(MotionKind::A, 0.5);
        let e0 = initial_flange_pose();
        let t = std::f64::consts::PI; // ωt = π/2
        let sp = tr.setpoint(t);
        let d = sp.pose.translation.vector - e0.translation.vector;
        assert!((d - Vector3::new(0.0, 0.1, 0.0)).norm() < 1e-12);
        assert!(sp.pose.rotation.angle_to(&e0.rotation) < 1e-12);
    }

    #[test]
    fn motion_b_keeps_the_eye_line_on_the_target_centre() {
        let tr = traj(MotionKind::B, 1.0);
        let c = target_centre(0.1, 0.7);
        let mount = flange_to_camera_f64(0.1);
        let mut max_theta: f64 = 0.0;
        for k in 0..200 {
            let t = 0.05 * k as f64;
            let cam = tr.setpoint(t).pose * mount;
            let in_cam = cam.inverse_transform_point(&c);
            assert!((in_cam.x + 0.05).abs() < 1e-12 && in_cam.y.abs() < 1e-12, "t={t}: {in_cam}");
            assert!((in_cam.z - 0.7).abs() < 1e-12);
            let yaw = (cam.rotation * initial_camera_pose(0.1).rotation.inverse()).angle();
            max_theta = max_theta.max(yaw);
        }
        assert!((max_theta - 15f64.to_radians()).abs() < 1e-3);
    }

    #[test]
    fn zero_omega_is_static() {
        for kind in [MotionKind::A, MotionKind::B] {
            let sp = traj(kind, 0.0).setpoint(3.3);
            assert_eq!(sp.pose, initial_flange_pose());
            assert_eq!(sp.twist, Twist::zero());
        }
    }

    #[test]
    fn target_rotates_about_vertical_axis_through_centre() {
        let m = TargetMotion {
            centre: target_centre(0.1, 0.7),
            yaw0_rad: 25f64.to_radians(),
            amplitude_rad: 15f64.to_radians(),
            omega_rad_s: 0.125,
            rest: target_rest_rotation(),
        };
        let rest = target_rest_rotation();
        let p0 = m.target_world_pose(0.0);
        assert!(((p0.rotation * rest.inverse()).angle() - 25f64.to_radians()).abs() < 1e-12);
        let quarter = std::f64::consts::FRAC_PI_2 / 0.125;
        let p1 = m.target_world_pose(quarter);
        let yaw = (p1.rotation * rest.inverse()).scaled_axis();
        assert!((yaw - Vector3::new(0.0, 0.0, 40f64.to_radians())).norm() < 1e-12);
        // The rest orientation maps the model axes as documented.
        assert!((rest * Vector3::x() - Vector3::new(0.0, -1.0, 0.0)).norm() < 1e-12);
        assert!((rest * Vector3::y() - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-12);
        assert!((rest * Vector3::z() - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-12);
        assert_eq!(p1.translation.vector, m.centre.coords);
        let h = 1e-5;
        let w = (m.target_world_pose(1.0 + h).rotation * m.target_world_pose(1.0 - h).rotation.inverse()).scaled_axis()
            / (2.0 * h);
        assert!((w - m.target_world_twist(1.0).w).norm() < 1e-8);
    }
}
