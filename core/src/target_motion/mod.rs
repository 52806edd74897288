//! The target's own motion in the world (the `J_n(q) ^W ψ̇_M` term of eq. 23 that the paper
//! leaves out), and the hand-over of a pose to a later time.
//!
//! Every estimate `^CR ψ_M` is taken into the world through the arm's forward kinematics and
//! the hand-eye transform, `^W T_M = ^W T_H(q) · ^H T_CR · ^CR T_M` ([`world_pose`]). A
//! [`TargetFilter`] — a Kalman filter, one independent filter per axis — estimates from that
//! sequence
//!
//! - the linear velocity `^W ṙ_M` of the block's centre (three position axes, each
//!   `[x, ẋ, ẍ]` with white jerk: a block that starts, stops and reverses is followed without
//!   a constant-velocity model's lag), and
//! - the angular velocity `^W ω_M` (three axes of an error state: the orientation is kept as a
//!   unit quaternion, the innovation is the rotation vector `log(Q_meas · Q̂⁻¹)` in `Σ_W`).
//!
//! Work per update is a fixed handful of products (no loops over data), storage is a few
//! dozen floats, and all transcendental functions go through [`crate::math`], so the filter is
//! bit-identical on host and board.
//!
//! The filter **resets** when the tracker loses the target (fitness below
//! [`TargetFilterParams::lost_fitness`]), when time runs backwards or jumps by more than
//! [`TargetFilterParams::max_gap_s`], and after [`TargetFilterParams::max_outliers`]
//! consecutive rejected measurements. A measurement is **rejected** (an outlier) when its
//! innovation on any axis exceeds [`TargetFilterParams::gate_sigma`] standard deviations. The
//! velocity is **trusted** once [`TargetFilterParams::converge_updates`] consecutive updates
//! have been accepted with the velocity's standard deviation below
//! [`TargetFilterParams::trusted_speed_sd_m_s`] and [`TargetFilterParams::trusted_rate_sd_rad_s`]
//! (the bound of a position axis grows with its measurement noise), and stays trusted until the
//! filter restarts or is reset.
//!
//! The tracker feeds it through [`TargetFilter::update_from_estimate`], which knows the camera: stereo
//! depth is far noisier than the position across the view, so a position is weighed with
//! [`TargetFilterParams::depth_noise_m`] along the line of sight and
//! [`TargetFilterParams::position_noise_m`] across it, and the velocity fed forward
//! ([`TargetFilter::feedforward_velocity_seen_along`]) keeps along the line of sight only what
//! the world axes seen across it say (plus [`TargetFilterParams::depth_feedforward`] of the
//! rest).
//!
//! [`TargetFilter::predict`] hands the pose over to a later time `t`: the last accepted
//! measurement moved by the trusted velocity over `t − t_capture`, seen from the camera at the
//! joint state of `t` (`q + q̇ (t − t_joints)`, forward kinematics).

use nalgebra::{Isometry3, Matrix3, Quaternion, Translation3, UnitQuaternion, Vector3};

use crate::kinematics::{Chain, JointSample};
use crate::pose::Psi;
use crate::status::Status;
use crate::{math, quat};

mod angular;
mod axis;
mod params;
mod predict;
use angular::SlowTurn;
use axis::{Axis, PosAxis};
pub use params::{Field, FilterParamsError, TargetFilterParams};
pub use predict::{PredictError, Prediction};

/// The target's velocity screw in the world frame `Σ_W` (`^W ψ̇_M` with the angular part as
/// an angular velocity, see [`crate::feedforward::jn`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetVelocity {
    /// Velocity of the block's centre (m/s, world frame).
    pub v: Vector3<f32>,
    /// Angular velocity of the block (rad/s, world frame).
    pub w: Vector3<f32>,
}

impl TargetVelocity {
    /// A target at rest.
    pub const ZERO: TargetVelocity = TargetVelocity { v: Vector3::new(0.0, 0.0, 0.0), w: Vector3::new(0.0, 0.0, 0.0) };
}

/// What one [`TargetFilter::update`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UpdateOutcome {
    /// The filter (re)started at this measurement (first one, after a reset, a time gap, or
    /// too many outliers).
    Started,
    /// The measurement was accepted.
    Accepted,
    /// The measurement was rejected as an outlier (the prediction was kept).
    Rejected,
    /// The target was lost: the filter was reset and holds no track.
    Lost,
}

/// The filter's state while it holds a track.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Track {
    pos: [PosAxis; 3],
    /// Error-state axes of the orientation (`x` is 0 between updates).
    rot: [Axis; 3],
    orientation: UnitQuaternion<f32>,
    /// The slow angular model (a steady turn).
    slow: SlowTurn,
    time_us: u64,
    /// The last accepted measurement and its time (the base of [`TargetFilter::predict`]).
    last: Isometry3<f32>,
    last_time_us: u64,
    streak: u16,
    outliers: u16,
    /// Set once the track has converged; cleared only by a restart.
    converged: bool,
    /// Set once the converged linear velocity was fed forward with
    /// [`TargetFilterParams::hold_motion`]; cleared only by a restart.
    moving: bool,
}

/// Kalman filter of the target's world pose: constant acceleration per position axis, constant
/// velocity per rotation axis (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetFilter {
    params: TargetFilterParams,
    track: Option<Track>,
    last_outcome: Option<UpdateOutcome>,
    last_innovation: [f32; 6],
}

/// `^W T_M = ^W T_H(q) · ^H T_CR · ^CR T_M(ψ)`: an estimate in the world frame. `psi` must be
/// a valid pose (every GA individual is).
pub fn world_pose<const DOF: usize>(
    chain: &Chain<DOF>,
    q: &[f32; DOF],
    flange_to_camera: &Isometry3<f32>,
    psi: &Psi,
) -> Isometry3<f32> {
    camera_to_world(&(chain.forward(q) * flange_to_camera), psi)
}

/// `^W T_CR · ^CR T_M(ψ)` for a known camera pose.
pub fn camera_to_world(camera: &Isometry3<f32>, psi: &Psi) -> Isometry3<f32> {
    camera * Isometry3::from_parts(Translation3::from(psi.translation()), psi.quaternion_unchecked())
}

/// The rotation `exp(φ)` of rotation vector `φ` (angle `|φ|` about `φ`).
fn exp_rotation(phi: &Vector3<f32>) -> UnitQuaternion<f32> {
    let n2 = phi.dot(phi);
    quat::from_angle_axis(math::sqrt(n2), phi).unwrap_or_else(|_| {
        // |φ| below ~1e-12 (or non-finite, which the callers exclude): first order.
        UnitQuaternion::new_unchecked(Quaternion::new(1.0, 0.5 * phi.x, 0.5 * phi.y, 0.5 * phi.z))
    })
}

/// The rotation vector `log(Q)` of the shortest rotation (`η ≥ 0` representative).
fn log_rotation(q: &UnitQuaternion<f32>) -> Vector3<f32> {
    let c = quat::canonical(q);
    let e = c.imag();
    let n = math::sqrt(e.dot(&e));
    if n < 1e-12 { e * 2.0 } else { e * (2.0 * math::atan2(n, c.w) / n) }
}

impl TargetFilter {
    /// An empty filter (no track).
    ///
    /// # Errors
    /// [`FilterParamsError`] for invalid parameters.
    pub fn new(params: TargetFilterParams) -> Result<Self, FilterParamsError> {
        params.validate()?;
        Ok(Self { params, track: None, last_outcome: None, last_innovation: [0.0; 6] })
    }

    /// An empty filter with [`TargetFilterParams::DEFAULT`].
    pub const fn with_defaults() -> Self {
        Self { params: TargetFilterParams::DEFAULT, track: None, last_outcome: None, last_innovation: [0.0; 6] }
    }

    /// The parameters.
    pub fn params(&self) -> &TargetFilterParams {
        &self.params
    }

    /// Replaces the parameters and forgets the track.
    ///
    /// # Errors
    /// [`FilterParamsError`] for invalid parameters (the filter is then unchanged).
    pub fn set_params(&mut self, params: TargetFilterParams) -> Result<(), FilterParamsError> {
        params.validate()?;
        self.params = params;
        self.track = None;
        Ok(())
    }

    /// Forgets the track (the tracker lost or re-seeded the target).
    pub fn reset(&mut self) {
        self.track = None;
    }

    /// Whether the filter holds a track.
    pub fn has_track(&self) -> bool {
        self.track.is_some()
    }

    /// Feeds one estimate `measured = ^W T_M` captured at `time_us` with fitness `fitness`.
    pub fn update(&mut self, measured: &Isometry3<f32>, time_us: u64, fitness: f32) -> UpdateOutcome {
        let outcome = self.update_inner(measured, time_us, fitness, None);
        self.last_outcome = Some(outcome);
        outcome
    }

    /// As [`TargetFilter::update`] for an estimate the tracker reported with `status`
    /// ([`crate::status`]): an estimate that is not [`Status::Tracking`] is no measurement of
    /// the block (searching, or carried along after the block was lost), so the filter resets.
    pub fn update_with_status(
        &mut self,
        measured: &Isometry3<f32>,
        time_us: u64,
        fitness: f32,
        status: Status,
    ) -> UpdateOutcome {
        if status != Status::Tracking {
            return self.lose();
        }
        self.update(measured, time_us, fitness)
    }

    /// What the last [`TargetFilter::update`] did (`None` before the first).
    pub fn last_outcome(&self) -> Option<UpdateOutcome> {
        self.last_outcome
    }

    /// Innovation of the last update that got as far as the gate: position (m, world) and
    /// rotation vector (rad, world).
    pub fn last_innovation(&self) -> [f32; 6] {
        self.last_innovation
    }

    /// Feeds the tracker's estimate `psi` (`^CR ψ_M`, with its `fitness` and `status`) of the
    /// frame captured with `joints`: the estimate taken into the world through `chain` at
    /// `joints.q` and `flange_to_camera` ([`world_pose`]) at `joints.time_us`. The position is
    /// weighed with [`TargetFilterParams::position_noise_m`] across the camera's line of sight
    /// to the block and [`TargetFilterParams::depth_noise_m`] along it (per world axis
    /// `σ² = σ_across² + (σ_depth² − σ_across²) uᵢ²`, `u` the unit line of sight), otherwise as
    /// [`TargetFilter::update_with_status`]. The tracker feeds its own filter with this call; a
    /// board that receives only the estimates feeds its copy with the same call on the same
    /// numbers, so its predictions are the tracker's.
    pub fn update_from_estimate<const DOF: usize>(
        &mut self,
        chain: &Chain<DOF>,
        flange_to_camera: &Isometry3<f32>,
        joints: &JointSample<DOF>,
        psi: &Psi,
        fitness: f32,
        status: Status,
    ) -> UpdateOutcome {
        if status != Status::Tracking {
            return self.lose();
        }
        let camera = chain.forward(&joints.q) * flange_to_camera;
        let measured = camera_to_world(&camera, psi);
        let los = unit(&(measured.translation.vector - camera.translation.vector));
        let outcome = self.update_inner(&measured, joints.time_us, fitness, los);
        self.last_outcome = Some(outcome);
        outcome
    }

    /// The tracker does not hold the target: forget the track.
    fn lose(&mut self) -> UpdateOutcome {
        self.track = None;
        self.last_outcome = Some(UpdateOutcome::Lost);
        UpdateOutcome::Lost
    }

    fn update_inner(
        &mut self,
        measured: &Isometry3<f32>,
        time_us: u64,
        fitness: f32,
        los: Option<Vector3<f32>>,
    ) -> UpdateOutcome {
        // A fitness drop stands for a lost target here; `update_with_status` also resets on the
        // tracker's status.
        let found = fitness >= self.params.lost_fitness; // false for NaN
        if !found || !finite(measured) {
            self.track = None;
            return UpdateOutcome::Lost;
        }
        let r_pos = self.position_variance(los);
        let Some(track) = self.track.as_mut() else {
            self.start(measured, time_us, los);
            return UpdateOutcome::Started;
        };
        let dt = if time_us >= track.time_us { (time_us - track.time_us) as f32 * 1e-6 } else { -1.0 };
        if !(dt >= 0.0 && dt <= self.params.max_gap_s) {
            self.start(measured, time_us, los);
            return UpdateOutcome::Started;
        }
        let p = &self.params;
        let r_rot = p.rotation_noise_rad * p.rotation_noise_rad;
        let mut predicted = *track;
        predicted.pos.iter_mut().for_each(|a| a.predict(dt, p.acceleration_psd, p.jerk_psd));
        predicted.rot.iter_mut().for_each(|a| a.predict(dt, p.angular_acceleration_psd));
        predicted.slow.predict(dt, p.slow_angular_acceleration_psd);
        let turn = Vector3::new(predicted.rot[0].x, predicted.rot[1].x, predicted.rot[2].x);
        predicted.orientation = exp_rotation(&turn) * predicted.orientation;
        predicted.rot.iter_mut().for_each(|a| a.x = 0.0);
        predicted.time_us = time_us;

        let t = measured.translation.vector;
        let y_pos = [t.x - predicted.pos[0].x, t.y - predicted.pos[1].x, t.z - predicted.pos[2].x];
        let y_rot = log_rotation(&(measured.rotation * predicted.orientation.inverse()));
        self.last_innovation = [y_pos[0], y_pos[1], y_pos[2], y_rot.x, y_rot.y, y_rot.z];
        let inlier =
            predicted.pos.iter().zip(y_pos.iter()).zip(r_pos.iter()).all(|((a, y), r)| a.inlier(*y, *r, p.gate_sigma))
                && predicted.rot.iter().zip(y_rot.iter()).all(|(a, y)| a.inlier(*y, r_rot, p.gate_sigma));
        if !inlier {
            predicted.streak = 0;
            predicted.outliers = predicted.outliers.saturating_add(1);
            if predicted.outliers >= p.max_outliers {
                self.start(measured, time_us, los);
                return UpdateOutcome::Started;
            }
            *track = predicted;
            return UpdateOutcome::Rejected;
        }
        for ((a, y), r) in predicted.pos.iter_mut().zip(y_pos.iter()).zip(r_pos.iter()) {
            a.update(*y, *r);
        }
        for (a, y) in predicted.rot.iter_mut().zip(y_rot.iter()) {
            a.update(*y, r_rot);
        }
        // The slow model is for a turn too slow for the fast one to see: it restarts while the
        // fast model's angular velocity is significant, or the block is poorly seen.
        let fast_turn = Self::significant(p, &angular(&predicted.rot), p.deadband_rad_s) != Vector3::zeros();
        if fitness >= p.slow_min_fitness && !fast_turn {
            predicted.slow.update(&measured.rotation, r_rot);
        } else {
            let w0 = p.initial_rate_sd_rad_s * p.initial_rate_sd_rad_s;
            predicted.slow = SlowTurn::start(measured.rotation, r_rot, w0);
        }
        let correction = Vector3::new(predicted.rot[0].x, predicted.rot[1].x, predicted.rot[2].x);
        predicted.orientation = exp_rotation(&correction) * predicted.orientation;
        predicted.rot.iter_mut().for_each(|a| a.x = 0.0);
        predicted.last = *measured;
        predicted.last_time_us = time_us;
        predicted.streak = predicted.streak.saturating_add(1);
        predicted.outliers = 0;
        let (sv, sw) =
            (p.trusted_speed_sd_m_s * p.trusted_speed_sd_m_s, p.trusted_rate_sd_rad_s * p.trusted_rate_sd_rad_s);
        // An axis along the line of sight is measured worse: its bound grows in proportion.
        let r_across = p.position_noise_m * p.position_noise_m;
        predicted.converged |= predicted.streak >= p.converge_updates
            && predicted.pos.iter().zip(r_pos.iter()).all(|(a, r)| a.var_v() <= sv * (r / r_across))
            && predicted.rot.iter().all(|a| a.p[2] <= sw);
        *track = predicted;
        if p.hold_motion && track.converged && !track.moving {
            track.moving = Self::significant(p, &linear(&track.pos), p.deadband_m_s) != Vector3::zeros();
        }
        UpdateOutcome::Accepted
    }

    /// Variance of a position measurement per world axis for the unit line of sight `los`.
    fn position_variance(&self, los: Option<Vector3<f32>>) -> [f32; 3] {
        let p = &self.params;
        let r_across = p.position_noise_m * p.position_noise_m;
        let r_depth = p.depth_noise_m * p.depth_noise_m - r_across;
        core::array::from_fn(|i| r_across + los.map_or(0.0, |u| r_depth * u[i] * u[i]))
    }

    fn start(&mut self, measured: &Isometry3<f32>, time_us: u64, los: Option<Vector3<f32>>) {
        let r_pos = self.position_variance(los);
        let p = &self.params;
        let r_rot = p.rotation_noise_rad * p.rotation_noise_rad;
        let (v0, w0) =
            (p.initial_speed_sd_m_s * p.initial_speed_sd_m_s, p.initial_rate_sd_rad_s * p.initial_rate_sd_rad_s);
        let a0 = p.initial_accel_sd_m_s2 * p.initial_accel_sd_m_s2;
        let t = measured.translation.vector;
        self.track = Some(Track {
            pos: core::array::from_fn(|i| PosAxis::start(t[i], r_pos[i], v0, a0)),
            rot: [Axis::start(0.0, r_rot, w0); 3],
            orientation: measured.rotation,
            slow: SlowTurn::start(measured.rotation, r_rot, w0),
            time_us,
            last: *measured,
            last_time_us: time_us,
            streak: 0,
            outliers: 0,
            converged: false,
            moving: false,
        });
    }

    /// Whether the velocity has converged (see the module docs).
    /// It stays trusted through single outliers until the filter restarts or is reset.
    pub fn is_trusted(&self) -> bool {
        self.track.as_ref().is_some_and(|t| t.converged)
    }

    /// The estimated `^W ψ̇_M`, whether trusted or not (`None` without a track).
    pub fn velocity_estimate(&self) -> Option<TargetVelocity> {
        self.track.as_ref().map(|t| TargetVelocity { v: linear(&t.pos).0, w: angular(&t.rot).0 })
    }

    /// The trusted velocity, or `None` while the filter has not converged.
    pub fn velocity(&self) -> Option<TargetVelocity> {
        if self.is_trusted() { self.velocity_estimate() } else { None }
    }

    /// The velocity to feed forward: the trusted velocity, its linear (angular) part set to 0
    /// while inside the dead band or not significant against its own uncertainty
    /// ([`TargetFilterParams::significance_sigma`]); zero while not trusted.
    pub fn feedforward_velocity(&self) -> TargetVelocity {
        let Some(track) = self.track.as_ref().filter(|t| t.converged) else { return TargetVelocity::ZERO };
        let p = &self.params;
        let lin = linear(&track.pos);
        let v = if track.moving { lin.0 } else { Self::significant(p, &lin, p.deadband_m_s) };
        let lead = Vector3::new(track.pos[0].a, track.pos[1].a, track.pos[2].a) * p.acceleration_lead_s;
        let v = if v == Vector3::zeros() { v } else { v + lead };
        TargetVelocity { v, w: Self::angular_feedforward(p, track) }
    }

    /// The angular velocity fed forward: the slow model's once it has learnt from
    /// [`TargetFilterParams::converge_updates`] updates since its last restart, if significant
    /// and outside [`TargetFilterParams::slow_deadband_rad_s`]; otherwise the fast model's, if
    /// significant and outside [`TargetFilterParams::deadband_rad_s`] and the linear motion is
    /// not held with [`TargetFilterParams::linear_motion_mutes_angular`].
    fn angular_feedforward(p: &TargetFilterParams, track: &Track) -> Vector3<f32> {
        let slow = if p.slow_angular_acceleration_psd > 0.0 && track.slow.updates() >= p.converge_updates {
            Self::significant(p, &track.slow.velocity(), p.slow_deadband_rad_s)
        } else {
            Vector3::zeros()
        };
        if slow != Vector3::zeros() || (p.linear_motion_mutes_angular && track.moving) {
            slow
        } else {
            Self::significant(p, &angular(&track.rot), p.deadband_rad_s)
        }
    }

    /// The velocity `(v, σ²)` if it is outside the dead band and significant, else zero.
    fn significant(p: &TargetFilterParams, (v, var): &(Vector3<f32>, Vector3<f32>), deadband: f32) -> Vector3<f32> {
        let v = *v;
        let sigmas2: f32 = v.iter().zip(var.iter()).map(|(v, s2)| v * v / s2.max(f32::MIN_POSITIVE)).sum();
        let significant = sigmas2 >= p.significance_sigma * p.significance_sigma;
        if significant && v.dot(&v) >= deadband * deadband { v } else { Vector3::zeros() }
    }

    /// [`TargetFilter::feedforward_velocity`] with its linear part along the line of sight
    /// `sight` (world frame, camera to block; `u` its unit vector) kept only as far as the world
    /// axes seen across the sight say, plus [`TargetFilterParams::depth_feedforward`] `d` of
    /// the rest: `v − (1 − d)(v·u − Σᵢ (1 − uᵢ²) vᵢ uᵢ) u`. A world axis across the view
    /// (`uᵢ = 0`) is measured well, and its velocity's part along a slanted sight is real
    /// motion in depth; an axis along the sight (`uᵢ = ±1`) is measured by the stereo depth.
    pub fn feedforward_velocity_seen_along(&self, sight: &Vector3<f32>) -> TargetVelocity {
        let mut vel = self.feedforward_velocity();
        vel.v = self.seen_along(vel.v, sight);
        vel
    }

    /// `v` with its part along the line of sight `sight` kept as the feedforward keeps it.
    fn seen_along(&self, v: Vector3<f32>, sight: &Vector3<f32>) -> Vector3<f32> {
        let Some(u) = unit(sight).filter(|_| v != Vector3::zeros()) else { return v };
        // What the world axes say along the sight, each weighed by the share of it the camera
        // sees across the sight (`1 − uᵢ²`): an axis across the view is measured well, and its
        // velocity's part along the sight is real motion in depth.
        let across: f32 = (0..3).map(|i| (1.0 - u[i] * u[i]) * v[i] * u[i]).sum();
        v - u * ((v.dot(&u) - across) * (1.0 - self.params.depth_feedforward))
    }
}

impl Default for TargetFilter {
    fn default() -> Self {
        Self::with_defaults()
    }
}

/// The velocity `[ẋ₀, ẋ₁, ẋ₂]` of the position axes and its variances.
fn linear(axes: &[PosAxis; 3]) -> (Vector3<f32>, Vector3<f32>) {
    (Vector3::new(axes[0].v, axes[1].v, axes[2].v), Vector3::new(axes[0].p[3], axes[1].p[3], axes[2].p[3]))
}

/// The angular velocity of the rotation axes and its variances.
fn angular(axes: &[Axis; 3]) -> (Vector3<f32>, Vector3<f32>) {
    (Vector3::new(axes[0].v, axes[1].v, axes[2].v), Vector3::new(axes[0].p[2], axes[1].p[2], axes[2].p[2]))
}

/// The unit vector along `v` (a line of sight), `None` for a (near) zero vector.
fn unit(v: &Vector3<f32>) -> Option<Vector3<f32>> {
    let n2 = v.dot(v);
    if n2 > 1e-12 { Some(v / math::sqrt(n2)) } else { None }
}

fn finite(iso: &Isometry3<f32>) -> bool {
    iso.translation.vector.iter().chain(iso.rotation.coords.iter()).all(|v| v.is_finite())
}

/// Rotation matrix `^CR R_W` of a camera pose (for [`crate::feedforward::jn`]).
pub fn camera_from_world_rotation(camera: &Isometry3<f32>) -> Matrix3<f32> {
    quat::to_rotation_matrix(&camera.rotation).transpose()
}

#[cfg(test)]
mod tests;
