//! Motion feedforward (paper §3, eq. 15–25, 36).
//!
//! With the cameras on the arm, a static target appears to move in `Σ_CR` whenever the arm
//! moves. For joint velocities `q̇` the apparent pose velocity is `^CR ψ̇ = J_m(q) q̇`
//! (eq. 24, the target's own motion `J_n ^W ψ̇_M` is not predicted), and every GA individual
//! is moved by `ψ̇ Δt` before it is evaluated on the next frame (eq. 25, 36).
//!
//! Derivation used here (equivalent to eq. 23, with the Jacobian taken at the camera origin
//! rather than assuming `Σ_H = Σ_CR`): with `v`, `ω` the camera's linear and angular velocity
//! expressed in `Σ_CR`,
//!
//! ```text
//! ṙ = −v − ω × r                 (r = ^CR r_CR,M; eq. 16 with ^W ṙ_M = 0)
//! ε̇ = ½ (η I − S(ε)) (−ω)         (eq. 19 with ^CR ω_CR,M = −ω; eq. 18)
//! ```
//!
//! and `v = ^CR R_W J_p q̇`, `ω = ^CR R_W J_o q̇` (eq. 20–22). [`psi_rate`] evaluates this per
//! individual from one [`CameraTwist`] per frame; [`jm`] builds the 6×DOF matrix itself.
//!
//! ## The target's own motion (eq. 23's `J_n` term)
//! A target whose centre moves with `^W ṙ_M` and which turns with `^W ω_M` (both in the world,
//! estimated by [`crate::target_motion::TargetFilter`]) adds, with `v_M = ^CR R_W ^W ṙ_M` and
//! `ω_M = ^CR R_W ^W ω_M` ([`TargetTwist`]),
//!
//! ```text
//! ṙ = −v − ω × r + v_M
//! ε̇ = ½ (η I − S(ε)) (ω_M − ω)
//! ```
//!
//! i.e. `J_n = diag(^CR R_W, ½ (η I − S(ε)) ^CR R_W)` acting on `[^W ṙ_M; ^W ω_M]` ([`jn`]).
//! The paper writes the lower block as `^CR R_W` acting on `^W ε̇_M`; that holds only for a
//! target frame aligned with the world, so the angular velocity is used here (eq. 18–19).
//! [`psi_rate_moving`] evaluates `J_m q̇ + J_n ^W ψ̇_M` per individual.

use nalgebra::{Isometry3, Matrix3, SMatrix, SVector, Vector3};

use crate::kinematics::Chain;
use crate::pose::Psi;
use crate::quat::skew;
use crate::target_motion::TargetVelocity;

/// The camera's velocity, expressed in `Σ_CR`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraTwist {
    /// Linear velocity of the camera origin (m/s).
    pub v: Vector3<f32>,
    /// Angular velocity (rad/s).
    pub w: Vector3<f32>,
}

impl CameraTwist {
    /// No motion.
    pub const ZERO: CameraTwist = CameraTwist { v: Vector3::new(0.0, 0.0, 0.0), w: Vector3::new(0.0, 0.0, 0.0) };
}

/// Camera twist from joint state: `J(q) q̇` at the camera origin, rotated into `Σ_CR`.
/// `flange_to_camera` is `^H T_CR`.
pub fn camera_twist<const DOF: usize>(
    chain: &Chain<DOF>,
    q: &[f32; DOF],
    qd: &[f32; DOF],
    flange_to_camera: &Isometry3<f32>,
) -> CameraTwist {
    let (j, r_wc, _) = chain.jacobian_at(q, flange_to_camera);
    let jqd = j * SVector::<f32, DOF>::from(*qd);
    let r_cw = r_wc.transpose();
    let [vx, vy, vz, wx, wy, wz]: [f32; 6] = jqd.into();
    CameraTwist { v: r_cw * Vector3::new(vx, vy, vz), w: r_cw * Vector3::new(wx, wy, wz) }
}

/// The camera's twist and its world pose from one kinematics pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraMotion {
    /// The camera's velocity in `Σ_CR`.
    pub twist: CameraTwist,
    /// `^W R_CR`.
    pub r_wc: Matrix3<f32>,
    /// `^W r_CR` (m).
    pub p_wc: Vector3<f32>,
}

/// [`camera_twist`] together with the camera's world rotation and position.
pub fn camera_motion<const DOF: usize>(
    chain: &Chain<DOF>,
    q: &[f32; DOF],
    qd: &[f32; DOF],
    flange_to_camera: &Isometry3<f32>,
) -> CameraMotion {
    let (j, r_wc, p_wc) = chain.jacobian_at(q, flange_to_camera);
    let jqd = j * SVector::<f32, DOF>::from(*qd);
    let r_cw = r_wc.transpose();
    let [vx, vy, vz, wx, wy, wz]: [f32; 6] = jqd.into();
    let twist = CameraTwist { v: r_cw * Vector3::new(vx, vy, vz), w: r_cw * Vector3::new(wx, wy, wz) };
    CameraMotion { twist, r_wc, p_wc }
}

/// The target's own velocity expressed in `Σ_CR`: `v_M = ^CR R_W ^W ṙ_M`,
/// `ω_M = ^CR R_W ^W ω_M`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetTwist {
    /// Velocity of the target's centre (m/s, in `Σ_CR`).
    pub v: Vector3<f32>,
    /// Angular velocity of the target (rad/s, in `Σ_CR`).
    pub w: Vector3<f32>,
}

impl TargetTwist {
    /// A target at rest.
    pub const ZERO: TargetTwist = TargetTwist { v: Vector3::new(0.0, 0.0, 0.0), w: Vector3::new(0.0, 0.0, 0.0) };

    /// The world velocity `vel` rotated into `Σ_CR` by `r_cw = ^CR R_W`.
    pub fn from_world(r_cw: &Matrix3<f32>, vel: &TargetVelocity) -> Self {
        Self { v: r_cw * vel.v, w: r_cw * vel.w }
    }
}

/// `^CR ψ̇ = J_m q̇ + J_n ^W ψ̇_M` (eq. 23 in full) of a target at `psi` moving with `target`,
/// seen from a camera moving with `twist`.
pub fn psi_rate_moving(twist: &CameraTwist, target: &TargetTwist, psi: &Psi) -> [f32; 6] {
    let r = psi.translation();
    let rdot = target.v - twist.v - twist.w.cross(&r);
    let eps = psi.eps();
    let omega_rel = target.w - twist.w;
    let edot = (omega_rel * psi.eta() - skew(&eps) * omega_rel) * 0.5;
    [rdot.x, rdot.y, rdot.z, edot.x, edot.y, edot.z]
}

/// The target-motion Jacobian `J_n(q)` of eq. 23 for a target at `psi` in `Σ_CR`, acting on
/// `[^W ṙ_M; ^W ω_M]` (see the module docs), with `r_cw = ^CR R_W(q)`:
///
/// ```text
/// J_n = [ ^CR R_W                 0                 ]
///       [ 0              ½ (η I − S(ε)) ^CR R_W     ]
/// ```
pub fn jn(r_cw: &Matrix3<f32>, psi: &Psi) -> SMatrix<f32, 6, 6> {
    let g: Matrix3<f32> = Matrix3::identity() * psi.eta() - skew(&psi.eps());
    let mut out = SMatrix::<f32, 6, 6>::zeros();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(r_cw);
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(&((g * r_cw) * 0.5));
    out
}

/// `^CR ψ̇` of a static target at `psi` seen from a camera moving with `twist` (eq. 24).
pub fn psi_rate(twist: &CameraTwist, psi: &Psi) -> [f32; 6] {
    let r = psi.translation();
    let rdot = -twist.v - twist.w.cross(&r);
    let eps = psi.eps();
    let omega_rel = -twist.w;
    let edot = (omega_rel * psi.eta() - skew(&eps) * omega_rel) * 0.5;
    [rdot.x, rdot.y, rdot.z, edot.x, edot.y, edot.z]
}

/// The motion-feedforward Jacobian `J_m(q)` of eq. 23 for a target at `psi` in `Σ_CR`:
///
/// ```text
/// J_m = [ −^CR R_W J_p + S(r) ^CR R_W J_o      ]
///       [ −½ (η I − S(ε)) ^CR R_W J_o          ]
/// ```
/// with `J_p` taken at the camera origin.
pub fn jm<const DOF: usize>(
    chain: &Chain<DOF>,
    q: &[f32; DOF],
    flange_to_camera: &Isometry3<f32>,
    psi: &Psi,
) -> SMatrix<f32, 6, DOF> {
    let (j, r_wc, _) = chain.jacobian_at(q, flange_to_camera);
    let r_cw = r_wc.transpose();
    let jp = r_cw * j.fixed_rows::<3>(0);
    let jo = r_cw * j.fixed_rows::<3>(3);
    let top = -jp + skew(&psi.translation()) * jo;
    let g: Matrix3<f32> = Matrix3::identity() * psi.eta() - skew(&psi.eps());
    let bottom = -(g * jo) * 0.5;
    let mut out = SMatrix::<f32, 6, DOF>::zeros();
    out.fixed_rows_mut::<3>(0).copy_from(&top);
    out.fixed_rows_mut::<3>(3).copy_from(&bottom);
    out
}

/// `ψ + ψ̇ Δt` (eq. 25). The caller clamps the result into its search space.
pub fn shift(psi: &mut Psi, rate: &[f32; 6], dt_s: f32) {
    for (x, r) in psi.0.iter_mut().zip(rate.iter()) {
        *x += r * dt_s;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::PA10;
    use crate::quat;
    use nalgebra::Translation3;

    fn flange_to_camera() -> Isometry3<f32> {
        Isometry3::from_parts(
            Translation3::new(0.05, 0.0, 0.06),
            quat::from_angle_axis(0.1, &Vector3::new(0.0, 1.0, 0.2)).unwrap(),
        )
    }

    /// `^CR ψ_M(q)` of a target fixed in the world, computed in f64-free but direct form.
    fn psi_of(q: &[f32; 7], world_target: &Isometry3<f32>) -> Psi {
        let cam = PA10.forward(q) * flange_to_camera();
        Psi::from_isometry(&(cam.inverse() * world_target))
    }

    #[test]
    fn jm_matches_finite_differences_of_the_camera_frame_pose() {
        let configs: [[f32; 7]; 3] = [
            [0.1, -0.4, 0.3, 1.2, -0.5, 0.7, 0.2],
            [-1.0, 0.6, -0.8, -1.4, 2.0, -1.1, 3.0],
            [0.0, 0.5, 0.0, 1.3, 0.0, 0.6, 0.0],
        ];
        let qd: [f32; 7] = [0.3, -0.2, 0.5, 0.1, -0.4, 0.25, 0.6];
        for q in &configs {
            // A target 0.7 m in front of the camera, rotated.
            let cam = PA10.forward(q) * flange_to_camera();
            let target = cam
                * Isometry3::from_parts(
                    Translation3::new(0.05, -0.03, 0.7),
                    quat::from_angle_axis(0.5, &Vector3::new(0.2, 1.0, -0.3)).unwrap(),
                );
            let psi = psi_of(q, &target);
            let h = 1e-3f32;
            let qp: [f32; 7] = core::array::from_fn(|i| q[i] + h * qd[i]);
            let qm: [f32; 7] = core::array::from_fn(|i| q[i] - h * qd[i]);
            let (pp, pm) = (psi_of(&qp, &target), psi_of(&qm, &target));
            let fd: [f32; 6] = core::array::from_fn(|i| (pp.0[i] - pm.0[i]) / (2.0 * h));
            let analytic = jm(&PA10, q, &flange_to_camera(), &psi) * SVector::<f32, 7>::from(qd);
            let twist = camera_twist(&PA10, q, &qd, &flange_to_camera());
            let per_individual = psi_rate(&twist, &psi);
            for i in 0..6 {
                let tol = if i < 3 { 5e-3 } else { 3e-3 };
                assert!((analytic[i] - fd[i]).abs() < tol, "J_m q̇ [{i}] {} vs fd {}", analytic[i], fd[i]);
                assert!((per_individual[i] - analytic[i]).abs() < 1e-5, "psi_rate [{i}]");
            }
        }
    }

    #[test]
    fn jn_matches_finite_differences_of_a_moving_target() {
        let q: [f32; 7] = [0.1, -0.4, 0.3, 1.2, -0.5, 0.7, 0.2];
        let qd: [f32; 7] = [0.3, -0.2, 0.5, 0.1, -0.4, 0.25, 0.6];
        let (v, w) = (Vector3::new(0.15, -0.3, 0.05), Vector3::new(0.2, -0.4, 0.9));
        let cam = PA10.forward(&q) * flange_to_camera();
        let target0 = cam
            * Isometry3::from_parts(
                Translation3::new(0.05, -0.03, 0.7),
                quat::from_angle_axis(0.5, &Vector3::new(0.2, 1.0, -0.3)).unwrap(),
            );
        // The target at time h: centre moved by v h, turned by ω h about its centre (world).
        let target_at = |h: f32| {
            let turn = quat::from_angle_axis(w.norm() * h, &w).unwrap();
            Isometry3::from_parts(Translation3::from(target0.translation.vector + v * h), turn * target0.rotation)
        };
        let psi = psi_of(&q, &target0);
        let h = 1e-3f32;
        // Camera still: the rate is J_n ^W ψ̇_M alone.
        let (pp, pm) = (psi_of(&q, &target_at(h)), psi_of(&q, &target_at(-h)));
        let fd: [f32; 6] = core::array::from_fn(|i| (pp.0[i] - pm.0[i]) / (2.0 * h));
        let r_cw = quat::to_rotation_matrix(&cam.rotation).transpose();
        let analytic = jn(&r_cw, &psi) * SVector::<f32, 6>::new(v.x, v.y, v.z, w.x, w.y, w.z);
        let vel = TargetVelocity { v, w };
        let still = psi_rate_moving(&CameraTwist::ZERO, &TargetTwist::from_world(&r_cw, &vel), &psi);
        for i in 0..6 {
            assert!((analytic[i] - fd[i]).abs() < 2e-3, "J_n ψ̇ [{i}] {} vs fd {}", analytic[i], fd[i]);
            assert!((still[i] - analytic[i]).abs() < 1e-5, "psi_rate_moving [{i}]");
        }
        // Both moving: J_m q̇ + J_n ψ̇ against finite differences of ψ(q(t), T_M(t)).
        let qp: [f32; 7] = core::array::from_fn(|i| q[i] + h * qd[i]);
        let qm: [f32; 7] = core::array::from_fn(|i| q[i] - h * qd[i]);
        let (pp, pm) = (psi_of(&qp, &target_at(h)), psi_of(&qm, &target_at(-h)));
        let fd: [f32; 6] = core::array::from_fn(|i| (pp.0[i] - pm.0[i]) / (2.0 * h));
        let motion = camera_motion(&PA10, &q, &qd, &flange_to_camera());
        let target = TargetTwist::from_world(&motion.r_wc.transpose(), &vel);
        let both = psi_rate_moving(&motion.twist, &target, &psi);
        let sum = jm(&PA10, &q, &flange_to_camera(), &psi) * SVector::<f32, 7>::from(qd) + analytic;
        for i in 0..6 {
            let tol = if i < 3 { 5e-3 } else { 3e-3 };
            assert!((both[i] - fd[i]).abs() < tol, "J_m q̇ + J_n ψ̇ [{i}] {} vs fd {}", both[i], fd[i]);
            assert!((both[i] - sum[i]).abs() < 1e-4, "psi_rate_moving vs matrices [{i}]");
        }
        assert_eq!(motion.twist, camera_twist(&PA10, &q, &qd, &flange_to_camera()));
    }

    #[test]
    fn static_arm_gives_no_shift() {
        let twist = camera_twist(&PA10, &[0.2; 7], &[0.0; 7], &Isometry3::identity());
        let mut psi = Psi::new([0.1, 0.0, 0.7], [0.1, 0.0, 0.0]);
        let before = psi;
        let rate = psi_rate(&twist, &psi);
        shift(&mut psi, &rate, 0.033);
        assert_eq!(psi, before);
    }

    #[test]
    fn pure_camera_translation_moves_target_opposite() {
        let twist = CameraTwist { v: Vector3::new(0.1, 0.0, 0.0), w: Vector3::zeros() };
        let rate = psi_rate(&twist, &Psi::new([0.0, 0.0, 0.7], [0.0; 3]));
        assert_eq!(rate, [-0.1, 0.0, 0.0, 0.0, 0.0, 0.0]);
    }
}
