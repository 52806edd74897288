//! PA-10 arm simulation: inverse kinematics for the start pose and a 1 kHz
//! resolved-rate joint controller that tracks a desired flange pose.
//!
//! Joint state is kept in `f64`; the kinematics come from the core's f32 chain
//! ([`PA10`]), called with the state rounded to f32. The linear algebra of the controller
//! (damped pseudo-inverse, null-space projection) is done in `f64`.
//!
//! ## Control law (one step of [`ArmSim::step`])
//! ```text
//! e   = [p_d − p;  θk(R_d Rᵀ)]                       (position, rotation-vector error; world)
//! q̇   = J⁺ (v_d + K e) + (I − J⁺J) q̇₀,   q̇₀ = −k_n ∇H(q)
//! H   = Σ ((q_i − q_mid,i) / (q_max,i − q_min,i))²    (joint-limit avoidance)
//! q  ← clamp(q + q̇ dt, q_min, q_max)
//! ```
//! `J` is the 6×7 geometric Jacobian **at the flange origin**, in base (world) coordinates
//! (`PA10.jacobian_at(q, &Isometry3::identity())`), and `J⁺ = Jᵀ(JJᵀ + λ²I)⁻¹` is damped with
//! a `λ` that grows only near singularities. `q̇` is scaled down uniformly if any joint would
//! exceed its velocity limit. The reported `q̇` is the commanded one, as a real joint
//! controller reports it.

use evorec_core::JointSample;
use evorec_core::kinematics::PA10;
use nalgebra::{Isometry3, Matrix3, Matrix6, SMatrix, SVector, Translation3, UnitQuaternion, Vector3, Vector6};

use crate::sim::motion::{FlangeTrajectory, Twist, flange_to_camera_f64, initial_flange_pose};

/// Number of joints of the PA-10.
pub const DOF: usize = 7;

/// Period of the joint control loop (s).
pub const CONTROL_PERIOD_S: f64 = 0.001;

/// An elbow-bent start guess for [`solve_ik`] near the experiment's start pose: shoulder
/// leaning slightly back, elbow bent ~103°, wrist pitched so the flange `z` looks forward
/// and down, flange rolled by −90°.
pub const IK_SEED: [f64; DOF] = [0.0, -0.3, 0.0, 1.8, 0.0, 0.4, -std::f64::consts::FRAC_PI_2];

/// Joint limits `(q_min, q_max)` of the PA-10 (rad), from the core's chain.
pub fn joint_limits() -> [(f64, f64); DOF] {
    std::array::from_fn(|i| (f64::from(PA10.joints[i].q_min), f64::from(PA10.joints[i].q_max)))
}

/// Flange pose `^W T_H(q)` from the core's forward kinematics.
pub fn forward(q: &[f64; DOF]) -> Isometry3<f64> {
    let (r, p) = PA10.forward_rp(&to_f32(q));
    iso_from_rp(&r.cast::<f64>(), &p.cast::<f64>())
}

fn to_f32(q: &[f64; DOF]) -> [f32; DOF] {
    q.map(|x| x as f32)
}

fn iso_from_rp(r: &Matrix3<f64>, p: &Vector3<f64>) -> Isometry3<f64> {
    let rot = nalgebra::Rotation3::from_matrix(r);
    Isometry3::from_parts(Translation3::from(*p), UnitQuaternion::from_rotation_matrix(&rot))
}

/// A flange pose error, world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseError {
    /// `p_d − p` (m).
    pub position: Vector3<f64>,
    /// Rotation vector `θk` of `R_d Rᵀ` (rad).
    pub rotation: Vector3<f64>,
}

impl PoseError {
    /// Error of the pose `(r, p)` against `desired`. The angle is computed with `atan2`, so it
    /// stays accurate for tiny errors even when `r` is only f32-orthonormal.
    pub fn between(r: &Matrix3<f64>, p: &Vector3<f64>, desired: &Isometry3<f64>) -> Self {
        let rd = desired.rotation.to_rotation_matrix().into_inner();
        let m = rd * r.transpose();
        let s = 0.5 * Vector3::new(m[(2, 1)] - m[(1, 2)], m[(0, 2)] - m[(2, 0)], m[(1, 0)] - m[(0, 1)]);
        let sn = s.norm();
        let angle = sn.atan2(0.5 * (m.trace() - 1.0));
        let rotation = if sn > 1e-300 { s * (angle / sn) } else { Vector3::zeros() };
        Self { position: desired.translation.vector - p, rotation }
    }

    /// `‖position‖` (m).
    pub fn position_norm(&self) -> f64 {
        self.position.norm()
    }

    /// `‖rotation‖`, the rotation angle (rad).
    pub fn rotation_norm(&self) -> f64 {
        self.rotation.norm()
    }

    fn stacked(&self) -> Vector6<f64> {
        let (p, r) = (self.position, self.rotation);
        Vector6::new(p.x, p.y, p.z, r.x, r.y, r.z)
    }
}

/// Controller gains and limits of [`ArmSim`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmGains {
    /// Position feedback gain `K_p` (1/s).
    pub kp_position: f64,
    /// Orientation feedback gain (1/s).
    pub kp_rotation: f64,
    /// Largest damping `λ` of the pseudo-inverse, reached at manipulability 0.
    pub damping_max: f64,
    /// Manipulability `√det(JJᵀ)` below which damping starts.
    pub manipulability_threshold: f64,
    /// Gain `k_n` of the joint-limit-avoidance gradient (rad²/s).
    pub null_space_gain: f64,
    /// Joint velocity limits (rad/s).
    pub qd_max: [f64; DOF],
}

impl Default for ArmGains {
    /// `K = 100/s`, `λ_max = 0.05` below manipulability `0.005`, `k_n = 1`, velocity limits
    /// 1 rad/s (S1, S2) and 2 rad/s (S3 … W2).
    fn default() -> Self {
        Self {
            kp_position: 100.0,
            kp_rotation: 100.0,
            damping_max: 0.05,
            manipulability_threshold: 0.005,
            null_space_gain: 1.0,
            qd_max: [1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 2.0],
        }
    }
}

/// The joint rates `J⁺ v + (I − J⁺J) q̇₀` with the damped pseudo-inverse.
fn resolved_rates(
    j: &SMatrix<f64, 6, DOF>,
    v: &Vector6<f64>,
    qd0: &SVector<f64, DOF>,
    gains: &ArmGains,
) -> SVector<f64, DOF> {
    let jjt: Matrix6<f64> = j * j.transpose();
    // det(JJᵀ) from the Cholesky factor; fall back to heavy damping if it fails.
    let lambda2 = match jjt.cholesky() {
        Some(ch) => {
            let det: f64 = ch.l_dirty().diagonal().iter().map(|d| d * d).product();
            let w = det.max(0.0).sqrt();
            let w0 = gains.manipulability_threshold;
            if w < w0 { (gains.damping_max * (1.0 - w / w0)).powi(2) } else { 0.0 }
        }
        None => gains.damping_max * gains.damping_max,
    };
    let a = jjt + Matrix6::identity() * (lambda2 + 1e-12);
    let rhs = v - j * qd0;
    let y = match a.cholesky() {
        Some(ch) => ch.solve(&rhs),
        None => Vector6::zeros(),
    };
    j.transpose() * y + qd0
}

/// `−k ∇H`, `H = Σ ((q_i − q_mid,i)/(q_max,i − q_min,i))²`.
fn limit_avoidance(q: &[f64; DOF], gain: f64) -> SVector<f64, DOF> {
    let lim = joint_limits();
    SVector::from_fn(|i, _| {
        let (lo, hi) = lim[i];
        let range = hi - lo;
        -gain * 2.0 * (q[i] - 0.5 * (lo + hi)) / (range * range)
    })
}

fn clamp_to_limits(q: &mut [f64; DOF]) {
    for (qi, (lo, hi)) in q.iter_mut().zip(joint_limits()) {
        *qi = qi.clamp(lo, hi);
    }
}

/// Jacobian at the flange origin, flange rotation and position, all f64.
fn jacobian_f64(q: &[f64; DOF]) -> (SMatrix<f64, 6, DOF>, Matrix3<f64>, Vector3<f64>) {
    let (j, r, p) = PA10.jacobian_at(&to_f32(q), &Isometry3::identity());
    (j.cast::<f64>(), r.cast::<f64>(), p.cast::<f64>())
}

/// Why [`solve_ik`] failed.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("inverse kinematics did not converge: residual {position_m:.3e} m, {rotation_rad:.3e} rad")]
pub struct IkError {
    /// Remaining position error (m).
    pub position_m: f64,
    /// Remaining rotation error (rad).
    pub rotation_rad: f64,
}

/// Residual accepted by [`solve_ik`] (m and rad); about what f32 forward kinematics resolves.
pub const IK_TOLERANCE: f64 = 1e-6;

/// Inverse kinematics of the flange pose `target` by damped least-squares (Newton) steps from
/// `seed`, with joint-limit avoidance in the null space and every iterate clamped into the
/// joint limits. Returns the best iterate once its residual is below [`IK_TOLERANCE`].
///
/// # Errors
/// [`IkError`] with the best residual if no iterate got below [`IK_TOLERANCE`].
pub fn solve_ik(target: &Isometry3<f64>, seed: &[f64; DOF]) -> Result<[f64; DOF], IkError> {
    let gains = ArmGains::default();
    let mut q = *seed;
    clamp_to_limits(&mut q);
    let mut best = (f64::INFINITY, q, IkError { position_m: f64::INFINITY, rotation_rad: f64::INFINITY });
    for iter in 0..2000 {
        let (j, r, p) = jacobian_f64(&q);
        let err = PoseError::between(&r, &p, target);
        let (ep, er) = (err.position_norm(), err.rotation_norm());
        let score = ep.max(er);
        if score < best.0 {
            best = (score, q, IkError { position_m: ep, rotation_rad: er });
        }
        // After a settling phase, stop at convergence.
        if iter > 300 && score < 0.1 * IK_TOLERANCE {
            break;
        }
        // Null-space drift towards mid-range only while far from the last iterations.
        let null_gain = if iter < 1500 { 0.05 } else { 0.0 };
        let mut dq = resolved_rates(&j, &err.stacked(), &limit_avoidance(&q, null_gain), &gains);
        let n = dq.amax();
        if n > 0.2 {
            dq *= 0.2 / n;
        }
        for (qi, d) in q.iter_mut().zip(dq.iter()) {
            *qi += d;
        }
        clamp_to_limits(&mut q);
    }
    if best.0 < IK_TOLERANCE { Ok(best.1) } else { Err(best.2) }
}

/// The joint angles `q0` of the experiment's start pose ([`initial_flange_pose`]), from
/// [`IK_SEED`].
///
/// # Errors
/// [`IkError`] if the inverse kinematics fails (it does not for the fixed geometry).
pub fn initial_joint_angles() -> Result<[f64; DOF], IkError> {
    solve_ik(&initial_flange_pose(), &IK_SEED)
}

/// The simulated PA-10 under resolved-rate flange-pose control.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmSim {
    q: [f64; DOF],
    qd: [f64; DOF],
    time: f64,
    gains: ArmGains,
}

impl ArmSim {
    /// An arm at rest at `q` (clamped into the joint limits), time 0, default gains.
    pub fn new(q: [f64; DOF]) -> Self {
        let mut q = q;
        clamp_to_limits(&mut q);
        Self { q, qd: [0.0; DOF], time: 0.0, gains: ArmGains::default() }
    }

    /// An arm at rest at the experiment's start pose ([`initial_joint_angles`]).
    ///
    /// # Errors
    /// [`IkError`] if the start pose cannot be solved.
    pub fn at_start() -> Result<Self, IkError> {
        Ok(Self::new(initial_joint_angles()?))
    }

    /// Replaces the controller gains.
    pub fn with_gains(mut self, gains: ArmGains) -> Self {
        self.gains = gains;
        self
    }

    /// Controller gains.
    pub fn gains(&self) -> &ArmGains {
        &self.gains
    }

    /// Joint positions (rad).
    pub fn q(&self) -> &[f64; DOF] {
        &self.q
    }

    /// Joint velocities commanded by the last step (rad/s).
    pub fn qd(&self) -> &[f64; DOF] {
        &self.qd
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The joint state as the board would sample it (f32, time in µs).
    pub fn joint_sample(&self) -> JointSample<DOF> {
        JointSample { q: to_f32(&self.q), qd: to_f32(&self.qd), time_us: (self.time * 1e6).round().max(0.0) as u64 }
    }

    /// The flange pose `^W T_H(q)`.
    pub fn flange_pose(&self) -> Isometry3<f64> {
        forward(&self.q)
    }

    /// The right camera's pose `^W T_CR = ^W T_H · ^H T_CR`.
    pub fn camera_pose(&self, baseline_m: f64) -> Isometry3<f64> {
        self.flange_pose() * flange_to_camera_f64(baseline_m)
    }

    /// The flange's error against `desired` at the current joint angles.
    pub fn flange_error(&self, desired: &Isometry3<f64>) -> PoseError {
        let (r, p) = PA10.forward_rp(&to_f32(&self.q));
        PoseError::between(&r.cast::<f64>(), &p.cast::<f64>(), desired)
    }

    /// One control period of `dt` seconds: computes `q̇` from the desired flange pose and twist
    /// (the setpoint at the current [`time`](Self::time), twist in world coordinates at the
    /// flange origin), integrates `q += q̇ dt` (clamped into the joint limits) and advances the
    /// time. See the module documentation for the control law.
    pub fn step(&mut self, dt: f64, desired: &Isometry3<f64>, twist: &Twist) {
        let g = self.gains;
        let (j, r, p) = jacobian_f64(&self.q);
        let err = PoseError::between(&r, &p, desired);
        let v = err.position * g.kp_position + twist.v;
        let w = err.rotation * g.kp_rotation + twist.w;
        let cmd = Vector6::new(v.x, v.y, v.z, w.x, w.y, w.z);
        let mut qd = resolved_rates(&j, &cmd, &limit_avoidance(&self.q, g.null_space_gain), &g);
        let scale = qd.iter().zip(g.qd_max.iter()).map(|(x, m)| x.abs() / m).fold(1.0, f64::max);
        if !scale.is_finite() {
            qd.fill(0.0);
        } else if scale > 1.0 {
            qd /= scale;
        }
        for ((qi, qdi), cmd) in self.q.iter_mut().zip(self.qd.iter_mut()).zip(qd.iter()) {
            *qdi = *cmd;
            *qi += cmd * dt;
        }
        clamp_to_limits(&mut self.q);
        self.time += dt;
    }

    /// [`step`](Self::step) towards `trajectory`'s setpoint at the current time.
    pub fn follow(&mut self, dt: f64, trajectory: &FlangeTrajectory) {
        let sp = trajectory.setpoint(self.time);
        self.step(dt, &sp.pose, &sp.twist);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::motion::{MotionKind, flange_to_camera, target_centre};

    fn q0() -> [f64; DOF] {
        match initial_joint_angles() {
            Ok(q) => q,
            Err(e) => unreachable!("{e}"),
        }
    }

    #[test]
    fn ik_reaches_the_start_pose_within_limits_and_away_from_singularity() {
        let q = q0();
        let err = PoseError::between(
            &forward(&q).rotation.to_rotation_matrix().into_inner(),
            &forward(&q).translation.vector,
            &initial_flange_pose(),
        );
        assert!(err.position_norm() < 1e-5, "{err:?}");
        assert!(err.rotation_norm() < 1e-5, "{err:?}");
        // Also through the raw f32 FK.
        let sim = ArmSim::new(q);
        let e2 = sim.flange_error(&initial_flange_pose());
        assert!(e2.position_norm() < 1e-5 && e2.rotation_norm() < 1e-5);
        for (qi, (lo, hi)) in q.iter().zip(joint_limits()) {
            // At least 10° from every limit.
            assert!(*qi > lo + 0.17 && *qi < hi - 0.17, "q = {q:?}");
        }
        let (j, _, _) = jacobian_f64(&q);
        let sv = j.svd(false, false).singular_values;
        assert!(sv.min() > 0.05, "singular values {sv}");
    }

    #[test]
    fn mount_offsets_the_camera_along_flange_axes() {
        let m = flange_to_camera(0.12);
        assert_eq!(m.translation.vector, Vector3::new(0.06f32, 0.0, 0.05));
        assert_eq!(m.rotation, UnitQuaternion::identity());
    }

    fn max_tracking_error(kind: MotionKind, omega: f64, seconds: f64) -> (f64, f64) {
        let traj = crate::sim::motion::test_trajectory(kind, omega);
        let mut sim = ArmSim::new(q0());
        let (mut ep, mut er) = (0.0f64, 0.0f64);
        let steps = (seconds / CONTROL_PERIOD_S).round() as usize;
        for _ in 0..steps {
            sim.follow(CONTROL_PERIOD_S, &traj);
            if sim.time() > 0.1 {
                let e = sim.flange_error(&traj.setpoint(sim.time()).pose);
                ep = ep.max(e.position_norm());
                er = er.max(e.rotation_norm());
            }
        }
        (ep, er)
    }

    #[test]
    fn tracks_motion_a_and_b_within_a_tenth_of_a_millimetre() {
        for kind in [MotionKind::A, MotionKind::B] {
            for omega in [0.125, 1.0] {
                let (ep, er) = max_tracking_error(kind, omega, 10.0);
                assert!(ep < 1e-4 && er < 1e-4, "{kind:?} ω={omega}: {ep:.3e} m, {er:.3e} rad");
            }
        }
    }

    #[test]
    fn static_setpoint_keeps_the_arm_still() {
        let mut sim = ArmSim::new(q0());
        let e0 = initial_flange_pose();
        for _ in 0..1000 {
            sim.step(CONTROL_PERIOD_S, &e0, &Twist::zero());
        }
        let e = sim.flange_error(&e0);
        assert!(e.position_norm() < 1e-5 && e.rotation_norm() < 1e-5);
        assert!((sim.time() - 1.0).abs() < 1e-9);
        assert_eq!(sim.joint_sample().time_us, 1_000_000);
    }

    #[test]
    fn velocity_and_position_limits_hold() {
        let mut sim = ArmSim::new(q0());
        // A far-away, unreachable setpoint drives the arm as hard as it can go.
        let far = Isometry3::translation(3.0, 3.0, 3.0);
        let lim = joint_limits();
        for _ in 0..3000 {
            sim.step(CONTROL_PERIOD_S, &far, &Twist::zero());
            for (i, (qd, m)) in sim.qd().iter().zip(sim.gains().qd_max).enumerate() {
                assert!(qd.abs() <= m + 1e-12, "joint {i}: {qd}");
            }
            for (qi, (lo, hi)) in sim.q().iter().zip(lim) {
                assert!(*qi >= lo && *qi <= hi);
            }
            assert!(sim.q().iter().all(|x| x.is_finite()));
        }
    }

    #[test]
    fn reported_qd_moves_the_flange_with_the_desired_twist() {
        // Camera twist from q̇ through the core's feedforward path agrees with the motion.
        let traj = FlangeTrajectory {
            kind: MotionKind::B,
            start: initial_flange_pose(),
            orbit_centre: target_centre(0.1, 0.7),
            omega_rad_s: 1.0,
            amplitude_m: 0.1,
            amplitude_rad: 15f64.to_radians(),
        };
        let mut sim = ArmSim::new(q0());
        for _ in 0..500 {
            sim.follow(CONTROL_PERIOD_S, &traj);
        }
        let s = sim.joint_sample();
        let (j, _, _) = PA10.jacobian_at(&s.q, &Isometry3::identity());
        let x = j * SVector::<f32, DOF>::from(s.qd);
        let tw = traj.setpoint(sim.time() - CONTROL_PERIOD_S).twist;
        let got = Vector6::new(x[0], x[1], x[2], x[3], x[4], x[5]).cast::<f64>();
        let want = Vector6::new(tw.v.x, tw.v.y, tw.v.z, tw.w.x, tw.w.y, tw.w.z);
        assert!((got - want).norm() < 1e-3, "{got} vs {want}");
    }
}
